"""The scene solution file (``"format": "nbst-scene-solution"``, version 1) and its replay.

A solution file records what the search found (docs/scene.md, "The solution file"): the fates file
and the scene it was solved for (absolute paths, and the scene's SHA-256), the timestep and steps,
the controls chosen per body, the initial state (``qpos0``, ``qvel0``; JSON keeps every float's
bits), the final state the search saw, the verdict of every fate, the seed, the search's numbers
and the versions of nbst and MuJoCo.

:func:`replay_solution` rolls ``qpos0``/``qvel0`` out with the plain ``mj_step`` loop of
docs/scene.md (``nbst.scene.rollout.replay``) and compares the final state with the file's, bit for
bit; it also judges the fates again. :func:`ladder_solution` rolls the same initial state out at
h/2 and h/4: does the motion still meet its fates when the integrator is finer? :func:`export_scene` writes the user's MJCF with one more
keyframe, holding the found initial state at full precision: loaded in ``python -m mujoco.viewer``
and reset to that key, it plays the same motion (checked bit for bit before the file is kept).

Length: a little past 510 lines, as reading, replaying, picking and exporting one file format share
its checks (the moved folder's, the fates file given by mistake) here.
"""
from __future__ import annotations

import hashlib
import json
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from nbst._version import __version__
from nbst.errors import InputError
from nbst.files import read_regular
from nbst.models.mjsearch.ladder import Ladder, climb
from nbst.models.mjsearch.probability import Probability
from nbst.scene.fates import Fates
from nbst.scene.scenefile import load_fates
from nbst.scene.judge import Judgement, signature_text
from nbst.scene.rollout import SceneRollout, SceneSim, quiet_mujoco_warnings, replay

__all__ = ["SOLUTION_FORMAT", "SOLUTION_VERSION", "EXPORT_KEY", "SceneSolutionError", "SceneResult", "SceneReplay",
           "solution_dict", "read_solution", "replay_solution", "ladder_solution", "file_sha256", "scene_changed",
           "export_scene"]

#: The name of the keyframe :func:`export_scene` adds (``nbst_1``, ... if the scene has one by that name).
EXPORT_KEY = "nbst"

SOLUTION_FORMAT = "nbst-scene-solution"
SOLUTION_VERSION = 1
_MAX_BYTES = 64 * 2**20


class SceneSolutionError(InputError):
    """A scene solution file nbst refuses: one line, ``FILE: FIELD: why``."""


@dataclass(frozen=True)
class SceneResult:
    """What ``nbst.scene.solve`` returns.

    Args:
        fates: the checked fates solved for.
        model: the compiled ``mujoco.MjModel`` (its timestep set).
        best: the best rollout found: its controls, initial and final state, verdicts.
        met: every fate met (and MuJoCo did not warn; with ``ladder``, at the finer steps too).
        rollouts: rollouts spent.
        stopped: ``"met"``, ``"budget"`` or ``"interrupted"``.
        seed: the seed used (drawn when none was given).
        max_rollouts: the budget asked.
        wall_time: seconds.
        signatures: distinct signatures seen.
        nstep: steps per rollout.
        key: the keyframe's index (-1: none).
        probability: how often the best controls meet every fate under the fates' noise (None:
            not asked, or interrupted).
        answers: with ``answers`` > 1: the rollouts that meet every fate, each with a contact
            sequence of its own, the best first.
        answer_probabilities: each answer's probability (with ``samples``).
        ladder: with ``ladder``: the timesteps asked, h first.
        ladder_held: whether the best meets every fate at each of them (None: not asked or not met).
        robust: with ``robust``: the maximiser's budget, rollouts, screens (k of m before and
            after), its screen's seed and the pick's ladder rows (None: not asked).
        interrupted: what an interrupt cut short after the search ended by itself (``"robust"``,
            ``"samples"``, ``"answers' samples"``): ``stopped`` keeps the search's own reason, and
            the probabilities are None (None: nothing was cut short after the search).
    """

    fates: Fates
    model: Any
    best: SceneRollout
    met: bool
    rollouts: int
    stopped: str
    seed: int
    max_rollouts: int
    wall_time: float
    signatures: int
    nstep: int
    key: int
    probability: Probability | None = None
    answers: tuple[SceneRollout, ...] = ()
    answer_probabilities: tuple[Probability, ...] = ()
    ladder: tuple[float, ...] = ()
    ladder_held: bool | None = None
    robust: dict | None = None
    interrupted: str | None = None

    @property
    def judgement(self) -> Judgement:
        return self.best.judgement


