"""Planted instances: problems whose zero-cost solution is known.

Random non-overlapping starts and random cue velocities; each noncueable disk is
the aim of a strike by a cueable disk (``nbst.search.aim.strike_velocity``, towards a
random point of the box); the motion is simulated exactly and each disk's target
is where it ends. So the velocities used are a solution of cost 0 (up to the
round-off of writing the targets), and a search has a ground truth.

Placement is rejection sampling: a uniform random centre per try, kept when it is at
least ``2 r + START_GAP`` from every disk placed so far. The tries are drawn in batches
and checked by a compiled kernel against a uniform grid of cells (side >= that distance,
so only the 3 x 3 cells around a try can hold a disk too close): O(1) per try instead of
O(N). The batches consume the random stream exactly as one ``rng.uniform`` per try did
(the unused tail of the last batch is given back by rewinding the generator), so every
(n, seed, options) that worked before gives the same problem bit for bit.
"""
from __future__ import annotations

import math
import time
from typing import Any

import numpy as np
from numba import njit

from nbst.errors import InputError, SolveError
from nbst.problem import Problem, problem_from_dict
from nbst.search.aim import strike_velocity
from nbst.sim import simulate

__all__ = ["START_GAP", "SPEED_RANGE", "PLACE_TRIES", "PLACE_TRIES_PER_DISK", "STRIKE_TRIES", "DEFAULT_SIDE",
           "DENSITY_DISKS", "DEFAULT_BOX_UP_TO", "PLACE_BATCH", "speed_scale", "default_box", "place_tries",
           "place_disks", "planted"]

#: Extra gap between starts (units) so that planted starts are not in contact.
START_GAP = 2.0
#: Cue speeds are uniform in this fraction range of ``speed_scale`` per t_final: the box
#: diagonal up to 63 disks.
SPEED_RANGE = (0.05, 0.35)
#: Tries to place the disks: at least PLACE_TRIES, and PLACE_TRIES_PER_DISK per disk for large N
#: (at the default density a try is kept with probability > 0.6, so ~1.5 N tries suffice;
#: the rest is room for a crowded --box). STRIKE_TRIES: tries to find a strike from the right side.
PLACE_TRIES = 20_000
PLACE_TRIES_PER_DISK = 200
STRIKE_TRIES = 64
#: The default box: DEFAULT_SIDE x DEFAULT_SIDE up to DEFAULT_BOX_UP_TO disks (nbst's old
#: 63-disk cap, so every problem generated before keeps its box); above, the box grows to keep
#: the density of DENSITY_DISKS disks of radius 15 in 800 x 800: each side DEFAULT_SIDE * sqrt(N / 60).
DEFAULT_SIDE = 800.0
DENSITY_DISKS = 60
DEFAULT_BOX_UP_TO = 63
#: Tries per placement batch (one kernel call, one progress update).
PLACE_BATCH = 65_536


def speed_scale(n: int, box) -> float:
    """The length that cue speeds are drawn against: the box diagonal up to 63 disks (as
    always), and past that the diagonal shrunk by sqrt(DENSITY_DISKS / n). In the default box
    that is the diagonal of 800 x 800 at every N: disks travel as far and meet as many others
    as at 60 disks (fixed density and fixed speeds), where scaling speed with the diagonal
    made 3.9 collisions per disk at 1,000 disks and 5.7 at 2,000."""
    diag = float(np.hypot(*box))
    return diag if n <= DEFAULT_BOX_UP_TO else diag * math.sqrt(DENSITY_DISKS / n)


def default_box(n: int) -> tuple[float, float]:
    """The box ``nbst generate --planted N`` uses without --box (see DEFAULT_BOX_UP_TO)."""
    if n <= DEFAULT_BOX_UP_TO:
        return (DEFAULT_SIDE, DEFAULT_SIDE)
    side = DEFAULT_SIDE * math.sqrt(n / DENSITY_DISKS)
    return (side, side)


def place_tries(n: int) -> int:
    """The try budget for placing n disks."""
    return max(PLACE_TRIES, PLACE_TRIES_PER_DISK * n)


@njit(cache=True)
def _grid_place(cand, starts, placed, n, gap, head, nxt, cell, nx, ny):
    """Keep each candidate centre (cand, (B, 2), in order) whose distance to every disk placed
    so far is >= gap, until n are placed. The cells (nx x ny of side ``cell`` >= gap) hold
    linked lists: ``head[cy * nx + cx]`` is the last disk put in a cell, ``nxt[i]`` the one
    before it (-1 ends). Returns (placed, tries used)."""
    for k in range(cand.shape[0]):
        if placed == n:
            return placed, k
        x = cand[k, 0]
        y = cand[k, 1]
        cx = min(max(int(x / cell), 0), nx - 1)
        cy = min(max(int(y / cell), 0), ny - 1)
        ok = True
        for gy in range(max(cy - 1, 0), min(cy + 2, ny)):
            for gx in range(max(cx - 1, 0), min(cx + 2, nx)):
                j = head[gy * nx + gx]
                while j >= 0:
                    if math.hypot(starts[j, 0] - x, starts[j, 1] - y) < gap:
                        ok = False
                        break
                    j = nxt[j]
                if not ok:
                    break
            if not ok:
                break
        if ok:
            starts[placed, 0] = x
            starts[placed, 1] = y
            c = cy * nx + cx
            nxt[placed] = head[c]
            head[c] = placed
            placed += 1
    return placed, cand.shape[0]


