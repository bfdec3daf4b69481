"""Exact event-driven dynamics of frictionless elastic disks in a box.

Between events every disk moves in a straight line, so the time of the next
disk-disk or disk-wall contact has a closed form; the simulator jumps from
event to event and ends exactly at ``t_final``.

Kernel layout (numba ``njit(cache=True)``, arrays only):

* each disk keeps its position ``(px, py)`` at its own last-event time ``tl``
  (lazy update: a disk untouched by an event is not moved);
* ``T[i, k]`` (k != i) is the absolute time of the next contact of disks i and
  k on their current straight paths (inf if none); ``T[i, i]`` is disk i's next
  wall contact, ``wall[i]`` which wall;
* ``rowmin[i]`` / ``rowarg[i]`` cache the minimum of row i.

An event changes the velocity of one disk (wall) or two (disk-disk); only their
rows are recomputed (O(N) predictions), other rows are patched in O(1) unless
their cached minimum pointed at a changed disk and grew, in which case that row
is rescanned from stored times (no new predictions). The next event is the
minimum of ``rowmin`` (O(N)). Simultaneous events are processed one at a time,
in a fixed order (lowest row index first, then the row's lowest column, a wall
before a disk in the same row), so a run is a pure function of its inputs.

Collision times use the numerically stable root ``tau = c / (-b + sqrt(b^2 - a c))``
of ``|dp + dv tau|^2 = (ri + rk)^2``; only approaching pairs (``b < 0``) are
predicted, so a pair that just collided is never re-predicted at tau = 0, and a
wall is predicted only for the wall a disk moves towards, so a disk pushed back
into the wall it just left (or bouncing into the opposite wall) is still caught.
A contact time that round-off makes negative is clamped to "now". These closed forms,
the elastic impulse and the other physics rules are written once, in
``nbst.sim.primitives``; ``_update_row`` repeats ``pair_tau``'s formula branch-free so
LLVM vectorizes it (tests/test_primitives.py checks every event against a naive rescan).

A run that stops early (``MAX_EVENTS`` reached, or stalled: a jam of rigid disks pinned
between opposite walls bouncing infinitely often at one instant) is exact up to its last
event; its final positions are those at that event's time, never extrapolated past it
(straight flight beyond the last event would cross walls).
"""
from __future__ import annotations

import math
from enum import IntEnum
from typing import NamedTuple

import numpy as np
from numba import njit

from nbst.constants import STALL_EVENTS_PER_DISK, STALL_RTOL, WALL_BOTTOM, WALL_LEFT, WALL_RIGHT
from nbst.sim.primitives import INF, elastic_impulse, pair_tau, wall_tau

__all__ = ["INF", "SimStatus", "Work", "STATUS_OK", "STATUS_OVERFLOW", "STATUS_STALLED", "STATUS_TRUNCATED", "alloc_work", "cost_signature", "cost_signature_words",
           "evaluate_kernel", "pair_tau", "run", "wall_tau"]



class SimStatus(IntEnum):
    """How a run of the kernel ended (numba compiles the members as constants)."""

    OK = 0  # reached t_final
    TRUNCATED = 1  # MAX_EVENTS reached before t_final
    OVERFLOW = 2  # event record buffer full (simulate() retries with a larger one)
    STALLED = 3  # a jam: STALL_EVENTS_PER_DISK * N events within one instant


STATUS_OK, STATUS_TRUNCATED, STATUS_OVERFLOW, STATUS_STALLED = (SimStatus.OK, SimStatus.TRUNCATED,
                                                                SimStatus.OVERFLOW, SimStatus.STALLED)


# --------------------------------------------------------------------------- the event loop's safety valves

@njit(cache=True)
def stall_limits(n: int, t_final: float):
    """(events, seconds): a run stalls when more than ``events`` events fall within ``seconds`` of
    each other (``STALL_EVENTS_PER_DISK`` per disk within ``STALL_RTOL`` of t_final: a jam)."""
    return STALL_EVENTS_PER_DISK * n, STALL_RTOL * t_final


