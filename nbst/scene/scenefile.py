"""The scene side of a fates file: the MJCF's files, its compilation, the names against the model.

:func:`load_fates` is the way in: it reads the fates file (``nbst.scene.fates.parse_fates``),
checks the MJCF's files (:func:`check_scene_files`: ``<include>``, mesh, texture, hfield, skin
and flexcomp files must lie under the scene's folder, meshes at most :data:`~nbst.scene.fates.MAX_MESH_BYTES`),
compiles the scene with MuJoCo (:func:`compile_scene`: MuJoCo's message, with the line, when it
will not) and checks the fates' names against the model (:func:`check_against_model`: bodies,
geoms, free joints, the keyframe, the step cap). Every refusal is one line naming the file and the
field (:class:`~nbst.scene.fates.FatesError`).

mujoco is imported only inside the functions that need it.
"""
from __future__ import annotations

import difflib
import os
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import numpy as np

from nbst.files import FileRefused, read_regular
from nbst.scene.fates import (MAX_MESH_BYTES, MAX_SCENE_BYTES, MAX_STEPS, STILL_DISTANCE, Fates, FatesError, _Src,
                              parse_fates, read_fates_json)

__all__ = ["check_scene_files", "compile_scene", "check_against_model", "load_fates", "geoms_named", "start_touches",
           "unforced_still_moves", "body_radius"]

#: The MJCF elements whose attributes name files, and the <compiler> folder each resolves under.
_FILE_ATTRS = {"include": (("file",), None), "mesh": (("file",), "meshdir"), "skin": (("file",), "meshdir"),
               "hfield": (("file",), "texturedir"),
               "texture": (("file", "fileright", "fileleft", "fileup", "filedown", "filefront", "fileback"),
                           "texturedir"),
               "flexcomp": (("file",), "meshdir"), "model": (("file",), None)}

def _inside(path: Path, folder: Path) -> bool:
    try:
        return os.path.commonpath([os.path.realpath(path), os.path.realpath(folder)]) == os.path.realpath(folder)
    except ValueError:
        return False


def check_scene_files(scene: Path, *, source: str = "") -> list[Path]:
    """Refuse an MJCF whose ``<include>``, mesh, texture, hfield or skin files lie outside its folder.

    The XML is parsed (with each ``<include>`` in turn, to any depth); a file attribute is resolved
    as MuJoCo does, under ``<compiler meshdir|texturedir|assetdir>`` when set, relative to the
    scene's folder; links are followed before the check.

    Args:
        scene: the MJCF file.
        source: the fates file, for messages (defaults to the scene).

    Returns:
        the files the scene reads (the scene first), each checked.

    Raises:
        FatesError: a file outside the folder, a mesh over :data:`MAX_MESH_BYTES`, a missing file,
            XML that does not parse.
    """
    folder = scene.resolve().parent
    where = source or str(scene)
    seen: list[Path] = []
    dirs = {"meshdir": "", "texturedir": "", "assetdir": ""}

    def parse(path: Path, field: str) -> ET.Element:
        try:
            data = read_regular(path, max_bytes=MAX_SCENE_BYTES, what="MJCF file", allow_empty=False)
        except FileRefused as e:
            raise FatesError(where, field, str(e)) from None
        if b"<!ENTITY" in data or b"<!DOCTYPE" in data:
            raise FatesError(where, field, f"{path}: a DOCTYPE or ENTITY declaration is not read in a scene")
        try:
            return ET.fromstring(data)
        except ET.ParseError as e:
            raise FatesError(where, field, f"{path}: not XML ({e})") from None

    def walk(path: Path, field: str, depth: int) -> None:
        if depth > 16:
            raise FatesError(where, field, f"{path}: <include> nested deeper than 16")
        seen.append(path)
        root = parse(path, field)
        for c in root.iter("compiler"):
            for k in dirs:
                if c.get(k) is not None:
                    dirs[k] = c.get(k) or ""
        for el in root.iter():
            spec = _FILE_ATTRS.get(el.tag)
            if spec is None:
                continue
            attrs, dirkey = spec
            for a in attrs:
                name = el.get(a)
                if not name:
                    continue
                sub = dirs[dirkey] if dirkey and dirs[dirkey] else dirs["assetdir"] if dirkey else ""
                f = Path(name) if os.path.isabs(name) else folder / sub / name
                what = f"scene: <{el.tag} {a}=\"{name}\">"
                if not _inside(f, folder):
                    real = os.path.realpath(f)
                    via = f" (a link to {real})" if real != os.path.abspath(f) else ""
                    raise FatesError(where, what, f"{f}{via} is outside the scene's folder {folder}; a scene reads "
                                                  f"only files under its folder")
                if el.tag == "include":
                    walk(f, what, depth + 1)
                    continue
                try:
                    size = os.stat(f).st_size
                except OSError as e:
                    raise FatesError(where, what, f"{f}: {e.strerror or e}") from None
                if el.tag == "mesh" and size > MAX_MESH_BYTES:
                    raise FatesError(where, what, f"{f}: {size:,} bytes, larger than the {MAX_MESH_BYTES:,} bytes "
                                                  f"a scene's mesh may have")
                seen.append(f)

    walk(scene, "scene", 0)
    return seen


