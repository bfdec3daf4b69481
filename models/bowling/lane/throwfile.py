"""Throw files: a frame from the foul line (:mod:`.frame`) as a file, and an atlas of them.

A **throw file** is one JSON object that says what was thrown and what it did, in a bowler's
and a ball maker's units; ``nbst bowl frame -o THROW.json`` writes it, ``nbst bowl replay``
runs it again (:func:`replay_file`) and compares the pins down::

    {"format": "nbst-bowling-throw", "version": 1,
     "scene": "lane-2",                    # the lane scene it was thrown on (absent: "lane-1")
     "oil": "house",                       # the pattern's name
     "oil_pattern": Pattern.to_dict(),     # the pattern itself (a pattern file's content)
     "ball": Ball.to_dict(),               # weight_lb, rg, diff, friction, intdiff, layout, absorb_s
     "delivery": Delivery.to_dict(),       # hand, board, at, angle, mph, rpm, rotation, tilt
     "standing": [1, ..., 10],             # pins in play before the throw
     "requested": {"down": [...]} | null,  # what the thrower asked for, if anything
     "outcome": {"down", "leave", "settled", "settle_s", "cap_hit", "board_at_pins",
                 "entry_angle_deg", "timestep"},
     "probability": Estimate.to_dict() + {"want": {"down": [...]}} | null,
     "ladder": [{"timestep": h, "leave": [...], "kept": bool}, ...] | null}

``probability`` is :class:`.noise.Estimate`: ``k`` of ``n`` noisy throws (seed, noise sigmas)
gave the outcome ``want`` (the pins down counted as a success; for ``bowl frame``, every pin in
play: a strike or the spare), ``p = k/n`` and its 95 % Wilson interval ``[lo, hi]``, and how
often each leave came up. ``ladder`` is the same delivery thrown at each timestep of the
engine-robustness ladder, and whether it ``kept`` the outcome there (the same pins left as the
outcome's; files written before ``kept`` existed lack it and still load). A frame is replayed with :func:`.frame.run_frame` at the outcome's
``timestep`` on a fresh lane of the file's own pattern with the lane's oil law
(:data:`.lane.LAW`); it is deterministic, so the pins down are the file's. The outcome of one
throw is a sample: the probability (under the release noise) is the result; a throw whose
outcome holds at h = 1, 0.5 and 0.25 ms is one a replay on another machine also keeps.

**Scenes.** A file names the lane scene it was thrown on (``scene``); a file without one was
thrown on ``lane-1``, issue 22's scene (MuJoCo's soft friction on boxes of relative oil). A
throw is replayed only on its own scene: :func:`replay` refuses any other in one line (its
outcome stands as recorded), while :func:`load` and :func:`load_atlas` still read it (an atlas
of an earlier scene holds starts of searches, not answers: ``nbst bowl atlas --foul-line --from``
throws its deliveries again on this scene; the shipped foul-line atlas names this scene).
A lane-1 file names a registered pattern and a ball of four fields (weight, RG, differential,
coverstock); the fields added since take their defaults.

A **throw atlas** is ``{"format": "nbst-bowling-throw-atlas", "version": 1, "oil", "ball",
"noise", "throws": [throw, ...]}``: every throw on the atlas's oil and ball, its probability
(if any) under the atlas's noise, no two with the same pins standing and down;
:func:`lookup` finds the throw of a down set on a full rack.

Both come in through the gate of :mod:`nbst.models.bowling.files` (a regular file, checked by
``stat`` before it is opened; nbst's core JSON reader with its size, depth and number caps; no
integer too large for a float), then
:func:`check_throw` / :func:`check_atlas` check every field: one
:class:`ThrowFileError` line naming the file and the field (``throws[3].ball.rg``). Keys
beyond the schema are ignored, as in 5 m throw files (the CLI adds ``bowler``, ``line``,
``names`` and ``note`` for people: :mod:`.advise`, :mod:`.names`). The 5 m throw files of
:mod:`nbst.models.bowling.deck.throwfile` are a different format.

Compute apart from I/O: :func:`throw_dict`, :func:`check_throw`, :func:`replay` take values;
:func:`load`, :func:`load_atlas` and :func:`replay_file` read files; nothing here writes.

Length: two file formats (a throw and an atlas of them), their writers and their field-by-field
checkers belong together (the schema is read in one place); ~560 lines.
"""
from __future__ import annotations

