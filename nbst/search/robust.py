"""Robust solutions: cheap *and* insensitive, so that they survive a real engine.

A fixed-step engine (MuJoCo at h = 0.25 ms, docs/mujoco.md) resolves every impact one step
late, so each impact shifts the disks it involves by up to |dv| h and turns an oblique
collision's outgoing direction slightly; later collisions amplify that error, and a solution
whose motion is a chain of glancing strikes, or whose disks end near the edge of their target
neighbourhood, loses its signature. Robust mode (``nbst solve --robust``,
``solve(..., robust=True)``) changes what the search optimizes and what it writes:

1. **noisy score in the search** (``robust_k`` > 0): every candidate is also simulated with
   its disks' *start positions* shifted by ``robust_k`` fixed draws
   ``x0_i + sigma zeta[k, i]``, zeta ~ N(0, I), sigma = ``SHIFT_STEPS`` x h x (the
   candidate's fastest speed), h = ``robust_timestep``. Its cost is the worst over the
   unshifted run and the shifted ones, its signature the AND of theirs (the disks within R
   in every one of them). The signature machinery, elitism and polish then work on that
   score unchanged: order counts the disks that are on target *robustly*.
2. **archive**: after every chunk of the search the population members of the highest
   order seen are kept (deduplicated, the ``robust_archive`` cheapest by the search's score);
3. **final choice**: the search's best and the archive are rescored under ``robust_samples``
   fresh draws: (lowest order over the draws, then the ``QUANTILE`` of the largest distance
   to its target among the disks on target), the ``robust_polish`` best are polished towards
   the target centres of their on-target disks (:func:`polish_on_target`) and kept polished
   where that scores at least as well; the best score is the solution.

Why shifted starts: MuJoCo's error is made *at* each impact (measured, docs/mujoco.md) and a
shift of the start moves the impact geometry of every first collision by the same amount
whenever it happens, where a velocity error would be negligible for an early impact. The
per-impact error |dv| h with a uniformly random phase averages ~ v h / 2 for a relative speed
v, hence SHIFT_STEPS = 0.5; measured on over5 solutions, the median final error under these
shifts matches MuJoCo's per-disk error within a factor ~2 (docs/results/disks.md, "Robust
solutions"). The score does not run MuJoCo (``import nbst`` does not import it).

Everything is a function of the seed: the draws come from streams of their own
(``np.random.default_rng([seed, key])``), so the search's random numbers are untouched.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numba import njit

from nbst.constants import MAX_EVENTS
from nbst.problem import Problem
from nbst.search.loop import evaluate_one, loop_scratch, problem_arrays
from nbst.search.ops import limit_crossings
from nbst.search.polish import LAMBDA0, LAMBDA_DOWN, LAMBDA_MAX, LAMBDA_MIN, LAMBDA_UP, LAMBDA_UP_SINGULAR, RIDGE
from nbst.sim import evaluate
from nbst.sim.jacobian import final_jacobian

__all__ = ["TIMESTEP", "SHIFT_STEPS", "SEARCH_SAMPLES", "SAMPLES", "QUANTILE", "ARCHIVE_SIZE", "POLISH_TOP",
           "POLISH_SIMS", "MARGIN_POWER", "SEARCH_STREAM", "CHOICE_STREAM", "draws", "shift_sigma", "shift_starts",
           "RobustDraws", "robust_eval", "RobustScore", "score", "robust_score", "RobustArchive", "polish_on_target",
           "choose"]

#: The fixed step of the engine the solution must survive (s): MuJoCo's default in nbst.
TIMESTEP = 0.00025
#: Start shift std per axis, in steps of travel at the candidate's fastest speed (module doc).
SHIFT_STEPS = 0.5
#: Shifts per candidate during the search (``robust_k``): a candidate costs 1 + K simulations
#: (fewer: scoring stops once no disk is left on target); the same draws for every candidate,
#: so a candidate's score is a function of its velocities.
SEARCH_SAMPLES = 8
#: Shifts per candidate in the final choice (fresh draws): enough for a 90 % quantile.
SAMPLES = 64
#: Quantile (over the shifted runs) of the on-target disks' largest distance that the final choice uses.
QUANTILE = 0.9
#: Candidates kept in the archive (the cheapest of the top order, by the search's score).
ARCHIVE_SIZE = 256
#: Candidates polished in the final choice, and the simulation budget of each polish.
POLISH_TOP = 16
POLISH_SIMS = 60
#: The final polish minimizes sum d_i^MARGIN_POWER over the on-target disks: close to the
#: largest distance (the margin), smooth enough for Gauss-Newton steps.
MARGIN_POWER = 8
#: Keys of the noise streams (``np.random.default_rng([seed, key])``).
SEARCH_STREAM, CHOICE_STREAM = 0x726F62, 0x726F63


def draws(problem: Problem, rng: np.random.Generator, k: int) -> tuple[np.ndarray, np.ndarray]:
    """K standard-normal start shifts zeta (K, N, 2) and, per draw, the largest sigma (K,) that
    keeps every shifted start inside the box and clear of the others (0 where the problem's
    starts touch: that draw then shifts nothing)."""
    k = int(k)
    zeta = rng.standard_normal((k, problem.n, 2))
    x0 = np.asarray(problem.start, float)
    r = np.asarray(problem.radius, float)
    lo, hi = r[:, None], np.asarray(problem.box, float)[None, :] - r[:, None]
    smax = np.full(k, np.inf)
    d = x0[:, None] - x0[None]
    gap = np.hypot(d[..., 0], d[..., 1]) - (r[:, None] + r[None])
    iu = np.triu_indices(problem.n, 1)
    with np.errstate(divide="ignore", invalid="ignore"):
        for q in range(k):
            z = zeta[q]
            # walls: x0 + s z within [r, W - r]
            room = np.where(z > 0, (hi - x0) / z, np.where(z < 0, (lo - x0) / z, np.inf))
            s = float(room.min())
            # pairs: |x0_i - x0_j + s (z_i - z_j)| >= r_i + r_j; sufficient (triangle inequality, half
            # the gap kept): s |z_i - z_j| <= gap / 2
            dz = np.hypot(*(z[:, None] - z[None]).transpose(2, 0, 1))
            if iu[0].size:
                s = min(s, float(np.min(np.where(dz[iu] > 0, 0.5 * gap[iu] / dz[iu], np.inf))))
            smax[q] = max(s, 0.0)
    return zeta, smax


@njit(cache=True, error_model="numpy")
def shift_sigma(v, cue_idx, shift):
    """sigma of a candidate: shift (= SHIFT_STEPS x h) x its fastest cueable speed."""
    top = 0.0
    for q in range(cue_idx.shape[0]):
        i = cue_idx[q]
        top = max(top, math.sqrt(v[i, 0] * v[i, 0] + v[i, 1] * v[i, 1]))
    return shift * top


@njit(cache=True, inline="always", error_model="numpy")
def shift_starts(x0, z, s, px0):
    """px0 = x0 + s z: the start positions shifted by one draw z (N, 2) of scale s."""
    for i in range(x0.shape[0]):
        px0[i, 0] = x0[i, 0] + s * z[i, 0]
        px0[i, 1] = x0[i, 1] + s * z[i, 1]


class RobustDraws(NamedTuple):
    """The fixed start shifts of the search's robust score (``draws``)."""

    zeta: np.ndarray  # (K, N, 2) standard normal
    smax: np.ndarray  # (K,) the largest scale each draw allows


