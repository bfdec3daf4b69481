"""The signature search's driver: ``run_search`` packs a problem and its
:class:`~nbst.search.params.SearchParams` into arrays, run the compiled loop
(``nbst.search.loop``, or ``nbst.search.nbst_loop`` for nbst's variant) chunk by chunk
with progress and Ctrl-C, and unpack the best solution with its statistics.
"""
from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from nbst._version import __version__
from nbst.constants import GA_MAX_DISKS, many_body
from nbst.errors import SolveError
from nbst.outputs import signals_deferred
from nbst.problem import Problem
from nbst.search import loop as _L, nbst_loop as S
from nbst.search.loop import ChunkResult
from nbst.search.ops import CULL_SUBSUMED, CULL_WORST, SIZE, Population, new_population, seed_state
from nbst.search.params import (ALGORITHM, ALGORITHM_NBST, ProgressCallback, SearchParams, SearchProgress,
                                StopReason, check_run, mirror_images, variant_params)
from nbst.search.planner import plan
from nbst.search.robust import SEARCH_STREAM, SHIFT_STEPS, RobustDraws, choose, draws
from nbst.search.variants import VARIANTS, SolveRequest
from nbst.seeds import resolve_seed
from nbst.sim import evaluate
from nbst.solution import SolveResult, signature_string

__all__ = ["HISTORY0", "SearchRun", "run_search", "SearchStats"]

#: Room of the improvement history at the start (doubled whenever the loop fills it).
HISTORY0 = 1024


@dataclass
class _State:
    """The arrays a search carries between chunks (mutable by design: the kernel writes them)."""

    pop: Population
    st: np.ndarray
    best_cost: np.ndarray
    best_v: np.ndarray
    rng: np.ndarray
    hist_t: np.ndarray
    hist_c: np.ndarray
    hist_o: np.ndarray
    op_count: np.ndarray = field(default_factory=lambda: np.zeros((len(_L.OP_NAMES), 2), np.int64))

    @property
    def pop_size(self) -> int:
        """Members in the population now."""
        return int(self.pop.state[SIZE])

    def arrays(self) -> _L.SearchArrays:
        """The state as the compiled loops take it."""
        return _L.SearchArrays(self.pop, self.st, self.best_cost, self.best_v, self.rng, self.hist_t, self.hist_c,
                               self.hist_o, self.op_count)

    def grow_history(self) -> None:
        """Double the improvement history's room (the loop returned HISTORY_FULL)."""
        k = len(self.hist_t)
        self.hist_t = np.concatenate([self.hist_t, np.zeros(k, np.int64)])
        self.hist_c = np.concatenate([self.hist_c, np.zeros(k)])
        self.hist_o = np.concatenate([self.hist_o, np.zeros(k, np.int64)])


def _pack(problem: Problem, params: SearchParams, *, max_trials: int, patience: int, target_cost: float | None,
          record_every: int = 0) -> _L.LoopParams:
    """The loop's parameters (``nbst.search.loop.LoopParams``) from the search parameters and run options."""
    w = np.asarray(params.op_weights, float)
    w = w / w.sum()
    return _L.LoopParams(
        pop_limit=int(params.pop_limit), sig_limit=int(params.sig_limit), diversity=int(params.diversity),
        init_max_tries=int(params.init_max_tries), init_population=int(params.init_population),
        senate=int(params.senate), engineered=int(params.engineered),
        cull={"subsumed": CULL_SUBSUMED, "worst": CULL_WORST}[params.cull], elitism=int(params.elitism),
        hard_limit=int(params.hard_limit), max_trials=int(max_trials), patience=int(patience),
        max_events=int(params.max_events), record_every=int(record_every),
        R=float(params.signature_radius if params.signature_radius is not None else problem.target_radius),
        creep_sigma=float(params.creep_fraction * problem.target_radius / problem.t_final),
        target_cost=-math.inf if target_cost is None else float(target_cost),
        p_directed_init=float(params.p_directed_init),
        w_creep=float(w[0]), w_directed=float(w[1]), w_uniform=float(w[2]), w_crossover=float(w[3]))