import json
from dataclasses import asdict, is_dataclass

from nbst import seeds
from nbst.models.bowling import files, lane, scene
from nbst.models.bowling.lane import frame, noise as _noise
from nbst.errors import MujocoError

__all__ = ["FORMAT", "SCENES", "ATLAS_FORMAT", "VERSION", "MAX_THROWS", "MAX_LADDER", "BOARD_RANGE", "ANGLE_RANGE",
           "SECONDS_MAX", "SEED_MAX", "ThrowFileError", "BALL_KEYS", "BALL_KEYS_1", "DELIVERY_KEYS",
           "OUTCOME_KEYS", "ESTIMATE_KEYS", "THROW_KEYS", "ATLAS_KEYS", "ATLAS_REQUIRED", "FULL_RACK",
           "throw_dict", "atlas_dict", "OIL_KEYS", "dumps", "check_ball", "check_delivery", "check_noise",
           "check_scene", "check_oil", "check_throw", "ladder_kept", "check_atlas", "is_throw", "load",
           "load_atlas", "lookup", "replayable", "oil_of", "replay", "replay_file"]

FORMAT = "nbst-bowling-throw"
#: Scenes a file may name; a file without ``scene`` was thrown on the first.
SCENES = (*lane.EARLIER_SCENES, lane.SCENE)
ATLAS_FORMAT = "nbst-bowling-throw-atlas"
VERSION = 1
#: The most throws an atlas holds: one per subset of a full rack (1,023) and per spare leave
#: and subset of it is far below; the JSON reader's caps bound the file first.
MAX_THROWS = 20_000
#: The longest ladder a throw file holds (frame.LADDER has 3 steps).
MAX_LADDER = 16
#: Sanity bounds of the outcome (a frame's ball crosses the deck on the lane, boards 1..39; a
#: frame is capped 6 s after the ball reaches the pins, at most lane.MAX_SECONDS + 6 s).
BOARD_RANGE = (-60.0, 100.0)
ANGLE_RANGE = (-90.0, 90.0)
SECONDS_MAX = 120.0
#: Largest seed: nbst's one seed range (:data:`nbst.seeds.SEED_MAX`).
SEED_MAX = seeds.SEED_MAX

ThrowFileError = files.BowlingFileError
"""A throw or throw-atlas file that cannot be read: one line naming the file and the field
(every bowling file's error: one ``except`` catches them all)."""

BALL_KEYS = tuple(asdict(lane.Ball()))
#: The ball of lane-1 files: the fields before issue 34 (the others take their defaults).
BALL_KEYS_1 = ("weight_lb", "rg", "diff", "friction")
DELIVERY_KEYS = tuple(asdict(lane.Delivery()))
OUTCOME_KEYS = ("down", "leave", "settled", "settle_s", "cap_hit", "board_at_pins", "entry_angle_deg", "timestep")
ESTIMATE_KEYS = ("k", "n", "p", "lo", "hi", "seed", "noise", "leaves", "want")
THROW_KEYS = ("format", "version", "scene", "oil", "oil_pattern", "ball", "delivery", "standing", "requested",
              "outcome", "probability", "ladder")
ATLAS_KEYS = ("format", "version", "scene", "oil", "oil_pattern", "ball", "noise", "throws")
ATLAS_REQUIRED = ("format", "version", "oil", "ball", "noise", "throws")
FULL_RACK = list(scene.PIN_NUMBERS)

_fail = files.fail


# --------------------------------------------------------------------------- building


def _pins(pins) -> list[int]:
    """Sorted distinct pin numbers from a list of pins or a 10-bit mask (int)."""
    if isinstance(pins, int) and not isinstance(pins, bool):
        return [n for n in scene.PIN_NUMBERS if pins >> (n - 1) & 1]
    return sorted({int(n) for n in pins})


def _as_dict(x) -> dict | None:
    if x is None:
        return None
    if hasattr(x, "to_dict"):
        return x.to_dict()
    if is_dataclass(x) and not isinstance(x, type):
        return asdict(x)
    return dict(x)


