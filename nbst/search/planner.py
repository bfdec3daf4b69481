"""Backward (constructive) planner for problems with noncueable disks.

A noncueable disk moves only when struck, so a zero-cost motion of an overconstrained
problem re-creates a precise chain of strikes. The planner builds such chains from the
targets backwards instead of sampling cue velocities forwards:

* **A route** of cueable disk c is a chain ``c = a0 -> a1 -> ... -> aL`` (L = 0..3,
  the a_k distinct noncueable disks at rest) plus one mirror image per leg. The last
  disk aL must reach its target: it leaves along n_L = (T' - p_L)/|T' - p_L| (T' the
  image of its target, see ``nbst.sim.primitives.mirror``), so a_{L-1} must touch it at
  q_L = p_L - (r_{L-1} + r_L) n_L, arriving (along its own leg, direct or banked) with a
  normal component that gives aL its speed. Going back leg by leg fixes every leg's
  direction; the speeds follow from the elastic exchange (masses included):
  w_{k+1} = w_k c_k 2 m_k / (m_k + m_{k+1}), c_k the cosine between a_k's arrival
  direction and n_{k+1}. The timing equation ``sum_k leg_k / w_k + D_L / w_L = t_final``
  is linear in 1/w_0, so each leaf is solved in closed form (``chain_aim``) and gives
  the cue velocity. L = 0 is a bank shot at the cue's own target.
* The route's other disks (the cue, the intermediate a_k) then move as they must; the
  closed form predicts where each ends (free flight after its last strike), so every
  route has a predicted *gain* (its disks' squared misses minus the noncueable disks'
  misses at rest). Routes are ranked by it (best first) and the best are checked with
  the exact simulator, that cue and the noncueable disks alone (the other cues are
  elsewhere by then; another disk may get in the way, a cue may strike a second disk on
  its way: the simulation sees it), and re-scored with the simulated gain.
* **Per cue, the paper's bookkeeping**: routes are grouped by their signature (which disks
  they move, which of those end within R) and each signature keeps its ``sig_limit``
  cheapest routes, as the paper's per-signature limit does.
* **Combination**: one route per cueable disk, the moved noncueable sets disjoint; the
  combinations are enumerated best-first by their predicted total cost (A* over the cues,
  the heuristic being the remaining cues' best compatible routes) and each is simulated in
  full. The cheapest become the search's first candidates (``nbst.search.nbst_loop``:
  initialize's first trials), where polish refines them; the checked routes feed its
  ``plan`` operator.
* **Sweeps**: for the best combinations, each cue's routes are re-simulated with the
  other cues moving as combined (coordinate descent over the discrete choices), which
  catches chains in which disks of different cues meet.

Every simulation the planner runs is a trial (``PlanResult.trials``); the search charges
them before its own.

Length: ~530 lines, over the house's ~500, on purpose: the four stages above share the
route arrays and the ``_Sim`` closure, and read best in order in one file.
"""
from __future__ import annotations

import heapq
import itertools
import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from nbst.constants import MAX_EVENTS
from nbst.problem import Problem
from nbst.sim import evaluate_kernel
from nbst.sim.primitives import fold, images, impulse_share, mirror, transferred_speed

__all__ = ["MIN_COS", "MAX_SPEED", "MAX_ROUTES_PER_LENGTH", "ROUTES_PER_CUE", "MOVED_EPS", "BANKS_PER_CUE", "BATCH",
           "ROUTE_SHARE", "BANK_SHARE", "SWEEP_SHARE", "SWEEP_PASSES", "MIN_POPS", "POPS_PER_COMBINATION", "chain_aim",
           "aim_routes", "PlanResult", "MAX_MASK_BITS", "plan"]

