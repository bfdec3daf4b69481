"""The many-body search: problems past the compiled loop's 63 disks, solved by local repair.

At fixed density a disk meets only its neighbours, so a choreography of N disks is mostly
independent small problems. The search works on the whole motion and repairs it locally:

1. **Directed start.** Every cueable disk flies straight to its target (image (0, 0) of
   the mirror unfolding, the paper's directed randomize): the shortest path, so the fewest
   crossings. A disk that meets nothing lands exactly.
2. **Missing disks, found by the exact simulator.** One simulation of all N disks (the
   cell-grid kernel, O(1) per event) says which disks miss their targets; the disk-disk
   events form a graph whose components holding a missing disk are the *conflicts*.
3. **Moves**, each kept only if the whole motion gets better (``run_many`` has the rounds):
   two-disk contacts in closed form (``nbst.search.aim.pair_contact``), straight and bank
   shots, strikes on resting disks that must move (``_strikes``), chains (a contact whose
   group is polished with its own Jacobian: the blocked Jacobian of the whole problem, no
   N x N matrix), cleared and re-paired neighbourhoods, and optionally each conflict's polish
   and windowed sub-searches. "Better" counts the disks not landed exactly first, or, when a
   resting disk must move, the disks outside R first (``ManyParams.order_first``).

The best whole motion is kept; the result is never worse than the directed start. Trials
are counted in whole-problem simulations: one of m disks counts m / N.

Length: ~570 lines, past the house's ~500: the search's moves (contacts, strikes, chains, cleared
neighbourhoods, windowed sub-searches) share one state object and its acceptance rule, and
stay together so that rule is written once (the local pieces they work on: ``nbst.search.local``).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from nbst.constants import GA_MAX_DISKS
from nbst.problem import Problem
from nbst.search.aim import bank_velocity, pair_contact, strike_velocity
from nbst.search.driver import run_search as signature_search
from nbst.search.local import conflicts, labels, must_be_struck, nearest, subproblem
from nbst.search.params import ProgressCallback, SearchProgress, StopReason
from nbst.search.polish import polish
from nbst.search.variants import SolveRequest
from nbst.sim import evaluate, simulate

__all__ = ["ALGORITHM_MANY", "ManyParams", "ManyRun", "run_many"]

#: ``meta["algorithm"]`` of a many-body search's solution.
ALGORITHM_MANY = "nbst-many"


@dataclass(frozen=True)
class ManyParams:
    """The many-body search's choices, each with why."""

    #: Sub-search trial budget per disk of a conflict (a 2-disk conflict gets 2 x this):
    #: planted conflicts of 2-6 disks are solved exactly in a few thousand trials.
    sub_trials_per_disk: int = 3_000
    #: Partners a missing disk tries a two-disk contact with (missing ones first, then nearest).
    #: Planted all-cueable N = 250, seeds 1-6, 60 s: 237-248 disks exact (mean 240) with 30,
    #: 223-246 (mean 234) with 10; the nearest 20 whether missing or not: mean 239.
    partners: int = 30
    #: Two-disk contacts per missing disk extended into chains (the disks they meet, polished).
    chains: int = 4
    #: Chance that a cleared neighbourhood with as many misses as before (but another
    #: arrangement) is kept: a walk on the plateau. The best motion is kept apart.
    plateau: float = 0.3
    #: Neighbours (beyond the conflict's own size) a cleared neighbourhood takes in.
    neighbours: int = 6
    #: From this many disks, candidates are first simulated among the disks near them only
    #: (``_Search.local_filter``): a whole simulation of 1,000 disks costs ~20 local ones.
    local_from: int = 400
    #: Cueable disks grouped with a resting disk that must move (its possible strikers).
    strikers: int = 3
    #: Nearest cueable disks that aim a strike at a resting disk that must move (``_strikes``).
    strike_from: int = 10
    #: Disks a failing conflict grows by, per failure (its nearest outsiders).
    grow: int = 2
    #: Largest conflict handed to the sub-search (its compiled loop's limit).
    max_conflict: int = GA_MAX_DISKS
    #: Rounds without a better whole motion before the search stops.
    patience_rounds: int = 20
    #: Simulations of one conflict's polish (Levenberg-Marquardt on its own Jacobian).
    polish_sims: int = 60
    #: Sub-searches per conflict and round (different seeds: different solutions to try); 0
    #: (the default) skips step 3: measured on planted problems of 250 disks, its windowed
    #: sub-searches repaired 5 of 136 conflicts and cost half the time.
    searches: int = 0
    #: A sub-search's window: this many largest radii around its disks (times 1 + failures).
    window: float = 8.0
    #: Sub-search variant (nbst's, with the backward planner).
    variant: str = "nbst"
    #: What the search counts first: disks outside R (the paper's order; True) or disks not
    #: landed exactly (False). None: the order when a resting disk must move (one strike has
    #: two unknowns for four landing coordinates, so such a disk and its striker rarely both
    #: land exactly), exactness otherwise. Measured on planted N = 100 with 10 resting disks,
    #: seeds 1-3 (``benchmarks/bench_scale.py --part noncue``): 64, 60 and 81 disks within R
    #: with the order first, 56, 50 and 70 with exactness first.
    order_first: bool | None = None


