"""The default camera of a scene video: what it frames and from where.

:func:`focus_points` gathers what must be in the picture (the moving bodies' paths, their regions,
what they must hit); :func:`default_camera` looks at it from :data:`AZIMUTH` and :data:`ELEVATION`
and fits it into the part of the frame the readout leaves (an off-axis frustum).

Compute only (numpy; MuJoCo's names).
"""
from __future__ import annotations

import math
from typing import Any

import numpy as np

from nbst.render.core.camera import look_at, perspective
from nbst.render.core import geoms as sg
from nbst.render.scene.motion import SceneMotion
from nbst.scene.fates import Fates

__all__ = ["AZIMUTH", "DISTANCE", "ELEVATION", "FILL", "FOV", "focus_points", "default_camera", "regions_of"]

#: The framing camera looks at the bodies from this azimuth (degrees from +x, about +z; -90: from
#: -y, the front) and elevation (degrees above the horizon), with this vertical field of view.
AZIMUTH, ELEVATION, FOV = -70.0, 35.0, 40.0
#: ... from this many times the framed points' extent (a longer lens: the near side of a table does
#: not dwarf the dice on the floor beside it) ...
DISTANCE = 2.5
#: ... as near as it can with every corner of the framed box within this share of the frame.
FILL = 0.8

_CUBE = np.array([[(-1.0, 1.0)[(k >> i) & 1] for i in range(3)] for k in range(8)])


def focus_points(motion: SceneMotion, fates: Fates, model: Any) -> np.ndarray:
    """(N, 3) the points the default camera frames: the controlled and fated bodies' paths (the
    corners of their geoms' bounding cubes at every frame), their regions' corners, and what their
    ``hits`` and ``never_hits`` name (planes aside), where it starts."""
    import mujoco

    bodies = {int(mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, n))
              for n in [c.body for c in fates.controls] + [f.body for f in fates.fates]}
    pts = []
    for f in fates.fates:   # what they must touch or miss (a backboard, a bell), but no plane
        for n in (*f.hits, *f.never_hits):
            b = int(mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, n))
            gs = ([g for g in range(int(model.ngeom)) if int(model.geom_bodyid[g]) == b] if b > 0
                  else [int(mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, n))])
            for g in gs:
                if g >= 0 and int(model.geom_type[g]) != sg.PLANE:
                    pts.append(motion.geom_xpos[0, g] + float(model.geom_rbound[g]) * _CUBE)
    for b in bodies:
        gs = [g for g in range(int(model.ngeom)) if int(model.geom_bodyid[g]) == b]
        r = max((float(model.geom_rbound[g]) + float(np.linalg.norm(model.geom_pos[g])) for g in gs), default=0.05)
        pts.append((motion.body_xpos[:, b, None, :] + r * _CUBE).reshape(-1, 3))
    for f in fates.fates:
        for reg in regions_of(f):
            if reg.center is not None:
                pts.append(np.asarray(reg.center) + reg.radius * _CUBE)
            else:
                lo, hi = np.asarray(reg.lo, float), np.asarray(reg.hi, float)
                pts.append((lo + hi) / 2 + (hi - lo) / 2 * _CUBE)
    return np.concatenate(pts)


def regions_of(f: Any) -> list[Any]:
    """A fate's regions: its ``rest_in``, its ``at`` regions, its ``through`` regions."""
    return ([f.rest_in] if f.rest_in is not None else []) + [r for _, r in f.at] + list(f.through)


def default_camera(points: np.ndarray, aspect: float, free: tuple[float, float, float, float]
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The camera that frames ``points`` (N, 3) from :data:`AZIMUTH` and :data:`ELEVATION`.

    It stands :data:`DISTANCE` times the points' extent from their box's centre and looks at it with a
    :data:`FOV` lens; then the picture is scaled and moved (an off-axis frustum) so that the
    points' projections fill :data:`FILL` of the ``free`` part of the frame (x0, y0, x1, y1 in
    normalised device coordinates, y down: the part the readout leaves).

    Returns:
        (eye (3,), target (3,), the (4, 4) view-projection, image row 0 at the top).
    """
    lo, hi = points.min(axis=0), points.max(axis=0)
    c = (lo + hi) / 2
    az, el = math.radians(AZIMUTH), math.radians(ELEVATION)
    d = np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])
    dist = DISTANCE * max(float(np.linalg.norm(hi - lo)), 0.05)
    eye = c + d * dist
    flip = np.diag([1.0, -1.0, 1.0, 1.0])
    vp = flip @ perspective(FOV, aspect, dist / 100, dist * 50) @ look_at(eye, c, np.array([0.0, 0.0, 1.0]))
    p = vp @ np.c_[points, np.ones(len(points))].T
    ndc = p[:2] / p[3]
    (x0, y0), (x1, y1) = ndc.min(axis=1), ndc.max(axis=1)
    fx0, fy0, fx1, fy1 = free
    sc = FILL * min((fx1 - fx0) / max(x1 - x0, 1e-9), (fy1 - fy0) / max(y1 - y0, 1e-9))
    tx, ty = (fx0 + fx1) / 2 - sc * (x0 + x1) / 2, (fy0 + fy1) / 2 - sc * (y0 + y1) / 2
    shift = np.array([[sc, 0, 0, tx], [0, sc, 0, ty], [0, 0, 1, 0], [0, 0, 0, 1.0]])
    return eye, c, shift @ vp
