"""Each MuJoCo geom type as triangles in the geom's own frame, and the marks of the fates.

Rows are (V, 6) float32: position, normal (unshared triangles), in the frame MuJoCo poses the
geom in (``geom_xpos``, ``geom_xmat``): plane (its half sizes; an infinite one, size 0, drawn
``extent`` across), sphere, capsule and cylinder (about z), ellipsoid, box, and meshes (MuJoCo's
compiled ``mesh_vert``/``mesh_face``, already in the geom's frame). Smooth normals on round
shapes, flat ones on boxes and meshes' creases.

The fates' marks: a region's solid (:func:`region_solid`, a ball or a box) and its outline
(:func:`region_outline`, line segments), and an arrow (:func:`arrow_solid`) for an up-axis.

Compute only (numpy; trimesh for the primitives).
"""
from __future__ import annotations

from typing import Any

import numpy as np

from nbst.render.core.camera import mesh_arrays

__all__ = ["PLANE", "HFIELD", "SPHERE", "CAPSULE", "ELLIPSOID", "CYLINDER", "BOX", "MESH", "HIDDEN_GROUPS",
           "geom_rgba", "geom_rows", "visible_geoms", "region_solid", "region_outline", "arrow_solid", "sphere_rows"]

#: MuJoCo's geom types (``mjtGeom``).
PLANE, HFIELD, SPHERE, CAPSULE, ELLIPSOID, CYLINDER, BOX, MESH = range(8)
#: Geom groups MuJoCo's viewer hides by default (it shows groups 0, 1 and 2).
HIDDEN_GROUPS = frozenset(range(3, 6))
_SPHERE_LEVEL = 3   # icosphere subdivisions: 642 vertices, smooth at video sizes


def _rows(v: np.ndarray, n: np.ndarray) -> np.ndarray:
    return np.concatenate([v, n], axis=1).astype("f4")


def _smooth(mesh: Any) -> np.ndarray:
    """Unshared triangles of a trimesh with its vertex normals (a smooth surface)."""
    f = mesh.faces.reshape(-1)
    return _rows(mesh.vertices[f], mesh.vertex_normals[f])


def _flat(v: np.ndarray, faces: np.ndarray) -> np.ndarray:
    tri = v[faces]                                   # (F, 3, 3)
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    return _rows(tri.reshape(-1, 3), np.repeat(n, 3, axis=0))


def sphere_rows(radius: float) -> np.ndarray:
    """(V, 6) a sphere of ``radius`` about the origin, smooth."""
    import trimesh

    s = trimesh.creation.icosphere(subdivisions=_SPHERE_LEVEL, radius=float(radius))
    f = s.faces.reshape(-1)
    v = s.vertices[f]
    return _rows(v, v / np.linalg.norm(v, axis=1, keepdims=True))


def geom_rows(model: Any, g: int, *, extent: float = 10.0) -> np.ndarray | None:
    """(V, 6) float32 geom ``g`` of ``model`` in its own frame, or None (a type not drawn: a height field).

    Args:
        model: the compiled ``mujoco.MjModel``.
        g: the geom's index.
        extent: the half size (m) an infinite plane (size 0) is drawn to.
    """
    import trimesh

    t = int(model.geom_type[g])
    sx, sy, sz = (float(c) for c in model.geom_size[g])
    if t == PLANE:
        hx, hy = sx if sx > 0 else extent, sy if sy > 0 else extent
        v = np.array([[-hx, -hy, 0], [hx, -hy, 0], [hx, hy, 0], [-hx, -hy, 0], [hx, hy, 0], [-hx, hy, 0]], float)
        return _rows(v, np.tile([0.0, 0.0, 1.0], (6, 1)))
    if t == SPHERE:
        return sphere_rows(sx)
    if t == ELLIPSOID:
        rows = sphere_rows(1.0).astype(float)
        s = np.array([sx, sy, sz])
        n = rows[:, 3:] / s
        return _rows(rows[:, :3] * s, n / np.linalg.norm(n, axis=1, keepdims=True))
    if t == CAPSULE:
        return _smooth(trimesh.creation.capsule(height=2 * sy, radius=sx, count=[32, 16]))
    if t == CYLINDER:
        return mesh_arrays(trimesh.creation.cylinder(radius=sx, height=2 * sy, sections=48))
    if t == BOX:
        b = trimesh.creation.box(extents=[2 * sx, 2 * sy, 2 * sz])
        return _flat(np.asarray(b.vertices, float), np.asarray(b.faces))
    if t == MESH:
        m = int(model.geom_dataid[g])
        if m < 0:
            return None
        va, vn = int(model.mesh_vertadr[m]), int(model.mesh_vertnum[m])
        fa, fn = int(model.mesh_faceadr[m]), int(model.mesh_facenum[m])
        v = np.asarray(model.mesh_vert[va:va + vn], float)
        faces = np.asarray(model.mesh_face[fa:fa + fn], int)
        mesh = trimesh.Trimesh(v, faces, process=False)
        # smooth where the surface is smooth, flat across creases (over 30 degrees): a die's edges
        # stay sharp, a ball's facets do not show
        smooth = trimesh.graph.smooth_shade(mesh, angle=np.radians(30))
        return _smooth(smooth)
    return None


