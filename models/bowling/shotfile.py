"""Shot files: what ``nbst bowl solve`` writes and ``nbst bowl replay`` reads.

A shot file is JSON that any MuJoCo user can replay without nbst (docs/bowling.md):

* ``scene``: the MJCF file, relative to the shot file (written beside it, every
  number at full precision; it also holds the shot as keyframe ``shot``);
* ``qpos0``, ``qvel0``: the full initial state (JSON floats written by ``repr``:
  exact); ``duration`` (s) and ``timestep`` (s);
* ``pins``: the 10 pin body names in pin-number order; ``down``: the pin numbers down
  at the end; ``rule``: how "down" is decided (tilt, below-deck depth, pit edge, lane
  half-width);
* ``launch``: the human-readable throw; ``robustness``: the largest lateral and speed
  changes that keep the outcome; ``requested``, ``found``, ``hamming``, ``search``.

Compute apart from I/O: :func:`shot_dict` and :func:`replay` take values; the writers
are thin.
"""
from __future__ import annotations

import json
import math
import os
import re
import stat
from pathlib import Path

import numpy as np

from nbst.errors import InputError
from nbst.models.bowling import scene, shot

SCHEMA_VERSION = 1
KIND = "nbst-bowling-shot"


class ShotFileError(InputError):
    """A shot file that cannot be read; the message names the file and the field."""


def scene_with_shot(qpos0, qvel0) -> str:
    """Scene XML (full precision) with keyframe ``shot`` = (qpos0, qvel0)."""
    spec = scene.build_spec()
    key = spec.add_key()
    key.name = "shot"
    key.time = 0.0
    key.qpos = [float(v) for v in qpos0]
    key.qvel = [float(v) for v in qvel0]
    return scene.scene_xml(spec)


def rule() -> dict:
    return {"tilt_deg": shot.DOWN_TILT_DEG, "below_deck_m": shot.LEFT_DECK_DEPTH,
            "pit_edge_x_m": scene.PIT_EDGE_X, "lane_half_width_m": scene.LANE_WIDTH / 2}


def shot_dict(model, launch, *, scene_name: str, down_mask: int, requested=None, robustness=None,
              search=None) -> dict:
    """The shot file's content for ``launch`` ((4,) array) whose outcome is ``down_mask``."""
    import mujoco

    qpos0, qvel0 = shot.initial_qpos_qvel(model, launch)
    lau = shot.Launch.from_array(shot.clamp(launch))
    d = {
        "schema_version": SCHEMA_VERSION,
        "kind": KIND,
        "scene": scene_name,
        "qpos0": [float(v) for v in qpos0],
        "qvel0": [float(v) for v in qvel0],
        "duration": shot.DURATION,
        "timestep": float(model.opt.timestep),
        "pins": scene.pin_names(),
        "down": shot.pins_of(down_mask),
        "rule": rule(),
        "launch": {**lau.to_dict(), "units": {"y": "m (+ = bowler's left)", "speed": "m/s",
                                              "angle": "deg (+ = towards the left)",
                                              "spin": "rad/s about the travel direction (+ hooks right)"}},
        "mujoco": mujoco.__version__,
    }
    if requested is not None:
        req = int(requested)
        d["requested"] = shot.pins_of(req)
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
            raise ValueError(f"{k} has a non-finite number")
    return json.dumps(d, indent=1) + "\n"


# --------------------------------------------------------------------------- the input gate
# Every shot and atlas file, and the scene XML it names, comes in through here: regular files
# only (checked by stat before opening: a FIFO would block, a device never end), the core JSON
# reader of nbst.problem (size cap first, strict JSON, depth, big integers), every number
# finite, the state bounded, the shapes checked against the scene, the scene inside the
# document's own folder (or the shipped scene). One ShotFileError line names file and field.

