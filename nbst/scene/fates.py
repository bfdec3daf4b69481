"""The fates file (``"format": "nbst-fates"``, version 1): what must happen in a user's MJCF scene.

:func:`parse_fates` checks every field of the JSON document (the names of issue 46, kept: scenes
written by others are tried against them; an unknown key, a typo, is refused by name) and returns
frozen dataclasses (:class:`Fates`, :class:`Control`, :class:`Fate`, :class:`Region`,
:class:`Range3`). Refused: a missing or unknown key, a value of the wrong type, a NaN or infinite
number or one past :data:`MAX_ABS` (an integer literal of more than 15 digits is refused before it
is built), a key given twice in one object, an inverted range (lo > hi) or one that is not two numbers (an empty one), a region of
zero or negative size, an ``"at"`` time after the duration. Every refusal is one line naming the
file and the field: :class:`FatesError` (an ``InputError``), exit 2. The scene side (the MJCF's
files, MuJoCo's compilation, the names) is ``nbst.scene.scenefile``, whose ``load_fates`` is the
way in.

The stated thresholds are module constants (docs/scene.md lists them): :data:`AT_REST_SPEED`
and :data:`AT_REST_SPIN` (``"at_rest"``), :data:`STILL_DISTANCE` (``"still"``), :data:`MAX_STEPS`
(duration / timestep), :data:`MAX_MESH_BYTES`, :data:`DEFAULT_NOISE` (``"noise"``).

No MuJoCo here. Length: the schema is read in one place, each field's check beside its parse
(a second module would split one format's rules); about 550 lines.
"""
from __future__ import annotations

import difflib
import json
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from nbst.errors import InputError
from nbst.files import read_regular

__all__ = ["FORMAT", "VERSION", "AT_REST_SPEED", "AT_REST_SPIN", "STILL_DISTANCE", "MAX_STEPS", "MAX_MESH_BYTES",
           "MAX_FATES_BYTES", "MAX_SCENE_BYTES", "MAX_ABS", "DEFAULT_NOISE", "FatesError", "Region", "Range3",
           "Control", "Fate", "Fates", "parse_fates", "read_fates_json"]

FORMAT = "nbst-fates"
VERSION = 1

#: ``"at_rest"``: at the end the body's origin moves slower than this (m/s) ...
AT_REST_SPEED = 0.05
#: ... and it turns slower than this (rad/s).
AT_REST_SPIN = 0.5
#: ``"still"``: the body's origin never moves farther than this from where it started (m): 1 cm.
STILL_DISTANCE = 0.01
#: The most steps one rollout may take (duration / timestep, rounded).
MAX_STEPS = 100_000
#: The largest mesh file a scene may load (bytes).
MAX_MESH_BYTES = 16 * 2**20
#: The largest fates file and the largest MJCF (or included) file read (bytes).
MAX_FATES_BYTES = 2**20
MAX_SCENE_BYTES = 8 * 2**20
#: The largest magnitude of any number in a fates file (a typo of 1e300 is refused).
MAX_ABS = 1e6
#: The noise used for a probability when the file gives none: sigma per control coordinate
#: (m/s for linvel, rad/s for angvel, m for pos).
DEFAULT_NOISE = {"linvel": 0.02, "angvel": 0.2, "pos": 0.001}

_TOP = ("format", "version", "scene", "keyframe", "timestep", "duration", "controls", "fates", "noise",
        "description")
_CONTROL = ("linvel", "angvel", "pos")
_FATE = ("rest_in", "at", "through", "up", "hits", "never_hits", "at_rest", "still")


class FatesError(InputError):
    """A fates file (or its scene) nbst refuses: one line, ``FILE: FIELD: why``."""

    def __init__(self, source: str | os.PathLike, field: str, why: str):
        self.source, self.field, self.why = str(source), field, why
        super().__init__(f"{self.source}: {field + ': ' if field else ''}{why}")