@njit(cache=True, error_model="numpy")
def robust_eval(pa, v, R, max_events, rd, shift, cost, sig, stop_early, px0, scr):
    """Search score of v (N, 2) whose unshifted (cost, sig) are given: the worst cost and the
    AND of the signatures over the unshifted run and the K runs from pa.x0 + sigma rd.zeta[k]
    (sigma = ``shift_sigma``, capped by rd.smax[k]). Returns (cost, signature, simulations run);
    with stop_early, stops once no disk is left acceptable (the cost is then a lower bound:
    a search that uses the AND rejects such a candidate whatever its cost).
    pa: ``nbst.search.loop.ProblemArrays``; scr: its ``LoopScratch``; px0 (N, 2) scratch."""
    sims = 0
    sigma = shift_sigma(v, pa.cue_idx, shift)
    for k in range(rd.zeta.shape[0]):
        if stop_early and sig == 0:
            break
        shift_starts(pa.x0, rd.zeta[k], min(sigma, rd.smax[k]), px0)
        c, sg, trunc = evaluate_one(px0, v, pa.radius, pa.mass, pa.target, pa.W, pa.H, pa.t_final, R, max_events,
                                    scr.work, scr.fin, scr.vel, scr.no_t, scr.no_i, scr.no_s)
        sims += 1
        if trunc:
            return np.inf, np.int64(0), sims
        cost = max(cost, c)
        sig = sig & sg
    return cost, sig, sims


