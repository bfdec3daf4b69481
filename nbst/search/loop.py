"""The compiled initialize / generate-insert loop of the signature search.

``run_chunk`` advances a search by up to ``n_steps`` trials (one trial = one
candidate simulated) and returns; all state lives in arrays between calls, so
a search split into chunks is bit-for-bit the search run in one call.
The operators themselves are in ``nbst.search.ops``; the parameters and the
Python driver in ``nbst.search``.
"""
from __future__ import annotations

from enum import IntEnum
from typing import NamedTuple

import numpy as np
from numba import njit

from nbst.search.ops import (INS_CULLED, INS_FALLBACK, SIZE, Population, acceptable_counts, creep_velocity, crossover,
                             directed_velocity, insert, insert_initial, limit_crossings, popcount, rng_int,
                             rng_uniform, select_senate, select_uniform, uniform_velocity)
from nbst.sim import alloc_work, cost_signature, run
from nbst.sim.kernel import Work

__all__ = ["LoopParams", "ProblemArrays", "problem_arrays", "SearchArrays", "ST_PHASE", "ST_TRIALS", "ST_INIT_TRIALS",
           "ST_SINCE", "ST_REJECTED", "ST_CULLS", "ST_FALLBACK", "ST_FIRST_FULL", "ST_NHIST", "ST_BEST_SIG",
           "ST_TRUNCATED", "ST_MAX_ORDER", "N_ST", "PHASE_INIT", "PHASE_GENERATE", "OP_CREEP", "OP_DIRECTED",
           "OP_UNIFORM", "OP_CROSSOVER", "OP_NAMES", "ChunkResult", "RC_CHUNK_DONE", "RC_MAX_TRIALS", "RC_PATIENCE",
           "RC_TARGET_COST", "RC_HISTORY_FULL", "LoopScratch", "loop_scratch", "stop_code", "evaluate_one",
           "init_child", "select_parent", "mutate_one", "book_trial", "settle", "run_chunk"]


class LoopParams(NamedTuple):
    """The loop's parameters (``nbst.search.driver`` builds them from ``SearchParams`` and the run
    options); numba compiles them as a tuple of scalars. Flags are ints (0 off)."""

    pop_limit: int
    sig_limit: int
    diversity: int
    init_max_tries: int
    init_population: int
    senate: int
    engineered: int
    cull: int  # ops.CULL_SUBSUMED or ops.CULL_WORST
    elitism: int
    hard_limit: int
    max_trials: int
    patience: int  # 0: no patience limit
    max_events: int
    record_every: int  # > 0: copy every k-th trial's candidate to rec_v
    R: float  # the search's signature radius
    creep_sigma: float  # units/s per axis
    target_cost: float  # -inf: none
    p_directed_init: float
    w_creep: float  # the four generate weights, normalized
    w_directed: float
    w_uniform: float
    w_crossover: float


class ProblemArrays(NamedTuple):
    """The problem as both loops take it (``Problem.kernel_arrays()`` plus the index sets)."""

    x0: np.ndarray  # (N, 2) starts
    target: np.ndarray  # (N, 2)
    radius: np.ndarray  # (N,)
    mass: np.ndarray  # (N,)
    cue_idx: np.ndarray  # (C,) int64 cueable disks
    non_idx: np.ndarray  # (N - C,) int64 noncueable disks
    W: float
    H: float
    t_final: float
    images: np.ndarray  # (M, 2) int64 mirror images of uniform randomize


def problem_arrays(problem, images) -> ProblemArrays:
    """A problem's ProblemArrays (``images``: uniform randomize's mirror images, (M, 2) int64)."""
    ka = problem.kernel_arrays()
    return ProblemArrays(ka.start, ka.target, ka.radius, ka.mass, np.flatnonzero(problem.cueable).astype(np.int64),
                         np.flatnonzero(~problem.cueable).astype(np.int64), ka.W, ka.H, ka.t_final,
                         np.ascontiguousarray(images, dtype=np.int64))


