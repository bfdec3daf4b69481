"""A reconstruction case: the evidence, its tolerances, and the unknowns besides the drivers.

A case is a crash script (:mod:`.script`) whose fates are evidence (whom each vehicle hit, its
rest position and heading, its centre of mass at the impact, ``impact_at``), read through the
script's gate, plus, in a file of kind ``nbst-crash-case`` (docs/formats.md, "Crash evidence"),
two more top-level keys:

* ``unknowns``: what the reconstruction does not know besides the drivers' intents, each a
  range it draws from uniformly (a number fixes it): the road's ``friction`` (default: the
  script's +- :data:`FRICTION_SPREAD`), each vehicle's ``load`` (kg added to its type's mass,
  default :data:`LOAD`), and the body contact's ``stiffness`` and ``damping`` (factors on the
  vehicle type's contact stiffness and damping ratio; the damping ratio sets restitution;
  default :data:`CONTACT_FACTOR`);
* ``evidence``: per vehicle name, the evidence kinds the script's fates do not carry, each with
  its tolerance: ``skid`` (a pre-impact skid: where the marks start and their length up to the
  impact), ``edr`` (an event data recorder's speed some seconds before the impact) and ``crush``
  (residual crush depth, for a vehicle whose type records it).

:func:`distances` turns one simulated crash into one distance per piece of evidence, in units
of its tolerance (a piece is met at 1 or less): the reconstruction's ABC kernel.

Compute only.
"""
from __future__ import annotations

import copy
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from nbst.models.crash import driver as drv
from nbst.models.crash import script as script_mod
from nbst.models.crash.fields import Fields, ScriptError
from nbst.models.crash.outcome import _wrap
from nbst.problem import ProblemError, parse_json, read_json

__all__ = ["CASE_KIND", "FRICTION_SPREAD", "LOAD", "CONTACT_FACTOR", "SKID_RADIUS", "SKID_LENGTH_TOL",
           "EDR_TOL_KMH", "EDR_MAX_BEFORE", "CRUSH_TOL", "MISS", "PLANT_TEMPLATES", "PLANT_REST", "PLANT_HEADING",
           "PLANT_IMPACT", "planted", "Skid", "Edr", "Crush", "Unknowns", "Evidence",
           "Case", "case_from_dict", "load_case", "records_crush", "distances", "labels"]

CASE_KIND = "nbst-crash-case"
#: The road friction's default range: the script's friction +- this (a dry road's 0.8 gives
#: 0.7-0.9, the range dry asphalt is given for locked-wheel skids; docs/crash.md).
FRICTION_SPREAD = 0.1
#: Default load range (kg added to each vehicle's type mass: occupants and luggage).
LOAD = (0.0, 250.0)
#: Default range of the factors on the body contact's stiffness and damping ratio.
CONTACT_FACTOR = (0.8, 1.25)
#: Default tolerances: skid start (m), skid length (m), EDR speed (km/h), residual crush (m).
SKID_RADIUS, SKID_LENGTH_TOL, EDR_TOL_KMH, CRUSH_TOL = 1.0, 1.0, 2.0, 0.05
#: An event data recorder's pre-crash data reach 5 s back (US 49 CFR 563: -5.0 to 0 s).
EDR_MAX_BEFORE = 5.0
#: The distance of a piece of evidence the simulation cannot even compare (a contact that did
#: not happen, a skid that never started): far outside any tolerance.
MISS = 10.0
_LIMITS = {"load": (0.0, 2000.0), "factor": (0.1, 10.0), "radius": (0.05, 100.0), "length": (0.0, 500.0),
           "tol": (0.01, 100.0), "kmh": (0.0, 250.0), "tol_kmh": (0.1, 100.0), "depth": (0.0, 3.0),
           "crush_tol": (0.001, 1.0)}


@dataclass(frozen=True)
class Skid:
    """A pre-impact skid: its marks start at (x, y) within ``radius`` m (the centre of mass when
    the wheels locked) and run ``length`` +- ``tol`` m (the path from there to the impact)."""

    x: float
    y: float
    radius: float
    length: float
    tol: float


@dataclass(frozen=True)
class Edr:
    """An event data recorder's speed (m/s, +- ``tol`` m/s) ``before`` s before the first impact."""

    speed: float
    before: float
    tol: float


@dataclass(frozen=True)
class Crush:
    """Residual crush depth (m, +- ``tol``)."""

    depth: float
    tol: float


@dataclass(frozen=True)
class Unknowns:
    """Ranges (lo, hi) the reconstruction draws uniformly; lo == hi is fixed. ``load`` per vehicle (kg)."""

    friction: tuple
    load: tuple
    stiffness: tuple
    damping: tuple