#: A strike whose arrival direction makes a cosine below this with the line of centres is
#: rejected: it transfers almost nothing, and its outcome is hypersensitive.
MIN_COS = 0.02
#: Fastest cue a route may ask for, in box diagonals per t_final: a faster route bounces so
#: often, and amplifies errors so much, that its seeds mislead the search (measured: without
#: the cap, planner seeds at 8 diagonals/t_final and worse searches). A planted generator's
#: striker right behind its target can be faster (15 of 370 cues, N = 6-20, seeds 1-10).
MAX_SPEED = 4.0
#: Enumerate at most this many routes per chain length (longer chains drop to fewer images).
MAX_ROUTES_PER_LENGTH = 60_000
#: Routes of one cue kept for the combination (best predicted or simulated gain first).
ROUTES_PER_CUE = 48
#: A disk counts as moved by a route if it ends farther than this from its start (units).
MOVED_EPS = 1e-9
#: Bank shots per cue kept for the sweeps and the search's plan operator (besides the best).
BANKS_PER_CUE = 4
#: Simulations per batch (memory: batch x N x 2 floats).
BATCH = 4096
#: Share of the budget for checking single routes (stage 2); the rest goes to combinations
#: and sweeps. Routes are cheap to check (one cue and the noncueable disks alone), and a
#: combination is only as good as the routes it is built from.
ROUTE_SHARE = 2  # 1 / ROUTE_SHARE of the budget
#: Of a cue's route checks, at most 1 / BANK_SHARE go to bank shots (its own target through
#: images): they move no noncueable disk, so one good bank per cue is all a combination needs.
BANK_SHARE = 8
#: The sweeps may take at most 1 / SWEEP_SHARE of what is left after the route checks, so the
#: combinations keep most of it (the sweeps only refine the best few).
SWEEP_SHARE = 3
#: Passes of coordinate descent per swept combination (each cue's routes re-simulated with
#: the others moving); a second pass catches a cue whose best route changed with another's.
SWEEP_PASSES = 2
#: The best-first combination search pops at most max(MIN_POPS, POPS_PER_COMBINATION x the
#: combinations it may simulate) heap entries: enough to find them, bounded when most
#: partial combinations clash (shared noncueable disks).
MIN_POPS = 10_000
POPS_PER_COMBINATION = 20


@njit(cache=True, error_model="numpy")
def chain_aim(x0, radius, mass, target, W, H, t_final, chain, L, imgs, out_v, out_t, out_pred):
    # Thirteen parameters on purpose: a closed form over flat arrays (numba), called per route
    # from ``aim_routes``'s loop.
    """Closed-form aim of one chain ``chain[0] -> chain[1] -> ... -> chain[L]`` (disks at rest
    but the first). ``imgs[k]`` (kx, ky): for k < L the image, in chain[k]'s frame, of the point
    where chain[k] touches chain[k+1]; for k = L the image of chain[L]'s target.

    Writes the first disk's velocity to out_v (2,), the contact times to out_t[0:L] and each
    chain disk's predicted final position (free flight after its last strike) to
    out_pred[0:L+1]; returns the first disk's speed, or -1 when the chain is impossible (a
    contact point outside the box, a strike from the far side or too glancing)."""
    nd = np.empty((L + 1, 2))
    arr = np.empty((L + 1, 2))
    q = np.empty((L + 1, 2))
    leg = np.empty(L + 1)
    cs = np.empty(L + 1)
    g = np.empty(L + 1)
    a = chain[L]
    r = radius[a]
    tx = mirror(target[a, 0], imgs[L, 0], r, W - r)
    ty = mirror(target[a, 1], imgs[L, 1], r, H - r)
    dx = tx - x0[a, 0]
    dy = ty - x0[a, 1]
    D = math.sqrt(dx * dx + dy * dy)
    if D == 0.0:
        if L > 0:
            return -1.0
        out_v[0] = 0.0
        out_v[1] = 0.0
        out_pred[0, 0] = target[a, 0]
        out_pred[0, 1] = target[a, 1]
        return 0.0
    nd[L, 0] = dx / D
    nd[L, 1] = dy / D
    for k in range(L - 1, -1, -1):
        a = chain[k]
        b = chain[k + 1]
        ra = radius[a]
        s = ra + radius[b]
        qx = x0[b, 0] - s * nd[k + 1, 0]
        qy = x0[b, 1] - s * nd[k + 1, 1]
        if qx < ra or qx > W - ra or qy < ra or qy > H - ra:
            return -1.0
        ex = mirror(qx, imgs[k, 0], ra, W - ra) - x0[a, 0]
        ey = mirror(qy, imgs[k, 1], ra, H - ra) - x0[a, 1]
        lk = math.sqrt(ex * ex + ey * ey)
        if lk == 0.0:
            return -1.0
        ex /= lk
        ey /= lk
        ax = ex if imgs[k, 0] % 2 == 0 else -ex
        ay = ey if imgs[k, 1] % 2 == 0 else -ey
        c = ax * nd[k + 1, 0] + ay * nd[k + 1, 1]
        if c < MIN_COS:
            return -1.0
        nd[k, 0] = ex
        nd[k, 1] = ey
        arr[k, 0] = ax
        arr[k, 1] = ay
        q[k, 0] = qx
        q[k, 1] = qy
        leg[k] = lk
        cs[k] = c
    g[0] = 1.0
    for k in range(L):
        a = chain[k]
        b = chain[k + 1]
        g[k + 1] = transferred_speed(g[k] * cs[k], mass[a], mass[b])
    total = D / g[L]
    for k in range(L):
        total += leg[k] / g[k]
    w0 = total / t_final
    out_v[0] = w0 * nd[0, 0]
    out_v[1] = w0 * nd[0, 1]
    t = 0.0
    for k in range(L):
        a = chain[k]
        b = chain[k + 1]
        w = w0 * g[k]
        t += leg[k] / w
        out_t[k] = t
        # the striker keeps its tangential part and loses the transferred normal part
        tr = impulse_share(mass[b], mass[a]) * w * cs[k]
        vx = w * arr[k, 0] - tr * nd[k + 1, 0]
        vy = w * arr[k, 1] - tr * nd[k + 1, 1]
        dt = t_final - t
        ra = radius[a]
        out_pred[k, 0] = fold(q[k, 0] + vx * dt, ra, W - ra)
        out_pred[k, 1] = fold(q[k, 1] + vy * dt, ra, H - ra)
    out_pred[L, 0] = target[chain[L], 0]
    out_pred[L, 1] = target[chain[L], 1]
    return w0


