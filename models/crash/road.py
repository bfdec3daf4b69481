"""Road layouts: a straight road, a 4-way intersection, a curve; curbs, barriers, friction.

Axes: x east, y north, z up, metres; headings in radians counter-clockwise from +x. The
ground is one plane, z = 0, everywhere (the road's friction rules it). On top of it:

* **straight**: the carriageway ``|y| <= width/2`` for ``|x| <= length/2``;
* **intersection**: two such roads crossing at the origin, one along x, one along y;
* **curve**: a straight lead-in from ``(-length/2, 0)`` to the origin along +x, an arc of
  centreline radius ``radius`` turning left through ``angle`` (centre at ``(0, radius)``), and a
  straight lead-out of ``length/2`` beyond it.

**Curbs** (``curb`` > 0 m high, 0.3 m wide boxes) line the carriageway's edges (at the
intersection they stop at the crossing roads' edges). **Barriers** are boxes along segments the
script names (``from``, ``to``, ``height``), 0.5 m thick. Curbs sit in the static body
``curbs`` and barriers in ``barriers``, so one contact sensor per vehicle tells a strike.

The **map** is the carriageway's bounding box grown by :data:`MAP_MARGIN`: every position a
script names (starts, aim points, rest regions) must lie inside it.

Compute only: :class:`Road` answers geometric questions; :func:`add_road` adds geoms to a spec.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from nbst.models.crash.vehicle import BIT_STATIC

__all__ = ["MAP_MARGIN", "CURB_WIDTH", "BARRIER_THICKNESS", "ARC_PIECE", "GROUND_RGBA", "ROAD_RGBA",
           "CURB_RGBA", "BARRIER_RGBA", "ROAD_SOLREF", "LAYOUTS", "Barrier", "Road", "add_road"]

#: How far the map reaches past the carriageway's bounding box (m).
MAP_MARGIN = 30.0
#: Curb stones: width (m); barriers: thickness (m).
CURB_WIDTH = 0.3
BARRIER_THICKNESS = 0.5
#: Arcs are drawn and lined with curbs in pieces of at most this length (m).
ARC_PIECE = 2.0
#: Colours: ground, carriageway, curbs, barriers, lane markings.
GROUND_RGBA = (0.42, 0.47, 0.38, 1.0)
ROAD_RGBA = (0.25, 0.25, 0.27, 1.0)
CURB_RGBA = (0.72, 0.72, 0.70, 1.0)
BARRIER_RGBA = (0.80, 0.55, 0.15, 1.0)
#: Road contact: a stiff, critically damped surface (time constant s, damping ratio).
ROAD_SOLREF = (0.01, 1.0)
LAYOUTS = ("straight", "intersection", "curve")


@dataclass(frozen=True)
class Barrier:
    """A barrier box along the segment a -> b (m), ``height`` m tall."""

    a: tuple
    b: tuple
    height: float


@dataclass(frozen=True)
class Road:
    """A validated road (SI units): see the module docstring for the layouts."""

    layout: str
    width: float = 7.0
    length: float = 120.0
    radius: float = 40.0
    angle: float = math.pi / 2
    curb: float = 0.0
    friction: float = 0.8
    barriers: tuple = field(default_factory=tuple)

    # ---------------------------------------------------------------- centreline
    def centreline(self) -> list[np.ndarray]:
        """The carriageway as polylines of its centre, (k, 2) each."""
        h = self.length / 2
        if self.layout == "straight":
            return [np.array([[-h, 0.0], [h, 0.0]])]
        if self.layout == "intersection":
            return [np.array([[-h, 0.0], [h, 0.0]]), np.array([[0.0, -h], [0.0, h]])]
        n = max(2, int(math.ceil(self.radius * self.angle / ARC_PIECE)) + 1)
        t = np.linspace(0.0, self.angle, n)
        arc = np.stack([self.radius * np.sin(t), self.radius * (1 - np.cos(t))], axis=1)
        end, d = arc[-1], np.array([math.cos(self.angle), math.sin(self.angle)])
        return [np.vstack([[[-h, 0.0]], arc, [end + h * d]])]

    def distance_to_centre(self, p) -> float:
        """Distance (m) from point ``p`` (x, y) to the nearest centreline."""
        p = np.asarray(p, dtype=float)
        best = math.inf
        for line in self.centreline():
            a, b = line[:-1], line[1:]
            ab = b - a
            t = np.clip(((p - a) * ab).sum(axis=1) / np.maximum((ab * ab).sum(axis=1), 1e-300), 0.0, 1.0)
            d = np.hypot(*(a + t[:, None] * ab - p).T)
            best = min(best, float(d.min()))
        return best

    def on_road(self, p, slack: float = 1e-9) -> bool:
        """Whether point ``p`` lies on the carriageway (within width/2 of a centreline)."""
        return self.distance_to_centre(p) <= self.width / 2 + slack

    def bounds(self) -> tuple[float, float, float, float]:
        """The map: (xmin, ymin, xmax, ymax) in m (the carriageway's box plus MAP_MARGIN)."""
        pts = np.vstack(self.centreline())
        for bar in self.barriers:
            pts = np.vstack([pts, [bar.a, bar.b]])
        lo = pts.min(axis=0) - self.width / 2 - MAP_MARGIN
        hi = pts.max(axis=0) + self.width / 2 + MAP_MARGIN
        return float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1])

    def in_map(self, p) -> bool:
        x0, y0, x1, y1 = self.bounds()
        return x0 <= p[0] <= x1 and y0 <= p[1] <= y1

    # ---------------------------------------------------------------- curbs
    def curb_segments(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """Curb centre segments (a, b), each a (2,) pair; empty when ``curb`` is 0."""
        if self.curb <= 0:
            return []
        off = self.width / 2 + CURB_WIDTH / 2
        h = self.length / 2
        if self.layout == "straight":
            return [(np.array([-h, s * off]), np.array([h, s * off])) for s in (1, -1)]
        if self.layout == "intersection":
            inner = self.width / 2 + CURB_WIDTH  # stop at the crossing road's curb line
            segs = []
            for s in (1, -1):
                for sign in (1, -1):
                    segs.append((np.array([sign * inner, s * off]), np.array([sign * h, s * off])))
                    segs.append((np.array([s * off, sign * inner]), np.array([s * off, sign * h])))
            return segs
        segs = []
        line = self.centreline()[0]
        for s in (1, -1):  # left edge (+1), right edge (-1)
            pts = []
            for i in range(len(line)):
                d = line[min(i + 1, len(line) - 1)] - line[max(i - 1, 0)]
                nrm = np.array([-d[1], d[0]]) / np.hypot(*d)
                pts.append(line[i] + s * off * nrm)
            segs += [(pts[i], pts[i + 1]) for i in range(len(pts) - 1)]
        return segs

    def to_dict(self) -> dict:
        """The road in the script's units (degrees for the curve's angle)."""
        d = {"layout": self.layout, "width": self.width, "length": self.length, "curb": self.curb,
             "friction": self.friction}
        if self.layout == "curve":
            d["radius"] = self.radius
            d["angle"] = math.degrees(self.angle)
        if self.barriers:
            d["barriers"] = [{"from": list(b.a), "to": list(b.b), "height": b.height} for b in self.barriers]
        return d


def _six(x: float) -> float:
    return float(f"{float(x):.6g}")


def _segment_box(parent, name, a, b, width, height, rgba, *, z0=0.0, contact=True, mu=None):
    """A box along segment a -> b (centre line on the ground), ``width`` wide, ``height`` tall."""
    import mujoco

    a, b = np.asarray(a, float), np.asarray(b, float)
    c = (a + b) / 2
    L = float(np.hypot(*(b - a)))
    yaw = math.atan2(b[1] - a[1], b[0] - a[0])
    g = parent.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_BOX,
                        size=[_six(L / 2), _six(width / 2), _six(height / 2)],
                        pos=[_six(c[0]), _six(c[1]), _six(z0 + height / 2)],
                        quat=[_six(math.cos(yaw / 2)), 0.0, 0.0, _six(math.sin(yaw / 2))], rgba=list(rgba))
    if contact:
        _static(g, mu)
    else:
        g.contype = g.conaffinity = 0
        g.group = 2
    return g


