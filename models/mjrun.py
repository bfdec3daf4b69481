"""Run a scene in MuJoCo: positions every step, contact events, kinetic energy; and ``rollout``.

Two ways to step (``stepping``): ``"fixed"``, MuJoCo's own fixed steps of h (each impact
resolved one step late), and ``"aligned"``, :func:`nbst.models.stepping.step_aligned` (steps
shortened to end at each touch, every impact resolved by a matched micro-step). ``run_final``
is the lean fixed-step run of the convergence study: final positions only, nothing kept per step.

Compute only; mujoco is imported on first call.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from nbst.errors import InputError
from nbst.problem import Problem

from nbst.models.scene import DEFAULT_TIMESTEP, DEFAULT_UNIT, build_model
from nbst.models.stepping import step_aligned

__all__ = ["EVENT_DISK", "EVENT_WALL", "EVENT_DTYPE", "STEPPINGS", "MAX_STEPS", "RECORD_FLOATS", "PROGRESS_EVERY",
           "record_stride", "steps_needed", "check_steps", "MujocoRun", "run_mujoco", "run_final", "rollout"]

#: Event kinds, as in ``nbst.sim`` (0 disk-disk, 1 wall); j = partner disk or wall 0 left 1 right 2 bottom 3 top.
EVENT_DISK, EVENT_WALL = 0, 1
EVENT_DTYPE = np.dtype([("time", "f8"), ("kind", "i1"), ("i", "i4"), ("j", "i4")])
_WALLS = ("wall_left", "wall_right", "wall_bottom", "wall_top")
#: The ways ``run_mujoco`` can step (module docstring).
STEPPINGS = ("fixed", "aligned")

#: Most MuJoCo steps one run may take. A run keeps every step's state (positions, velocities,
#: the per-step comparison in ``validate``: a few hundred bytes per disk and step, about
#: 1 GB for 14 disks at this limit) so the work must be bounded up front: t_final = 1e6 s at
#: the default 0.25 ms step would be 4e9 steps (~300 GiB). 1e6 steps is 250 s of simulated
#: time at the default step, a minute or two of MuJoCo; ``--max-steps`` raises it.
MAX_STEPS = 1_000_000
#: Most numbers a run keeps of its recorded positions (2 per disk and record: 160 MB). Up to it every
#: step is recorded; above it (many disks over many steps: 1,000 disks x 20,000 steps is 4e7) every
#: k-th step, k the smallest stride that fits, plus the last two steps (the final position is then
#: still interpolated between the steps around t_end). Energy and contacts are kept for every step.
RECORD_FLOATS = 20_000_000
#: Steps between two calls of a run's ``progress`` callback.
PROGRESS_EVERY = 500


def record_stride(records: int, n: int, budget: int = RECORD_FLOATS) -> int:
    """Every how many steps a run of ``records`` states of ``n`` disks records positions."""
    return max(1, -(-int(records) * 2 * int(n) // int(budget)))


def _scene_at_start(problem: Problem, velocities: np.ndarray, timestep: float, unit: float):
    """(model, data) of the problem's scene with the solution, data at keyframe ``initial``."""
    import mujoco

    model = build_model(problem, velocities, timestep=timestep, unit=unit)
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, 0)
    return model, data


def steps_needed(t_end: float, timestep: float) -> int:
    """MuJoCo steps to reach ``t_end`` (s) with ``timestep`` (s)."""
    x = t_end / timestep - 1e-9
    return int(math.ceil(x)) if math.isfinite(x) else 2**63 - 1


def check_steps(t_end: float, timestep: float, max_steps: int = MAX_STEPS, *,
                hint: str = "raise it with --max-steps N or use a coarser --timestep") -> int:
    """The step count, or InputError (one line: why, and ``hint``: what changes it) above ``max_steps``."""
    steps = steps_needed(t_end, timestep)
    if steps > max_steps:
        raise InputError(f"t = {t_end:g} s at timestep {timestep:g} s is {steps:,} MuJoCo steps, over the limit "
                         f"of {max_steps:,} (each step's state is kept); {hint}")
    return steps


