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

from nbst.search.ops import (INS_CULLED, INS_FALLBACK, SIZE, acceptable_counts, limit_crossings,
                         creep_velocity, crossover, directed_velocity, insert, insert_initial, popcount,
                         rng_int, rng_uniform, select_senate, select_uniform, uniform_velocity)
from nbst.sim import alloc_work, cost_signature, run
from nbst.sim.kernel import Work

# integer parameters (pi)
PI_POP_LIMIT, PI_SIG_LIMIT, PI_DIVERSITY, PI_INIT_MAX_TRIES, PI_INIT_POPULATION, PI_SENATE, PI_ENGINEERED, \
    PI_CULL, PI_ELITISM, PI_HARD_LIMIT, PI_MAX_TRIALS, PI_PATIENCE, PI_MAX_EVENTS, PI_RECORD_EVERY = range(14)
N_PI = 14
# float parameters (pf)
PF_R, PF_CREEP_SIGMA, PF_TARGET_COST, PF_P_DIRECTED_INIT, PF_W_CREEP, PF_W_DIRECTED, PF_W_UNIFORM, \
    PF_W_CROSSOVER = range(8)
N_PF = 8

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
def stop_code(pi, pf, st, best_cost, hist_room):
    """Why a search loop must stop before its next trial (RC_*), or RC_CHUNK_DONE to go on.
    ``hist_room``: how many history entries the loop may fill."""
    if st[ST_TRIALS] >= pi[PI_MAX_TRIALS]:
        return RC_MAX_TRIALS
    if best_cost[0] <= pf[PF_TARGET_COST]:
        return RC_TARGET_COST
    if st[ST_PHASE] == PHASE_GENERATE and pi[PI_PATIENCE] > 0 and st[ST_SINCE] >= pi[PI_PATIENCE]:
        return RC_PATIENCE
    if st[ST_NHIST] >= hist_room:
        return RC_HISTORY_FULL
    return RC_CHUNK_DONE


@njit(cache=True, error_model="numpy")
def evaluate_one(x0, v, radius, mass, target, W, H, t_final, R, max_events, work, fin, vel, no_t, no_i, no_s):
    """Simulate one candidate: (cost, signature, truncated); a truncated run scores inf, 0."""
    st, _, _, _ = run(x0, v, radius, mass, W, H, t_final, work, fin, vel, max_events, no_t, no_i, no_i, no_s)
    if st != 0:
        return np.inf, np.int64(0), True
    c, s = cost_signature(fin, target, R)
    return c, s, False


@njit(cache=True, error_model="numpy")
def settle(pop, child, cost, sig, op, p1, p2, pi, st, best_cost, best_v, hist_t, hist_c, hist_o, op_count, rng,
           scr_ord, acc, n):
    """Book one simulated candidate (after the trial counters): order statistics, an
    improvement of the best (and the history), the insert of initialize or generate,
    and the end of initialize. Shared by this loop and ``nbst.search.nbst_loop``'s."""
    ist = pop.state
    elitism = pi[PI_ELITISM] != 0
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
            insert_initial(pop, child, cost, sig, improvement, elitism, pi[PI_SIG_LIMIT], pi[PI_POP_LIMIT])
        else:
            code = insert(pop, child, cost, sig, p1, p2, improvement, elitism, pi[PI_SIG_LIMIT],
                          pi[PI_POP_LIMIT], pi[PI_HARD_LIMIT], pi[PI_CULL], n, rng, scr_ord)
            if code == INS_CULLED:
                st[ST_CULLS] += 1
            elif code == INS_FALLBACK:
                st[ST_FALLBACK] += 1
    if st[ST_PHASE] == PHASE_INIT and ist[SIZE] > 0:
        done = st[ST_INIT_TRIALS] >= pi[PI_INIT_MAX_TRIES]
        if pi[PI_INIT_POPULATION] > 0:
            done = done or ist[SIZE] >= pi[PI_INIT_POPULATION]
        else:
            acceptable_counts(pop, n, acc)
            ok = True
            for i in range(n):
                if acc[i] < pi[PI_DIVERSITY]:
                    ok = False
                    break
            done = done or ok
        if done:
            st[ST_PHASE] = PHASE_GENERATE