@njit(cache=True, error_model="numpy")
def aim_routes(x0, radius, mass, target, W, H, t_final, chains, L, imgs, vmax, V, gain):
    # Thirteen parameters on purpose: the batch entry point over flat arrays (numba).
    """Aim every route (chains (M, L+1), imgs (M, L+1, 2)): cue velocities V (M, 2) and the
    predicted gain (M,) (squared misses of the chain's disks at their predicted ends minus the
    noncueable ones' misses at rest; inf when the chain is impossible or the cue would need
    more than vmax units/s)."""
    out_t = np.empty(max(L, 1))
    pred = np.empty((L + 1, 2))
    v = np.empty(2)
    for m in range(chains.shape[0]):
        w = chain_aim(x0, radius, mass, target, W, H, t_final, chains[m], L, imgs[m], v, out_t, pred)
        if w < 0.0 or w > vmax:
            gain[m] = np.inf
            V[m, 0] = 0.0
            V[m, 1] = 0.0
            continue
        V[m, 0] = v[0]
        V[m, 1] = v[1]
        acc = 0.0
        for k in range(L + 1):
            a = chains[m, k]
            dx = pred[k, 0] - target[a, 0]
            dy = pred[k, 1] - target[a, 1]
            acc += dx * dx + dy * dy
            if k > 0:
                dx = x0[a, 0] - target[a, 0]
                dy = x0[a, 1] - target[a, 1]
                acc -= dx * dx + dy * dy
        gain[m] = acc


def _images(b: int) -> np.ndarray:
    """Mirror images with at most b bounces, fewest bounces first (then kx, ky ascending)."""
    im = images(0, b)
    return im[np.argsort(np.abs(im).sum(axis=1), kind="stable")]


@dataclass(frozen=True)
class PlanResult:
    """The planner's output: candidate velocities (S, N, 2) cheapest first, their costs (S,),
    its statistics (``trials``: every simulation it ran), and the routes it kept for the
    search's ``plan`` operator: route_cue (R,) the cue, route_v (R, 2) its velocity,
    route_mask (R,) int64 the noncueable disks the route moved (bitmask over all disks)."""

    velocities: np.ndarray
    costs: np.ndarray
    trials: int
    stats: dict
    route_cue: np.ndarray | None = None
    route_v: np.ndarray | None = None
    route_mask: np.ndarray | None = None