def file_sha256(path: str | os.PathLike) -> str:
    """The SHA-256 of a file's bytes, in hex."""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def scene_changed(doc: dict, fates: Fates) -> bool:
    """Whether the solution's scene file changed since it was solved (its SHA-256 is not the one the
    file recorded; a file without one is not said to have changed)."""
    return scene_changed_at(doc, fates.scene)


def scene_changed_at(doc: dict, scene: str | os.PathLike | None = None) -> bool:
    """:func:`scene_changed` of the scene file ``scene`` (default the one ``doc`` names)."""
    p = Path(doc["scene"] if scene is None else scene)
    return doc.get("scene_sha256") is not None and p.is_file() and doc["scene_sha256"] != file_sha256(p)


def _controls(fates: Fates, x: np.ndarray) -> dict:
    out: dict = {}
    for c, sl in zip(fates.controls, fates.blocks()):
        v = x[sl]
        out[c.body] = {part: [float(a) for a in v[3 * k:3 * k + 3]] for k, (part, _) in enumerate(c.parts())}
    return out


def _probability(p: Probability, f: Fates, seed: int) -> dict:
    return {"k": p.k, "n": p.n, "p": p.p, "lo": p.lo, "hi": p.hi, "noise": [float(a) for a in f.noise()], "seed": seed}


def _answer(r: SceneRollout, f: Fates, p: Probability | None, seed: int) -> dict:
    return {"sequence": list(r.sequence), "controls": _controls(f, r.x), "x": [float(a) for a in r.x],
            "qpos0": [float(a) for a in r.qpos0], "qvel0": [float(a) for a in r.qvel0],
            "final": {"qpos": [float(a) for a in r.qpos], "qvel": [float(a) for a in r.qvel]},
            **({} if p is None else {"probability": _probability(p, f, seed)})}


def solution_dict(res: SceneResult) -> dict:
    """The solution file's JSON object for a result (see the module docstring).

    Raises:
        SceneSolutionError: ``res`` is not a :class:`SceneResult`.
    """
    import mujoco

    if not isinstance(res, SceneResult):
        raise SceneSolutionError(f"solution_dict takes the SceneResult that solve returns, got {type(res).__name__}")
    f, b = res.fates, res.best
    src = Path(f.source)
    return {
        "format": SOLUTION_FORMAT, "version": SOLUTION_VERSION,
        "fates": f.source,
        "fates_file": str(src.resolve()) if src.is_file() else None,
        "fates_sha256": file_sha256(src) if src.is_file() else None,
        "scene": str(f.scene.resolve()),
        "scene_sha256": file_sha256(f.scene),
        "keyframe": f.keyframe,
        "timestep": float(res.model.opt.timestep),
        "nstep": res.nstep,
        "duration": f.duration,
        "met": res.met,
        "signature": signature_text(b.signature),
        "cost": b.cost,
        "controls": _controls(f, b.x),
        "x": [float(a) for a in b.x],
        "qpos0": [float(a) for a in b.qpos0],
        "qvel0": [float(a) for a in b.qvel0],
        "final": {"qpos": [float(a) for a in b.qpos], "qvel": [float(a) for a in b.qvel]},
        "verdicts": b.judgement.to_dict()["bodies"],
        "warnings": list(b.warnings),
        "seed": res.seed,
        "search": {"rollouts": res.rollouts, "stopped": res.stopped, "max_rollouts": res.max_rollouts,
                   "wall_time_s": round(res.wall_time, 2), "signatures": res.signatures},
        "versions": {"nbst": __version__, "mujoco": mujoco.__version__},
        **({} if res.probability is None else {"probability": _probability(res.probability, f, res.seed)}),
        **({} if not res.ladder else {"ladder": {"timesteps": list(res.ladder), "holds": bool(res.ladder_held)}}),
        **({} if res.robust is None else {"robust": res.robust}),
        **({} if res.interrupted is None else {"interrupted": res.interrupted}),
        **({} if not res.answers else {"answers": [
            _answer(a, f, res.answer_probabilities[k] if k < len(res.answer_probabilities) else None, res.seed)
            for k, a in enumerate(res.answers)]}),
    }


