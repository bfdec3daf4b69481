"""The tenpin: a solid of revolution from the USBC pin profile, built with trimesh.

One source for every use of the pin's shape: the collision pieces and the visual
mesh in the MuJoCo scene (:mod:`nbst.models.bowling.scene`), the mass properties
(from the whole solid, uniform density) and the renderer.

Frame: z up the pin's axis, origin at the centre of the base; metres.

Profile: (height, diameter) pairs in inches from the USBC dimension table of the
tenpin (15 in tall, 4.766 in at the belly 4 1/2 in up, 1.797 in at the neck 10 in
up, base 2.031 in); the head above 13 1/2 in is closed by an elliptic arc. The
numbers between the table's named ones are read off the drawing to ~0.02 in, so
the profile is "approximate USBC": every dimension the rules state is exact.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from nbst.errors import InputError

__all__ = ["INCH", "PROFILE_IN", "HEIGHT_IN", "HEAD_POINTS", "MASS", "MASS_LIMITS", "COM_LIMITS_IN",
           "VISUAL_SEGMENTS", "COLLISION_SEGMENTS", "CUTS_IN", "profile", "PinGeometry", "geometry",
           "mass_properties"]

INCH = 0.0254
#: (height, diameter) in inches, base to the start of the head cap.
PROFILE_IN = (
    (0.0, 2.031), (0.375, 2.45), (0.75, 2.828), (1.5, 3.41), (2.25, 3.906), (3.375, 4.510),
    (4.5, 4.766), (5.875, 4.512), (7.25, 3.705), (8.625, 2.620), (9.375, 1.970), (10.0, 1.797),
    (10.875, 1.870), (11.75, 2.152), (12.625, 2.414), (13.5, 2.515),
)
#: Height of the pin (USBC: 15 in +/- 1/32).
HEIGHT_IN = 15.0
#: Points on the head cap (an elliptic arc from 13.5 in to the top).
HEAD_POINTS = 8
#: Pin mass, kg: the middle of USBC's 3 lb 6 oz .. 3 lb 10 oz (1.531 .. 1.644 kg).
MASS = 1.588
#: USBC's limits on the pin's weight (kg) and on its centre of gravity's height above the base (in:
#: 5 40/64 .. 5 60/64 in, bowl.com/specs/systemBowling/pins.aspx).
MASS_LIMITS = (1.531, 1.644)
COM_LIMITS_IN = (5 + 40 / 64, 5 + 60 / 64)
#: Segments around the axis: visual mesh (smooth) and collision pieces (a 16-gon is
#: within 2 % of the circle; fewer vertices keep MuJoCo's convex collisions fast).
VISUAL_SEGMENTS = 48
COLLISION_SEGMENTS = 16
#: Heights (in) where the collision solid is cut into convex pieces (MuJoCo collides
#: the convex hull of each mesh): base, belly, neck, head. The neck piece's hull fills
#: the neck by at most ~0.2 in of radius.
CUTS_IN = (3.375, 7.25, 10.875)


def profile() -> np.ndarray:
    """The pin's outline, (K, 2) float: (radius, height) in metres, base (z = 0) to top (r = 0)."""
    h = np.array([p[0] for p in PROFILE_IN])
    r = np.array([p[1] for p in PROFILE_IN]) / 2
    h0, r0 = h[-1], r[-1]
    t = np.linspace(0, np.pi / 2, HEAD_POINTS + 1)[1:]
    hh = h0 + (HEIGHT_IN - h0) * np.sin(t)
    rh = r0 * np.cos(t)
    rh[-1] = 0.0
    return np.column_stack([np.concatenate([r, rh]), np.concatenate([h, hh])]) * INCH


def _revolve(rz: np.ndarray, segments: int):
    """A closed trimesh solid from a (radius, height) outline; caps the base if r > 0 there."""
    import trimesh

    pts = rz.copy()
    if pts[0, 0] > 0:  # close the flat base at the axis
        pts = np.vstack([[0.0, pts[0, 1]], pts])
    if pts[-1, 0] > 0:  # close a flat top (a cut piece)
        pts = np.vstack([pts, [0.0, pts[-1, 1]]])
    mesh = trimesh.creation.revolve(pts, sections=segments)
    if mesh.volume < 0:
        mesh.invert()
    return mesh


