"""The 5 m throw file: what ``nbst bowl solve`` writes and ``nbst bowl replay`` reads.

A 5 m throw file is JSON that any MuJoCo user can replay without nbst (docs/bowling.md). Its
``kind`` is ``nbst-bowling-shot``, its delivery is under ``launch`` and its scene's keyframe is
``shot``: the names of the format's first version, kept so that files written before and
after read the same (docs/bowling.md, "Words").

* ``scene``: the MJCF file, relative to the throw file (written beside it, every
  number at full precision; it also holds the throw's start as keyframe ``shot``);
* ``qpos0``, ``qvel0``: the full initial state (JSON floats written by ``repr``:
  exact); ``duration`` (s) and ``timestep`` (s);
* ``pins``: the 10 pin body names in pin-number order; ``down``: the pin numbers down
  at the end; ``rule``: how "down" is decided (tilt, below-deck depth, pit edge, lane
  half-width);
* ``launch``: the delivery in its units; ``robustness``: the largest lateral and speed
  changes that keep the outcome; ``requested``, ``found``, ``hamming``, ``search``.

Every file comes in through the gate of :mod:`nbst.models.bowling.files`, then the checks
below (and the scene's own gate: inside the file's folder, self-contained, parsed by MuJoCo).

Compute apart from I/O: :func:`throw_dict` and :func:`replay` take values; the writers
are thin (:mod:`.folder`).
"""
from __future__ import annotations

import json
import math
import os
import re
from pathlib import Path

import numpy as np

from nbst.errors import InputError, MujocoError
from nbst.seeds import SEED_MAX
from nbst.models.bowling import deck, files, pinfall, scene, geometry
from nbst.models.mjsearch.runner import mujoco_warnings_raise

__all__ = ["SCHEMA_VERSION", "KIND", "ThrowFileError", "scene_with_start", "rule", "throw_dict", "dumps",
           "MAX_SCENE_BYTES", "QPOS_MAX", "QVEL_MAX", "MAX_STEPS", "SHIPPED_SCENE", "SHIPPED_ATLAS",
           "SCENE_JOINTS", "regular_file", "read_doc", "check_throw", "resolve_scene", "read_scene_text",
           "load_scene", "check_against_scene", "load", "load_with_scene", "ATLAS_KIND", "load_atlas", "replay",
           "replay_file"]

SCHEMA_VERSION = 1
KIND = "nbst-bowling-shot"


ThrowFileError = files.BowlingFileError
"""A throw file that cannot be read; the message names the file and the field (every bowling
file's error: one ``except`` catches them all)."""


def scene_with_start(qpos0, qvel0) -> str:
    """Scene XML (full precision) with keyframe ``shot`` = (qpos0, qvel0), the throw's start."""
    spec = scene.build_spec()
    key = spec.add_key()
    key.name = "shot"
    key.time = 0.0
    key.qpos = [float(v) for v in qpos0]
    key.qvel = [float(v) for v in qvel0]
    return scene.scene_xml(spec)


def rule() -> dict:
    return {"tilt_deg": pinfall.DOWN_TILT_DEG, "below_deck_m": pinfall.LEFT_DECK_DEPTH,
            "pit_edge_x_m": scene.PIT_EDGE_X, "lane_half_width_m": scene.LANE_WIDTH / 2}