@dataclass(frozen=True)
class Evidence:
    """Per vehicle (script order): its Skid, Edr, Crush or None."""

    skid: tuple
    edr: tuple
    crush: tuple


@dataclass(frozen=True)
class Case:
    """A reconstruction case: the script (its fates the evidence), the unknowns and the evidence kinds."""

    script: script_mod.Script
    unknowns: Unknowns
    evidence: Evidence
    raw: dict = field(default_factory=dict, repr=False)

    @property
    def n(self) -> int:
        return self.script.n


def records_crush(vtype) -> bool:
    """Whether a vehicle type records residual crush (the opt-in crush model)."""
    return bool(getattr(vtype, "crush", False))


def _range(c: Fields, v, path: str, lim: tuple, why: str) -> tuple:
    return c.range(v, path, lim[0], lim[1], why)


def case_from_dict(d: Any, *, source: str = "<dict>") -> Case:
    """Validate a reconstruction case (``nbst-crash-case``, or a plain ``nbst-crash-script`` whose
    fates are the evidence and whose unknowns take their defaults).

    Args:
        d: the decoded JSON object.
        source: how a refusal names the case (its file name).

    Returns:
        the :class:`Case`.

    Raises:
        ScriptError: (an :class:`nbst.errors.InputError`) one line naming ``source``, the field
            and the problem: anything the script's gate refuses, and in ``unknowns`` and
            ``evidence`` unknown keys and vehicles, numbers out of their domain, a skid for a
            driver who never brakes before the impact, residual crush for a vehicle type that
            records none.
    """
    c = Fields(source)
    if not isinstance(d, dict):
        c.fail("", "must be a JSON object (an nbst-crash-case or nbst-crash-script)")
    d = copy.deepcopy(d)
    extra: dict = {}
    if d.get("kind") == CASE_KIND:
        c.obj(d, "", script_mod.TOP_KEYS + ("unknowns", "evidence"))
        extra = {k: d.pop(k) for k in ("unknowns", "evidence") if k in d}
        d["kind"] = script_mod.KIND
    s = script_mod.script_from_dict(d, source=source)
    names = s.names()
    u = extra.get("unknowns", {})
    c.obj(u, "unknowns", ("friction", "load", "stiffness", "damping"))
    mu = s.road.friction
    lo_hi = script_mod.LIMITS["friction"]
    fr = (_range(c, u["friction"], "unknowns.friction", lo_hi, "tyre-road friction") if "friction" in u
          else (max(lo_hi[0], mu - FRICTION_SPREAD), min(lo_hi[1], mu + FRICTION_SPREAD)))
    load = LOAD
    if "load" in u:
        load = _range(c, u["load"], "unknowns.load", _LIMITS["load"], "kg added to each vehicle")
    st = _range(c, u["stiffness"], "unknowns.stiffness", _LIMITS["factor"], "factor") if "stiffness" in u \
        else CONTACT_FACTOR
    dm = _range(c, u["damping"], "unknowns.damping", _LIMITS["factor"], "factor") if "damping" in u \
        else CONTACT_FACTOR
    ev = extra.get("evidence", {})
    c.obj(ev, "evidence", tuple(names))
    skid: list = [None] * s.n
    edr: list = [None] * s.n
    crush: list = [None] * s.n
    for nm, e in ev.items():
        i = names.index(nm)
        p = f"evidence.{nm}"
        v = s.vehicles[i]
        c.obj(e, p, ("skid", "edr", "crush"))
        if not v.fate.hits:
            c.fail(p, "evidence of an impact for a vehicle whose fate lists no hits")
        if "skid" in e:
            k = c.obj(e["skid"], f"{p}.skid", ("x", "y", "radius", "length", "length_tol"),
                      required=("x", "y", "length"))
            if v.driver.brake_at is None:
                c.fail(f"{p}.skid", "the driver never brakes before the impact: give driver.brake_at a range "
                                    "that a skid could start in")
            skid[i] = Skid(c.number(k["x"], f"{p}.skid.x"), c.number(k["y"], f"{p}.skid.y"),
                           c.number(k.get("radius", SKID_RADIUS), f"{p}.skid.radius", *_LIMITS["radius"], "m"),
                           c.number(k["length"], f"{p}.skid.length", *_LIMITS["length"], "m"),
                           c.number(k.get("length_tol", SKID_LENGTH_TOL), f"{p}.skid.length_tol", *_LIMITS["tol"],
                                    "m"))
        if "edr" in e:
            k = c.obj(e["edr"], f"{p}.edr", ("speed", "before", "tol"), required=("speed", "before"))
            edr[i] = Edr(c.number(k["speed"], f"{p}.edr.speed", *_LIMITS["kmh"], "km/h") / 3.6,
                         c.number(k["before"], f"{p}.edr.before", 0.0, EDR_MAX_BEFORE,
                                  "s before the impact; pre-crash data reach 5 s"),
                         c.number(k.get("tol", EDR_TOL_KMH), f"{p}.edr.tol", *_LIMITS["tol_kmh"], "km/h") / 3.6)
        if "crush" in e:
            k = c.obj(e["crush"], f"{p}.crush", ("depth", "tol"), required=("depth",))
            if not records_crush(v.vtype):
                c.fail(f"{p}.crush", f"vehicle type {v.vtype.name!r} records no residual crush (crush is off for "
                                     "it): residual crush is evidence only for a type that records it")
            crush[i] = Crush(c.number(k["depth"], f"{p}.crush.depth", *_LIMITS["depth"], "m"),
                             c.number(k.get("tol", CRUSH_TOL), f"{p}.crush.tol", *_LIMITS["crush_tol"], "m"))
    return Case(script=s, unknowns=Unknowns(friction=fr, load=load, stiffness=st, damping=dm),
                evidence=Evidence(skid=tuple(skid), edr=tuple(edr), crush=tuple(crush)), raw=extra)