@njit(cache=True)
def event_guard(te: float, n_ev: int, max_events: int, t_inst: float, n_inst: int, stall_events: int,
                stall_dt: float):
    """Both event kernels' check before the event at time ``te``: ``STATUS_TRUNCATED`` once
    ``max_events`` events are done, ``STATUS_STALLED`` past ``stall_events`` events within
    ``stall_dt`` of the instant that began at ``t_inst`` (a new instant begins at the first event
    later than that), else ``STATUS_OK``. Returns (status, t_inst, n_inst), the instant's start and
    its events counted so far, for the next call."""
    if n_ev >= max_events:
        return STATUS_TRUNCATED, t_inst, n_inst
    if te > t_inst + stall_dt:
        t_inst = te
        n_inst = 0
    n_inst += 1
    if n_inst > stall_events:
        return STATUS_STALLED, t_inst, n_inst
    return STATUS_OK, t_inst, n_inst


@njit(cache=True, inline="always")
def record_event(ev_t, ev_i, ev_j, ev_state, e, te, i, j, xi, yi, vxi, vyi, xj, yj, vxj, vyj):
    # Sixteen parameters on purpose: both event kernels record an event through this one
    # inlined store, each from its own state layout.
    """Both event kernels' record of event ``e``: its time ``te``, disk ``i`` and partner ``j``
    (-1 for a wall) and their states after it; the j half is left as it was for a wall."""
    ev_t[e] = te
    ev_i[e] = i
    ev_j[e] = j
    ev_state[e, 0] = xi
    ev_state[e, 1] = yi
    ev_state[e, 2] = vxi
    ev_state[e, 3] = vyi
    if j >= 0:
        ev_state[e, 4] = xj
        ev_state[e, 5] = yj
        ev_state[e, 6] = vxj
        ev_state[e, 7] = vyj


@njit(cache=True, inline="always", error_model="numpy")
def _dist2(final, target, i):
    """Squared distance of disk ``i``'s final position from its target."""
    dx = final[i, 0] - target[i, 0]
    dy = final[i, 1] - target[i, 1]
    return dx * dx + dy * dy


# --------------------------------------------------------------------------- the kernel

class Work(NamedTuple):
    """Scratch arrays of ``run`` (allocate once with ``alloc_work``, reuse for many runs).
    Per-disk arrays have m >= N lanes (padded, see ``alloc_work``)."""

    px: np.ndarray  # (m,) x at the disk's last event time
    py: np.ndarray  # (m,) y at the disk's last event time
    vx: np.ndarray  # (m,) current velocity
    vy: np.ndarray  # (m,)
    tl: np.ndarray  # (m,) the disk's last event time
    T: np.ndarray  # (N, N) predicted event times: T[i, k] pair, T[i, i] wall
    wall: np.ndarray  # (N,) int64 which wall T[i, i] is
    rowmin: np.ndarray  # (N,) min of row i of T
    rowarg: np.ndarray  # (N,) int64 its column
    tw: np.ndarray  # (m,) next wall time (-inf in padding lanes)
    tmp: np.ndarray  # (m,) a row of fresh pair predictions
    rad: np.ndarray  # (m,) radii (0 in padding lanes)


@njit(cache=True, error_model="numpy")
def alloc_work(n):
    """Scratch arrays for ``run``: a :class:`Work` (allocate once, reuse for many runs).

    Per-disk arrays are padded to a multiple of 16 lanes so the vectorized
    prediction loop has no scalar remainder; padding lanes have wall time -inf,
    which makes their horizon negative, so they never produce a prediction.

    Args:
        n: the number of disks.

    Returns:
        A :class:`Work` for ``n`` disks.
    """
    m = (n + 15) // 16 * 16
    return Work(np.zeros(m), np.zeros(m), np.zeros(m), np.zeros(m), np.zeros(m), np.empty((n, n)),
                np.empty(n, np.int64), np.empty(n), np.empty(n, np.int64), np.full(m, -np.inf), np.empty(m),
                np.zeros(m))


