"""The simulator's public API: ``evaluate`` (a batch, costs only), ``simulate`` (one
motion with its events, as a :class:`Trajectory`). The compiled event kernel is in
``nbst.sim.kernel``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from nbst.constants import EVENT_BUFFER, EVENT_DISK, EVENT_WALL, MAX_EVENTS, PARALLEL_BATCH, WALL_NAMES
from nbst.problem import Problem
from nbst.sim.kernel import (INF, STATUS_OVERFLOW, STATUS_STALLED, STATUS_TRUNCATED, alloc_work, cost_signature,
                             evaluate_kernel, run)

def _check_velocities(problem: Problem, V: np.ndarray) -> None:
    if V.shape[-2:] != (problem.n, 2):
        raise ValueError(f"velocities have shape {V.shape}; expected (..., {problem.n}, 2) for problem {problem.name!r}")
    if not np.all(np.isfinite(V)):
        raise ValueError("velocities must be finite")
    if np.any(V[..., ~problem.cueable, :] != 0.0):
        raise ValueError("noncueable disks must have zero initial velocity")


def evaluate(problem: Problem, V, *, max_events: int = MAX_EVENTS, jobs: int | None = None):
    """Simulate a batch of candidate velocity sets (no per-trial Python).

    V : (B, N, 2) float, units/s
    returns final (B, N, 2), cost (B,) float, signature (B,) int64 bitmask. cost is inf
    (signature 0) for a run that needed more than ``max_events`` events (or jammed).
    jobs : threads for a batch of at least PARALLEL_BATCH candidates (the kernel releases
           the GIL; each thread takes a contiguous slice); None: every core; 1: this thread.
           The results do not depend on it: each candidate is simulated alone.
    ``evaluate_events`` returns the event counts too.
    """
    final, cost, sig, _ = evaluate_events(problem, V, max_events=max_events, jobs=jobs)
    return final, cost, sig


def evaluate_events(problem: Problem, V, *, max_events: int = MAX_EVENTS, jobs: int | None = None):
    """:func:`evaluate`, also returning each run's number of events: (final, cost, signature,
    n_events (B,) int64)."""
    V = np.ascontiguousarray(V, dtype=np.float64)
    if V.ndim != 3:
        raise ValueError(f"V must have shape (B, N, 2), got {V.shape}")
    _check_velocities(problem, V)
    ka = problem.kernel_arrays()
    B = V.shape[0]
    final = np.empty((B, problem.n, 2))
    cost = np.empty(B)
    sig = np.empty(B, np.int64)
    n_events = np.empty(B, np.int64)

    def run_slice(a: int, b: int) -> None:
        evaluate_kernel(ka.start, V[a:b], ka.radius, ka.mass, ka.target, ka.W, ka.H, ka.t_final, ka.R,
                        int(max_events), final[a:b], cost[a:b], sig[a:b], n_events[a:b])

    if jobs is None:
        from nbst.parallel import default_jobs

        jobs = default_jobs()
    k = max(1, min(int(jobs), B // PARALLEL_BATCH))
    if k == 1:
        run_slice(0, B)
    else:
        from concurrent.futures import ThreadPoolExecutor

        cuts = np.linspace(0, B, k + 1).astype(np.int64)
        with ThreadPoolExecutor(k) as ex:
            for f in [ex.submit(run_slice, int(cuts[i]), int(cuts[i + 1])) for i in range(k)]:
                f.result()
    return final, cost, sig, n_events


@dataclass(frozen=True, eq=False)
class Trajectory:
    """The exact motion of one simulation.

    times      : (K,) keyframe times: 0, then each event time (non-decreasing)
    positions  : (K, N, 2) positions at those times (after the event)
    velocities : (K, N, 2) velocities just after those times
    events     : structured (E,) array: time, kind (0 disk-disk, 1 wall), i, j
                 (j = partner disk, or the wall 0 left, 1 right, 2 bottom, 3 top)
    final_positions / final_velocities : (N, 2) at t_final
    truncated  : the run stopped before t_final (``max_events`` reached, or ``stalled``);
                 the motion is exact up to ``t_end`` (its last event) and is held there:
                 ``final_positions`` and ``at(t)`` for t > t_end are the positions at
                 t_end, inside the box (never extrapolated through the walls)
    stalled    : it stopped because of a jam (disks pinned between opposite walls
                 bouncing infinitely often at one instant), not the event cap
    t_end      : t_final, or the time of the last event of a truncated run
    """

    problem: Problem
    initial_velocities: np.ndarray
    times: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray
    events: np.ndarray
    final_positions: np.ndarray
    final_velocities: np.ndarray
    cost: float
    signature: int
    truncated: bool
    stalled: bool = False
    t_end: float | None = None

    @property
    def end_time(self) -> float:
        """Time up to which the motion is exact: t_final, or ``t_end`` for a truncated run."""
        return float(self.problem.t_final if self.t_end is None else self.t_end)

    @property
    def order(self) -> int:
        return int(self.signature).bit_count()

    @property
    def signature_string(self) -> str:
        from nbst.solution import signature_string
        return signature_string(self.signature, self.problem.n)

    @property
    def n_disk_disk(self) -> int:
        return int(np.count_nonzero(self.events["kind"] == EVENT_DISK))

    @property
    def n_wall(self) -> int:
        return int(np.count_nonzero(self.events["kind"] == EVENT_WALL))

    def at(self, t):
        """Positions at time(s) t in [0, t_final]: (N, 2) for a scalar, (T, N, 2) for an array.

        Exact: the keyframe before t plus straight flight. At an event time the
        state after the event is used (positions are continuous anyway). A truncated
        run holds its positions at ``t_end`` for later t.
        """
        ts = np.asarray(t, dtype=float)
        if np.any(ts < 0.0) or np.any(ts > self.problem.t_final * (1 + 1e-12)):
            raise ValueError(f"t must lie in [0, t_final = {self.problem.t_final}]")
        if self.truncated:
            ts = np.minimum(ts, self.end_time)
        k = np.searchsorted(self.times, ts, side="right") - 1
        dt = (ts - self.times[k])[..., None, None]
        return self.positions[k] + self.velocities[k] * dt

    def velocity_at(self, t):
        """Velocities at time(s) t (just after any event at exactly t)."""
        ts = np.asarray(t, dtype=float)
        k = np.searchsorted(self.times, ts, side="right") - 1
        return self.velocities[k]

    def describe_event(self, e: int) -> str:
        ev = self.events[e]
        if ev["kind"] == EVENT_WALL:
            return f"t={ev['time']:.6f}s disk {ev['i']} hits the {WALL_NAMES[ev['j']]} wall"
        return f"t={ev['time']:.6f}s disks {ev['i']} and {ev['j']} collide"


EVENT_DTYPE = np.dtype([("time", "f8"), ("kind", "i1"), ("i", "i4"), ("j", "i4")])


def simulate(problem: Problem, velocities, *, max_events: int = MAX_EVENTS) -> Trajectory:
    """Simulate one motion exactly and keep its events (for rendering, MuJoCo checks, reports).

    velocities : (N, 2) float, units/s (zero rows for noncueable disks)
    A run that stops early (``max_events``, or a jam) comes back with ``truncated`` (and
    ``stalled``) set, cost inf, positions held at its last event (see ``Trajectory``).
    """
    v0 = np.ascontiguousarray(velocities, dtype=np.float64)
    if v0.ndim != 2:
        raise ValueError(f"velocities must have shape (N, 2), got {v0.shape}")
    _check_velocities(problem, v0)
    ka = problem.kernel_arrays()
    x0 = ka.start
    n = problem.n
    cap = EVENT_BUFFER
    work = alloc_work(n)
    final = np.empty((n, 2))
    fvel = np.empty((n, 2))
    while True:
        ev_t = np.empty(cap)
        ev_i = np.empty(cap, np.int64)
        ev_j = np.empty(cap, np.int64)
        ev_s = np.empty((cap, 8))
        status, n_ev, _, _ = run(x0, v0, ka.radius, ka.mass, ka.W, ka.H, ka.t_final, work, final, fvel,
                                 int(max_events), ev_t, ev_i, ev_j, ev_s)
        if status != STATUS_OVERFLOW:
            break
        cap *= 4
    n_ev = min(n_ev, cap)
    # keyframes: after each event every disk's state (participants exact from the kernel)
    K = n_ev + 1
    times = np.empty(K)
    pos = np.empty((K, n, 2))
    vel = np.empty((K, n, 2))
    times[0] = 0.0
    pos[0] = x0
    vel[0] = v0
    cur_p = x0.copy()  # position of each disk at its own last event time
    cur_t = np.zeros(n)
    cur_v = v0.copy()
    for e in range(n_ev):
        t = ev_t[e]
        i, j = ev_i[e], ev_j[e]
        cur_p[i] = ev_s[e, 0:2]
        cur_v[i] = ev_s[e, 2:4]
        cur_t[i] = t
        if j >= 0:
            cur_p[j] = ev_s[e, 4:6]
            cur_v[j] = ev_s[e, 6:8]
            cur_t[j] = t
        times[e + 1] = t
        pos[e + 1] = cur_p + cur_v * (t - cur_t)[:, None]
        vel[e + 1] = cur_v
    events = np.empty(n_ev, EVENT_DTYPE)
    events["time"] = ev_t[:n_ev]
    wall_ev = ev_j[:n_ev] < 0
    events["kind"] = np.where(wall_ev, EVENT_WALL, EVENT_DISK)
    events["i"] = ev_i[:n_ev]
    events["j"] = np.where(wall_ev, -1 - ev_j[:n_ev], ev_j[:n_ev])
    truncated = status in (STATUS_TRUNCATED, STATUS_STALLED)
    t_end = float(times[-1]) if truncated else float(problem.t_final)
    if truncated:
        cost, sig = INF, 0
    else:
        cost, sig = cost_signature(final, ka.target, ka.R)
    for a in (times, pos, vel, events, final, fvel):
        a.setflags(write=False)
    return Trajectory(problem=problem, initial_velocities=v0, times=times, positions=pos, velocities=vel,
                      events=events, final_positions=final, final_velocities=fvel, cost=float(cost),
                      signature=int(sig), truncated=truncated, stalled=status == STATUS_STALLED, t_end=t_end)
