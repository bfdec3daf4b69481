"""MuJoCo models to glTF bodies, and recorded states to body poses.

:func:`model_bodies` turns every body of a compiled ``mujoco.MjModel`` into a
:class:`~nbst.export.gltf.Body` whose solids are its visible geoms in the body's frame, with the
renderer's geometry, visibility and colours (:mod:`nbst.render.core.geoms`, the code ``nbst render``
draws a scene with): plane (a quad: its half-sizes, or :data:`PLANE_HALF` m for an infinite one),
sphere, capsule, ellipsoid, cylinder, box and mesh (the compiled vertices and faces), each coloured
by its material's RGBA when it has one, else its own ``geom_rgba``; a geom is visible when its alpha
is above 0 and its group is one MuJoCo's viewer shows by default (0, 1, 2). Heightfields are not
exported (none of nbst's worlds has one). The world body (id 0) is one static body. :func:`body_poses` runs
``mj_kinematics`` on recorded ``qpos`` rows: every body's ``xpos`` and ``xquat``.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from nbst.export.gltf import Body, BodyMotion, Solid, turn_angles
from nbst.render.core.geoms import geom_rgba, geom_rows, visible_geoms

__all__ = ["PLANE_HALF", "geom_body_rows", "model_bodies", "body_poses", "sampled_steps", "qpos_motion"]

#: Half-size (m) of the quad drawn for an infinite plane (size 0 in MJCF).
PLANE_HALF = 50.0


def _quat_matrix(q: np.ndarray) -> np.ndarray:
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def geom_body_rows(model: Any, g: int) -> np.ndarray | None:
    """Geom ``g`` of ``model`` as triangle rows (position, normal) in its body's frame: the
    renderer's own geometry (:func:`nbst.render.core.geoms.geom_rows`, in the geom's frame)
    placed by ``geom_pos`` and ``geom_quat``.

    Args:
        model: a compiled ``mujoco.MjModel``.
        g: the geom's id.

    Returns:
        (V, 6) float64 array, or None for a type not drawn (a heightfield).
    """
    rows = geom_rows(model, g, extent=PLANE_HALF)
    if rows is None:
        return None
    R = _quat_matrix(np.asarray(model.geom_quat[g], float))
    out = np.asarray(rows, float).copy()
    out[:, :3] = out[:, :3] @ R.T + np.asarray(model.geom_pos[g], float)
    out[:, 3:] = out[:, 3:] @ R.T
    return out


def model_bodies(model: Any) -> list[Body]:
    """Every body of ``model``, body id order, each with its visible geoms as solids.

    Args:
        model: a compiled ``mujoco.MjModel``.

    Returns:
        ``nbody`` bodies; a body without a visible geom has no solids. Static: the world (id 0) and
        every body welded to it (no joint between it and the world, not a mocap body: a post, a
        bin, a hoop), which never moves and gets no animation channel.
    """
    bodies = [Body(name=model.body(b).name or f"body{b}", solids=[],
                   moves=int(model.body_weldid[b]) != 0 or int(model.body_mocapid[b]) >= 0)
              for b in range(model.nbody)]
    for g in visible_geoms(model):
        rows = geom_body_rows(model, g)
        if rows is not None:
            bodies[int(model.geom_bodyid[g])].solids.append(Solid(rows=rows, rgba=geom_rgba(model, g)))
    return bodies


def body_poses(model: Any, qpos: np.ndarray, mocap: tuple[np.ndarray, np.ndarray] | None = None
               ) -> tuple[np.ndarray, np.ndarray]:
    """Every body's world pose at each recorded state (``mj_kinematics``).

    Args:
        model: a compiled ``mujoco.MjModel``.
        qpos: (T, nq) float64 array, recorded states.
        mocap: ``(mocap_pos (nmocap, 3), mocap_quat (nmocap, 4))`` the mocap bodies are held at (a
            key's ``mpos``/``mquat``); default the model's own (``body_pos``/``body_quat``).

    Returns:
        ``(pos (T, nbody, 3), quat (T, nbody, 4))`` float64 arrays, quaternions (w, x, y, z).
    """
    import mujoco

    d = mujoco.MjData(model)
    if mocap is not None:
        d.mocap_pos[:], d.mocap_quat[:] = mocap
    pos = np.empty((len(qpos), model.nbody, 3))
    quat = np.empty((len(qpos), model.nbody, 4))
    for k, q in enumerate(qpos):
        d.qpos[:] = q
        mujoco.mj_kinematics(model, d)
        pos[k], quat[k] = d.xpos, d.xquat
    return pos, quat


def sampled_steps(times: np.ndarray, fps: float) -> np.ndarray:
    """The recorded states nearest the keyframe times 0, 1/fps, 2/fps, ... up to the last state's time,
    always with the first and the last state.

    Args:
        times: (S,) float64 array, the recorded states' times in s, increasing from 0.
        fps: keyframes per second.

    Returns:
        (K,) int array of indices into ``times``, strictly increasing.
    """
    times = np.asarray(times, float)
    want = np.arange(0.0, float(times[-1]) + 0.5 / fps, 1.0 / fps)
    k = np.clip(np.searchsorted(times, want), 1, len(times) - 1) if len(times) > 1 else np.zeros(len(want), int)
    if len(times) > 1:
        k = np.where(want - times[k - 1] <= times[k] - want, k - 1, k)
    idx = np.unique(np.concatenate([[0], k, [len(times) - 1]]))
    return idx.astype(int)


def qpos_motion(model: Any, qpos: np.ndarray, times: np.ndarray, fps: float,
                mocap: tuple[np.ndarray, np.ndarray] | None = None) -> BodyMotion:
    """The motion of recorded states: every body of ``model`` at the states nearest the keyframes
    (:func:`sampled_steps`); the keyframe times are those states' own times.

    Args:
        model: a compiled ``mujoco.MjModel``.
        qpos: (S, nq) float64 array, recorded states.
        times: (S,) float64 array, their times in s, increasing from 0.
        fps: keyframes per second.
        mocap: the mocap bodies' pose (:func:`body_poses`); default the model's.

    Returns:
        the :class:`~nbst.export.gltf.BodyMotion`.
    """
    idx = sampled_steps(times, fps)
    pos, quat = body_poses(model, np.asarray(qpos), mocap)   # every state once: the keyframes and the turn rates
    t = np.asarray(times, float)
    rate = (turn_angles(quat) / np.maximum(np.diff(t), 1e-12)[:, None]).max(axis=0) if len(t) > 1 else None
    return BodyMotion(bodies=model_bodies(model), times=t[idx], pos=pos[idx], quat=quat[idx], turn_rate=rate)