def load_case(name_or_path: str | Path) -> Case:
    """A reconstruction case by path (a JSON file) or built-in script name (``crossing-case``).

    Args:
        name_or_path: the path of an ``nbst-crash-case`` or ``nbst-crash-script`` file, or a
            built-in script name.

    Returns:
        the :class:`Case` (:func:`case_from_dict`).

    Raises:
        ScriptError: (an :class:`nbst.errors.InputError`) no such file or built-in, not JSON, or
            anything :func:`case_from_dict` refuses: one line naming the file and the field.
    """
    s = str(name_or_path)
    p = Path(s)
    if not p.is_file() and s in script_mod.builtin_names():
        src = f"<built-in {s}>"
        try:
            return case_from_dict(parse_json(script_mod.builtin_text(s), src), source=src)
        except ProblemError as e:
            raise ScriptError(e.source, e.field, e.reason) from None
    if not p.is_file():
        script_mod.load_script(s)  # its one-line refusal: no such file, the nearest built-in names
    try:
        return case_from_dict(read_json(p), source=str(p))
    except ProblemError as e:
        raise ScriptError(e.source, e.field, e.reason) from None


# --------------------------------------------------------------------------- the kernel

def labels(case: Case) -> list[str]:
    """The name of each entry :func:`distances` returns, in order."""
    out = []
    s = case.script
    for i, v in enumerate(s.vehicles):
        f, nm = v.fate, v.name
        if f.hits is not None:
            out.append(f"{nm}.hits")
        for key in ("impact_at", "rest", "heading", "impact_speed", "delta_v", "quarter_turns", "attitude", "spin",
                    "curb", "barrier"):
            if getattr(f, key) is not None:
                out.append(f"{nm}.{key}")
        if case.evidence.skid[i] is not None:
            out += [f"{nm}.skid.start", f"{nm}.skid.length"]
        if case.evidence.edr[i] is not None:
            out.append(f"{nm}.edr")
        if case.evidence.crush[i] is not None:
            out.append(f"{nm}.crush")
    if s.order is not None:
        out.append("order")
    return out


def _at(series: np.ndarray, t: float) -> float:
    """Linear interpolation of a per-period series at time t (s) (clamped to its ends)."""
    k = t / drv.PERIOD
    if k <= 0:
        return float(series[0])
    j = min(int(k), len(series) - 2)
    a = min(k - j, 1.0)
    return float(series[j] * (1 - a) + series[j + 1] * a)


