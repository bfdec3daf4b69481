"""Formations: disks that start on a grid (or scattered) and end forming a picture.

The animator's use of nbst (``nbst generate --targets-from SRC``): the targets are points
on the dark pixels of an image, or on the glyphs of a text that matplotlib renders
offscreen (Agg, DejaVu Sans Bold); the starts are a grid over the whole box, or random
cells of a coarser grid, jittered. Every disk is cueable and has the same radius r.

Spacing. Targets are a hexagonal lattice over the dark region, starts a square grid (or
jittered cells); both are spaced at least ``s = 2 sqrt(2) r (1 + margin)`` apart (centre
to centre), margin = ``SPACING_MARGIN``.

Assignment by pairwise swaps. Start i (at x_i) is sent to target y_i. While some pair
(i, j) has ``(x_i - x_j) . (y_i - y_j) < 0``, swap their targets. A swap changes the total
squared distance sum_k |x_k - y_k|^2 by exactly ``2 (x_i - x_j) . (y_i - y_j) < 0``, so
every swap strictly lowers it; there are finitely many assignments, so the passes end.
Then every pair has a = x_i - x_j, b = y_i - y_j with ``a . b >= 0``, and the straight,
constant-speed paths p_k(u) = (1 - u) x_k + u y_k (u = t / t_final in [0, 1]) keep

    |p_i(u) - p_j(u)|^2 = (1-u)^2 |a|^2 + u^2 |b|^2 + 2 u (1-u) a . b
                        >= (1-u)^2 |a|^2 + u^2 |b|^2
                        >= |a|^2 |b|^2 / (|a|^2 + |b|^2)       (the minimum over u)
                        >= s^2 / 2                              (|a|, |b| >= s)

so two centres never come closer than s / sqrt(2) = 2 r (1 + margin) > 2 r: the straight
shots ``(y_i - x_i) / t_final`` never touch. Starts and targets lie at least r inside the
walls and the box is convex, so no path meets a wall either: the straight velocities are
an exact, collision-free solution of cost zero (up to the round-off of x + v t_final).

The swap passes are a compiled kernel (arrays in, arrays out): N (N - 1) / 2 pair checks
a pass, from a start that already matches starts and targets in the same sweep order.
"""
from __future__ import annotations

import math
import shlex
from pathlib import Path
from typing import Any

import numpy as np
from numba import njit

from nbst.domain import BOX_MAX, BOX_MIN, RADIUS_MIN_FRACTION
from nbst.pictures import (DARK_BELOW, IMAGE_EXTENSIONS, MAX_TEXT_CHARS, FormationError, check_text, hex_lattice,
                           image_mask, is_image_source, lattice_for, text_mask)
from nbst.problem import Problem, ProblemError, problem_from_dict

__all__ = ["formation", "FormationError", "is_image_source", "assign", "spacing", "MAX_FORMATION_DISKS"]

#: Spacing of starts and of targets: s = 2 sqrt(2) r (1 + SPACING_MARGIN); then straight
#: paths keep centres >= 2 r (1 + SPACING_MARGIN) apart (module docstring).
SPACING_MARGIN = 0.1
#: Random starts: cells of pitch up to RANDOM_PITCH x s (one start per cell, jittered so that
#: starts stay >= s apart), at least RANDOM_SPARE x N cells so that the chosen ones scatter.
RANDOM_PITCH = 2.0
RANDOM_SPARE = 1.5
#: Swap passes allowed (each pass is N^2 / 2 checks; measured passes stay in the tens).
MAX_SWAP_PASSES = 10_000
#: Most disks in one formation: the swap passes check every pair (N^2 / 2 a pass, ~0.5 s a pass
#: at this size on one core), and a few tens of passes are needed.
MAX_FORMATION_DISKS = 20_000
START_LAYOUTS = ("grid", "random")


