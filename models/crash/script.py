"""The crash script: a JSON file of kind ``nbst-crash-script`` and its strict validation.

A script names the road, the duration and timestep, and per vehicle its type, start pose,
speed range, driver ranges and fate; optionally a global order of contacts. The format, in the
user's units (metres, km/h, degrees, seconds), is in docs/crash.md; every field is checked
here, and a bad one raises :class:`ScriptError` (an :class:`nbst.errors.InputError`): one line
naming the file, the field as a path (``vehicles[1].fate.rest.x``) and the problem. Files come
in through nbst's input gate (``nbst.problem.read_json``: regular files only, a size cap,
strict JSON, bounded depth, no huge integers).

Refused, besides wrong types, unknown keys, NaN and numbers out of their domain
(:data:`LIMITS`): vehicles overlapping at the start, a start (any corner of the vehicle) off the
carriageway, a position (aim point, rest region) outside the map, hit lists that contradict each
other or the global order, a fate that asks for the impossible (a curb strike on a road without
curbs, an attitude its quarter turns cannot give).

Compute only: :func:`script_from_dict` takes decoded JSON; :func:`load_script` reads a file
or a built-in (:data:`SCRIPTS`, a ``nbst.registry.Registry`` of the JSON files of
``models/crash/scripts/``).

Length: ~540 lines, past the house's ~500: one validator per part of one file format (road,
vehicle, driver, fate, order, the cross-checks), kept together so that every rule of the format
sits in one place beside the dataclasses it builds (the typed field access is :mod:`.fields`).
"""
from __future__ import annotations

import difflib
import math
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from nbst.models.crash import road as road_mod
from nbst.models.crash.fields import Fields, ScriptError, jtype as _jtype
from nbst.models.crash import vehicle as veh
from nbst.problem import ProblemError, parse_json, read_json
from nbst.registry import Registry

__all__ = ["KIND", "SCHEMA_VERSION", "KMH", "SURFACES", "AFTER_IMPACT", "ATTITUDES", "LIMITS", "MAX_VEHICLES",
           "MAX_BARRIERS", "MAX_WAYPOINTS", "MAX_NAME_CHARS", "MAX_DESCRIPTION_CHARS", "Range", "Driver",
           "Fate", "VehicleScript", "Script", "TOP_KEYS", "ROAD_KEYS", "VEHICLE_KEYS", "DRIVER_KEYS",
           "FATE_KEYS", "START_CLEARANCE", "script_from_dict", "attitude_of_turns", "footprint", "SCRIPTS",
           "builtin_names", "builtin_text", "load_script"]

KIND = "nbst-crash-script"
SCHEMA_VERSION = 1
KMH = 1 / 3.6
#: Friction of the named surfaces (tyre on asphalt): dry within the issue's 0.7-0.9, wet assumed.
SURFACES = {"dry": 0.8, "wet": 0.5}
AFTER_IMPACT = ("brake", "coast", "hold")
ATTITUDES = ("upright", "side", "roof")

#: The accepted domain, each limit with why (docs/results/crash.md has the same table).
LIMITS = {
    "width": (3.0, 30.0),        # m: a one-lane road to a wide boulevard
    "length": (20.0, 1000.0),    # m: room for a vehicle to start and stop; a bounded map
    "radius": (10.0, 500.0),     # m: the curve's centreline radius
    "angle": (5.0, 180.0),       # deg: the curve's sweep
    "curb": (0.0, 0.5),          # m: a curb stone is 0.1-0.2 m; above 0.5 m it is a wall
    "friction": (0.1, 1.2),      # tyre on ice (0.1) to a dry racing surface (1.2)
    "barrier_height": (0.2, 3.0),
    "barrier_length": (0.5, 1000.0),
    "duration": (1.0, 30.0),     # s: a crash plays out in seconds; 30 s bounds the rollout
    "timestep": (0.00025, 0.004),  # s: contacts need >= 2 steps per 0.01 s time constant
    "speed": (0.0, 200.0),       # km/h
    "steer": (-35.0, 35.0),      # deg: the steering's lock
    "headway": (0.1, 5.0),       # s: IDM's time gap
    "reaction": (0.0, 3.0),      # s: a driver's reaction delay
    "impact_speed": (0.0, 250.0),  # km/h
    "delta_v": (0.0, 200.0),     # km/h
    "rest_radius": (0.1, 100.0),  # m
    "heading_tol": (0.1, 180.0),  # deg
    "quarter_turns": (0, 40),
    "spin": (0.0, 3600.0),       # deg of yaw turned
    "spin_tol": (1.0, 360.0),
}
MAX_VEHICLES = 8        # contact sensors grow as n^2; a scene of 8 cars is 28 pairs
MAX_BARRIERS = 32
MAX_WAYPOINTS = 32
MAX_NAME_CHARS = 32
MAX_DESCRIPTION_CHARS = 2000