@dataclass(frozen=True, eq=False)
class SearchRun:
    """A finished search: its result and the final population.

    Args:
        result: the :class:`~nbst.solution.SolveResult`.
        velocities: (P, N, 2) float64 array, units/s: the final population's candidates.
        costs: (P,) float64 array, units^2.
        signatures: (P,) int64 array of bitmasks (bit i: disk i within R).
        recorded: (M, N, 2) float64 array: the candidates of every ``record_every``-th trial
            (empty unless asked).

    Returns:
        The run, as ``nbst.search.run_search`` returns it.
    """

    result: SolveResult
    velocities: np.ndarray
    costs: np.ndarray
    signatures: np.ndarray
    recorded: np.ndarray  # (M, N, 2) candidates of every record_every-th trial (empty unless asked)


def run_search(problem: Problem, request: SolveRequest, *, params: SearchParams | None = None,
               callback: ProgressCallback | None = None, chunk: int = 2048, record_every: int = 0) -> SearchRun:
    """The signature search on ``problem`` (at most 63 disks): the best solution and the final population.

    Args:
        problem: the problem, at most ``GA_MAX_DISKS`` = 63 disks (``nbst.search.solve`` sends
            larger ones to the many-body search).
        request: the run's settings (:class:`~nbst.search.variants.SolveRequest`):
            ``seed`` (None draws one, recorded in the result; same seed, same parameters: the
            same solution, bit for bit, chunking aside), ``max_trials`` (one trial = one
            simulated candidate, initialize included), ``patience`` (trials without improvement;
            0: never; None: ``DEFAULT_PATIENCE``), ``target_cost`` (None: never), ``variant``
            (a name of ``VARIANTS``, None: "nbst"; ignored when ``params`` is given) and
            ``robust`` (True: return the most noise-robust top-order solution found rather than
            the cheapest, ``nbst.search.robust``, setting ``params.robust``; None: as ``params``
            says). ``jobs`` is not used: the signature search runs on one core.
        params: every knob of the search (default: the variant's).
        callback: called with a :class:`SearchProgress` after every chunk; a truthy return stops
            the search. A KeyboardInterrupt (Ctrl-C, or raised by the callback) stops it too: the
            result is then the best so far, ``stopped == "interrupted"``.
        chunk: trials per compiled call (progress / Ctrl-C granularity only; in robust mode also
            the archive's cadence, so a robust result is reproducible for one chunk).
        record_every: k > 0 also returns the candidate velocities of trials k, 2k, ... (the
            paper's loop only; for benchmarks and analysis).

    Returns:
        A :class:`SearchRun`: the result (:class:`~nbst.solution.SolveResult`) and the final population.
    """
    if many_body(problem.n):
        raise SolveError(f"the signature search's compiled loop takes at most {GA_MAX_DISKS} disks (problem "
                         f"{problem.name!r} has {problem.n}); nbst.search.solve runs the many-body search for it")
    if params is None:
        params = variant_params(request.variant_or_default, problem)
    if request.robust is not None:
        params = dataclasses.replace(params, robust=bool(request.robust))
    max_trials, patience, target_cost = int(request.max_trials), request.patience_or_default, request.target_cost
    seed = resolve_seed(request.seed)
    check_run(max_trials, patience, seed)
    prm = _pack(problem, params, max_trials=max_trials, patience=patience, target_cost=target_cost,
                record_every=int(record_every))
    s = _new_state(problem, params, seed)
    rec_v = np.zeros((max_trials // record_every if record_every > 0 else 0, problem.n, 2))
    if params.nbst_loop:
        if record_every > 0:
            raise SolveError("record_every is supported by the paper's loop only (variants A-H)")
        advance: _NbstStepper | _PaperStepper = _NbstStepper(problem, params, s, prm, seed)
    else:
        advance = _PaperStepper(problem, params, s, prm, rec_v)
    archive = None
    if params.robust:
        from nbst.search.robust import RobustArchive

        archive = RobustArchive(n=problem.n, size=params.robust_archive)  # size 0: the search's best alone
    t0 = time.perf_counter()
    stopped = _run_chunks(advance, s, int(chunk), archive, callback, t0)
    wall = time.perf_counter() - t0
    with signals_deferred(reraise=False) as late:  # a Ctrl-C now waits for the result, which says so
        best_v, meta = _finish(problem, params, s, advance, archive, seed, max_trials=max_trials,
                               patience=patience, target_cost=target_cost, stopped=stopped, wall=wall)
    if late:
        meta["stopped"] = StopReason.INTERRUPTED.value
    size = s.pop_size
    trials = int(s.st[_L.ST_TRIALS])
    return SearchRun(result=SolveResult.from_meta(problem, best_v, meta), velocities=s.pop.vel[:size].copy(),
                     costs=s.pop.cost[:size].copy(), signatures=s.pop.sig[:size].copy(),
                     recorded=rec_v[:trials // record_every] if record_every > 0 else rec_v)


def _new_state(problem: Problem, params: SearchParams, seed: int) -> _State:
    """The arrays of a fresh search: an empty population (room for hard_limit + 2), no best yet."""
    st = np.zeros(_L.N_ST, np.int64)
    st[_L.ST_FIRST_FULL] = -1
    n = problem.n
    return _State(pop=new_population(params.hard_limit + 2, n), st=st, best_cost=np.array([np.inf]),
                  best_v=np.zeros((n, 2)), rng=seed_state(seed), hist_t=np.zeros(HISTORY0, np.int64),
                  hist_c=np.zeros(HISTORY0), hist_o=np.zeros(HISTORY0, np.int64))


def _run_chunks(advance, s: _State, chunk: int, archive, callback, t0: float) -> StopReason:
    """Advance the search chunk by chunk until a stopping rule, the callback or Ctrl-C ends it."""
    reasons = {ChunkResult.MAX_TRIALS: StopReason.MAX_TRIALS, ChunkResult.PATIENCE: StopReason.PATIENCE,
               ChunkResult.TARGET_COST: StopReason.TARGET_COST}
    stopped = None
    try:
        advance.start()
        while stopped is None:
            rc = advance(chunk)
            if rc == ChunkResult.HISTORY_FULL:
                s.grow_history()
                continue
            if archive is not None:
                size = s.pop_size
                archive.add(s.pop.vel[:size], s.pop.cost[:size], s.pop.sig[:size])
            stopped = reasons.get(rc)
            if callback is not None:
                prog = SearchProgress(trials=int(s.st[_L.ST_TRIALS]), best_cost=float(s.best_cost[0]),
                                      best_order=_popcount(int(s.st[_L.ST_BEST_SIG])),
                                      elapsed=time.perf_counter() - t0, population=s.pop_size,
                                      phase="initialize" if s.st[_L.ST_PHASE] == _L.PHASE_INIT else "generate")
                if callback(prog) and stopped is None:
                    stopped = StopReason.CALLBACK
    except KeyboardInterrupt:
        stopped = StopReason.INTERRUPTED
    return stopped


def _finish(problem: Problem, params: SearchParams, s: _State, advance, archive, seed: int, *, max_trials: int,
            patience: int, target_cost: float | None, stopped: StopReason, wall: float):
    """The written velocities (the best, or robust mode's choice) and the solution's ``meta``."""
    n = problem.n
    best_v = s.best_v.copy()
    cost = float(s.best_cost[0])
    sig = int(s.st[_L.ST_BEST_SIG])
    if not math.isfinite(cost):  # nothing accepted yet (interrupted at once): report the straight start
        best_v = np.array(problem.straight_velocities(), dtype=float)
    robust_info = None
    if archive is not None and math.isfinite(cost):
        best_v, robust_info = _robust_choice(problem, params, archive, best_v, cost, sig, seed)
    # cost, signature and order as `nbst simulate` sees them (the problem's R, also for variant E)
    search_sig = sig
    _, c, sg = evaluate(problem, best_v[None], max_events=params.max_events)
    cost, sig = float(c[0]), int(sg[0])
    if robust_info is not None:  # the written velocities are the choice's, not the search's best
        search_sig = sig
    trials = int(s.st[_L.ST_TRIALS])
    stats = SearchStats.of(s, advance)
    meta = {
        "algorithm": advance.algorithm,
        "cost": cost,
        "signature": signature_string(sig, n),
        "order": _popcount(sig),
        "trials": stats.trials,
        "init_trials": stats.init_trials,
        "seed": seed,
        "search_signature": signature_string(search_sig, n),
        "variant": params.variant,
        "variant_description": VARIANTS.entry(params.variant).help if params.variant in VARIANTS else "",
        "params": params.to_dict(),
        "max_trials": max_trials,
        "patience": patience,
        "target_cost": target_cost,
        "stopped": None if stopped is None else stopped.value,
        "wall_time": wall,
        "trials_per_s": trials / wall if wall > 0 else None,
        "nbst_version": __version__,
        **stats.run_meta(),
    }
    if params.robust:
        meta["robust"] = robust_info
    return best_v, meta


@dataclass(frozen=True)
class SearchStats:
    """A finished search's statistics, as ``meta`` writes them (the file format: see docs/search.md).

    operators : per operator name, {"children", "improvements"}
    history   : [trial, cost, order] per improvement of the best
    extra     : nbst's loop only: polish, restarts, simulations, planner, robust simulations and
                operator probabilities (``_NbstStepper.stats``)
    """

    trials: int
    init_trials: int
    first_full_order_trial: int | None
    max_order_seen: int
    population_size: int
    rejected_order0: int
    truncated_runs: int
    cull_rounds: int
    fallback_deletions: int
    operators: dict
    history: list
    extra: dict = field(default_factory=dict)

    @classmethod
    def of(cls, s: _State, advance) -> "SearchStats":
        st = s.st
        nh = int(st[_L.ST_NHIST])
        return cls(trials=int(st[_L.ST_TRIALS]), init_trials=int(st[_L.ST_INIT_TRIALS]),
                   first_full_order_trial=int(st[_L.ST_FIRST_FULL]) if st[_L.ST_FIRST_FULL] >= 0 else None,
                   max_order_seen=int(st[_L.ST_MAX_ORDER]), population_size=s.pop_size,
                   rejected_order0=int(st[_L.ST_REJECTED]), truncated_runs=int(st[_L.ST_TRUNCATED]),
                   cull_rounds=int(st[_L.ST_CULLS]), fallback_deletions=int(st[_L.ST_FALLBACK]),
                   operators={name: {"children": int(s.op_count[k, 0]), "improvements": int(s.op_count[k, 1])}
                              for k, name in enumerate(advance.op_names)},
                   history=[[int(s.hist_t[k]), float(s.hist_c[k]), int(s.hist_o[k])] for k in range(nh)],
                   extra=advance.stats())

    def run_meta(self) -> dict:
        """The statistics' part of ``meta``, in the file's key order (trials and init_trials are
        written earlier, beside the cost)."""
        return {"first_full_order_trial": self.first_full_order_trial, "max_order_seen": self.max_order_seen,
                "population_size": self.population_size, "rejected_order0": self.rejected_order0,
                "truncated_runs": self.truncated_runs, "cull_rounds": self.cull_rounds,
                "fallback_deletions": self.fallback_deletions, "operators": self.operators,
                "history": self.history, **self.extra}


def _robust_choice(problem: Problem, params: SearchParams, archive, best_v, best_cost: float, best_sig: int,
                   seed: int):
    """Robust mode's pick: the search's best first, then the archive; see ``nbst.search.robust``."""
    V = np.concatenate([best_v[None], archive.V]) if archive.V.shape[0] else best_v[None]
    v, info = choose(problem, V, seed=seed, samples=params.robust_samples, timestep=params.robust_timestep,
                     polish_top=params.robust_polish)
    info["archive_order"] = int(archive.order)
    info["archive_seen"] = int(archive.seen)
    info["search_best"] = {"cost": best_cost, "order": _popcount(best_sig)}
    return v, info


class _PaperStepper:
    """Advances the paper's loop (``nbst.search.loop.run_chunk``) by one chunk per call."""

    algorithm = ALGORITHM
    op_names = _L.OP_NAMES

    def __init__(self, problem: Problem, params: SearchParams, s: _State, prm: _L.LoopParams, rec_v):
        self.s, self.prm, self.rec_v = s, prm, rec_v
        self.pa = _L.problem_arrays(problem, mirror_images(params.max_bounces))

    def start(self) -> None:
        """Nothing to prepare before the first chunk."""

    def __call__(self, n_steps: int) -> ChunkResult:
        return _L.run_chunk(self.pa, self.prm, self.s.arrays(), self.rec_v, n_steps)

    def stats(self) -> dict:
        return {}


class _NbstStepper:
    """Advances nbst's loop (``nbst.search.nbst_loop.run_chunk_nbst``) by one chunk per call, with its
    extra parameters and state; runs the backward planner first when the problem has noncueable disks."""

    algorithm = ALGORITHM_NBST

    def __init__(self, problem: Problem, params: SearchParams, s: _State, prm: _L.LoopParams, seed: int):
        self.S, self.s, self.prm = S, s, prm
        self.op_names = S.OP_NAMES
        robust = (S.ROBUST_AND if params.robust_signature == "and" else S.ROBUST_PLAIN) \
            if params.robust and params.robust_k > 0 else S.ROBUST_OFF
        self.q = S.NbstParams(
            polish=int(params.polish), polish_sims=int(params.polish_sims), bank_bounces=int(params.bank_bounces),
            adapt=int(params.adapt), straight_start=int(params.straight_start),
            strike_bounces=int(params.strike_bounces), restart=int(params.restart), robust=robust,
            seed_polish_sims=int(params.planner_polish_sims), polish_ratio=float(params.polish_ratio),
            adapt_rate=float(params.adapt_rate), adapt_floor=float(params.adapt_floor),
            robust_shift=float(SHIFT_STEPS * params.robust_timestep))
        self.rd = RobustDraws(*draws(problem, np.random.default_rng([seed, SEARCH_STREAM]),
                                     params.robust_k if robust != S.ROBUST_OFF else 0))
        self.pa = _L.problem_arrays(problem, mirror_images(params.max_bounces))
        qs = np.zeros(S.N_QS, np.int64)
        s.op_count = np.zeros((S.N_OPS, 2), np.int64)
        s.best_cost = np.array([np.inf, np.inf])  # [overall, since the last restart]
        self.planned: Any = None  # the planner's result (nbst.search.planner.PlanResult), once it ran
        self.pl = S.Plans(np.zeros((0, problem.n, 2)), np.zeros(0, np.int64), np.zeros((0, 2)), np.zeros(0, np.int64))
        self.problem, self.params = problem, params
        self._weights(qs)  # without the planner's routes; start() plans, and weighs them in

    def _weights(self, qs) -> None:
        """The operators' probabilities (the plan operator's only once the planner gave routes)."""
        params = self.params
        has_non = self.pa.non_idx.size > 0
        w_plan = params.planner_weight if len(self.pl.route_cue) else 0.0
        base = np.array([*params.op_weights, params.bank_weight, params.strike_weight if has_non else 0.0, w_plan])
        base = base / base.sum()
        self.na = self.S.NbstArrays(qs, base.copy(), base, base.copy())

    def start(self) -> None:
        """Before the first chunk: the backward planner, when the problem has noncueable disks (a
        Ctrl-C here stops the search like one during a chunk: the result is the best so far)."""
        if self.params.planner and self.pa.non_idx.size > 0:
            qs = self.na.qs
            self._plan(self.problem, self.params, qs)
            self._weights(qs)

    def _plan(self, problem: Problem, params: SearchParams, qs) -> None:
        """The backward planner's seeds and routes; its simulations are charged as trials."""
        S, s, prm = self.S, self.s, self.prm
        planned = plan(problem, budget=min(params.planner_trials, prm.max_trials // 4),
                       max_chain=params.planner_chain, seeds=params.planner_seeds, sig_limit=params.sig_limit,
                       max_events=params.max_events, target_cost=prm.target_cost)
        self.planned = planned
        self.pl = S.Plans(np.ascontiguousarray(planned.velocities), planned.route_cue, planned.route_v,
                          planned.route_mask)
        s.st[_L.ST_TRIALS] += planned.trials  # every planner simulation is a trial
        s.st[_L.ST_SINCE] += planned.trials
        qs[S.QS_SIMS] += planned.trials

    def __call__(self, n_steps: int) -> ChunkResult:
        return self.S.run_chunk_nbst(self.pa, self.prm, self.q, self.s.arrays(), self.na, self.rd, self.pl, n_steps)

    def stats(self) -> dict:
        S, qs, planned = self.S, self.na.qs, self.planned
        return {"polish": {"runs": int(qs[S.QS_POLISH_RUNS]), "simulations": int(qs[S.QS_POLISH_SIMS]),
                           "improved": int(qs[S.QS_POLISH_GAINS])},
                "restarts": int(qs[S.QS_RESTARTS]),
                "simulations": int(qs[S.QS_SIMS]),
                **({"planner": {"trials": planned.trials, "seeds": int(len(planned.costs)),
                                "best_cost": float(planned.costs[0]) if len(planned.costs) else None,
                                **planned.stats}} if planned is not None else {}),
                **({"robust_simulations": int(qs[S.QS_ROBUST_SIMS])} if self.q.robust != S.ROBUST_OFF else {}),
                "operator_probabilities": {name: float(w) for name, w in zip(S.OP_NAMES, self.na.weights)}}


def _popcount(x: int) -> int:
    return int(x).bit_count()