def compile_scene(fates: Fates) -> Any:
    """The compiled ``mujoco.MjModel`` of the fates' scene, its timestep set.

    Raises:
        FatesError: MuJoCo will not compile it (its message, with the line), or the scene's files
            are refused (:func:`check_scene_files`).
    """
    import mujoco

    check_scene_files(fates.scene, source=fates.source)
    try:
        model = mujoco.MjModel.from_xml_path(str(fates.scene))
    except ValueError as e:
        msg = "; ".join(line.strip() for line in str(e).splitlines() if line.strip())
        raise FatesError(fates.source, "scene", f"{fates.scene}: MuJoCo will not compile it: {msg}") from None
    if fates.timestep is not None:
        model.opt.timestep = fates.timestep
    return model


def body_radius(model: Any, body: int) -> float:
    """The radius (m) of the sphere about ``body``'s origin that holds its geoms (each geom's offset
    plus its ``geom_rbound``); 0 for a body with none."""
    gs = np.flatnonzero(model.geom_bodyid == body)
    return float(max((np.linalg.norm(model.geom_pos[g]) + model.geom_rbound[g] for g in gs), default=0.0))


def _collides(model: Any, g1: int, g2: int, pairs: set[tuple[int, int]], excluded: set[int]) -> bool:
    """Whether MuJoCo's collision filter lets geoms ``g1`` and ``g2`` touch at all (any pose): an explicit
    ``<pair>``, else contype/conaffinity, ``<exclude>``, both fixed to the world, one rigid body, a
    parent and its child (mj_collision's filters). ``pairs``: the model's ``<pair>`` geoms;
    ``excluded``: its ``exclude_signature`` (:func:`_can_touch` gives both)."""
    import mujoco

    if model.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_CONTACT:
        return False
    if (g1, g2) in pairs or (g2, g1) in pairs:
        return True
    if not (model.geom_contype[g1] & model.geom_conaffinity[g2] or model.geom_contype[g2] & model.geom_conaffinity[g1]):
        return False
    b1, b2 = int(model.geom_bodyid[g1]), int(model.geom_bodyid[g2])
    w1, w2 = int(model.body_weldid[b1]), int(model.body_weldid[b2])
    if w1 == w2:   # one rigid body, or both fixed to the world
        return False
    if (b1 << 16) + b2 in excluded or (b2 << 16) + b1 in excluded:
        return False
    if not model.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_FILTERPARENT and w1 and w2:
        if w1 == int(model.body_weldid[model.body_parentid[w2]]) or w2 == int(model.body_weldid[model.body_parentid[w1]]):
            return False
    return True


def _can_touch(model: Any, body: int, name: str) -> bool:
    """Whether some geom of ``body`` may ever touch the body (its own geoms) or geom named ``name``."""
    import mujoco

    others = geoms_named(model, name)
    mine = [g for g in range(model.ngeom) if int(model.geom_bodyid[g]) == body]
    pairs = set(zip(model.pair_geom1.tolist(), model.pair_geom2.tolist()))
    excluded = set(model.exclude_signature.tolist())
    return any(_collides(model, g1, g2, pairs, excluded) for g1 in mine for g2 in others)


