"""What the crash video draws, as vertex arrays: the road and the vehicles from the scene's geoms,
the marks on the road (lane lines, targets, trails, skids, scrapes, impacts).

Two row layouts, both float32:

* **solids** (V, 9): position, normal, colour: triangles shaded by the bowling videos' lit shader
  (``nbst.render.core.shaders.SOLID_VS``/``SOLID_FS``): the static scene baked in world coordinates
  (:func:`static_solids`), each vehicle geom in its own frame (:func:`geom_solid`);
* **marks** (V, 8): position, RGBA, time: flat triangles on the road, each drawn from its time on
  (``-1``: always), so a ribbon whose vertices carry the times they were laid grows as the
  frame's time passes (:func:`ribbon_marks`).

Compute only: numpy (and trimesh for the meshes); the GL lives in :mod:`nbst.render.crash.video`.
"""
from __future__ import annotations

import math

import numpy as np

from nbst.render.core import geoms as cg
from nbst.render.core.camera import mesh_arrays
from nbst.render.core.solids import box as _box, flat_poly as _flat_poly, ribbon as _ribbon

__all__ = ["ARROW_MIN", "PDOF", "PDOF_LENGTH", "VELOCITY_SECONDS", "GLASS", "GROUND_DRAWN", "IMPACT", "MARKING", "SCRAPE", "SKID", "STRIKE", "TYRE", "WELL",
           "arrow_xy", "body_box", "disc_xy", "geom_solid", "impact_arrows", "impact_marks", "lane_marks", "motion_marks",
           "polyline_distance", "ribbon_marks", "static_solids", "strip_triangles", "target_marks", "tyre_solid",
           "vehicle_arches", "vehicle_geoms", "wedge_xy"]

#: Colours.
GLASS = (0.16, 0.20, 0.26)
TYRE = (0.07, 0.07, 0.08)
HUB, SPOKE = (0.30, 0.31, 0.33), (0.85, 0.86, 0.88)
MARKING = (0.92, 0.92, 0.88, 0.9)
SKID = (0.03, 0.03, 0.03, 0.85)
SCRAPE = (0.80, 0.80, 0.76, 0.85)
IMPACT = (1.0, 0.55, 0.08, 0.95)
STRIKE = (0.97, 0.97, 0.97, 0.95)
TRAIL_ALPHA, TARGET_FILL_ALPHA, TARGET_RIM_ALPHA = 0.55, 0.18, 0.9
#: Heights (m) of the flat marks over the road, lowest first (the road's top is at 0.5 mm).
Z_MARKING, Z_TARGET, Z_SKID, Z_TRAIL, Z_IMPACT = 0.002, 0.003, 0.004, 0.005, 0.006
#: Half widths (m): lane lines, trails, a target ring's rim; the centre line's dashes (m of
#: paint, m of gap); an edge line this far inside the carriageway's edge.
LINE_HALF, TRAIL_HALF, TARGET_RIM, DASH, EDGE_IN = 0.07, 0.09, 0.12, (3.0, 6.0), 0.3
#: Impact markers: ring radii (m) of a vehicle pair and of a curb or barrier strike.
IMPACT_RING, STRIKE_RING = (0.9, 1.25), (0.45, 0.65)
#: A heading arrow is at least this long (m), else the rest region's radius.
ARROW_MIN = 2.5
#: At each vehicle pair's impact, from its time on: each vehicle's velocity arrow (from its CoM
#: where it was at the impact, as long as the ground it covered in VELOCITY_SECONDS s, at least
#: VELOCITY_MIN m, in its colour lightened by VELOCITY_LIGHT) and its PDOF arrow (PDOF_LENGTH m
#: long, along the force, its head at the CoM), in PDOF's colour.
VELOCITY_SECONDS, VELOCITY_MIN, VELOCITY_LIGHT, VELOCITY_HALF = 0.3, 1.5, 0.45, 0.14
PDOF_LENGTH, PDOF_HALF = 3.5, 0.16
PDOF = (1.0, 0.90, 0.10, 0.95)
#: Tyres: sides of the cylinder drawn for an ellipsoid tyre, and the spokes (angles, rad, of the
#: wheel's two light wedges: the spin reads from any side).
TYRE_SIDES, SPOKES = 24, (0.0, math.pi)
GEOM_PLANE, GEOM_BOX, GEOM_ELLIPSOID = 0, 6, 4
#: The ground plane is drawn at least this far (m) each way: its edge is the chase view's horizon.
GROUND_DRAWN = 1500.0