@dataclass(frozen=True)
class Region:
    """A region of space: a ball (``center``, ``radius``) or a box (``lo``, ``hi``), metres.

    Args:
        center: (3,) the ball's centre (None for a box).
        radius: the ball's radius > 0 (0.0 for a box).
        lo: (3,) the box's lower corner (None for a ball).
        hi: (3,) the box's upper corner, each above ``lo``.
    """

    center: tuple[float, float, float] | None = None
    radius: float = 0.0
    lo: tuple[float, float, float] | None = None
    hi: tuple[float, float, float] | None = None

    def distance(self, p: np.ndarray) -> np.ndarray:
        """Distance (m) from points ``p`` (..., 3) to the region: 0 inside."""
        p = np.asarray(p, dtype=float)
        if self.center is not None:
            return np.maximum(np.linalg.norm(p - np.asarray(self.center), axis=-1) - self.radius, 0.0)
        assert self.lo is not None and self.hi is not None
        gap = np.maximum(np.maximum(np.asarray(self.lo) - p, p - np.asarray(self.hi)), 0.0)
        return np.asarray(np.linalg.norm(gap, axis=-1))

    def mid(self) -> np.ndarray:
        """(3,) the region's centre."""
        if self.center is not None:
            return np.asarray(self.center, dtype=float)
        return (np.asarray(self.lo, dtype=float) + np.asarray(self.hi, dtype=float)) / 2

    def to_dict(self) -> dict:
        if self.center is not None:
            return {"center": list(self.center), "radius": self.radius}
        return {"min": list(self.lo or ()), "max": list(self.hi or ())}


def _apart(a: Region, b: Region) -> bool:
    """Whether two regions share no point (touching is sharing): a ball is apart from the other region
    when its centre lies farther than its radius from it; two boxes when apart along some axis."""
    if a.center is None and b.center is None:
        return bool(np.any(np.asarray(a.lo) > np.asarray(b.hi)) or np.any(np.asarray(b.lo) > np.asarray(a.hi)))
    ball, other = (a, b) if a.center is not None else (b, a)
    return float(other.distance(np.asarray(ball.center))) > ball.radius


@dataclass(frozen=True)
class Range3:
    """Three closed ranges ``[lo[k], hi[k]]`` (lo == hi fixes that coordinate)."""

    lo: tuple[float, float, float]
    hi: tuple[float, float, float]

    def to_list(self) -> list[list[float]]:
        return [[a, b] for a, b in zip(self.lo, self.hi)]


@dataclass(frozen=True)
class Control:
    """What the search may choose for one body with a free joint (None: as in the model).

    Args:
        body: the body's name.
        linvel: world-frame linear velocity ranges (m/s) of the body's origin.
        angvel: world-frame angular velocity ranges (rad/s).
        pos: offsets (m) from the model's (or keyframe's) position.
        noise: sigma per coordinate, in the order linvel, angvel, pos (the ranges given).
    """

    body: str
    linvel: Range3 | None
    angvel: Range3 | None
    pos: Range3 | None
    noise: tuple[float, ...]

    def parts(self) -> list[tuple[str, Range3]]:
        """The ranges given, in the block's order: ``[("linvel", r), ("angvel", r), ("pos", r)]``."""
        return [(k, r) for k, r in (("linvel", self.linvel), ("angvel", self.angvel), ("pos", self.pos))
                if r is not None]

    @property
    def size(self) -> int:
        """Coordinates in this body's block of the controls vector."""
        return 3 * len(self.parts())


@dataclass(frozen=True)
class Fate:
    """What must happen to one body (None / empty / False: not asked). See docs/scene.md.

    Args:
        body: the body's name.
        rest_in: the region it is in at the end.
        at: ``((t, region), ...)``: where it is at time t.
        through: regions passed in this order.
        up: ``(axis (3,) unit body-frame vector, within_deg)``: that axis ends pointing up.
        hits: names (bodies or geoms) whose first touches come in this order.
        never_hits: names it never touches.
        at_rest: it ends still (:data:`AT_REST_SPEED`, :data:`AT_REST_SPIN`).
        still: it never moves more than :data:`STILL_DISTANCE`.
    """

    body: str
    rest_in: Region | None = None
    at: tuple[tuple[float, Region], ...] = ()
    through: tuple[Region, ...] = ()
    up: tuple[tuple[float, float, float], float] | None = None
    hits: tuple[str, ...] = ()
    never_hits: tuple[str, ...] = ()
    at_rest: bool = False
    still: bool = False

    def asks(self) -> list[str]:
        """The fates asked, in the file's vocabulary."""
        return [k for k, v in (("rest_in", self.rest_in), ("at", self.at), ("through", self.through),
                               ("up", self.up), ("hits", self.hits), ("never_hits", self.never_hits),
                               ("at_rest", self.at_rest), ("still", self.still)) if v]