@njit(cache=True, error_model="numpy")
def _score_kernel(pa, V, R, max_events, rd, shift, cost, sig, worst):
    """Every candidate V[m] unshifted (column 0) and under every draw (columns 1..K):
    cost (M, K+1), signature (M, K+1), and the largest distance to its target among the disks
    on target in the unshifted run (M, K+1; 0 if none is)."""
    n = pa.x0.shape[0]
    scr = loop_scratch(n, 1)
    px0 = np.empty((n, 2))
    for m in range(V.shape[0]):
        sigma = shift_sigma(V[m], pa.cue_idx, shift)
        for k in range(rd.zeta.shape[0] + 1):
            if k == 0:
                px0[:, :] = pa.x0
            else:
                shift_starts(pa.x0, rd.zeta[k - 1], min(sigma, rd.smax[k - 1]), px0)
            c, sg, trunc = evaluate_one(px0, V[m], pa.radius, pa.mass, pa.target, pa.W, pa.H, pa.t_final, R,
                                        max_events, scr.work, scr.fin, scr.vel, scr.no_t, scr.no_i, scr.no_s)
            cost[m, k] = c
            sig[m, k] = sg
            d = 0.0
            for i in range(n):
                if (sig[m, 0] >> i) & 1 == 0:
                    continue
                dx = scr.fin[i, 0] - pa.target[i, 0]
                dy = scr.fin[i, 1] - pa.target[i, 1]
                d = max(d, math.sqrt(dx * dx + dy * dy))
            worst[m, k] = np.inf if trunc else d


@dataclass(frozen=True)
class RobustScore:
    """Scores of M candidates under the same K shifts.

    order : (M,) int, lowest order over the unshifted run and the shifted ones
    kept  : (M,) float, fraction of shifted runs with the unshifted signature
    worst : (M,) float, QUANTILE of the largest distance to its target among the disks on
            target in the unshifted run (the margin left: R - worst), units
    cost  : (M,) float, QUANTILE of the cost, units^2
    """

    order: np.ndarray
    kept: np.ndarray
    worst: np.ndarray
    cost: np.ndarray

    def key(self, m: int) -> tuple:
        """Sort key of candidate m, lower is better: (-order, worst distance)."""
        return (-int(self.order[m]), float(self.worst[m]))

    def row(self, m: int) -> dict:
        return {"order": int(self.order[m]), "kept": float(self.kept[m]), "worst_distance": float(self.worst[m]),
                "cost_quantile": float(self.cost[m])}


