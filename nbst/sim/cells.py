"""The event kernel for many disks: a cell grid, an event calendar and lazy invalidation.

``nbst.sim.kernel`` keeps an N x N table of pair times and rescans a row per event: O(N)
per event and O(N^2) memory (800 MB at N = 10,000). This kernel is the event-driven
molecular-dynamics design (Lubachevsky 1991; Donev, Torquato & Stillinger 2005; DynamO):

* **cell grid.** The box is cut into ``nx x ny`` cells at least one contact distance wide
  (and about one disk per cell). A disk belongs to the cell of its centre; two disks can
  touch only while their cells are neighbours (3 x 3), so a disk predicts contacts only
  with the disks of its 9 cells, and a *cell crossing* is an event of its own: the disk
  moves to the next cell's list and scans again (the disks of the new row or column of
  cells are the ones it had not seen).
* **one pending event per disk**: the earliest of its wall contact, its next cell
  crossing, and its contacts with the neighbours it scanned. The disks' pending times sit
  in a *calendar*, a complete binary tournament tree (each node holds the disk with the
  earlier event of its two children, ties to the lower index), so the next event is at the
  root and a change costs O(log N).
* **lazy invalidation.** A disk-disk prediction stores its partner's collision counter;
  when it reaches the root and the partner has since changed course, it is stale: the disk
  scans again and nothing happens. Nothing is ever searched for and deleted.

Exactness: the same events, in the same order, with the same numbers as the table. A
pair's contact time is a function of the two straight paths only; the table computes it
when the later of the two last changed course, from that instant. This kernel computes it
from the same instant (``t0 = max(tl_i, tl_k)``, advancing only the disk that changed
earlier) with the same formula and the same horizon (each disk's next wall contact and
t_final), whenever it scans, so every time it finds is bit-for-bit the table's, and the
event processing (advance, impulse, wall reflection) is the same code.
``tests/test_cells.py`` checks event lists against the table kernel and the slow reference.
Exactly simultaneous events (symmetric starts) are processed lowest disk first, as in the
table, but may come in another order among themselves; ``simulate`` uses the table below
``CELLS_MIN_DISKS`` disks, where it is also the faster of the two.

Length: the kernel and its calendar, predictions and batch entry stay in one module so numba
inlines them into one loop (as ``nbst.sim.kernel`` does for the table).

Memory: a packed row of 10 numbers per disk (what a contact test reads of a neighbour, in
one 80-byte row: the test is bound by memory at large N), 11 more per disk, the grid (at
most N cells) and the tree (2 P, P the power of two >= N): about 200 bytes per disk.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from nbst.constants import WALL_BOTTOM, WALL_LEFT, WALL_RIGHT
from nbst.sim.kernel import (STATUS_OK, STATUS_OVERFLOW, alloc_work, cost_signature_words, event_guard, record_event,
                             run, stall_limits)
from nbst.sim.primitives import INF, elastic_impulse, pair_tau, wall_tau

__all__ = ["CELLS_MIN_DISKS", "CellWork", "alloc_cells", "evaluate_words_kernel", "grid_shape", "run_cells"]

#: From this many disks up ``simulate`` and ``evaluate`` use this kernel, below it the table
#: (``nbst.sim.kernel``). Measured by ``benchmarks/bench_scale.py``: the table is faster
#: for small N (it has no crossings to process), the grid from a few hundred disks.
CELLS_MIN_DISKS = 128

#: Pending-event kinds (their order breaks ties of one disk's candidates: a wall first,
#: then a disk (lowest index first), then a cell crossing).
KIND_WALL, KIND_PAIR, KIND_CROSS = 0, 1, 2


#: Columns of ``CellWork.S``, the packed per-disk row a contact test reads: position and
#: velocity at the disk's last change of course, that time, its next wall contact, radius,
#: its count of changes of course (lazy invalidation), the partner of its last change (-1: a
#: wall or the start), and the next disk in its cell (-1: none); integers held exactly.
X, Y, VX, VY, TL, TW, R, CNT, LASTP, NXT = range(10)
S_COLS = 10


class CellWork(NamedTuple):
    """Scratch arrays of ``run_cells`` (``alloc_cells(n)``; reuse for many runs of n disks)."""

    S: np.ndarray  # (n, S_COLS) the packed rows (columns X .. NXT)
    wall: np.ndarray  # (n,) int64 which wall S[:, TW] is
    cx: np.ndarray  # (n,) int64 cell column
    cy: np.ndarray  # (n,) int64 cell row
    prv: np.ndarray  # (n,) int64 previous disk in the same cell (-1: it is the head)
    head: np.ndarray  # (n + 1,) int64 first disk of each cell
    et: np.ndarray  # (n,) pending event time: min(pt, ct)
    pt: np.ndarray  # (n,) its earliest contact (wall or disk) found so far
    pk: np.ndarray  # (n,) int64 which: KIND_WALL or KIND_PAIR
    pp: np.ndarray  # (n,) int64 the wall or the partner disk
    pc: np.ndarray  # (n,) int64 the partner's count of changes when predicted
    ct: np.ndarray  # (n,) its next cell crossing
    cd: np.ndarray  # (n,) int64 the crossing's direction: 0 +x, 1 -x, 2 +y, 3 -y
    tree: np.ndarray  # (2 P,) int64 tournament tree over the disks' pending events: the winner
    tree_t: np.ndarray  # (2 P,) its time (kept in the node: an update reads only its path)


@njit(cache=True)
def alloc_cells(n):
    """Scratch arrays for ``run_cells`` with n disks (the grid has at most n cells)."""
    P = 1
    while P < n:
        P *= 2
    return CellWork(np.zeros((n, S_COLS)), np.zeros(n, np.int64), np.zeros(n, np.int64), np.zeros(n, np.int64),
                    np.zeros(n, np.int64), np.zeros(n + 1, np.int64), np.zeros(n), np.zeros(n), np.zeros(n, np.int64),
                    np.zeros(n, np.int64), np.zeros(n, np.int64), np.zeros(n), np.zeros(n, np.int64),
                    np.zeros(2 * P, np.int64), np.zeros(2 * P))


# --------------------------------------------------------------------------- the calendar

@njit(cache=True, inline="always")
def _tree_update(tree, tree_t, et, P, i):
    """Disk i's pending time changed: replay the matches on its path to the root (the earlier
    event wins, ties to the lower disk index; -1 is an empty leaf at time inf)."""
    node = P + i
    tree_t[node] = et[i]
    node >>= 1
    while node >= 1:
        a = tree[2 * node]
        b = tree[2 * node + 1]
        ta = tree_t[2 * node]
        tb = tree_t[2 * node + 1]
        if b >= 0 and (a < 0 or tb < ta or (tb == ta and b < a)):
            tree[node] = b
            tree_t[node] = tb
        else:
            tree[node] = a
            tree_t[node] = ta
        node >>= 1


# --------------------------------------------------------------------------- predictions

@njit(cache=True, inline="always", error_model="numpy")
def _pair_time(i, xi, yi, ui, wi, ti, twi, ci, li, ri, k, xk, yk, uk, wk, tk, twk, ck, lk, rk, t_final):
    """The table kernel's contact time of disks i and k on their current paths (absolute; inf
    if none before either's next wall contact or t_final): the same formula, from the same
    instant, as ``nbst.sim.kernel`` computed it when the later of the two last changed course.
    Per disk: position and velocity at its last change of course (time t), next wall time,
    change count, last partner, radius."""
    if ci == 0.0 and ck == 0.0:
        # the table's start-up predictions: pair_tau, row min(i, k), times not offset
        if i < k:
            return pair_tau(xk - xi, yk - yi, uk - ui, wk - wi, ri + rk, min(min(twi, t_final), twk))
        return pair_tau(xi - xk, yi - yk, ui - uk, wi - wk, rk + ri, min(min(twk, t_final), twi))
    if li == k and lk == i and ti == tk:
        # the pair that just collided: pair_tau from its contact, horizon t_final
        if i < k:
            return ti + pair_tau(xk - xi, yk - yi, uk - ui, wk - wi, ri + rk, t_final - ti)
        return ti + pair_tau(xi - xk, yi - yk, ui - uk, wi - wk, rk + ri, t_final - ti)
    # the table's branch-free row update of the disk that changed course last (at t0); its
    # early exits return inf exactly where that update's mask does
    if ti >= tk:
        t0 = ti
        dt = t0 - tk
        dx = xk + uk * dt - xi
        dy = yk + wk * dt - yi
        dvx = uk - ui
        dvy = wk - wi
        s = ri + rk
        hz = min(min(twi, t_final), twk) - t0
    else:
        t0 = tk
        dt = t0 - ti
        dx = xi + ui * dt - xk
        dy = yi + wi * dt - yk
        dvx = ui - uk
        dvy = wi - wk
        s = rk + ri
        hz = min(min(twk, t_final), twi) - t0
    b = dx * dvx + dy * dvy
    if b >= 0.0:
        return INF
    aa = dvx * dvx + dvy * dvy
    c = dx * dx + dy * dy - s * s
    disc = b * b - aa * c
    if disc < 0.0:
        return INF
    tau = max(c / (-b + math.sqrt(disc)), 0.0)
    if tau <= hz:
        return t0 + tau
    return INF


@njit(cache=True, inline="always", error_model="numpy")
def _scan_cells(i, gx0, gx1, gy0, gy1, S, head, pt, pk, pp, pc, nx, t_final):
    """Lower disk i's earliest contact (pt, pk, pp, pc) by its contacts with the disks of
    cells [gx0, gx1] x [gy0, gy1] (ties: a wall, then the lowest partner)."""
    xi = S[i, X]
    yi = S[i, Y]
    ui = S[i, VX]
    wi = S[i, VY]
    ti = S[i, TL]
    twi = S[i, TW]
    ci = S[i, CNT]
    li = S[i, LASTP]
    ri = S[i, R]
    for gy in range(gy0, gy1 + 1):
        for gx in range(gx0, gx1 + 1):
            k = head[gy * nx + gx]
            while k >= 0:
                if k != i:
                    tk = _pair_time(i, xi, yi, ui, wi, ti, twi, ci, li, ri, k, S[k, X], S[k, Y], S[k, VX], S[k, VY],
                                    S[k, TL], S[k, TW], S[k, CNT], S[k, LASTP], S[k, R], t_final)
                    if tk < pt[i] or (tk == pt[i] and pk[i] == KIND_PAIR and k < pp[i]):
                        pt[i] = tk
                        pk[i] = KIND_PAIR
                        pp[i] = k
                        pc[i] = int(S[k, CNT])
                k = int(S[k, NXT])


@njit(cache=True, inline="always", error_model="numpy")
def _scan(i, S, wall, cx, cy, head, et, pt, pk, pp, pc, ct, nx, ny, t_final):
    """Disk i's earliest contact from scratch: its wall, then the disks of its 9 cells."""
    pt[i] = S[i, TW]
    pk[i] = KIND_WALL
    pp[i] = wall[i]
    pc[i] = 0
    _scan_cells(i, max(cx[i] - 1, 0), min(cx[i] + 1, nx - 1), max(cy[i] - 1, 0), min(cy[i] + 1, ny - 1),
                S, head, pt, pk, pp, pc, nx, t_final)
    et[i] = min(pt[i], ct[i])


