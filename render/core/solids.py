"""Flat-shaded solids for the 3D scenes, as vertex arrays: the pieces the bowling lane and the crash
scene both build from (one place, not a copy in each).

Rows are float32-ready (V, 9): position, normal, colour (RGB 0..1), unshared triangles, as the
bowling videos' lit shader (``nbst.render.core.shaders.SOLID_VS``/``SOLID_FS``) takes them.

Compute only (numpy; trimesh for the box).
"""
from __future__ import annotations

import numpy as np

__all__ = ["box", "flat_poly", "ribbon"]


def box(x0, x1, y0, y1, z0, z1, rgb) -> np.ndarray:
    """(36, 9) an axis-aligned box from (x0, y0, z0) to (x1, y1, z1), face normals, one colour."""
    import trimesh

    b = trimesh.creation.box(extents=[x1 - x0, y1 - y0, z1 - z0])
    b.apply_translation([(x0 + x1) / 2, (y0 + y1) / 2, (z0 + z1) / 2])
    tris = b.faces.reshape(-1)
    fn = np.repeat(b.face_normals, 3, axis=0)
    return np.concatenate([b.vertices[tris], fn, np.tile(rgb, (len(tris), 1))], axis=1)


def flat_poly(xy, rgb, z=0.0) -> np.ndarray:
    """A convex polygon on the plane z (a triangle fan), normal up: (V, 9)."""
    xy = np.asarray(xy, float)
    tris = np.concatenate([[xy[0], xy[k], xy[k + 1]] for k in range(1, len(xy) - 1)])
    n = len(tris)
    return np.concatenate([tris, np.full((n, 1), z), np.tile([0.0, 0.0, 1.0], (n, 1)), np.tile(rgb, (n, 1))], axis=1)


def ribbon(xy: np.ndarray, half: float, rgb) -> np.ndarray:
    """(2K, 9) vertices of a flat triangle strip along the path ``xy`` (K, 2), ``half`` wide either side."""
    d = np.gradient(xy, axis=0)
    d /= np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-12)
    nrm = np.stack([-d[:, 1], d[:, 0]], 1) * half
    pts = np.stack([xy + nrm, xy - nrm], 1).reshape(-1, 2)
    n = len(pts)
    return np.concatenate([pts, np.zeros((n, 1)), np.tile([0.0, 0.0, 1.0], (n, 1)), np.tile(rgb, (n, 1))],
                          axis=1).astype("f4")