def _floats(doc: dict, key: str, n: int, path: str) -> np.ndarray:
    v: Any = doc
    for k in key.split("."):
        v = v.get(k) if isinstance(v, dict) else None
    if not isinstance(v, list) or len(v) != n or not all(
            isinstance(a, (int, float)) and not isinstance(a, bool) and math.isfinite(a) for a in v):
        raise SceneSolutionError(f"{path}: {key}: must be a list of {n} finite numbers")
    return np.array(v, dtype=float)


def read_solution(path: str | os.PathLike) -> dict:
    """Read a solution file and check its format, version and fields' types.

    Args:
        path: the solution JSON file.

    Returns:
        the JSON object (its arrays still lists; :func:`replay_solution` checks their lengths
        against the model).

    Raises:
        SceneSolutionError: not JSON, another format or version, a field missing or of the wrong type.
    """
    data = read_regular(path, max_bytes=_MAX_BYTES, what="scene solution file", allow_empty=False)
    try:
        doc = json.loads(data.decode("utf-8"))
    except (UnicodeDecodeError, ValueError) as e:
        raise SceneSolutionError(f"{path}: not JSON ({e})") from None
    except RecursionError:
        raise SceneSolutionError(f"{path}: not accepted: nested too deeply") from None
    if isinstance(doc, dict) and doc.get("format") == "nbst-fates":
        raise SceneSolutionError(f"{path}: format: a fates file, not a solution: solve it first (`nbst scene solve "
                                 f"{path} -o sol.json`), then give the solution")
    if not isinstance(doc, dict) or doc.get("format") != SOLUTION_FORMAT:
        raise SceneSolutionError(f"{path}: format: not a scene solution (expected {SOLUTION_FORMAT!r})")
    if doc.get("version") != SOLUTION_VERSION:
        raise SceneSolutionError(f"{path}: version: must be {SOLUTION_VERSION}, got {doc.get('version')!r}")
    for key, kind in (("scene", str), ("nstep", int), ("timestep", float), ("qpos0", list), ("qvel0", list),
                      ("final", dict), ("x", list)):
        v = doc.get(key)
        ok = isinstance(v, kind) or (kind is float and isinstance(v, int))
        if not ok or isinstance(v, bool):
            raise SceneSolutionError(f"{path}: {key}: missing or not a {kind.__name__}")
    if doc.get("fates_file") is None and not isinstance(doc.get("fates"), str):
        raise SceneSolutionError(f"{path}: fates: missing")
    _found_beside(doc, Path(path))
    return doc


def solution_reads(path: str | os.PathLike, doc: dict) -> list[str]:
    """The files that reading the solution ``path`` (``doc``, from :func:`read_solution`) reads
    again: itself, its fates file and its scene (the files the scene reads are :func:`export_scene`'s
    to refuse, by name). An output that is one of them would leave the solution unusable (a tester
    exported into the fates file)."""
    return [str(path), *(str(doc[k]) for k in ("fates_file", "scene") if isinstance(doc.get(k), str))]


def _found_beside(doc: dict, path: Path) -> None:
    """A solution moved (or sent) with its folder: where the recorded fates file or scene is gone,
    the file of the same name at the same place relative to the solution (the scene: relative to the
    fates file, as its ``"scene"`` says) is taken instead. The fates file only when its SHA-256 is
    the one recorded (another file of that name is not taken for it); its scene whenever it is there,
    as it would be read in place: edited since, it is told as changed (replay's ``scene_changed``,
    export's note), as in place."""
    def same(p: Path, digest: Any) -> bool:
        return isinstance(digest, str) and p.is_file() and file_sha256(p) == digest

    old_fates = doc.get("fates_file")
    if isinstance(old_fates, str) and not os.path.exists(old_fates):
        here = path.resolve().parent / Path(old_fates).name
        if same(here, doc.get("fates_sha256")):
            doc["fates_file"] = str(here)
            if not os.path.exists(doc["scene"]):
                rel = os.path.relpath(doc["scene"], Path(old_fates).parent)
                moved = (here.parent / rel).resolve()
                if moved.is_file():
                    doc["scene"] = str(moved)
        elif here.is_file():
            raise SceneSolutionError(f"{path}: fates_file: {old_fates} is gone, and {here} beside the solution is "
                                     f"not the fates file it was solved with (its SHA-256 differs)")


