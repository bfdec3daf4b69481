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
from pathlib import Path

import numpy as np

from nbst.models.bowling import scene, shot

SCHEMA_VERSION = 1
KIND = "nbst-bowling-shot"


class ShotFileError(ValueError):
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
        d["hamming"] = bin(req ^ int(down_mask)).count("1")
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


def load(path) -> dict:
    """Read and check a shot file; ShotFileError naming the file and field."""
    p = Path(path)
    try:
        d = json.loads(p.read_text())
    except OSError as e:
        raise ShotFileError(f"{path}: cannot read ({e.strerror or e})") from None
    except json.JSONDecodeError as e:
        raise ShotFileError(f"{path}: not JSON ({e.msg} at line {e.lineno})") from None
    if not isinstance(d, dict) or d.get("kind") != KIND:
        raise ShotFileError(f"{path}: not an nbst bowling shot (kind must be {KIND!r})")
    for k in ("scene", "qpos0", "qvel0", "duration", "pins", "down"):
        if k not in d:
            raise ShotFileError(f"{path}: {k}: missing")
    if not isinstance(d["scene"], str):
        raise ShotFileError(f"{path}: scene: must be a file name")
    for k in ("qpos0", "qvel0"):
        if not (isinstance(d[k], list) and all(isinstance(v, (int, float)) for v in d[k])):
            raise ShotFileError(f"{path}: {k}: must be a list of numbers")
    if not (isinstance(d["duration"], (int, float)) and 0 < d["duration"] <= 60):
        raise ShotFileError(f"{path}: duration: must be a number of seconds in (0, 60]")
    if not (isinstance(d["down"], list) and all(isinstance(n, int) and 1 <= n <= 10 for n in d["down"])):
        raise ShotFileError(f"{path}: down: must be a list of pin numbers 1..10")
    return d


def replay(model, qpos0, qvel0, duration: float, rule_: dict | None = None) -> list[int]:
    """Pins down after a plain ``mj_step`` replay from a fresh MjData (pin numbers)."""
    q = shot.replay_final_qpos(model, np.asarray(qpos0, float), np.asarray(qvel0, float), duration)
    return shot.pins_of(int(shot.mask_of(shot.pins_down(model, q[None, :]))[0]))


def replay_file(path) -> tuple[dict, list[int]]:
    """(shot dict, pins down) replaying ``path`` with its own scene file."""
    import mujoco

    d = load(path)
    xml = Path(path).parent / d["scene"]
    try:
        model = mujoco.MjModel.from_xml_path(str(xml))
    except (ValueError, OSError) as e:
        why = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
        raise ShotFileError(f"{path}: scene: cannot load {xml} ({why})") from None
    if len(d["qpos0"]) != model.nq or len(d["qvel0"]) != model.nv:
        raise ShotFileError(f"{path}: qpos0/qvel0: sizes {len(d['qpos0'])}/{len(d['qvel0'])} do not fit the scene "
                            f"(nq {model.nq}, nv {model.nv})")
    return d, replay(model, d["qpos0"], d["qvel0"], float(d["duration"]))
