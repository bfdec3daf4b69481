"""The landing aim of two bodies that must hit each other in mid-air, then each rest in its own
region (``nbst.scene.search``'s pair aim): a model of the two flights and their touch, solved for
the two launch velocities.

The model (no MuJoCo in the loop; every aim is then rolled out and judged):

* before the touch both fly ballistically under the same gravity, so their separation moves in a
  straight line: the touch is the first time it equals the two bounding radii' sum (a quadratic);
* the touch is an impulse along the line of centres, frictionless, with the pair's coefficient of
  restitution ``e`` (:func:`restitution`: measured once under MuJoCo, head on, from the model's own
  contact settings: solref, solimp, margins) and their masses (the bodies' subtree masses);
* after it each flies ballistically to where it falls through its region's height (the later root:
  from above).

:func:`land_pair` solves it for both launch velocities by bounded least squares (scipy's
``least_squares``, the controls' ranges as bounds), from a meeting aim: residuals are the two
landing points' horizontal misses of their targets, the gap by which they miss each other (no
touch: the separation's least value less the radii), and how far the touch lies below both
targets' heights plus a diameter (a touch that low would not fall in from above). Measured on a user's
scene (two bouncy balls, e = 0.73, that meet and fall into two boxes): 10 of 10 seeds met within
3,000 rollouts, against 2 of 10 with the meeting aim alone (docs/results/scene.md).

Pure numpy and scipy, but for :func:`restitution` (and the model's radii, read in :func:`pair_of`).
"""
from __future__ import annotations

import copy
from dataclasses import dataclass
from typing import Any

import numpy as np

from nbst.scene.scenefile import body_radius

__all__ = ["Pair", "RESTITUTION_GAP", "RESTITUTION_SPEED", "pair_of", "restitution", "pair_touch", "pair_flights",
           "land_pair"]

#: Each body's speed (m/s) in the head-on test that measures the pair's restitution, and the gap
#: (m) between them at its start. Two bouncy balls (solref 0.02 0.1, 1 ms steps) measure 0.7262 to
#: 0.7317 from 0.5 to 4 m/s at gaps of 5 and 20 cm; from 1 cm apart, 0.80 (the first steps of a
#: contact that begins within a few steps of the start differ), hence the 20 cm.
RESTITUTION_SPEED, RESTITUTION_GAP = 1.0, 0.2
#: Weights of the least squares' residuals: a missed touch and a touch too low (per metre), against
#: the landing misses (1 per metre).
MISS_WEIGHT, LOW_WEIGHT = 10.0, 10.0
#: The most residual evaluations of one landing aim.
LAND_EVALS = 200


@dataclass(frozen=True)
class Pair:
    """Two bodies that must hit each other: start origins (m), bounding radii about them (m),
    masses (kg), restitution of their touch, the model's gravity (m/s^2), and the time (s) within
    which they must touch (the scene's duration)."""

    oi: np.ndarray
    oj: np.ndarray
    ri: float
    rj: float
    mi: float
    mj: float
    e: float
    gravity: np.ndarray
    horizon: float = np.inf


def restitution(model: Any, bi: int, bj: int) -> float:
    """The coefficient of restitution of bodies ``bi`` and ``bj`` (each with a free joint), measured:
    in a copy of ``model`` without gravity and with every other geom's collisions off, the two are
    set :data:`RESTITUTION_GAP` apart on a line far from everything and sent at each other at
    :data:`RESTITUTION_SPEED` each; the ratio of their parting speed to their closing speed, in [0, 1]
    (0: the model keeps them from touching)."""
    import mujoco

    m = copy.deepcopy(model)
    m.opt.gravity[:] = 0.0
    mine = np.isin(m.geom_bodyid, [bi, bj])
    m.geom_contype[~mine] = 0
    m.geom_conaffinity[~mine] = 0
    d = mujoco.MjData(m)
    gap = body_radius(m, bi) + body_radius(m, bj) + RESTITUTION_GAP
    for b, x, v in ((bi, 0.0, RESTITUTION_SPEED), (bj, gap, -RESTITUTION_SPEED)):
        jq, jv = int(m.jnt_qposadr[m.body_jntadr[b]]), int(m.jnt_dofadr[m.body_jntadr[b]])
        d.qpos[jq:jq + 7] = [x, 0.0, 1e3, 1.0, 0.0, 0.0, 0.0]
        d.qvel[jv:jv + 6] = [v, 0.0, 0.0, 0.0, 0.0, 0.0]
    va, vb = int(m.jnt_dofadr[m.body_jntadr[bi]]), int(m.jnt_dofadr[m.body_jntadr[bj]])
    for _ in range(int(np.ceil((RESTITUTION_GAP / (2 * RESTITUTION_SPEED) + 0.3) / m.opt.timestep))):
        mujoco.mj_step(m, d)
    return float(np.clip((d.qvel[vb] - d.qvel[va]) / (2 * RESTITUTION_SPEED), 0.0, 1.0))