@dataclass(frozen=True)
class SceneReplay:
    """What :func:`replay_solution` found.

    Args:
        same: the plain ``mj_step`` loop ends in the file's final state, bit for bit.
        judgement: the fates judged again on the replayed motion.
        qpos: (nq,) the replayed final qpos; qvel: (nv,) its qvel.
        scene_changed: the scene's SHA-256 differs from the file's.
        fates_changed: the fates file's SHA-256 differs from the one it was solved with (the fates
            are read again from that file: edited since, they judge the motion anew).
    """

    same: bool
    judgement: Judgement
    qpos: np.ndarray
    qvel: np.ndarray
    scene_changed: bool
    fates_changed: bool = False


def replay_solution(path: str | os.PathLike) -> SceneReplay:
    """Replay a solution file with the plain ``mj_step`` loop and compare, bit for bit.

    Args:
        path: the solution file.

    Returns:
        the :class:`SceneReplay`.

    Raises:
        SceneSolutionError: the file is refused, or its state does not fit the model.
        FatesError: its fates file or scene is refused.
    """
    doc = read_solution(path)
    fates_path = doc.get("fates_file") or doc["fates"]
    fates, model = load_fates(fates_path, scene=doc["scene"])
    model.opt.timestep = float(doc["timestep"])
    nq, nv = int(model.nq), int(model.nv)
    q0, v0 = _floats(doc, "qpos0", nq, str(path)), _floats(doc, "qvel0", nv, str(path))
    qf, vf = _floats(doc, "final.qpos", nq, str(path)), _floats(doc, "final.qvel", nv, str(path))
    x = _floats(doc, "x", fates.dim, str(path))
    with quiet_mujoco_warnings(), SceneSim(fates, model) as sim:
        q, v = replay(model, q0, v0, int(doc["nstep"]), key=sim.key)
        judged = sim.rollout(x, state=(q0, v0))   # the file's state, as the loop plays it (an edited scene
        # would not give it again from the controls: a free body's moved <body pos> its qpos0 ignores)
    same = q.tobytes() == qf.tobytes() and v.tobytes() == vf.tobytes()
    changed = scene_changed(doc, fates)
    fates_changed = (doc.get("fates_sha256") is not None and doc.get("fates_file") is not None
                     and Path(fates_path).is_file() and doc["fates_sha256"] != file_sha256(Path(fates_path)))
    return SceneReplay(same=same, judgement=judged.judgement, qpos=q, qvel=v, scene_changed=changed,
                       fates_changed=fates_changed)


def ladder_solution(path: str | os.PathLike, *, divisors: tuple[int, ...] = (1, 2, 4)) -> Ladder:
    """Does the solution still meet every fate at a finer timestep? The same initial state rolled
    out for the same duration at h / k for each k of ``divisors`` (the rollout room's ladder).

    Args:
        path: the solution file.
        divisors: the rungs, h / k each (h: the solution's timestep).

    Returns:
        the ``nbst.models.mjsearch.ladder.Ladder``: per rung, whether every fate is met; ``holds``
        when all are; ``results`` the rollouts (their judgements say what happened).

    Raises:
        SceneSolutionError: the solution is refused.
        FatesError: its fates file or scene is refused (or a rung's steps pass the cap).
    """
    doc = read_solution(path)
    fates, model = load_fates(doc.get("fates_file") or doc["fates"], scene=doc["scene"])
    return _ladder(fates, model, float(doc["timestep"]), _floats(doc, "x", fates.dim, str(path)), divisors)


def _ladder(fates: Fates, model: Any, h: float, x: np.ndarray, divisors: tuple[int, ...]) -> Ladder:
    from nbst.scene.scenefile import check_against_model

    def run(step: float) -> SceneRollout:
        model.opt.timestep = step
        check_against_model(fates, model)  # the step cap, at this rung
        with quiet_mujoco_warnings(), SceneSim(fates, model) as sim:
            return sim.rollout(x)

    return climb(run, [h / k for k in divisors], outcome=lambda r: bool(r.judgement.met and not r.warnings),
                 wanted=True)


