"""The signature search's driver: ``solve`` and ``run_search`` pack a problem and its
:class:`~nbst.search.params.SearchParams` into arrays, run the compiled loop
(``nbst.search.loop``, or ``nbst.search.nbst_loop`` for nbst's variant) chunk by chunk
with progress and Ctrl-C, and unpack the best solution with its statistics.
"""
from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from nbst._version import __version__
from nbst.constants import ROUNDOFF_REL
from nbst.problem import Problem, ProblemError
from nbst.search.params import (ALGORITHM, ALGORITHM_NBST, VARIANTS, SearchParams, SearchProgress, _check, mirror_images,
                                variant_params)

@dataclass
class _State:
    """The arrays a search carries between chunks (mutable by design: the kernel writes them)."""

    pop: tuple
    st: np.ndarray
    best_cost: np.ndarray
    best_v: np.ndarray
    rng: np.ndarray
    hist_t: np.ndarray
    hist_c: np.ndarray
    hist_o: np.ndarray
    op_count: np.ndarray = field(default_factory=lambda: np.zeros((4, 2), np.int64))


def _pack(problem: Problem, params: SearchParams, *, max_trials: int, patience: int, target_cost: float | None,
          record_every: int = 0):
    from nbst.search import loop as L

    pi = np.zeros(L.N_PI, np.int64)
    pi[L.PI_POP_LIMIT] = params.pop_limit
    pi[L.PI_SIG_LIMIT] = params.sig_limit
    pi[L.PI_DIVERSITY] = params.diversity
    pi[L.PI_INIT_MAX_TRIES] = params.init_max_tries
    pi[L.PI_INIT_POPULATION] = params.init_population
    pi[L.PI_SENATE] = int(params.senate)
    pi[L.PI_ENGINEERED] = int(params.engineered)
    pi[L.PI_CULL] = {"subsumed": 0, "worst": 1}[params.cull]
    pi[L.PI_ELITISM] = int(params.elitism)
    pi[L.PI_HARD_LIMIT] = params.hard_limit
    pi[L.PI_MAX_TRIALS] = max_trials
    pi[L.PI_PATIENCE] = patience
    pi[L.PI_MAX_EVENTS] = params.max_events
    pi[L.PI_RECORD_EVERY] = record_every
    pf = np.zeros(L.N_PF)
    pf[L.PF_R] = params.signature_radius if params.signature_radius is not None else problem.target_radius
    pf[L.PF_CREEP_SIGMA] = params.creep_fraction * problem.target_radius / problem.t_final
    pf[L.PF_TARGET_COST] = -math.inf if target_cost is None else target_cost
    pf[L.PF_P_DIRECTED_INIT] = params.p_directed_init
    w = np.asarray(params.op_weights, float)
    pf[L.PF_W_CREEP:L.PF_W_CROSSOVER + 1] = w / w.sum()
    return pi, pf


@dataclass(frozen=True, eq=False)
class SearchRun:
    """A finished search: the best solution and the final population.

    velocities : (P, N, 2) float, units/s; costs : (P,) float; signatures : (P,) int64 bitmasks
    """

    solution: object
    velocities: np.ndarray
    costs: np.ndarray
    signatures: np.ndarray
    recorded: np.ndarray  # (M, N, 2) candidates of every record_every-th trial (empty unless asked)


def roundoff_cost(problem: Problem) -> float:
    """The cost of a solution whose every disk ends ROUNDOFF_REL x max(W, H) from its
    target: N (ROUNDOFF_REL max(W, H))^2, units^2. Below it a search has nothing left to
    gain (``nbst solve``'s default target cost)."""
    return problem.n * (ROUNDOFF_REL * max(problem.box)) ** 2


def solve(problem: Problem, *, seed: int | None = None, max_trials: int = 1_000_000, patience: int = 100_000,
          target_cost: float | None = None, variant: str = "nbst", params: SearchParams | None = None,
          callback: Callable[[SearchProgress], bool | None] | None = None, chunk: int = 2048,
          robust: bool | None = None):
    """Run the signature search on ``problem``; return the best :class:`~nbst.solution.Solution`.

    seed        : int >= 0; None draws one (recorded in ``meta["seed"]``). Same seed, same
                  parameters -> the same solution, bit for bit (chunking does not matter).
    max_trials  : trial budget (one trial = one simulated candidate, initialize included)
    patience    : stop after this many trials without improvement (0: never)
    target_cost : stop once the best cost is <= this (None: never)
    variant     : "nbst" (nbst's search, the default), "A" (the paper's full algorithm) .. "H"
                  (its simplified variants); ignored when ``params`` is given
    callback    : called with a :class:`SearchProgress` after every chunk; a truthy return
                  stops the search. A KeyboardInterrupt (Ctrl-C, or raised by the callback)
                  stops it too: ``solve`` then returns the best so far with
                  ``meta["stopped"] == "interrupted"``.
    chunk       : trials per compiled call (progress / Ctrl-C granularity only; in robust mode
                  also the archive's cadence, so a robust result is reproducible for one chunk)
    robust      : True: write the most noise-robust top-order solution found rather than the
                  cheapest (``nbst.search.robust``; sets ``params.robust``); None: as ``params`` says

    ``meta`` holds cost, signature, order, trials, seed, variant, params, wall_time,
    nbst_version, history ([trial, cost, order] per improvement) and run statistics.
    """
    return run_search(problem, seed=seed, max_trials=max_trials, patience=patience, target_cost=target_cost,
                      variant=variant, params=params, callback=callback, chunk=chunk, robust=robust).solution


