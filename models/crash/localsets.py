"""The local sets' geometry: the reconstruction's linear model about one accepted draw.

:func:`models.crash.reconstruct._local` linearises a draw (forward differences, rollouts on the
engine); this module holds what follows without a rollout: the evidence's signed residuals of one
rollout and their constraints (:func:`residual`), the chord of a line through the convex set
where every constraint holds (:func:`chord`), hit-and-run on that set (:func:`sample_set`: R. L.
Smith, *Efficient Monte Carlo procedures for generating points uniformly distributed over bounded
regions*, Operations Research 32, 1984) and a set cut by half-spaces of its quantities
(:func:`cut`). Plain functions on arrays; the method is described in docs/crash.md.
"""
from __future__ import annotations

import math

import numpy as np

from nbst.models.crash.outcome import _wrap

__all__ = ["LOCAL_TRUST", "LOCAL_SAMPLES", "LOCAL_BURN", "residual", "chord", "sample_set", "cut"]

#: A local set's intents reach at most LOCAL_TRUST (unit cube) from the draw, at first; it is
#: sampled by LOCAL_SAMPLES steps of hit-and-run after LOCAL_BURN.
LOCAL_TRUST, LOCAL_SAMPLES, LOCAL_BURN = 0.15, 400, 100


def residual(ps: list, o, d: np.ndarray) -> tuple[np.ndarray, list]:
    """The evidence's signed residuals of one rollout in units of the tolerances, and their
    constraints: a position (rest, impact) two components within the unit disc, a heading one
    within [-1, 1]; any other piece its distance (at most 1: a half-space once linearised)."""
    r: list = []
    kinds: list = []
    for j, p in enumerate(ps):
        vo = o.vehicles[p.vehicle] if p.vehicle is not None else None
        if p.kind in ("rest", "impact_at") and vo is not None:
            x = vo.rest if p.kind == "rest" else vo.impact_pos
            if np.all(np.isfinite(x[:2])):
                kinds.append(("disc", len(r)))
                r += [(x[0] - p.value[0]) / p.tol, (x[1] - p.value[1]) / p.tol]
                continue
        if p.kind == "heading" and vo is not None:
            kinds.append(("slab", len(r)))
            r.append(float(_wrap(vo.rest[2] - p.value[0])) / p.tol)
            continue
        kinds.append(("half", len(r)))
        r.append(float(d[j]))
    return np.array(r), kinds


def chord(kinds: list, c: np.ndarray, w: np.ndarray) -> tuple[float, float]:
    """The t with every constraint of residuals c + t w met (an interval: the set is convex)."""
    lo, hi = -math.inf, math.inf
    for kind, j in kinds:
        if kind == "disc":
            cc, ww = c[j:j + 2], w[j:j + 2]
            A, B, C = float(ww @ ww), float(cc @ ww), float(cc @ cc) - 1.0
            if A < 1e-12:
                continue
            disc = B * B - A * C
            if disc < 0:
                return 0.0, 0.0
            r = math.sqrt(disc)
            lo, hi = max(lo, (-B - r) / A), min(hi, (-B + r) / A)
        elif abs(w[j]) > 1e-12:
            if kind == "slab":
                a1, a2 = (-1.0 - c[j]) / w[j], (1.0 - c[j]) / w[j]
                lo, hi = max(lo, min(a1, a2)), min(hi, max(a1, a2))
            elif w[j] > 0:
                hi = min(hi, (1.0 - c[j]) / w[j])
            else:
                lo = max(lo, (1.0 - c[j]) / w[j])
    return lo, hi


def sample_set(m: dict, rng) -> tuple[np.ndarray, np.ndarray, bool]:
    """Hit-and-run on one draw's local set (:func:`models.crash.reconstruct._local`'s linear model ``m``, its intents
    within ``m["trust"]`` of the draw): (the samples' steps from the draw (LOCAL_SAMPLES, nd),
    their quantities (LOCAL_SAMPLES, 3 n + 1), whether the trust region bounds the set: a sample
    within 2 % of the trust's face where that face lies inside the ranges)."""
    x0, dim, r0, kinds, J, Jq, free = m["x0"], m["dim"], m["r0"], m["kinds"], m["J"], m["Jq"], m["free"]
    nd = len(x0)
    trust = float(m.get("trust", LOCAL_TRUST))
    tr = np.r_[np.full(dim, trust), np.full(nd - dim, 1.0)]
    lo_box, hi_box = np.maximum(-x0, -tr), np.minimum(1.0 - x0, tr)
    x = np.zeros(nd)
    idx = np.flatnonzero(free)
    samples = []
    if len(idx):
        # directions shaped like the set (the linear model's, the trust region's): a symmetric
        # law of directions keeps hit-and-run uniform on the set, and a long thin set mixes
        Ji = J[:, idx]
        M = Ji.T @ Ji + np.diag(1.0 / np.maximum(hi_box[idx] - lo_box[idx], 1e-6) ** 2)
        L = np.linalg.cholesky(np.linalg.inv(M))
        for it in range(LOCAL_BURN + LOCAL_SAMPLES):
            v = np.zeros(nd)
            v[idx] = L @ rng.standard_normal(len(idx))
            lo, hi = chord(kinds, r0 + J @ x, J @ v)
            for kb in idx.tolist():  # the ranges and the trust region
                if abs(v[kb]) > 1e-12:
                    a1, a2 = (lo_box[kb] - x[kb]) / v[kb], (hi_box[kb] - x[kb]) / v[kb]
                    lo, hi = max(lo, min(a1, a2)), min(hi, max(a1, a2))
            if hi > lo:
                x = x + float(rng.uniform(lo, hi)) * v
            if it >= LOCAL_BURN:
                samples.append(x.copy())
    Xs = np.array(samples) if samples else np.zeros((1, nd))
    q = m["q"][None] + Xs @ Jq.T
    for c in range(2, q.shape[1] - 1, 3):
        q[:, c] = (q[:, c] - 1e-9) % 12.0 + 1e-9
    near = 0.02 * trust
    bound = bool(trust < 1.0 and np.any(((Xs[:, :dim] <= -trust + near) & (-trust > -x0[:dim] + 1e-9))
                                        | ((Xs[:, :dim] >= trust - near) & (trust < 1.0 - x0[:dim] - 1e-9))))
    return Xs, q, bound


def cut(sample: tuple, cuts: list) -> tuple:
    """A set's samples (:func:`sample_set`) within the half-spaces ``cuts`` [(quantity column,
    side, limit)]: side -1 keeps the quantity at or above the limit, +1 at or below (a quantity
    is linear on the set, so the cut set is convex and the kept samples uniform on it)."""
    X, q, bound = sample
    keep = np.ones(len(q), bool)
    for c, side, limit in cuts:
        keep &= (q[:, c] >= limit - 1e-12) if side < 0 else (q[:, c] <= limit + 1e-12)
    return X[keep], q[keep], bound