@dataclass(frozen=True)
class Fates:
    """A checked fates file.

    Args:
        source: the fates file (or built-in name) it was read from.
        scene: the MJCF file, resolved.
        keyframe: the model's key to start from (None: the model's default pose).
        timestep: the timestep (s) to simulate with (None: the model's).
        duration: seconds simulated.
        controls: what the search may choose, one block per body, in the file's order.
        fates: what must happen, one per body with fates (one signature bit each), in the file's order.
        description: free text.
    """

    source: str
    scene: Path
    keyframe: str | None
    timestep: float | None
    duration: float
    controls: tuple[Control, ...]
    fates: tuple[Fate, ...]
    description: str = ""

    @property
    def dim(self) -> int:
        """Length of the controls vector (the blocks of :attr:`controls`, one after another)."""
        return sum(c.size for c in self.controls)

    def blocks(self) -> list[slice]:
        """Each control's slice of the controls vector."""
        out, a = [], 0
        for c in self.controls:
            out.append(slice(a, a + c.size))
            a += c.size
        return out

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """(lo (D,), hi (D,)) of the controls vector."""
        lo = [x for c in self.controls for _, r in c.parts() for x in r.lo]
        hi = [x for c in self.controls for _, r in c.parts() for x in r.hi]
        return np.array(lo, dtype=float), np.array(hi, dtype=float)

    def noise(self) -> np.ndarray:
        """(D,) sigma per coordinate of the controls vector."""
        return np.array([s for c in self.controls for s in c.noise], dtype=float)


# --------------------------------------------------------------------------- reading

class _Src:
    """The file being read, for messages."""

    def __init__(self, source: str):
        self.source = source

    def fail(self, field: str, why: str) -> FatesError:
        return FatesError(self.source, field, why)


class _Bad:
    """A number the parser read and refuses (NaN, Infinity, an integer of over 15 digits): kept in
    place so that the loader names its field."""

    def __init__(self, why: str):
        self.why = why


class _Twice(dict):
    """An object with a key given twice (the last kept): kept so that the loader names its field."""

    why = ""


def _reject_constant(s: str) -> _Bad:
    return _Bad(f"{s} is not a finite number")


def _unique_keys(pairs: list[tuple[str, Any]]) -> dict:
    out: dict = {}
    twice = None
    for k, v in pairs:
        if k in out and twice is None:
            twice = k
        out[k] = v
    if twice is None:
        return out
    marked = _Twice(out)
    marked.why = f"the key {twice!r} appears twice in one object"
    return marked


def _parse_int(s: str) -> int | _Bad:
    if len(s.lstrip("-")) > 15:
        return _Bad(f"the integer {s[:20]}... has more than 15 digits")
    return int(s)


def _first_refused(obj: Any, field: str = "") -> tuple[str, str] | None:
    """(the field, why) of the first value the parser refused in ``obj``, depth first, or None."""
    if isinstance(obj, (_Bad, _Twice)):
        return field, obj.why
    if isinstance(obj, dict):
        subs = ((f"{field}.{k}" if field else k, v) for k, v in obj.items())
    elif isinstance(obj, list):
        subs = ((f"{field}[{i}]", v) for i, v in enumerate(obj))
    else:
        return None
    return next((found for sub, v in subs if (found := _first_refused(v, sub)) is not None), None)


def _keys(src: _Src, obj: Any, field: str, allowed: tuple[str, ...], required: tuple[str, ...] = ()) -> dict:
    if not isinstance(obj, dict):
        raise src.fail(field, f"must be a JSON object, not {type(obj).__name__}")
    for k in obj:
        if k not in allowed:
            near = difflib.get_close_matches(str(k), allowed, n=1)
            hint = f" (did you mean {near[0]!r}?)" if near else f" (known: {', '.join(allowed)})"
            raise src.fail(f"{field}.{k}" if field else str(k), f"unknown key{hint}")
    for k in required:
        if k not in obj:
            raise src.fail(f"{field}.{k}" if field else k, "missing")
    return obj