def throw_dict(model, delivery, *, scene_name: str, down_mask: int, requested=None, robustness=None,
               search=None) -> dict:
    """The throw file's content for ``delivery`` ((4,) array) whose outcome is ``down_mask``."""
    import mujoco

    qpos0, qvel0 = deck.initial_qpos_qvel(model, delivery)
    lau = deck.Delivery.from_array(deck.clamp(delivery))
    d = {
        "schema_version": SCHEMA_VERSION,
        "kind": KIND,
        "scene": scene_name,
        "qpos0": [float(v) for v in qpos0],
        "qvel0": [float(v) for v in qvel0],
        "duration": deck.DURATION,
        "timestep": float(model.opt.timestep),
        "pins": scene.pin_names(),
        "down": pinfall.pins_of(down_mask),
        "rule": rule(),
        "launch": {**lau.to_dict(), "units": {"y": "m (+ = bowler's left)", "speed": "m/s",
                                              "angle": "deg (+ = towards the left)",
                                              "spin": "rad/s about the travel direction (+ hooks right)"}},
        "mujoco": mujoco.__version__,
    }
    if requested is not None:
        req = int(requested)
        d["requested"] = pinfall.pins_of(req)
        d["found"] = req == int(down_mask)
        d["hamming"] = (req ^ int(down_mask)).bit_count()
    if robustness is not None:
        d["robustness"] = robustness
    if search is not None:
        d["search"] = search
    return d


def dumps(d: dict) -> str:
    """JSON text; floats by ``repr`` (Python's json does), so qpos0/qvel0 read back exactly."""
    for k in ("qpos0", "qvel0"):
        if not all(math.isfinite(v) for v in d[k]):
            raise InputError(f"{k} has a non-finite number")
    return json.dumps(d, indent=1) + "\n"


# --------------------------------------------------------------------------- the input gate
# Every throw and atlas file comes in through the gate of nbst.models.bowling.files (regular files
# only, the core JSON reader, no integer beyond a float); then every number finite, the state
# bounded, the shapes checked against the scene, and the scene XML it names read through here:
# inside the document's own folder (or the shipped scene), self-contained, parsed by MuJoCo.
# One ThrowFileError line names file and field.

#: Largest scene XML read (bytes): the shipped scene is ~90 kB (its pin meshes inline).
MAX_SCENE_BYTES = 8 * 1024 * 1024
#: Bound on every qpos entry (m, or quaternion components): the simulated lane is 6.4 m
#: long and the pit 1 m deep; 1e3 leaves room for any real state and keeps MuJoCo's
#: squares and products far from float64 overflow (1e300 reaches inf in one step).
QPOS_MAX = 1e3
#: Bound on every qvel entry (m/s, rad/s): a delivery is at most 10 m/s and ~125 rad/s
#: (rolling at 10 m/s plus 30 rad/s of spin, :data:`.delivery.BOUNDS`).
QVEL_MAX = 1e3
#: Longest replay (steps): duration <= 60 s at the scene's 1 ms step is 60,000; a scene
#: with a tiny timestep would make a replay that never ends.
MAX_STEPS = 60_000
#: The shipped scene (models/bowling/deck/scene.xml), which any throw file may name.
SHIPPED_SCENE = Path(__file__).resolve().with_name("scene.xml")
#: The shipped atlas (one throw for each subset found; ``nbst bowl solve`` starts from it).
SHIPPED_ATLAS = SHIPPED_SCENE.with_name("atlas.json")
#: Joints and geoms every bowling scene has (the replay, the rule and the render use them).
SCENE_JOINTS = ("ball_free", *(f"pin{n}_free" for n in scene.PIN_NUMBERS))
#: A scene may not read other files (meshes, textures, includes): it is one self-contained XML.
_READS_FILES = re.compile(r"\bfile\s*=|<\s*include\b|\b(?:mesh|texture|asset)dir\s*=", re.IGNORECASE)


regular_file = files.regular_file
read_doc = files.read_doc
_fail = files.fail


def _vector(d: dict, key: str, src, pre: str, bound: float) -> list:
    v = d[key]
    if not isinstance(v, list):
        _fail(src, pre + key, "must be a list of numbers")
    for i, x in enumerate(v):
        if isinstance(x, bool) or not isinstance(x, (int, float)):
            _fail(src, f"{pre}{key}[{i}]", f"must be a number, got {json.dumps(x)[:40]}")
        if not abs(x) <= bound:  # also false for nan
            _fail(src, f"{pre}{key}[{i}]", f"{x:g} is outside [-{bound:g}, {bound:g}] (a bowling state is "
                                            f"far inside; MuJoCo would overflow)")
    return [float(x) for x in v]