class _Sim:
    """Batched exact simulation with a trial budget (every call is charged)."""

    def __init__(self, problem: Problem, budget: int, max_events: int):
        self.p = problem
        self.budget = int(budget)
        self.used = 0
        self.max_events = int(max_events)
        ka = problem.kernel_arrays()
        self.ka = ka
        self.args = (ka.start, ka.radius, ka.mass, ka.target)

    @property
    def left(self) -> int:
        return self.budget - self.used

    def __call__(self, V: np.ndarray, keep: np.ndarray | None = None):
        """Simulate up to ``left`` of the (B, N, 2) candidates: (final, cost, sig) of those run.
        With ``keep`` (indices), only those disks exist (the others stay at their starts and
        are left out of cost and signature)."""
        V = np.ascontiguousarray(V[:max(self.left, 0)], dtype=np.float64)
        B, n = V.shape[0], self.p.n
        x0, radius, mass, target = self.args
        if keep is not None:
            x0, radius, mass, target = (np.ascontiguousarray(a[keep]) for a in self.args)
            V = np.ascontiguousarray(V[:, keep])
            n = len(keep)
        final = np.empty((B, n, 2))
        cost = np.empty(B)
        sig = np.empty(B, np.int64)
        nev = np.empty(B, np.int64)
        for s in range(0, B, BATCH):
            e = min(B, s + BATCH)
            evaluate_kernel(x0, V[s:e], radius, mass, target, self.ka.W, self.ka.H, self.ka.t_final, self.ka.R,
                            self.max_events, final[s:e], cost[s:e], sig[s:e], nev[s:e])
        self.used += B
        if keep is not None:
            full = np.repeat(np.asarray(self.p.start, float)[None], B, axis=0)
            full[:, keep] = final
            final = full
        return final, cost, sig


def _enumerate(problem: Problem, c: int, non: np.ndarray, max_chain: int, bank_b: int, pre_b: int, fin_b: int):
    """All routes of cue c up to chain length max_chain: (chains, imgs, V, gain) per length
    (impossible chains dropped). A length whose routes would exceed MAX_ROUTES_PER_LENGTH
    uses fewer images for the strikers' legs, or is left out."""
    x0, target, radius, mass, W, H, t_final, _ = problem.kernel_arrays()
    out = []
    for L in range(0, max_chain + 1):
        perms = [(c,)] if L == 0 else [(c,) + t for t in itertools.permutations(non.tolist(), L)]
        if not perms:
            break
        fin = _images(bank_b if L == 0 else fin_b)
        pb = pre_b
        while pb > 0 and len(perms) * len(_images(pb)) ** L * len(fin) > MAX_ROUTES_PER_LENGTH:
            pb -= 1
        pre = _images(pb)
        if len(perms) * len(pre) ** L * len(fin) > MAX_ROUTES_PER_LENGTH:
            break
        combos = list(itertools.product(range(len(pre)), repeat=L))
        M = len(perms) * len(combos) * len(fin)
        chains = np.repeat(np.array(perms, np.int64), len(combos) * len(fin), axis=0)
        imgs = np.empty((M, L + 1, 2), np.int64)
        pre_part = np.array([[pre[i] for i in cb] for cb in combos], np.int64).reshape(len(combos), L, 2)
        block = np.concatenate([np.repeat(pre_part, len(fin), axis=0),
                                np.tile(fin, (len(combos), 1)).reshape(-1, 1, 2)], axis=1)
        imgs[:] = np.tile(block, (len(perms), 1, 1))
        V = np.empty((M, 2))
        gain = np.empty(M)
        vmax = MAX_SPEED * math.hypot(W, H) / t_final
        aim_routes(x0, radius, mass, target, W, H, t_final, chains, L, imgs, vmax, V, gain)
        ok = np.isfinite(gain)
        out.append((chains[ok], imgs[ok], V[ok], gain[ok]))
    return out


def _routes(problem: Problem, c: int, non: np.ndarray, max_chain: int, bank_b: int, pre_b: int, fin_b: int):
    """Cue c's routes, all lengths together, best predicted first:
    (V (M, 2), gain (M,), length (M,), first struck disk (M,), -1 for a bank shot)."""
    Vs, gs, Ls, firsts, bs = [], [], [], [], []
    for chains, imgs, V, gain in _enumerate(problem, c, non, max_chain, bank_b, pre_b, fin_b):
        L = chains.shape[1] - 1
        Vs.append(V)
        gs.append(gain)
        Ls.append(np.full(len(gain), L))
        firsts.append(chains[:, 1] if L > 0 else np.full(len(gain), -1))
        bs.append(np.abs(imgs).sum(axis=(1, 2)))
    V, g, L, first, b = (np.concatenate(x) for x in (Vs, gs, Ls, firsts, bs))
    o = np.lexsort((b, L, g))
    return V[o], g[o], L[o], first[o]