def check_against_model(fates: Fates, model: Any) -> None:
    """Refuse names the model does not have, and a controlled body without a free joint.

    Raises:
        FatesError: a body, geom or key that is not in the model; a controlled body whose first
            joint is not free; a duration past :data:`MAX_STEPS` steps.
    """
    import mujoco

    src = _Src(fates.source)

    def body_id(name: str, field: str) -> int:
        i = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name)
        if i < 0:
            names = [model.body(k).name for k in range(model.nbody)]
            near = difflib.get_close_matches(name, names, n=1)
            raise src.fail(field, f"no body {name!r} in {fates.scene.name}" + (_other_kind(model, name) or (
                f" (did you mean {near[0]!r}?)" if near else "")))
        return i

    if fates.keyframe is not None and mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_KEY, fates.keyframe) < 0:
        keys = [model.key(k).name for k in range(model.nkey)]
        near = difflib.get_close_matches(fates.keyframe, keys, n=1)
        have = f" (did you mean {near[0]!r}?)" if near else (f" (its keys: {', '.join(keys)})" if any(keys) else
                                                             " (it has no named key)")
        raise src.fail("keyframe", f"no key {fates.keyframe!r} in {fates.scene.name}{have}")
    steps = int(round(fates.duration / model.opt.timestep))
    if steps > MAX_STEPS:
        raise src.fail("duration", f"{fates.duration:g} s at a {model.opt.timestep:g} s timestep is {steps:,} steps, "
                                   f"more than the {MAX_STEPS:,} a rollout may take")
    if steps < 1:
        raise src.fail("duration", f"{fates.duration:g} s is shorter than one timestep ({model.opt.timestep:g} s)")
    for c in fates.controls:
        b = body_id(c.body, f"controls.{c.body}")
        j = int(model.body_jntadr[b])
        if model.body_jntnum[b] < 1 or model.jnt_type[j] != mujoco.mjtJoint.mjJNT_FREE:
            raise src.fail(f"controls.{c.body}", f"body {c.body!r} has no free joint; only free bodies can be "
                                                 f"given velocities")
    start = _start_data(fates, model)
    mujoco.mj_kinematics(model, start)
    for fa in fates.fates:
        b = body_id(fa.body, f"fates.{fa.body}")
        if b == 0:
            raise src.fail(f"fates.{fa.body}", f"{fa.body!r} is MuJoCo's world body, which never moves: fates are "
                                               f"for the scene's bodies")
        if fa.still:   # a bystander that must also be somewhere else
            places = [(k, r) for k, r in ([("rest_in", fa.rest_in)] if fa.rest_in is not None else [])
                      + [("at", r) for _t, r in fa.at] + [("through", r) for r in fa.through]]
            for k, r in places:
                far = float(r.distance(np.asarray(start.xpos[b])[None])[0])
                if far > STILL_DISTANCE:
                    raise src.fail(f"fates.{fa.body}.{k}", f"its region is {far:.3g} m from where {fa.body!r} "
                                                           f"starts, and it is also still (never farther than "
                                                           f"{STILL_DISTANCE * 100:g} cm): no motion meets both")
        for key, names in (("hits", fa.hits), ("never_hits", fa.never_hits)):
            for n in names:
                g = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, n)
                nb = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, n)
                if nb < 0 and g < 0:
                    known = [model.body(k).name for k in range(model.nbody)] + [model.geom(k).name
                                                                               for k in range(model.ngeom)]
                    near = difflib.get_close_matches(n, [k for k in known if k], n=1)
                    raise src.fail(f"fates.{fa.body}.{key}", f"no body or geom {n!r} in {fates.scene.name}"
                                   + (_other_kind(model, n) or (f" (did you mean {near[0]!r}?)" if near else "")))
                if nb >= 0 and g >= 0 and int(model.geom_bodyid[g]) != nb:
                    raise src.fail(f"fates.{fa.body}.{key}", f"{n!r} names both a body and a geom (of "
                                   f"{model.body(int(model.geom_bodyid[g])).name!r}) in {fates.scene.name}: MuJoCo "
                                   f"keeps the two names apart, a fate can not tell which is meant; rename one")
                if n == fa.body or (g >= 0 and model.body(int(model.geom_bodyid[g])).name == fa.body):
                    raise src.fail(f"fates.{fa.body}.{key}", f"{n!r} is the body itself" if n == fa.body
                                   else f"{n!r} is a geom of {fa.body!r} itself: a body never touches its own geoms")
                if key == "hits" and not _can_touch(model, b, n):
                    why = (f"{n!r} has no geoms (a flex's vertex bodies have none)" if not geoms_named(model, n)
                           else f"{fa.body!r} has no geoms" if not geoms_named(model, fa.body)
                           else "MuJoCo collides no geom of one with one of the other (contype/conaffinity, "
                                "<exclude>, contacts disabled, both fixed to the world, one rigid body, or a "
                                "parent and its child)")
                    raise src.fail(f"fates.{fa.body}.{key}", f"{fa.body!r} can never touch {n!r} in "
                                   f"{fates.scene.name}: {why}")
        never = set().union(*(geoms_named(model, n) for n in fa.never_hits))
        for n in fa.hits:   # "hits b" with every geom of b in never_hits (by the geom's own name): a tester's
            if geoms_named(model, n) <= never:
                raise src.fail(f"fates.{fa.body}.never_hits", f"every geom of {n!r}, which it hits, is in never_hits: "
                                                              f"no motion can both touch it and not")