def check_throw(d, src, pre: str = "") -> dict:
    """Check a decoded throw (structure, types, finite and bounded numbers; not yet the
    scene's shapes: :func:`check_against_scene`); ``pre`` prefixes field paths
    (``shots[3].``). Returns ``d``."""
    if not isinstance(d, dict) or d.get("kind") != KIND:
        _fail(src, pre.rstrip("."), f"not an nbst 5 m throw file (kind must be {KIND!r})")
    for k in ("scene", "qpos0", "qvel0", "duration", "pins", "down"):
        if k not in d:
            _fail(src, pre + k, "missing")
    bad = files.non_finite(d, pre.rstrip("."))
    if bad:
        _fail(src, bad[0], f"must be a finite number, got {bad[1]}")
    if not isinstance(d["scene"], str) or not d["scene"] or "\x00" in d["scene"]:
        _fail(src, pre + "scene", "must be a file name")
    _vector(d, "qpos0", src, pre, QPOS_MAX)
    _vector(d, "qvel0", src, pre, QVEL_MAX)
    dur = d["duration"]
    if isinstance(dur, bool) or not isinstance(dur, (int, float)) or not 0 < dur <= 60:
        _fail(src, pre + "duration", "must be a number of seconds in (0, 60]")
    if not (isinstance(d["down"], list) and all(isinstance(n, int) and not isinstance(n, bool) and 1 <= n <= 10
                                                  for n in d["down"])):
        _fail(src, pre + "down", "must be a list of pin numbers 1..10")
    if d["pins"] != scene.pin_names():
        _fail(src, pre + "pins", f"must be the 10 pin bodies in pin-number order, {scene.pin_names()}")
    for k in ("requested",):
        if k in d and not (isinstance(d[k], list) and all(isinstance(n, int) and not isinstance(n, bool)
                                                           and 1 <= n <= 10 for n in d[k])):
            _fail(src, pre + k, "must be a list of pin numbers 1..10")
    if "launch" in d:
        la = d["launch"]
        if not isinstance(la, dict) or not all(isinstance(la.get(k), (int, float)) and not isinstance(la.get(k), bool)
                                               for k in deck.KEYS):
            _fail(src, pre + "launch", f"must hold the numbers {', '.join(deck.KEYS)}")
        for k in deck.KEYS:  # a recorded output: within the delivery's own bounds, as the search clamps it
            lo, hi = deck.BOUNDS[k]
            if not lo <= la[k] <= hi:
                _fail(src, f"{pre}launch.{k}", f"{la[k]:g} is outside [{lo:g}, {hi:g}]")
    _recorded(d, src, pre)
    return d


def _recorded(d: dict, src, pre: str) -> None:
    """The recorded outputs beside the replayed fields, each to its domain when present: the
    timestep, the Hamming distance, whether it was found, the robustness probes' figures."""
    def number(v, field: str, lo: float, hi: float, integer: bool = False) -> None:
        if isinstance(v, bool) or not isinstance(v, int if integer else (int, float)) or not lo <= v <= hi:
            kind = "a whole number" if integer else "a number"
            _fail(src, pre + field, f"must be {kind} in [{lo:g}, {hi:g}], got {json.dumps(v)[:40]}")

    if "timestep" in d:
        number(d["timestep"], "timestep", 1e-6, 0.1)
    if "hamming" in d:
        number(d["hamming"], "hamming", 0, 10, integer=True)
    if "found" in d and not isinstance(d["found"], bool):
        _fail(src, pre + "found", f"must be true or false, got {json.dumps(d['found'])[:40]}")
    rob = d.get("robustness")
    if rob is not None:
        if not isinstance(rob, dict):
            _fail(src, pre + "robustness", "must be an object or null")
        for k, v in rob.items():
            if k.endswith("_rollouts"):
                number(v, f"robustness.{k}", 0, 10_000_000, integer=True)
            elif k in ("lateral_m", "speed_m_s"):
                number(v, f"robustness.{k}", 0, 1_000)