def throw_dict(result: frame.FrameResult, *, oil: str, ball=None, requested=None, estimate=None, want=None,
               ladder=None) -> dict:
    """The throw file's content for a settled frame ``result`` (``extra_s`` 0: the frame as
    :func:`replay` runs it) thrown on ``oil`` with ``ball`` (:class:`.lane.Ball` or its dict;
    None: the default ball). ``requested``: the pins asked for down (pins or a mask), or
    None. ``estimate``: a :class:`.noise.Estimate` (or its dict) counting ``want`` (pins or a
    mask; default: the estimate's own ``want`` if it has one, else every pin in play, as
    :func:`.noise.estimate` counts by default). ``ladder``: the
    same throw at other timesteps (FrameResults, or dicts with ``timestep`` and ``leave``).
    The result is checked (:func:`check_throw`); ThrowFileError names the field."""
    if result.extra_s:
        raise ThrowFileError(f"result: ran {result.extra_s:g} s past the settle; a throw file records the frame "
                         f"as it settled (extra_s 0), which is what a replay runs")
    pat = lane.pattern(oil)
    if result.oil != pat.name:
        raise ThrowFileError(f"oil: {pat.name!r} is not the frame's oil {result.oil!r}")
    ball_d = _as_dict(ball if ball is not None else lane.Ball())
    if not isinstance(ball_d, dict) or set(ball_d) != set(BALL_KEYS):
        raise ThrowFileError(f"ball: must be a lane.Ball (or its dict: {', '.join(BALL_KEYS)}), got {ball!r}")
    est = _as_dict(estimate)
    if est is not None:
        w = want if want is not None else est.get("want")  # an Estimate that carries its own want
        w = w.get("down") if isinstance(w, dict) else w
        est = {k: est[k] for k in ESTIMATE_KEYS if k in est and k != "want"}
        est["want"] = {"down": _pins(result.in_play if w is None else w)}
    lad = None
    if ladder is not None:
        lad = [{"timestep": float(x.timestep), "leave": list(x.leave)} if isinstance(x, frame.FrameResult)
               else {"timestep": float(x["timestep"]), "leave": _pins(x["leave"])} for x in ladder]
        for x in lad:
            x["kept"] = x["leave"] == list(result.leave)
    d = {
        "format": FORMAT,
        "version": VERSION,
        "scene": lane.SCENE,
        "oil": pat.name,
        "oil_pattern": pat.to_dict(),
        "ball": {k: ball_d[k] for k in BALL_KEYS},
        "delivery": {k: result.delivery[k] for k in DELIVERY_KEYS},
        "standing": list(result.in_play),
        "requested": None if requested is None else {"down": _pins(requested)},
        "outcome": {"down": list(result.down), "leave": list(result.leave), "settled": bool(result.settled),
                    "settle_s": result.settle_s, "cap_hit": bool(result.cap_hit),
                    "board_at_pins": result.board_at_pins, "entry_angle_deg": result.entry_angle_deg,
                    "timestep": float(result.timestep)},
        "probability": est,
        "ladder": lad,
    }
    try:
        return check_throw(d, "throw")
    except ThrowFileError as e:
        raise ThrowFileError(str(e).removeprefix("throw: ")) from None


def atlas_dict(throws, *, oil, ball=None, noise=None) -> dict:
    """A throw atlas of ``throws`` (throw dicts, kept in the order given) on ``oil`` and
    ``ball``, with probabilities under ``noise`` (:class:`.noise.Noise` or its dict; default
    :data:`.noise.DEFAULT`). Checked (:func:`check_atlas`); ThrowFileError names the field."""
    pat = lane.pattern(oil)
    a = {"format": ATLAS_FORMAT, "version": VERSION, "scene": lane.SCENE, "oil": pat.name,
         "oil_pattern": pat.to_dict(),
         "ball": _as_dict(ball if ball is not None else lane.Ball()),
         "noise": _as_dict(noise if noise is not None else _noise.DEFAULT), "throws": list(throws)}
    try:
        return check_atlas(a, "atlas")
    except ThrowFileError as e:
        raise ThrowFileError(str(e).removeprefix("atlas: ")) from None


