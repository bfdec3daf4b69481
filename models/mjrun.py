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

from nbst.problem import Problem

from nbst.models.scene import DEFAULT_TIMESTEP, DEFAULT_UNIT, build_model

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
    """The step count, or ValueError (one line: why, and ``hint``: what changes it) above ``max_steps``."""
    steps = steps_needed(t_end, timestep)
    if steps > max_steps:
        raise ValueError(f"t = {t_end:g} s at timestep {timestep:g} s is {steps:,} MuJoCo steps, over the limit "
                         f"of {max_steps:,} (each step's state is kept); {hint}")
    return steps


@dataclass(frozen=True, eq=False)
class MujocoRun:
    """One MuJoCo run of a scene, in problem units.

    times     : (S+1,) s, 0 then after each step
    positions : (S+1, N, 2) disk centres, units
    energy    : (S+1,) kinetic energy, mass units x units^2/s^2
    in_contact: (S+1,) bool, any contact active in the step that ended there
    events    : structured (E,): time (s: fixed stepping: the first step state in which the pair
                overlaps; MuJoCo detects it there and resolves it during the next step; aligned
                stepping: the touch, located to ~1e-13 s), kind, i, j (i < j for disk pairs)
    final_positions : (N, 2) at t_final (linear between the two steps around it)
    stepping  : "fixed" (times = k h) or "aligned" (times: every accepted step and micro-step)
    stats     : aligned stepping's cost (``AlignedStats.to_dict()``), None for fixed
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

    @property
    def steps(self) -> int:
        return int(self.times.size - 1)

    def at(self, t):
        """Positions at time(s) t in [0, t_final], linear between steps: (N, 2) or (T, N, 2)."""
        ts = np.asarray(t, dtype=float)
        if self.stepping != "fixed":  # records at uneven times
            k = np.clip(np.searchsorted(self.times, ts, side="right") - 1, 0, max(self.steps - 1, 0))
            k1 = np.minimum(k + 1, self.steps)
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
    for i in range(n):
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
               t_end: float | None = None, max_steps: int = MAX_STEPS, stepping: str = "fixed") -> MujocoRun:
    """Step the problem's scene from keyframe ``initial`` to ``t_end`` (default t_final).

    velocities : (N, 2) float, units/s
    max_steps  : ValueError, before any work, if reaching t_end takes more steps (``check_steps``);
                 aligned stepping: RuntimeError past max_steps accepted steps + micro-steps
    stepping   : "fixed" or "aligned" (module docstring)
    """
    import time as _time

    if stepping not in STEPPINGS:
        raise ValueError(f"stepping must be one of {', '.join(STEPPINGS)}, got {stepping!r}")
    t_end = float(problem.t_final if t_end is None else t_end)
    steps = check_steps(t_end, timestep, max_steps)

    import mujoco

    v = np.asarray(velocities, dtype=float)
    model, data = _scene_at_start(problem, v, timestep, unit)
    n = problem.n
    owner = _owners(model, n)
    if stepping == "aligned":
        return _run_aligned(problem, model, data, owner, float(timestep), float(unit), t_end, max_steps)
    mass = np.asarray(problem.mass, dtype=float)
    start = np.asarray(problem.start, dtype=float)

    qpos = np.empty((steps + 1, 2 * n))
    qvel = np.empty((steps + 1, 2 * n))
    in_contact = np.zeros(steps + 1, dtype=bool)
    qpos[0] = data.qpos
    qvel[0] = data.qvel
    active: set = set()
    events = []
    step = mujoco.mj_step
    t0 = _time.perf_counter()
    for s in range(1, steps + 1):
        step(model, data)
        qpos[s] = data.qpos
        qvel[s] = data.qvel
        nc = data.ncon
        if nc or active:
            now = set()
            if nc:
                in_contact[s] = True
                geoms = data.contact.geom[:nc]  # a fresh view: the contact list is rebuilt every step
                for g1, g2 in geoms:
                    key = _event(owner, g1, g2)
                    if key is not None:
                        now.add(key)
            for key in now - active:
                events.append(((s - 1) * timestep, *key))
            active = now
    wall = _time.perf_counter() - t0
    times = np.arange(steps + 1) * timestep
    pos = start[None] + qpos.reshape(steps + 1, n, 2) / unit
    vel = qvel.reshape(steps + 1, n, 2) / unit
    energy = 0.5 * np.einsum("i,sij,sij->s", mass, vel, vel)
    ev = np.array(sorted(events), dtype=EVENT_DTYPE) if events else np.empty(0, EVENT_DTYPE)
    run = MujocoRun(problem=problem, timestep=float(timestep), unit=float(unit), times=times, positions=pos,
                    energy=energy, in_contact=in_contact, events=ev, final_positions=np.empty((n, 2)),
                    wall_time=wall)
    object.__setattr__(run, "final_positions", run.at(t_end))
    return run


def _run_aligned(problem, model, data, owner, timestep, unit, t_end, max_steps) -> MujocoRun:
    """``run_mujoco`` with ``step_aligned``: a record after every accepted step and micro-step."""
    from nbst.models.stepping import step_aligned

    n = problem.n
    rec_t, rec_q, rec_v = [float(data.time)], [data.qpos.copy()], [data.qvel.copy()]
    events = []

    def on_step(d):
        rec_t.append(float(d.time))
        rec_q.append(d.qpos.copy())
        rec_v.append(d.qvel.copy())

    def on_event(t, g1, g2, u):
        key = _event(owner, g1, g2)
        if key is not None:
            events.append((t, *key))

    stats = step_aligned(model, data, t_end, on_event=on_event, on_step=on_step, max_steps=max_steps)
    times = np.array(rec_t)
    k = times.size
    pos = np.asarray(problem.start, dtype=float)[None] + np.array(rec_q).reshape(k, n, 2) / unit
    vel = np.array(rec_v).reshape(k, n, 2) / unit
    energy = 0.5 * np.einsum("i,sij,sij->s", np.asarray(problem.mass, dtype=float), vel, vel)
    ev = np.array(sorted(events), dtype=EVENT_DTYPE) if events else np.empty(0, EVENT_DTYPE)
    run = MujocoRun(problem=problem, timestep=timestep, unit=unit, times=times, positions=pos, energy=energy,
                    in_contact=np.zeros(k, dtype=bool), events=ev, final_positions=np.empty((n, 2)),
                    wall_time=stats.wall_time, stepping="aligned", stats=stats.to_dict())
    object.__setattr__(run, "final_positions", run.at(t_end))
    return run


def run_final(problem: Problem, velocities, *, timestep: float, unit: float = DEFAULT_UNIT,
              t_end: float | None = None, max_steps: int = MAX_STEPS) -> tuple[np.ndarray, int, float]:
    """Fixed steps of ``timestep`` to ``t_end`` (default t_final), keeping nothing per step:
    (final positions (N, 2) units, linear between the two steps around t_end as ``run_mujoco``;
    steps; wall time s). The scene is built for this timestep (k = 2 / h^2 follows h)."""
    import time as _time

    import mujoco

    t_end = float(problem.t_final if t_end is None else t_end)
    steps = check_steps(t_end, timestep, max_steps)
    v = np.asarray(velocities, dtype=float)
    model, data = _scene_at_start(problem, v, timestep, unit)
    start = np.asarray(problem.start, dtype=float)
    t0 = _time.perf_counter()
    if steps > 1:
        mujoco.mj_step(model, data, nstep=steps - 1)
    before = data.qpos.copy()
    if steps:
        mujoco.mj_step(model, data)
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
        raise ValueError(f"times must be sorted and lie in [0, t_final = {problem.t_final:g}]")
    t_end = float(ts[-1]) if ts.size else 0.0
    run = run_mujoco(problem, velocities, timestep=timestep, unit=unit, t_end=t_end, max_steps=max_steps)
    return run.at(ts)
