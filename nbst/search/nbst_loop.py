"""nbst's own search (variant ``nbst``): the paper's signature machinery plus the
structure it leaves unused.

What is added to the paper's algorithm (each can be switched off, for ablation):

* **polish** (``nbst.search.polish``): Levenberg-Marquardt with the analytic Jacobian,
  run on promising children -- a new best, or a child of the best order whose
  cost is within ``polish_ratio`` of the best -- and charged as the simulations
  it runs. The polished child is what gets inserted.
* **bank** operator (footnote 5): one disk of the parent is re-aimed straight at
  a mirror image of its target (0..``bank_bounces`` bounces), choosing among the
  images whose unfolded path meets the fewest other disks' current free flights
  (exact clearance, ``nbst.search.aim.choose_bank``; ties at random). Disks that are not
  acceptable in the parent are picked first half of the time. Repeated by the
  search, this is a min-conflicts walk towards a collision-free routing.
* **strike** operator (footnote 5, overconstrained problems only): a cueable disk
  is aimed to strike a noncueable disk so that the struck disk leaves towards its
  target or an image of it (``strike_bounces`` = b, default 1) and arrives at t_final.
  The image (kx, ky) is drawn uniformly from the square |kx|, |ky| <= b and an image
  outside the diamond |kx| + |ky| <= b falls back to the target itself, so the
  unreflected target is favoured: for b = 1 it has probability 5/9 and each of the
  four one-bounce images 1/9 (a direct strike is the likeliest to work). Drawing
  uniformly over the diamond instead would change every seeded result; half of the time
  (with two or more noncueable disks) through a chain: the cue strikes a first
  noncueable disk, which strikes the second towards its target.
* **backward planner** (``nbst.search.planner``, overconstrained problems only, before the loop):
  strike chains built from the targets backwards in closed form and checked with the
  simulator; its cheapest full candidates are initialize's first trials (``seeds``; a seed
  that triggers polish gets ``planner_polish_sims``), and its checked routes feed the
  **plan** operator: one noncueable disk of the parent (a non-acceptable one half of the
  time) gets a random route that moves it.
* **schedule**: operator probabilities adapt during the run: each operator's
  success (its child beats its parent, or raises the order) is an exponential
  moving average with rate ``adapt_rate``; probabilities are proportional to it,
  with a floor ``adapt_floor`` each.
* **straight start**: initialize's first trial sends every cueable disk straight
  at its target.
* **restarts**: after ``restart`` trials without improving the best found since
  the last restart, the population is re-initialized around the best so far
  (kept, elitism); polish's trigger is relative to the best since the restart,
  so a new basin gets polished too. The paper's stopping rule (patience) still
  counts trials since the overall best last improved.

Everything else -- Senate-like selection, engineered crossover, insert, culling,
elitism, stopping -- is the paper's, from ``nbst.search.ops``.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from nbst.search.aim import alloc_clearance, chain_strike_velocity, choose_bank, strike_velocity
from nbst.search.loop import OP_NAMES as PAPER_OP_NAMES
from nbst.search.loop import (PHASE_GENERATE, PHASE_INIT, RC_CHUNK_DONE, ST_BEST_SIG, ST_INIT_TRIALS, ST_PHASE,
                              ST_SINCE, ST_TRIALS, book_trial, evaluate_one, init_child, loop_scratch, mutate_one,
                              select_parent, settle, stop_code)
from nbst.search.ops import BEST, NTAB, SIZE, creep_velocity, crossover, insert_initial, limit_crossings, popcount, \
    rng_int, rng_uniform
from nbst.search.polish import POLISH_EVENT_CAP, alloc_polish, polish_kernel
from nbst.search.robust import robust_eval
from nbst.sim.primitives import mirror

__all__ = ["OP_NAMES", "N_OPS", "OP_CREEP", "OP_DIRECTED", "OP_UNIFORM", "OP_CROSSOVER", "OP_BANK", "OP_STRIKE",
           "OP_PLAN", "ROBUST_OFF", "ROBUST_AND", "ROBUST_PLAIN", "NbstParams", "QS_POLISH_RUNS", "QS_POLISH_SIMS",
           "QS_POLISH_GAINS", "QS_RESTARTS", "QS_LOCAL_SIG", "QS_LOCAL_SINCE", "QS_ROBUST_SIMS", "QS_SIMS", "N_QS",
           "NbstArrays", "Plans", "NbstScratch", "run_chunk_nbst"]

# operators of the nbst variant: the paper's four (``nbst.search.loop.OP_NAMES``), then nbst's
OP_NAMES = PAPER_OP_NAMES + ("bank", "strike", "plan")
N_OPS = len(OP_NAMES)
OP_CREEP, OP_DIRECTED, OP_UNIFORM, OP_CROSSOVER, OP_BANK, OP_STRIKE, OP_PLAN = range(N_OPS)

#: ``NbstParams.robust``: off, the AND of the shifted signatures, or the unshifted signature.
ROBUST_OFF, ROBUST_AND, ROBUST_PLAIN = 0, 1, 2


class NbstParams(NamedTuple):
    """nbst's additions' parameters (``SearchParams`` fields; flags are ints, 0 off)."""

    polish: int
    polish_sims: int
    bank_bounces: int
    adapt: int
    straight_start: int
    strike_bounces: int
    restart: int  # 0: never
    robust: int  # ROBUST_*
    seed_polish_sims: int  # polish budget of a planner seed
    polish_ratio: float
    adapt_rate: float
    adapt_floor: float
    robust_shift: float  # SHIFT_STEPS x robust_timestep


# nbst's extra counters (qs: int64 array, mutable between chunks)
QS_POLISH_RUNS, QS_POLISH_SIMS, QS_POLISH_GAINS, QS_RESTARTS, QS_LOCAL_SIG, QS_LOCAL_SINCE, QS_ROBUST_SIMS, \
    QS_SIMS = range(8)
N_QS = 8


class NbstArrays(NamedTuple):
    """nbst's extra state between chunks: counters and the operator schedule."""

    qs: np.ndarray  # (N_QS,) int64, QS_* indices
    weights: np.ndarray  # (N_OPS,) operator probabilities now
    base: np.ndarray  # (N_OPS,) starting probabilities (0: operator off)
    reward: np.ndarray  # (N_OPS,) success moving averages (adapt)