def _other_kind(model: Any, name: str) -> str:
    """What else ``name`` names in the model, for a refusal: `` ('x' is a site of body 'b': ...)``, the
    same for a flex, or ``""``."""
    import mujoco

    i = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, name)
    if i >= 0:
        return (f" ({name!r} is a site of body {model.body(int(model.site_bodyid[i])).name!r}: fates name bodies "
                f"and geoms)")
    if model.nflex and mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_FLEX, name) >= 0:
        return f" ({name!r} is a flex: fates name bodies and geoms, and nbst does not read a flex's contacts)"
    return ""


def geoms_named(model: Any, name: str) -> set[int]:
    """The geoms a ``hits`` name stands for: a body's own geoms, or the geom of that name."""
    import mujoco

    nb = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name)
    if nb >= 0:
        return {g for g in range(model.ngeom) if int(model.geom_bodyid[g]) == nb}
    return {mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, name)}


def _start_data(fates: Fates, model: Any) -> Any:
    """A fresh ``mujoco.MjData`` at the start the fates name: the model's pose, or its keyframe's."""
    import mujoco

    d = mujoco.MjData(model)
    if fates.keyframe is not None:
        mujoco.mj_resetDataKeyframe(model, d, mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_KEY, fates.keyframe))
    return d


def start_touches(fates: Fates, model: Any) -> list[tuple[str, str, str]]:
    """The touches already there at the start (the model's or key's pose, before any control): each
    ``(body, "hits" | "never_hits", name)`` whose body and name are in contact (distance <= 0, as the
    rollout counts a touch). A ``never_hits`` among them can not be met by any velocity; a ``hits``
    one is met at 0 s. Compute only (``nbst scene check`` prints them)."""
    import mujoco

    d = _start_data(fates, model)
    mujoco.mj_forward(model, d)
    pairs = set()
    for c in d.contact[:d.ncon]:
        if c.dist <= 0:
            pairs.add((int(c.geom1), int(c.geom2)))
            pairs.add((int(c.geom2), int(c.geom1)))
    out = []
    for fa in fates.fates:
        b = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, fa.body)
        for key, names in (("hits", fa.hits), ("never_hits", fa.never_hits)):
            for n in names:
                nb = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, n)
                if any(int(model.geom_bodyid[g1]) == b and (int(model.geom_bodyid[g2]) == nb if nb >= 0 else
                                                            model.geom(g2).name == n) for g1, g2 in pairs):
                    out.append((fa.body, key, n))
    return out