@njit(cache=True, inline="always", error_model="numpy")
def _set_cross(i, now, S, cx, cy, ct, cd, cw, ch, nx, ny):
    """Disk i's next cell crossing (ct, cd): direction 0 +x, 1 -x, 2 +y, 3 -y; inf if none."""
    vx = S[i, VX]
    vy = S[i, VY]
    tb = INF
    d = -1
    if vx > 0.0 and cx[i] < nx - 1:
        tb = S[i, TL] + ((cx[i] + 1) * cw - S[i, X]) / vx
        d = 0
    elif vx < 0.0 and cx[i] > 0:
        tb = S[i, TL] + (cx[i] * cw - S[i, X]) / vx
        d = 1
    if vy > 0.0 and cy[i] < ny - 1:
        t2 = S[i, TL] + ((cy[i] + 1) * ch - S[i, Y]) / vy
        if t2 < tb:
            tb = t2
            d = 2
    elif vy < 0.0 and cy[i] > 0:
        t2 = S[i, TL] + (cy[i] * ch - S[i, Y]) / vy
        if t2 < tb:
            tb = t2
            d = 3
    ct[i] = max(tb, now)  # round-off may put a crossing an ulp in the past
    cd[i] = d


@njit(cache=True, inline="always")
def _unlink(i, S, prv, head, c):
    nx_ = int(S[i, NXT])
    if prv[i] >= 0:
        S[prv[i], NXT] = nx_
    else:
        head[c] = nx_
    if nx_ >= 0:
        prv[nx_] = prv[i]


