"""Planted instances: problems whose zero-cost solution is known.

Random non-overlapping starts and random cue velocities; each noncueable disk is
the aim of a strike by a cueable disk (``nbst.search.aim.strike_velocity``, towards a
random point of the box); the motion is simulated exactly and each disk's target
is where it ends. So the velocities used are a solution of cost 0 (up to the
round-off of writing the targets), and a search has a ground truth.
"""
from __future__ import annotations

import numpy as np

from nbst.problem import Problem, problem_from_dict
from nbst.search.aim import strike_velocity
from nbst.sim import simulate

#: Extra gap between starts (units) so that planted starts are not in contact.
START_GAP = 2.0
#: Cue speeds are uniform in this fraction range of the box diagonal per t_final.
SPEED_RANGE = (0.05, 0.35)
#: Tries to place the disks / to find a strike from the right side.
PLACE_TRIES = 20_000
STRIKE_TRIES = 64


def planted(n: int, *, noncue: int = 0, radius: float = 15.0, seed: int, box=(800.0, 800.0), t_final: float = 5.0,
            target_radius: float = 75.0, name: str | None = None) -> tuple[Problem, np.ndarray]:
    """A random problem with n disks (the last ``noncue`` noncueable) and its zero-cost velocities.

    Raises ValueError when the request cannot be met (no cueable disk, disks do not fit).
    """
    if n < 1:
        raise ValueError("--planted needs at least 1 disk")
    if not 0 <= noncue < n:
        raise ValueError(f"--noncue must be between 0 and {n - 1} (at least one disk must be cueable)")
    if radius <= 0 or 2 * radius >= min(box):
        raise ValueError(f"--radius must be > 0 and fit the {box[0]:g} x {box[1]:g} box")
    rng = np.random.default_rng(seed)
    W, H = box
    r = float(radius)
    starts = np.empty((n, 2))
    placed = 0
    for _ in range(PLACE_TRIES):
        c = rng.uniform([r, r], [W - r, H - r])
        if placed == 0 or np.min(np.hypot(*(starts[:placed] - c).T)) >= 2 * r + START_GAP:
            starts[placed] = c
            placed += 1
            if placed == n:
                break
    if placed < n:
        raise ValueError(f"could not place {n} disks of radius {r:g} in the {W:g} x {H:g} box; use a smaller --radius")
    cue = np.arange(n) < n - noncue
    diag = float(np.hypot(W, H))
    ang = rng.uniform(0, 2 * np.pi, n)
    speed = rng.uniform(*SPEED_RANGE, n) * diag / t_final
    v = np.stack([np.cos(ang), np.sin(ang)], axis=1) * speed[:, None]
    v[~cue] = 0.0
    # each noncueable disk is struck by a cueable one, towards a random point
    cue_idx = np.flatnonzero(cue)
    mass = np.ones(n)
    out = np.empty(2)
    for m, s in enumerate(np.flatnonzero(~cue)):
        c = cue_idx[m % cue_idx.size]
        for _ in range(STRIKE_TRIES):
            T = rng.uniform([r, r], [W - r, H - r])
            if strike_velocity(starts[c], r, mass[c], starts[s], r, mass[s], T, t_final, out) > 0:
                v[c] = out
                break
    d = {
        "name": name or f"planted-n{n}-k{noncue}-s{seed}",
        "description": f"Planted instance: {n} disks (r={r:g}), {noncue} noncueable; a zero-cost solution exists "
                       f"(nbst generate --planted {n} --noncue {noncue} --radius {r:g} --seed {seed}).",
        "box": [float(W), float(H)],
        "t_final": float(t_final),
        "target_radius": float(target_radius),
        "disks": [{"start": starts[i].tolist(), "target": starts[i].tolist(), "radius": r, "cueable": bool(cue[i])}
                  for i in range(n)],
    }
    tr = simulate(problem_from_dict(d), v)
    final = np.clip(tr.final_positions, r, np.array([W - r, H - r]))  # round-off at a wall
    for i in range(n):
        d["disks"][i]["target"] = final[i].tolist()
    d["planted"] = {"velocities": v.tolist(), "seed": int(seed), "disk_disk_collisions": tr.n_disk_disk,
                    "wall_bounces": tr.n_wall,
                    "struck_noncueable": int(sum(1 for s in np.flatnonzero(~cue)
                                                 if np.any(tr.final_positions[s] != starts[s])))}
    return problem_from_dict(d, source=d["name"]), v