def _score(final: np.ndarray, target: np.ndarray, miss2: float, R2: float,
           order_first: bool) -> tuple[int, int, float]:
    """A motion's score, lower is better: (disks whose squared miss exceeds miss2, 0, cost), or
    with ``order_first`` (disks outside the target radius (squared: R2), those disks, cost): the
    paper's order first, so a move that brings a disk within R is kept even if it costs another
    disk its exact landing."""
    e2 = np.sum((np.asarray(final) - target) ** 2, axis=1)
    inexact = int(np.count_nonzero(e2 > miss2))
    if order_first:
        return (int(np.count_nonzero(e2 > R2)), inexact, float(e2.sum()))
    return (inexact, 0, float(e2.sum()))


def _candidates(problem: Problem, a: int, V: np.ndarray, err2: np.ndarray, miss2: float, partners: int, scratch):
    """Velocity changes that could bring missing disk a home, cheapest first: (disks, rows).

    * two-disk contacts with a partner b (``nbst.search.aim.pair_contact``: a and b touch once
      and both land exactly), partners that miss too first, then the nearest;
    * a straight shot again (if a is not on one);
    * bank shots off one or two walls (images with |kx|, |ky| <= 1).
    """
    ka = problem.kernel_arrays()
    W, H, T = ka.W, ka.H, ka.t_final
    out = []
    if problem.cueable[a]:
        d = np.hypot(*(ka.start - ka.start[a]).T)
        d[a] = np.inf
        order = np.lexsort((d, err2 <= miss2))  # missing first, each group nearest first
        order = order[order != a][:partners]
        for b in order.tolist():
            if not problem.cueable[b]:
                continue
            k = pair_contact(ka.start[a], ka.start[b], ka.target[a], ka.target[b], ka.mass[a], ka.mass[b],
                             ka.radius[a], ka.radius[b], W, H, T, 200, scratch)
            for q in range(k):
                out.append((np.array([a, b]), np.array([scratch[q, 0:2], scratch[q, 2:4]])))
        straight = (ka.target[a] - ka.start[a]) / T
        if np.any(V[a] != straight):
            out.append((np.array([a]), straight[None]))
        vb = np.empty(2)
        for kx in (-1, 0, 1):
            for ky in (-1, 0, 1):
                if kx or ky:
                    bank_velocity(ka.start[a], ka.target[a], ka.radius[a], W, H, T, kx, ky, vb)
                    out.append((np.array([a]), vb.copy()[None]))
    return out


def _strikes(problem: Problem, b: int, strikers: int, keep: int, polish_sims: int):
    """Strikes that could send resting disk b home, best first: (disks, rows) as ``_candidates``.

    Each of the ``strikers`` cueable disks nearest b aims (``nbst.search.aim.strike_velocity``)
    at b's target or one of its 8 mirror images (b banks off walls on its way); the two disks
    alone (no other disk) rank the aims by (disks outside R, squared misses), and the ``keep``
    best are polished on the striker's velocity (b's landing and the striker's own, least
    squares) and offered polished and as aimed.
    """
    ka = problem.kernel_arrays()
    W, H, T = ka.W, ka.H, ka.t_final
    R2 = float(problem.target_radius) ** 2
    cue = nearest(problem, np.array([b]), np.array([b]), strikers, True)
    vb, out = np.empty(2), np.empty(2)
    aims = []
    for kx in (-1, 0, 1):
        for ky in (-1, 0, 1):
            bank_velocity(ka.start[b], ka.target[b], ka.radius[b], W, H, T, kx, ky, vb)
            aims.append(ka.start[b] + vb * T)
    ranked = []
    for c in cue.tolist():
        pair = subproblem(problem, np.array([c, b]), "strike")
        rows = []
        for aim in aims:
            t_hit = strike_velocity(ka.start[c], ka.radius[c], ka.mass[c], ka.start[b], ka.radius[b], ka.mass[b],
                                    aim, T, out)
            if 0.0 < t_hit < T:
                rows.append(out.copy())
        if not rows:
            continue
        Vs = np.zeros((len(rows), 2, 2))
        Vs[:, 0] = rows
        fin = evaluate(pair, Vs, jobs=1)[0]
        for q in range(len(rows)):
            e2 = np.sum((fin[q] - pair.target) ** 2, axis=1)
            ranked.append(((int(np.count_nonzero(e2 > R2)), float(e2.sum())), c, pair, Vs[q]))
    ranked.sort(key=lambda r: r[0])
    cands = []
    for _, c, pair, v2 in ranked[:keep]:
        v, _, _, _ = polish(pair, v2, max_sims=polish_sims)
        cands.append((np.array([c]), v[:1].copy()))
        cands.append((np.array([c]), v2[:1].copy()))
    return cands