def resolve_scene(doc_path, name: str, src, field: str = "scene") -> Path:
    """The scene file a throw or atlas at ``doc_path`` names: inside the document's own folder,
    or the shipped scene; anything else (an absolute path elsewhere, ``../``, a link out of
    the folder) is refused with one line naming the path."""
    try:
        folder = Path(doc_path).resolve().parent
        cand = (folder / name).resolve()
    except (OSError, RuntimeError, ValueError) as e:  # a name too long, a link loop
        _fail(src, field, f"{name[:80]!r}: cannot resolve ({getattr(e, 'strerror', None) or e})")
    if cand == SHIPPED_SCENE or cand.is_relative_to(folder):
        return cand
    _fail(src, field, f"{name!r} resolves to {cand}, outside the file's own folder {folder}; a scene must sit "
                      f"in that folder (or be nbst's shipped scene)")


def read_scene_text(xml_path, src, field: str = "scene") -> str:
    """The text of a scene file: a regular file (stat first), at most MAX_SCENE_BYTES, UTF-8."""
    p = Path(xml_path)
    try:
        regular_file(p)
    except ThrowFileError as e:
        _fail(src, field, str(e))
    try:
        with open(p, "rb") as f:
            data = f.read(MAX_SCENE_BYTES + 1)
    except OSError as e:
        _fail(src, field, f"cannot read {p} ({e.strerror or e})")
    if len(data) > MAX_SCENE_BYTES:
        _fail(src, field, f"{p} is larger than {MAX_SCENE_BYTES:,} bytes; not a bowling scene")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        _fail(src, field, f"{p} is not a text file (not UTF-8)")


def load_scene(xml_path, src, field: str = "scene"):
    """(MjModel, XML text) of a bowling scene file, read through the gate and parsed by MuJoCo
    from the text read (MuJoCo opens no file); ThrowFileError naming ``src`` and ``field``."""
    import mujoco

    p = Path(xml_path)
    text = read_scene_text(p, src, field)
    if _READS_FILES.search(text):
        _fail(src, field, f"{p} reads other files (file=, include or a *dir attribute); a bowling scene is one "
                          f"self-contained XML")
    try:
        with mujoco_warnings_raise():
            model = mujoco.MjModel.from_xml_string(text)
    except (ValueError, MujocoError) as e:
        why = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
        _fail(src, field, f"cannot load {p} as a MuJoCo scene ({why})")
    for j in SCENE_JOINTS:
        try:
            model.joint(j)
        except KeyError:
            _fail(src, field, f"{p} is not a bowling scene (it has no joint {j!r})")
    try:
        model.geom("ball")
        for n in scene.pin_names():
            model.body(n)
    except KeyError as e:
        _fail(src, field, f"{p} is not a bowling scene (it has no {e.args[0] if e.args else 'ball or pin'})")
    if not (model.opt.timestep > 0 and math.isfinite(model.opt.timestep)):
        _fail(src, field, f"{p}: timestep {model.opt.timestep:g} must be a positive number")
    return model, text


def check_against_scene(d: dict, model, src, pre: str = "") -> None:
    """The throw's shapes fit ``model``: qpos0/qvel0 lengths, a bounded number of steps."""
    if len(d["qpos0"]) != model.nq or len(d["qvel0"]) != model.nv:
        _fail(src, f"{pre}qpos0/{pre}qvel0", f"sizes {len(d['qpos0'])}/{len(d['qvel0'])} do not fit the scene "
                                              f"(nq {model.nq}, nv {model.nv})")
    steps = float(d["duration"]) / model.opt.timestep
    if not steps <= MAX_STEPS:
        _fail(src, pre + "duration", f"{d['duration']:g} s at the scene's step {model.opt.timestep:g} s is "
                                     f"{steps:.3g} steps; at most {MAX_STEPS:,}")


def load(path) -> dict:
    """Read and check a throw file (not its scene: :func:`load_with_scene`); ThrowFileError
    naming the file and field.

    Args:
        path: a 5 m throw file.

    Returns:
        the checked throw dict.

    Raises:
        ThrowFileError: the file or a field refused (one line, file and field).
    """
    return check_throw(read_doc(path), path)