def run_search(problem: Problem, *, seed: int | None = None, max_trials: int = 1_000_000, patience: int = 100_000,
               target_cost: float | None = None, variant: str = "nbst", params: SearchParams | None = None,
               callback: Callable[[SearchProgress], bool | None] | None = None, chunk: int = 2048,
               record_every: int = 0, robust: bool | None = None) -> SearchRun:
    """:func:`solve`, also returning the final population (for benchmarks and analysis) and, with
    ``record_every`` = k > 0, the candidate velocities of trials k, 2k, ... (the loop's exact mix)."""
    from nbst.search import loop as L
    from nbst.search.ops import SIZE, new_population, seed_state
    from nbst.solution import make_solution, signature_string

    if params is None:
        params = variant_params(variant, problem)
    if robust is not None:
        params = dataclasses.replace(params, robust=bool(robust))
    max_trials, patience = int(max_trials), int(patience)
    _check(params, max_trials, patience)
    if seed is None:
        seed = int(np.random.default_rng().integers(2**63))
    seed = int(seed)
    if seed < 0:
        raise ProblemError("<search parameters>", "seed", f"must be >= 0, got {seed}")
    pi, pf = _pack(problem, params, max_trials=max_trials, patience=patience, target_cost=target_cost,
                   record_every=int(record_every))
    n = problem.n
    x0 = np.ascontiguousarray(problem.start, dtype=np.float64)
    target = np.ascontiguousarray(problem.target, dtype=np.float64)
    radius = np.ascontiguousarray(problem.radius, dtype=np.float64)
    mass = np.ascontiguousarray(problem.mass, dtype=np.float64)
    cue_idx = np.flatnonzero(problem.cueable).astype(np.int64)
    images = mirror_images(params.max_bounces)
    W, H = (float(x) for x in problem.box)
    cap = params.hard_limit + 2
    st = np.zeros(L.N_ST, np.int64)
    st[L.ST_FIRST_FULL] = -1
    s = _State(pop=new_population(cap, n), st=st, best_cost=np.array([np.inf]), best_v=np.zeros((n, 2)),
               rng=seed_state(seed), hist_t=np.zeros(1024, np.int64), hist_c=np.zeros(1024),
               hist_o=np.zeros(1024, np.int64))
    rec_v = np.zeros((max_trials // record_every if record_every > 0 else 0, n, 2))
    advance = _nbst_stepper(problem, params, s, pi, pf, seed) if params.nbst_loop else None
    archive = None
    if params.robust:
        from nbst.search.robust import Archive

        archive = Archive(n, params.robust_archive)  # size 0 keeps nothing: the search's best alone
    if advance is not None and record_every > 0:
        raise ValueError("record_every is supported by the paper's loop only (variants A-H)")
    stopped = None
    t0 = time.perf_counter()
    reasons = {L.RC_MAX_TRIALS: "max_trials", L.RC_PATIENCE: "patience", L.RC_TARGET_COST: "target_cost"}
    try:
        while stopped is None:
            if advance is not None:
                rc = advance(int(chunk))
            else:
                rc = L.run_chunk(x0, target, radius, mass, cue_idx, W, H, float(problem.t_final), images, pi, pf,
                                 s.pop, s.st, s.best_cost, s.best_v, s.rng, s.hist_t, s.hist_c, s.hist_o,
                                 s.op_count, rec_v, int(chunk))
            if rc == L.RC_HISTORY_FULL:
                k = len(s.hist_t)
                s.hist_t = np.concatenate([s.hist_t, np.zeros(k, np.int64)])
                s.hist_c = np.concatenate([s.hist_c, np.zeros(k)])
                s.hist_o = np.concatenate([s.hist_o, np.zeros(k, np.int64)])
                continue
            if archive is not None:
                size = int(s.pop[5][SIZE])
                archive.add(s.pop[0][:size], s.pop[1][:size], s.pop[2][:size])
            stopped = reasons.get(rc)
            if callback is not None:
                prog = SearchProgress(trials=int(s.st[L.ST_TRIALS]), best_cost=float(s.best_cost[0]),
                                      best_order=_popcount(int(s.st[L.ST_BEST_SIG])),
                                      elapsed=time.perf_counter() - t0, population=int(s.pop[5][SIZE]),
                                      phase="initialize" if s.st[L.ST_PHASE] == L.PHASE_INIT else "generate")
                if callback(prog) and stopped is None:
                    stopped = "callback"
    except KeyboardInterrupt:
        stopped = "interrupted"
    wall = time.perf_counter() - t0

    st = s.st
    best_v = s.best_v.copy()
    cost = float(s.best_cost[0])
    sig = int(st[L.ST_BEST_SIG])
    from nbst.sim import evaluate

    if not math.isfinite(cost):  # nothing accepted yet: report the motionless start
        best_v = np.zeros((n, 2))
    robust_info = None
    if archive is not None and math.isfinite(cost):
        best_v, robust_info = _robust_choice(problem, params, archive, best_v, cost, sig, seed)
    # cost, signature and order as `nbst simulate` sees them (the problem's R, also for variant E)
    search_sig = sig
    _, c, sg = evaluate(problem, best_v[None], max_events=params.max_events)
    cost, sig = float(c[0]), int(sg[0])
    if robust_info is not None:  # the written velocities are the choice's, not the search's best
        search_sig = sig
    nh = int(st[L.ST_NHIST])
    trials = int(st[L.ST_TRIALS])
    op_names = advance.op_names if advance is not None else L.OP_NAMES
    meta = {
        "algorithm": ALGORITHM_NBST if advance is not None else ALGORITHM,
        "cost": cost,
        "signature": signature_string(sig, n),
        "order": _popcount(sig),
        "trials": trials,
        "init_trials": int(st[L.ST_INIT_TRIALS]),
        "seed": seed,
        "search_signature": signature_string(search_sig, n),
        "variant": params.variant,
        "variant_description": VARIANTS.get(params.variant, ""),
        "params": params.to_dict(),
        "max_trials": max_trials,
        "patience": patience,
        "target_cost": target_cost,
        "stopped": stopped,
        "wall_time": wall,
        "trials_per_s": trials / wall if wall > 0 else None,
        "nbst_version": __version__,
        "first_full_order_trial": int(st[L.ST_FIRST_FULL]) if st[L.ST_FIRST_FULL] >= 0 else None,
        "max_order_seen": int(st[L.ST_MAX_ORDER]),
        "population_size": int(s.pop[5][SIZE]),
        "rejected_order0": int(st[L.ST_REJECTED]),
        "truncated_runs": int(st[L.ST_TRUNCATED]),
        "cull_rounds": int(st[L.ST_CULLS]),
        "fallback_deletions": int(st[L.ST_FALLBACK]),
        "operators": {name: {"children": int(s.op_count[k, 0]), "improvements": int(s.op_count[k, 1])}
                      for k, name in enumerate(op_names)},
        "history": [[int(s.hist_t[k]), float(s.hist_c[k]), int(s.hist_o[k])] for k in range(nh)],
    }
    if advance is not None:
        meta.update(advance.stats())
    if params.robust:
        meta["robust"] = robust_info
    size = int(s.pop[5][SIZE])
    return SearchRun(solution=make_solution(problem, best_v, **meta), velocities=s.pop[0][:size].copy(),
                     costs=s.pop[1][:size].copy(), signatures=s.pop[2][:size].copy(),
                     recorded=rec_v[:trials // record_every] if record_every > 0 else rec_v)


def _robust_choice(problem: Problem, params: SearchParams, archive, best_v, best_cost: float, best_sig: int,
                   seed: int):
    """Robust mode's pick: the search's best first, then the archive; see ``nbst.search.robust``."""
    from nbst.search.robust import choose

    V = np.concatenate([best_v[None], archive.V]) if archive.V.shape[0] else best_v[None]
    v, info = choose(problem, V, seed=seed, samples=params.robust_samples, timestep=params.robust_timestep,
                     polish_top=params.robust_polish)
    info["archive_order"] = int(archive.order)
    info["archive_seen"] = int(archive.seen)
    info["search_best"] = {"cost": best_cost, "order": _popcount(best_sig)}
    return v, info


def _nbst_stepper(problem: Problem, params: SearchParams, s: _State, pi, pf, seed: int):
    """A chunk-advancing closure over ``nbst.search.nbst_loop.run_chunk_nbst`` and its extra state."""
    from nbst.search import nbst_loop as S
    from nbst.search import loop as L

    qi = np.zeros(S.N_QI, np.int64)
    qi[S.QI_POLISH] = int(params.polish)
    qi[S.QI_POLISH_SIMS] = params.polish_sims
    qi[S.QI_BANK_BOUNCES] = params.bank_bounces
    qi[S.QI_ADAPT] = int(params.adapt)
    qi[S.QI_STRAIGHT_START] = int(params.straight_start)
    qi[S.QI_STRIKE_BOUNCES] = params.strike_bounces
    qi[S.QI_RESTART] = params.restart
    qi[S.QI_ROBUST] = (1 if params.robust_signature == "and" else 2) if params.robust and params.robust_k > 0 else 0
    qi[S.QI_SEED_POLISH_SIMS] = params.planner_polish_sims
    qf = np.zeros(S.N_QF)
    qf[S.QF_POLISH_RATIO] = params.polish_ratio
    qf[S.QF_ADAPT_RATE] = params.adapt_rate
    qf[S.QF_ADAPT_FLOOR] = params.adapt_floor
    from nbst.search.robust import SEARCH_STREAM, SHIFT_STEPS, draws

    qf[S.QF_ROBUST_SHIFT] = SHIFT_STEPS * params.robust_timestep
    zeta, smax = draws(problem, np.random.default_rng([seed, SEARCH_STREAM]), params.robust_k if qi[S.QI_ROBUST] else 0)
    qs = np.zeros(S.N_QS, np.int64)
    non_idx = np.flatnonzero(~problem.cueable).astype(np.int64)
    s.op_count = np.zeros((S.N_OPS, 2), np.int64)
    s.best_cost = np.array([np.inf, np.inf])  # [overall, since the last restart]
    seeds = np.zeros((0, problem.n, 2))
    routes = (np.zeros(0, np.int64), np.zeros((0, 2)), np.zeros(0, np.int64))
    planned = None
    if params.planner and non_idx.size:
        from nbst.search.planner import plan

        planned = plan(problem, budget=min(params.planner_trials, int(pi[L.PI_MAX_TRIALS]) // 4),
                       max_chain=params.planner_chain, seeds=params.planner_seeds, sig_limit=params.sig_limit,
                       max_events=params.max_events, target_cost=float(pf[L.PF_TARGET_COST]))
        seeds = np.ascontiguousarray(planned.velocities)
        routes = (planned.route_cue, planned.route_v, planned.route_mask)
        s.st[L.ST_TRIALS] += planned.trials  # every planner simulation is a trial
        s.st[L.ST_SINCE] += planned.trials
        qs[S.QS_SIMS] += planned.trials
    w_plan = params.planner_weight if len(routes[0]) else 0.0
    base = np.array([*params.op_weights, params.bank_weight, params.strike_weight if non_idx.size else 0.0, w_plan])
    base = base / base.sum()
    weights, reward = base.copy(), base.copy()
    args = (np.ascontiguousarray(problem.start, dtype=np.float64), np.ascontiguousarray(problem.target, dtype=np.float64),
            np.ascontiguousarray(problem.radius, dtype=np.float64), np.ascontiguousarray(problem.mass, dtype=np.float64),
            np.flatnonzero(problem.cueable).astype(np.int64), non_idx, float(problem.box[0]), float(problem.box[1]),
            float(problem.t_final), mirror_images(params.max_bounces), pi, pf, qi, qf)

    def advance(n_steps: int) -> int:
        return S.run_chunk_nbst(*args, s.pop, s.st, qs, s.best_cost, s.best_v, s.rng, s.hist_t, s.hist_c, s.hist_o,
                                s.op_count, weights, base, reward, zeta, smax, seeds, *routes, n_steps)

    def stats() -> dict:
        return {"polish": {"runs": int(qs[S.QS_POLISH_RUNS]), "simulations": int(qs[S.QS_POLISH_SIMS]),
                           "improved": int(qs[S.QS_POLISH_GAINS])},
                "restarts": int(qs[S.QS_RESTARTS]),
                "simulations": int(qs[S.QS_SIMS]),
                **({"planner": {"trials": planned.trials, "seeds": int(len(planned.costs)),
                                "best_cost": float(planned.costs[0]) if len(planned.costs) else None,
                                **planned.stats}} if planned is not None else {}),
                **({"robust_simulations": int(qs[S.QS_ROBUST_SIMS])} if qi[S.QI_ROBUST] else {}),
                "operator_probabilities": {name: float(w) for name, w in zip(S.OP_NAMES, weights)}}

    advance.op_names = S.OP_NAMES
    advance.stats = stats
    return advance


def _popcount(x: int) -> int:
    return bin(x).count("1")
