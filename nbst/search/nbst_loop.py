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

import numpy as np
from numba import njit

from nbst.search.aim import alloc_clearance, chain_strike_velocity, choose_bank, strike_velocity
from nbst.search.polish import POLISH_EVENT_CAP, alloc_polish, polish_kernel
from nbst.search.robust import robust_eval
from nbst.search.loop import (PF_CREEP_SIGMA, PF_P_DIRECTED_INIT, PF_R, PF_TARGET_COST, PHASE_GENERATE, PHASE_INIT,
                          PI_ELITISM, PI_ENGINEERED, PI_MAX_EVENTS, PI_MAX_TRIALS, PI_POP_LIMIT, PI_SENATE,
                          PI_SIG_LIMIT, RC_CHUNK_DONE, ST_BEST_SIG, ST_INIT_TRIALS, ST_PHASE, ST_SINCE, ST_TRIALS,
                          ST_TRUNCATED, evaluate_one, loop_scratch, settle, stop_code)
from nbst.search.loop import OP_NAMES as PAPER_OP_NAMES
from nbst.sim.primitives import mirror
from nbst.search.ops import (BEST, NTAB, SIZE, limit_crossings, creep_velocity, crossover, directed_velocity, insert_initial, popcount,
                         rng_int, rng_uniform, select_senate, select_uniform, uniform_velocity)

# operators of the nbst variant: the paper's four (``nbst.search.loop.OP_NAMES``), then nbst's
OP_NAMES = PAPER_OP_NAMES + ("bank", "strike", "plan")
N_OPS = len(OP_NAMES)
OP_CREEP, OP_DIRECTED, OP_UNIFORM, OP_CROSSOVER, OP_BANK, OP_STRIKE, OP_PLAN = range(N_OPS)

# extra parameters (qi: int64, qf: float64)
QI_POLISH, QI_POLISH_SIMS, QI_BANK_BOUNCES, QI_ADAPT, QI_STRAIGHT_START, QI_STRIKE_BOUNCES, QI_RESTART, \
    QI_ROBUST, QI_SEED_POLISH_SIMS = range(9)
N_QI = 9
QF_POLISH_RATIO, QF_ADAPT_RATE, QF_ADAPT_FLOOR, QF_ROBUST_SHIFT = range(4)
N_QF = 4

# extra state (qs: int64)
QS_POLISH_RUNS, QS_POLISH_SIMS, QS_POLISH_GAINS, QS_RESTARTS, QS_LOCAL_SIG, QS_LOCAL_SINCE, QS_ROBUST_SIMS, \
    QS_SIMS = range(8)
