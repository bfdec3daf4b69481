"""MuJoCo models to glTF bodies, and recorded states to body poses.

:func:`model_bodies` turns every body of a compiled ``mujoco.MjModel`` that has a visible geom into
a :class:`~nbst.export.gltf.Body` whose solids are its geoms in the body's frame: plane (a quad: its
half-sizes, or :data:`PLANE_HALF` m for an infinite one), sphere, capsule, ellipsoid, cylinder, box
and mesh (the compiled vertices and faces), each coloured by its material's RGBA when it has one,
else its own ``geom_rgba``. A geom is visible when its alpha is above 0 and its group is one
MuJoCo's viewer shows by default (0, 1, 2). Heightfields and SDFs are not exported (none of nbst's
worlds has one). The world body (id 0) is one static body. :func:`body_poses` runs
``mj_kinematics`` on recorded ``qpos`` rows: every body's ``xpos`` and ``xquat``.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from nbst.export.gltf import Body, BodyMotion, Solid

__all__ = ["PLANE_HALF", "VISIBLE_GROUPS", "geom_mesh", "model_bodies", "body_poses", "sampled_steps", "qpos_motion"]

#: Half-size (m) of the quad drawn for an infinite plane (size 0 in MJCF).
PLANE_HALF = 50.0
#: The geom groups MuJoCo's viewer shows by default.
VISIBLE_GROUPS = (0, 1, 2)


def _quat_matrix(q: np.ndarray) -> np.ndarray:
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def geom_mesh(model: Any, g: int) -> Any:
    """Geom ``g`` of ``model`` as a ``trimesh.Trimesh`` in its body's frame, or None (a type not exported).

    Args:
        model: a compiled ``mujoco.MjModel``.
        g: the geom's id.

    Returns:
        the mesh, or None for a heightfield, SDF or other type.
    """
    import mujoco
    import trimesh

    t, size = int(model.geom_type[g]), np.asarray(model.geom_size[g], float)
    G = mujoco.mjtGeom
    if t == G.mjGEOM_PLANE:
        hx, hy = (float(size[0]) or PLANE_HALF), (float(size[1]) or PLANE_HALF)
        v = np.array([[-hx, -hy, 0.0], [hx, -hy, 0.0], [hx, hy, 0.0], [-hx, hy, 0.0]])
        m = trimesh.Trimesh(vertices=v, faces=[[0, 1, 2], [0, 2, 3]], process=False)
    elif t == G.mjGEOM_SPHERE:
        m = trimesh.creation.icosphere(subdivisions=3, radius=float(size[0]))
    elif t == G.mjGEOM_ELLIPSOID:
        m = trimesh.creation.icosphere(subdivisions=3, radius=1.0)
        m.apply_scale(size[:3])
    elif t == G.mjGEOM_CAPSULE:
        m = trimesh.creation.capsule(height=2.0 * float(size[1]), radius=float(size[0]), count=[32, 16])
    elif t == G.mjGEOM_CYLINDER:
        m = trimesh.creation.cylinder(radius=float(size[0]), height=2.0 * float(size[1]), sections=48)
    elif t == G.mjGEOM_BOX:
        m = trimesh.creation.box(extents=2.0 * size[:3])
    elif t == G.mjGEOM_MESH:
        k = int(model.geom_dataid[g])
        va, vn = int(model.mesh_vertadr[k]), int(model.mesh_vertnum[k])
        fa, fn = int(model.mesh_faceadr[k]), int(model.mesh_facenum[k])
        m = trimesh.Trimesh(vertices=np.array(model.mesh_vert[va:va + vn], float),
                            faces=np.array(model.mesh_face[fa:fa + fn]), process=False)
    else:
        return None
    tf = np.eye(4)
    tf[:3, :3] = _quat_matrix(np.asarray(model.geom_quat[g], float))
    tf[:3, 3] = model.geom_pos[g]
    m.apply_transform(tf)
    return m


def _rgba(model: Any, g: int) -> tuple[float, float, float, float]:
    mat = int(model.geom_matid[g])
    c = model.mat_rgba[mat] if mat >= 0 else model.geom_rgba[g]
    r, gr, b, a = (float(x) for x in c)
    return (r, gr, b, a)


def model_bodies(model: Any) -> list[Body]:
    """Every body of ``model``, body id order, each with its visible geoms as solids.

    Args:
        model: a compiled ``mujoco.MjModel``.

    Returns:
        ``nbody`` bodies (the world, id 0, static; the others moving); a body without a visible
        geom has no solids.
    """
    bodies = [Body(name=model.body(b).name or f"body{b}", solids=[], moves=b > 0) for b in range(model.nbody)]
    for g in range(model.ngeom):
        if _rgba(model, g)[3] <= 0 or int(model.geom_group[g]) not in VISIBLE_GROUPS:
            continue
        m = geom_mesh(model, g)
        if m is not None:
            bodies[int(model.geom_bodyid[g])].solids.append(Solid(mesh=m, rgba=_rgba(model, g)))
    return bodies


def body_poses(model: Any, qpos: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Every body's world pose at each recorded state (``mj_kinematics``).

    Args:
        model: a compiled ``mujoco.MjModel``.
        qpos: (T, nq) float64 array, recorded states.

    Returns:
        ``(pos (T, nbody, 3), quat (T, nbody, 4))`` float64 arrays, quaternions (w, x, y, z).
    """
    import mujoco

    d = mujoco.MjData(model)
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


def qpos_motion(model: Any, qpos: np.ndarray, times: np.ndarray, fps: float) -> BodyMotion:
    """The motion of recorded states: every body of ``model`` at the states nearest the keyframes
    (:func:`sampled_steps`); the keyframe times are those states' own times.

    Args:
        model: a compiled ``mujoco.MjModel``.
        qpos: (S, nq) float64 array, recorded states.
        times: (S,) float64 array, their times in s, increasing from 0.
        fps: keyframes per second.

    Returns:
        the :class:`~nbst.export.gltf.BodyMotion`.
    """
    idx = sampled_steps(times, fps)
    pos, quat = body_poses(model, np.asarray(qpos)[idx])
    return BodyMotion(bodies=model_bodies(model), times=np.asarray(times, float)[idx], pos=pos, quat=quat)