#: Largest scene XML read (bytes): the shipped scene is ~90 kB (its pin meshes inline).
MAX_SCENE_BYTES = 8 * 1024 * 1024
#: Bound on every qpos entry (m, or quaternion components): the simulated lane is 6.4 m
#: long and the pit 1 m deep; 1e3 leaves room for any real state and keeps MuJoCo's
#: squares and products far from float64 overflow (1e300 reaches inf in one step).
QPOS_MAX = 1e3
#: Bound on every qvel entry (m/s, rad/s): a launch is at most 10 m/s and ~125 rad/s
#: (rolling at 10 m/s plus 30 rad/s of spin, shot.BOUNDS).
QVEL_MAX = 1e3
#: Longest replay (steps): duration <= 60 s at the scene's 1 ms step is 60,000; a scene
#: with a tiny timestep would make a replay that never ends.
MAX_STEPS = 60_000
#: The shipped scene (models/bowling/scene.xml), which any shot may name.
SHIPPED_SCENE = Path(__file__).resolve().with_name("scene.xml")
#: The shipped atlas (one throw for each subset found; ``nbst bowl solve`` starts from it).
SHIPPED_ATLAS = SHIPPED_SCENE.with_name("atlas.json")
#: Joints and geoms every bowling scene has (the replay, the rule and the render use them).
SCENE_JOINTS = ("ball_free", *(f"pin{n}_free" for n in scene.PIN_NUMBERS))
#: A scene may not read other files (meshes, textures, includes): it is one self-contained XML.
_READS_FILES = re.compile(r"\bfile\s*=|<\s*include\b|\b(?:mesh|texture|asset)dir\s*=", re.IGNORECASE)


def regular_file(path, what: str = "") -> Path:
    """``path`` if it is a regular file (stat, before any open), else ShotFileError: a FIFO,
    device, socket or directory is refused without being opened."""
    p = Path(path)
    where = f"{p}: {what}: " if what else f"{p}: "
    try:
        st = os.stat(p)
    except FileNotFoundError:
        raise ShotFileError(f"{where}no such file") from None
    except (OSError, ValueError) as e:  # ValueError: a NUL in the name
        raise ShotFileError(f"{where}cannot read ({getattr(e, 'strerror', None) or e})") from None
    if stat.S_ISDIR(st.st_mode):
        raise ShotFileError(f"{where}is a directory, not a file")
    if not stat.S_ISREG(st.st_mode):
        raise ShotFileError(f"{where}is not a regular file (a FIFO, device or socket); nbst reads regular files only")
    return p


def read_doc(path):
    """Decoded JSON of a shot or atlas file through nbst's core reader; ShotFileError, one line."""
    from nbst.problem import ProblemError, read_json

    regular_file(path)
    try:
        return read_json(path)
    except ProblemError as e:
        raise ShotFileError(str(e)) from None


def _fail(src, field: str, why: str):
    raise ShotFileError(f"{src}: {field}: {why}" if field else f"{src}: {why}")


def _non_finite(obj, path: str):
    """First (path, value) of a non-finite float in decoded JSON (NaN, Infinity), or None."""
    stack = [(obj, path)]
    while stack:
        o, p = stack.pop()
        if isinstance(o, float) and not math.isfinite(o):
            return p, o
        if isinstance(o, dict):
            stack.extend((v, f"{p}.{k}" if p else str(k)) for k, v in o.items())
        elif isinstance(o, list):
            stack.extend((v, f"{p}[{i}]") for i, v in enumerate(o))
    return None


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


def check_shot(d, src, pre: str = "") -> dict:
    """Check a decoded shot (structure, types, finite and bounded numbers; not yet the
    scene's shapes: :func:`check_against_scene`); ``pre`` prefixes field paths
    (``shots[3].``). Returns ``d``."""
    if not isinstance(d, dict) or d.get("kind") != KIND:
        _fail(src, pre.rstrip("."), f"not an nbst bowling shot (kind must be {KIND!r})")
    for k in ("scene", "qpos0", "qvel0", "duration", "pins", "down"):
        if k not in d:
            _fail(src, pre + k, "missing")
    bad = _non_finite(d, pre.rstrip("."))
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
                                               for k in shot.KEYS):
            _fail(src, pre + "launch", f"must hold the numbers {', '.join(shot.KEYS)}")
    return d


