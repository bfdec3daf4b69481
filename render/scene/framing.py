"""The default camera of a scene video: what it frames and from where.

:func:`focus_points` gathers what must be in the picture (the moving bodies' paths, their regions,
what they must hit); :func:`default_camera` looks at it from :data:`AZIMUTH` and :data:`ELEVATION`
and fits it into the part of the frame the readout leaves (an off-axis frustum).

The camera tracks (:func:`tracking_boxes`): at each frame it frames the regions and what the
bodies must hit, and the bodies where they are within :data:`TRACK_WINDOW` s of that frame,
the box smoothed over :data:`TRACK_TAU` s both ways; so the bodies stay large (two dice at rest
in their square fill the view, not a speck beside the table they fell from) and the view
glides, never jumps.

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

__all__ = ["AZIMUTH", "AZIMUTHS", "DISTANCE", "TRACK_FPS", "track_grid", "on_track_grid", "ELEVATION", "FILL", "FOV", "TRACK_TAU", "TRACK_WINDOW", "box_corners",
           "focus_points", "geom_box_points", "default_camera", "hidden_count", "clear_azimuth", "regions_of",
           "tracking_boxes"]

#: The framing camera looks at the bodies from this azimuth (degrees from +x, about +z; -90: from
#: -y, the front) and elevation (degrees above the horizon), with this vertical field of view.
AZIMUTH, ELEVATION, FOV = -70.0, 35.0, 40.0
#: The azimuths the tracking camera may look from, the first preferred: it takes the first from
#: which the fewest of the fated bodies and their touches hide behind other geoms
#: (:func:`clear_azimuth`: a door's far side hid the knob a ball hit).
AZIMUTHS = (AZIMUTH, -110.0, -30.0, -150.0, 10.0, 170.0, 50.0, 130.0)
#: ... from this many times the framed points' extent (a longer lens: the near side of a table does
#: not dwarf the dice on the floor beside it) ...
DISTANCE = 2.5
#: ... as near as it can with every corner of the framed box within this share of the frame.
FILL = 0.8

#: The tracking camera frames the bodies within this many seconds of the frame, its box smoothed
#: with this time constant (s), forwards and backwards.
TRACK_WINDOW, TRACK_TAU = 0.35, 0.25

#: The tracking camera's own clock: its boxes are worked out on the frames of this many per second
#: of motion (:func:`on_track_grid`), whatever the video's fps, and read between them linearly, so a
#: still at t is the video's frame at t.
TRACK_FPS = 30.0

_CUBE = np.array([[(-1.0, 1.0)[(k >> i) & 1] for i in range(3)] for k in range(8)])


def _fixed_and_bodies(motion: SceneMotion, fates: Fates, model: Any) -> tuple[np.ndarray, list[tuple[int, float]]]:
    """(the fixed points: regions' corners and what the bodies must touch or miss, (N, 3); the
    framed bodies as (body id, the radius of a cube about its origin holding its geoms))."""
    pts = focus_points(motion, fates, model, bodies=False)
    import mujoco

    bodies = {int(mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, n))
              for n in [c.body for c in fates.controls] + [f.body for f in fates.fates]}
    out = []
    for b in sorted(bodies):
        gs = [g for g in range(int(model.ngeom)) if int(model.geom_bodyid[g]) == b]
        out.append((b, max((float(model.geom_rbound[g]) + float(np.linalg.norm(model.geom_pos[g])) for g in gs),
                           default=0.05)))
    return pts, out


def track_grid(duration: float) -> np.ndarray:
    """The times of the frames the framing is worked out on (:data:`TRACK_FPS`)."""
    from nbst.render.core.times import frame_times

    return frame_times(duration, TRACK_FPS)


def on_track_grid(motion: SceneMotion) -> SceneMotion:
    """``motion``'s frames nearest the :func:`track_grid` times (recorded exactly by the renderer)."""
    from dataclasses import replace

    idx = np.unique([motion.index(t) for t in track_grid(motion.duration)])
    segs = None if motion.tendon_segs is None else motion.tendon_segs[idx]
    return replace(motion, times=motion.times[idx], geom_xpos=motion.geom_xpos[idx], geom_xmat=motion.geom_xmat[idx],
                   body_xpos=motion.body_xpos[idx], body_xmat=motion.body_xmat[idx], cam_xpos=motion.cam_xpos[idx],
                   cam_xmat=motion.cam_xmat[idx], tendon_segs=segs)