def _ordered(d: dict, keys) -> dict:
    """``d`` with ``keys`` first in that order, any other keys after them, sorted."""
    out = {k: d[k] for k in keys if k in d}
    out.update({k: d[k] for k in sorted(d, key=str) if k not in out})
    return out


OIL_KEYS = ("format", "version", "name", "description", "forward", "reverse")


def _ordered_throw(t: dict) -> dict:
    t = _ordered(t, THROW_KEYS)
    if isinstance(t.get("oil_pattern"), dict):
        t["oil_pattern"] = _ordered(t["oil_pattern"], OIL_KEYS)
    for k, keys in (("ball", BALL_KEYS), ("delivery", DELIVERY_KEYS), ("outcome", OUTCOME_KEYS),
                    ("probability", ESTIMATE_KEYS)):
        if isinstance(t.get(k), dict):
            t[k] = _ordered(t[k], keys)
    p = t.get("probability")
    if isinstance(p, dict) and isinstance(p.get("noise"), dict):
        p["noise"] = _ordered(p["noise"], _noise.KEYS)
    if isinstance(t.get("ladder"), list):
        t["ladder"] = [_ordered(x, ("timestep", "leave", "kept")) if isinstance(x, dict) else x for x in t["ladder"]]
    return t


def dumps(d: dict) -> str:
    """JSON text of a throw or a throw atlas: the schema's keys in a fixed order (then any
    others, sorted), 2-space indent (a list of pins on one line), a final newline; floats by ``repr`` (exact on reading
    back). ValueError on a non-finite number."""
    if d.get("format") == ATLAS_FORMAT:
        d = _ordered(d, ATLAS_KEYS)
        if isinstance(d.get("oil_pattern"), dict):
            d["oil_pattern"] = _ordered(d["oil_pattern"], OIL_KEYS)
        d["ball"] = _ordered(d["ball"], BALL_KEYS) if isinstance(d.get("ball"), dict) else d.get("ball")
        d["noise"] = _ordered(d["noise"], _noise.KEYS) if isinstance(d.get("noise"), dict) else d.get("noise")
        d["throws"] = [_ordered_throw(t) if isinstance(t, dict) else t for t in d.get("throws", [])]
    else:
        d = _ordered_throw(d)
    return _text(d, "") + "\n"


def _text(o, ind: str) -> str:
    """JSON with a 2-space indent, a list of plain values (pins) on one line."""
    if isinstance(o, dict) and o:
        inner = ind + "  "
        return "{\n" + ",\n".join(f"{inner}{json.dumps(str(k))}: {_text(v, inner)}" for k, v in o.items()) \
            + f"\n{ind}}}"
    if isinstance(o, list) and any(isinstance(v, (dict, list)) for v in o):
        inner = ind + "  "
        return "[\n" + ",\n".join(inner + _text(v, inner) for v in o) + f"\n{ind}]"
    return json.dumps(o, allow_nan=False)


# --------------------------------------------------------------------------- checking