@dataclass(frozen=True)
class Range:
    """A closed interval [lo, hi] in SI units; a fixed value has lo == hi."""

    lo: float
    hi: float

    @property
    def fixed(self) -> bool:
        return self.lo == self.hi

    def at(self, u: float) -> float:
        """The value a unit coordinate ``u`` in [0, 1] stands for."""
        return self.lo + (self.hi - self.lo) * float(u)


@dataclass(frozen=True)
class Driver:
    """A vehicle's driver ranges (SI: m, s, rad); None = the behaviour is off."""

    aim_x: Range | None = None
    aim_y: Range | None = None
    waypoints: tuple = ()
    arrive: Range | None = None
    brake_at: Range | None = None
    slide_at: Range | None = None
    slide_steer: Range | None = None
    slide_power: Range | None = None
    follow: int | None = None           # index of the leader (IDM)
    headway: Range | None = None
    reaction: Range | None = None
    after_impact: tuple = ("brake",)    # the choices the search may take
    after_steer: Range | None = None


@dataclass(frozen=True)
class Fate:
    """What the script asks of a vehicle; None / empty = not asked."""

    hits: tuple | None = None           # indices of the vehicles it touches, in order
    impact_speed: Range | None = None   # m/s at its first contact with a vehicle
    delta_v: Range | None = None        # m/s in its first vehicle impact
    rest: tuple | None = None           # (x, y, radius) m
    impact_at: tuple | None = None      # (x, y, radius) m: its CoM at its first vehicle contact
    heading: tuple | None = None        # (angle, tolerance) rad
    quarter_turns: tuple | None = None  # (lo, hi) of |roll| / 90 deg, rounded
    attitude: str | None = None
    spin: tuple | None = None           # (angle, tolerance) rad of yaw turned, either way
    curb: bool | None = None            # strikes a curb (True) or must not (False)
    barrier: bool | None = None

    def asks(self) -> bool:
        return any(v is not None for v in (self.hits, self.impact_speed, self.delta_v, self.rest, self.impact_at,
                                          self.heading,
                                          self.quarter_turns, self.attitude, self.spin, self.curb, self.barrier))


@dataclass(frozen=True)
class VehicleScript:
    name: str
    vtype: veh.VehicleType
    x: float
    y: float
    heading: float                      # rad
    speed: Range                        # m/s
    driver: Driver
    fate: Fate


@dataclass(frozen=True, eq=False)
class Script:
    """A validated crash script (SI units inside; ``raw`` is the decoded JSON)."""

    name: str
    description: str
    road: road_mod.Road
    duration: float
    timestep: float
    vehicles: tuple
    order: tuple | None                 # ((i, j), ...) first contacts between vehicle pairs, in time order
    source: str = "<dict>"
    raw: dict = field(default_factory=dict, repr=False)

    @property
    def n(self) -> int:
        return len(self.vehicles)

    def names(self) -> list[str]:
        return [v.name for v in self.vehicles]


def _rng(lo_hi, scale: float = 1.0) -> Range:
    return Range(lo_hi[0] * scale, lo_hi[1] * scale)


# --------------------------------------------------------------------------- parsing