@dataclass(frozen=True)
class PinGeometry:
    """The pin's meshes and mass properties (metres, kg).

    visual : (V, 3) float32 vertices and (F, 3) int faces of the smooth solid
    pieces : tuple of (P_i, 3) float32 vertex arrays, one per convex collision piece
    com : (3,) centre of mass; inertia : (3,) principal moments about it (x, y, z axes)
    """

    visual_vertices: np.ndarray
    visual_faces: np.ndarray
    pieces: tuple
    mass: float
    com: np.ndarray
    inertia: np.ndarray
    volume: float


@lru_cache(maxsize=1)
def geometry() -> PinGeometry:
    """The pin (cached): meshes from :func:`profile`, mass and inertia of the uniform solid."""
    rz = profile()
    solid = _revolve(rz, VISUAL_SEGMENTS)
    density = MASS / solid.volume
    solid.density = density
    com = np.array(solid.center_mass, dtype=float)
    inertia_tensor = np.array(solid.moment_inertia, dtype=float)  # about the COM, axes of the frame
    inertia = np.diag(inertia_tensor).copy()
    inertia[0] = inertia[1] = 0.5 * (inertia[0] + inertia[1])  # exact symmetry of revolution
    com[0] = com[1] = 0.0
    pieces = []
    cuts = [0.0, *(c * INCH for c in CUTS_IN), np.inf]
    z = rz[:, 1]
    for lo, hi in zip(cuts[:-1], cuts[1:]):
        keep = (z >= lo - 1e-12) & (z <= hi + 1e-12)
        ring = rz[keep]
        ang = np.linspace(0, 2 * np.pi, COLLISION_SEGMENTS, endpoint=False)
        verts = [(r * np.cos(a), r * np.sin(a), h) for r, h in ring for a in (ang if r > 0 else [0.0])]
        pieces.append(np.asarray(verts, dtype=np.float32))
    return PinGeometry(visual_vertices=np.asarray(solid.vertices, dtype=np.float32),
                       visual_faces=np.asarray(solid.faces, dtype=np.int32), pieces=tuple(pieces),
                       mass=MASS, com=com, inertia=inertia, volume=float(solid.volume))


def _slices(n: int = 4000) -> tuple[np.ndarray, np.ndarray, float]:
    """(z, r, dz): the solid of :func:`profile` cut into ``n`` slices (midpoints), metres."""
    rz = profile()
    dz = rz[-1, 1] / n
    z = (np.arange(n) + 0.5) * dz
    return z, np.interp(z, rz[:, 1], rz[:, 0]), dz


def mass_properties(mass: float = MASS, com_in: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(com (3,), principal inertia (3,)) of a pin of ``mass`` (kg) whose centre of gravity is
    ``com_in`` inches above the base (None: the uniform solid's, :func:`geometry`).

    A real pin is not uniform (a maple core, a plastic coat, a hollow): its weight and centre of
    gravity are what USBC limits (:data:`MASS_LIMITS`, :data:`COM_LIMITS_IN`). Here the density
    varies linearly along the axis, rho(z) = rho0 (1 + a (z - z0)) (z0: the uniform solid's
    centre), with ``a`` set so the centre lands at ``com_in``; the inertia is the uniform
    solid's (:func:`geometry`, from the mesh) times the ratio of the graded to the uniform
    slice integrals, so ``com_in`` None, or the uniform centre, gives :func:`geometry`'s values
    scaled by ``mass / MASS``. InputError outside USBC's limits."""
    geo = geometry()
    lo, hi = MASS_LIMITS
    if not lo - 1e-9 <= mass <= hi + 1e-9:
        raise InputError(f"pin mass: must be within USBC's {lo}..{hi} kg, got {mass!r}")
    if com_in is None:
        return geo.com.copy(), geo.inertia * (mass / MASS)
    clo, chi = COM_LIMITS_IN
    if not clo - 1e-9 <= com_in <= chi + 1e-9:
        raise InputError(f"pin centre of gravity: must be within USBC's {clo:.4f}..{chi:.4f} in, got {com_in!r}")
    z, r, dz = _slices()
    area = np.pi * r**2
    z0 = float((z * area).sum() / area.sum())
    a = (com_in * INCH - z0) * area.sum() / float((area * (z - z0) ** 2).sum())

    def moments(w):
        m = (w * area).sum()
        c = (w * area * z).sum() / m
        izz = (w * np.pi * r**4 / 2).sum() / m
        ixx = (w * (np.pi * r**4 / 4 + area * (z - c) ** 2)).sum() / m
        return c, np.array([ixx, ixx, izz])

    c1, i1 = moments(1.0 + a * (z - z0))
    _, i0 = moments(np.ones_like(z))
    com = np.array([0.0, 0.0, c1])
    return com, geo.inertia / MASS * mass * (i1 / i0)