def _is_num(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _number(d: dict, key: str, src, field: str, lo: float, hi: float, *, null: bool = False, integer: bool = False):
    v = d[key]
    if v is None and null:
        return None
    kind = "a whole number" if integer else "a number"
    if not _is_num(v) or (integer and not isinstance(v, int)):
        _fail(src, field, f"must be {kind}{' or null' if null else ''}, got {json.dumps(v)[:40]}")
    if not lo <= v <= hi:  # also false for nan
        _fail(src, field, f"{v!r} is outside [{lo:g}, {hi:g}]")
    return v


def _flag(d: dict, key: str, src, field: str) -> bool:
    if not isinstance(d[key], bool):
        _fail(src, field, f"must be true or false, got {json.dumps(d[key])[:40]}")
    return d[key]


def _object(d, src, field: str, required) -> dict:
    if not isinstance(d, dict):
        _fail(src, field, f"must be an object, got {json.dumps(d)[:40]}")
    for k in required:
        if k not in d:
            _fail(src, f"{field}.{k}" if field else k, "missing")
    return d


def _pin_list(v, src, field: str, *, within=None, empty: bool = True) -> list[int]:
    """A list of distinct pin numbers 1..10 (all in ``within`` if given), returned sorted."""
    if not isinstance(v, list) or not all(isinstance(n, int) and not isinstance(n, bool) and 1 <= n <= 10
                                          for n in v):
        _fail(src, field, f"must be a list of pin numbers 1..10, got {json.dumps(v)[:40]}")
    if len(set(v)) != len(v):
        _fail(src, field, f"names a pin twice: {v}")
    if not v and not empty:
        _fail(src, field, "must name at least one pin")
    if within is not None and not set(v) <= set(within):
        _fail(src, field, f"pins {sorted(set(v) - set(within))} are not among the pins standing {sorted(within)}")
    return sorted(v)


def _exact_keys(d: dict, keys, src, field: str) -> None:
    extra = [k for k in d if k not in keys]
    if extra:
        _fail(src, f"{field}.{extra[0]}", f"unknown field (the fields are {', '.join(keys)})")


def _lane_value(make, src, field: str):
    """``make()`` (a Ball, Delivery or Noise built and checked), its one-line error re-aimed at
    ``field`` (the dataclasses' messages start with the field's own name)."""
    try:
        return make()
    except (ValueError, TypeError) as e:
        msg = str(e)
        name, sep, why = msg.partition(": ")
        if sep and " " not in name:
            name = name.split(".")[-1]
            _fail(src, f"{field}.{name}", why)
        _fail(src, field, msg)


def check_ball(b, src, field: str = "ball") -> lane.Ball:
    """The :class:`.lane.Ball` of a ball object, within USBC's limits; ThrowFileError otherwise.
    The fields added since lane-1 (:data:`BALL_KEYS_1`) may be missing: they take their defaults."""
    _object(b, src, field, BALL_KEYS_1)
    _exact_keys(b, BALL_KEYS, src, field)
    return _lane_value(lambda: lane.Ball(**b).check(), src, field)


def check_delivery(d, src, field: str = "delivery") -> lane.Delivery:
    _object(d, src, field, DELIVERY_KEYS)
    _exact_keys(d, DELIVERY_KEYS, src, field)
    for k in ("hand", "at"):
        if not isinstance(d[k], str):
            _fail(src, f"{field}.{k}", f"must be a string, got {json.dumps(d[k])[:40]}")
    return _lane_value(lambda: lane.Delivery(**d).check(), src, field)


def check_noise(n, src, field: str = "noise") -> _noise.Noise:
    _object(n, src, field, _noise.KEYS)
    _exact_keys(n, _noise.KEYS + _noise.CORR_KEYS, src, field)
    return _lane_value(lambda: _noise.Noise(**n).check(), src, field)


def check_scene(d: dict, src, field: str = "scene") -> str:
    """The scene a file names (absent: "lane-1"), one of :data:`SCENES`."""
    sc = d.get("scene", SCENES[0])
    if sc not in SCENES:
        _fail(src, field, f"unknown lane scene {json.dumps(sc)[:40]}; this nbst knows {', '.join(SCENES)}")
    return sc


def check_oil(d: dict, src, pre: str = "") -> lane.Pattern:
    """The pattern a file names: its own ``oil_pattern`` (a pattern file's content, whose name
    must be ``oil``) or, without one, a registered pattern's name."""
    oil = d.get("oil")
    if not isinstance(oil, str):
        _fail(src, pre + "oil", f"must be a pattern's name, got {json.dumps(oil)[:40]}")
    embedded = d.get("oil_pattern")
    if embedded is None:
        if oil not in lane.PATTERNS:
            _fail(src, pre + "oil", f"no oil pattern {json.dumps(oil)[:40]} (and no oil_pattern); patterns: "
                                    f"{', '.join(lane.PATTERNS.names())}")
        return lane.PATTERNS[oil]
    try:
        pat = lane.pattern_from_dict(embedded, f"{src}: {pre}oil_pattern")
    except lane.LaneError as e:
        raise ThrowFileError(str(e)) from None
    if pat.name != oil:
        _fail(src, pre + "oil", f"{oil!r} is not the name of its oil_pattern {pat.name!r}")
    return pat


def _check_timestep(d: dict, key: str, src, field: str) -> float:
    return _number(d, key, src, field, 1e-5, 0.002)


def _check_estimate(e, standing, src, pre: str) -> None:
    f = pre + "probability"
    _object(e, src, f, ESTIMATE_KEYS)
    n = _number(e, "n", src, f + ".n", 1, 10**9, integer=True)
    k = _number(e, "k", src, f + ".k", 0, 10**9, integer=True)
    if k > n:
        _fail(src, f + ".k", f"{k} successes in {n} throws: k must be at most n")
    p, lo, hi = (_number(e, x, src, f"{f}.{x}", 0.0, 1.0) for x in ("p", "lo", "hi"))
    if not lo <= p <= hi:
        _fail(src, f + ".p", f"p = {p!r} must lie in its interval [lo, hi] = [{lo!r}, {hi!r}]")
    if abs(p - k / n) > 1e-9:
        _fail(src, f + ".p", f"p = {p!r} is not k/n = {k}/{n}")
    _number(e, "seed", src, f + ".seed", 0, SEED_MAX, integer=True)
    check_noise(e["noise"], src, f + ".noise")
    want = _object(e["want"], src, f + ".want", ("down",))
    want_down = set(_pin_list(want["down"], src, f + ".want.down", within=standing))
    leaves = e["leaves"]
    if not isinstance(leaves, dict):
        _fail(src, f + ".leaves", "must be an object {leave: count} (a leave: pins standing joined by '-')")
    total = hits = 0
    for name, count in leaves.items():
        lf = f"{f}.leaves[{json.dumps(name)[:20]}]"
        try:
            pins = [int(x) for x in name.split("-")] if name else []
        except ValueError:
            _fail(src, lf, "a leave is pin numbers joined by '-' ('' for none)")
        _pin_list(pins, src, lf, within=standing)
        if not isinstance(count, int) or isinstance(count, bool) or not 0 <= count <= n:
            _fail(src, lf, f"must be a count in [0, n = {n}], got {json.dumps(count)[:40]}")
        total += count
        if set(standing) - set(pins) == want_down:
            hits += count
    if total != n:
        _fail(src, f + ".leaves", f"the counts add up to {total}, not n = {n}")
    if hits != k:
        _fail(src, f + ".k", f"{k} successes, but the leaves give the wanted outcome (down "
                             f"{sorted(want_down)}) {hits} times")


def check_throw(d, src, pre: str = "") -> dict:
    """Check a decoded throw (every field: types, finite numbers, the ball's and delivery's
    limits, pins, the outcome's and the estimate's consistency); ``pre`` prefixes field paths
    (``throws[3].``). Returns ``d``; ThrowFileError (one line, file and field) otherwise."""
    if not isinstance(d, dict) or d.get("format") != FORMAT:
        _fail(src, pre.rstrip("."), f"not an nbst bowling throw (format must be {FORMAT!r})")
    for k in ("version", "oil", "ball", "delivery", "standing", "outcome"):
        if k not in d:
            _fail(src, pre + k, "missing")
    bad = files.non_finite(d, pre.rstrip("."))
    if bad:
        _fail(src, bad[0], f"must be a finite number, got {bad[1]}")
    if d["version"] != VERSION or isinstance(d["version"], bool):
        _fail(src, pre + "version", f"this nbst reads version {VERSION}, got {json.dumps(d['version'])[:40]}")
    check_scene(d, src, pre + "scene")
    check_oil(d, src, pre)
    check_ball(d["ball"], src, pre + "ball")
    check_delivery(d["delivery"], src, pre + "delivery")
    standing = _pin_list(d["standing"], src, pre + "standing", empty=False)
    req = d.get("requested")
    if req is not None:
        _object(req, src, pre + "requested", ("down",))
        _pin_list(req["down"], src, pre + "requested.down", within=standing)
    o = _object(d["outcome"], src, pre + "outcome", OUTCOME_KEYS)
    f = pre + "outcome"
    down = _pin_list(o["down"], src, f + ".down", within=standing)
    leave = _pin_list(o["leave"], src, f + ".leave", within=standing)
    if set(down) & set(leave) or sorted(set(down) | set(leave)) != standing:
        _fail(src, f + ".leave", f"down {down} and leave {leave} must split the pins standing {standing}")
    settled = _flag(o, "settled", src, f + ".settled")
    cap_hit = _flag(o, "cap_hit", src, f + ".cap_hit")
    if settled == cap_hit:
        _fail(src, f + ".cap_hit", "a frame either settled or hit the cap: settled and cap_hit must differ")
    settle_s = _number(o, "settle_s", src, f + ".settle_s", 0.0, SECONDS_MAX, null=True)
    if (settle_s is None) == settled:
        _fail(src, f + ".settle_s", "must be the settle time (s) of a settled frame, null for a capped one")
    _number(o, "board_at_pins", src, f + ".board_at_pins", *BOARD_RANGE, null=True)
    _number(o, "entry_angle_deg", src, f + ".entry_angle_deg", *ANGLE_RANGE, null=True)
    _check_timestep(o, "timestep", src, f + ".timestep")
    if d.get("probability") is not None:
        _check_estimate(d["probability"], standing, src, pre)
    lad = d.get("ladder")
    if lad is not None:
        if not isinstance(lad, list) or not 1 <= len(lad) <= MAX_LADDER:
            _fail(src, pre + "ladder", f"must be a list of 1..{MAX_LADDER} {{timestep, leave}} objects, or null")
        for i, x in enumerate(lad):
            g = f"{pre}ladder[{i}]"
            _object(x, src, g, ("timestep", "leave"))
            _check_timestep(x, "timestep", src, g + ".timestep")
            lv = _pin_list(x["leave"], src, g + ".leave", within=standing)
            if "kept" in x and _flag(x, "kept", src, g + ".kept") != (lv == leave):
                _fail(src, g + ".kept", f"says {str(x['kept']).lower()}, but the leave there {lv} is "
                                        f"{'' if lv == leave else 'not '}the outcome's {leave}")
    return d


def ladder_kept(d: dict) -> tuple[list, list]:
    """(timesteps, the timesteps that kept the outcome) of a checked throw dict's ladder ([], []
    without one)."""
    lad = d.get("ladder") or []
    leave = sorted(d["outcome"]["leave"])
    return ([float(x["timestep"]) for x in lad],
            [float(x["timestep"]) for x in lad if x.get("kept", sorted(x["leave"]) == leave)])


def check_atlas(a, src) -> dict:
    """Check a decoded throw atlas: its oil, ball and noise, and every throw as a throw file
    (field paths ``throws[i].``) on the atlas's oil and ball, its probability under the
    atlas's noise, no two throws with the same pins standing and down. Returns ``a``."""
    if not isinstance(a, dict) or a.get("format") != ATLAS_FORMAT:
        _fail(src, "", f"not an nbst bowling throw atlas (format must be {ATLAS_FORMAT!r})")
    for k in ATLAS_REQUIRED:
        if k not in a:
            _fail(src, k, "missing")
    if a["version"] != VERSION or isinstance(a["version"], bool):
        _fail(src, "version", f"this nbst reads version {VERSION}, got {json.dumps(a['version'])[:40]}")
    bad = files.non_finite({k: a[k] for k in ("ball", "noise")}, "")
    if bad:
        _fail(src, bad[0], f"must be a finite number, got {bad[1]}")
    scene_ = check_scene(a, src)
    check_oil(a, src)
    ball = check_ball(a["ball"], src)
    nz = check_noise(a["noise"], src)
    throws = a["throws"]
    if not isinstance(throws, list) or len(throws) > MAX_THROWS:
        _fail(src, "throws", f"must be a list of at most {MAX_THROWS:,} throws")
    seen: dict = {}
    for i, t in enumerate(throws):
        pre = f"throws[{i}]."
        check_throw(t, src, pre)
        if t.get("scene", SCENES[0]) != scene_:
            _fail(src, pre + "scene", f"{t.get('scene', SCENES[0])!r} is not the atlas's scene {scene_!r}")
        if t["oil"] != a["oil"]:
            _fail(src, pre + "oil", f"{t['oil']!r} is not the atlas's oil {a['oil']!r}")
        if lane.Ball(**t["ball"]) != ball:
            _fail(src, pre + "ball", f"{t['ball']} is not the atlas's ball {a['ball']}")
        p = t.get("probability")
        if p is not None and _noise.Noise(**p["noise"]) != nz:
            _fail(src, pre + "probability.noise", f"{p['noise']} is not the atlas's noise {a['noise']}")
        key = (tuple(sorted(t["standing"])), tuple(sorted(t["outcome"]["down"])))
        if key in seen:
            _fail(src, pre + "outcome.down", f"the same pins standing and down as throws[{seen[key]}]")
        seen[key] = i
    return a


# --------------------------------------------------------------------------- files and replays


def is_throw(doc) -> bool:
    """Whether decoded JSON says it is a throw file (by its ``format``)."""
    return isinstance(doc, dict) and doc.get("format") == FORMAT


def load(path) -> dict:
    """Read (the bowling files' gate: a regular file, stat first, size and depth caps) and check a
    throw file; ThrowFileError naming the file and the field."""
    return check_throw(files.read_doc(path), path)


def load_atlas(path) -> dict:
    """Read and check a throw atlas (:func:`check_atlas`); ThrowFileError naming the file and field.

    Args:
        path: a throw atlas file.

    Returns:
        the checked atlas dict.

    Raises:
        ThrowFileError: the file or a field refused (one line, file and field).
    """
    return check_atlas(files.read_doc(path), path)


def lookup(atlas: dict, down) -> dict | None:
    """The throw of ``atlas`` that knocks down exactly ``down`` (pins or a 10-bit mask) on a
    full rack, or None."""
    want = _pins(down)
    for t in atlas["throws"]:
        if sorted(t["standing"]) == FULL_RACK and sorted(t["outcome"]["down"]) == want:
            return t
    return None


def replayable(d: dict, src="throw") -> None:
    """Nothing if the checked throw ``d`` was thrown on this nbst's scene; else ThrowFileError,
    one line: a throw replays only on the scene it names."""
    sc = d.get("scene", SCENES[0])
    if sc != lane.SCENE:
        what = {"lane-1": "issue 22's soft-contact friction on relative oil",
                "lane-2": "issue 22's pins, before the carry fit"}.get(sc, "the pins on a pin deck at friction 0.2")
        _fail(src, "scene", f"thrown on the {sc} lane scene ({what}); this nbst runs {lane.SCENE} (Coulomb "
                            f"friction from the oil film, pins fitted to carry, the pins on the pin deck at 0.1) and does "
                            f"not replay it: its outcome stands as recorded")


def oil_of(d: dict) -> lane.Pattern:
    """The pattern of a checked throw dict."""
    return check_oil(d, "throw")


def replay(d: dict, *, model=None, src="throw") -> frame.FrameResult:
    """Run the throw of a checked throw dict again: :func:`.frame.run_frame` with its delivery,
    pattern (a fresh lane), ball and pins standing at the outcome's timestep (``model``: a
    compiled :func:`.frame.frame_model` of the same ball and timestep, to reuse). A throw of
    another scene is refused (:func:`replayable`)."""
    replayable(d, src)
    return frame.run_frame(lane.Delivery(**d["delivery"]), oil_of(d), lane.Ball(**d["ball"]), standing=d["standing"],
                           timestep=float(d["outcome"]["timestep"]), model=model)


def replay_file(path) -> tuple[dict, frame.FrameResult, bool]:
    """(throw dict, the replayed frame, whether its pins down are the file's) of a throw file.
    MuJoCo's warnings (a diverging state) become a ThrowFileError naming the file; a throw of
    another scene is refused in one line.

    Args:
        path: a foul-line throw file.

    Returns:
        (the checked throw dict, the replayed :class:`.frame.FrameResult`, whether its pins down
        are the file's).

    Raises:
        ThrowFileError: the file or a field refused, another scene's throw, or MuJoCo warned.
    """
    d = load(path)
    replayable(d, path)
    try:
        r = replay(d, src=path)
    except MujocoError as e:
        raise ThrowFileError(f"{path}: delivery: {e}") from None
    return d, r, r.down == sorted(d["outcome"]["down"])