TOP_KEYS = ("kind", "schema_version", "name", "description", "road", "duration", "timestep", "vehicles", "order")
ROAD_KEYS = ("layout", "width", "length", "radius", "angle", "curb", "friction", "surface", "barriers")
VEHICLE_KEYS = ("name", "type", "start", "speed", "driver", "fate")
DRIVER_KEYS = ("aim", "waypoints", "arrive", "brake_at", "slide", "follow", "after_impact", "after_steer")
FATE_KEYS = ("hits", "impact_speed", "delta_v", "rest", "impact_at", "heading", "quarter_turns", "attitude", "spin", "strikes")
#: Headway of the footprint check (m): starts closer than this overlap.
START_CLEARANCE = 0.05


def script_from_dict(d: Any, *, source: str = "<dict>") -> Script:
    """Validate a decoded crash script and build a :class:`Script` (see the module docstring).

    Args:
        d: the decoded JSON object of an ``nbst-crash-script`` (km/h, degrees and metres, as
            docs/crash.md's "The script" writes them).
        source: how a refusal names the script (its file name).

    Returns:
        the :class:`Script`, in SI units (m/s, rad), with ``raw`` the decoded object.

    Raises:
        ScriptError: (an :class:`nbst.errors.InputError`) anything the gate refuses, in one line
            naming ``source``, the field as a path (``vehicles[1].fate.rest.x``) and the problem.
    """
    c = Fields(source)
    c.obj(d, "", TOP_KEYS, required=("kind", "road", "duration", "vehicles"))
    if d["kind"] != KIND:
        c.fail("kind", f"must be {KIND!r}, got {_jtype(d['kind'])}")
    if "schema_version" in d and c.integer(d["schema_version"], "schema_version", 1, 10**6) != SCHEMA_VERSION:
        c.fail("schema_version", f"this nbst reads crash scripts of schema version {SCHEMA_VERSION}")
    name = c.text(d.get("name", Path(source).stem if source.endswith(".json") else "crash"), "name", 200)
    description = c.text(d.get("description", ""), "description", MAX_DESCRIPTION_CHARS, allow_newlines=True)
    road = _road(c, d["road"])
    duration = c.number(d["duration"], "duration", *LIMITS["duration"], "seconds")
    timestep = c.number(d.get("timestep", 0.002), "timestep", *LIMITS["timestep"], "seconds")
    if duration / timestep > 60_000:
        c.fail("timestep", f"{duration:g} s at {timestep:g} s is {duration / timestep:,.0f} steps; at most 60,000")
    vs = d["vehicles"]
    if not isinstance(vs, list) or not vs:
        c.fail("vehicles", f"must be a non-empty list of vehicles, got {_jtype(vs)}")
    if len(vs) > MAX_VEHICLES:
        c.fail("vehicles", f"{len(vs)} vehicles; at most {MAX_VEHICLES}")
    names: list[str] = []
    for i, v in enumerate(vs):
        p = f"vehicles[{i}]"
        c.obj(v, p, VEHICLE_KEYS, required=("name", "type", "start", "speed"))
        nm = c.text(v["name"], f"{p}.name", MAX_NAME_CHARS)
        if not nm.strip():
            c.fail(f"{p}.name", "must not be empty")
        if nm in names:
            c.fail(f"{p}.name", f"{nm!r} is the name of vehicles[{names.index(nm)}]; names must differ")
        names.append(nm)
    vehicles = tuple(_vehicle(c, v, f"vehicles[{i}]", road, duration, names, i) for i, v in enumerate(vs))
    _starts(c, vehicles, road)
    order = _order(c, d.get("order"), names) if "order" in d else None
    _hits_agree(c, vehicles, order, names)
    return Script(name=name, description=description, road=road, duration=duration, timestep=timestep,
                  vehicles=vehicles, order=order, source=source, raw=d)