def visible_geoms(model: Any) -> list[int]:
    """The geoms MuJoCo's viewer draws by default: alpha above 0 (``geom_rgba``, or the
    material's when the geom has one) and a group it shows (0, 1, 2)."""
    out = []
    for g in range(int(model.ngeom)):
        if int(model.geom_group[g]) in HIDDEN_GROUPS or geom_rgba(model, g)[3] <= 0:
            continue
        out.append(g)
    return out


def geom_rgba(model: Any, g: int) -> tuple[float, float, float, float]:
    """The geom's colour: its material's ``mat_rgba`` when it has a material, else ``geom_rgba``."""
    m = int(model.geom_matid[g])
    c = model.mat_rgba[m] if m >= 0 else model.geom_rgba[g]
    return (float(c[0]), float(c[1]), float(c[2]), float(c[3]))


def region_solid(region: Any) -> tuple[np.ndarray, np.ndarray]:
    """(rows (V, 6) float32 in world coordinates, its centre (3,)) of a fates region: a ball or a box."""
    import trimesh

    if region.center is not None:
        c = np.asarray(region.center, float)
        rows = sphere_rows(region.radius)
        rows[:, :3] += c
        return rows, c
    lo, hi = np.asarray(region.lo, float), np.asarray(region.hi, float)
    b = trimesh.creation.box(extents=hi - lo)
    v = np.asarray(b.vertices, float) + (lo + hi) / 2
    return _flat(v, np.asarray(b.faces)), (lo + hi) / 2


def region_outline(region: Any, *, sides: int = 64) -> np.ndarray:
    """(2K, 3) float32 line segments (pairs of points) outlining a region: a ball's three great
    circles (its equator level with the floor: a hoop seen from above), or a box's 12 edges."""
    if region.center is not None:
        c, r = np.asarray(region.center, float), float(region.radius)
        a = np.linspace(0, 2 * np.pi, sides + 1)
        ring = np.stack([np.cos(a), np.sin(a)], axis=1) * r
        segs = []
        for i, j in ((0, 1), (0, 2), (1, 2)):
            p = np.zeros((sides + 1, 3))
            p[:, i], p[:, j] = ring[:, 0], ring[:, 1]
            segs.append(np.stack([p[:-1], p[1:]], axis=1).reshape(-1, 3))
        return (np.concatenate(segs) + c).astype("f4")
    lo, hi = np.asarray(region.lo, float), np.asarray(region.hi, float)
    corners = np.array([[(lo, hi)[(k >> i) & 1][i] for i in range(3)] for k in range(8)])
    edges = [(a, b) for a in range(8) for b in range(a + 1, 8) if bin(a ^ b).count("1") == 1]
    return corners[np.array(edges).reshape(-1)].astype("f4")


def arrow_solid(length: float, radius: float) -> np.ndarray:
    """(V, 6) float32 an arrow along +z from the origin, ``length`` long: a shaft of ``radius``
    and a cone head twice as wide, a quarter of the length."""
    import trimesh

    head = 0.25 * length
    shaft = trimesh.creation.cylinder(radius=radius, height=length - head, sections=16)
    shaft.apply_translation([0, 0, (length - head) / 2])
    cone = trimesh.creation.cone(radius=2.2 * radius, height=head, sections=16)
    cone.apply_translation([0, 0, length - head])
    return np.concatenate([mesh_arrays(shaft), _flat(np.asarray(cone.vertices, float), np.asarray(cone.faces))])