@njit(cache=True, error_model="numpy")
def run_chunk(x0, target, radius, mass, cue_idx, W, H, t_final, images, pi, pf,
              pop, st, best_cost, best_v, rng, hist_t, hist_c, hist_o, op_count, rec_v, n_steps):
    """Advance the search by at most n_steps trials. Returns an RC_* code.

    x0, target : (N, 2); radius, mass : (N,); cue_idx : indices of cueable disks
    images     : (M, 2) int64 mirror images for uniform randomize
    pi, pf     : parameters (PI_*, PF_* indices); st : state (ST_*); best_cost : (1,)
    best_v     : (N, 2) best velocities so far; rng : (4,) uint64
    hist_*     : improvement history (trial, cost, order), st[ST_NHIST] entries used
    op_count   : (4, 2) int64 per operator: children made, improvements
    rec_v      : (M, N, 2): with pi[PI_RECORD_EVERY] = k > 0, the candidate of every k-th trial
                 (trial k, 2k, ...) is copied to rec_v[trial / k - 1] while there is room
                 (for benchmarks: the exact mix of velocities the loop simulates)
    """
    n = x0.shape[0]
    cap = pop.vel.shape[0]
    ist = pop.state
    work, child, fin, vel, no_t, no_i, no_s, scr_ord, scr_ok, acc = loop_scratch(n, cap)
    R = pf[PF_R]
    max_events = pi[PI_MAX_EVENTS]
    w_c = pf[PF_W_CREEP]
    w_d = w_c + pf[PF_W_DIRECTED]
    w_u = w_d + pf[PF_W_UNIFORM]
    w_tot = w_u + pf[PF_W_CROSSOVER]
    ncue = cue_idx.shape[0]

    for _ in range(n_steps):
        rc = stop_code(pi, pf, st, best_cost, hist_t.shape[0])
        if rc != RC_CHUNK_DONE:
            return rc

        p1 = -1
        p2 = -1
        op = -1
        if st[ST_PHASE] == PHASE_INIT:
            child[:, :] = 0.0
            for q in range(ncue):
                i = cue_idx[q]
                if rng_uniform(rng) < pf[PF_P_DIRECTED_INIT]:
                    directed_velocity(x0, target, t_final, i, child)
                else:
                    uniform_velocity(x0, radius, W, H, t_final, images, i, rng, child)
        else:
            u = rng_uniform(rng) * w_tot
            op = OP_CREEP if u < w_c else (OP_DIRECTED if u < w_d else (OP_UNIFORM if u < w_u else OP_CROSSOVER))
            if op == OP_CROSSOVER and ist[SIZE] < 2:
                op = OP_CREEP  # a lone member cannot be crossed
            if pi[PI_SENATE] != 0:
                p1 = select_senate(pop, n, rng, -1, scr_ord, scr_ok)
            else:
                p1 = select_uniform(pop, rng, -1)
            if op == OP_CROSSOVER:
                if pi[PI_SENATE] != 0:
                    p2 = select_senate(pop, n, rng, p1, scr_ord, scr_ok)
                else:
                    p2 = select_uniform(pop, rng, p1)
                crossover(pop.vel[p1], pop.vel[p2], pop.sig[p1], pop.sig[p2], cue_idx, pi[PI_ENGINEERED] != 0,
                          rng, child)
            else:
                child[:, :] = pop.vel[p1]
                i = cue_idx[rng_int(rng, ncue)]
                if op == OP_CREEP:
                    creep_velocity(pf[PF_CREEP_SIGMA], i, rng, child)
                elif op == OP_DIRECTED:
                    directed_velocity(x0, target, t_final, i, child)
                else:
                    uniform_velocity(x0, radius, W, H, t_final, images, i, rng, child)
            op_count[op, 0] += 1
        limit_crossings(child, cue_idx, radius, W, H, t_final)

        cost, sig, trunc = evaluate_one(x0, child, radius, mass, target, W, H, t_final, R, max_events, work,
                                        fin, vel, no_t, no_i, no_s)
        st[ST_TRIALS] += 1
        st[ST_SINCE] += 1
        rec_k = pi[PI_RECORD_EVERY]
        if rec_k > 0 and st[ST_TRIALS] % rec_k == 0 and st[ST_TRIALS] // rec_k <= rec_v.shape[0]:
            rec_v[st[ST_TRIALS] // rec_k - 1, :, :] = child
        if st[ST_PHASE] == PHASE_INIT:
            st[ST_INIT_TRIALS] += 1
        if trunc:
            st[ST_TRUNCATED] += 1
        settle(pop, child, cost, sig, op, p1, p2, pi, st, best_cost, best_v, hist_t, hist_c, hist_o, op_count, rng,
               scr_ord, acc, n)
    return RC_CHUNK_DONE