def _road(c: Fields, r) -> road_mod.Road:
    c.obj(r, "road", ROAD_KEYS, required=("layout",))
    layout = c.choice(r["layout"], "road.layout", road_mod.LAYOUTS)
    width = c.number(r.get("width", 7.0), "road.width", *LIMITS["width"], "m")
    length = c.number(r.get("length", 120.0), "road.length", *LIMITS["length"], "m")
    curb = c.number(r.get("curb", 0.0), "road.curb", *LIMITS["curb"], "m, the curb's height; 0 = none")
    if "friction" in r and "surface" in r:
        c.fail("road.surface", "give the friction or the surface, not both")
    if "surface" in r:
        mu = SURFACES[c.choice(r["surface"], "road.surface", tuple(SURFACES))]
    else:
        mu = c.number(r.get("friction", SURFACES["dry"]), "road.friction", *LIMITS["friction"],
                      "tyre-road friction coefficient")
    kw = {}
    if layout == "curve":
        radius = c.number(r.get("radius", 40.0), "road.radius", *LIMITS["radius"], "m")
        if radius <= width:
            c.fail("road.radius", f"{radius:g} m is not more than the road's width {width:g} m")
        kw = {"radius": radius, "angle": math.radians(c.number(r.get("angle", 90.0), "road.angle",
                                                               *LIMITS["angle"], "degrees"))}
    else:
        for k in ("radius", "angle"):
            if k in r:
                c.fail(f"road.{k}", f"only a curve has a {k} (layout is {layout!r})")
    bars = r.get("barriers", [])
    if not isinstance(bars, list) or len(bars) > MAX_BARRIERS:
        c.fail("road.barriers", f"must be a list of at most {MAX_BARRIERS} barriers")
    barriers = []
    for i, b in enumerate(bars):
        p = f"road.barriers[{i}]"
        c.obj(b, p, ("from", "to", "height"), required=("from", "to"))
        a, e = c.point(b["from"], f"{p}.from"), c.point(b["to"], f"{p}.to")
        ln = math.hypot(e[0] - a[0], e[1] - a[1])
        if not LIMITS["barrier_length"][0] <= ln <= LIMITS["barrier_length"][1]:
            c.fail(p, f"{ln:g} m long; a barrier is {LIMITS['barrier_length'][0]:g}-{LIMITS['barrier_length'][1]:g} m")
        h = c.number(b.get("height", 0.8), f"{p}.height", *LIMITS["barrier_height"], "m")
        barriers.append(road_mod.Barrier(a, e, h))
    return road_mod.Road(layout=layout, width=width, length=length, curb=curb, friction=mu,
                         barriers=tuple(barriers), **kw)


def _in_map(c: Fields, road, p, path: str) -> None:
    if not road.in_map(p):
        x0, y0, x1, y1 = road.bounds()
        c.fail(path, f"[{p[0]:g}, {p[1]:g}] is outside the map (x {x0:g}..{x1:g}, y {y0:g}..{y1:g} m)")


def _vehicle(c: Fields, v: dict, p: str, road, duration: float, names: list, me: int) -> VehicleScript:
    t = c.choice(v["type"], f"{p}.type", veh.VEHICLE_TYPES.names())
    s = c.obj(v["start"], f"{p}.start", ("x", "y", "heading"), required=("x", "y", "heading"))
    x, y = c.number(s["x"], f"{p}.start.x"), c.number(s["y"], f"{p}.start.y")
    _in_map(c, road, (x, y), f"{p}.start")
    heading = math.radians(c.number(s["heading"], f"{p}.start.heading", -3600.0, 3600.0, "degrees"))
    speed = _rng(c.range(v["speed"], f"{p}.speed", *LIMITS["speed"], "km/h"), KMH)
    driver = _driver(c, v.get("driver", {}), f"{p}.driver", road, duration, names, me)
    fate = _fate(c, v.get("fate", {}), f"{p}.fate", road, names, me)
    return VehicleScript(name=names[me], vtype=veh.VEHICLE_TYPES[t], x=x, y=y, heading=heading, speed=speed,
                         driver=driver, fate=fate)