def tracking_boxes(motion: SceneMotion, fates: Fates, model: Any) -> tuple[np.ndarray, np.ndarray]:
    """(lo (F, 3), hi (F, 3)): the box the tracking camera frames at each recorded frame: the fixed
    points (regions, what must be touched) and the bodies within TRACK_WINDOW s, smoothed over
    TRACK_TAU s forwards and backwards (never a jump)."""
    fixed, bodies = _fixed_and_bodies(motion, fates, model)
    t = np.asarray(motion.times, float)
    F = len(t)
    lo = np.empty((F, 3))
    hi = np.empty((F, 3))
    for k in range(F):
        sel = np.abs(t - t[k]) <= TRACK_WINDOW + 1e-12
        parts = [fixed] if len(fixed) else []
        for b, r in bodies:
            p = motion.body_xpos[sel, b]
            parts.append(np.concatenate([p.min(axis=0) - r, p.max(axis=0) + r])[None].reshape(2, 3))
        allp = np.concatenate(parts)
        lo[k], hi[k] = allp.min(axis=0), allp.max(axis=0)
    a = 1.0 - np.exp(-np.diff(t) / TRACK_TAU) if F > 1 else np.zeros(0)
    for arr in (lo, hi):
        for k in range(1, F):                      # forwards
            arr[k] = arr[k - 1] + a[k - 1] * (arr[k] - arr[k - 1])
        for k in range(F - 2, -1, -1):             # and backwards: no lag
            arr[k] = arr[k + 1] + a[k] * (arr[k] - arr[k + 1])
    return lo, hi


def geom_box_points(motion: SceneMotion, model: Any, g: int, frame: int = 0) -> np.ndarray:
    """(8, 3) the corners of geom ``g``'s own bounding box (MuJoCo's ``geom_aabb``, in the geom's frame)
    at ``frame``: tight about a long thin geom (a wall 2 m long and 10 cm thick), where the cube of its
    bounding sphere's radius would frame 2 m of empty air on each side of it."""
    aabb = np.asarray(model.geom_aabb[g], float)
    R = np.asarray(motion.geom_xmat[frame, g], float).reshape(3, 3)
    return motion.geom_xpos[frame, g] + (aabb[:3] + aabb[3:] * _CUBE) @ R.T


def box_corners(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """(8, 3) the corners of the box lo..hi."""
    return (lo + hi) / 2 + (hi - lo) / 2 * _CUBE


def focus_points(motion: SceneMotion, fates: Fates, model: Any, *, bodies: bool = True) -> np.ndarray:
    """(N, 3) the points the default camera frames: the controlled and fated bodies' paths (the
    corners of their geoms' bounding cubes at every frame), their regions' corners, and what their
    ``hits`` and ``never_hits`` name (planes aside), where it starts; ``bodies`` False: the paths left out."""
    import mujoco

    moving = {int(mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, n))
              for n in [c.body for c in fates.controls] + [f.body for f in fates.fates]}
    pts = []
    for f in fates.fates:   # what they must touch or miss (a backboard, a bell), but no plane
        for n in (*f.hits, *f.never_hits):
            b = int(mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, n))
            gs = ([g for g in range(int(model.ngeom)) if int(model.geom_bodyid[g]) == b] if b > 0
                  else [int(mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, n))])
            for g in gs:
                if g >= 0 and int(model.geom_type[g]) != sg.PLANE:
                    pts.append(geom_box_points(motion, model, g))
    for b in (moving if bodies else ()):
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
    return np.concatenate(pts) if pts else np.zeros((0, 3))


def regions_of(f: Any) -> list[Any]:
    """A fate's regions: its ``rest_in``, its ``at`` regions, its ``through`` regions."""
    return ([f.rest_in] if f.rest_in is not None else []) + [r for _, r in f.at] + list(f.through)


def _eye(lo: np.ndarray, hi: np.ndarray, azimuth: float) -> tuple[np.ndarray, np.ndarray, float]:
    """(eye, the box's centre, the distance) of the camera that frames the box lo..hi from ``azimuth``."""
    c = (lo + hi) / 2
    az, el = math.radians(azimuth), math.radians(ELEVATION)
    d = np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])
    dist = DISTANCE * max(float(np.linalg.norm(hi - lo)), 0.05)
    return c + d * dist, c, dist