# --------------------------------------------------------------------------- marks (V, 8)

def _marks(tris_xy: np.ndarray, z: float, rgba, time) -> np.ndarray:
    """(V, 8) rows: x, y, z, r, g, b, a, time for triangles ``tris_xy`` (V, 2); ``time`` a number or (V,)."""
    n = len(tris_xy)
    return np.column_stack([tris_xy, np.full(n, z), np.tile(rgba, (n, 1)),
                            np.broadcast_to(np.asarray(time, float), (n,))]).astype("f4")


def strip_triangles(strip: np.ndarray) -> np.ndarray:
    """The rows of a triangle strip's triangles, three per triangle, in one winding."""
    k = np.arange(len(strip) - 2)
    idx = np.stack([k, k + 1 + (k % 2), k + 2 - (k % 2)], axis=1).ravel()
    return strip[idx]


def ribbon_marks(xy: np.ndarray, half: float, z: float, rgba, times) -> np.ndarray:
    """A flat ribbon ``half`` m either side of the path ``xy`` (K, 2), laid at ``times`` ((K,) or one)."""
    strip = _ribbon(np.asarray(xy, float), half, (0.0, 0.0, 0.0))[:, :2]   # (2K, 2): a pair per point
    t = np.repeat(np.broadcast_to(np.asarray(times, float), (len(xy),)), 2)
    rows = strip_triangles(np.column_stack([strip, t]))
    return _marks(rows[:, :2], z, rgba, rows[:, 2])


def disc_xy(cx: float, cy: float, r0: float, r1: float, sides: int = 48) -> np.ndarray:
    """Triangles (V, 2) of the annulus r0..r1 (a disc when r0 is 0) about (cx, cy)."""
    a = np.linspace(0, 2 * math.pi, sides + 1)
    c, s = np.cos(a), np.sin(a)
    outer = np.stack([cx + r1 * c, cy + r1 * s], 1)
    if r0 <= 0:
        return np.concatenate([[[cx, cy], outer[k], outer[k + 1]] for k in range(sides)])
    inner = np.stack([cx + r0 * c, cy + r0 * s], 1)
    return strip_triangles(np.stack([outer, inner], 1).reshape(-1, 2))


def arrow_xy(x: float, y: float, heading: float, length: float, half: float) -> np.ndarray:
    """Triangles (V, 2) of an arrow from (x, y), ``length`` m along ``heading`` (rad)."""
    head = min(1.2, 0.4 * length)
    c, s = math.cos(heading), math.sin(heading)
    R = np.array([[c, s], [-s, c]])
    tris = []
    for poly in ([(0, -half), (length - head, -half), (length - head, half), (0, half)],
                 [(length - head, -2.6 * half), (length, 0), (length - head, 2.6 * half)]):
        p = np.asarray(poly, float) @ R + (x, y)
        tris += [[p[0], p[k], p[k + 1]] for k in range(1, len(p) - 1)]
    return np.concatenate(tris)


def wedge_xy(x: float, y: float, heading: float, tol: float, r: float, sides: int = 24) -> np.ndarray:
    """Triangles (V, 2) of the sector heading +- tol (rad), radius r, about (x, y)."""
    a = np.linspace(heading - tol, heading + tol, sides + 1)
    rim = np.stack([x + r * np.cos(a), y + r * np.sin(a)], 1)
    return np.concatenate([[[x, y], rim[k], rim[k + 1]] for k in range(sides)])


