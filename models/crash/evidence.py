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
  (residual crush depth, the deepest of the vehicle's zones, for a vehicle whose type crushes:
  the ``-crush`` twins, ``sedan-crush`` and the like; a rigid type's is refused).

:func:`pieces` lists the evidence as pieces, each a target value and its tolerance;
:func:`jitter` moves each target by an error drawn within its tolerance (the model of the
evidence: every piece is known to within its tolerance, a uniform error; Wilkinson, *ABC gives
exact results under the assumption of model error*, SAGMB 12, 2013); :func:`distances` turns
one simulated crash into one distance per piece, in units of its tolerance (met at 1 or less).

Compute only.
"""
from __future__ import annotations

import copy
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from nbst.models.crash import script as script_mod
from nbst.models.crash.fields import Fields, ScriptError
from nbst.models.crash.outcome import _wrap
from nbst.problem import ProblemError, parse_json, read_json

__all__ = ["CASE_KIND", "FRICTION_SPREAD", "LOAD", "CONTACT_FACTOR", "SKID_RADIUS", "SKID_LENGTH_TOL",
           "EDR_TOL_KMH", "EDR_MAX_BEFORE", "CRUSH_TOL", "MISS", "Skid", "Edr", "Crush", "Unknowns", "Evidence",
           "Case", "case_from_dict", "load_case", "records_crush", "Piece", "pieces", "jitter", "distances", "labels"]

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
                c.fail(f"{p}.crush", f"vehicle type {v.vtype.name!r} records no residual crush (a rigid type): "
                                     "residual crush is evidence only for a type that crushes, e.g. 'sedan-crush'")
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


# --------------------------------------------------------------------------- the evidence as pieces

@dataclass(frozen=True)
class Piece:
    """One piece of evidence: its label (``A.rest``), the vehicle's index (None: the whole
    crash), its kind, its target ``value`` (a tuple: (x, y) of a position, (deg,) of a heading,
    (m,) of a length, (m/s,) of a speed) and its tolerance ``tol`` in the same unit; ``jitter``
    False: a yes/no piece (whom it hit, an order, a band) that no error moves."""

    label: str
    vehicle: int | None
    kind: str
    value: tuple
    tol: float
    jitter: bool = True


def pieces(case: Case) -> list[Piece]:
    """The evidence of ``case`` as :class:`Piece` s, in the order :func:`distances` returns them."""
    out: list[Piece] = []
    s = case.script
    for i, v in enumerate(s.vehicles):
        f, nm = v.fate, v.name
        if f.hits is not None:
            out.append(Piece(f"{nm}.hits", i, "hits", tuple(f.hits), 1.0, False))
        if f.impact_at is not None:
            out.append(Piece(f"{nm}.impact_at", i, "impact_at", (f.impact_at[0], f.impact_at[1]), f.impact_at[2]))
        if f.rest is not None:
            out.append(Piece(f"{nm}.rest", i, "rest", (f.rest[0], f.rest[1]), f.rest[2]))
        if f.heading is not None:
            out.append(Piece(f"{nm}.heading", i, "heading", (f.heading[0],), f.heading[1]))
        for key in ("impact_speed", "delta_v"):
            band = getattr(f, key)
            if band is not None:
                out.append(Piece(f"{nm}.{key}", i, key, ((band.lo + band.hi) / 2,),
                                 max((band.hi - band.lo) / 2, 1e-9), False))
        for key in ("quarter_turns", "attitude", "spin", "curb", "barrier"):
            if getattr(f, key) is not None:
                out.append(Piece(f"{nm}.{key}", i, key, (), 1.0, False))
        sk, ed, cr = case.evidence.skid[i], case.evidence.edr[i], case.evidence.crush[i]
        if sk is not None:
            out.append(Piece(f"{nm}.skid.start", i, "skid_start", (sk.x, sk.y), sk.radius))
            out.append(Piece(f"{nm}.skid.length", i, "skid_length", (sk.length,), sk.tol))
        if ed is not None:
            out.append(Piece(f"{nm}.edr", i, "edr", (ed.speed, ed.before), ed.tol))
        if cr is not None:
            out.append(Piece(f"{nm}.crush", i, "crush", (cr.depth,), cr.tol))
    if s.order is not None:
        out.append(Piece("order", None, "order", (), 1.0, False))
    return out


def labels(case: Case) -> list[str]:
    """The name of each entry :func:`distances` returns, in order."""
    return [p.label for p in pieces(case)]


def jitter(ps: list[Piece], rng: np.random.Generator, scale: float) -> list[Piece]:
    """The pieces with each movable target moved by an error drawn uniformly within ``scale``
    times its tolerance (a position: uniform in the disc; a scalar: uniform in the interval; an
    EDR's time before the impact stays)."""
    out = []
    for p in ps:
        if not p.jitter or scale <= 0:
            out.append(p)
            continue
        if len(p.value) == 2 and p.kind != "edr":
            r, a = scale * p.tol * math.sqrt(float(rng.random())), 2 * math.pi * float(rng.random())
            out.append(Piece(p.label, p.vehicle, p.kind, (p.value[0] + r * math.cos(a), p.value[1] + r * math.sin(a)),
                             p.tol, True))
        else:
            e = scale * p.tol * (2 * float(rng.random()) - 1)
            out.append(Piece(p.label, p.vehicle, p.kind, (p.value[0] + e,) + tuple(p.value[1:]), p.tol, True))
    return out


def _at(series: np.ndarray, t: float, period: float) -> float:
    """Linear interpolation of a per-period series at time t (s) (clamped to its ends)."""
    k = t / period
    if k <= 0:
        return float(series[0])
    j = min(int(k), len(series) - 2)
    a = min(k - j, 1.0)
    return float(series[j] * (1 - a) + series[j + 1] * a)


def distances(case: Case, ps: list[Piece], o, track: dict | None, s: int,
              min_dist: np.ndarray | None = None) -> np.ndarray:
    """One distance per piece of evidence ``ps`` (:func:`pieces`, maybe :func:`jitter` ed), in
    units of its tolerance (met at <= 1), for simulation ``s`` of a batch: ``o`` its judged
    Outcome, ``track`` the batch's per-period record (``pos`` (S, periods, n, 2), ``speed``
    (S, periods, n), ``locked`` (S, periods, n) bool: every wheel braked; None: no skid or EDR
    evidence asks for it); a contact that did not happen is :data:`MISS` plus the closest
    approach (m) in ``min_dist``."""
    sc = case.script
    pairs = [(i, j) for i in range(sc.n) for j in range(i + 1, sc.n)]
    out: list[float] = []
    for p in ps:
        if p.kind == "order":
            out.append(0.0 if o.order_ok else MISS)
            continue
        i = int(p.vehicle)  # type: ignore[arg-type]
        vo = o.vehicles[i]
        hit = bool(vo.hits) and math.isfinite(vo.impact_speed)
        k = p.kind
        if k == "hits":
            got = [j for j, _ in vo.hits]
            if got == list(p.value):
                out.append(0.0)
                continue
            near = 0.0
            if min_dist is not None:
                near = sum(min(float(min_dist[pairs.index((min(i, j), max(i, j)))]), MISS) for j in p.value)
            out.append(MISS + near)
        elif k == "impact_at":
            out.append(math.hypot(vo.impact_pos[0] - p.value[0], vo.impact_pos[1] - p.value[1]) / p.tol if hit else MISS)
        elif k == "rest":
            out.append(math.hypot(vo.rest[0] - p.value[0], vo.rest[1] - p.value[1]) / p.tol)
        elif k == "heading":
            out.append(abs(float(_wrap(vo.rest[2] - p.value[0]))) / p.tol)
        elif k in ("impact_speed", "delta_v"):
            val = vo.impact_speed if k == "impact_speed" else vo.delta_v
            out.append(abs(val - p.value[0]) / p.tol if math.isfinite(val) else MISS)
        elif k in ("quarter_turns", "attitude", "spin", "curb", "barrier"):
            out.append(0.0 if vo.fates.get(k, False) else 2.0)
        elif k in ("skid_start", "skid_length"):
            if not hit or track is None:
                out.append(MISS)
                continue
            start, length = _skid(track, s, i, vo.hits[0][1], vo.impact_pos)
            if start is None:
                out.append(MISS)
            elif k == "skid_start":
                out.append(math.hypot(start[0] - p.value[0], start[1] - p.value[1]) / p.tol)
            else:
                out.append(abs(length - p.value[0]) / p.tol)
        elif k == "edr":
            if not hit or track is None:
                out.append(MISS)
                continue
            out.append(abs(_at(track["speed"][s, :, i], vo.hits[0][1] - p.value[1], track["period"]) - p.value[0])
                       / p.tol)
        elif k == "crush":
            got_c = getattr(vo, "residual_crush", None)
            got_c = float(np.max(got_c)) if got_c is not None and np.size(got_c) else math.nan
            out.append(abs(got_c - p.value[0]) / p.tol if math.isfinite(got_c) else MISS)
        else:  # pragma: no cover - pieces() makes no other kind
            out.append(MISS)
    return np.array(out)


def _skid(track: dict, s: int, i: int, t_hit: float, impact_pos) -> tuple:
    """(start (x, y), length m) of a pre-impact skid: the first period before the impact with
    every wheel braked starts it; its length is the path from there to the impact position;
    (None, nan) when the wheels never locked before the impact."""
    k_hit = int(t_hit / track["period"])
    locked = np.flatnonzero(track["locked"][s, :k_hit + 1, i])
    if not len(locked):
        return None, math.nan
    k = int(locked[0])
    p = track["pos"][s, k:k_hit + 1, i]
    path = float(np.sum(np.hypot(*np.diff(p, axis=0).T))) if len(p) > 1 else 0.0
    path += math.hypot(impact_pos[0] - p[-1][0], impact_pos[1] - p[-1][1])
    return (float(p[0][0]), float(p[0][1])), path