def place_disks(rng: np.random.Generator, n: int, r: float, box, *, gap: float = START_GAP, progress=None):
    """n centres in the box, pairwise >= 2 r + gap apart, by rejection sampling with
    ``place_tries(n)`` tries (one ``rng.uniform`` pair per try, in order). Returns (starts, placed):
    ``placed < n`` when the budget ran out. ``progress(stage, done, total)`` is called between batches."""
    W, H = box
    d = 2 * r + gap
    lo, hi = np.array([r, r]), np.array([W - r, H - r])
    # cells of side >= d (a hair more, so that a disk two cells away is surely >= d away whatever
    # the round-off of x / cell), and about 4 cells per disk at most; a centre past the last cell
    # counts in it (merging cells only adds checks, it never hides a close disk)
    cell = max(d * (1.0 + 1e-9), math.sqrt(W * H / (4.0 * n)))
    nx = max(1, min(int(W / cell) + 1, 1 << 15))
    ny = max(1, min(int(H / cell) + 1, 1 << 15))
    head = np.full(nx * ny, -1, np.int64)
    nxt = np.full(n, -1, np.int64)
    starts = np.empty((n, 2))
    placed, budget = 0, place_tries(n)
    if progress is not None:
        progress("placing disks", 0, n)
    while budget > 0 and placed < n:
        b = min(budget, PLACE_BATCH)
        state = rng.bit_generator.state
        cand = rng.uniform(lo, hi, size=(b, 2))
        placed, used = _grid_place(cand, starts, placed, n, d, head, nxt, cell, nx, ny)
        if used < b:  # give back the draws this batch did not use
            rng.bit_generator.state = state
            rng.uniform(lo, hi, size=(used, 2))
        budget -= used
        if progress is not None:
            progress("placing disks", placed, n)
    return starts, placed


def planted(n: int, *, noncue: int = 0, radius: float = 15.0, seed: int, box=None, t_final: float = 5.0,
            target_radius: float = 75.0, name: str | None = None, progress=None) -> tuple[Problem, np.ndarray]:
    """A random problem with n disks (the last ``noncue`` noncueable) and its zero-cost velocities.

    box: (W, H), or None for ``default_box(n)``. progress: None, or ``progress(stage, done, total)``,
    called between placement batches and before and after the exact simulation.

    Raises:
        InputError: ``n``, ``noncue``, ``radius`` or ``box`` cannot be met (no cueable disk, the
            disks do not fit).
        SolveError: the planted motion needs more events than the simulator's cap.
    """
    if box is None:
        box = default_box(n)
    if n < 1:
        raise InputError(f"n (the number of disks) must be at least 1, got {n}")
    if not 0 <= noncue < n:
        raise InputError(f"noncue must be between 0 and {n - 1} (at least one disk must be cueable), got {noncue}")
    if radius <= 0 or 2 * radius >= min(box):
        raise InputError(f"radius must be > 0 and fit the {box[0]:g} x {box[1]:g} box, got {radius:g}")
    rng = np.random.default_rng(seed)
    W, H = box
    r = float(radius)
    starts, placed = place_disks(rng, n, r, box, progress=progress)
    if placed < n:
        raise InputError(f"could not place {n} disks of radius {r:g} in the {W:g} x {H:g} box "
                         f"({place_tries(n):,} tries placed {placed:,}); use a smaller radius or a larger box")
    cue = np.arange(n) < n - noncue
    ang = rng.uniform(0, 2 * np.pi, n)
    speed = rng.uniform(*SPEED_RANGE, n) * speed_scale(n, box) / t_final
    v = np.stack([np.cos(ang), np.sin(ang)], axis=1) * speed[:, None]
    v[~cue] = 0.0
    # each noncueable disk is struck by a cueable one, towards a random point
    cue_idx = np.flatnonzero(cue)
    mass = np.ones(n)
    out = np.empty(2)
    for m, s in enumerate(np.flatnonzero(~cue)):
        c = cue_idx[m % cue_idx.size]
        for _ in range(STRIKE_TRIES):
            T = rng.uniform([r, r], [W - r, H - r])
            if strike_velocity(starts[c], r, mass[c], starts[s], r, mass[s], T, t_final, out) > 0:
                v[c] = out
                break
    d: dict[str, Any] = {
        "name": name or f"planted-n{n}-k{noncue}-s{seed}",
        "description": f"Planted instance: {n} disks (r={r:g}), {noncue} noncueable; a zero-cost solution exists "
                       f"(nbst generate --planted {n} --noncue {noncue} --radius {r:g} --seed {seed}).",
        "box": [float(W), float(H)],
        "t_final": float(t_final),
        "target_radius": float(target_radius),
        "disks": [{"start": starts[i].tolist(), "target": starts[i].tolist(), "radius": r, "cueable": bool(cue[i])}
                  for i in range(n)],
    }
    if progress is not None:
        progress("simulating the planted motion", 0, 1)
    tr = simulate(problem_from_dict(d), v)
    if tr.truncated:
        raise SolveError(f"the planted motion of {n} disks needs more events than the simulator's cap "
                         f"({tr.events.size:,} events by t = {tr.t_end:.3g} s); use fewer disks or a larger box")
    if progress is not None:
        progress("simulating the planted motion", 1, 1)
    final = np.clip(tr.final_positions, r, np.array([W - r, H - r]))  # round-off at a wall
    for i in range(n):
        d["disks"][i]["target"] = final[i].tolist()
    d["planted"] = {"velocities": v.tolist(), "seed": int(seed), "disk_disk_collisions": tr.n_disk_disk,
                    "wall_bounces": tr.n_wall,
                    "struck_noncueable": int(sum(1 for s in np.flatnonzero(~cue)
                                                 if np.any(tr.final_positions[s] != starts[s])))}
    return problem_from_dict(d, source=d["name"]), v