def load_with_scene(path):
    """(throw dict, MjModel, scene path) of a throw file, everything checked: the scene resolved
    inside the throw's folder (or the shipped scene), parsed, and the shapes fitting it."""
    d = load(path)
    xml = resolve_scene(path, d["scene"], path)
    model, _ = load_scene(xml, path)
    check_against_scene(d, model, path)
    return d, model, xml


ATLAS_KIND = "nbst-bowling-atlas"


def load_atlas(path):
    """(atlas dict, MjModel, scene XML text) of a 5 m atlas file, every throw (its ``shots``, the
    format's first name) checked like a throw file (field paths ``shots[i].qpos0``) against the
    atlas's scene."""
    a = read_doc(path)
    if not isinstance(a, dict) or a.get("kind") != ATLAS_KIND:
        _fail(path, "", f"not an nbst bowling atlas (kind must be {ATLAS_KIND!r})")
    for k in ("scene", "shots"):
        if k not in a:
            _fail(path, k, "missing")
    if not isinstance(a["scene"], str) or not a["scene"] or "\x00" in a["scene"]:
        _fail(path, "scene", "must be a file name")
    shots = a["shots"]
    if not isinstance(shots, list) or len(shots) > geometry.N_SUBSETS:
        _fail(path, "shots", f"must be a list of at most {geometry.N_SUBSETS} throws (one per subset)")
    seed = a.get("seed")  # recorded outputs, to their domains when present
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed <= SEED_MAX):
        _fail(path, "seed", f"must be null or a whole number in [0, 2^63-1], got {json.dumps(seed)[:40]}")
    n = a.get("subsets")
    if n is not None and (isinstance(n, bool) or not isinstance(n, int) or not 0 <= n <= geometry.N_SUBSETS):
        _fail(path, "subsets", f"must be a whole number in [0, {geometry.N_SUBSETS}], got {json.dumps(n)[:40]}")
    seen = set()
    for i, d in enumerate(shots):
        check_throw(d, path, f"shots[{i}].")
        key = tuple(sorted(set(d["down"])))
        if not key or key in seen:
            _fail(path, f"shots[{i}].down", "empty or the same subset as an earlier throw")
        seen.add(key)
    xml = resolve_scene(path, a["scene"], path)
    try:
        missing = not os.path.lexists(xml)
    except (OSError, ValueError):
        missing = True
    if missing:  # the common mistake: an atlas copied without its scene
        _fail(path, "scene", f"its throws need their scene {a['scene']!r} beside it, and {xml} is missing "
                             f"(copy it from where the atlas came from)")
    model, text = load_scene(xml, path)
    for i, d in enumerate(shots):
        check_against_scene(d, model, path, f"shots[{i}].")
    return a, model, text


def replay(model, qpos0, qvel0, duration: float, rule_: dict | None = None) -> list[int]:
    """Pins down after a plain ``mj_step`` replay from a fresh MjData (pin numbers).
    MuJoCo's warnings (a diverging state) raise :class:`MujocoError`."""
    q = deck.replay_final_qpos(model, np.asarray(qpos0, float), np.asarray(qvel0, float), duration)
    return pinfall.pins_of(int(pinfall.mask_of(pinfall.pins_down(model, q[None, :]))[0]))


def replay_file(path) -> tuple[dict, list[int]]:
    """(throw dict, pins down) replaying ``path`` with its own scene file.

    Args:
        path: a 5 m throw file (its scene beside it, or the shipped scene).

    Returns:
        (the checked throw dict, the pins down after the replay, sorted).

    Raises:
        ThrowFileError: the file, its scene or a field refused, or MuJoCo warned.
    """
    d, model, _ = load_with_scene(path)
    try:
        return d, replay(model, d["qpos0"], d["qvel0"], float(d["duration"]))
    except MujocoError as e:
        raise ThrowFileError(f"{path}: qpos0/qvel0: {e}") from None