def hidden_count(motion: SceneMotion, fates: Fates, model: Any, boxes: tuple[np.ndarray, np.ndarray],
                 azimuth: float, *, frames: int = 24) -> int:
    """How many sightlines the tracking camera (its ``boxes``, :func:`tracking_boxes`) from ``azimuth``
    has blocked: to each fated or controlled body's origin at ``frames`` frames spread over the
    motion, and to each first touch's point at its time. A sightline is blocked when it crosses the
    bounding box (MuJoCo's ``geom_aabb``, turned with the geom) of a visible geom (groups 0-2, not
    transparent, no plane) other than the body's own and the touched one's, before 98 % of its length."""
    import mujoco

    F = len(motion.times)
    ids = {int(mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, n))
           for n in [c.body for c in fates.controls] + [f.body for f in fates.fates]}
    seen = [g for g in range(int(model.ngeom)) if int(model.geom_group[g]) <= 2 and model.geom_rgba[g, 3] > 0
            and int(model.geom_type[g]) not in (sg.PLANE, int(mujoco.mjtGeom.mjGEOM_HFIELD))]
    if not seen:
        return 0
    gbody = np.asarray(model.geom_bodyid)[seen]
    aabb = np.asarray(model.geom_aabb, float)[seen]
    sights: list[tuple[int, np.ndarray, set[int]]] = []   # (frame, target, bodies whose geoms may be in the way)
    for k in sorted({int(round(x)) for x in np.linspace(0, F - 1, min(frames, F))}):
        sights += [(k, motion.body_xpos[k, b], {b}) for b in ids]
    for tc in motion.touches:
        k = int(np.clip(np.searchsorted(motion.times, tc.t), 0, F - 1))
        mine = set()
        for n in (tc.body, tc.other):
            b = int(mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, n))
            g = int(mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, n))
            mine.add(b if b >= 0 else (int(model.geom_bodyid[g]) if g >= 0 else -1))
        sights.append((k, np.asarray(tc.pos, float), mine))
    hidden = 0
    for k, target, mine in sights:
        eye, _, _ = _eye(boxes[0][k], boxes[1][k], azimuth)
        R = np.asarray(motion.geom_xmat[k], float)[seen].reshape(-1, 3, 3)
        e = np.einsum("gji,gj->gi", R, eye - motion.geom_xpos[k][seen]) - aabb[:, :3]   # in each geom's frame
        v = np.einsum("gji,j->gi", R, target - eye)
        with np.errstate(divide="ignore", invalid="ignore"):
            t1, t2 = (-aabb[:, 3:] - e) / v, (aabb[:, 3:] - e) / v
        inside = np.abs(e) <= aabb[:, 3:]
        lo = np.where(v == 0, np.where(inside, -np.inf, np.inf), np.minimum(t1, t2)).max(axis=1)
        hi = np.where(v == 0, np.where(inside, np.inf, -np.inf), np.maximum(t1, t2)).min(axis=1)
        block = (hi >= np.maximum(lo, 0.0)) & (lo < 0.98) & ~np.isin(gbody, list(mine))
        hidden += int(block.any())
    return hidden


def clear_azimuth(motion: SceneMotion, fates: Fates, model: Any, boxes: tuple[np.ndarray, np.ndarray]) -> float:
    """The first of :data:`AZIMUTHS` with the fewest blocked sightlines (:func:`hidden_count`)."""
    counts = [hidden_count(motion, fates, model, boxes, a) for a in AZIMUTHS]
    return float(AZIMUTHS[int(np.argmin(counts))])


def default_camera(points: np.ndarray, aspect: float, free: tuple[float, float, float, float],
                   azimuth: float = AZIMUTH) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The camera that frames ``points`` (N, 3) from ``azimuth`` and :data:`ELEVATION`.

    It stands :data:`DISTANCE` times the points' extent from their box's centre and looks at it with a
    :data:`FOV` lens; then the picture is scaled and moved (an off-axis frustum) so that the
    points' projections fill :data:`FILL` of the ``free`` part of the frame (x0, y0, x1, y1 in
    normalised device coordinates, y down: the part the readout leaves).

    Returns:
        (eye (3,), target (3,), the (4, 4) view-projection, image row 0 at the top).
    """
    eye, c, dist = _eye(points.min(axis=0), points.max(axis=0), azimuth)
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