def _num(src: _Src, x: Any, field: str, *, positive: bool = False, nonneg: bool = False) -> float:
    if isinstance(x, bool) or not isinstance(x, (int, float)):
        raise src.fail(field, f"must be a number, not {json.dumps(x)[:40]}")
    v = float(x)
    if not math.isfinite(v):
        raise src.fail(field, "must be a finite number")
    if abs(v) > MAX_ABS:
        raise src.fail(field, f"{x!r} is larger in magnitude than {MAX_ABS:g}")
    if positive and not v > 0:
        raise src.fail(field, f"must be > 0, got {x!r}")
    if nonneg and v < 0:
        raise src.fail(field, f"must be >= 0, got {x!r}")
    return v


def _vec3(src: _Src, x: Any, field: str) -> tuple[float, float, float]:
    if not isinstance(x, list) or len(x) != 3:
        raise src.fail(field, "must be a list of 3 numbers [x, y, z]")
    a, b, c = (_num(src, v, f"{field}[{k}]") for k, v in enumerate(x))
    return (a, b, c)


def _range3(src: _Src, x: Any, field: str) -> Range3:
    if not isinstance(x, list) or len(x) != 3:
        raise src.fail(field, "must be 3 ranges [[lo, hi], [lo, hi], [lo, hi]] (x, y, z)")
    lo, hi = [], []
    for k, r in enumerate(x):
        if not isinstance(r, list) or len(r) != 2:
            raise src.fail(f"{field}[{k}]", "must be a range [lo, hi] of two numbers"
                           + (" (it is empty)" if r == [] else ""))
        a, b = _num(src, r[0], f"{field}[{k}][0]"), _num(src, r[1], f"{field}[{k}][1]")
        if a > b:
            raise src.fail(f"{field}[{k}]", f"inverted range [{r[0]!r}, {r[1]!r}]: lo must be <= hi")
        lo.append(a)
        hi.append(b)
    return Range3(lo=(lo[0], lo[1], lo[2]), hi=(hi[0], hi[1], hi[2]))


def _region(src: _Src, x: Any, field: str) -> Region:
    both = isinstance(x, dict) and bool({"center", "radius"} & set(x)) and bool({"min", "max"} & set(x))
    if isinstance(x, dict) and "center" in x and not both:
        _keys(src, x, field, ("center", "radius"), ("center", "radius"))
        r = _num(src, x["radius"], f"{field}.radius")
        if not r > 0:
            raise src.fail(f"{field}.radius", f"a region must have a positive size, got radius {x['radius']!r}")
        return Region(center=_vec3(src, x["center"], f"{field}.center"), radius=r)
    if isinstance(x, dict) and ("min" in x or "max" in x) and not both:
        _keys(src, x, field, ("min", "max"), ("min", "max"))
        lo, hi = _vec3(src, x["min"], f"{field}.min"), _vec3(src, x["max"], f"{field}.max")
        for k in range(3):
            if not hi[k] > lo[k]:
                raise src.fail(f"{field}.max[{k}]", f"a region must have a positive size: max {hi[k]!r} is not above min {lo[k]!r}")
        return Region(lo=lo, hi=hi)
    raise src.fail(field, 'a region is a ball {"center": [x, y, z], "radius": r} or a box {"min": [x, y, z], '
                          '"max": [x, y, z]}' + (", not both" if both else ""))


def _names(src: _Src, x: Any, field: str) -> tuple[str, ...]:
    if not isinstance(x, list) or not x or not all(isinstance(n, str) and n for n in x):
        raise src.fail(field, "must be a non-empty list of body or geom names")
    if len(set(x)) != len(x):
        raise src.fail(field, "names a body or geom twice")
    return tuple(x)


def _flag(src: _Src, x: Any, field: str) -> bool:
    if not isinstance(x, bool):
        raise src.fail(field, "must be true or false")
    return x