def pick_answer(path: str | os.PathLike, n: int) -> dict:
    """Answer ``n`` of a solution solved with ``--answers`` (0-based, as in its ``"answers"``) as a
    solution file of its own, which replay, validate, export and render take as they take any.

    Its controls, initial and final states are the answer's; it is rolled out again (its initial
    state and final state must come back bit for bit) and judged anew (verdicts, signature, cost),
    and its ladder is climbed again (h/2, h/4); its probability is the answer's. ``"picked"``
    records the file and the answer it came from, and its contact sequence.

    Raises:
        SceneSolutionError: the file is refused, has no answer ``n``, or the answer does not replay.
        FatesError: its fates file or scene is refused.
    """
    doc = read_solution(path)
    answers = doc.get("answers")
    if not isinstance(answers, list) or not answers:
        raise SceneSolutionError(f"{path}: answers: none: it was solved without --answers, so its one answer is "
                                 f"the file itself (use it as it is, or solve with --answers K to have several)")
    if not (isinstance(n, int) and 0 <= n < len(answers)) or not isinstance(answers[n], dict):
        raise SceneSolutionError(f"{path}: answers: no answer {n}; it has {len(answers)} (0 to {len(answers) - 1})")
    a = answers[n]
    fates, model = load_fates(doc.get("fates_file") or doc["fates"], scene=doc["scene"])
    model.opt.timestep = float(doc["timestep"])
    where = f"{path}: answers[{n}]"
    x = _floats(a, "x", fates.dim, where)
    q0, v0 = _floats(a, "qpos0", int(model.nq), where), _floats(a, "qvel0", int(model.nv), where)
    qf, vf = _floats(a, "final.qpos", int(model.nq), where), _floats(a, "final.qvel", int(model.nv), where)
    with quiet_mujoco_warnings(), SceneSim(fates, model) as sim:
        r = sim.rollout(x)
    if not all(u.tobytes() == w.tobytes() for u, w in ((r.qpos0, q0), (r.qvel0, v0), (r.qpos, qf), (r.qvel, vf))):
        raise SceneSolutionError(f"{where}: does not replay to its own states (the scene or MuJoCo changed since "
                                 f"the solve)")
    out = {k: v for k, v in doc.items() if k not in ("answers", "robust", "probability", "ladder")}
    out.update(met=bool(r.judgement.met and not r.warnings), signature=signature_text(r.signature), cost=r.cost,
               controls=a.get("controls", _controls(fates, x)), x=[float(v) for v in x],
               qpos0=[float(v) for v in q0], qvel0=[float(v) for v in v0],
               final={"qpos": [float(v) for v in qf], "qvel": [float(v) for v in vf]},
               verdicts=r.judgement.to_dict()["bodies"], warnings=list(r.warnings),
               picked={"from": str(Path(path).resolve()), "answer": n, "sequence": a.get("sequence", [])})
    if isinstance(a.get("probability"), dict):
        out["probability"] = a["probability"]
    if isinstance(doc.get("ladder"), dict):   # climbed again for this answer's controls
        ladder = _ladder(fates, model, float(doc["timestep"]), x, (1, 2, 4))
        out["ladder"] = {"timesteps": [float(doc["timestep"]) / k for k in (1, 2, 4)], "holds": bool(ladder.holds)}
        out["met"] = out["met"] and bool(ladder.holds)
    return out


def _key_text(values: np.ndarray) -> str:
    return " ".join(repr(float(v)) for v in np.asarray(values, dtype=float).ravel())