@njit(cache=True, inline="always", error_model="numpy")
def _rescan(T, rowmin, rowarg, i, n):
    m = T[i, i]
    a = i
    for k in range(n):
        if T[i, k] < m:
            m = T[i, k]
            a = k
    rowmin[i] = m
    rowarg[i] = a


@njit(cache=True, inline="always", error_model="numpy")
def _update_row(i, skip, t, px, py, vx, vy, tl, T, wall, rowmin, rowarg, radius, W, H, n, t_final, tw, tmp, rad):
    # Twenty parameters on purpose: inlined into ``run``'s loop; its arrays are run's locals
    # (unpacked from Work once per run), passed flat so the prediction loop vectorizes.
    """Disk i (at time t, tl[i] == t) has a new velocity: re-predict row i.
    ``skip`` is a disk whose pair entry with i was already set (or -1).

    A pair prediction only has to be exact if it comes before either disk's next
    wall contact (``tw``) and before t_final: any later one is re-predicted when
    that disk's velocity changes. The prediction loop is branch-free so LLVM
    vectorizes it; ``pair_tau`` is the same formula, branchy, for single pairs.
    """
    t_w, w = wall_tau(px[i], py[i], vx[i], vy[i], radius[i], W, H)
    T[i, i] = t + t_w
    tw[i] = t + t_w
    wall[i] = w
    hi = min(t + t_w, t_final)
    xi = px[i]
    yi = py[i]
    ui = vx[i]
    wi = vy[i]
    ri = radius[i]
    for k in range(tmp.shape[0]):
        dt = t - tl[k]
        dx = px[k] + vx[k] * dt - xi
        dy = py[k] + vy[k] * dt - yi
        dvx = vx[k] - ui
        dvy = vy[k] - wi
        s = ri + rad[k]
        b = dx * dvx + dy * dvy
        a = dvx * dvx + dvy * dvy
        c = dx * dx + dy * dy - s * s
        disc = b * b - a * c
        tau = max(c / (-b + math.sqrt(max(disc, 0.0))), 0.0)  # stable root; 0 if round-off overlap
        ok = (b < 0.0) & (disc >= 0.0) & (tau <= min(hi, tw[k]) - t)
        tmp[k] = t + tau if ok else INF
    m = T[i, i]
    am = i
    for k in range(n):
        if k == i:
            continue
        if k == skip:
            tk = T[i, k]
        else:
            tk = tmp[k]
            T[i, k] = tk
            T[k, i] = tk
            if tk < rowmin[k]:
                rowmin[k] = tk
                rowarg[k] = i
            elif rowarg[k] == i:
                _rescan(T, rowmin, rowarg, k, n)
        if tk < m:
            m = tk
            am = k
    rowmin[i] = m
    rowarg[i] = am


