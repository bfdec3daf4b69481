"""Many-disk test motions of any size for checks and benchmarks: :func:`gas_motion`.

A gas at fixed density: exact solutions (cost 0) with real collisions and wall bounces, so that
validation, stepping and their benchmarks can be measured over N (docs/mujoco.md, "Many disks").
"""
from __future__ import annotations

import numpy as np

from nbst.errors import InputError
from nbst.problem import problem_from_dict

__all__ = ["GAS_AREA_FRACTION", "GAS_RADIUS", "GAS_SPEED", "GAS_T_FINAL", "gas_motion"]

#: Scale motions (:func:`gas_motion`): area fraction of the disks, radius (units), speeds
#: (units/s) and duration (s). At this density a disk's mean free path is pi r / (2 phi) ~ 200
#: units, about one collision per disk per second at the speeds drawn, plus wall bounces near
#: the walls, at every N (the box grows as sqrt(N)).
GAS_AREA_FRACTION = 0.08
GAS_RADIUS = 10.0
GAS_SPEED = (100.0, 250.0)
GAS_T_FINAL = 2.0


def gas_motion(n: int, *, seed: int = 1, t_final: float = GAS_T_FINAL, fraction: float = GAS_AREA_FRACTION):
    """A many-disk motion for checks and benchmarks at any N: (problem, velocities).

    N disks of radius :data:`GAS_RADIUS` start at the centres of a square grid in a square box
    sized so that they cover ``fraction`` of its area (fixed density: the box grows as sqrt(N)),
    with velocities of random direction and speed in :data:`GAS_SPEED` (seeded). Each target is
    where the exact simulator takes its disk at t_final, so the motion is an exact solution
    (cost 0) with real collisions and wall bounces; target radius 2r. ``seed`` defaults to 1 on
    purpose: a benchmark fixture is the same motion on every run (``gas_motion(N)`` names it).
    """
    from nbst.sim import simulate

    n = int(n)
    if n < 1:
        raise InputError(f"n must be >= 1, got {n}")
    r = GAS_RADIUS
    side = float(np.sqrt(n * np.pi * r * r / fraction))
    k = int(np.ceil(np.sqrt(n)))
    pitch = side / k
    if pitch < 2 * r * (1 + 1e-9):
        raise InputError(f"fraction {fraction:g} is too dense for a square grid")
    ij = np.array([(a, b) for a in range(k) for b in range(k)][:n], dtype=float)
    start = (ij + 0.5) * pitch
    rng = np.random.default_rng(seed)
    ang = rng.uniform(0.0, 2 * np.pi, n)
    speed = rng.uniform(*GAS_SPEED, n)
    v = np.stack([speed * np.cos(ang), speed * np.sin(ang)], axis=1)
    disks = [{"start": s.tolist(), "target": s.tolist(), "radius": r} for s in start]
    d = {"name": f"gas-{n}-s{seed}", "description": f"{n} disks, area fraction {fraction:g}, seed {seed} "
         f"(nbst.models.gas.gas_motion)", "box": [side, side], "t_final": float(t_final),
         "target_radius": 2 * r, "disks": disks}
    final = simulate(problem_from_dict(d), v).final_positions
    for disk, f in zip(disks, final):
        disk["target"] = [float(f[0]), float(f[1])]
    return problem_from_dict(d), v