def _fate(src: _Src, body: str, x: Any) -> Fate:
    f = f"fates.{body}"
    _keys(src, x, f, _FATE)
    if not x:
        raise src.fail(f, f"asks nothing; give one of {', '.join(_FATE)}")
    at: list[tuple[float, Region]] = []
    if "at" in x:
        if not isinstance(x["at"], list) or not x["at"]:
            raise src.fail(f"{f}.at", 'must be a non-empty list of {"t": seconds, "in": REGION}')
        for k, a in enumerate(x["at"]):
            _keys(src, a, f"{f}.at[{k}]", ("t", "in"), ("t", "in"))
            at.append((_num(src, a["t"], f"{f}.at[{k}].t", nonneg=True), _region(src, a["in"], f"{f}.at[{k}].in")))
            for j, (t, r) in enumerate(at[:-1]):
                if t == at[-1][0] and _apart(r, at[-1][1]):
                    raise src.fail(f"{f}.at[{k}]", f"asks the body at t = {t:g} s in a region apart from at[{j}]'s "
                                   "at the same time: both can never be met")
    through: tuple[Region, ...] = ()
    if "through" in x:
        if not isinstance(x["through"], list) or not x["through"]:
            raise src.fail(f"{f}.through", "must be a non-empty list of regions")
        through = tuple(_region(src, r, f"{f}.through[{k}]") for k, r in enumerate(x["through"]))
    up = None
    if "up" in x:
        _keys(src, x["up"], f"{f}.up", ("axis", "within_deg"), ("axis", "within_deg"))
        axis = np.array(_vec3(src, x["up"]["axis"], f"{f}.up.axis"))
        n = float(np.linalg.norm(axis))
        if not n > 1e-9:
            raise src.fail(f"{f}.up.axis", "must not be zero")
        d = _num(src, x["up"]["within_deg"], f"{f}.up.within_deg", positive=True)
        if d > 180:
            raise src.fail(f"{f}.up.within_deg", f"must be in (0, 180], got {x['up']['within_deg']!r}")
        u = axis / n
        up = ((float(u[0]), float(u[1]), float(u[2])), d)
    hits = _names(src, x["hits"], f"{f}.hits") if "hits" in x else ()
    never = _names(src, x["never_hits"], f"{f}.never_hits") if "never_hits" in x else ()
    if both := [n for n in never if n in hits]:
        raise src.fail(f"{f}.never_hits", f"{both[0]!r} is in hits too: no motion can both touch it and not")
    fate = Fate(body=body, rest_in=_region(src, x["rest_in"], f"{f}.rest_in") if "rest_in" in x else None,
                at=tuple(at), through=through, up=up, hits=hits, never_hits=never,
                at_rest=_flag(src, x["at_rest"], f"{f}.at_rest") if "at_rest" in x else False,
                still=_flag(src, x["still"], f"{f}.still") if "still" in x else False)
    if not fate.asks():   # {"still": false}: a bit that is always set
        raise src.fail(f, f"asks nothing (every flag false); give one of {', '.join(_FATE)}")
    return fate


def _noise(src: _Src, body: str, parts: list[str], given: Any) -> tuple[float, ...]:
    f = f"noise.{body}"
    if given is None:
        given = {}
    _keys(src, given, f, _CONTROL)
    for k in given:
        if k not in parts:  # noise is on what the search chooses: a part not chosen would be ignored
            raise src.fail(f"{f}.{k}", f"controls.{body} chooses no {k} (it chooses {', '.join(parts)}); noise is "
                                       f"on what the search chooses")
    out: list[float] = []
    for k in parts:
        s = given.get(k, DEFAULT_NOISE[k])
        if isinstance(s, list):
            out.extend(_vec3(src, s, f"{f}.{k}"))
            if any(v < 0 for v in out[-3:]):
                raise src.fail(f"{f}.{k}", "must be >= 0")
        else:
            out.extend([_num(src, s, f"{f}.{k}", nonneg=True)] * 3)
    return tuple(out)