#: The combination search uses masks of the noncueable disks as table indices up to this many.
MAX_MASK_BITS = 10


def _best_first(lists, n_non_bits, limit_pops):
    """Combinations of one route per cue with disjoint moved sets, in nondecreasing predicted
    total gain: A* over the cues in turn. ``lists``: per cue (gain (m,) sorted, mask (m,)),
    masks over ``n_non_bits`` bits (the noncueable disks, renumbered). The heuristic (exact
    for one remaining cue, admissible for more) is the sum over the remaining cues of their best
    route compatible with the disks already moved, tabulated per mask. Yields index tuples."""
    C = len(lists)
    use_masks = n_non_bits <= MAX_MASK_BITS
    M = 1 << n_non_bits if use_masks else 1
    Hs = np.zeros((C + 1, M))
    for k in range(C - 1, -1, -1):
        g, mk = lists[k]
        if use_masks:
            best = np.full(M, np.inf)
            np.minimum.at(best, mk, g)
            comp = np.array([best[(np.arange(M) & m) == 0].min() for m in range(M)])
        else:
            comp = np.full(1, g.min())
        Hs[k] = Hs[k + 1] + comp
    heap = [(Hs[0, 0], 0.0, 0, 0, ())]
    pops = 0
    while heap and pops < limit_pops:
        f, gsum, k, mask, idx = heapq.heappop(heap)
        pops += 1
        if k == C:
            yield idx
            continue
        g, mk = lists[k]
        for i in range(len(g)):
            m = int(mk[i])
            if m & mask:
                continue
            nm = mask | m
            ng = gsum + float(g[i])
            h = Hs[k + 1, nm] if use_masks else Hs[k + 1, 0]
            if np.isfinite(h):
                heapq.heappush(heap, (ng + h, ng, k + 1, nm, idx + (i,)))


def _score_routes(problem: Problem, c: int, non: np.ndarray, fin: np.ndarray, cost: np.ndarray):
    """Simulated gains (B,), moved-noncueable bitmasks (B,) and signature keys (B,) of cue c's
    routes from their final positions fin (B, N, 2) (c and the noncueable disks alone)."""
    start, target = np.asarray(problem.start, float), np.asarray(problem.target, float)
    rest = np.sum((start - target) ** 2, axis=1)
    miss = np.sum((fin - target) ** 2, axis=2)
    moved = np.hypot(*(fin - start).transpose(2, 0, 1)) > MOVED_EPS
    moved[:, c] = False
    g = miss[:, c] + np.sum((miss - rest) * moved, axis=1)
    g[~np.isfinite(cost)] = np.inf
    bits = np.left_shift(np.int64(1), np.arange(problem.n, dtype=np.int64))
    mask = (moved[:, non] * bits[non]).sum(axis=1)
    ok = miss <= problem.target_radius ** 2
    inv = moved.copy()
    inv[:, c] = True
    okmask = ((ok & inv) * bits).sum(axis=1)
    return g, mask, mask * (np.int64(1) << np.int64(min(problem.n, 31))) + okmask


class _Planning:
    """One planner run's shared state: the problem's index sets, the budgeted simulator, the
    candidates found (cheapest per velocity set) and the statistics."""

    def __init__(self, problem: Problem, budget: int, max_events: int, target_cost: float):
        self.problem = problem
        self.n = problem.n
        cueable = np.asarray(problem.cueable, bool)
        self.cue = np.flatnonzero(cueable)
        self.non = np.flatnonzero(~cueable)
        self.sim = _Sim(problem, budget, max_events)
        self.target_cost = target_cost
        self.found: dict = {}
        self.stats = {"routes_aimed": 0, "routes_simulated": 0, "combinations": 0, "sweep_simulations": 0}

    def record(self, Vb, costs) -> None:
        for k in range(len(costs)):
            if np.isfinite(costs[k]):
                kb = Vb[k].tobytes()
                if kb not in self.found or costs[k] < self.found[kb][0]:
                    self.found[kb] = (float(costs[k]), Vb[k].copy())

    def done(self) -> bool:
        return self.sim.left <= 0 or any(c <= self.target_cost for c, _ in self.found.values())

    def assemble(self, lists, idx) -> np.ndarray:
        """The full velocity set of one route per cue (idx[k]: cue k's route in lists[k])."""
        v = np.zeros((self.n, 2))
        for k, i in enumerate(idx):
            v[self.cue[k]] = lists[k][0][i]
        return v