def _driver(c: Fields, d, p: str, road, duration: float, names: list, me: int) -> Driver:
    c.obj(d, p, DRIVER_KEYS)
    kw: dict = {}
    if "aim" in d and "waypoints" in d:
        c.fail(f"{p}.waypoints", "give an aim point or waypoints, not both")
    if "aim" in d:
        a = c.obj(d["aim"], f"{p}.aim", ("x", "y"), required=("x", "y"))
        kw["aim_x"] = _rng(c.range(a["x"], f"{p}.aim.x", -1e6, 1e6, "m"))
        kw["aim_y"] = _rng(c.range(a["y"], f"{p}.aim.y", -1e6, 1e6, "m"))
        for corner in ((kw["aim_x"].lo, kw["aim_y"].lo), (kw["aim_x"].hi, kw["aim_y"].hi)):
            _in_map(c, road, corner, f"{p}.aim")
    if "waypoints" in d:
        w = d["waypoints"]
        if not isinstance(w, list) or not 1 <= len(w) <= MAX_WAYPOINTS:
            c.fail(f"{p}.waypoints", f"must be a list of 1 to {MAX_WAYPOINTS} points [x, y]")
        pts = tuple(c.point(q, f"{p}.waypoints[{k}]") for k, q in enumerate(w))
        for k, q in enumerate(pts):
            _in_map(c, road, q, f"{p}.waypoints[{k}]")
        kw["waypoints"] = pts
    for key in ("arrive", "brake_at"):
        if key in d:
            kw[key] = _rng(c.range(d[key], f"{p}.{key}", 0.0, duration, f"seconds within the {duration:g} s script"))
    if "slide" in d:
        s = c.obj(d["slide"], f"{p}.slide", ("at", "steer", "power"), required=("at", "steer"))
        kw["slide_at"] = _rng(c.range(s["at"], f"{p}.slide.at", 0.0, duration, "seconds"))
        kw["slide_steer"] = _rng(c.range(s["steer"], f"{p}.slide.steer", *LIMITS["steer"], "degrees, + = left"),
                                 math.pi / 180)
        if "power" in s:
            kw["slide_power"] = _rng(c.range(s["power"], f"{p}.slide.power", 0.0, 1.0,
                                             "share of the full drive torque; 0 = handbrake"))
    if "follow" in d:
        f = c.obj(d["follow"], f"{p}.follow", ("leader", "headway", "reaction"), required=("leader",))
        lead = c.text(f["leader"], f"{p}.follow.leader", MAX_NAME_CHARS)
        if lead not in names:
            c.fail(f"{p}.follow.leader", f"{lead!r} is no vehicle of the script ({', '.join(names)})")
        if names.index(lead) == me:
            c.fail(f"{p}.follow.leader", "a vehicle cannot follow itself")
        kw["follow"] = names.index(lead)
        kw["headway"] = _rng(c.range(f.get("headway", 1.5), f"{p}.follow.headway", *LIMITS["headway"], "s"))
        kw["reaction"] = _rng(c.range(f.get("reaction", 1.0), f"{p}.follow.reaction", *LIMITS["reaction"], "s"))
    if "after_impact" in d:
        a = d["after_impact"]
        opts = a if isinstance(a, list) else [a]
        if not opts:
            c.fail(f"{p}.after_impact", f"must be one of {', '.join(AFTER_IMPACT)} or a list of them")
        for k, o in enumerate(opts):
            c.choice(o, f"{p}.after_impact" + (f"[{k}]" if isinstance(a, list) else ""), AFTER_IMPACT)
        if len(set(opts)) != len(opts):
            c.fail(f"{p}.after_impact", "lists a choice twice")
        kw["after_impact"] = tuple(opts)
    if "after_steer" in d:
        kw["after_steer"] = _rng(c.range(d["after_steer"], f"{p}.after_steer", *LIMITS["steer"], "degrees, + = left"),
                                 math.pi / 180)
    return Driver(**kw)