def parse_fates(doc: Any, source: str, *, folder: Path, scene: str | os.PathLike | None = None) -> Fates:
    """Check a parsed fates document (no MuJoCo: names are checked by :func:`check_against_model`).

    Args:
        doc: the JSON document.
        source: the file it came from, for messages.
        folder: the folder the ``"scene"`` path is relative to.
        scene: an MJCF path that overrides the file's ``"scene"`` (relative to the working folder).

    Returns:
        the :class:`Fates`.

    Raises:
        FatesError: a field is missing, unknown, of the wrong type or out of its domain.
    """
    src = _Src(source)
    # what the file is comes first: another kind of file, or another version, is told so by name
    # (not by the first of its keys that this version does not know)
    kind = doc.get("format", doc.get("kind")) if isinstance(doc, dict) else None   # nbst's others write "kind"
    if isinstance(kind, str) and kind.startswith("nbst") and kind != FORMAT:   # (a solution names its own)
        raise src.fail("format", f"must be {FORMAT!r}: this is a {kind!r} file, not a fates file"
                       + (" (a solution keeps its fates file under \"fates_file\")" if "solution" in kind else ""))
    _keys(src, doc, "", tuple(doc) if isinstance(doc, dict) else (), ("format", "version"))
    if doc["format"] != FORMAT:
        raise src.fail("format", f"must be {FORMAT!r}, got {doc['format']!r}")
    if isinstance(doc["version"], bool) or doc["version"] != VERSION:
        raise src.fail("version", f"must be {VERSION}, got {doc['version']!r}")
    _keys(src, doc, "", _TOP, ("duration", "controls", "fates") + (() if scene is not None else ("scene",)))
    if scene is not None:
        path = Path(scene)
    else:
        if not isinstance(doc["scene"], str) or not doc["scene"]:
            raise src.fail("scene", "must be the MJCF file's path (relative to the fates file)")
        path = folder / doc["scene"]
    keyframe = doc.get("keyframe")
    if keyframe is not None and (not isinstance(keyframe, str) or not keyframe):
        raise src.fail("keyframe", "must be the name of one of the model's keys")
    timestep = None if doc.get("timestep") is None else _num(src, doc["timestep"], "timestep", positive=True)
    duration = _num(src, doc["duration"], "duration", positive=True)
    controls_in = _keys(src, doc["controls"], "controls", tuple(doc["controls"]) if isinstance(doc["controls"], dict)
                        else ())
    if not controls_in:
        raise src.fail("controls", "names no body: give at least one body with a free joint")
    noise_in = doc.get("noise") or {}
    _keys(src, noise_in, "noise", tuple(controls_in))
    controls = []
    for body, c in controls_in.items():
        f = f"controls.{body}"
        _keys(src, c, f, _CONTROL)
        if not c:
            raise src.fail(f, f"chooses nothing; give one of {', '.join(_CONTROL)}")
        ranges = {k: _range3(src, c[k], f"{f}.{k}") for k in _CONTROL if k in c}
        parts = [k for k in _CONTROL if k in ranges]
        controls.append(Control(body=body, linvel=ranges.get("linvel"), angvel=ranges.get("angvel"),
                                pos=ranges.get("pos"), noise=_noise(src, body, parts, noise_in.get(body))))
    fates_in = _keys(src, doc["fates"], "fates", tuple(doc["fates"]) if isinstance(doc["fates"], dict) else ())
    if not fates_in:
        raise src.fail("fates", "names no body: give at least one body and what must happen to it")
    fates = tuple(_fate(src, body, x) for body, x in fates_in.items())
    for fa in fates:
        for k, (t, _) in enumerate(fa.at):
            if t > duration:
                raise src.fail(f"fates.{fa.body}.at[{k}].t", f"{t:g} s is after the duration, {duration:g} s")
    desc = doc.get("description", "")
    if not isinstance(desc, str):
        raise src.fail("description", "must be a string")
    return Fates(source=source, scene=path, keyframe=keyframe, timestep=timestep, duration=duration,
                 controls=tuple(controls), fates=fates, description=desc)


def read_fates_json(path: Path) -> Any:
    """The JSON document of a fates file, read through nbst's bounded reader (FatesError if it is not JSON)."""
    data = read_regular(path, max_bytes=MAX_FATES_BYTES, what="fates file", allow_empty=False)
    try:
        doc = json.loads(data.decode("utf-8"), parse_constant=_reject_constant, parse_int=_parse_int,
                         object_pairs_hook=_unique_keys)
        found = _first_refused(doc)
    except UnicodeDecodeError:
        raise FatesError(path, "", "not a text file (not UTF-8)") from None
    except json.JSONDecodeError as e:
        raise FatesError(path, "", f"not JSON: {e.msg} at line {e.lineno}, column {e.colno}") from None
    except ValueError as e:
        raise FatesError(path, "", f"not accepted: {e}") from None
    except RecursionError:
        raise FatesError(path, "", "not accepted: nested too deeply") from None
    if found is not None:
        raise FatesError(path, found[0], f"not accepted: {found[1]}")
    return doc
