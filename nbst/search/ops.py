"""The operators of the paper's signature search, as small numba kernels over arrays.

Each operator is its own ``@njit(cache=True)`` function so tests can call it on
hand-built populations; ``nbst.search`` strings them together into the compiled
generate-insert loop. No I/O, no objects, no global random state.

Population layout (a :class:`Population` NamedTuple of arrays, which numba compiles as a
tuple; built by :func:`new_population`)::

    pop.vel       : (cap, N, 2) float64  velocities of members 0 .. size-1
    pop.cost      : (cap,)      float64  cost (L2)
    pop.sig       : (cap,)      int64    signature bitmask (bit i: disk i within R)
    pop.tab_sig   : (cap,)      int64    distinct signatures present (the signature table)
    pop.tab_count : (cap,)      int64    number of members holding tab_sig[k]
    pop.state     : (3,)        int64    [SIZE, NTAB (table entries), BEST (index of the best member or -1)]

Members are kept compact: removing member j moves the last member into slot j
(and the table likewise), so ``best`` is re-pointed when its member moves.

Random numbers: xoshiro256** over a (4,) uint64 state array (``rng``), so a run
is a pure function of its seed however it is chunked.

Length: ~550 lines, past the house's ~500: every operator reads and writes the one
population layout above, so they stay beside it; each is a small kernel with its own test.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from nbst.domain import MAX_BOX_CROSSINGS

__all__ = ["SIZE", "NTAB", "BEST", "INS_DISPLACED", "INS_ADDED", "INS_SIG_LIMIT", "INS_CULLED", "INS_WORST",
           "INS_FALLBACK", "CULL_SUBSUMED", "CULL_WORST", "SEARCH_MAX_CROSSINGS", "limit_crossings", "seed_state",
           "rng_next", "rng_uniform", "rng_int", "rng_normal", "popcount", "Population", "new_population", "tab_find",
           "sig_count", "pop_append", "pop_set", "pop_remove", "worst_member", "acceptable_counts", "select_senate",
           "select_uniform", "directed_velocity", "uniform_velocity", "creep_velocity", "crossover", "cull_subsumed",
           "insert", "insert_initial"]

SIZE, NTAB, BEST = 0, 1, 2

# insert() outcomes
INS_DISPLACED = 0  # the child replaced a parent of its signature
INS_ADDED = 1  # the child was added, nothing deleted
INS_SIG_LIMIT = 2  # added; the worst member of its signature (maybe the child) was deleted
INS_CULLED = 3  # added; the population limit triggered culling of subsumed solutions
INS_WORST = 4  # added; the worst member of the population was deleted (variant F)
INS_FALLBACK = 5  # added; culling freed nothing and the hard limit deleted the worst member

# culling modes
CULL_SUBSUMED = 0  # the paper's culling (A)
CULL_WORST = 1  # variant F

_U53 = 1.0 / 9007199254740992.0  # 2**-53


# --------------------------------------------------------------------------- the velocity domain

#: Most box crossings the search proposes for one disk: a hair under the solution checker's
#: limit (``nbst.domain.MAX_BOX_CROSSINGS``), so round-off in the checker's recount of a
#: proposal scaled onto the limit never refuses it.
SEARCH_MAX_CROSSINGS = 0.999 * MAX_BOX_CROSSINGS


@njit(cache=True, inline="always", error_model="numpy")
def limit_crossings(v, cue_idx, radius, W, H, t_final):
    """Keep velocities v (N, 2) inside the accepted domain, in place: a cueable disk whose free
    flight would cross the box more than SEARCH_MAX_CROSSINGS times in t_final
    (|vx| t / (W - 2r) + |vy| t / (H - 2r), as ``nbst.problem.box_crossings`` counts) is slowed
    down, direction kept, to exactly that many; along an axis the disk fills (W = 2r or
    H = 2r) its velocity is set to 0. Returns how many disks it changed (0 for a velocity set
    already inside: such a set is left bit for bit as it is).

    Every proposal of the search (randomize, creep, crossover, bank, strike, plan, planner
    seeds, polish steps) goes through it, so a legal problem never yields a refused solution.
    """
    changed = 0
    half = 0.5 * SEARCH_MAX_CROSSINGS
    for q in range(cue_idx.shape[0]):
        i = cue_idx[q]
        gx = W - 2.0 * radius[i]
        gy = H - 2.0 * radius[i]
        # fast path (every proposal of a normal search): at most half the limit on each axis
        if abs(v[i, 0]) * t_final <= half * gx and abs(v[i, 1]) * t_final <= half * gy and gx > 0.0 and gy > 0.0:
            continue
        hit = False
        if gx <= 0.0 and v[i, 0] != 0.0:
            v[i, 0] = 0.0
            hit = True
        if gy <= 0.0 and v[i, 1] != 0.0:
            v[i, 1] = 0.0
            hit = True
        k = 0.0
        if v[i, 0] != 0.0:
            k += abs(v[i, 0]) * t_final / gx
        if v[i, 1] != 0.0:
            k += abs(v[i, 1]) * t_final / gy
        if k > SEARCH_MAX_CROSSINGS:
            f = SEARCH_MAX_CROSSINGS / k
            v[i, 0] *= f
            v[i, 1] *= f
            hit = True
        if hit:
            changed += 1
    return changed


# --------------------------------------------------------------------------- random numbers

def seed_state(seed: int) -> np.ndarray:
    """(4,) uint64 xoshiro256** state from an integer seed (via numpy's SeedSequence)."""
    st = np.random.SeedSequence(int(seed)).generate_state(4, np.uint64)
    if not st.any():
        st[0] = 1
    return st


@njit(cache=True, inline="always")
def _rotl(x, k):
    return (x << np.uint64(k)) | (x >> np.uint64(64 - k))


@njit(cache=True, inline="always")
def rng_next(s):
    """Next uint64 of xoshiro256** (Blackman & Vigna); advances s in place."""
    s0 = s[0]
    s1 = s[1]
    s2 = s[2]
    s3 = s[3]
    result = _rotl(s1 * np.uint64(5), 7) * np.uint64(9)
    t = s1 << np.uint64(17)
    s2 ^= s0
    s3 ^= s1
    s1 ^= s2
    s0 ^= s3
    s2 ^= t
    s3 = _rotl(s3, 45)
    s[0] = s0
    s[1] = s1
    s[2] = s2
    s[3] = s3
    return result


@njit(cache=True, inline="always")
def rng_uniform(s):
    """Uniform float in [0, 1)."""
    return np.float64(rng_next(s) >> np.uint64(11)) * _U53


@njit(cache=True, inline="always")
def rng_int(s, n):
    """Uniform integer in [0, n) (n >= 1)."""
    k = np.int64(rng_uniform(s) * n)
    return k if k < n else n - 1


@njit(cache=True, inline="always")
def rng_normal(s):
    """Standard normal (Box-Muller, one value per two uniforms)."""
    u1 = 1.0 - rng_uniform(s)  # (0, 1]
    u2 = rng_uniform(s)
    return math.sqrt(-2.0 * math.log(u1)) * math.cos(2.0 * math.pi * u2)


# --------------------------------------------------------------------------- bits

_M1 = np.uint64(0x5555555555555555)
_M2 = np.uint64(0x3333333333333333)
_M4 = np.uint64(0x0F0F0F0F0F0F0F0F)
_H01 = np.uint64(0x0101010101010101)


@njit(cache=True, inline="always")
def popcount(x):
    """Number of set bits of a non-negative int64 (branch-free SWAR; LLVM emits popcnt)."""
    u = np.uint64(x)
    u = u - ((u >> np.uint64(1)) & _M1)
    u = (u & _M2) + ((u >> np.uint64(2)) & _M2)
    u = (u + (u >> np.uint64(4))) & _M4
    return np.int64((u * _H01) >> np.uint64(56))


# --------------------------------------------------------------------------- population storage

class Population(NamedTuple):
    """The search's population (see the module docstring); mutable arrays in a fixed tuple."""

    vel: np.ndarray
    cost: np.ndarray
    sig: np.ndarray
    tab_sig: np.ndarray
    tab_count: np.ndarray
    state: np.ndarray


def new_population(cap: int, n: int) -> Population:
    """An empty population with room for ``cap`` members of ``n`` disks."""
    return Population(np.zeros((cap, n, 2)), np.full(cap, np.inf), np.zeros(cap, np.int64),
                      np.zeros(cap, np.int64), np.zeros(cap, np.int64), np.array([0, 0, -1], np.int64))


@njit(cache=True)
def tab_find(pop, s):
    """Index of signature s in the signature table, or -1."""
    ts = pop.tab_sig
    for k in range(pop.state[NTAB]):
        if ts[k] == s:
            return k
    return -1


@njit(cache=True)
def sig_count(pop, s):
    """How many members hold signature s."""
    k = tab_find(pop, s)
    return 0 if k < 0 else pop.tab_count[k]


@njit(cache=True)
def _tab_add(pop, s):
    ts, tc, ist = pop.tab_sig, pop.tab_count, pop.state
    k = tab_find(pop, s)
    if k < 0:
        k = ist[NTAB]
        ts[k] = s
        tc[k] = 0
        ist[NTAB] += 1
    tc[k] += 1


@njit(cache=True)
def _tab_sub(pop, s):
    ts, tc, ist = pop.tab_sig, pop.tab_count, pop.state
    k = tab_find(pop, s)
    tc[k] -= 1
    if tc[k] == 0:
        last = ist[NTAB] - 1
        ts[k] = ts[last]
        tc[k] = tc[last]
        ist[NTAB] = last


@njit(cache=True)
def pop_append(pop, v, cost, sig):
    """Add a member; returns its slot."""
    pv, pc, ps, ist = pop.vel, pop.cost, pop.sig, pop.state
    j = ist[SIZE]
    pv[j, :, :] = v
    pc[j] = cost
    ps[j] = sig
    ist[SIZE] = j + 1
    _tab_add(pop, sig)
    return j


@njit(cache=True)
def pop_set(pop, j, v, cost, sig):
    """Overwrite member j."""
    pv, pc, ps = pop.vel, pop.cost, pop.sig
    if ps[j] != sig:
        _tab_sub(pop, ps[j])
        _tab_add(pop, sig)
    pv[j, :, :] = v
    pc[j] = cost
    ps[j] = sig


@njit(cache=True)
def pop_remove(pop, j):
    """Delete member j (the last member moves into slot j; ``best`` follows it)."""
    pv, pc, ps, ist = pop.vel, pop.cost, pop.sig, pop.state
    _tab_sub(pop, ps[j])
    last = ist[SIZE] - 1
    if ist[BEST] == j:
        ist[BEST] = -1
    if j != last:
        pv[j, :, :] = pv[last]
        pc[j] = pc[last]
        ps[j] = ps[last]
        if ist[BEST] == last:
            ist[BEST] = j
    pc[last] = np.inf
    ist[SIZE] = last


@njit(cache=True)
def worst_member(pop, sig, protect, skip_sig=-1):
    """Index of the highest-cost member (of signature ``sig``, or of all if sig < 0),
    never ``protect`` nor a member of signature ``skip_sig`` (if >= 0); ties go to the
    lowest index; -1 if there is none."""
    pc, ps = pop.cost, pop.sig
    w = -1
    wc = -np.inf
    for j in range(pop.state[SIZE]):
        if j == protect or (sig >= 0 and ps[j] != sig) or (skip_sig >= 0 and ps[j] == skip_sig):
            continue
        if w < 0 or pc[j] > wc:
            w = j
            wc = pc[j]
    return w


@njit(cache=True)
def acceptable_counts(pop, n, out):
    """out[i] = number of members that are i-acceptable."""
    ps = pop.sig
    for i in range(n):
        out[i] = 0
    for j in range(pop.state[SIZE]):
        s = ps[j]
        for i in range(n):
            if (s >> i) & 1:
                out[i] += 1


# --------------------------------------------------------------------------- parent selection

@njit(cache=True)
def select_senate(pop, n, rng, first, scratch_ord, scratch_ok):
    """"Senate-like" parent selection.

    first < 0: every order represented in the population is equally likely, then
    every signature of that order, then every member of that signature.
    first >= 0 (second crossover parent): the same, but only over signatures s2
    held by some member other than ``first`` that maximize popcount(s1 | s2),
    s1 = the first parent's signature, and never ``first`` itself.
    scratch_ord : (n + 1,) int64, scratch_ok : (cap,) bool. Returns a member index.
    """
    ps, ts, tc, ist = pop.sig, pop.tab_sig, pop.tab_count, pop.state
    ntab = ist[NTAB]
    s1 = ps[first] if first >= 0 else np.int64(0)
    best_or = -1
    for k in range(ntab):
        cnt = tc[k] - (1 if (first >= 0 and ts[k] == s1) else 0)
        scratch_ok[k] = cnt > 0
        if first >= 0 and cnt > 0:
            b = popcount(s1 | ts[k])
            if b > best_or:
                best_or = b
    for o in range(n + 1):
        scratch_ord[o] = 0
    for k in range(ntab):
        if first >= 0 and scratch_ok[k] and popcount(s1 | ts[k]) != best_or:
            scratch_ok[k] = False
        if scratch_ok[k]:
            scratch_ord[popcount(ts[k])] += 1
    n_ord = 0
    for o in range(n + 1):
        if scratch_ord[o] > 0:
            n_ord += 1
    r = rng_int(rng, n_ord)
    o_pick = -1
    for o in range(n + 1):
        if scratch_ord[o] > 0:
            if r == 0:
                o_pick = o
                break
            r -= 1
    r = rng_int(rng, scratch_ord[o_pick])
    s_pick = np.int64(-1)
    cnt = 0
    for k in range(ntab):
        if scratch_ok[k] and popcount(ts[k]) == o_pick:
            if r == 0:
                s_pick = ts[k]
                cnt = tc[k] - (1 if (first >= 0 and ts[k] == s1) else 0)
                break
            r -= 1
    r = rng_int(rng, cnt)
    for j in range(ist[SIZE]):
        if ps[j] == s_pick and j != first:
            if r == 0:
                return j
            r -= 1
    return -1


@njit(cache=True, inline="always")
def select_uniform(pop, rng, exclude):
    """Variant B: every member equally likely (never ``exclude``; -1 excludes none)."""
    size = pop.state[SIZE]
    if exclude < 0:
        return rng_int(rng, size)
    j = rng_int(rng, size - 1)
    return j + 1 if j >= exclude else j


# --------------------------------------------------------------------------- making children

@njit(cache=True, inline="always")
def directed_velocity(x0, target, t_final, i, out):
    """Directed randomize: straight to the target, no wall, arriving at t_final."""
    out[i, 0] = (target[i, 0] - x0[i, 0]) / t_final
    out[i, 1] = (target[i, 1] - x0[i, 1]) / t_final


@njit(cache=True, inline="always")
def uniform_velocity(x0, radius, W, H, t_final, images, i, rng, out):
    """Uniform randomize: the free flight ends at a point uniform over the box
    (centre region [r, W - r] x [r, H - r]), reached through a mirror image (kx, ky)
    drawn uniformly from ``images`` (all |kx| + |ky| <= max_bounces), i.e. after
    |kx| + |ky| wall bounces. Image kx spans [r + kx L, r + (kx + 1) L], L = W - 2r;
    a uniform point there folds back to a uniform point of the box."""
    r = radius[i]
    Lx = W - 2.0 * r
    Ly = H - 2.0 * r
    m = rng_int(rng, images.shape[0])
    ex = r + (images[m, 0] + rng_uniform(rng)) * Lx
    ey = r + (images[m, 1] + rng_uniform(rng)) * Ly
    out[i, 0] = (ex - x0[i, 0]) / t_final
    out[i, 1] = (ey - x0[i, 1]) / t_final


@njit(cache=True, inline="always")
def creep_velocity(sigma, i, rng, out):
    """Creep: add an isotropic normal perturbation (std ``sigma`` units/s per axis)."""
    out[i, 0] += sigma * rng_normal(rng)
    out[i, 1] += sigma * rng_normal(rng)


@njit(cache=True, inline="always")
def crossover(v1, v2, s1, s2, cue_idx, engineered, rng, out):
    """Child velocities from two parents, disk by disk over the cueable disks.

    engineered: disk i comes from the i-acceptable parent when exactly one parent is
    i-acceptable, else from either parent with probability 1/2 (variant D: always
    the coin). Noncueable disks keep velocity zero (copied from v1, which has it)."""
    out[:, :] = v1
    for q in range(cue_idx.shape[0]):
        i = cue_idx[q]
        a1 = (s1 >> i) & 1
        a2 = (s2 >> i) & 1
        if engineered and a1 != a2:
            take2 = a2 == 1
        else:
            take2 = rng_uniform(rng) < 0.5
        if take2:
            out[i, 0] = v2[i, 0]
            out[i, 1] = v2[i, 1]


# --------------------------------------------------------------------------- insert and cull

@njit(cache=True)
def cull_subsumed(pop, n, exempt_best, scratch_or):
    """Delete every solution of the lowest order among those subsumed by higher-order
    solutions (each of its bits is set in some solution of higher order).
    exempt_best: members sharing the best member's signature are never deleted.
    scratch_or : (n + 2,) int64. Returns the number deleted."""
    ps, ist = pop.sig, pop.state
    size = ist[SIZE]
    for o in range(n + 2):
        scratch_or[o] = 0
    for j in range(size):
        scratch_or[popcount(ps[j])] |= ps[j]
    # scratch_or[o] := OR of the signatures of order > o
    acc = np.int64(0)
    for o in range(n + 1, -1, -1):
        cur = scratch_or[o]
        scratch_or[o] = acc
        acc |= cur
    best_sig = np.int64(-1)
    if exempt_best and ist[BEST] >= 0:
        best_sig = ps[ist[BEST]]
    low = n + 1
    for j in range(size):
        s = ps[j]
        o = popcount(s)
        if s != best_sig and (s & ~scratch_or[o]) == 0 and o < low:
            low = o
    if low > n:
        return 0
    above = scratch_or[low]
    deleted = 0
    for j in range(size - 1, -1, -1):  # descending: the member swapped in was already seen
        s = ps[j]
        if s != best_sig and popcount(s) == low and (s & ~above) == 0:
            pop_remove(pop, j)
            deleted += 1
    return deleted


@njit(cache=True)
def insert(pop, child, cost, sig, p1, p2, improvement, elitism, sig_limit, pop_limit, hard_limit, cull_mode,
           n, rng, scratch_or):
    # Fifteen parameters on purpose: each operator of ops.py takes plain arrays and scalars so it can
    # be tested on hand-built populations (tests/test_search_ops.py).
    """The paper's insert. p2 = -1 unless the child came from crossover.

    If the child's signature equals exactly one parent's, the child replaces that
    parent (both: one of the two at random) -- unless, with elitism, that parent is
    the best member and the child is no improvement. Otherwise the child is added;
    then, if its signature now has more than ``sig_limit`` members, the worst of them
    (maybe the child; never the best with elitism) is deleted; else, if the
    population exceeds ``pop_limit``, subsumed solutions are culled (CULL_SUBSUMED;
    if that frees nothing and the size exceeds ``hard_limit``, the worst member
    outside the best's signature is deleted) or, for CULL_WORST (variant F), the
    worst member is deleted after every addition.
    ``improvement``: the child beats the best so far; it becomes ``best``.
    Returns an INS_* code.
    """
    ps, ist = pop.sig, pop.state
    m1 = p1 >= 0 and ps[p1] == sig
    m2 = p2 >= 0 and ps[p2] == sig
    cand = -1
    if m1 and m2:
        cand = p1 if rng_uniform(rng) < 0.5 else p2
    elif m1:
        cand = p1
    elif m2:
        cand = p2
    if cand >= 0 and not (elitism and cand == ist[BEST] and not improvement):
        pop_set(pop, cand, child, cost, sig)
        if improvement:
            ist[BEST] = cand
        return INS_DISPLACED
    j = pop_append(pop, child, cost, sig)
    if improvement:
        ist[BEST] = j
    protect = ist[BEST] if elitism else -1
    if sig_count(pop, sig) > sig_limit:
        w = worst_member(pop, sig, protect)
        if w >= 0:
            pop_remove(pop, w)
            return INS_SIG_LIMIT
    if cull_mode == CULL_WORST:
        w = worst_member(pop, -1, protect)
        if w >= 0:
            pop_remove(pop, w)
        return INS_WORST
    if ist[SIZE] > pop_limit:
        if cull_subsumed(pop, n, elitism, scratch_or) > 0:
            return INS_CULLED
        if ist[SIZE] > hard_limit:
            # the hard-limit fallback: the worst member outside the best's signature (elitism)
            bs = pop.sig[ist[BEST]] if (elitism and ist[BEST] >= 0) else np.int64(-1)
            w = worst_member(pop, -1, -1, bs)
            if w >= 0:
                pop_remove(pop, w)
                return INS_FALLBACK
    return INS_ADDED


@njit(cache=True)
def insert_initial(pop, child, cost, sig, improvement, elitism, sig_limit, pop_limit):
    """The initialize step's insert: add the solution; if its signature now has more
    than ``sig_limit`` members or the population more than ``pop_limit``, delete the
    worst member of its signature (possibly itself; never the best with elitism).
    Returns True if the solution stayed."""
    ist = pop.state
    j = pop_append(pop, child, cost, sig)
    if improvement:
        ist[BEST] = j
    if sig_count(pop, sig) > sig_limit or ist[SIZE] > pop_limit:
        w = worst_member(pop, sig, ist[BEST] if elitism else -1)
        if w >= 0:
            pop_remove(pop, w)
            return w != j
    return True