def idle_fates(fates: Fates, model: Any) -> list[tuple[str, str]]:
    """Fates met or meaningless before any motion (``nbst scene check`` notes them): ``(body, why)``
    for a ``through`` whose first region holds the body's origin at the start (the model's or key's
    pose; passed at 0 s), a ``never_hits`` name it can never touch (always met), and an ``up`` on a body whose every geom is a sphere (no face marks which
    way is up). Compute only."""
    import mujoco

    d = _start_data(fates, model)
    mujoco.mj_kinematics(model, d)
    out = []
    for fa in fates.fates:
        b = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, fa.body)
        if fa.through and float(fa.through[0].distance(np.asarray(d.xpos[b])[None])[0]) <= 0.0:
            out.append((fa.body, "its origin starts inside through's first region, so it is passed at 0 s "
                                 "(the model's pose, before any control)"))
        for n in fa.never_hits:
            if not _can_touch(model, b, n):
                out.append((fa.body, f"never_hits {n!r}, which it can never touch (no geom of one collides with one "
                                     f"of the other in MuJoCo's filters): that fate is always met"))
        mine = geoms_named(model, fa.body)
        if fa.up is not None and mine and all(int(model.geom_type[g]) == mujoco.mjtGeom.mjGEOM_SPHERE for g in mine):
            out.append((fa.body, "asks up of a body whose every geom is a sphere: no face shows which way is up "
                                 "(only its frame's turn does)"))
    return out


def unforced_still_moves(fates: Fates, model: Any) -> list[tuple[str, float]]:
    """The ``still`` bodies that move by themselves: the scene as written (the model's or key's state,
    no control applied) stepped for the fates' duration, each ``(body, farthest)`` whose origin went
    farther than :data:`~nbst.scene.fates.STILL_DISTANCE` from its start (a body placed in the air,
    a ball in a wind, a pendulum let go). Such a ``still`` is met only if some control holds the body
    in place. Compute only (``nbst scene check`` prints them)."""
    import mujoco
    import numpy as np

    from nbst.scene.fates import STILL_DISTANCE

    ids = {f.body: mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, f.body) for f in fates.fates if f.still}
    if not ids:
        return []
    d = _start_data(fates, model)
    mujoco.mj_kinematics(model, d)
    b = list(ids.values())
    start, far = d.xpos[b].copy(), np.zeros(len(b))
    for _ in range(int(round(fates.duration / model.opt.timestep))):
        mujoco.mj_step(model, d)
        far = np.maximum(far, np.linalg.norm(d.xpos[b] - start, axis=1))
    return [(name, float(x)) for name, x in zip(ids, far) if x > STILL_DISTANCE]


def load_fates(path: str | os.PathLike, *, scene: str | os.PathLike | None = None) -> tuple[Fates, Any]:
    """Read and check a fates file and compile its scene.

    Args:
        path: the fates JSON file, or the name of a built-in example (``nbst scene examples``).
        scene: an MJCF path that overrides the file's ``"scene"``.

    Returns:
        ``(fates, model)``: the checked :class:`Fates` and the compiled ``mujoco.MjModel``.

    Raises:
        FatesError: anything refused (module docstring); one line naming the file and the field.
    """
    from nbst.scene.builtin import example_names, example_path

    try:  # a file that cannot be read (missing, empty, a folder, a FIFO) is the fates' refusal too
        p = Path(path)
        if not p.exists() and (ex := example_path(str(path))) is not None:
            p = ex
        elif not p.exists() and not p.is_symlink():  # a misspelt built-in is told its name
            near = difflib.get_close_matches(str(path), example_names(), n=1)
            if near:
                raise FileRefused(path, f"no such file, nor a built-in example by that name (did you mean {near[0]!r}?)")
        doc = read_fates_json(p)
        fates = parse_fates(doc, str(path), folder=p.resolve().parent, scene=scene)
        model = compile_scene(fates)
    except FileRefused as e:
        raise FatesError(e.path, "", e.reason) from None
    check_against_model(fates, model)
    return fates, model