class Plans(NamedTuple):
    """The backward planner's output for the loop (``nbst.search.planner``)."""

    seeds: np.ndarray  # (S, N, 2) initialize's first candidates
    route_cue: np.ndarray  # (R,) int64 the route's cue
    route_v: np.ndarray  # (R, 2) its velocity
    route_mask: np.ndarray  # (R,) int64 the noncueable disks it moved


class NbstScratch(NamedTuple):
    """Scratch of one chunk of nbst's loop (besides the paper loop's ``LoopScratch``)."""

    clear: tuple  # ``nbst.search.aim.alloc_clearance``
    polish: tuple  # ``nbst.search.polish.PolishScratch``
    out2: np.ndarray  # (2,) one disk's velocity
    T: np.ndarray  # (2,) a strike's aim point
    px0: np.ndarray  # (N, 2) shifted starts (robust)
    backup: np.ndarray  # (N, 2) a child before a robust polish


@njit(cache=True, error_model="numpy")
def _pick_op(rng, weights):
    tot = 0.0
    for k in range(weights.shape[0]):
        tot += weights[k]
    u = rng_uniform(rng) * tot
    acc = 0.0
    for k in range(weights.shape[0]):
        acc += weights[k]
        if u < acc and weights[k] > 0.0:
            return k
    for k in range(weights.shape[0] - 1, -1, -1):
        if weights[k] > 0.0:
            return k
    return 0


@njit(cache=True, error_model="numpy")
def _adapt(weights, base, reward, op, success, rate, floor):
    """Probability matching: reward[op] <- EMA of success; weights proportional to
    reward over the enabled operators (base > 0), each at least ``floor``."""
    reward[op] = (1.0 - rate) * reward[op] + rate * (1.0 if success else 0.0)
    tot = 0.0
    k_on = 0
    for k in range(weights.shape[0]):
        if base[k] > 0.0:
            tot += reward[k]
            k_on += 1
    for k in range(weights.shape[0]):
        if base[k] > 0.0:
            share = reward[k] / tot if tot > 0.0 else 1.0 / k_on
            weights[k] = floor + (1.0 - k_on * floor) * share
        else:
            weights[k] = 0.0


@njit(cache=True, error_model="numpy")
def _pick_disk(idx, sig, rng, prefer_bad):
    """A disk from idx: half of the time (if prefer_bad) one not acceptable in sig."""
    m = idx.shape[0]
    if prefer_bad and rng_uniform(rng) < 0.5:
        nbad = 0
        for q in range(m):
            if (sig >> idx[q]) & 1 == 0:
                nbad += 1
        if nbad > 0:
            r = rng_int(rng, nbad)
            for q in range(m):
                if (sig >> idx[q]) & 1 == 0:
                    if r == 0:
                        return idx[q]
                    r -= 1
    return idx[rng_int(rng, m)]