def distances(case: Case, o, track: dict, s: int, min_dist: np.ndarray | None = None) -> np.ndarray:
    """One distance per piece of evidence (:func:`labels`), in units of its tolerance (met at
    <= 1), for simulation ``s`` of a batch: ``o`` its judged Outcome, ``track`` the batch's
    per-period record (``pos`` (S, periods, n, 2), ``speed`` (S, periods, n), ``locked``
    (S, periods, n) bool: every wheel braked); a contact that did not happen is :data:`MISS`
    plus the closest approach (m) in ``min_dist``."""
    sc = case.script
    pairs = [(i, j) for i in range(sc.n) for j in range(i + 1, sc.n)]
    out: list[float] = []
    for i, (vs, vo) in enumerate(zip(sc.vehicles, o.vehicles)):
        f = vs.fate
        got = [j for j, _ in vo.hits]
        hits_ok = f.hits is None or got == list(f.hits)
        if f.hits is not None:
            near = 0.0
            if not hits_ok and min_dist is not None:
                near = sum(min(float(min_dist[pairs.index((min(i, j), max(i, j)))]), MISS) for j in f.hits)
            out.append(0.0 if hits_ok else MISS + near)
        hit = bool(vo.hits) and math.isfinite(vo.impact_speed)
        if f.impact_at is not None:
            out.append(math.hypot(vo.impact_pos[0] - f.impact_at[0], vo.impact_pos[1] - f.impact_at[1]) / f.impact_at[2]
                       if hit else MISS)
        if f.rest is not None:
            out.append(math.hypot(vo.rest[0] - f.rest[0], vo.rest[1] - f.rest[1]) / f.rest[2])
        if f.heading is not None:
            out.append(abs(float(_wrap(vo.rest[2] - f.heading[0]))) / f.heading[1])
        for key, val in (("impact_speed", vo.impact_speed), ("delta_v", vo.delta_v)):
            band = getattr(f, key)
            if band is not None:
                half = max((band.hi - band.lo) / 2, 1e-9)
                out.append(abs(val - (band.lo + band.hi) / 2) / half if math.isfinite(val) else MISS)
        for key in ("quarter_turns", "attitude", "spin", "curb", "barrier"):
            if getattr(f, key) is not None:
                out.append(0.0 if vo.fates.get(key, False) else 2.0)
        sk, ed, cr = case.evidence.skid[i], case.evidence.edr[i], case.evidence.crush[i]
        t_hit = vo.hits[0][1] if vo.hits else math.nan
        if sk is not None:
            out += list(_skid(sk, track, s, i, t_hit, vo.impact_pos) if hit else (MISS, MISS))
        if ed is not None:
            out.append(abs(_at(track["speed"][s, :, i], t_hit - ed.before) - ed.speed) / ed.tol if hit else MISS)
        if cr is not None:
            got_c = getattr(vo, "residual_crush", None)
            got_c = float(np.max(got_c)) if got_c is not None and np.size(got_c) else math.nan
            out.append(abs(got_c - cr.depth) / cr.tol if math.isfinite(got_c) else MISS)
    if sc.order is not None:
        out.append(0.0 if o.order_ok else MISS)
    return np.array(out)


def _skid(sk: Skid, track: dict, s: int, i: int, t_hit: float, impact_pos) -> tuple[float, float]:
    """(start, length) distances of a pre-impact skid: the first period before the impact with
    every wheel braked starts it; its length is the path from there to the impact position."""
    k_hit = int(t_hit / drv.PERIOD)
    locked = np.flatnonzero(track["locked"][s, :k_hit + 1, i])
    if not len(locked):
        return MISS, MISS
    k = int(locked[0])
    p = track["pos"][s, k:k_hit + 1, i]
    path = float(np.sum(np.hypot(*np.diff(p, axis=0).T))) if len(p) > 1 else 0.0
    path += math.hypot(impact_pos[0] - p[-1][0], impact_pos[1] - p[-1][1])
    start = math.hypot(p[0][0] - sk.x, p[0][1] - sk.y) / sk.radius
    return start, abs(path - sk.length) / sk.tol


# --------------------------------------------------------------------------- planted cases