class _Search:
    """The state of one many-body search: the current motion, its score and the counters."""

    def __init__(self, problem: Problem, prm: ManyParams, V: np.ndarray, miss2: float, max_trials: int, report,
                 jobs: int = 1):
        self.jobs = int(jobs)
        self.problem, self.prm, self.miss2, self.max_trials = problem, prm, miss2, max_trials
        self.R2 = float(problem.target_radius) ** 2
        self.order_first = prm.order_first if prm.order_first is not None else must_be_struck(problem)
        self.simulate = simulate
        self.report = report
        self.trials = 0.0
        self.stats = {"rounds": 0, "by_pair": 0, "by_shot": 0, "by_strike": 0, "by_chain": 0, "neighbourhoods": 0,
                      "by_neighbourhood": 0, "conflicts": 0, "by_polish": 0, "by_search": 0, "largest_conflict": 0,
                      "sub_trials": 0, "polish_sims": 0, "whole_sims": 0, "local_sims": 0}
        self.scratch = np.empty((8, 5))
        self.V = V
        self.tr = self.sim(V)
        self.score = self.score_of(self.tr)
        self.best: Any = None  # (score, velocities, trajectory) of the best whole motion so far
        self.keep_best()

    def sim(self, V):
        self.trials += 1
        self.stats["whole_sims"] += 1
        return self.simulate(self.problem, V)

    def evaluate(self, Vs):
        """Final positions of a batch of whole motions (``nbst.sim.evaluate`` on ``jobs`` threads;
        the scores do not depend on the threads)."""
        self.trials += len(Vs)
        self.stats["whole_sims"] += len(Vs)
        return evaluate(self.problem, Vs, jobs=self.jobs)[0]

    def score_of(self, tr) -> tuple[int, int, float]:
        """A motion's score (``_score`` of its final positions, as ``greedy`` scores a batch)."""
        return self.score_final(tr.final_positions)

    def score_final(self, final, target=None) -> tuple[int, int, float]:
        """``_score`` of final positions against ``target`` (default: the problem's), with this
        search's miss threshold, R and order rule."""
        target = self.problem.target if target is None else target
        return _score(final, target, self.miss2, self.R2, self.order_first)

    def err2(self, tr=None):
        tr = self.tr if tr is None else tr
        return np.sum((np.asarray(tr.final_positions) - self.problem.target) ** 2, axis=1)

    def greedy(self, disks, V, tr, score, stat=True):
        """For each missing disk of ``disks``: the first candidate (``_candidates``, then a
        contact extended into a chain) that makes the whole motion better. Returns the new
        (V, tr, score, number of changes kept)."""
        problem, prm, miss2, n = self.problem, self.prm, self.miss2, self.problem.n
        kept = 0
        for a in disks:
            err2 = np.sum((np.asarray(tr.final_positions) - problem.target) ** 2, axis=1)
            if err2[a] <= miss2 or self.trials >= self.max_trials:
                continue
            near = []
            done = False
            if problem.cueable[a]:
                cands = _candidates(problem, a, V, err2, miss2, prm.partners, self.scratch)
            else:
                cands = _strikes(problem, a, prm.strike_from, prm.chains, prm.polish_sims)
            if n >= prm.local_from:
                cands, near = self.local_filter(cands, V, tr)
            k = max(1, self.jobs)
            for c0 in range(0, len(cands), k):
                chunk = cands[c0:c0 + k]
                Vs = np.repeat(V[None], len(chunk), axis=0)
                for q, (disks2, rows) in enumerate(chunk):
                    Vs[q, disks2] = rows
                fin = self.evaluate(Vs)
                for q, (disks2, rows) in enumerate(chunk):
                    sn = self.score_final(fin[q])
                    if sn < score:
                        V, score, done = Vs[q].copy(), sn, True
                        tr = self.sim(V)
                        kept += 1
                        if stat:
                            self.stats["by_pair" if disks2.size == 2 else
                                       "by_shot" if problem.cueable[a] else "by_strike"] += 1
                        break
                    if disks2.size == 2:
                        near.append((sn, q + c0, Vs[q].copy()))
                if done:
                    break
            if not done:
                # a contact that lands a and its partner but sends a third disk off: polish the
                # disks it now meets, starting from there (a chain of contacts)
                near.sort(key=lambda c: (c[0], c[1]))
                for _, _, Vn in near[: prm.chains]:
                    trn = self.sim(Vn)
                    lab = labels(trn)
                    idx = np.flatnonzero(lab == lab[a]).astype(np.int64)
                    if idx.size < 3 or idx.size > prm.max_conflict:
                        continue
                    sub = subproblem(problem, idx, f"{problem.name}[{idx.size}]")
                    v, c, _, sims = polish(sub, Vn[idx], max_sims=prm.polish_sims, tol=miss2 * idx.size)
                    self.stats["polish_sims"] += sims
                    self.trials += sims * idx.size / n
                    if c > miss2 * idx.size:
                        continue
                    Vn = Vn.copy()
                    Vn[idx] = v
                    trn = self.sim(Vn)
                    sn = self.score_of(trn)
                    if sn < score:
                        V, tr, score = Vn, trn, sn
                        kept += 1
                        if stat:
                            self.stats["by_chain"] += 1
                        break
            if self.report():
                raise KeyboardInterrupt
        return V, tr, score, kept

    def local_filter(self, cands, V, tr):
        """Many disks: drop the candidates that do not even help the disks around them. Each
        candidate and the current motion are simulated on the disks near the changed paths
        only (within a margin of the distance the fast disks travel); a candidate goes on to
        a whole simulation if it scores better there. Returns (kept candidates, the rest as
        (score, index, velocities) for the chains)."""
        problem = self.problem
        ka = problem.kernel_arrays()
        T = ka.t_final
        box = np.array([ka.W, ka.H])
        speed = np.hypot(V[:, 0], V[:, 1])
        margin = float(np.quantile(speed, 0.99)) * T + 4.0 * float(ka.radius.max())
        fin = np.asarray(tr.final_positions)
        keep, rest = [], []
        for c, (disks2, rows) in enumerate(cands):
            pts = [ka.start[disks2], ka.target[disks2]]
            for f in (0.25, 0.5, 0.75):
                pts.append(ka.start[disks2] + rows * (f * T))
            pts = np.concatenate(pts)
            if np.any(pts < 0.0) or np.any(pts > box):
                keep.append((disks2, rows))  # a bank shot: judged whole
                continue
            lo, hi = pts.min(axis=0) - margin, pts.max(axis=0) + margin
            near = np.zeros(problem.n, bool)
            for P in (ka.start, fin, ka.target):
                near |= np.all((P >= lo) & (P <= hi), axis=1)
            near[disks2] = True
            Q = np.flatnonzero(near)
            if Q.size >= problem.n // 2:
                keep.append((disks2, rows))
                continue
            sub = subproblem(problem, Q, "local")
            Vq = np.stack([V[Q], V[Q]])
            loc = np.searchsorted(Q, disks2)
            Vq[1, loc] = rows
            self.trials += 2 * Q.size / problem.n
            self.stats["local_sims"] += 2

            f2 = evaluate(sub, Vq, jobs=1)[0]
            s_old = self.score_final(f2[0], sub.target)
            s_new = self.score_final(f2[1], sub.target)
            if s_new < s_old:
                keep.append((disks2, rows))
            elif disks2.size == 2:
                full = V.copy()
                full[disks2] = rows
                # the whole motion's counts, moved by what the candidate changed locally
                counts = tuple(new - old + whole for new, old, whole in zip(s_new[:2], s_old[:2], self.score[:2]))
                rest.append((counts + (s_new[2],), c, full))
        return keep, rest

    def neighbourhood(self, idx, rng):
        """Large-neighbourhood move: the conflict's disks and their nearest neighbours go back
        to straight shots and are paired again, in a random order; kept if the whole motion is
        better than before."""
        problem, prm = self.problem, self.prm
        S = np.union1d(idx, nearest(problem, idx, idx, prm.neighbours + idx.size, False)).astype(np.int64)
        # and the disks they touch now (a cleared disk's partner would be left on a contact
        # velocity with nobody to meet)
        ev = self.tr.events[self.tr.events["kind"] == 0]
        touch = np.isin(ev["i"], S) | np.isin(ev["j"], S)
        S = np.union1d(S, np.concatenate([ev["i"][touch], ev["j"][touch]]).astype(np.int64))
        rest = S[~problem.cueable[S]]  # resting disks: struck again by the cleared ones
        S = S[problem.cueable[S]]
        V = self.V.copy()
        V[S] = problem.straight_velocities()[S]
        tr = self.sim(V)
        score = self.score_of(tr)
        order = np.concatenate([rest[rng.permutation(rest.size)], S[rng.permutation(S.size)]])
        for _ in range(2):
            V, tr, score, kept = self.greedy(order.tolist(), V, tr, score, stat=False)
            if not kept:
                break
        self.stats["neighbourhoods"] += 1
        if score < self.score or (score[:2] == self.score[:2] and rng.random() < prm.plateau):
            # better, or as many misses and another arrangement: a walk on the plateau that
            # lets the next round find what this one could not (the best is kept apart)
            better = score < self.score
            self.V, self.tr, self.score = V, tr, score
            self.keep_best()
            self.stats["by_neighbourhood"] += int(better)
            return better
        return False

    def keep_best(self):
        if self.best is None or self.score < self.best[0]:
            self.best = (self.score, self.V.copy(), self.tr)

    def repair(self, idx, k, rng):
        """A conflict by its own polish, then by sub-searches in a window around it; the first
        repair that makes the whole motion better is kept."""
        problem, prm, miss2, n = self.problem, self.prm, self.miss2, self.problem.n
        if idx.size > prm.max_conflict:
            err2 = self.err2()[idx]
            core = idx[np.argsort(-err2, kind="stable")[: prm.max_conflict // 3]]
            idx = np.union1d(core, nearest(problem, core, core, prm.max_conflict - core.size, False))
        self.stats["conflicts"] += 1
        self.stats["largest_conflict"] = max(self.stats["largest_conflict"], int(idx.size))
        tol = miss2 * idx.size
        candidates = []
        sub = subproblem(problem, idx, f"{problem.name}[{idx.size}]")
        v, c, _, sims = polish(sub, self.V[idx], max_sims=prm.polish_sims, tol=tol)
        self.stats["polish_sims"] += sims
        self.trials += sims * idx.size / n
        if c <= tol:
            candidates.append(("polish", v))
        win = subproblem(problem, idx, f"{problem.name}[{idx.size}]",
                         margin=prm.window * float(problem.radius.max()) * (1 + k))
        for _ in range(prm.searches):
            budget = prm.sub_trials_per_disk * idx.size
            run = signature_search(win, SolveRequest(seed=int(rng.integers(2**62)), max_trials=budget,
                                                     patience=budget, target_cost=tol, variant=prm.variant,
                                                     robust=None))
            used = run.result.trials
            self.stats["sub_trials"] += used
            self.trials += used * idx.size / n
            if run.result.cost <= tol:
                candidates.append(("search", run.result.velocities))
        for how, v in candidates:
            Vn = self.V.copy()
            Vn[idx] = v
            trn = self.sim(Vn)
            sn = self.score_of(trn)
            if sn < self.score:
                self.V, self.tr, self.score = Vn, trn, sn
                self.stats["by_" + how] += 1
                return True
        return False


@dataclass(frozen=True)
class ManyRun:
    """What :func:`run_many` found: the best whole motion and how the search went.

    velocities : (N, 2) float, units/s; trials : whole-problem simulations (rounded up);
    stopped : a ``StopReason`` value or None; wall_time : seconds; history : [trial, cost, order]
    per better whole motion; stats : rounds, moves kept by kind, conflicts, simulations
    """

    velocities: np.ndarray
    trials: int
    stopped: str | None
    wall_time: float
    history: list
    stats: dict


def run_many(problem: Problem, *, seed: int, max_trials: int, patience: int, target_cost: float,
             callback: ProgressCallback | None = None, params: ManyParams | None = None,
             start: np.ndarray | None = None, jobs: int | None = None) -> ManyRun:
    """Solve ``problem`` (any N) by local repair; returns a :class:`ManyRun`.

    target_cost : stop once the whole cost is <= this; a disk counts as missing while its
                  squared miss exceeds target_cost / N
    max_trials  : budget in whole-problem simulations (a sub-search trial of m disks: m / N)
    patience    : stop after this many trials without a better whole motion (0: never), or
                  ``params.patience_rounds`` rounds
    start       : velocities to start from (default: straight to each target)
    jobs        : threads that simulate candidates side by side (None: every core); the result
                  does not depend on it

    Every change is kept only if the whole motion gets better: fewer missing disks, or as
    many and a lower cost (so the result is never worse than the start). Each round:
    1. each missing disk tries two-disk contacts, straight and bank shots, and chains;
    2. if that changed nothing: each conflict is cleared (it and its neighbours back to
       straight shots) and paired again in a random order;
    3. if that changed nothing either: each conflict's own polish and windowed sub-searches.
    """
    prm = params or ManyParams()
    rng = np.random.default_rng(seed)
    n = problem.n
    t0 = time.perf_counter()
    box: list = []

    def report() -> bool:
        if callback is None or not box:
            return False
        s = box[0]
        # the best motion so far (fewest disks missing, then the lowest cost), not the one in repair
        score, best = (s.score, s.tr) if s.best is None or s.score < s.best[0] else (s.best[0], s.best[2])
        return bool(callback(SearchProgress(trials=int(s.trials), best_cost=float(best.cost),
                                            best_order=int(best.order), elapsed=time.perf_counter() - t0,
                                            population=score[int(s.order_first)], phase="repair",
                                            stall=(idle[0], prm.patience_rounds))))

    V = problem.straight_velocities() if start is None else np.array(start, float)
    if jobs is None:
        from nbst.parallel import default_jobs

        jobs = default_jobs()
    S = _Search(problem, prm, V, max(float(target_cost), 0.0) / n, max_trials, report, jobs)
    box.append(S)
    last_better = S.trials
    idle = [0]  # rounds since the whole motion last got better (the progress report reads it)
    tries = np.zeros(n, np.int64)
    history = [[int(S.trials), float(S.tr.cost), S.tr.order]]
    stopped = None
    try:
        while True:
            if S.best[0][2] <= target_cost:
                stopped = StopReason.TARGET_COST
                break
            if S.trials >= max_trials:
                stopped = StopReason.MAX_TRIALS
                break
            if (patience and S.trials - last_better >= patience) or idle[0] >= prm.patience_rounds:
                stopped = StopReason.PATIENCE
                break
            S.stats["rounds"] += 1
            before = S.score
            missing = np.flatnonzero(S.err2() > S.miss2).tolist()
            S.V, S.tr, S.score, _ = S.greedy(missing, S.V, S.tr, S.score)
            if S.score == before:
                for idx in sorted(conflicts(problem, S.tr, S.miss2, prm.strikers), key=len):
                    if S.trials >= max_trials:
                        break
                    if np.all(S.err2()[idx] <= S.miss2):
                        continue
                    S.neighbourhood(idx, rng)
            if S.score == before and prm.searches > 0:
                for idx in sorted(conflicts(problem, S.tr, S.miss2, prm.strikers), key=len):
                    if S.trials >= max_trials:
                        break
                    if np.all(S.err2()[idx] <= S.miss2):
                        continue
                    k = int(tries[idx].max())
                    tries[idx] += 1
                    if k >= 1:
                        idx = np.union1d(idx, nearest(problem, idx, idx, prm.grow * k, False)).astype(np.int64)
                    if S.repair(idx, k, rng):
                        tries[idx] = 0
            S.keep_best()
            if S.score < before:
                last_better = S.trials
                idle[0] = 0
                history.append([int(S.trials), float(S.tr.cost), S.tr.order])
            else:
                idle[0] += 1
            if report():
                stopped = StopReason.CALLBACK
                break
    except KeyboardInterrupt:
        stopped = StopReason.INTERRUPTED
    wall = time.perf_counter() - t0
    S.keep_best()
    return ManyRun(velocities=S.best[1], trials=int(math.ceil(S.trials)),
                   stopped=None if stopped is None else stopped.value, wall_time=wall, history=history,
                   stats=S.stats)