def score(problem: Problem, V, zeta, smax, *, timestep: float = TIMESTEP, quantile: float = QUANTILE,
          max_events: int | None = None) -> RobustScore:
    """Score candidates V (M, N, 2), units/s, under the start shifts (zeta, smax) of :func:`draws`."""
    V = np.ascontiguousarray(np.asarray(V, dtype=np.float64).reshape(-1, problem.n, 2))
    M, K = V.shape[0], zeta.shape[0]
    cost = np.empty((M, K + 1))
    sig = np.empty((M, K + 1), np.int64)
    worst = np.empty((M, K + 1))
    ka = problem.kernel_arrays()
    pa = problem_arrays(problem, np.zeros((0, 2), np.int64))
    rd = RobustDraws(np.ascontiguousarray(zeta, dtype=np.float64), np.ascontiguousarray(smax, dtype=np.float64))
    _score_kernel(pa, V, ka.R, int(MAX_EVENTS if max_events is None else max_events), rd,
                  SHIFT_STEPS * float(timestep), cost, sig, worst)
    order = np.array([min(int(s).bit_count() for s in row) for row in sig], dtype=np.int64)
    kept = (sig[:, 1:] == sig[:, :1]).mean(axis=1) if K else np.ones(M)
    return RobustScore(order=order, kept=kept, worst=np.quantile(worst, quantile, axis=1, method="higher"),
                       cost=np.quantile(cost, quantile, axis=1, method="higher"))


def robust_score(problem: Problem, velocities, *, seed: int = 0, samples: int = SAMPLES,
                 timestep: float = TIMESTEP, quantile: float = QUANTILE) -> dict:
    """The final choice's score of one solution (N, 2) under ``samples`` draws from ``seed``:
    {order, kept, worst_distance, cost_quantile} (see :class:`RobustScore`)."""
    zeta, smax = draws(problem, np.random.default_rng([int(seed), CHOICE_STREAM]), samples)
    return score(problem, velocities, zeta, smax, timestep=timestep, quantile=quantile).row(0)


class RobustArchive:
    """The distinct population members of the highest order seen, the ``size`` cheapest."""

    def __init__(self, n: int, size: int = ARCHIVE_SIZE):
        self.size = int(size)
        self.order = 0
        self.V = np.zeros((0, n, 2))
        self.cost = np.zeros(0)
        self.seen = 0

    def add(self, V, cost, sig) -> None:
        """Offer population members V (P, N, 2) with their scores (P,) and signatures (P,)."""
        if len(cost) == 0:
            return
        order = np.array([int(s).bit_count() for s in sig])
        top = int(order.max())
        if top < self.order:
            return
        if top > self.order:
            self.order = top
            self.V, self.cost = self.V[:0], self.cost[:0]
        k = (order == top) & np.isfinite(cost)
        V = np.concatenate([self.V, np.asarray(V)[k]])
        c = np.concatenate([self.cost, np.asarray(cost)[k]])
        _, first = np.unique(V.reshape(V.shape[0], -1), axis=0, return_index=True)
        keep = np.sort(first)  # arrival order among equals: deterministic
        keep = np.sort(keep[np.argsort(c[keep], kind="stable")[: self.size]])
        self.seen += int(k.sum())
        self.V, self.cost = V[keep], c[keep]