@njit(cache=True, error_model="numpy")
def _restart(sa, prm, na, n_seeds):
    """A fresh population around nothing but the best so far (kept, elitism); initialize again
    (not the seeds nor the straight start)."""
    ist = sa.pop.state
    ist[SIZE] = 0
    ist[NTAB] = 0
    ist[BEST] = -1
    insert_initial(sa.pop, sa.best_v, sa.best_cost[0], sa.st[ST_BEST_SIG], True, prm.elitism != 0, prm.sig_limit,
                   prm.pop_limit)
    sa.st[ST_PHASE] = PHASE_INIT
    sa.st[ST_INIT_TRIALS] = n_seeds + 1
    sa.best_cost[1] = np.inf
    na.qs[QS_LOCAL_SIG] = 0
    na.qs[QS_LOCAL_SINCE] = 0
    na.qs[QS_RESTARTS] += 1


@njit(cache=True, inline="always", error_model="numpy")
def _strike(x0, radius, mass, target, cue_idx, non_idx, W, H, t_final, bounces, sig, rng, T, out2):
    # Fourteen parameters on purpose: per-trial helpers take flat arrays (nbst.search.loop's note).
    """Strike operator on a copy of the parent (signature sig): a cueable disk aimed to strike a
    noncueable one (a non-acceptable one half of the time) towards its target or an image of
    it (the image draw favours the target itself, 5/9 for one bounce: module docstring); half
    of the time (two or more noncueable disks) through a chain. Returns (the cue, the strike
    time or -1 when the aim is impossible); its velocity is in out2."""
    nnon = non_idx.shape[0]
    s = _pick_disk(non_idx, sig, rng, True)
    c = cue_idx[rng_int(rng, cue_idx.shape[0])]
    b = bounces
    kx = rng_int(rng, 2 * b + 1) - b
    ky = rng_int(rng, 2 * b + 1) - b
    if abs(kx) + abs(ky) > b:
        kx = 0
        ky = 0
    T[0] = mirror(target[s, 0], kx, radius[s], W - radius[s])
    T[1] = mirror(target[s, 1], ky, radius[s], H - radius[s])
    if nnon >= 2 and rng_uniform(rng) < 0.5:
        s1 = non_idx[rng_int(rng, nnon)]
        while s1 == s:
            s1 = non_idx[rng_int(rng, nnon)]
        th = chain_strike_velocity(x0[c], radius[c], mass[c], x0[s1], radius[s1], mass[s1], x0[s], radius[s], mass[s],
                                   T, t_final, out2)
    else:
        th = strike_velocity(x0[c], radius[c], mass[c], x0[s], radius[s], mass[s], T, t_final, out2)
    return c, th


@njit(cache=True, inline="always", error_model="numpy")
def _plan_route(non_idx, route_cue, route_v, route_mask, sig, rng, child):
    """Plan operator: one noncueable disk (a non-acceptable one half of the time) gets a random
    planner route that moves it (any route if none does): that route's cue takes its velocity."""
    s = _pick_disk(non_idx, sig, rng, True)
    cnt = 0
    for r in range(route_cue.shape[0]):
        if (route_mask[r] >> s) & 1:
            cnt += 1
    if cnt == 0:
        r = rng_int(rng, route_cue.shape[0])
    else:
        k = rng_int(rng, cnt)
        r = 0
        while True:
            if (route_mask[r] >> s) & 1:
                if k == 0:
                    break
                k -= 1
            r += 1
    child[route_cue[r], 0] = route_v[r, 0]
    child[route_cue[r], 1] = route_v[r, 1]