_STRAIGHT = {"layout": "straight", "width": 7, "length": 200}
#: Two-car templates of the coverage benchmark (benchmarks/bench_reconstruct.py) and the tests:
#: a 90 degree crossing, a 30 degree oblique on a wide plaza, an offset head-on and a same-lane rear-end.
PLANT_TEMPLATES = {
    "crossing": {
        "kind": "nbst-crash-script", "road": {"layout": "intersection", "width": 7, "length": 120, "curb": 0.15},
        "duration": 5.5,
        "vehicles": [
            {"name": "A", "type": "sedan", "start": {"x": -45, "y": -1.75, "heading": 0}, "speed": [30, 80],
             "driver": {"aim": {"x": [-3, 6], "y": [-3, 0]}, "arrive": [2.2, 4.0], "after_impact": "brake"}},
            {"name": "B", "type": "suv", "start": {"x": 1.75, "y": -45, "heading": 90}, "speed": [30, 80],
             "driver": {"aim": {"x": [0, 3], "y": [-3, 6]}, "arrive": [2.2, 4.0], "after_impact": "brake"}}]},
    "oblique": {
        "kind": "nbst-crash-script", "road": {"layout": "straight", "width": 30, "length": 160}, "duration": 5.5,
        "vehicles": [
            {"name": "A", "type": "sedan", "start": {"x": -40, "y": 0, "heading": 0}, "speed": [40, 80],
             "driver": {"aim": {"x": [-2, 3], "y": [-1.5, 1.5]}, "arrive": [2.2, 3.2], "after_impact": "brake"}},
            {"name": "B", "type": "suv", "start": {"x": -22, "y": -12, "heading": 30}, "speed": [30, 60],
             "driver": {"aim": {"x": [-2, 3], "y": [-2, 2]}, "arrive": [2.2, 3.2], "after_impact": "brake"}}]},
    "head-on": {
        "kind": "nbst-crash-script", "road": _STRAIGHT, "duration": 4.5,
        "vehicles": [
            {"name": "A", "type": "sedan", "start": {"x": -30, "y": -1.75, "heading": 0}, "speed": [30, 70],
             "driver": {"aim": {"x": [10, 30], "y": [0.0, 2.5]}, "after_impact": "brake"}},
            {"name": "B", "type": "suv", "start": {"x": 30, "y": 1.75, "heading": 180}, "speed": [30, 70],
             "driver": {"after_impact": "brake"}}]},
    "rear-end": {
        "kind": "nbst-crash-script", "road": _STRAIGHT, "duration": 5.0,
        "vehicles": [
            {"name": "A", "type": "sedan", "start": {"x": 0, "y": -1.75, "heading": 0}, "speed": [30, 50],
             "driver": {"after_impact": "brake"}},
            {"name": "B", "type": "suv", "start": {"x": -12, "y": -1.75, "heading": 0}, "speed": [70, 90],
             "driver": {"after_impact": "brake"}}]},
}
#: The evidence's tolerances of a planted case: rest (m), heading at rest (deg), impact position (m).
PLANT_REST, PLANT_HEADING, PLANT_IMPACT = 1.5, 15.0, 1.0


def planted(template: str, seed: int, *, impact_at: bool = True, friction: tuple = (0.7, 0.9)) -> tuple[dict, dict]:
    """(case dict, truth): hidden intents, road friction (uniform in ``friction``, which the case
    states as its range but not the value), loads and contact factors (uniform in the defaults),
    simulated; what happened written as the evidence (whom each hit, rest within
    :data:`PLANT_REST`, heading within :data:`PLANT_HEADING`, with ``impact_at`` the impact
    positions within :data:`PLANT_IMPACT`). The truth: per vehicle impact speed and delta-V
    (m/s), PDOF (h), and the friction."""
    from nbst.models.crash import reconstruct as rc
    from nbst.models.crash.space import space_of

    d = copy.deepcopy(PLANT_TEMPLATES[template])
    d["name"] = f"planted-{template}-{seed}"
    d["kind"] = CASE_KIND
    d["unknowns"] = {"friction": list(friction)}
    case = case_from_dict(d, source="<planted>")
    S = space_of(case.script)
    pc = rc.phys_coords(case)
    rng = np.random.default_rng([int(seed), 470])
    R = rc.AbcRunner(case)
    try:
        for _ in range(64):
            Z = rng.random((16, S.dim + len(pc)))
            phys = rc._phys_values(case, Z[:, S.dim:])
            rolls, track = R.run_phys(S.intents(Z[:, :S.dim]), phys)
            for k, o in enumerate(rolls.outcomes):
                if len(o.contacts) != 1 or any(v.moving or not v.hits for v in o.vehicles):
                    continue
                mass = R.L.mass + phys["load"][k]
                q = rc._quantities(case, o, track, k, mass)
                names = case.script.names()
                for v, vo in zip(d["vehicles"], o.vehicles):
                    v["fate"] = {"hits": [names[j] for j, _ in vo.hits],
                                 "rest": {"x": round(vo.rest[0], 3), "y": round(vo.rest[1], 3), "radius": PLANT_REST},
                                 "heading": {"deg": round(math.degrees(vo.rest[2]), 2), "tol": PLANT_HEADING}}
                    if impact_at:
                        v["fate"]["impact_at"] = {"x": round(vo.impact_pos[0], 3), "y": round(vo.impact_pos[1], 3),
                                                  "radius": PLANT_IMPACT}
                truth = {"vehicles": [{"impact_speed": float(q[3 * i]), "delta_v": float(q[3 * i + 1]),
                                       "pdof": float(q[3 * i + 2])} for i in range(case.n)],
                         "closing_speed": float(q[-1]), "friction": float(phys["friction"][k]),
                         "load": [float(x) for x in phys["load"][k]]}
                return d, truth
    finally:
        R.close()
    raise ProblemError("<planted>", "", f"no single-contact crash of template {template!r} at seed {seed}")
