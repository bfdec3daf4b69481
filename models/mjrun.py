"""Run a scene in MuJoCo: positions every step, contact events, kinetic energy; and ``rollout``.

Compute only; mujoco is imported on first call.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from nbst.problem import Problem

from .scene import DEFAULT_TIMESTEP, DEFAULT_UNIT, build_model

#: Event kinds, as in ``nbst.sim`` (0 disk-disk, 1 wall); j = partner disk or wall 0 left 1 right 2 bottom 3 top.
EVENT_DISK, EVENT_WALL = 0, 1
EVENT_DTYPE = np.dtype([("time", "f8"), ("kind", "i1"), ("i", "i4"), ("j", "i4")])
_WALLS = ("wall_left", "wall_right", "wall_bottom", "wall_top")


@dataclass(frozen=True, eq=False)
class MujocoRun:
    """One MuJoCo run of a scene, in problem units.

    times     : (S+1,) s, 0 then after each step
    positions : (S+1, N, 2) disk centres, units
    energy    : (S+1,) kinetic energy, mass units x units^2/s^2
    in_contact: (S+1,) bool, any contact active in the step that ended there
    events    : structured (E,): time (s: the first step state in which the pair overlaps; MuJoCo
                detects it there and resolves it during the next step), kind, i, j (i < j for disk pairs)
    final_positions : (N, 2) at t_final (linear between the two steps around it)
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

    @property
    def steps(self) -> int:
        return int(self.times.size - 1)

    def at(self, t):
        """Positions at time(s) t in [0, t_final], linear between steps: (N, 2) or (T, N, 2)."""
        ts = np.asarray(t, dtype=float)
        s = np.clip(ts / self.timestep, 0.0, self.steps)
        k = np.minimum(np.floor(s).astype(np.int64), self.steps - 1) if self.steps else np.zeros_like(s, int)
        f = (s - k)[..., None, None]
        return self.positions[k] * (1 - f) + self.positions[np.minimum(k + 1, self.steps)] * f


def run_mujoco(problem: Problem, velocities, *, timestep: float = DEFAULT_TIMESTEP, unit: float = DEFAULT_UNIT,
               t_end: float | None = None) -> MujocoRun:
    """Step the problem's scene from keyframe ``initial`` to ``t_end`` (default t_final).

    velocities : (N, 2) float, units/s
    """
    import time as _time

    import mujoco

    v = np.asarray(velocities, dtype=float)
    model = build_model(problem, v, timestep=timestep, unit=unit)
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, 0)
    n = problem.n
    t_end = float(problem.t_final if t_end is None else t_end)
    steps = int(math.ceil(t_end / timestep - 1e-9))
    # geom id -> ("disk", i) or ("wall", w)
    owner = np.full(model.ngeom, -100, dtype=np.int64)  # >= 0 disk index, -1-w wall w, -100 none
    for i in range(n):
        owner[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, f"disk{i}_collision")] = i
    for w, name in enumerate(_WALLS):
        owner[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, name)] = -1 - w
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
                    a, b = owner[g1], owner[g2]
                    if a == -100 or b == -100:
                        continue
                    if a < 0:
                        a, b = b, a
                    key = (int(min(a, b)), int(max(a, b))) if b >= 0 else (int(a), int(b))
                    now.add(key)
            for key in now - active:
                a, b = key
                if b >= 0:
                    events.append(((s - 1) * timestep, EVENT_DISK, a, b))
                else:
                    events.append(((s - 1) * timestep, EVENT_WALL, a, -1 - b))
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


def rollout(problem: Problem, velocities, times, *, timestep: float = DEFAULT_TIMESTEP,
            unit: float = DEFAULT_UNIT) -> np.ndarray:
    """Disk centres under MuJoCo at the requested times: (T, N, 2), problem units.

    velocities : (N, 2) float, units/s
    times      : (T,) s, sorted, in [0, t_final]; positions are linear between MuJoCo steps
    """
    ts = np.asarray(times, dtype=float).reshape(-1)
    if ts.size and (np.any(np.diff(ts) < 0) or ts[0] < 0 or ts[-1] > problem.t_final * (1 + 1e-12)):
        raise ValueError(f"times must be sorted and lie in [0, t_final = {problem.t_final:g}]")
    t_end = float(ts[-1]) if ts.size else 0.0
    run = run_mujoco(problem, velocities, timestep=timestep, unit=unit, t_end=t_end)
    return run.at(ts)