def grid_starts(n: int, box, s: float) -> np.ndarray | None:
    """n starts on a square grid over the box (the largest pitch >= s that holds n, the last
    row centred), at least s / 2 from the walls; None when pitch s cannot hold n."""
    W, H = box
    Wa, Ha = W - s, H - s  # centres live in [s/2, W - s/2] x [s/2, H - s/2]
    if Wa < 0 or Ha < 0:
        return None

    def count(g):
        return (int(Wa / g) + 1) * (int(Ha / g) + 1)

    if count(s) < n:
        return None
    lo, hi = s, max(s, math.hypot(Wa, Ha)) * 2.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if count(mid) >= n:
            lo = mid
        else:
            hi = mid
    g = lo
    cols, rows = int(Wa / g) + 1, int(Ha / g) + 1
    rows_used = -(-n // cols)
    # centre the used rows and columns in the box
    x0 = (W - (cols - 1) * g) / 2.0
    y_top = (H + (rows_used - 1) * g) / 2.0
    pts = np.empty((n, 2))
    for k in range(n):
        row, col = divmod(k, cols)
        in_row = min(cols, n - row * cols)
        xr = (W - (in_row - 1) * g) / 2.0 if in_row < cols else x0
        pts[k] = (xr + col * g, y_top - row * g)
    return pts


def _starts_fit(start: str, n: int, box, s: float, r: float) -> bool:
    """Whether the box holds n starts spaced s apart in the ``start`` layout (as laid out below)."""
    W, H = box
    if start == "grid":
        return W >= s and H >= s and (int((W - s) / s) + 1) * (int((H - s) / s) + 1) >= n
    return W - 2 * r >= s and H - 2 * r >= s and int((W - 2 * r) / s) * int((H - 2 * r) / s) >= n


def random_starts(n: int, box, s: float, r: float, rng: np.random.Generator) -> np.ndarray | None:
    """n starts in random cells of a grid over the box, each jittered inside its cell so that
    any two stay >= s apart (pitch g, jitter +-(g - s) / 2); None when the box holds fewer
    than n cells of pitch s."""
    W, H = box
    Wa, Ha = W - 2 * r, H - 2 * r

    def cells(g):
        return int(Wa / g) * int(Ha / g)

    if Wa < s or Ha < s or cells(s) < n:
        return None
    g = s
    want = math.ceil(RANDOM_SPARE * n)
    hi = RANDOM_PITCH * s
    if cells(hi) >= want:
        g = hi
    elif cells(s) >= want:
        lo = s
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            if cells(mid) >= want:
                lo = mid
            else:
                hi = mid
        g = lo
    cols, rows = int(Wa / g), int(Ha / g)
    pick = np.sort(rng.choice(cols * rows, size=n, replace=False))
    row, col = np.divmod(pick, cols)
    ox = r + (Wa - cols * g) / 2.0
    oy = r + (Ha - rows * g) / 2.0
    j = (g - s) / 2.0
    jit = rng.uniform(-j, j, size=(n, 2)) if j > 0 else np.zeros((n, 2))
    return np.stack([ox + (col + 0.5) * g, oy + (row + 0.5) * g], axis=1) + jit


# --------------------------------------------------------------------------- assignment


@njit(cache=True)
def swap_passes(X, Y, perm, max_passes):
    """Swap targets of pairs (i, j) with (X[i] - X[j]) . (Y[perm[i]] - Y[perm[j]]) < 0, pass
    after pass, until a pass swaps nothing. X, Y: (N, 2) starts and targets; perm: (N,) int64,
    start i goes to Y[perm[i]], changed in place. Returns (passes, swaps); passes = -1 when
    ``max_passes`` passes all swapped something (never seen: the module docstring's argument
    says the passes end)."""
    n = X.shape[0]
    swaps = 0
    for p in range(max_passes):
        changed = 0
        for i in range(n):
            xi0 = X[i, 0]
            xi1 = X[i, 1]
            for j in range(i + 1, n):
                a0 = xi0 - X[j, 0]
                a1 = xi1 - X[j, 1]
                pi = perm[i]
                pj = perm[j]
                b0 = Y[pi, 0] - Y[pj, 0]
                b1 = Y[pi, 1] - Y[pj, 1]
                if a0 * b0 + a1 * b1 < 0.0:
                    perm[i] = pj
                    perm[j] = pi
                    changed += 1
        swaps += changed
        if changed == 0:
            return p + 1, swaps
    return -1, swaps


def assign(X: np.ndarray, Y: np.ndarray, *, progress=None) -> tuple[np.ndarray, int, int]:
    """perm with (X[i] - X[j]) . (Y[perm[i]] - Y[perm[j]]) >= 0 for every pair: starts and
    targets first matched in the same sweep order (by x + y, then x - y), then swap passes
    (one kernel call a pass, ``progress(stage, passes done, 0)`` before and after each). Returns
    (perm, passes, swaps)."""
    X = np.ascontiguousarray(X, dtype=np.float64)
    Y = np.ascontiguousarray(Y, dtype=np.float64)
    ox = np.lexsort((X[:, 0] - X[:, 1], X[:, 0] + X[:, 1]))
    oy = np.lexsort((Y[:, 0] - Y[:, 1], Y[:, 0] + Y[:, 1]))
    perm = np.empty(X.shape[0], np.int64)
    perm[ox] = oy
    swaps = 0
    stage = "assigning targets by pairwise swaps"
    if progress is not None:
        progress(stage, 0, 0)
    for k in range(1, MAX_SWAP_PASSES + 1):
        done, m = swap_passes(X, Y, perm, 1)
        swaps += m
        if progress is not None:
            progress(stage, k, 0)
        if done == 1:
            return perm, k, swaps
    raise FormationError(f"the swap passes did not settle in {MAX_SWAP_PASSES:,} passes")


# --------------------------------------------------------------------------- the problem


def spacing(radius: float) -> float:
    """The least centre distance between two starts or two targets: 2 sqrt(2) r (1 + margin)."""
    return 2.0 * math.sqrt(2.0) * radius * (1.0 + SPACING_MARGIN)


def _slug(text: str, limit: int = 60) -> str:
    s = "".join(ch if ch.isalnum() else "-" for ch in text.strip().lower())
    s = "-".join(w for w in s.split("-") if w)
    return s[:limit].strip("-")


def formation(src: str, n: int, *, radius: float = 15.0, start: str = "grid", seed: int, t_final: float = 5.0,
              target_radius: float | None = None, box=None, name: str | None = None,
              progress=None) -> tuple[Problem, np.ndarray, dict]:
    """A problem whose n disks start on a grid (or at random) and end on the dark pixels of the
    image ``src`` (a path ending in an image extension) or on the glyphs of the text ``src``;
    with its straight velocities, an exact collision-free solution (module docstring).

    box: (W, H), or None to size it to fit: the picture scaled so that its hexagonal target
    lattice has spacing s (``spacing(radius)``) and n points, with a border of s on every side
    (grown if the start grid needs more room). target_radius: default s / 2, the largest R for
    which no two targets' neighbourhoods overlap (a disk within R of its target is nearer to it
    than to any other target). progress: None or ``progress(stage, done, total)`` (the swap
    passes). Returns (problem, velocities, info: timings and counts).
    Raises ProblemError (a bad image file) or FormationError (a request that cannot be met)."""
    import time

    if start not in START_LAYOUTS:
        raise FormationError(f"start must be one of {', '.join(START_LAYOUTS)}, got {start!r}")
    if not 1 <= n <= MAX_FORMATION_DISKS:
        raise FormationError(f"the number of disks must be in 1..{MAX_FORMATION_DISKS:,} for a formation, got {n:,}")
    r = float(radius)
    s = spacing(r)
    rng = np.random.default_rng(seed)
    info = {}
    t0 = time.perf_counter()
    if is_image_source(src):
        kind, label = "image", Path(src).name
        mask = image_mask(src)
        if not mask.any():
            raise ProblemError(src, "", f"has no dark pixels (luminance below {DARK_BELOW:g}) to form")
    else:
        kind, label = "text", src
        check_text(src)
        if not src.strip():
            raise FormationError("the target text is empty; give a text to write or an image file "
                                 f"({', '.join(IMAGE_EXTENSIONS)})")
        if len(src) > MAX_TEXT_CHARS:
            raise FormationError(f"the target text has {len(src):,} characters; at most {MAX_TEXT_CHARS}")
        mask = text_mask(src)
        if not mask.any():
            raise FormationError(f"the target text {src!r} draws no dark pixels")
    rows = np.flatnonzero(mask.any(axis=1))
    cols = np.flatnonzero(mask.any(axis=0))
    mask = mask[rows[0]:rows[-1] + 1, cols[0]:cols[-1] + 1]  # the dark region's bounding box
    ph, pw = mask.shape
    h_px, pts = lattice_for(mask, n)
    info["picture_s"] = time.perf_counter() - t0
    if box is None:
        k = s / h_px  # units per pixel: lattice spacing s
        W, H = pw * k + 2 * s, ph * k + 2 * s
        while not _starts_fit(start, n, (W, H), s, r):  # a fully dark picture holds more than a grid
            W, H = W * 1.05, H * 1.05
        box_note = "sized to fit"
    else:
        W, H = map(float, box)
        if W - 2 * s <= 0 or H - 2 * s <= 0:
            raise FormationError(f"the {W:g} x {H:g} box leaves no room for disks of radius {r:g} "
                                 f"(border {s:.4g} on each side); use a larger box or a smaller radius")
        k = min((W - 2 * s) / pw, (H - 2 * s) / ph)
        if h_px * k < s:
            cap = hex_lattice(mask, s / k).shape[0]
            raise FormationError(f"the picture of {label!r} scaled into the {W:g} x {H:g} box holds at most {cap:,} "
                                 f"disks of radius {r:g} at spacing {s:.4g} (asked for {n:,}); use fewer disks, "
                                 f"a smaller radius, a larger box, or no box (sized to fit)")
        box_note = "given"
    if not (BOX_MIN <= W <= BOX_MAX and BOX_MIN <= H <= BOX_MAX):
        raise FormationError(f"the box would be {W:.4g} x {H:.4g}, outside nbst's [{BOX_MIN:g}, {BOX_MAX:g}]; "
                             f"use a different radius")
    if r < RADIUS_MIN_FRACTION * max(W, H):
        raise FormationError(f"the picture's dark part is {pw:,} x {ph:,} px: at the spacing of disks of radius "
                             f"{r:g} its box would be {W:.4g} x {H:.4g}, over {1 / RADIUS_MIN_FRACTION:,.0f} radii "
                             f"long; use a picture of a less extreme shape, or fewer disks")
    # thin the lattice to n points (seeded), then picture pixels -> box units, y up, centred
    if pts.shape[0] > n:
        pts = pts[np.sort(rng.choice(pts.shape[0], size=n, replace=False))]
    ox = (W - pw * k) / 2.0
    oy = (H - ph * k) / 2.0
    targets = np.stack([ox + pts[:, 0] * k, oy + (ph - pts[:, 1]) * k], axis=1)
    starts = grid_starts(n, (W, H), s) if start == "grid" else random_starts(n, (W, H), s, r, rng)
    if starts is None:
        raise FormationError(f"the {W:g} x {H:g} box cannot hold {n:,} starts of radius {r:g} spaced {s:.4g} apart "
                             f"({start} layout); use fewer disks, a smaller radius or a larger box")
    t1 = time.perf_counter()
    perm, passes, swaps = assign(starts, targets, progress=progress)
    info.update(assign_s=time.perf_counter() - t1, passes=passes, swaps=swaps)
    targets = targets[perm]
    v = (targets - starts) / t_final
    R = s / 2.0 if target_radius is None else float(target_radius)
    how = "text" if kind == "text" else "image"
    what = f"the glyphs of the text {src!r}" if kind == "text" else f"the dark pixels of the image {label}"
    cmd = (f"nbst generate --targets-from {shlex.quote(src)} --disks {n} --radius {r:g} --start {start} --seed {seed}"
           + (f" --box {W:g} {H:g}" if box is not None else "") + f" --t-final {t_final:g}")
    d: dict[str, Any] = {
        "name": name or "-".join(filter(None, (how, _slug(src if kind == "text" else Path(src).stem)))),
        "description": (f"Formation: {n} disks (r={r:g}) start on a {'grid' if start == 'grid' else 'random jittered grid'} "
                        f"and end forming {what[:300]}"
                        f"{' (matplotlib, DejaVu Sans Bold)' if kind == 'text' else ''}. Starts and targets are "
                        f">= {s:.4g} apart (2 sqrt(2) r (1 + {SPACING_MARGIN:g})); targets assigned by pairwise "
                        f"swaps, so the straight shots (target - start) / t_final never touch: a zero-cost "
                        f"solution. Box {box_note}. Made by `{cmd[:500]}`."),
        "box": [float(W), float(H)],
        "t_final": float(t_final),
        "target_radius": float(R),
        "disks": [{"start": starts[i].tolist(), "target": targets[i].tolist(), "radius": r, "cueable": True}
                  for i in range(n)],
        "formation": {"source": how, how: label if kind == "image" else src, "start": start, "seed": int(seed),
                      "disks": int(n), "spacing": s, "target_spacing": h_px * k,
                      "start_spacing": _least_distance(starts), "box": box_note},
    }
    return problem_from_dict(d, source=d["name"]), v, info


def _least_distance(pts: np.ndarray) -> float | None:
    """The least distance between two of the points (None for one point)."""
    from scipy.spatial import cKDTree

    return float(cKDTree(pts).query(pts, k=2)[0][:, 1].min()) if pts.shape[0] > 1 else None