def _static(geom, mu) -> None:
    """A static surface: contype 1 (it touches tyres and bodies), priority 1 (its friction ``mu``
    rules the tyres), critically damped."""
    geom.contype, geom.conaffinity = BIT_STATIC, 0
    geom.condim = 3
    geom.priority = 1
    if mu is not None:
        geom.friction = [mu, 0.0, 0.0]
    geom.solref = list(ROAD_SOLREF)


def add_road(spec, road: Road) -> dict:
    """Add the ground, the carriageway (visual), curbs and barriers to ``spec``; returns
    ``{"curbs": bool, "barriers": bool}`` (whether those bodies exist)."""
    import mujoco

    wb = spec.worldbody
    x0, y0, x1, y1 = road.bounds()
    ground = wb.add_geom(name="ground", type=mujoco.mjtGeom.mjGEOM_PLANE,
                         size=[_six((x1 - x0) / 2 + 50), _six((y1 - y0) / 2 + 50), 1.0],
                         pos=[_six((x0 + x1) / 2), _six((y0 + y1) / 2), 0.0], rgba=list(GROUND_RGBA))
    _static(ground, road.friction)
    # the carriageway, drawn only (a thin box just under the surface: the plane carries the contacts)
    k = 0
    for line in road.centreline():
        for a, b in zip(line[:-1], line[1:]):
            d = (b - a) / max(float(np.hypot(*(b - a))), 1e-12)
            ext = road.width / 2 * 0.0 if road.layout != "curve" else 0.15
            _segment_box(wb, f"road{k}", a - ext * d, b + ext * d, road.width, 0.002, ROAD_RGBA, z0=-0.0015,
                         contact=False)
            k += 1
    out = {"curbs": False, "barriers": False}
    segs = road.curb_segments()
    if segs:
        body = wb.add_body(name="curbs")
        for i, (a, b) in enumerate(segs):
            _segment_box(body, f"curb{i}", a, b, CURB_WIDTH, road.curb, CURB_RGBA, mu=road.friction)
        out["curbs"] = True
    if road.barriers:
        body = wb.add_body(name="barriers")
        for i, bar in enumerate(road.barriers):
            _segment_box(body, f"barrier{i}", bar.a, bar.b, BARRIER_THICKNESS, bar.height, BARRIER_RGBA, mu=road.friction)
        out["barriers"] = True
    return out