def export_scene(path: str | os.PathLike, out: str | os.PathLike) -> str:
    """Write the solution's scene with a keyframe holding its initial state (module docstring).

    The MJCF's own text is kept (comments and every number as written); added: a ``<key>`` named
    :data:`EXPORT_KEY` (time, qpos, qvel, act, ctrl and mocap of the solution's initial state, each
    float written with all its digits) and, when the fates set one, the timestep on ``<option>``.
    Before the file is kept, it is compiled, reset to the key and stepped ``nstep`` times with
    ``mj_step``: the final state must be the solution's, bit for bit.

    Args:
        path: the solution file.
        out: the MJCF to write; in the scene's folder when the scene reads other files (its
            includes, meshes, textures are found relative to it).

    Returns:
        the keyframe's name.

    Raises:
        SceneSolutionError: the solution is refused, or ``out`` is in another folder while the
            scene reads other files.
        FatesError: its fates file or scene is refused.
        OutputError: ``out`` cannot be written, or the exported scene does not replay bit for bit
            (nothing is written then).
    """
    import xml.etree.ElementTree as ET

    import mujoco

    from nbst.outputs import atomic_path
    from nbst.scene.scenefile import check_scene_files

    doc = read_solution(path)
    fates, model = load_fates(doc.get("fates_file") or doc["fates"], scene=doc["scene"])
    model.opt.timestep = float(doc["timestep"])
    files = check_scene_files(fates.scene, source=fates.source)
    outp = Path(out)
    if (same := [f for f in files if os.path.realpath(f) == os.path.realpath(outp)]):
        raise SceneSolutionError(f"{out}: is {same[0]}, a file the scene reads; give another file name")
    if len(files) > 1 and outp.resolve().parent != fates.scene.resolve().parent:
        home = fates.scene.resolve().parent
        others = ", ".join(os.path.relpath(os.path.realpath(f), home) for f in files[1:4]) + (
            ", ..." if len(files) > 4 else "")   # as the scene names them: parts/props.xml
        raise SceneSolutionError(f"{out}: the scene reads other files ({others}) found relative to its "
                                 f"folder: write the exported scene in {fates.scene.resolve().parent}")
    nq, nv = int(model.nq), int(model.nv)
    q0, v0 = _floats(doc, "qpos0", nq, str(path)), _floats(doc, "qvel0", nv, str(path))
    qf, vf = _floats(doc, "final.qpos", nq, str(path)), _floats(doc, "final.qvel", nv, str(path))
    if scene_changed(doc, fates):  # edited since the solve: is the motion still its? (else the written file's check)
        with quiet_mujoco_warnings(), SceneSim(fates, model) as sim:
            q, v = replay(model, q0, v0, int(doc["nstep"]), key=sim.key)
        if q.tobytes() != qf.tobytes() or v.tobytes() != vf.tobytes():
            raise SceneSolutionError(f"{path}: replayed in the scene as it is now, it does not end in the solution's "
                                     "final state bit for bit: the scene file changed since it was solved (solve it "
                                     "again); nothing was written")
    d = mujoco.MjData(model)
    with SceneSim(fates, model) as sim:
        sim._reset(d)
    names = {model.key(k).name for k in range(model.nkey)}
    name, k = EXPORT_KEY, 0
    while name in names:
        k += 1
        name = f"{EXPORT_KEY}_{k}"
    attrs = {"name": name, "time": repr(float(d.time)), "qpos": _key_text(q0), "qvel": _key_text(v0)}
    if model.na:
        attrs["act"] = _key_text(d.act)
    if model.nu:
        attrs["ctrl"] = _key_text(d.ctrl)
    if model.nmocap:
        attrs["mpos"], attrs["mquat"] = _key_text(d.mocap_pos), _key_text(d.mocap_quat)
    text = fates.scene.read_text(encoding="utf-8")
    root = ET.fromstring(text, parser=ET.XMLParser(target=ET.TreeBuilder(insert_comments=True)))
    if fates.timestep is not None:
        options = root.findall("option")
        if options:
            options[-1].set("timestep", repr(float(doc["timestep"])))
        else:
            opt = ET.Element("option", {"timestep": repr(float(doc["timestep"]))})
            opt.tail = root.text if root.text and not root.text.strip() else "\n  "   # on its own line
            root.insert(0, opt)
    if len(root):
        root[-1].tail = "\n  "
    keyframe = ET.SubElement(root, "keyframe")
    keyframe.text, keyframe.tail = "\n    ", "\n"
    key = ET.SubElement(keyframe, "key", attrs)
    key.tail = "\n  "
    body = ET.tostring(root, encoding="unicode")

    def check(partial: str) -> str | None:
        try:
            m = mujoco.MjModel.from_xml_path(partial)
        except ValueError as e:
            return f"MuJoCo will not compile it: {' '.join(str(e).split())}"
        data = mujoco.MjData(m)
        mujoco.mj_resetDataKeyframe(m, data, m.key(name).id)
        for _ in range(int(doc["nstep"])):
            mujoco.mj_step(m, data)
        if data.qpos.tobytes() != qf.tobytes() or data.qvel.tobytes() != vf.tobytes():
            return "reset to its key and stepped, it does not end in the solution's final state bit for bit"
        return None

    with atomic_path(out, check=check) as tmp:
        Path(tmp).write_text(body + "\n", encoding="utf-8")
    return name