def resolve_scene(doc_path, name: str, src, field: str = "scene") -> Path:
    """The scene file a shot or atlas at ``doc_path`` names: inside the document's own folder,
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
    except ShotFileError as e:
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
    from the text read (MuJoCo opens no file); ShotFileError naming ``src`` and ``field``."""
    import mujoco

    p = Path(xml_path)
    text = read_scene_text(p, src, field)
    if _READS_FILES.search(text):
        _fail(src, field, f"{p} reads other files (file=, include or a *dir attribute); a bowling scene is one "
                          f"self-contained XML")
    try:
        with shot.mujoco_warnings_raise():
            model = mujoco.MjModel.from_xml_string(text)
    except (ValueError, shot.MujocoError) as e:
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
    """The shot's shapes fit ``model``: qpos0/qvel0 lengths, a bounded number of steps."""
    if len(d["qpos0"]) != model.nq or len(d["qvel0"]) != model.nv:
        _fail(src, f"{pre}qpos0/{pre}qvel0", f"sizes {len(d['qpos0'])}/{len(d['qvel0'])} do not fit the scene "
                                              f"(nq {model.nq}, nv {model.nv})")
    steps = float(d["duration"]) / model.opt.timestep
    if not steps <= MAX_STEPS:
        _fail(src, pre + "duration", f"{d['duration']:g} s at the scene's step {model.opt.timestep:g} s is "
                                     f"{steps:.3g} steps; at most {MAX_STEPS:,}")


def load(path) -> dict:
    """Read and check a shot file (not its scene: :func:`load_with_scene`); ShotFileError
    naming the file and field."""
    return check_shot(read_doc(path), path)


def load_with_scene(path):
    """(shot dict, MjModel, scene path) of a shot file, everything checked: the scene resolved
    inside the shot's folder (or the shipped scene), parsed, and the shapes fitting it."""
    d = load(path)
    xml = resolve_scene(path, d["scene"], path)
    model, _ = load_scene(xml, path)
    check_against_scene(d, model, path)
    return d, model, xml


ATLAS_KIND = "nbst-bowling-atlas"


def load_atlas(path):
    """(atlas dict, MjModel, scene XML text) of an atlas file, every shot checked like a shot
    file (field paths ``shots[i].qpos0``) against the atlas's scene."""
    from nbst.models.bowling import geometry

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
        _fail(path, "shots", f"must be a list of at most {geometry.N_SUBSETS} shots (one per subset)")
    seen = set()
    for i, d in enumerate(shots):
        check_shot(d, path, f"shots[{i}].")
        key = tuple(sorted(set(d["down"])))
        if not key or key in seen:
            _fail(path, f"shots[{i}].down", "empty or the same subset as an earlier shot")
        seen.add(key)
    xml = resolve_scene(path, a["scene"], path)
    try:
        missing = not os.path.lexists(xml)
    except (OSError, ValueError):
        missing = True
    if missing:  # the common mistake: an atlas copied without its scene
        _fail(path, "scene", f"its shots need their scene {a['scene']!r} beside it, and {xml} is missing "
                             f"(copy it from where the atlas came from)")
    model, text = load_scene(xml, path)
    for i, d in enumerate(shots):
        check_against_scene(d, model, path, f"shots[{i}].")
    return a, model, text


def replay(model, qpos0, qvel0, duration: float, rule_: dict | None = None) -> list[int]:
    """Pins down after a plain ``mj_step`` replay from a fresh MjData (pin numbers).
    MuJoCo's warnings (a diverging state) raise :class:`shot.MujocoError`."""
    q = shot.replay_final_qpos(model, np.asarray(qpos0, float), np.asarray(qvel0, float), duration)
    return shot.pins_of(int(shot.mask_of(shot.pins_down(model, q[None, :]))[0]))


def replay_file(path) -> tuple[dict, list[int]]:
    """(shot dict, pins down) replaying ``path`` with its own scene file."""
    d, model, _ = load_with_scene(path)
    try:
        return d, replay(model, d["qpos0"], d["qvel0"], float(d["duration"]))
    except shot.MujocoError as e:
        raise ShotFileError(f"{path}: qpos0/qvel0: {e}") from None