@njit(cache=True, error_model="numpy")
def run(x0, v0, radius, mass, W, H, t_final, work, out_final, out_vel, max_events,
        ev_t, ev_i, ev_j, ev_state):
    # Length and parameters on purpose: the event loop is the hot path of every simulation; numba
    # takes arrays, and each caller (evaluate, simulate, polish, the Jacobian's records) passes its own
    # buffers, so the inputs stay flat arrays and the loop stays one function LLVM optimizes whole.
    """Simulate from t = 0 to t_final.

    Args:
        x0, v0: (N, 2) float64 arrays: start positions (units) and velocities (units/s).
        radius, mass: (N,) float64 arrays.
        W, H: the box, units.
        t_final: seconds.
        work: from ``alloc_work(N)``.
        out_final: (N, 2) float64 array, filled with positions at t_final (a run that stops
            early: at its last event's time, inside the box).
        out_vel: (N, 2) float64 array, filled with velocities at t_final (or after the last event).
        max_events: the event cap.
        ev_t, ev_i, ev_j, ev_state: event record buffers of equal length (length 0: record
            nothing): ev_t time, ev_i / ev_j participants (ev_j = -1 - wall for a wall event),
            ev_state[e] = (xi, yi, vxi, vyi, xj, yj, vxj, vyj) after it.

    Returns:
        (status, n_events, n_disk_disk, n_wall); status STATUS_TRUNCATED: max_events reached
        before t_final, STATUS_STALLED: more than STALL_EVENTS_PER_DISK * N events within
        STALL_RTOL * t_final seconds (a jam that would never end).
    """
    px, py, vx, vy, tl, T, wall, rowmin, rowarg, tw, tmp, rad = work
    n = x0.shape[0]
    for i in range(n):
        rad[i] = radius[i]
    cap = ev_t.shape[0]
    for i in range(n):
        px[i] = x0[i, 0]
        py[i] = x0[i, 1]
        vx[i] = v0[i, 0]
        vy[i] = v0[i, 1]
        tl[i] = 0.0
    for i in range(n):
        t_w, w = wall_tau(px[i], py[i], vx[i], vy[i], radius[i], W, H)
        T[i, i] = t_w
        tw[i] = t_w
        wall[i] = w
    for i in range(n):
        hi = min(tw[i], t_final)
        for k in range(i + 1, n):
            tk = pair_tau(px[k] - px[i], py[k] - py[i], vx[k] - vx[i], vy[k] - vy[i], radius[i] + radius[k],
                          min(hi, tw[k]))
            T[i, k] = tk
            T[k, i] = tk
    for i in range(n):
        _rescan(T, rowmin, rowarg, i, n)

    status = STATUS_OK
    n_ev = 0
    n_dd = 0
    n_wall = 0
    t_last = 0.0  # time of the last processed event
    t_inst = 0.0  # start of the current "instant" (stall test)
    n_inst = 0
    stall_events, stall_dt = stall_limits(n, t_final)
    while True:
        i = 0
        te = rowmin[0]
        for k in range(1, n):
            if rowmin[k] < te:
                te = rowmin[k]
                i = k
        if te > t_final:
            break
        status, t_inst, n_inst = event_guard(te, n_ev, max_events, t_inst, n_inst, stall_events, stall_dt)
        if status != STATUS_OK:
            break
        t_last = te
        j = rowarg[i]
        # advance i (and j) to the event time
        px[i] += vx[i] * (te - tl[i])
        py[i] += vy[i] * (te - tl[i])
        tl[i] = te
        if j == i:
            w = wall[i]
            r = radius[i]
            if w == WALL_LEFT or w == WALL_RIGHT:
                vx[i] = -vx[i]
                px[i] = r if w == WALL_LEFT else W - r  # exactly at contact: no drift through walls
            else:
                vy[i] = -vy[i]
                py[i] = r if w == WALL_BOTTOM else H - r
            n_wall += 1
            jj = -1 - w
            _update_row(i, -1, te, px, py, vx, vy, tl, T, wall, rowmin, rowarg, radius, W, H, n, t_final, tw, tmp, rad)
        else:
            px[j] += vx[j] * (te - tl[j])
            py[j] += vy[j] * (te - tl[j])
            tl[j] = te
            nx = px[j] - px[i]
            ny = py[j] - py[i]
            d = math.sqrt(nx * nx + ny * ny)
            nx /= d
            ny /= d
            vx[i], vy[i], vx[j], vy[j] = elastic_impulse(vx[i], vy[i], vx[j], vy[j], nx, ny, mass[i], mass[j])
            n_dd += 1
            jj = j
            # the pair entry (i, j) first, so neither row update re-predicts it
            tij = te + pair_tau(px[j] - px[i], py[j] - py[i], vx[j] - vx[i], vy[j] - vy[i],
                                radius[i] + radius[j], t_final - te)
            T[i, j] = tij
            T[j, i] = tij
            _update_row(i, j, te, px, py, vx, vy, tl, T, wall, rowmin, rowarg, radius, W, H, n, t_final, tw, tmp, rad)
            _update_row(j, i, te, px, py, vx, vy, tl, T, wall, rowmin, rowarg, radius, W, H, n, t_final, tw, tmp, rad)
        if cap > 0:
            if n_ev >= cap:
                status = STATUS_OVERFLOW
                break
            record_event(ev_t, ev_i, ev_j, ev_state, n_ev, te, i, jj,
                         px[i], py[i], vx[i], vy[i], px[jj], py[jj], vx[jj], vy[jj])
        n_ev += 1
    t_stop = t_final if status == STATUS_OK else t_last  # never extrapolate past the last event
    for i in range(n):
        out_final[i, 0] = px[i] + vx[i] * (t_stop - tl[i])
        out_final[i, 1] = py[i] + vy[i] * (t_stop - tl[i])
        out_vel[i, 0] = vx[i]
        out_vel[i, 1] = vy[i]
    return status, n_ev, n_dd, n_wall