class SearchArrays(NamedTuple):
    """A search's state between chunks (the kernel writes the arrays in place; the driver
    rebuilds the tuple when it grows the history)."""

    pop: Population
    st: np.ndarray  # (N_ST,) int64 counters, ST_* indices
    best_cost: np.ndarray  # (1,) the paper's loop; (2,) nbst's: [overall, since the last restart]
    best_v: np.ndarray  # (N, 2)
    rng: np.ndarray  # (4,) uint64 xoshiro256** state
    hist_t: np.ndarray  # improvement history: trial,
    hist_c: np.ndarray  # cost,
    hist_o: np.ndarray  # order (st[ST_NHIST] entries used)
    op_count: np.ndarray  # (operators, 2) int64: children made, improvements


# search state (st, int64)
ST_PHASE, ST_TRIALS, ST_INIT_TRIALS, ST_SINCE, ST_REJECTED, ST_CULLS, ST_FALLBACK, \
    ST_FIRST_FULL, ST_NHIST, ST_BEST_SIG, ST_TRUNCATED, ST_MAX_ORDER = range(12)
N_ST = 12
PHASE_INIT, PHASE_GENERATE = 0, 1

# operators (op counts, per generate trial)
OP_CREEP, OP_DIRECTED, OP_UNIFORM, OP_CROSSOVER = range(4)
OP_NAMES = ("creep", "directed", "uniform", "crossover")


class ChunkResult(IntEnum):
    """Why ``run_chunk`` (or ``run_chunk_nbst``) returned (numba compiles the members as constants)."""

    CHUNK_DONE = 0  # n_steps trials run: call again
    MAX_TRIALS = 1  # the trial budget is spent
    PATIENCE = 2  # patience trials without improving the best
    TARGET_COST = 3  # the best cost reached the target
    HISTORY_FULL = 4  # the improvement history is full: grow it and call again


RC_CHUNK_DONE, RC_MAX_TRIALS, RC_PATIENCE, RC_TARGET_COST, RC_HISTORY_FULL = tuple(ChunkResult)


class LoopScratch(NamedTuple):
    """Scratch of one chunk of a search loop (N disks, population capacity cap)."""

    work: Work  # the simulator's (``nbst.sim.alloc_work``)
    child: np.ndarray  # (N, 2) the candidate being made
    fin: np.ndarray  # (N, 2) its final positions
    vel: np.ndarray  # (N, 2) its final velocities
    no_t: np.ndarray  # empty event record: record nothing
    no_i: np.ndarray
    no_s: np.ndarray
    scr_ord: np.ndarray  # (N + 2,) int64 selection / culling scratch
    scr_ok: np.ndarray  # (cap,) bool selection scratch
    acc: np.ndarray  # (N,) int64 acceptable counts (initialize's diversity test)


@njit(cache=True, error_model="numpy")
def loop_scratch(n, cap):
    """Scratch of one chunk of a search loop: a :class:`LoopScratch`."""
    return LoopScratch(alloc_work(n), np.zeros((n, 2)), np.empty((n, 2)), np.empty((n, 2)), np.empty(0),
                       np.empty(0, np.int64), np.empty((0, 8)), np.empty(n + 2, np.int64), np.empty(cap, np.bool_),
                       np.empty(n, np.int64))


@njit(cache=True, inline="always", error_model="numpy")
def stop_code(prm, st, best_cost, hist_room):
    """Why a search loop must stop before its next trial (RC_*), or RC_CHUNK_DONE to go on.
    ``hist_room``: how many history entries the loop may fill (a trial adds at most one)."""
    if st[ST_TRIALS] >= prm.max_trials:
        return RC_MAX_TRIALS
    if best_cost[0] <= prm.target_cost:
        return RC_TARGET_COST
    if st[ST_PHASE] == PHASE_GENERATE and prm.patience > 0 and st[ST_SINCE] >= prm.patience:
        return RC_PATIENCE
    if st[ST_NHIST] >= hist_room:
        return RC_HISTORY_FULL
    return RC_CHUNK_DONE


# The per-trial helpers below take plain arrays and scalars, never the NamedTuples: numba copies a
# tuple argument into an inlined helper (or a call) by taking a reference to each of its arrays,
# an atomic increment and decrement per array; with ~40 arrays per trial that cost a quarter of the
# loop's speed (measured, issue 24). The chunk functions unpack their tuples once per chunk.