def polyline_distance(p: np.ndarray, line: np.ndarray) -> np.ndarray:
    """Distance (N,) from points ``p`` (N, 2) to the polyline ``line`` (K, 2)."""
    a, b = line[:-1], line[1:]
    ab = b - a
    ap = p[:, None, :] - a[None]
    t = np.clip((ap * ab).sum(-1) / np.maximum((ab * ab).sum(-1), 1e-300), 0.0, 1.0)
    return np.hypot(*np.moveaxis(ap - t[..., None] * ab, -1, 0)).min(axis=1)


def _true_runs(ok: np.ndarray) -> list[np.ndarray]:
    idx = np.nonzero(ok)[0]
    if not len(idx):
        return []
    return np.split(idx, np.nonzero(np.diff(idx) > 1)[0] + 1)


def lane_marks(road) -> np.ndarray:
    """(V, 8) lane markings of ``road`` (``nbst.models.crash.road.Road``): the centre line dashed,
    the edge lines EDGE_IN inside the carriageway, each left out where it crosses another road."""
    lines = road.centreline()
    out = []
    for i, line in enumerate(lines):
        L = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(line, axis=0).T))])
        s = np.arange(0.0, L[-1], 0.5)
        pts = np.stack([np.interp(s, L, line[:, 0]), np.interp(s, L, line[:, 1])], 1)
        d = np.gradient(pts, axis=0)
        nrm = np.stack([-d[:, 1], d[:, 0]], 1) / np.maximum(np.hypot(*d.T), 1e-12)[:, None]
        edge = road.width / 2 - EDGE_IN
        for off, dashed in ((0.0, True), (edge, False), (-edge, False)):
            p = pts + off * nrm
            ok = np.ones(len(p), bool)
            for j, other in enumerate(lines):
                if j != i:
                    ok &= polyline_distance(p, other) > road.width / 2 + EDGE_IN
            if dashed:
                ok &= (s % sum(DASH)) < DASH[0]
            out += [ribbon_marks(p[run], LINE_HALF, Z_MARKING, MARKING, -1.0) for run in _true_runs(ok) if len(run) > 1]
    return np.concatenate(out) if out else np.zeros((0, 8), "f4")


def target_marks(fates: list[dict], colours) -> np.ndarray:
    """(V, 8) the script's rest regions (a disc in the vehicle's colour, rimmed) and heading
    arrows (with the tolerance's wedge) at the region's centre; ``fates``: ``crashfile.fate_dict``."""
    out = []
    for f, rgb in zip(fates, colours):
        rgb = tuple(rgb[:3])
        if "rest" not in f:
            continue
        x, y, r = f["rest"]["x"], f["rest"]["y"], f["rest"]["radius"]
        out.append(_marks(disc_xy(x, y, 0.0, r), Z_TARGET, (*rgb, TARGET_FILL_ALPHA), -1.0))
        out.append(_marks(disc_xy(x, y, r - TARGET_RIM, r + TARGET_RIM), Z_TARGET, (*rgb, TARGET_RIM_ALPHA), -1.0))
        if "heading" in f:
            h, tol = math.radians(f["heading"]["deg"]), math.radians(f["heading"]["tol"])
            length = max(ARROW_MIN, r)
            out.append(_marks(wedge_xy(x, y, h, tol, length), Z_TARGET, (*rgb, TARGET_FILL_ALPHA), -1.0))
            out.append(_marks(arrow_xy(x, y, h, length, 0.12), Z_TARGET, (*rgb, TARGET_RIM_ALPHA), -1.0))
    return np.concatenate(out) if out else np.zeros((0, 8), "f4")