def _check_routes(pl: _Planning, c: int, share: int, routes_args: tuple, sig_limit: int):
    """Stages 1-2 for cue c: aim its routes in closed form, check the best ``share`` with the
    simulator (the cue and the noncueable disks alone), keep each signature's ``sig_limit``
    best. Returns (kept: the best bank and the useful strikes, wide: the same plus up to
    BANKS_PER_CUE banks), each (V (m, 2), gain (m,), moved mask (m,)) sorted by gain."""
    n, non, sim = pl.n, pl.non, pl.sim
    V, g, L, first = _routes(pl.problem, int(c), non, *routes_args)
    pl.stats["routes_aimed"] += len(g)
    nb = max(1, share // BANK_SHARE)
    banks = np.flatnonzero(L == 0)[:nb]
    strikes = np.flatnonzero(L > 0)[:max(0, share - len(banks))]
    todo = np.concatenate([banks, strikes])[:max(sim.left, 0) if not pl.done() else 0]
    if len(todo) == 0:
        kept = (V[:1], np.zeros(1), np.zeros(1, np.int64))
        return kept, kept
    VV = np.zeros((len(todo), n, 2))
    VV[:, c] = V[todo]
    fin, cost, _ = sim(VV, np.concatenate([[c], non]))  # the other cues are elsewhere by then
    pl.stats["routes_simulated"] += len(fin)
    gs, mask, key = _score_routes(pl.problem, int(c), non, fin, cost)
    # the paper's per-signature limit, per cue: each signature keeps its sig_limit best routes
    o = np.lexsort((gs, key))
    rank = np.zeros(len(o), np.int64)
    for q in range(1, len(o)):
        rank[o[q]] = rank[o[q - 1]] + 1 if key[o[q]] == key[o[q - 1]] else 0
    keep = np.isfinite(gs) & (rank < sig_limit)
    bank_ok = keep & (mask == 0)
    floor = gs[bank_ok].min() if bank_ok.any() else np.inf
    best_bank = np.flatnonzero(bank_ok & (gs == floor))[:1]
    useful = np.flatnonzero(keep & (mask != 0) & (gs < floor))
    useful = useful[np.argsort(gs[useful], kind="stable")][:ROUTES_PER_CUE]
    sel = np.concatenate([best_bank, useful])
    if len(sel) == 0:
        sel = np.array([0])
    sel = sel[np.argsort(gs[sel], kind="stable")]
    kept = (V[todo][sel], np.where(np.isfinite(gs[sel]), gs[sel], 0.0), mask[sel])
    banks_ok = np.flatnonzero(bank_ok)
    more = banks_ok[np.argsort(gs[banks_ok], kind="stable")][:BANKS_PER_CUE]
    sel = np.unique(np.concatenate([sel, more]))
    sel = sel[np.argsort(gs[sel], kind="stable")]
    return kept, (V[todo][sel], np.where(np.isfinite(gs[sel]), gs[sel], 0.0), mask[sel])


def _combine(pl: _Planning, lists, wide, sweeps: int) -> list:
    """Stage 3: combinations of one route per cue, best first (disjoint noncueable sets), each
    simulated in full; returns the ``sweeps`` cheapest (index tuples)."""
    n, non, sim = pl.n, pl.non, pl.sim
    sweep_cost = sweeps * SWEEP_PASSES * sum(len(lst[1]) for lst in wide)
    combo_budget = max(1, sim.left - min(sim.left // SWEEP_SHARE, sweep_cost))
    batch: list = []
    picks: list = []
    renum = np.zeros(n, np.int64)  # masks over the noncueable disks only, renumbered 0..K-1
    renum[non] = np.arange(non.size)
    small = []
    for _, gl, ml in lists:
        bits = np.array([sum(1 << int(renum[j]) for j in non if (int(m) >> int(j)) & 1) for m in ml], np.int64)
        small.append((gl, bits))
    for idx in _best_first(small, non.size, limit_pops=max(MIN_POPS, POPS_PER_COMBINATION * combo_budget)):
        if len(batch) >= combo_budget:
            break
        batch.append(pl.assemble(lists, idx))
        picks.append(idx)
    if not batch or pl.done():
        return []
    Vb = np.array(batch)
    _, cost, _ = sim(Vb)
    pl.stats["combinations"] = len(cost)
    pl.record(Vb[:len(cost)], cost)
    o = np.argsort(cost, kind="stable")
    return [picks[i] for i in o[:sweeps] if np.isfinite(cost[i])]


def _sweep(pl: _Planning, lists, wide, idx) -> None:
    """Stage 4 for one top combination: each cue's routes (banks included) again, with the other
    cues moving as combined; the best route of each cue in turn is kept (coordinate descent)."""
    cue = pl.cue
    v = pl.assemble(lists, idx)
    cur = [-1] * len(cue)
    for _ in range(SWEEP_PASSES):
        changed = False
        for k in range(len(cue)):
            if len(wide[k][1]) < 2 or pl.done():
                continue
            Vb = np.repeat(v[None], len(wide[k][1]), axis=0)
            Vb[:, cue[k]] = wide[k][0]
            _, cost, _ = pl.sim(Vb)
            pl.stats["sweep_simulations"] += len(cost)
            pl.record(Vb[:len(cost)], cost)
            if len(cost) and np.isfinite(cost).any():
                b = int(np.argmin(cost))
                if b != cur[k]:
                    cur[k] = b
                    changed = True
                v[cue[k]] = wide[k][0][b]
        if not changed:
            break


def plan(problem: Problem, *, budget: int, max_chain: int = 3, bank_bounces: int = 3, pre_bounces: int = 1,
         final_bounces: int = 2, sig_limit: int = 10, seeds: int = 16, sweeps: int = 4,
         max_events: int = MAX_EVENTS, target_cost: float = -math.inf) -> PlanResult:
    """Plan strike chains backwards from the targets; return the best full candidates found.

    budget        : simulations allowed (route checks, combinations, sweeps), all counted
    max_chain     : longest chain cue -> noncueable -> ... (number of struck disks)
    bank_bounces  : images of a cue's own target (route of length 0)
    pre_bounces   : images of each contact point (a striker's leg: direct or banked)
    final_bounces : images of the last struck disk's target
    sig_limit     : routes kept per signature and cue (the paper's per-signature limit)
    seeds         : candidates returned (cheapest first)
    sweeps        : combinations refined by re-simulating each cue's routes with the others moving
    target_cost   : stop as soon as a candidate costs this little (the straight shot is tried first)
    """
    pl = _Planning(problem, budget, max_events, target_cost)
    n, cue = pl.n, pl.cue
    if pl.non.size == 0 or cue.size == 0 or budget <= 0:
        return PlanResult(np.zeros((0, n, 2)), np.zeros(0), 0, pl.stats, np.zeros(0, np.int64), np.zeros((0, 2)),
                          np.zeros(0, np.int64))
    straight = problem.straight_velocities()[None]
    pl.record(straight, pl.sim(straight)[1])
    # 1.-2. every cue's routes, the best checked with the simulator: 1 / ROUTE_SHARE of the budget
    share = max(1, (budget // ROUTE_SHARE) // len(cue))
    lists = []  # per cue: the best bank and the useful strikes
    wide = []  # per cue, the same plus up to BANKS_PER_CUE banks (for sweeps and the search's plan operator)
    for c in cue:
        kept, more = _check_routes(pl, int(c), share, (max_chain, bank_bounces, pre_bounces, final_bounces),
                                   sig_limit)
        lists.append(kept)
        wide.append(more)
    # 3. combinations; 4. sweeps of the best ones
    for idx in _combine(pl, lists, wide, sweeps):
        if pl.done():
            break
        _sweep(pl, lists, wide, idx)
    rc = np.concatenate([np.full(len(w[1]), cue[k], np.int64) for k, w in enumerate(wide)])
    rv = np.concatenate([w[0] for w in wide]).reshape(-1, 2)
    rm = np.concatenate([np.asarray(w[2], np.int64) for w in wide])
    items = sorted(pl.found.values(), key=lambda t: t[0])[:seeds]
    V = np.array([v for _, v in items]).reshape(-1, n, 2)
    return PlanResult(V, np.array([c for c, _ in items]), pl.sim.used, pl.stats, rc, np.ascontiguousarray(rv), rm)