@njit(cache=True, error_model="numpy")
def evaluate_one(x0, v, radius, mass, target, W, H, t_final, R, max_events, work, fin, vel, no_t, no_i, no_s):
    # Sixteen parameters on purpose: the per-trial simulation, flat arrays (see above).
    """Simulate one candidate: (cost, signature, truncated); a truncated run scores inf, 0."""
    st, _, _, _ = run(x0, v, radius, mass, W, H, t_final, work, fin, vel, max_events, no_t, no_i, no_i, no_s)
    if st != 0:
        return np.inf, np.int64(0), True
    c, s = cost_signature(fin, target, R)
    return c, s, False


@njit(cache=True, inline="always", error_model="numpy")
def init_child(x0, target, radius, W, H, t_final, images, cue_idx, p_directed, straight, rng, child):
    """Initialize's candidate: each cueable disk directed (all of them when ``straight``) or, with
    probability 1 - p_directed, uniform randomize; noncueable disks at rest."""
    child[:, :] = 0.0
    for q in range(cue_idx.shape[0]):
        i = cue_idx[q]
        if straight or rng_uniform(rng) < p_directed:
            directed_velocity(x0, target, t_final, i, child)
        else:
            uniform_velocity(x0, radius, W, H, t_final, images, i, rng, child)


@njit(cache=True, inline="always", error_model="numpy")
def select_parent(pop, n, senate, rng, first, scr_ord, scr_ok):
    """A parent: Senate-like (``senate`` != 0) or uniform; ``first`` >= 0 picks the second
    crossover parent (never ``first`` itself)."""
    if senate != 0:
        return select_senate(pop, n, rng, first, scr_ord, scr_ok)
    return select_uniform(pop, rng, first)


@njit(cache=True, inline="always", error_model="numpy")
def mutate_one(op, i, x0, target, radius, W, H, t_final, images, creep_sigma, rng, child):
    """The paper's one-disk operators on disk i of a copy of the parent: creep, directed or uniform."""
    if op == OP_CREEP:
        creep_velocity(creep_sigma, i, rng, child)
    elif op == OP_DIRECTED:
        directed_velocity(x0, target, t_final, i, child)
    else:
        uniform_velocity(x0, radius, W, H, t_final, images, i, rng, child)