def pair_of(model: Any, bi: int, bj: int, oi: np.ndarray, oj: np.ndarray, horizon: float = np.inf) -> Pair:
    """The :class:`Pair` of bodies ``bi`` and ``bj`` of ``model`` starting at origins ``oi``, ``oj``,
    to touch within ``horizon`` s."""
    return Pair(np.asarray(oi, float), np.asarray(oj, float), body_radius(model, bi), body_radius(model, bj),
                float(model.body_subtreemass[bi]), float(model.body_subtreemass[bj]), restitution(model, bi, bj),
                np.array(model.opt.gravity, dtype=float), float(horizon))


def pair_touch(p: Pair, vi0: np.ndarray, vj0: np.ndarray) -> tuple[float | None, np.ndarray, np.ndarray,
                                                                   np.ndarray, np.ndarray, float]:
    """The two launched at ``vi0`` and ``vj0`` (m/s), to their touch, under the model above.

    Returns:
        (the touch's time or None, each origin there, each velocity just after it, the gap (m) by
        which they miss each other: 0 when they touch); without a touch, the starts, the launch
        velocities and that gap.
    """
    g = p.gravity
    d0, dv = p.oj - p.oi, vj0 - vi0
    R = p.ri + p.rj
    a, b, c = float(dv @ dv), float(2 * d0 @ dv), float(d0 @ d0 - R * R)
    disc = b * b - 4 * a * c
    t = (-b - np.sqrt(disc)) / (2 * a) if a > 1e-12 and disc >= 0 else -1.0
    if not 0 < t <= p.horizon:   # no touch (or only after the scene ends): the least gap within it
        tc = min(max(0.0, -b / (2 * a)), p.horizon) if a > 1e-12 else 0.0
        return None, p.oi, p.oj, vi0, vj0, max(0.0, float(np.linalg.norm(d0 + dv * tc)) - R)
    ci, cj = p.oi + vi0 * t + 0.5 * g * t * t, p.oj + vj0 * t + 0.5 * g * t * t
    n = (cj - ci) / np.linalg.norm(cj - ci)
    vi, vj = vi0 + g * t, vj0 + g * t
    J = (1 + p.e) * max(float((vi - vj) @ n), 0.0) / (1 / p.mi + 1 / p.mj)
    return float(t), ci, cj, vi - J / p.mi * n, vj + J / p.mj * n, 0.0


def pair_flights(p: Pair, vi0: np.ndarray, vj0: np.ndarray, heights: tuple[float, float]
                 ) -> tuple[np.ndarray, np.ndarray, float, float | None]:
    """Where the two land, launched at ``vi0`` and ``vj0`` (m/s), under the model above.

    Returns:
        (landing point of i, of j, the gap (m) by which they miss each other (0 when they touch),
        the lower of the two origins' heights at the touch or None): a landing point is where the
        body's origin falls through its height in ``heights`` after the touch (or without one); a
        body that never comes down to it lands at its flight's apex.
    """
    g = p.gravity
    t, ci, cj, ui, uj, miss = pair_touch(p, vi0, vj0)
    lands = []
    for c0, u, z in ((ci, ui, heights[0]), (cj, uj, heights[1])):
        A, B, C = 0.5 * g[2], float(u[2]), float(c0[2] - z)
        disc = B * B - 4 * A * C
        tl = (-B - np.sqrt(disc)) / (2 * A) if A < 0 and disc >= 0 else (-B / (2 * A) if A < 0 else 0.0)
        lands.append(c0 + u * tl + 0.5 * g * tl * tl)
    return lands[0], lands[1], miss, (None if t is None else float(min(ci[2], cj[2])))


def land_pair(p: Pair, vi0: np.ndarray, vj0: np.ndarray, targets: tuple[np.ndarray, np.ndarray],
              lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Launch velocities (6,: i's then j's) that land each body on its target, from ``vi0``, ``vj0``
    (a meeting aim), by bounded least squares (the module docstring).

    Args:
        p: the pair.
        vi0, vj0: (3,) the starting launch velocities.
        targets: each body's landing target (its region's point; its z the height landed at).
        lo, hi: (6,) the two linvel ranges.
    """
    from scipy.optimize import least_squares

    heights = (float(targets[0][2]), float(targets[1][2]))
    top = max(heights) + 2 * max(p.ri, p.rj)   # the touch's lowest origin must be above both targets by a diameter

    def residuals(x: np.ndarray) -> np.ndarray:
        li, lj, miss, at = pair_flights(p, x[:3], x[3:], heights)
        low = 0.0 if at is None else max(0.0, top - at)
        return np.array([*(li[:2] - targets[0][:2]), *(lj[:2] - targets[1][:2]), MISS_WEIGHT * miss, LOW_WEIGHT * low])

    span = np.maximum(hi - lo, 1e-12)
    x0 = np.clip(np.concatenate([vi0, vj0]), lo + 1e-9 * span, hi - 1e-9 * span)
    return np.asarray(least_squares(residuals, x0, bounds=(lo, hi), max_nfev=LAND_EVALS).x)