@dataclass(frozen=True, eq=False)
class MujocoRun:
    """One MuJoCo run of a scene, in problem units.

    times     : (K,) s, 0 then after each recorded step (every step up to :data:`RECORD_FLOATS`;
                ``stride``: every how many)
    positions : (K, N, 2) disk centres at those times, units
    energy    : (S+1,) kinetic energy after every step, mass units x units^2/s^2
    in_contact: (S+1,) bool, any contact active in the step that ended there (every step)
    events    : structured (E,): time (s: fixed stepping: the first step state in which the pair
                overlaps; MuJoCo detects it there and resolves it during the next step; aligned
                stepping: the touch, located to ~1e-13 s), kind, i, j (i < j for disk pairs)
    final_positions : (N, 2) at t_final (linear between the two steps around it)
    stepping  : "fixed" (times = k h) or "aligned" (times: every accepted step and micro-step)
    stats     : aligned stepping's cost (``AlignedStats.to_dict()``), None for fixed
    n_steps   : S, the steps taken (fixed) or accepted steps + micro-steps (aligned)
    stride    : every how many steps positions were recorded (1: all)
    """

    problem: Problem
    timestep: float
    unit: float
    times: np.ndarray
    positions: np.ndarray
    energy: np.ndarray
    in_contact: np.ndarray
    events: np.ndarray
    final_positions: np.ndarray
    wall_time: float
    stepping: str = "fixed"
    stats: dict | None = None
    n_steps: int | None = None
    stride: int = 1

    @property
    def steps(self) -> int:
        return int(self.times.size - 1) if self.n_steps is None else int(self.n_steps)

    def at(self, t):
        """Positions at time(s) t in [0, t_final], linear between steps: (N, 2) or (T, N, 2)."""
        ts = np.asarray(t, dtype=float)
        if self.stepping != "fixed" or self.stride != 1:  # records at uneven times
            last = self.times.size - 1
            k = np.clip(np.searchsorted(self.times, ts, side="right") - 1, 0, max(last - 1, 0))
            k1 = np.minimum(k + 1, last)
            span = self.times[k1] - self.times[k]
            f = np.clip(np.divide(ts - self.times[k], span, out=np.zeros_like(span), where=span > 0), 0.0, 1.0)
            f = f[..., None, None]
            return self.positions[k] * (1 - f) + self.positions[k1] * f
        s = np.clip(ts / self.timestep, 0.0, self.steps)
        k = np.minimum(np.floor(s).astype(np.int64), self.steps - 1) if self.steps else np.zeros_like(s, int)
        f = (s - k)[..., None, None]
        return self.positions[k] * (1 - f) + self.positions[np.minimum(k + 1, self.steps)] * f


def _owners(model, n: int) -> np.ndarray:
    """geom id -> disk index (>= 0), -1 - w for wall w, -100 for anything else."""
    import mujoco
    owner = np.full(model.ngeom, -100, dtype=np.int64)
    for i in range(n):  # by name: ~1 us each, 1 ms at 1,000 disks
        owner[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, f"disk{i}_collision")] = i
    for w, name in enumerate(_WALLS):
        owner[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, name)] = -1 - w
    return owner


def _event(owner, g1: int, g2: int):
    """(kind, i, j) of a contact between geoms g1 and g2, or None if it is no disk's."""
    a, b = int(owner[g1]), int(owner[g2])
    if a == -100 or b == -100:
        return None
    if a < 0:
        a, b = b, a
    if b >= 0:
        return (EVENT_DISK, min(a, b), max(a, b))
    return (EVENT_WALL, a, -1 - b)