def motion_marks(motion, colours) -> np.ndarray:
    """(V, 8) what the motion lays on the road: each vehicle's trail (its CoM path, every 10th
    sample), skid marks and scrapes (``motion.marks``), each vertex at the time it was laid."""
    out = []
    step = max(1, len(motion.times) // 600)
    for i, rgb in enumerate(colours):
        idx = np.arange(0, len(motion.times), step)
        out.append(ribbon_marks(motion.pos[idx, i, :2], TRAIL_HALF, Z_TRAIL, (*rgb[:3], TRAIL_ALPHA),
                                motion.times[idx]))
    for m in motion.marks:
        out.append(ribbon_marks(m.xy, m.half, Z_SKID, SKID if m.kind == "skid" else SCRAPE, m.times))
    return np.concatenate(out)


def impact_arrows(impacts, pos_at, colours) -> np.ndarray:
    """(V, 8) at each vehicle pair's impact, from its time on, each vehicle's velocity arrow and
    PDOF arrow (see VELOCITY_SECONDS, PDOF_LENGTH) where it was then: ``pos_at(t, i)`` its (x, y)."""
    out = []
    for m in impacts:
        if m.what != "vehicle" or not m.dv:
            continue
        for i, (vx, vy) in m.v_before.items():
            x, y = (float(c) for c in pos_at(m.t, i)[:2])
            speed = math.hypot(vx, vy)
            if speed > 0.1:
                light = tuple(c + VELOCITY_LIGHT * (1 - c) for c in colours[i][:3])
                out.append(_marks(arrow_xy(x, y, math.atan2(vy, vx), max(VELOCITY_MIN, VELOCITY_SECONDS * speed),
                                           VELOCITY_HALF), Z_IMPACT, (*light, 0.95), m.t))
            dx, dy = m.dv[i]
            if math.hypot(dx, dy) > 1e-6:
                h = math.atan2(dy, dx)
                out.append(_marks(arrow_xy(x - PDOF_LENGTH * math.cos(h), y - PDOF_LENGTH * math.sin(h), h,
                                           PDOF_LENGTH, PDOF_HALF), Z_IMPACT, PDOF, m.t))
    return np.concatenate(out) if out else np.zeros((0, 8), "f4")


def impact_marks(impacts) -> np.ndarray:
    """(V, 8) a ring at each impact's point from its time on: orange for a vehicle pair, white
    (smaller) for a curb or barrier strike; none where the point is unknown."""
    out = []
    for m in impacts:
        if not all(math.isfinite(c) for c in m.pos[:2]):
            continue
        r0, r1 = IMPACT_RING if m.what == "vehicle" else STRIKE_RING
        out.append(_marks(disc_xy(m.pos[0], m.pos[1], r0, r1), Z_IMPACT, IMPACT if m.what == "vehicle" else STRIKE,
                          m.t))
    return np.concatenate(out) if out else np.zeros((0, 8), "f4")


# --------------------------------------------------------------------------- solids (V, 9)

def static_solids(model, data) -> tuple[np.ndarray, np.ndarray, tuple]:
    """(ground (V, 9), the rest (V, 9), the ground's RGB) of the scene's static geoms in world
    coordinates (``data`` after ``mj_kinematics``), each the core's triangles of its MJCF geom
    (:func:`nbst.render.core.geoms.geom_rows`) in its own colour: the ground plane (drawn to
    GROUND_DRAWN, 2 mm under the carriageway), and the carriageway, curbs and barriers."""
    from nbst.models.crash import scene as scene_mod

    movers = {model.body(scene_mod.vehicle_prefix(i)).id for i in range(_vehicles(model))}
    ground: list = []
    rest: list = []
    ground_rgb: tuple[float, ...] = (0.0, 0.0, 0.0)
    for g in range(model.ngeom):
        b = int(model.geom_bodyid[g])
        while b and b not in movers:
            b = int(model.body_parentid[b])
        if b in movers or model.geom_type[g] not in (GEOM_PLANE, GEOM_BOX):
            continue
        rgb = tuple(float(c) for c in model.geom_rgba[g][:3])
        R, p = data.geom_xmat[g].reshape(3, 3), data.geom_xpos[g]
        rows = cg.geom_rows(model, g, extent=GROUND_DRAWN, plane_at_least=GROUND_DRAWN)
        assert rows is not None   # a plane or a box: always drawn
        if model.geom_type[g] == GEOM_PLANE:
            ground.append(cg.coloured(cg.posed(rows, R, p - np.array([0.0, 0.0, 0.002])), rgb))
            ground_rgb = rgb
        else:
            rest.append(cg.coloured(cg.posed(rows, R, p), rgb))

    def rows_of(parts):
        return np.concatenate(parts).astype("f4") if parts else np.zeros((0, 9), "f4")

    return rows_of(ground), rows_of(rest), ground_rgb


def _vehicles(model) -> int:
    n = 0
    while True:
        try:
            model.body(f"v{n}")
        except KeyError:
            return n
        n += 1


def vehicle_geoms(model, i: int) -> list[int]:
    """The geoms of vehicle ``i`` (body ``v{i}``) that the video draws with :func:`geom_solid`: its body's
    geoms, its four tyres, and its crush zones' slabs (a crushing type: docs/crash.md "Crush"), which
    ride their plastic joints."""
    from nbst.models.crash.crush import CRUSH_ZONES

    body = model.body(f"v{i}").id
    out = np.nonzero(model.geom_bodyid == body)[0].tolist() + [model.geom(f"v{i}_tyre_{c}").id
                                                              for c in ("fl", "fr", "rl", "rr")]
    for z in CRUSH_ZONES:
        try:
            out.append(int(model.geom(f"v{i}_crush_{z}").id))
        except KeyError:
            pass
    return [int(g) for g in out]


def vehicle_arches(model, data, i: int, g: int) -> list[tuple[float, float, float]]:
    """Wheel arches of vehicle ``i``'s lower body box ``g`` (none for another geom): (x, half length,
    top z) in the box's frame, over its tyres where ``data``'s kinematics put them (the start)."""
    if not model.geom(g).name.endswith("_lower"):
        return []
    R, p = data.geom_xmat[g].reshape(3, 3), data.geom_xpos[g]
    out: list[tuple[float, float, float]] = []
    for c in ("fl", "fr", "rl", "rr"):
        t = model.geom(f"v{i}_tyre_{c}").id
        x, _, z = R.T @ (data.geom_xpos[t] - p)
        r = float(model.geom_size[t][0]) + ARCH_CLEAR
        if not any(abs(a[0] - x) < 1e-6 for a in out):
            out.append((float(x), r, float(z) + r))
    return out


def geom_solid(model, g: int, arches=()) -> np.ndarray | None:
    """(V, 9) vehicle geom ``g`` in its own frame, or None (not drawn: a hub): a box in its colour
    (with ``arches``, :func:`body_box`); a cabin (the darker box above the belt line) glazed all
    round, with a windscreen strip at the front of its roof so the heading reads from above; an
    ellipsoid tyre as a cylinder about its axle (y) with two light spokes on each face."""
    rgb = tuple(float(c) for c in model.geom_rgba[g][:3])
    sx, sy, sz = (float(c) for c in model.geom_size[g])
    name = model.geom(g).name
    if model.geom_type[g] == GEOM_BOX:
        if not name.endswith("_cabin"):
            return body_box(sx, sy, sz, rgb, arches).astype("f4")
        box = cg.geom_rows(model, g)
        assert box is not None   # a box: always drawn
        rows = cg.coloured(box, rgb)
        rows[np.abs(rows[:, 5]) < 0.5, 6:9] = GLASS
        screen = _flat_poly([(0.45 * sx, -0.9 * sy), (0.95 * sx, -0.9 * sy), (0.95 * sx, 0.9 * sy),
                             (0.45 * sx, 0.9 * sy)], GLASS, z=sz + 0.004)
        return np.concatenate([rows, screen]).astype("f4")
    if model.geom_type[g] == GEOM_ELLIPSOID and "_tyre_" in name:
        return tyre_solid(sx, sy).astype("f4")
    return None


#: A wheel arch clears its tyre by this much (m); the well behind it is this deep (m).
ARCH_CLEAR, WELL_DEPTH = 0.06, 0.32
WELL = (0.05, 0.05, 0.06)


def _quad(a, b, c, d, normal, rgb) -> np.ndarray:
    p = np.array([a, b, c, a, c, d], float)
    return np.column_stack([p, np.tile(normal, (6, 1)), np.tile(rgb, (6, 1))])


def body_box(sx: float, sy: float, sz: float, rgb, arches=()) -> np.ndarray:
    """(V, 9) a box of half sizes (sx, sy, sz) whose two long sides (+-y) have a wheel arch at each
    of ``arches``: (x, half length, top z) in the box's frame, open from its bottom up to ``top``,
    with a dark well behind it, so that the tyre inside shows (spinning, steering) while the box
    stays the geom's own size everywhere else."""
    arches = sorted((float(x), float(h), float(min(top, sz))) for x, h, top in arches)
    if not arches:
        return _box(-sx, sx, -sy, sy, -sz, sz, rgb)   # the core's box (a geom's, without a model)
    rows = [r for r in _box(-sx, sx, -sy, sy, -sz, sz, rgb).reshape(-1, 3, 9) if abs(r[0, 4]) < 0.5]
    cuts = sorted({-sx, sx, *(c for x, h, _ in arches for c in (max(-sx, x - h), min(sx, x + h)))})
    out = [np.concatenate(rows)]
    for side in (1.0, -1.0):
        y, n = side * sy, (0.0, side, 0.0)
        yw = side * (sy - WELL_DEPTH)
        for a, b in zip(cuts[:-1], cuts[1:]):
            arch = next(((x, h, top) for x, h, top in arches if x - h <= a + 1e-9 and b <= x + h + 1e-9), None)
            z0 = -sz if arch is None else arch[2]
            if z0 < sz:
                out.append(_quad((a, y, z0), (b, y, z0), (b, y, sz), (a, y, sz), n, rgb))
            if arch is not None:   # the well: its back wall and its roof
                out.append(_quad((a, yw, -sz), (b, yw, -sz), (b, yw, z0), (a, yw, z0), n, WELL))
                out.append(_quad((a, yw, z0), (b, yw, z0), (b, y, z0), (a, y, z0), (0.0, 0.0, -1.0), WELL))
    return np.concatenate(out)


def tyre_solid(radius: float, half_width: float) -> np.ndarray:
    """(V, 9) a tyre about the y axis: black tread and sidewalls, grey faces with two light spokes."""
    import trimesh


    m = trimesh.creation.cylinder(radius=radius, height=2 * half_width, sections=TYRE_SIDES)
    pn = mesh_arrays(m).astype(float)                     # (V, 6), axis along z
    tri = pn[:, :3].reshape(-1, 3, 3)
    cap = np.abs(pn[:, 5].reshape(-1, 3)[:, 0]) > 0.5
    ang = np.arctan2(tri[:, :, 1].mean(1), tri[:, :, 0].mean(1))
    spoke = np.zeros(len(tri), bool)
    for a in SPOKES:
        spoke |= np.abs((ang - a + math.pi) % (2 * math.pi) - math.pi) < math.pi / TYRE_SIDES * 1.5
    col = np.where(cap[:, None], np.where(spoke[:, None], SPOKE, HUB), TYRE)
    rows = np.concatenate([pn, np.repeat(col, 3, axis=0)], axis=1)
    R = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])     # z (axle) -> y
    return cg.posed(rows, R, np.zeros(3))