def _fate(c: Fields, f, p: str, road, names: list, me: int) -> Fate:
    c.obj(f, p, FATE_KEYS)
    kw: dict = {}
    if "hits" in f:
        h = f["hits"]
        if not isinstance(h, list):
            c.fail(f"{p}.hits", "must be a list of vehicle names, in the order they are hit ([] = hits nobody)")
        idx = []
        for k, nm in enumerate(h):
            nm = c.text(nm, f"{p}.hits[{k}]", MAX_NAME_CHARS)
            if nm not in names:
                c.fail(f"{p}.hits[{k}]", f"{nm!r} is no vehicle of the script ({', '.join(names)})")
            j = names.index(nm)
            if j == me:
                c.fail(f"{p}.hits[{k}]", "a vehicle cannot hit itself")
            if j in idx:
                c.fail(f"{p}.hits[{k}]", f"{nm!r} is listed twice (list each vehicle once, at its first contact)")
            idx.append(j)
        kw["hits"] = tuple(idx)
    for key in ("impact_speed", "delta_v"):
        if key in f:
            if not kw.get("hits"):
                c.fail(f"{p}.{key}", "asks about the first impact, so the fate must list whom it hits")
            kw[key] = _rng(c.range(f[key], f"{p}.{key}", *LIMITS[key], "km/h"), KMH)
    if "rest" in f:
        r = c.obj(f["rest"], f"{p}.rest", ("x", "y", "radius"), required=("x", "y"))
        x, y = c.number(r["x"], f"{p}.rest.x"), c.number(r["y"], f"{p}.rest.y")
        _in_map(c, road, (x, y), f"{p}.rest")
        kw["rest"] = (x, y, c.number(r.get("radius", 2.0), f"{p}.rest.radius", *LIMITS["rest_radius"], "m"))
    if "impact_at" in f:
        if not kw.get("hits"):
            c.fail(f"{p}.impact_at", "is where it was at its first impact, so the fate must list whom it hits")
        r = c.obj(f["impact_at"], f"{p}.impact_at", ("x", "y", "radius"), required=("x", "y"))
        x, y = c.number(r["x"], f"{p}.impact_at.x"), c.number(r["y"], f"{p}.impact_at.y")
        _in_map(c, road, (x, y), f"{p}.impact_at")
        kw["impact_at"] = (x, y, c.number(r.get("radius", 0.5), f"{p}.impact_at.radius", *LIMITS["rest_radius"], "m"))
    if "heading" in f:
        h = c.obj(f["heading"], f"{p}.heading", ("deg", "tol"), required=("deg",))
        kw["heading"] = (math.radians(c.number(h["deg"], f"{p}.heading.deg", -3600.0, 3600.0, "degrees")),
                         math.radians(c.number(h.get("tol", 20.0), f"{p}.heading.tol", *LIMITS["heading_tol"],
                                               "degrees")))
    if "quarter_turns" in f:
        q = f["quarter_turns"]
        lo, hi = LIMITS["quarter_turns"]
        if isinstance(q, list):
            if len(q) != 2:
                c.fail(f"{p}.quarter_turns", "must be a whole number or [low, high]")
            a, b = c.integer(q[0], f"{p}.quarter_turns[0]", lo, hi), c.integer(q[1], f"{p}.quarter_turns[1]", lo, hi)
            if a > b:
                c.fail(f"{p}.quarter_turns", f"[{a}, {b}]: the low end is above the high end")
            kw["quarter_turns"] = (a, b)
        else:
            a = c.integer(q, f"{p}.quarter_turns", lo, hi)
            kw["quarter_turns"] = (a, a)
    if "attitude" in f:
        kw["attitude"] = c.choice(f["attitude"], f"{p}.attitude", ATTITUDES)
        if "quarter_turns" in kw:
            a, b = kw["quarter_turns"]
            if not any(attitude_of_turns(k) == kw["attitude"] for k in range(a, b + 1)):
                c.fail(f"{p}.attitude", f"{kw['attitude']!r} cannot follow from {a}..{b} quarter turns of roll")
    if "spin" in f:
        s = c.obj(f["spin"], f"{p}.spin", ("deg", "tol"), required=("deg",))
        kw["spin"] = (math.radians(c.number(s["deg"], f"{p}.spin.deg", *LIMITS["spin"], "degrees of yaw, either way")),
                      math.radians(c.number(s.get("tol", 45.0), f"{p}.spin.tol", *LIMITS["spin_tol"], "degrees")))
    if "strikes" in f:
        s = c.obj(f["strikes"], f"{p}.strikes", ("curb", "barrier"))
        for what in ("curb", "barrier"):
            if what in s:
                want = c.boolean(s[what], f"{p}.strikes.{what}")
                has = road.curb > 0 if what == "curb" else bool(road.barriers)
                if want and not has:
                    c.fail(f"{p}.strikes.{what}", f"asks for a {what} strike, and the road has no {what}s")
                kw[what] = want
    return Fate(**kw)