def polish_on_target(problem: Problem, velocities, *, max_sims: int = POLISH_SIMS, power: int = MARGIN_POWER):
    """Levenberg-Marquardt that pulls the disks already on target towards their target centres,
    the farthest first: it minimizes sum_i d_i^power over the on-target disks (power 8: close
    to minimizing the largest d_i, the margin R - d that a real engine's error eats).

    ``nbst.search.polish`` minimizes the whole cost, so a disk that cannot reach its target (a noncueable
    disk nothing strikes) pulls the others off theirs, and a sum of squares trades the farthest
    disk's margin for the others'. A step is accepted only if it lowers the objective without
    losing an on-target disk. Returns (velocities (N, 2), simulations run). Analytic Jacobian
    (``nbst.sim.jacobian``), damping as ``nbst.search.polish``.
    """
    v = np.array(velocities, dtype=np.float64)
    cue = np.flatnonzero(problem.cueable)
    cue_idx = cue.astype(np.int64)
    ka = problem.kernel_arrays()
    R = float(problem.target_radius)
    h = 0.5 * power

    def dist(final):
        return np.hypot(*(final - problem.target).T)

    final, J = final_jacobian(problem, v)
    mask = dist(final) <= R
    if not mask.any():
        return v, 1
    idx = np.flatnonzero(mask)
    scale = R  # distances in units of R keep d^8 well scaled
    obj = float(((dist(final)[idx] / scale) ** power).sum())
    sims, lam = 1, LAMBDA0
    while sims < max_sims:
        e = (final - problem.target)[idx] / scale  # (m, 2)
        d = np.maximum(np.hypot(e[:, 0], e[:, 1]), 1e-300)
        rho = d ** h  # objective = sum rho^2
        # d rho_i / d v = h d_i^(h - 2) e_i . dfinal_i / dv  (dfinal in units of R)
        Jr = np.stack([h * d[q] ** (h - 2) * (e[q, 0] * J[2 * i] + e[q, 1] * J[2 * i + 1]) / scale
                       for q, i in enumerate(idx)])
        A = Jr.T @ Jr
        g = Jr.T @ rho
        dmax = float(np.max(np.diag(A)))
        if dmax == 0.0:
            break
        accepted = False
        while sims < max_sims and lam < LAMBDA_MAX:
            M = A + np.diag(lam * np.diag(A) + RIDGE * dmax * (1.0 + lam))
            try:
                step = np.linalg.solve(M, -g)
            except np.linalg.LinAlgError:
                lam *= LAMBDA_UP_SINGULAR
                continue
            vn = v.copy()
            vn[cue] += step.reshape(-1, 2)
            limit_crossings(vn, cue_idx, ka.radius, ka.W, ka.H, ka.t_final)
            dn = dist(evaluate(problem, vn[None])[0][0])
            sims += 1
            on = float(((dn[idx] / scale) ** power).sum())
            if np.all(dn[idx] <= R) and on < obj:
                v, obj, accepted = vn, on, True
                lam = max(lam / LAMBDA_DOWN, LAMBDA_MIN)
                break
            lam *= LAMBDA_UP
        if not accepted or sims >= max_sims:
            break
        final, J = final_jacobian(problem, v)  # its simulation counts too
        sims += 1
    return v, sims


def choose(problem: Problem, V, *, seed: int, samples: int = SAMPLES, timestep: float = TIMESTEP,
           quantile: float = QUANTILE, polish_top: int = POLISH_TOP, polish_sims: int = POLISH_SIMS):
    """The most robust of the candidates V (M, N, 2), polished where that scores at least as well.

    Returns (velocities (N, 2), info dict for ``meta["robust"]``: candidates, chosen index,
    polished count, its score and that of V[0]). Deterministic in ``seed``.
    """
    V = np.asarray(V, dtype=np.float64).reshape(-1, problem.n, 2)
    zeta, smax = draws(problem, np.random.default_rng([int(seed), CHOICE_STREAM]), samples)
    sc = score(problem, V, zeta, smax, timestep=timestep, quantile=quantile)
    cand = [V[m] for m in range(V.shape[0])]
    keys = [sc.key(m) for m in range(V.shape[0])]
    rows = [sc.row(m) for m in range(V.shape[0])]
    first = dict(rows[0]) if rows else None
    polished = 0
    if polish_top > 0 and V.shape[0]:
        top = sorted(range(V.shape[0]), key=lambda m: (keys[m], m))[:polish_top]
        Vp = np.array([polish_on_target(problem, V[m], max_sims=polish_sims)[0] for m in top])
        sp = score(problem, Vp, zeta, smax, timestep=timestep, quantile=quantile)
        for q, m in enumerate(top):
            if sp.key(q) <= keys[m]:
                cand[m], keys[m], rows[m] = Vp[q], sp.key(q), sp.row(q)
                polished += 1
    k = min(range(len(cand)), key=lambda m: (keys[m], m))
    info = {"candidates": int(V.shape[0]), "chosen": int(k), "polished": polished, "samples": int(samples),
            "timestep": float(timestep), "shift_steps": SHIFT_STEPS, "quantile": float(quantile),
            "score": rows[k], "score_of_search_best": first}
    return np.array(cand[k]), info