N_QS = 8


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
def run_chunk_nbst(x0, target, radius, mass, cue_idx, non_idx, W, H, t_final, images, pi, pf, qi, qf,
                   pop, st, qs, best_cost, best_v, rng, hist_t, hist_c, hist_o, op_count, weights, base, reward,
                   zeta, smax, seeds, route_cue, route_v, route_mask, n_steps):
    """Advance the nbst search by about n_steps trials (a polish may overrun by its
    budget, never past max_trials). Same contract as ``nbst.search.loop.run_chunk``,
    plus qi/qf (QI_*, QF_* parameters), qs (QS_* state and statistics), the
    operator schedule arrays (weights, base, reward; each (N_OPS,)),
    best_cost of shape (2,): [best overall, best since the last restart], and the
    start shifts zeta (K, N, 2), smax (K,) of ``nbst.search.robust.draws``: with qi[QI_ROBUST]
    on, every candidate is scored by ``nbst.search.robust.robust_eval`` under them (cost = the
    worst, signature = the AND), polished children rescored. seeds (S, N, 2): initialize's
    first S candidates (the backward planner's, ``nbst.search.planner``), then the straight start;
    a seed is polished with qi[QI_SEED_POLISH_SIMS] simulations when polish's trigger holds.
    route_cue (R,), route_v (R, 2), route_mask (R,): the planner's routes for the ``plan``
    operator (one noncueable disk of the parent, not acceptable half of the time, is given a
    random route that moves it: that route's cue takes the route's velocity).
    Every simulation is counted: qs[QS_SIMS] (robust mode's shifted runs apart, in
    qs[QS_ROBUST_SIMS])."""
    n = x0.shape[0]
    cap = pop.vel.shape[0]
    ist = pop.state
    work, child, fin, vel, no_t, no_i, no_s, scr_ord, scr_ok, acc = loop_scratch(n, cap)
    clear = alloc_clearance(n)
    pscr = alloc_polish(n, cue_idx.shape[0], POLISH_EVENT_CAP)
    out2 = np.empty(2)
    T = np.empty(2)
    R = pf[PF_R]
    max_events = pi[PI_MAX_EVENTS]
    elitism = pi[PI_ELITISM] != 0
    ncue = cue_idx.shape[0]
    nnon = non_idx.shape[0]
    tol = max(pf[PF_TARGET_COST], 0.0)
    robust = qi[QI_ROBUST] != 0
    and_sig = qi[QI_ROBUST] == 1  # 1: signature = the AND over the shifted runs; 2: the unshifted one
    shift = qf[QF_ROBUST_SHIFT]
    px0 = np.empty((n, 2))
    backup = np.empty((n, 2))
    nseed = seeds.shape[0]

    for _ in range(n_steps):
        rc = stop_code(pi, pf, st, best_cost, hist_t.shape[0] - 1)
        if rc != RC_CHUNK_DONE:
            return rc
        if (qi[QI_RESTART] > 0 and st[ST_PHASE] == PHASE_GENERATE and qs[QS_LOCAL_SINCE] >= qi[QI_RESTART]
                and best_cost[0] < np.inf):
            # restart: a fresh population around nothing but the best so far
            ist[SIZE] = 0
            ist[NTAB] = 0
            ist[BEST] = -1
            insert_initial(pop, best_v, best_cost[0], st[ST_BEST_SIG], True, elitism, pi[PI_SIG_LIMIT],
                           pi[PI_POP_LIMIT])
            st[ST_PHASE] = PHASE_INIT
            st[ST_INIT_TRIALS] = nseed + 1  # not the seeds nor the straight start again
            best_cost[1] = np.inf
            qs[QS_LOCAL_SIG] = 0
            qs[QS_LOCAL_SINCE] = 0
            qs[QS_RESTARTS] += 1

        p1 = -1
        p2 = -1
        op = -1
        parent_cost = np.inf
        parent_order = 0
        seeded = st[ST_PHASE] == PHASE_INIT and st[ST_INIT_TRIALS] < nseed
        if seeded:
            child[:, :] = seeds[st[ST_INIT_TRIALS]]
        elif st[ST_PHASE] == PHASE_INIT:
            child[:, :] = 0.0
            straight = qi[QI_STRAIGHT_START] != 0 and st[ST_INIT_TRIALS] == nseed
            for q in range(ncue):
                i = cue_idx[q]
                if straight or rng_uniform(rng) < pf[PF_P_DIRECTED_INIT]:
                    directed_velocity(x0, target, t_final, i, child)
                else:
                    uniform_velocity(x0, radius, W, H, t_final, images, i, rng, child)
        else:
            op = _pick_op(rng, weights)
            if op == OP_CROSSOVER and ist[SIZE] < 2:
                op = OP_CREEP
            if pi[PI_SENATE] != 0:
                p1 = select_senate(pop, n, rng, -1, scr_ord, scr_ok)
            else:
                p1 = select_uniform(pop, rng, -1)
            parent_cost = pop.cost[p1]
            parent_order = popcount(pop.sig[p1])
            if op == OP_CROSSOVER:
                if pi[PI_SENATE] != 0:
                    p2 = select_senate(pop, n, rng, p1, scr_ord, scr_ok)
                else:
                    p2 = select_uniform(pop, rng, p1)
                parent_cost = min(parent_cost, pop.cost[p2])
                parent_order = max(parent_order, popcount(pop.sig[p2]))
                crossover(pop.vel[p1], pop.vel[p2], pop.sig[p1], pop.sig[p2], cue_idx, pi[PI_ENGINEERED] != 0,
                          rng, child)
            else:
                child[:, :] = pop.vel[p1]
                if op == OP_STRIKE and nnon > 0:
                    s = _pick_disk(non_idx, pop.sig[p1], rng, True)
                    c = cue_idx[rng_int(rng, ncue)]
                    b = qi[QI_STRIKE_BOUNCES]
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
                        th = chain_strike_velocity(x0[c], radius[c], mass[c], x0[s1], radius[s1], mass[s1],
                                                   x0[s], radius[s], mass[s], T, t_final, out2)
                    else:
                        th = strike_velocity(x0[c], radius[c], mass[c], x0[s], radius[s], mass[s], T, t_final,
                                             out2)
                    if th > 0.0:
                        child[c, 0] = out2[0]
                        child[c, 1] = out2[1]
                    else:
                        creep_velocity(pf[PF_CREEP_SIGMA], c, rng, child)
                elif op == OP_PLAN and route_cue.shape[0] > 0:
                    s = _pick_disk(non_idx, pop.sig[p1], rng, True)
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
                else:
                    i = _pick_disk(cue_idx, pop.sig[p1], rng, op == OP_BANK)
                    if op == OP_CREEP or op == OP_STRIKE:
                        creep_velocity(pf[PF_CREEP_SIGMA], i, rng, child)
                    elif op == OP_DIRECTED:
                        directed_velocity(x0, target, t_final, i, child)
                    elif op == OP_UNIFORM:
                        uniform_velocity(x0, radius, W, H, t_final, images, i, rng, child)
                    else:
                        choose_bank(i, x0, child, radius, target, W, H, t_final, 0, qi[QI_BANK_BOUNCES], clear,
                                    rng, out2)
                        child[i, 0] = out2[0]
                        child[i, 1] = out2[1]
            op_count[op, 0] += 1
        limit_crossings(child, cue_idx, radius, W, H, t_final)

        cost, sig, trunc = evaluate_one(x0, child, radius, mass, target, W, H, t_final, R, max_events, work,
                                        fin, vel, no_t, no_i, no_s)
        if robust and not trunc and sig != 0:  # an order-0 candidate is rejected whatever its score
            c_r, s_r, sims = robust_eval(x0, child, radius, mass, target, W, H, t_final, R, max_events, cue_idx,
                                         zeta, smax, shift, cost, sig, and_sig, px0, work, fin, vel, no_t, no_i, no_s)
            cost = c_r
            if and_sig:
                sig = s_r
            qs[QS_ROBUST_SIMS] += sims
        st[ST_TRIALS] += 1
        st[ST_SINCE] += 1
        qs[QS_SIMS] += 1
        qs[QS_LOCAL_SINCE] += 1
        if st[ST_PHASE] == PHASE_INIT:
            st[ST_INIT_TRIALS] += 1
        if trunc:
            st[ST_TRUNCATED] += 1
        order = popcount(sig)
        if op >= 0 and qi[QI_ADAPT] != 0:
            _adapt(weights, base, reward, op, cost < parent_cost or order > parent_order, qf[QF_ADAPT_RATE],
                   qf[QF_ADAPT_FLOOR])

        # polish promising children (relative to this restart's best), charged as the simulations they run
        local_order = popcount(qs[QS_LOCAL_SIG])
        if (qi[QI_POLISH] != 0 and order > 0 and not trunc and cost > tol
                and (cost < best_cost[1] or (order >= local_order and cost < qf[QF_POLISH_RATIO] * best_cost[1]))):
            # every simulation is a trial, the polish's first (a repeat of the child's) included
            budget = min(qi[QI_SEED_POLISH_SIMS] if seeded else qi[QI_POLISH_SIMS], pi[PI_MAX_TRIALS] - st[ST_TRIALS])
            if budget >= 2:
                if robust:
                    backup[:, :] = child
                c2, s2, sims, _ = polish_kernel(x0, child, radius, mass, target, W, H, t_final, R, cue_idx, budget,
                                             tol, work, pscr)
                st[ST_TRIALS] += sims
                st[ST_SINCE] += sims
                qs[QS_SIMS] += sims
                qs[QS_LOCAL_SINCE] += sims
                qs[QS_POLISH_RUNS] += 1
                qs[QS_POLISH_SIMS] += sims
                if robust and c2 < cost:  # polish lowered the nominal cost: rescore under the perturbations
                    c2, s_r, rs = robust_eval(x0, child, radius, mass, target, W, H, t_final, R, max_events, cue_idx,
                                              zeta, smax, shift, c2, s2, and_sig, px0, work, fin, vel, no_t, no_i,
                                              no_s)
                    if and_sig:
                        s2 = s_r
                    qs[QS_ROBUST_SIMS] += rs
                    if not c2 < cost or popcount(s2) < order:
                        child[:, :] = backup
                        c2 = np.inf
                if c2 < cost:
                    qs[QS_POLISH_GAINS] += 1
                    cost = c2
                    sig = s2
                    order = popcount(sig)

        if order > 0 and cost < best_cost[1]:  # the best since the last restart (polish's reference)
            best_cost[1] = cost
            qs[QS_LOCAL_SIG] = sig
            qs[QS_LOCAL_SINCE] = 0
        settle(pop, child, cost, sig, op, p1, p2, pi, st, best_cost, best_v, hist_t, hist_c, hist_o, op_count, rng,
               scr_ord, acc, n)
    return RC_CHUNK_DONE