@njit(cache=True, inline="always")
def _link(i, S, prv, head, c):
    prv[i] = -1
    S[i, NXT] = head[c]
    if head[c] >= 0:
        prv[head[c]] = i
    head[c] = i


@njit(cache=True, error_model="numpy")
def grid_shape(radius, W, H, n):
    """(nx, ny, cw, ch): cells at least the largest contact distance wide (with a relative
    margin of 1e-9 for round-off in cell membership) and about one disk per cell area."""
    r1 = 0.0
    r2 = 0.0
    for i in range(n):
        r = radius[i]
        if r > r1:
            r2 = r1
            r1 = r
        elif r > r2:
            r2 = r
    if n == 1:
        r2 = r1
    side = max((r1 + r2) * (1.0 + 1e-9), math.sqrt(W * H / n))
    nx = max(1, int(W / side))
    ny = max(1, int(H / side))
    while nx * ny > n:
        # keep at most n cells (the work arrays' size)
        if nx >= ny:
            nx -= 1
        else:
            ny -= 1
    return nx, ny, W / nx, H / ny


@njit(cache=True, inline="always", error_model="numpy")
def _wall_update(i, te, S, wall, W, H):
    t_w, wl = wall_tau(S[i, X], S[i, Y], S[i, VX], S[i, VY], S[i, R], W, H)
    S[i, TW] = te + t_w
    wall[i] = wl