@njit(cache=True, inline="always", error_model="numpy")
def cost_signature(final, target, R):
    """The cost and signature of one run's final positions.

    Args:
        final: (N, 2) float64 array, units: the final positions.
        target: (N, 2) float64 array, units: the targets.
        R: the target radius, units.

    Returns:
        (cost, signature): the sum of squared final-target distances (units^2) and the bitmask
        (bit i iff disk i ends within R).
    """
    cost = 0.0
    sig = np.int64(0)
    R2 = R * R
    for i in range(final.shape[0]):
        d2 = _dist2(final, target, i)
        cost += d2
        if d2 <= R2:
            sig |= np.int64(1) << np.int64(i)
    return cost, sig


@njit(cache=True, nogil=True, error_model="numpy")
def evaluate_kernel(x0, V, radius, mass, target, W, H, t_final, R, max_events, final, cost, sig, n_events):
    # Fourteen parameters on purpose: the batch entry point over flat arrays (numba), called from
    # Python threads on slices of the output arrays.
    """A batch of runs (compiled, parallel over the batch); a run that hits max_events gets
    cost = inf and signature 0.

    Args:
        x0: (N, 2) float64 array, units: the start positions.
        V: (B, N, 2) float64 array, units/s: the initial velocities of each run.
        radius, mass: (N,) float64 arrays.
        target: (N, 2) float64 array, units.
        W, H: the box, units.
        t_final: seconds.
        R: the target radius, units.
        max_events: the event cap per run.
        final: (B, N, 2) float64 array, filled with the final positions.
        cost: (B,) float64 array, filled with the costs.
        sig: (B,) int64 array, filled with the signatures.
        n_events: (B,) int64 array, filled with each run's events.

    Returns:
        None: the results are written into ``final``, ``cost``, ``sig`` and ``n_events``.
    """
    n = x0.shape[0]
    work = alloc_work(n)
    vel = np.empty((n, 2))
    no_t = np.empty(0)
    no_i = np.empty(0, np.int64)
    no_s = np.empty((0, 8))
    for b in range(V.shape[0]):
        st, ne, _, _ = run(x0, V[b], radius, mass, W, H, t_final, work, final[b], vel, max_events,
                           no_t, no_i, no_i, no_s)
        n_events[b] = ne
        if st == STATUS_OK:
            c, s = cost_signature(final[b], target, R)
            cost[b] = c
            sig[b] = s
        else:
            cost[b] = INF
            sig[b] = 0


@njit(cache=True, inline="always", error_model="numpy")
def cost_signature_words(final, target, R, words):
    """``cost_signature`` for any N: the cost, and the signature as a multiword bitset written
    into ``words`` ((N + 63) // 64 uint64; bit i % 64 of word i // 64 iff disk i is within R)."""
    cost = 0.0
    R2 = R * R
    for w in range(words.shape[0]):
        words[w] = np.uint64(0)
    for i in range(final.shape[0]):
        d2 = _dist2(final, target, i)
        cost += d2
        if d2 <= R2:
            words[i >> 6] |= np.uint64(1) << np.uint64(i & 63)
    return cost