@njit(cache=True, error_model="numpy")
def _polish(pa, prm, q, sa, na, rd, scr, xs, cost, sig, seeded):
    """Polish the promising child scr.child in place (the caller checked polish's trigger);
    every simulation is a trial, the polish's first (a repeat of the child's) included. Returns
    its (cost, signature). Called once per polish (~20 simulations), so it may take tuples."""
    order = popcount(sig)
    tol = max(prm.target_cost, 0.0)
    st, qs, child = sa.st, na.qs, scr.child
    budget = min(q.seed_polish_sims if seeded else q.polish_sims, prm.max_trials - st[ST_TRIALS])
    if budget < 2:
        return cost, sig
    robust = q.robust != ROBUST_OFF
    if robust:
        xs.backup[:, :] = child
    c2, s2, sims, _ = polish_kernel(pa.x0, child, pa.radius, pa.mass, pa.target, pa.W, pa.H, pa.t_final, prm.R,
                                    pa.cue_idx, budget, tol, scr.work, xs.polish)
    st[ST_TRIALS] += sims
    st[ST_SINCE] += sims
    qs[QS_SIMS] += sims
    qs[QS_LOCAL_SINCE] += sims
    qs[QS_POLISH_RUNS] += 1
    qs[QS_POLISH_SIMS] += sims
    if robust and c2 < cost:  # polish lowered the nominal cost: rescore under the perturbations
        c2, s_r, rs = robust_eval(pa, child, prm.R, prm.max_events, rd, q.robust_shift, c2, s2,
                                  q.robust == ROBUST_AND, xs.px0, scr)
        if q.robust == ROBUST_AND:
            s2 = s_r
        qs[QS_ROBUST_SIMS] += rs
        if not c2 < cost or popcount(s2) < order:
            child[:, :] = xs.backup
            c2 = np.inf
    if c2 < cost:
        qs[QS_POLISH_GAINS] += 1
        return c2, s2
    return cost, sig