@njit(cache=True, error_model="numpy")
def run_cells(x0, v0, radius, mass, W, H, t_final, w, out_final, out_vel, max_events,
              ev_t, ev_i, ev_j, ev_state):
    # Length and parameters on purpose: ``nbst.sim.kernel.run``'s contract (the same arguments
    # but the scratch arrays), so callers choose a kernel by N and keep everything else.
    """Simulate from t = 0 to t_final: ``nbst.sim.kernel.run`` with ``w = alloc_cells(N)``.
    Returns (status, n_events, n_disk_disk, n_wall); the event record is the table's."""
    S, wall, cx, cy, prv, head, et, pt, pk, pp, pc, ct, cd, tree, tree_t = w
    n = x0.shape[0]
    nx, ny, cw, ch = grid_shape(radius, W, H, n)
    P = tree.shape[0] // 2
    for c in range(nx * ny):
        head[c] = -1
    for i in range(n):
        S[i, X] = x0[i, 0]
        S[i, Y] = x0[i, 1]
        S[i, VX] = v0[i, 0]
        S[i, VY] = v0[i, 1]
        S[i, TL] = 0.0
        S[i, R] = radius[i]
        S[i, CNT] = 0.0
        S[i, LASTP] = -1.0
        t_w, wl = wall_tau(S[i, X], S[i, Y], S[i, VX], S[i, VY], radius[i], W, H)
        S[i, TW] = t_w
        wall[i] = wl
        cx[i] = min(max(int(S[i, X] / cw), 0), nx - 1)
        cy[i] = min(max(int(S[i, Y] / ch), 0), ny - 1)
        _link(i, S, prv, head, cy[i] * nx + cx[i])
    for i in range(n):
        _set_cross(i, 0.0, S, cx, cy, ct, cd, cw, ch, nx, ny)
        _scan(i, S, wall, cx, cy, head, et, pt, pk, pp, pc, ct, nx, ny, t_final)
    for node in range(P, 2 * P):
        tree[node] = node - P if node - P < n else -1
        tree_t[node] = et[node - P] if node - P < n else INF
    for node in range(P - 1, 0, -1):
        a = tree[2 * node]
        b = tree[2 * node + 1]
        if b >= 0 and (a < 0 or tree_t[2 * node + 1] < tree_t[2 * node]):
            tree[node] = b
            tree_t[node] = tree_t[2 * node + 1]
        else:
            tree[node] = a
            tree_t[node] = tree_t[2 * node]
    if P == 1:
        tree[1] = 0  # one disk: the root is the leaf

    cap = ev_t.shape[0]
    status = STATUS_OK
    n_ev = 0
    n_dd = 0
    n_wall = 0
    t_last = 0.0
    t_inst = 0.0  # start of the current "instant" (stall test)
    n_inst = 0
    stall_events, stall_dt = stall_limits(n, t_final)
    while True:
        i = tree[1]
        te = et[i]
        if te > t_final:
            break
        if ct[i] < pt[i]:
            # a cell crossing: move to the next cell and look at the row or column of cells it
            # now neighbours (the contacts it found so far stay valid, or go stale lazily)
            d = cd[i]
            _unlink(i, S, prv, head, cy[i] * nx + cx[i])
            if d == 0:
                cx[i] += 1
            elif d == 1:
                cx[i] -= 1
            elif d == 2:
                cy[i] += 1
            else:
                cy[i] -= 1
            _link(i, S, prv, head, cy[i] * nx + cx[i])
            if d <= 1:
                g = cx[i] + 1 if d == 0 else cx[i] - 1
                if 0 <= g < nx:
                    _scan_cells(i, g, g, max(cy[i] - 1, 0), min(cy[i] + 1, ny - 1), S, head, pt, pk, pp, pc, nx,
                                t_final)
            else:
                g = cy[i] + 1 if d == 2 else cy[i] - 1
                if 0 <= g < ny:
                    _scan_cells(i, max(cx[i] - 1, 0), min(cx[i] + 1, nx - 1), g, g, S, head, pt, pk, pp, pc, nx,
                                t_final)
            _set_cross(i, te, S, cx, cy, ct, cd, cw, ch, nx, ny)
            et[i] = min(pt[i], ct[i])
            _tree_update(tree, tree_t, et, P, i)
            continue
        kind = pk[i]
        j = pp[i]
        if kind == KIND_PAIR:
            if int(S[j, CNT]) != pc[i]:
                # stale: the partner changed course since; look again, nothing happens
                _scan(i, S, wall, cx, cy, head, et, pt, pk, pp, pc, ct, nx, ny, t_final)
                _tree_update(tree, tree_t, et, P, i)
                continue
            if j < i:
                i, j = j, i  # the table's row is the lower index
        status, t_inst, n_inst = event_guard(te, n_ev, max_events, t_inst, n_inst, stall_events, stall_dt)
        if status != STATUS_OK:
            break
        t_last = te
        S[i, X] += S[i, VX] * (te - S[i, TL])
        S[i, Y] += S[i, VY] * (te - S[i, TL])
        S[i, TL] = te
        S[i, CNT] += 1.0
        if kind == KIND_WALL:
            wl = wall[i]
            r = radius[i]
            if wl == WALL_LEFT or wl == WALL_RIGHT:
                S[i, VX] = -S[i, VX]
                S[i, X] = r if wl == WALL_LEFT else W - r  # exactly at contact: no drift through walls
            else:
                S[i, VY] = -S[i, VY]
                S[i, Y] = r if wl == WALL_BOTTOM else H - r
            n_wall += 1
            jj = -1 - wl
            S[i, LASTP] = -1.0
            _wall_update(i, te, S, wall, W, H)
            _set_cross(i, te, S, cx, cy, ct, cd, cw, ch, nx, ny)
            _scan(i, S, wall, cx, cy, head, et, pt, pk, pp, pc, ct, nx, ny, t_final)
            _tree_update(tree, tree_t, et, P, i)
        else:
            S[j, X] += S[j, VX] * (te - S[j, TL])
            S[j, Y] += S[j, VY] * (te - S[j, TL])
            S[j, TL] = te
            S[j, CNT] += 1.0
            nxv = S[j, X] - S[i, X]
            nyv = S[j, Y] - S[i, Y]
            dd = math.sqrt(nxv * nxv + nyv * nyv)
            nxv /= dd
            nyv /= dd
            S[i, VX], S[i, VY], S[j, VX], S[j, VY] = elastic_impulse(S[i, VX], S[i, VY], S[j, VX], S[j, VY],
                                                                     nxv, nyv, mass[i], mass[j])
            n_dd += 1
            jj = j
            S[i, LASTP] = j
            S[j, LASTP] = i
            _wall_update(i, te, S, wall, W, H)
            _wall_update(j, te, S, wall, W, H)
            _set_cross(i, te, S, cx, cy, ct, cd, cw, ch, nx, ny)
            _set_cross(j, te, S, cx, cy, ct, cd, cw, ch, nx, ny)
            _scan(i, S, wall, cx, cy, head, et, pt, pk, pp, pc, ct, nx, ny, t_final)
            _tree_update(tree, tree_t, et, P, i)
            _scan(j, S, wall, cx, cy, head, et, pt, pk, pp, pc, ct, nx, ny, t_final)
            _tree_update(tree, tree_t, et, P, j)
        if cap > 0:
            if n_ev >= cap:
                status = STATUS_OVERFLOW
                break
            record_event(ev_t, ev_i, ev_j, ev_state, n_ev, te, i, jj,
                         S[i, X], S[i, Y], S[i, VX], S[i, VY], S[jj, X], S[jj, Y], S[jj, VX], S[jj, VY])
        n_ev += 1
    t_stop = t_final if status == STATUS_OK else t_last  # never extrapolate past the last event
    for i in range(n):
        out_final[i, 0] = S[i, X] + S[i, VX] * (t_stop - S[i, TL])
        out_final[i, 1] = S[i, Y] + S[i, VY] * (t_stop - S[i, TL])
        out_vel[i, 0] = S[i, VX]
        out_vel[i, 1] = S[i, VY]
    return status, n_ev, n_dd, n_wall