def run_mujoco(problem: Problem, velocities, *, timestep: float = DEFAULT_TIMESTEP, unit: float = DEFAULT_UNIT,
               t_end: float | None = None, max_steps: int = MAX_STEPS, stepping: str = "fixed",
               progress=None, record_floats: int = RECORD_FLOATS) -> MujocoRun:
    """Step the problem's scene from keyframe ``initial`` to ``t_end`` (default t_final).

    velocities : (N, 2) float, units/s
    max_steps  : InputError, before any work, if reaching t_end takes more steps (``check_steps``);
                 aligned stepping: RuntimeError past max_steps accepted steps + micro-steps
    stepping   : "fixed" or "aligned" (module docstring)
    progress   : None or a callable progress(k): k more simulated steps of h done (every
                 :data:`PROGRESS_EVERY` steps; aligned: accepted steps)
    record_floats : positions kept at most (:data:`RECORD_FLOATS`; a stride above it)
    """
    import time as _time

    if stepping not in STEPPINGS:
        raise InputError(f"stepping must be one of {', '.join(STEPPINGS)}, got {stepping!r}")
    t_end = float(problem.t_final if t_end is None else t_end)
    steps = check_steps(t_end, timestep, max_steps)

    import mujoco

    v = np.asarray(velocities, dtype=float)
    model, data = _scene_at_start(problem, v, timestep, unit)
    n = problem.n
    owner = _owners(model, n)
    if stepping == "aligned":
        return _run_aligned(problem, model, data, owner, float(timestep), float(unit), t_end, max_steps,
                            progress=progress, stride=record_stride(2 * (steps + 1), n, record_floats))
    mass2 = np.repeat(np.asarray(problem.mass, dtype=float), 2) / (unit * unit)
    start = np.asarray(problem.start, dtype=float)
    stride = record_stride(steps + 1, n, record_floats)
    rec = np.unique(np.concatenate([np.arange(0, steps + 1, stride), [max(steps - 1, 0), steps]]))
    qpos = np.empty((rec.size, 2 * n))
    energy = np.empty(steps + 1)
    in_contact = np.zeros(steps + 1, dtype=bool)
    qpos[0] = data.qpos
    energy[0] = 0.5 * np.dot(mass2, data.qvel * data.qvel)
    base = n + 4  # event code i * base + jj: jj = partner disk, or n + wall
    active = np.empty(0, np.int64)
    ev_codes, ev_steps = [], []
    step = mujoco.mj_step
    r = 1
    next_rec = int(rec[1]) if rec.size > 1 else -1
    t0 = _time.perf_counter()
    for s in range(1, steps + 1):
        step(model, data)
        qv = data.qvel
        energy[s] = 0.5 * np.dot(mass2, qv * qv)
        if s == next_rec:
            qpos[r] = data.qpos
            r += 1
            next_rec = int(rec[r]) if r < rec.size else -1
        nc = data.ncon
        if nc or active.size:
            if nc:
                in_contact[s] = True
                g = data.contact.geom[:nc]  # a fresh view: the contact list is rebuilt every step
                now = _codes(owner[g[:, 0]], owner[g[:, 1]], n, base)
            else:
                now = active[:0]
            new = np.setdiff1d(now, active, assume_unique=True)
            if new.size:
                ev_codes.append(new)
                ev_steps.append(np.full(new.size, s - 1))
            active = now
        if progress is not None and s % PROGRESS_EVERY == 0:
            progress(PROGRESS_EVERY)
    if progress is not None and steps % PROGRESS_EVERY:
        progress(steps % PROGRESS_EVERY)
    wall = _time.perf_counter() - t0
    times = rec * timestep
    pos = start[None] + qpos.reshape(rec.size, n, 2) / unit
    ev = _decode(np.concatenate(ev_codes) if ev_codes else np.empty(0, np.int64),
                 (np.concatenate(ev_steps) if ev_steps else np.empty(0)) * timestep, n, base)
    run = MujocoRun(problem=problem, timestep=float(timestep), unit=float(unit), times=times, positions=pos,
                    energy=energy, in_contact=in_contact, events=ev, final_positions=np.empty((n, 2)),
                    wall_time=wall, n_steps=steps, stride=stride)
    object.__setattr__(run, "final_positions", run.at(t_end))
    return run


def _codes(a: np.ndarray, b: np.ndarray, n: int, base: int) -> np.ndarray:
    """Sorted unique event codes of contacts between owners a and b (``_owners``): disk pair
    (i < j): i * base + j; disk i and wall w: i * base + n + w; contacts of no disk dropped."""
    keep = (a != -100) & (b != -100)
    a, b = a[keep], b[keep]
    swap = a < 0
    a, b = np.where(swap, b, a), np.where(swap, a, b)
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    code = np.where(b >= 0, lo * base + hi, a * base + n + (-1 - b))
    return np.unique(code)


def _decode(codes: np.ndarray, times: np.ndarray, n: int, base: int) -> np.ndarray:
    """Event codes and times -> EVENT_DTYPE array, sorted by (time, kind, i, j)."""
    ev = np.empty(codes.size, EVENT_DTYPE)
    i, jj = np.divmod(codes, base)
    wall = jj >= n
    ev["time"] = times
    ev["kind"] = np.where(wall, EVENT_WALL, EVENT_DISK)
    ev["i"] = i
    ev["j"] = np.where(wall, jj - n, jj)
    return ev[np.lexsort((ev["j"], ev["i"], ev["kind"], ev["time"]))]