def attitude_of_turns(k: int) -> str:
    """The end attitude after ``k`` quarter turns of roll: 0 mod 4 upright, 2 mod 4 roof, else side."""
    return ("upright", "side", "roof", "side")[k % 4]


def footprint(v: VehicleScript) -> np.ndarray:
    """(4, 2) corners of the vehicle's plan at its start pose (m)."""
    vt = v.vtype
    front = vt.a + vt.front_overhang
    rear = front - vt.length
    c, s = math.cos(v.heading), math.sin(v.heading)
    local = np.array([[front, vt.width / 2], [front, -vt.width / 2], [rear, -vt.width / 2], [rear, vt.width / 2]])
    return local @ np.array([[c, s], [-s, c]]) + [v.x, v.y]


def _overlap(a: np.ndarray, b: np.ndarray, clearance: float) -> bool:
    """Whether convex polygons a and b (k, 2) come closer than ``clearance`` (separating axes)."""
    for poly in (a, b):
        for i in range(len(poly)):
            e = poly[(i + 1) % len(poly)] - poly[i]
            n = np.array([-e[1], e[0]]) / np.hypot(*e)
            pa, pb = a @ n, b @ n
            if pa.max() + clearance <= pb.min() or pb.max() + clearance <= pa.min():
                return False
    return True


def _starts(c: Fields, vehicles, road) -> None:
    prints = [footprint(v) for v in vehicles]
    for i, (v, fp) in enumerate(zip(vehicles, prints)):
        for k, corner in enumerate(fp):
            if not road.on_road(corner, slack=0.05):
                c.fail(f"vehicles[{i}].start", f"{v.name!r} is not on the road: its "
                       f"{('front left', 'front right', 'rear right', 'rear left')[k]} corner "
                       f"[{corner[0]:.2f}, {corner[1]:.2f}] is off the {road.width:g} m carriageway")
        for j in range(i):
            if _overlap(prints[j], fp, START_CLEARANCE):
                c.fail(f"vehicles[{i}].start", f"{v.name!r} overlaps {vehicles[j].name!r} at the start "
                                               f"(their plans come within {START_CLEARANCE:g} m)")


def _order(c: Fields, o, names: list) -> tuple:
    if not isinstance(o, list):
        c.fail("order", "must be a list of pairs [\"A\", \"B\"]: first contacts between vehicles, in time order")
    pairs = []
    for k, pr in enumerate(o):
        if not isinstance(pr, list) or len(pr) != 2:
            c.fail(f"order[{k}]", "must be a pair of vehicle names [\"A\", \"B\"]")
        ij = []
        for m, nm in enumerate(pr):
            nm = c.text(nm, f"order[{k}][{m}]", MAX_NAME_CHARS)
            if nm not in names:
                c.fail(f"order[{k}][{m}]", f"{nm!r} is no vehicle of the script ({', '.join(names)})")
            ij.append(names.index(nm))
        if ij[0] == ij[1]:
            c.fail(f"order[{k}]", "a vehicle cannot hit itself")
        key = (min(ij), max(ij))
        if key in pairs:
            c.fail(f"order[{k}]", f"the pair {names[key[0]]!r}-{names[key[1]]!r} is listed twice (list first contacts)")
        pairs.append(key)
    return tuple(pairs)