@njit(cache=True, nogil=True, error_model="numpy")
def evaluate_words_kernel(x0, V, radius, mass, target, W, H, t_final, R, max_events, use_cells, final, cost, sig,
                          n_events):
    # Fifteen parameters on purpose: ``nbst.sim.kernel.evaluate_kernel``'s batch contract for any N.
    """Batch for any N: V (B, N, 2) -> final (B, N, 2), cost (B,), sig (B, (N + 63) // 64) uint64
    multiword signatures, n_events (B,); ``use_cells`` picks this module's kernel, else the
    table. A run that stops early gets cost = inf and an empty signature."""
    n = x0.shape[0]
    vel = np.empty((n, 2))
    no_t = np.empty(0)
    no_i = np.empty(0, np.int64)
    no_s = np.empty((0, 8))
    if use_cells:
        wc = alloc_cells(n)
        for b in range(V.shape[0]):
            st, ne, _, _ = run_cells(x0, V[b], radius, mass, W, H, t_final, wc, final[b], vel, max_events,
                                     no_t, no_i, no_i, no_s)
            n_events[b] = ne
            _score(st, final[b], target, R, cost, sig, b)
    else:
        wt = alloc_work(n)
        for b in range(V.shape[0]):
            st, ne, _, _ = run(x0, V[b], radius, mass, W, H, t_final, wt, final[b], vel, max_events,
                               no_t, no_i, no_i, no_s)
            n_events[b] = ne
            _score(st, final[b], target, R, cost, sig, b)


@njit(cache=True, inline="always", error_model="numpy")
def _score(st, final, target, R, cost, sig, b):
    if st == STATUS_OK:
        cost[b] = cost_signature_words(final, target, R, sig[b])
    else:
        cost[b] = INF
        for w in range(sig.shape[1]):
            sig[b, w] = np.uint64(0)