def _run_aligned(problem, model, data, owner, timestep, unit, t_end, max_steps, *, progress=None,
                 stride: int = 1) -> MujocoRun:
    """``run_mujoco`` with ``step_aligned``: a record after every accepted step and micro-step
    (every ``stride``-th of them when there are many disks, and always the last)."""
    n = problem.n
    mass2 = np.repeat(np.asarray(problem.mass, dtype=float), 2) / (unit * unit)
    rec_t, rec_q, rec_e = [float(data.time)], [data.qpos.copy()], [0.5 * np.dot(mass2, data.qvel * data.qvel)]
    events = []
    calls: list = [0, 0.0]  # on_step calls, simulated time reported to progress

    def on_step(d):
        calls[0] += 1
        if calls[0] % stride == 0:
            rec_t.append(float(d.time))
            rec_q.append(d.qpos.copy())
            rec_e.append(0.5 * np.dot(mass2, d.qvel * d.qvel))
        if progress is not None and d.time - calls[1] >= PROGRESS_EVERY * timestep:
            k = int((d.time - calls[1]) / timestep)
            calls[1] += k * timestep
            progress(k)

    def on_event(t, g1, g2, u):
        key = _event(owner, g1, g2)
        if key is not None:
            events.append((t, *key))

    stats = step_aligned(model, data, t_end, on_event=on_event, on_step=on_step, max_steps=max_steps)
    if rec_t[-1] != float(data.time):
        rec_t.append(float(data.time))
        rec_q.append(data.qpos.copy())
        rec_e.append(0.5 * np.dot(mass2, data.qvel * data.qvel))
    if progress is not None:
        progress(max(0, steps_needed(t_end, timestep) - int(round(calls[1] / timestep))))
    times = np.array(rec_t)
    k = times.size
    q = np.array(rec_q)
    del rec_q[:]
    pos = np.asarray(problem.start, dtype=float)[None] + q.reshape(k, n, 2) / unit
    del q
    energy = np.array(rec_e)
    ev = np.array(sorted(events), dtype=EVENT_DTYPE) if events else np.empty(0, EVENT_DTYPE)
    run = MujocoRun(problem=problem, timestep=timestep, unit=unit, times=times, positions=pos, energy=energy,
                    in_contact=np.zeros(k, dtype=bool), events=ev, final_positions=np.empty((n, 2)),
                    wall_time=stats.wall_time, stepping="aligned", stats=stats.to_dict(),
                    n_steps=calls[0], stride=stride)
    object.__setattr__(run, "final_positions", run.at(t_end))
    return run


def run_final(problem: Problem, velocities, *, timestep: float, unit: float = DEFAULT_UNIT,
              t_end: float | None = None, max_steps: int = MAX_STEPS,
              progress=None) -> tuple[np.ndarray, int, float]:
    """Fixed steps of ``timestep`` to ``t_end`` (default t_final), keeping nothing per step:
    (final positions (N, 2) units, linear between the two steps around t_end as ``run_mujoco``;
    steps; wall time s). The scene is built for this timestep (k = 2 / h^2 follows h).
    progress: None or progress(k) after each batch of steps (``mj_step(..., nstep)`` in batches
    of 10 x :data:`PROGRESS_EVERY`)."""
    import time as _time

    import mujoco

    t_end = float(problem.t_final if t_end is None else t_end)
    steps = check_steps(t_end, timestep, max_steps)
    v = np.asarray(velocities, dtype=float)
    model, data = _scene_at_start(problem, v, timestep, unit)
    start = np.asarray(problem.start, dtype=float)
    t0 = _time.perf_counter()
    done, batch = 0, 10 * PROGRESS_EVERY if progress is not None else max(steps - 1, 1)
    while done < steps - 1:
        k = min(batch, steps - 1 - done)
        mujoco.mj_step(model, data, nstep=k)
        done += k
        if progress is not None:
            progress(k)
    before = data.qpos.copy()
    if steps:
        mujoco.mj_step(model, data)
        if progress is not None:
            progress(1)
    wall = _time.perf_counter() - t0
    f = min(max(t_end / timestep - (steps - 1), 0.0), 1.0) if steps else 0.0
    q = before * (1 - f) + data.qpos * f
    return start + q.reshape(problem.n, 2) / unit, steps, wall


def rollout(problem: Problem, velocities, times, *, timestep: float = DEFAULT_TIMESTEP,
            unit: float = DEFAULT_UNIT, max_steps: int = MAX_STEPS) -> np.ndarray:
    """Disk centres under MuJoCo at the requested times: (T, N, 2), problem units.

    velocities : (N, 2) float, units/s
    times      : (T,) s, sorted, in [0, t_final]; positions are linear between MuJoCo steps
    """
    ts = np.asarray(times, dtype=float).reshape(-1)
    if ts.size and (np.any(np.diff(ts) < 0) or ts[0] < 0 or ts[-1] > problem.t_final * (1 + 1e-12)):
        raise InputError(f"times must be sorted and lie in [0, t_final = {problem.t_final:g}]")
    t_end = float(ts[-1]) if ts.size else 0.0
    run = run_mujoco(problem, velocities, timestep=timestep, unit=unit, t_end=t_end, max_steps=max_steps)
    return run.at(ts)
