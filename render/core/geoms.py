"""Each MuJoCo geom type as triangles in the geom's own frame, and the marks of the fates: the one
geometry code every 3D video draws bodies with (any scene, the bowling videos' pins and ball and
the 5 m lane, the crash's road and vehicle bodies).

Rows are (V, 6) float32: position, normal (unshared triangles), in the frame MuJoCo poses the
geom in (``geom_xpos``, ``geom_xmat``): plane (its half sizes; an infinite one, size 0, drawn
``extent`` across), sphere, capsule and cylinder (about z), ellipsoid, box, and meshes (MuJoCo's
compiled ``mesh_vert``/``mesh_face``, already in the geom's frame). Smooth normals on round
shapes, flat ones on boxes and meshes' creases.

The fates' marks: a region's solid (:func:`region_solid`, a ball or a box) and its outline
(:func:`region_outline`, line segments), and an arrow (:func:`arrow_solid`) for an up-axis.

Placing rows: :func:`body_rows` (a geom in its body's frame: ``geom_pos``/``geom_quat`` applied,
for a body posed from ``qpos``), :func:`posed` (rows moved by a rotation and a translation) and
:func:`coloured` ((V, 6) rows with a colour per vertex: the lit solid shader's (V, 9) rows).

Compute only (numpy; trimesh for the primitives).
"""
from __future__ import annotations

from typing import Any

import numpy as np

from nbst.render.core.camera import mesh_arrays

__all__ = ["PLANE", "HFIELD", "SPHERE", "CAPSULE", "ELLIPSOID", "CYLINDER", "BOX", "MESH", "HIDDEN_GROUPS",
           "body_rows", "coloured", "geom_rgba", "geom_rows", "posed", "quat_mat", "visible_geoms", "region_solid",
           "region_outline", "arrow_solid", "sphere_rows"]

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


def sphere_rows(radius: float, level: int = _SPHERE_LEVEL) -> np.ndarray:
    """(V, 6) a sphere of ``radius`` about the origin, smooth (an icosphere of ``level`` subdivisions)."""
    import trimesh

    s = trimesh.creation.icosphere(subdivisions=int(level), radius=float(radius))
    f = s.faces.reshape(-1)
    v = s.vertices[f]
    return _rows(v, v / np.linalg.norm(v, axis=1, keepdims=True))


def geom_rows(model: Any, g: int, *, extent: float = 10.0, plane_at_least: float = 0.0) -> np.ndarray | None:
    """(V, 6) float32 geom ``g`` of ``model`` in its own frame, or None (a type not drawn). A height field is
    its top surface (no sides or base).

    Args:
        model: the compiled ``mujoco.MjModel``.
        g: the geom's index.
        extent: the half size (m) an infinite plane (size 0) is drawn to.
        plane_at_least: a finite plane is drawn at least this far (m) each way (a road's ground
            out to the horizon).

    Returns:
        The rows, or None for a type not drawn.
    """
    import trimesh

    t = int(model.geom_type[g])
    sx, sy, sz = (float(c) for c in model.geom_size[g])
    if t == PLANE:
        hx = max(sx, plane_at_least) if sx > 0 else extent
        hy = max(sy, plane_at_least) if sy > 0 else extent
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
    if t == HFIELD:   # the top surface, MuJoCo's grid: row r at y = -hy + 2 hy r / (nrow - 1), column c along x
        h = int(model.geom_dataid[g])
        if h < 0:
            return None
        nr, nc = int(model.hfield_nrow[h]), int(model.hfield_ncol[h])
        hx, hy, hz = (float(c) for c in model.hfield_size[h][:3])
        adr = int(model.hfield_adr[h])
        X, Y = np.meshgrid(np.linspace(-hx, hx, nc), np.linspace(-hy, hy, nr))
        Z = np.asarray(model.hfield_data[adr:adr + nr * nc], float).reshape(nr, nc) * hz
        v = np.stack([X.ravel(), Y.ravel(), Z.ravel()], axis=1)
        k = np.arange(nr * nc).reshape(nr, nc)
        a, b, c, d = k[:-1, :-1].ravel(), k[:-1, 1:].ravel(), k[1:, 1:].ravel(), k[1:, :-1].ravel()
        return _flat(v, np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)]))
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


def quat_mat(q) -> np.ndarray:
    """(3, 3) the rotation of the quaternion ``q`` (w, x, y, z; normalised here)."""
    w, x, y, z = np.asarray(q, float) / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def posed(rows: np.ndarray, R: np.ndarray, p) -> np.ndarray:
    """``rows`` ((V, 6) or wider: position, normal, the rest kept) rotated by ``R`` (3, 3) and
    moved by ``p`` (3,): positions ``R x + p``, normals ``R n``."""
    out = np.array(rows, dtype=float)
    R = np.asarray(R, float)
    out[:, :3] = out[:, :3] @ R.T + np.asarray(p, float)
    out[:, 3:6] = out[:, 3:6] @ R.T
    return out


def body_rows(model: Any, g: int, **kw: Any) -> np.ndarray | None:
    """(V, 6) geom ``g`` in its body's frame (its ``geom_pos`` and ``geom_quat`` applied: MuJoCo
    moves a mesh's frame to its centre of mass), for a body posed from ``qpos``; None as
    :func:`geom_rows`. ``kw``: :func:`geom_rows`'s."""
    rows = geom_rows(model, g, **kw)
    if rows is None:
        return None
    return posed(rows, quat_mat(model.geom_quat[g]), model.geom_pos[g]).astype("f4")


def coloured(rows: np.ndarray, rgb) -> np.ndarray:
    """(V, 9) float32: ``rows`` (V, 6) with a colour: one RGB, or a function of the (3,) position
    giving each vertex's (a pin's stripes), or a (V, 3) array."""
    rows = np.asarray(rows, float)
    if callable(rgb):
        col = np.array([rgb(p) for p in rows[:, :3]], float).reshape(-1, 3)
    else:
        col = np.broadcast_to(np.asarray(rgb, float)[..., :3], (len(rows), 3))
    return np.concatenate([rows[:, :6], col], axis=1).astype("f4")


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