def _hits_agree(c: Fields, vehicles, order, names: list) -> None:
    """Contact is mutual: if A's hits name B, B's (when given) name A; each vehicle's hit list is
    the order of its pairs in the global order (when both are given)."""
    for i, v in enumerate(vehicles):
        if v.fate.hits is None:
            continue
        for j in v.fate.hits:
            other = vehicles[j].fate.hits
            if other is not None and i not in other:
                c.fail(f"vehicles[{j}].fate.hits", f"{names[j]!r} must list {v.name!r}: {v.name!r}'s fate says it "
                                                   f"hits {names[j]!r}, and a contact is mutual")
        if order is not None:
            mine = [b if a == i else a for a, b in order if i in (a, b)]
            if list(v.fate.hits) != mine:
                c.fail(f"vehicles[{i}].fate.hits", f"{[names[k] for k in v.fate.hits]} contradicts the global order, "
                                                   f"which gives {v.name!r} {[names[k] for k in mine]}")
    # the lists together must admit one time order of the pairs' first contacts (no cycle)
    after: dict = {}
    for i, v in enumerate(vehicles):
        hits = v.fate.hits or ()
        for a, b in zip(hits, hits[1:]):
            after.setdefault((min(i, a), max(i, a)), set()).add((min(i, b), max(i, b)))
    state: dict = {}

    def visit(node, path):
        state[node] = 1
        for nxt in sorted(after.get(node, ())):
            if state.get(nxt) == 1:
                cyc = " before ".join(f"{names[x]}-{names[y]}" for x, y in path + [nxt])
                c.fail("vehicles", f"the hit lists contradict each other: they need {cyc}")
            if nxt not in state:
                visit(nxt, path + [nxt])
        state[node] = 2

    for node in sorted(after):
        if node not in state:
            visit(node, [node])


# --------------------------------------------------------------------------- loading

#: The built-in crash scripts, registered once (``nbst crash scripts`` lists them in this order): a
#: new one is a JSON file in ``models/crash/scripts/`` and one line here.
SCRIPTS: Registry[str] = Registry("built-in crash script")
SCRIPTS.register("t-bone", "t-bone.json", help="a sedan T-bones an SUV at an intersection")
SCRIPTS.register("chain3", "chain3.json", help="a 3-car intersection chain: A hits B, B hits C, each in its region")
SCRIPTS.register("rear-end4", "rear-end4.json", help="a 4-car rear-end chain on a highway, the lead car braking")
SCRIPTS.register("rollover", "rollover.json", help="an SUV trips on a curb and ends on its roof")
SCRIPTS.register("stunt", "stunt.json", help="a sedan spins a full turn and stops in a marked bay")
SCRIPTS.register("crossing-case", "crossing-case.json",
                 help="a reconstruction case: two rest poses of a planted crossing crash")


def builtin_names() -> list[str]:
    """Names of the built-in crash scripts, in registration order (:data:`SCRIPTS`)."""
    return list(SCRIPTS.names())


def builtin_text(name: str) -> str:
    return resources.files("nbst.models.crash").joinpath("scripts", SCRIPTS[name]).read_text(encoding="utf-8")


def load_script(name_or_path: str | Path) -> Script:
    """A crash script by built-in name (``t-bone``) or by path to a JSON file (an existing file
    wins).

    Args:
        name_or_path: a name of :data:`SCRIPTS`, or the path of a script file.

    Returns:
        the validated :class:`Script` (:func:`script_from_dict`).

    Raises:
        ScriptError: (an :class:`nbst.errors.InputError`) no such file or built-in (with the
            nearest built-in names), a file that is not JSON, or anything the gate refuses: one
            line naming the file and the field.
    """
    s = str(name_or_path)
    p = Path(s)
    try:
        if p.is_file() or isinstance(name_or_path, Path):
            return script_from_dict(read_json(p), source=str(p))
        names = builtin_names()
        if s in names:
            src = f"<built-in {s}>"
            return script_from_dict(parse_json(builtin_text(s), src), source=src)
        if p.suffix.lower() == ".json" or "/" in s or p.exists():
            return script_from_dict(read_json(p), source=str(p))
    except ProblemError as e:
        raise ScriptError(e.source, e.field, e.reason) from None
    close = difflib.get_close_matches(s, names, n=3, cutoff=0.4)
    hint = f"; did you mean {', '.join(close)}?" if close else ""
    raise ScriptError(s, "", f"no such file and no built-in crash script of that name "
                             f"(built-ins: {', '.join(names)}){hint}")