@njit(cache=True, inline="always", error_model="numpy")
def book_trial(st, record_every, rec_v, child, trunc):
    """Count one simulated candidate (trials, trials since the best, initialize's trials,
    truncated runs) and record it for ``record_every``."""
    st[ST_TRIALS] += 1
    st[ST_SINCE] += 1
    if record_every > 0 and st[ST_TRIALS] % record_every == 0 and st[ST_TRIALS] // record_every <= rec_v.shape[0]:
        rec_v[st[ST_TRIALS] // record_every - 1, :, :] = child
    if st[ST_PHASE] == PHASE_INIT:
        st[ST_INIT_TRIALS] += 1
    if trunc:
        st[ST_TRUNCATED] += 1


@njit(cache=True, error_model="numpy")
def settle(pop, st, best_cost, best_v, hist_t, hist_c, hist_o, op_count, rng, child, cost, sig, op, p1, p2, prm,
           scr_ord, acc, n):
    # Nineteen parameters on purpose: the search state as flat arrays (see above); prm is scalars.
    """Book one simulated candidate (after ``book_trial``): order statistics, an improvement
    of the best (and the history), the insert of initialize or generate, and the end of
    initialize. Shared by this loop and ``nbst.search.nbst_loop``'s."""
    ist = pop.state
    elitism = prm.elitism != 0
    order = popcount(sig)
    if order > st[ST_MAX_ORDER]:
        st[ST_MAX_ORDER] = order
    if order == n and st[ST_FIRST_FULL] < 0:
        st[ST_FIRST_FULL] = st[ST_TRIALS]
    if order == 0:  # rejected: initialize rejects order 0; generate does too (see docs/search.md)
        st[ST_REJECTED] += 1
    else:
        improvement = cost < best_cost[0]
        if improvement:
            best_cost[0] = cost
            best_v[:, :] = child
            st[ST_BEST_SIG] = sig
            st[ST_SINCE] = 0
            k = st[ST_NHIST]
            hist_t[k] = st[ST_TRIALS]
            hist_c[k] = cost
            hist_o[k] = order
            st[ST_NHIST] = k + 1
            if op >= 0:
                op_count[op, 1] += 1
        if st[ST_PHASE] == PHASE_INIT:
            insert_initial(pop, child, cost, sig, improvement, elitism, prm.sig_limit, prm.pop_limit)
        else:
            code = insert(pop, child, cost, sig, p1, p2, improvement, elitism, prm.sig_limit, prm.pop_limit,
                          prm.hard_limit, prm.cull, n, rng, scr_ord)
            if code == INS_CULLED:
                st[ST_CULLS] += 1
            elif code == INS_FALLBACK:
                st[ST_FALLBACK] += 1
    if st[ST_PHASE] == PHASE_INIT and ist[SIZE] > 0:
        done = st[ST_INIT_TRIALS] >= prm.init_max_tries
        if prm.init_population > 0:
            done = done or ist[SIZE] >= prm.init_population
        else:
            acceptable_counts(pop, n, acc)
            ok = True
            for i in range(n):
                if acc[i] < prm.diversity:
                    ok = False
                    break
            done = done or ok
        if done:
            st[ST_PHASE] = PHASE_GENERATE


@njit(cache=True, error_model="numpy")
def run_chunk(pa, prm, sa, rec_v, n_steps):
    """Advance the search by at most n_steps trials. Returns a ChunkResult.

    pa   : ProblemArrays; prm : LoopParams; sa : SearchArrays (written in place)
    rec_v: (M, N, 2): with prm.record_every = k > 0, the candidate of every k-th trial
           (trial k, 2k, ...) is copied to rec_v[trial / k - 1] while there is room
           (for benchmarks: the exact mix of velocities the loop simulates)

    One trial: make a child (initialize's, or one operator on Senate-selected parents), limit it
    to the velocity domain, simulate it, count it, settle it.
    """
    x0, target, radius, mass, cue_idx, _, W, H, t_final, images = pa
    pop, st, best_cost, best_v, rng, hist_t, hist_c, hist_o, op_count = sa
    n = x0.shape[0]
    work, child, fin, vel, no_t, no_i, no_s, scr_ord, scr_ok, acc = loop_scratch(n, pop.vel.shape[0])
    ncue = cue_idx.shape[0]
    w_c = prm.w_creep
    w_d = w_c + prm.w_directed
    w_u = w_d + prm.w_uniform
    w_tot = w_u + prm.w_crossover
    for _ in range(n_steps):
        rc = stop_code(prm, st, best_cost, hist_t.shape[0])
        if rc != RC_CHUNK_DONE:
            return rc
        op = -1
        p1 = -1
        p2 = -1
        if st[ST_PHASE] == PHASE_INIT:
            init_child(x0, target, radius, W, H, t_final, images, cue_idx, prm.p_directed_init, False, rng, child)
        else:
            u = rng_uniform(rng) * w_tot
            op = OP_CREEP if u < w_c else (OP_DIRECTED if u < w_d else (OP_UNIFORM if u < w_u else OP_CROSSOVER))
            if op == OP_CROSSOVER and pop.state[SIZE] < 2:
                op = OP_CREEP  # a lone member cannot be crossed
            p1 = select_parent(pop, n, prm.senate, rng, -1, scr_ord, scr_ok)
            if op == OP_CROSSOVER:
                p2 = select_parent(pop, n, prm.senate, rng, p1, scr_ord, scr_ok)
                crossover(pop.vel[p1], pop.vel[p2], pop.sig[p1], pop.sig[p2], cue_idx, prm.engineered != 0, rng,
                          child)
            else:
                child[:, :] = pop.vel[p1]
                mutate_one(op, cue_idx[rng_int(rng, ncue)], x0, target, radius, W, H, t_final, images,
                           prm.creep_sigma, rng, child)
            op_count[op, 0] += 1
        limit_crossings(child, cue_idx, radius, W, H, t_final)
        cost, sig, trunc = evaluate_one(x0, child, radius, mass, target, W, H, t_final, prm.R, prm.max_events, work,
                                        fin, vel, no_t, no_i, no_s)
        book_trial(st, prm.record_every, rec_v, child, trunc)
        settle(pop, st, best_cost, best_v, hist_t, hist_c, hist_o, op_count, rng, child, cost, sig, op, p1, p2, prm,
               scr_ord, acc, n)
    return RC_CHUNK_DONE
