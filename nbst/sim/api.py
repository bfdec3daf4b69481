"""The simulator's public API: ``evaluate`` (a batch, costs only), ``simulate`` (one
motion with its events, as a :class:`Trajectory`). The compiled event kernel is in
``nbst.sim.kernel``.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numba import njit
from numpy.typing import ArrayLike

from nbst.constants import (EVENT_BUFFER, EVENT_DISK, EVENT_WALL, PARALLEL_BATCH, WALL_NAMES, many_body,
                            max_events_for)
from nbst.errors import InputError
from nbst.problem import Problem
from nbst.sim.cells import CELLS_MIN_DISKS, alloc_cells, evaluate_words_kernel, run_cells
from nbst.sim.kernel import (INF, STATUS_OVERFLOW, STATUS_STALLED, STATUS_TRUNCATED, alloc_work, cost_signature,
                             cost_signature_words, evaluate_kernel, run)
from nbst.solution import signature_string

__all__ = ["DENSE_KEYFRAMES", "uses_cells", "signature_words_to_int", "evaluate", "evaluate_events", "Trajectory",
           "EVENT_DTYPE", "simulate"]

#: Largest keyframe table (events x disks) a ``Trajectory`` builds on its own for ``at``;
#: past it ``at`` replays the event record (the same numbers, no K x N arrays: a 10,000-disk
#: motion with 50,000 events would need 16 GB of keyframes).
DENSE_KEYFRAMES = 4_000_000


_POOLS: dict = {}


def _pool(k: int):
    """A thread pool of k threads, made once and kept: a search that evaluates small batches
    many times a second would otherwise spend more time starting threads than simulating."""
    ex = _POOLS.get(k)
    if ex is None:
        from concurrent.futures import ThreadPoolExecutor

        ex = _POOLS[k] = ThreadPoolExecutor(k, thread_name_prefix="nbst-evaluate")
    return ex


def uses_cells(n: int) -> bool:
    """Whether ``simulate`` and ``evaluate`` run n disks on the cell-grid kernel
    (``nbst.sim.cells``) rather than the table (``nbst.sim.kernel``)."""
    return int(n) >= CELLS_MIN_DISKS


def signature_words_to_int(words) -> int:
    """A multiword signature ((N + 63) // 64 uint64, little-endian words) as a Python int."""
    return int.from_bytes(np.ascontiguousarray(words, dtype="<u8").tobytes(), "little")

def _check_velocities(problem: Problem, V: np.ndarray) -> None:
    if V.shape[-2:] != (problem.n, 2):
        raise InputError(f"velocities have shape {V.shape}; expected (..., {problem.n}, 2) for problem {problem.name!r}")
    if not np.all(np.isfinite(V)):
        raise InputError("velocities must be finite")
    if np.any(V[..., ~problem.cueable, :] != 0.0):
        raise InputError("noncueable disks must have zero initial velocity")


def evaluate(problem: Problem, V: ArrayLike, *, max_events: int | None = None,
             jobs: int | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Simulate a batch of candidate velocity sets (no per-trial Python).

    Args:
        problem: the problem (``nbst.load_problem``).
        V: (B, N, 2) float, units/s: B candidate sets of initial velocities (zero rows for
            noncueable disks).
        max_events: the event cap of each run (default ``nbst.constants.max_events_for(N)``).
        jobs: threads for a batch of at least PARALLEL_BATCH candidates (the kernel releases
            the GIL; each thread takes a contiguous slice); None: every core; 1: this thread.
            The results do not depend on it: each candidate is simulated alone.

    Returns:
        (final, cost, signature): final (B, N, 2) positions at t_final; cost (B,) float, the sum
        of squared distances to the targets (units^2); signature (B,): an int64 bitmask up to 63
        disks, past that an object array of Python ints (bit i: disk i within R; the kernels
        keep multiword bitsets). cost is inf (signature 0) for a run that needed more than
        ``max_events`` events or jammed. ``evaluate_events`` returns the event counts too.

    Raises:
        InputError: ``V`` is not (B, N, 2), not finite, or moves a noncueable disk.
    """
    final, cost, sig, _ = evaluate_events(problem, V, max_events=max_events, jobs=jobs)
    return final, cost, sig


def evaluate_events(problem: Problem, V: ArrayLike, *, max_events: int | None = None,
                    jobs: int | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`evaluate`, also returning each run's number of events.

    Args:
        problem, V, max_events, jobs: as :func:`evaluate`.

    Returns:
        (final, cost, signature, n_events): as :func:`evaluate`, and n_events (B,) int64 array.

    Raises:
        InputError: ``V`` is not (B, N, 2), not finite, or moves a noncueable disk.
    """
    V = np.ascontiguousarray(V, dtype=np.float64)
    if V.ndim != 3:
        raise InputError(f"V must have shape (B, N, 2), got {V.shape}")
    _check_velocities(problem, V)
    ka = problem.kernel_arrays()
    n = problem.n
    if max_events is None:
        max_events = max_events_for(n)
    B = V.shape[0]
    final = np.empty((B, n, 2))
    cost = np.empty(B)
    n_events = np.empty(B, np.int64)
    wide = many_body(n)  # multiword signatures
    sig = np.empty((B, (n + 63) // 64), np.uint64) if wide else np.empty(B, np.int64)

    def run_slice(a: int, b: int) -> None:
        if wide:
            evaluate_words_kernel(ka.start, V[a:b], ka.radius, ka.mass, ka.target, ka.W, ka.H, ka.t_final, ka.R,
                                  int(max_events), uses_cells(n), final[a:b], cost[a:b], sig[a:b], n_events[a:b])
        else:
            evaluate_kernel(ka.start, V[a:b], ka.radius, ka.mass, ka.target, ka.W, ka.H, ka.t_final, ka.R,
                            int(max_events), final[a:b], cost[a:b], sig[a:b], n_events[a:b])

    if jobs is None:
        from nbst.parallel import default_jobs

        jobs = default_jobs()
    # a candidate of many disks is work enough for a thread of its own
    k = max(1, min(int(jobs), B if wide else B // PARALLEL_BATCH))
    if k == 1:
        run_slice(0, B)
    else:
        cuts = np.linspace(0, B, k + 1).astype(np.int64)
        ex = _pool(k)
        for f in [ex.submit(run_slice, int(cuts[i]), int(cuts[i + 1])) for i in range(k)]:
            f.result()
    if wide:
        out = np.empty(B, object)
        for b in range(B):
            out[b] = signature_words_to_int(sig[b])
        sig = out
    return final, cost, sig, n_events


@dataclass(frozen=True, eq=False)
class Trajectory:
    """The exact motion of one simulation.

    ``at(t)`` gives the same numbers whether it reads the keyframes or, for a motion past
    ``DENSE_KEYFRAMES`` (events x disks), replays the event record without building them.
    ``positions`` and ``velocities``, (K, N, 2) at the keyframe times (after each event), are
    built on first use.

    Args:
        problem: the problem simulated.
        initial_velocities: (N, 2) float64 array, units/s.
        times: (K,) float64 array: keyframe times: 0, then each event time (non-decreasing),
            K = E + 1.
        events: (E,) structured array: time, kind (0 disk-disk, 1 wall), i, j (j = partner
            disk, or the wall 0 left, 1 right, 2 bottom, 3 top).
        event_state: (E, 8) float64 array: the participants' states after each event (xi, yi,
            vxi, vyi, xj, yj, vxj, vyj; the j half unused for a wall), as the kernel recorded them.
        final_positions, final_velocities: (N, 2) float64 arrays at t_final.
        cost: the sum of squared final-target distances, units^2.
        signature: Python int, bit i iff disk i ends within R.
        truncated: the run stopped before t_final (``max_events`` reached, or ``stalled``); the
            motion is exact up to ``t_end`` (its last event) and is held there: ``final_positions``
            and ``at(t)`` for t > t_end are the positions at t_end, inside the box.
        stalled: it stopped because of a jam (disks pinned between opposite walls bouncing
            infinitely often at one instant), not the event cap.
        t_end: t_final, or the time of the last event of a truncated run.

    Returns:
        The trajectory, as :func:`simulate` builds it.
    """

    problem: Problem
    initial_velocities: np.ndarray
    times: np.ndarray
    events: np.ndarray
    event_state: np.ndarray
    final_positions: np.ndarray
    final_velocities: np.ndarray
    cost: float
    signature: int
    truncated: bool
    stalled: bool = False
    t_end: float | None = None

    @cached_property
    def _keyframes(self):
        x0 = self.problem.kernel_arrays().start
        pos, vel = _keyframes(x0, np.ascontiguousarray(self.initial_velocities), self.times, self.events["i"],
                              _ev_j(self.events), self.event_state)
        pos.setflags(write=False)
        vel.setflags(write=False)
        return pos, vel

    @property
    def positions(self) -> np.ndarray:
        return self._keyframes[0]

    @property
    def velocities(self) -> np.ndarray:
        return self._keyframes[1]

    @property
    def end_time(self) -> float:
        """Time up to which the motion is exact: t_final, or ``t_end`` for a truncated run."""
        return float(self.problem.t_final if self.t_end is None else self.t_end)

    @property
    def order(self) -> int:
        return int(self.signature).bit_count()

    @property
    def signature_string(self) -> str:
        return signature_string(self.signature, self.problem.n)

    @property
    def n_disk_disk(self) -> int:
        return int(np.count_nonzero(self.events["kind"] == EVENT_DISK))

    @property
    def n_wall(self) -> int:
        return int(np.count_nonzero(self.events["kind"] == EVENT_WALL))

    def _dense(self, replay: bool | None = None) -> bool:
        if replay is not None:
            return not replay
        return "_keyframes" in self.__dict__ or self.times.size * self.problem.n <= DENSE_KEYFRAMES

    def at(self, t, *, replay: bool | None = None):
        """Positions at time(s) t in [0, t_final]: (N, 2) for a scalar, (T, N, 2) for an array.

        Exact: the keyframe before t plus straight flight. At an event time the
        state after the event is used (positions are continuous anyway). A truncated
        run holds its positions at ``t_end`` for later t. ``replay``: read the event record
        (True) or the keyframes (False); None chooses by size (the numbers are the same).
        """
        ts = np.asarray(t, dtype=float)
        if np.any(ts < 0.0) or np.any(ts > self.problem.t_final * (1 + 1e-12)):
            raise InputError(f"t must lie in [0, t_final = {self.problem.t_final}]")
        if self.truncated:
            ts = np.minimum(ts, self.end_time)
        if self._dense(replay):
            k = np.searchsorted(self.times, ts, side="right") - 1
            dt = (ts - self.times[k])[..., None, None]
            return self.positions[k] + self.velocities[k] * dt
        return self._replay(ts, False)

    def velocity_at(self, t, *, replay: bool | None = None):
        """Velocities at time(s) t (just after any event at exactly t)."""
        ts = np.asarray(t, dtype=float)
        if self._dense(replay):
            k = np.searchsorted(self.times, ts, side="right") - 1
            return self.velocities[k]
        return self._replay(ts, True)

    def _replay(self, ts: np.ndarray, velocity: bool) -> np.ndarray:
        """Positions (or velocities) at times ts from the event record, no keyframes."""
        flat = ts.reshape(-1)
        order = np.argsort(flat, kind="stable")
        out = np.empty((flat.size, self.problem.n, 2))
        _replay_at(self.problem.kernel_arrays().start, np.ascontiguousarray(self.initial_velocities), self.times,
                   self.events["i"].astype(np.int64), _ev_j(self.events), self.event_state, flat[order], order, out,
                   velocity)
        return out.reshape(ts.shape + (self.problem.n, 2))

    def describe_event(self, e: int) -> str:
        ev = self.events[e]
        if ev["kind"] == EVENT_WALL:
            return f"t={ev['time']:.6f}s disk {ev['i']} hits the {WALL_NAMES[ev['j']]} wall"
        return f"t={ev['time']:.6f}s disks {ev['i']} and {ev['j']} collide"


def _ev_j(events) -> np.ndarray:
    """The kernel's j of each event: the partner disk, or -1 - wall."""
    return np.where(events["kind"] == EVENT_WALL, -1 - events["j"].astype(np.int64), events["j"].astype(np.int64))


@njit(cache=True, inline="always")
def _apply_event(e, t, ev_i, ev_j, ev_s, cur_p, cur_v, cur_t):
    """Event e of the record (at time t): its participants' positions and velocities after it."""
    i = ev_i[e]
    j = ev_j[e]
    cur_p[i, 0] = ev_s[e, 0]
    cur_p[i, 1] = ev_s[e, 1]
    cur_v[i, 0] = ev_s[e, 2]
    cur_v[i, 1] = ev_s[e, 3]
    cur_t[i] = t
    if j >= 0:
        cur_p[j, 0] = ev_s[e, 4]
        cur_p[j, 1] = ev_s[e, 5]
        cur_v[j, 0] = ev_s[e, 6]
        cur_v[j, 1] = ev_s[e, 7]
        cur_t[j] = t


@njit(cache=True, error_model="numpy")
def _keyframes(x0, v0, times, ev_i, ev_j, ev_s):
    """The (K, N, 2) positions and velocities after each event (K = events + 1), from the record."""
    n = x0.shape[0]
    K = times.shape[0]
    pos = np.empty((K, n, 2))
    vel = np.empty((K, n, 2))
    cur_p = x0.copy()  # position of each disk at its own last event time
    cur_t = np.zeros(n)
    cur_v = v0.copy()
    pos[0] = x0
    vel[0] = v0
    for e in range(K - 1):
        t = times[e + 1]
        _apply_event(e, t, ev_i, ev_j, ev_s, cur_p, cur_v, cur_t)
        for k in range(n):
            pos[e + 1, k, 0] = cur_p[k, 0] + cur_v[k, 0] * (t - cur_t[k])
            pos[e + 1, k, 1] = cur_p[k, 1] + cur_v[k, 1] * (t - cur_t[k])
            vel[e + 1, k, 0] = cur_v[k, 0]
            vel[e + 1, k, 1] = cur_v[k, 1]
    return pos, vel


@njit(cache=True, error_model="numpy")
def _replay_at(x0, v0, times, ev_i, ev_j, ev_s, ts, slot, out, want_velocity=False):
    """``Trajectory.at`` (or ``velocity_at``) for sorted times ts without keyframes: replay the
    events up to each t and write, into out[slot[q]], the keyframe's numbers (the position at
    the last event time t_k, then straight flight from there: the same two steps as the table)."""
    n = x0.shape[0]
    cur_p = x0.copy()
    cur_t = np.zeros(n)
    cur_v = v0.copy()
    K = times.shape[0]
    e = 0
    for q in range(ts.shape[0]):
        t = ts[q]
        while e + 1 < K and times[e + 1] <= t:
            _apply_event(e, times[e + 1], ev_i, ev_j, ev_s, cur_p, cur_v, cur_t)
            e += 1
        tk = times[e]
        o = slot[q]
        for k in range(n):
            if want_velocity:
                out[o, k, 0] = cur_v[k, 0]
                out[o, k, 1] = cur_v[k, 1]
            else:
                out[o, k, 0] = (cur_p[k, 0] + cur_v[k, 0] * (tk - cur_t[k])) + cur_v[k, 0] * (t - tk)
                out[o, k, 1] = (cur_p[k, 1] + cur_v[k, 1] * (tk - cur_t[k])) + cur_v[k, 1] * (t - tk)


EVENT_DTYPE = np.dtype([("time", "f8"), ("kind", "i1"), ("i", "i4"), ("j", "i4")])


def simulate(problem: Problem, velocities: ArrayLike, *, max_events: int | None = None) -> Trajectory:
    """Simulate one motion exactly and keep its events (for rendering, MuJoCo checks, reports).

    From ``CELLS_MIN_DISKS`` disks it runs on the cell-grid kernel (the same events).

    Args:
        problem: the problem (``nbst.load_problem``).
        velocities: (N, 2) float, units/s (zero rows for noncueable disks), e.g. a solution's.
        max_events: the event cap (default ``nbst.constants.max_events_for(N)``).

    Returns:
        A :class:`Trajectory`: the events, ``at(t)``, the final positions and velocities, the
        cost, the signature and order. A run that stops early (``max_events``, or a jam) comes
        back with ``truncated`` (and ``stalled``) set, cost inf, positions held at its last event.

    Raises:
        InputError: ``velocities`` is not (N, 2), not finite, or moves a noncueable disk.
    """
    v0 = np.ascontiguousarray(velocities, dtype=np.float64)
    if v0.flags.writeable:  # read-only, as a solution file's are: one signature of each kernel below
        v0 = v0.view()      # (numba compiles writable and read-only arrays apart; the cell-grid
        v0.setflags(write=False)  # kernel takes ~1 min a signature on a cold cache)
    if v0.ndim != 2:
        raise InputError(f"velocities must have shape (N, 2), got {v0.shape}")
    _check_velocities(problem, v0)
    ka = problem.kernel_arrays()
    x0 = ka.start
    n = problem.n
    if max_events is None:
        max_events = max_events_for(n)
    cap = EVENT_BUFFER
    cells = uses_cells(n)
    work = alloc_cells(n) if cells else alloc_work(n)
    kernel = run_cells if cells else run
    final = np.empty((n, 2))
    fvel = np.empty((n, 2))
    while True:
        ev_t = np.empty(cap)
        ev_i = np.empty(cap, np.int64)
        ev_j = np.empty(cap, np.int64)
        ev_s = np.empty((cap, 8))
        status, n_ev, _, _ = kernel(x0, v0, ka.radius, ka.mass, ka.W, ka.H, ka.t_final, work, final, fvel,
                                    int(max_events), ev_t, ev_i, ev_j, ev_s)
        if status != STATUS_OVERFLOW:
            break
        cap = min(cap * 4, int(max_events) + 1)
    n_ev = min(n_ev, cap)
    times = np.empty(n_ev + 1)
    times[0] = 0.0
    times[1:] = ev_t[:n_ev]
    events = np.empty(n_ev, EVENT_DTYPE)
    events["time"] = ev_t[:n_ev]
    wall_ev = ev_j[:n_ev] < 0
    events["kind"] = np.where(wall_ev, EVENT_WALL, EVENT_DISK)
    events["i"] = ev_i[:n_ev]
    events["j"] = np.where(wall_ev, -1 - ev_j[:n_ev], ev_j[:n_ev])
    ev_state = ev_s[:n_ev].copy()
    ev_state[wall_ev, 4:] = 0.0  # the j half of a wall event is not written by the kernel
    truncated = status in (STATUS_TRUNCATED, STATUS_STALLED)
    t_end = float(times[-1]) if truncated else float(problem.t_final)
    if truncated:
        cost, sig = INF, 0
    elif many_body(n):
        words = np.empty((n + 63) // 64, np.uint64)
        cost = cost_signature_words(final, ka.target, ka.R, words)
        sig = signature_words_to_int(words)
    else:
        cost, sig = cost_signature(final, ka.target, ka.R)
    for a in (times, events, ev_state, final, fvel):
        a.setflags(write=False)
    return Trajectory(problem=problem, initial_velocities=v0, times=times, events=events, event_state=ev_state,
                      final_positions=final, final_velocities=fvel, cost=float(cost), signature=int(sig),
                      truncated=truncated, stalled=status == STATUS_STALLED, t_end=t_end)
