"""The 3D cameras' matrices and the meshes' vertex arrays, shared by the 3D views (the disks'
3D view, both bowling videos, the crash video).

Compute only (numpy).
"""
from __future__ import annotations

import math

import numpy as np

__all__ = ["look_at", "mesh_arrays", "orthographic", "perspective"]


def mesh_arrays(mesh) -> np.ndarray:
    """Unshared vertices with per-face-corner normals: flat caps, smooth sides for
    shapes of revolution about z (cylinder, annulus), flat faces for boxes.
    Returns (V, 6) float32: position, normal."""
    tris = mesh.vertices[mesh.faces]  # (F, 3, 3)
    fn = mesh.face_normals  # (F, 3)
    normals = np.repeat(fn[:, None, :], 3, axis=1).copy()
    side = np.abs(fn[:, 2]) < 0.5
    if side.any():
        radial = tris[side].copy()
        radial[..., 2] = 0.0
        L = np.linalg.norm(radial, axis=2, keepdims=True)
        radial = np.where(L > 1e-9, radial / np.maximum(L, 1e-9), normals[side])
        # outward or inward surface (an annulus's inner wall): follow the face normal's side
        sign = np.sign((radial * fn[side][:, None, :]).sum(axis=2, keepdims=True))
        normals[side] = radial * np.where(sign == 0, 1.0, sign)
    return np.concatenate([tris, normals], axis=2).reshape(-1, 6).astype("f4")


def look_at(eye, target, up) -> np.ndarray:
    """(4, 4) the view matrix of a camera at ``eye`` looking at ``target``, ``up`` up (OpenGL's gluLookAt)."""
    f = np.asarray(target, float) - eye
    f /= np.linalg.norm(f)
    s = np.cross(f, up)
    s /= np.linalg.norm(s)
    u = np.cross(s, f)
    m = np.eye(4)
    m[0, :3], m[1, :3], m[2, :3] = s, u, -f
    m[:3, 3] = -m[:3, :3] @ eye
    return m


def perspective(fov_y_deg, aspect, near, far) -> np.ndarray:
    """(4, 4) the projection of a vertical field of view ``fov_y_deg`` (degrees), ``aspect`` = width /
    height, clipped to [near, far] (OpenGL's gluPerspective)."""
    f = 1.0 / math.tan(math.radians(fov_y_deg) / 2)
    m = np.zeros((4, 4))
    m[0, 0], m[1, 1] = f / aspect, f
    m[2, 2], m[2, 3] = (far + near) / (near - far), 2 * far * near / (near - far)
    m[3, 2] = -1.0
    return m


def orthographic(left, right, bottom, top, near, far) -> np.ndarray:
    """(4, 4) an orthographic projection of the box [left, right] x [bottom, top] x [-near, -far] in
    eye coordinates (OpenGL's glOrtho): a directional light's shadow map, an overhead view."""
    m = np.eye(4)
    m[0, 0], m[1, 1], m[2, 2] = 2 / (right - left), 2 / (top - bottom), -2 / (far - near)
    m[:3, 3] = -(right + left) / (right - left), -(top + bottom) / (top - bottom), -(far + near) / (far - near)
    return m