@njit(cache=True, error_model="numpy")
def run_chunk_nbst(pa, prm, q, sa, na, rd, pl, n_steps):
    """Advance the nbst search by about n_steps trials (a polish may overrun by its budget,
    never past max_trials). Same contract as ``nbst.search.loop.run_chunk``, plus
    q (NbstParams), na (NbstArrays: counters and the operator schedule), rd
    (``nbst.search.robust.RobustDraws``: with q.robust on, every candidate is scored by
    ``robust_eval`` under them, polished children rescored) and pl (Plans: the planner's
    seeds, initialize's first candidates before the straight start, and its routes for
    the plan operator). sa.best_cost has shape (2,): [best overall, best since the last
    restart]. Every simulation is counted: qs[QS_SIMS] (robust mode's shifted runs apart, in
    qs[QS_ROBUST_SIMS]).

    One trial: restart if due; make a child (a planner seed, initialize's, or one operator on
    selected parents: the paper's steps from nbst.search.loop, or bank, strike, plan); limit it
    to the velocity domain; score it; count it; adapt the schedule; polish it if promising;
    settle it as the paper's loop does."""
    # Length on purpose (~110 lines): the tuples are unpacked once per chunk and the per-trial
    # steps take flat arrays (nbst.search.loop's note: a tuple per call costs a quarter of the speed).
    x0, target, radius, mass, cue_idx, non_idx, W, H, t_final, images = pa
    pop, st, best_cost, best_v, rng, hist_t, hist_c, hist_o, op_count = sa
    qs, weights, base, reward = na
    seeds, route_cue, route_v, route_mask = pl
    n = x0.shape[0]
    scr = loop_scratch(n, pop.vel.shape[0])
    work, child, fin, vel, no_t, no_i, no_s, scr_ord, scr_ok, acc = scr
    xs = NbstScratch(alloc_clearance(n), alloc_polish(n, cue_idx.shape[0], POLISH_EVENT_CAP), np.empty(2),
                     np.empty(2), np.empty((n, 2)), np.empty((n, 2)))
    clear, _, out2, T, _, _ = xs
    no_rec = np.empty((0, n, 2))
    n_seeds = seeds.shape[0]
    tol = max(prm.target_cost, 0.0)
    for _ in range(n_steps):
        rc = stop_code(prm, st, best_cost, hist_t.shape[0])
        if rc != RC_CHUNK_DONE:
            return rc
        if (q.restart > 0 and st[ST_PHASE] == PHASE_GENERATE and qs[QS_LOCAL_SINCE] >= q.restart
                and best_cost[0] < np.inf):
            _restart(sa, prm, na, n_seeds)
        # make a child
        op = -1
        p1 = -1
        p2 = -1
        parent_cost = np.inf
        parent_order = 0
        seeded = st[ST_PHASE] == PHASE_INIT and st[ST_INIT_TRIALS] < n_seeds
        if seeded:
            child[:, :] = seeds[st[ST_INIT_TRIALS]]
        elif st[ST_PHASE] == PHASE_INIT:
            init_child(x0, target, radius, W, H, t_final, images, cue_idx, prm.p_directed_init,
                       q.straight_start != 0 and st[ST_INIT_TRIALS] == n_seeds, rng, child)
        else:
            op = _pick_op(rng, weights)
            if op == OP_CROSSOVER and pop.state[SIZE] < 2:
                op = OP_CREEP
            p1 = select_parent(pop, n, prm.senate, rng, -1, scr_ord, scr_ok)
            parent_cost = pop.cost[p1]
            parent_order = popcount(pop.sig[p1])
            if op == OP_CROSSOVER:
                p2 = select_parent(pop, n, prm.senate, rng, p1, scr_ord, scr_ok)
                parent_cost = min(parent_cost, pop.cost[p2])
                parent_order = max(parent_order, popcount(pop.sig[p2]))
                crossover(pop.vel[p1], pop.vel[p2], pop.sig[p1], pop.sig[p2], cue_idx, prm.engineered != 0, rng,
                          child)
            else:
                child[:, :] = pop.vel[p1]
                if op == OP_STRIKE and non_idx.shape[0] > 0:
                    c, th = _strike(x0, radius, mass, target, cue_idx, non_idx, W, H, t_final, q.strike_bounces,
                                    pop.sig[p1], rng, T, out2)
                    if th > 0.0:
                        child[c, 0] = out2[0]
                        child[c, 1] = out2[1]
                    else:
                        creep_velocity(prm.creep_sigma, c, rng, child)
                elif op == OP_PLAN and route_cue.shape[0] > 0:
                    _plan_route(non_idx, route_cue, route_v, route_mask, pop.sig[p1], rng, child)
                else:
                    i = _pick_disk(cue_idx, pop.sig[p1], rng, op == OP_BANK)
                    if op == OP_CREEP or op == OP_STRIKE or op == OP_DIRECTED or op == OP_UNIFORM:
                        # a strike without noncueable disks is a creep
                        mutate_one(OP_CREEP if op == OP_STRIKE else op, i, x0, target, radius, W, H, t_final,
                                   images, prm.creep_sigma, rng, child)
                    else:  # bank (and plan without routes, which its zero weight never picks)
                        choose_bank(i, x0, child, radius, target, W, H, t_final, 0, q.bank_bounces, clear, rng,
                                    out2)
                        child[i, 0] = out2[0]
                        child[i, 1] = out2[1]
            op_count[op, 0] += 1
        limit_crossings(child, cue_idx, radius, W, H, t_final)
        # score it (robust mode: under the start shifts)
        cost, sig, trunc = evaluate_one(x0, child, radius, mass, target, W, H, t_final, prm.R, prm.max_events, work,
                                        fin, vel, no_t, no_i, no_s)
        if q.robust != ROBUST_OFF and not trunc and sig != 0:  # an order-0 candidate is rejected whatever its score
            c_r, s_r, sims = robust_eval(pa, child, prm.R, prm.max_events, rd, q.robust_shift, cost, sig,
                                         q.robust == ROBUST_AND, xs.px0, scr)
            cost = c_r
            if q.robust == ROBUST_AND:
                sig = s_r
            qs[QS_ROBUST_SIMS] += sims
        book_trial(st, 0, no_rec, child, trunc)
        qs[QS_SIMS] += 1
        qs[QS_LOCAL_SINCE] += 1
        order = popcount(sig)
        if op >= 0 and q.adapt != 0:
            _adapt(weights, base, reward, op, cost < parent_cost or order > parent_order, q.adapt_rate,
                   q.adapt_floor)
        # polish promising children (relative to this restart's best)
        if (q.polish != 0 and order > 0 and not trunc and cost > tol
                and (cost < best_cost[1] or (order >= popcount(qs[QS_LOCAL_SIG])
                                             and cost < q.polish_ratio * best_cost[1]))):
            cost, sig = _polish(pa, prm, q, sa, na, rd, scr, xs, cost, sig, seeded)
        if popcount(sig) > 0 and cost < best_cost[1]:  # the best since the last restart (polish's reference)
            best_cost[1] = cost
            qs[QS_LOCAL_SIG] = sig
            qs[QS_LOCAL_SINCE] = 0
        settle(pop, st, best_cost, best_v, hist_t, hist_c, hist_o, op_count, rng, child, cost, sig, op, p1, p2, prm,
               scr_ord, acc, n)
    return RC_CHUNK_DONE
