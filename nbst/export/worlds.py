"""Every world's file replayed to body poses, for :mod:`nbst.export.gltf`.

One function per kind of file, each replaying it with its own room's replay (no physics here):

* a 2D solution (``nbst solve``): the exact simulator (:func:`nbst.sim.simulate`, as ``nbst
  render`` draws it); each disk a puck (a cylinder of its radius, :data:`PUCK_HEIGHT_FRAC` of it
  tall, amber cueable, blue noncueable; the 3D view's shape, :func:`nbst.render.core.camera.mesh_arrays`)
  sliding on the box's floor (a quad at z = 0; z up, the box's units);
* a 5 m bowling throw (``nbst bowl solve``): :func:`nbst.render.bowling.deck.record`;
* a foul-line bowling throw (``nbst bowl throw``/``replay``): :func:`nbst.render.bowling.throw.record_throw`,
  the frame as ``nbst bowl replay`` runs it (the ball's rotation is relative to its release, as in
  the video, and the ball wears the video's texture: :func:`uv_sphere`);
* a crash file (``nbst crash solve``): :func:`nbst.render.crash.motion.record`;
* a scene solution (``nbst scene solve``): the plain ``mj_step`` loop of docs/scene.md from the
  file's initial state (the same loop as :func:`nbst.scene.rollout.replay`, its states kept).

The pins and a crash's vehicles are written as their videos draw them (the pins' neck stripes, the
tyres' spokes; per-corner colours), so that a spin shows in a viewer as it does in the video.

MuJoCo worlds keep the recorded states nearest each keyframe (exact replayed states at their own
times; :func:`nbst.export.mjbodies.sampled_steps`); the 2D world is exact at every keyframe.
:func:`file_motion` sniffs the kind (:func:`file_kind`) and dispatches.
"""
from __future__ import annotations

import os
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from nbst import palette
from nbst.domain import plain
from nbst.errors import InputError
from nbst.export.gltf import Body, BodyMotion, Solid
from nbst.files import sniff_kind
from nbst.render.core.camera import mesh_arrays

__all__ = ["BALL_RINGS", "BALL_SECTORS", "DEFAULT_FPS", "FPS_MAX", "PUCK_HEIGHT_FRAC", "FLOOR_RGBA", "KINDS", "NOT_MOTIONS", "file_kind", "disks_motion",
           "deck_motion", "lane_motion", "crash_motion", "scene_motion", "file_motion", "uv_sphere"]

#: Keyframes per second unless asked otherwise, and the most accepted.
DEFAULT_FPS = 60.0
FPS_MAX = 1000.0
#: A 2D disk's puck height as a fraction of its radius (the 3D view's).
PUCK_HEIGHT_FRAC = 0.6
#: The 2D box's floor.
FLOOR_RGBA = (0.16, 0.17, 0.20, 1.0)
#: The files :func:`file_kind` knows, by the kind string each writes in its first lines.
KINDS = (("scene", "nbst-scene-solution"), ("crash", "nbst-crash"), ("deck", "nbst-bowling-shot"),
         ("lane", "nbst-bowling-throw"))
#: Files of nbst's that hold no motion yet, and what to do instead (refused in one line).
NOT_MOTIONS = {"nbst-crash-script": "a crash script: solve it first (`nbst crash solve`) and export the crash file",
               "nbst-fates": "a fates file: solve it first (`nbst scene solve`) and export the solution",
               "nbst-bowling-atlas": "an atlas of 5 m throws: export one throw file",
               "nbst-bowling-throw-atlas": "an atlas of foul-line throws: export one throw file",
               # `bowl throw -o` writes the ball's phases (no "format": its first key is "oil")
               "board_at_foul_line": "the ball's phases from `nbst bowl throw -o`, no motion: throw it into the "
                                     "pins with `nbst bowl frame ... -o THROW.json` (the same flags) and export that"}
_SNIFF_BYTES = 4096


def file_kind(path: str | os.PathLike) -> str:
    """What ``path`` holds, by the kind string in its first bytes: "scene", "crash", "deck" (a 5 m throw),
    "lane" (a foul-line throw), else "disks" (a 2D solution; its loader checks it).

    Args:
        path: the file.

    Returns:
        the kind's name.

    Raises:
        InputError: a file of nbst's that holds no motion (:data:`NOT_MOTIONS`).
    """
    kinds = KINDS + tuple((k, k) for k in NOT_MOTIONS)
    kind = sniff_kind(path, kinds, max_bytes=_SNIFF_BYTES) or "disks"
    if kind in NOT_MOTIONS:
        raise InputError(f"{path}: format: {NOT_MOTIONS[kind]}")
    return kind


def _check_fps(fps: float) -> float:
    if not (isinstance(fps, (int, float)) and 0 < fps <= FPS_MAX):
        raise InputError(f"fps: {fps!r}: must be in (0, {FPS_MAX:g}]")
    return float(fps)


def disks_motion(path: str | os.PathLike, *, problem: str | Path | None = None,
                 fps: float = DEFAULT_FPS) -> BodyMotion:
    """A 2D solution's disks as pucks on the floor of the box, exact at every keyframe.

    Args:
        path: the solution file (``nbst solve -o``).
        problem: the problem (built-in name or file); default the one the solution names.
        fps: keyframes per second (the last keyframe at t_final).

    Returns:
        the floor (static) and one body per disk.

    Raises:
        InputError: the solution or problem refused (one line naming the file and field).
    """
    import trimesh

    from nbst.problem import ProblemError, load_problem, read_json
    from nbst.sim import simulate
    from nbst.solution import load_solution, named_problem

    fps = _check_fps(fps)
    if problem is None:
        problem = named_problem(path)
        if problem is None:
            read_json(Path(path))  # a file that cannot be read is refused as itself
            raise ProblemError(str(path), "problem", "names no problem; give the problem (a built-in name or file)")
        try:
            prob = load_problem(problem)
        except InputError as e:  # the name the solution gives: say whose, and what to do
            raise ProblemError(str(path), "problem", f"names {problem!r}, which nbst cannot load ({plain(e)}); give "
                                                     f"it with --problem FILE") from None
    else:
        prob = load_problem(problem)
    sol = load_solution(Path(path), prob)
    tr = simulate(prob, sol.velocities)
    if tr.truncated:
        raise ProblemError(str(path), "velocities", f"the motion stops at t = {tr.end_time:.6g} s, before t_final = "
                                                    f"{prob.t_final:g} s; nbst cannot simulate it to the end")
    times = np.arange(0.0, prob.t_final, 1.0 / fps)
    times = np.append(times[times < prob.t_final * (1 - 1e-9)], prob.t_final)
    xy = np.asarray(tr.at(times), float)
    w, h = prob.box
    corners = np.array([[0, 0, 0], [w, 0, 0], [w, h, 0], [0, 0, 0], [w, h, 0], [0, h, 0]], float)
    floor = np.concatenate([corners, np.tile([0.0, 0.0, 1.0], (6, 1))], axis=1)
    bodies = [Body(name="box", solids=[Solid(rows=floor, rgba=FLOOR_RGBA)], moves=False)]
    half = np.asarray(prob.radius, float) * PUCK_HEIGHT_FRAC / 2
    for i in range(prob.n):
        rgb = palette.CUEABLE if prob.cueable[i] else palette.NONCUEABLE
        puck = mesh_arrays(trimesh.creation.cylinder(radius=float(prob.radius[i]), height=2 * float(half[i]),
                                                     sections=48))
        bodies.append(Body(name=f"disk{i}", solids=[Solid(rows=puck, rgba=(*rgb, 1.0))]))
    n = len(times)
    pos = np.zeros((n, prob.n + 1, 3))
    pos[:, 1:, :2] = xy
    pos[:, 1:, 2] = half
    quat = np.zeros((n, prob.n + 1, 4))
    quat[..., 0] = 1.0
    return BodyMotion(bodies=bodies, times=times, pos=pos, quat=quat)


def _free_qpos(model: Any, ball: np.ndarray, pins: np.ndarray, pin_adr: np.ndarray) -> np.ndarray:
    """Full qpos rows from a bowling motion's ball (S, 7) and pins (S, 10, 7) poses (every joint of the
    bowling scenes is the ball's or a pin's free joint)."""
    ba = int(model.joint("ball_free").qposadr[0])
    q = np.tile(np.asarray(model.qpos0, float), (len(ball), 1))
    q[:, ba:ba + 7] = ball
    for j, a in enumerate(pin_adr):
        q[:, int(a):int(a) + 7] = pins[:, j]
    return q


def _skinned(motion: BodyMotion, skins: dict[int, list[Solid]]) -> BodyMotion:
    """``motion`` with the solids of the bodies in ``skins`` (body index -> solids) replaced: what a
    world's video draws for them (a pin's neck stripes, a tyre's spokes) instead of their plain geoms."""
    bodies = [replace(b, solids=skins[k]) if k in skins else b for k, b in enumerate(motion.bodies)]
    return replace(motion, bodies=bodies)


def _pin_skins(model: Any) -> dict[int, list[Solid]]:
    """Each pin body's solid as the bowling videos draw it: white maple with the red neck stripes."""
    from nbst.render.bowling.deck import pin_solid

    solid = Solid.coloured(pin_solid(model))
    return {int(model.body(f"pin{n}").id): [solid] for n in range(1, 11)}


def deck_motion(path: str | os.PathLike, *, fps: float = DEFAULT_FPS) -> BodyMotion:
    """A 5 m bowling throw file replayed (``nbst render``'s recording): the lane, the ball and the pins.

    Args:
        path: the throw file (``nbst bowl solve``).
        fps: keyframes per second.

    Returns:
        every body of the throw's scene.

    Raises:
        ThrowFileError: the file refused, or MuJoCo warned in the replay.
    """
    from nbst.errors import MujocoError
    from nbst.export.mjbodies import qpos_motion
    from nbst.models.bowling import pinfall
    from nbst.models.bowling.deck import throwfile
    from nbst.render.bowling.deck import record

    fps = _check_fps(fps)
    throw, model, _ = throwfile.load_with_scene(path)
    try:
        m = record(throw, model)
    except MujocoError as e:
        raise throwfile.ThrowFileError(f"{path}: qpos0/qvel0: {e}") from None
    q = _free_qpos(model, m.ball, m.pins, pinfall.pin_addresses(model))
    return _skinned(qpos_motion(model, q, m.times, fps), _pin_skins(model))


#: The textured ball's sphere: rings from pole to pole and sectors round the axis (a texel of the
#: video's 1024 x 512 texture is 0.35 deg; a sector 2.8 deg, a 1 in finger hole is 13 deg across).
BALL_RINGS, BALL_SECTORS = 64, 128


def uv_sphere(radius: float, rings: int = BALL_RINGS, sectors: int = BALL_SECTORS) -> tuple[np.ndarray, np.ndarray]:
    """A sphere about the origin whose texture coordinates are the video's equirectangular mapping
    (``nbst.render.bowling.throw.ball_texture``): u = azimuth / 2 pi + 1/2, v = polar angle / pi, v = 0
    at +z. The seam's corners are doubled (u = 0 and u = 1), so no triangle wraps round.

    Returns:
        rows (V, 6) position and unit normal, and uv (V, 2), three corners a triangle, wound
        counter-clockwise seen from outside.
    """
    th = np.linspace(0.0, np.pi, rings + 1)
    ph = np.linspace(-np.pi, np.pi, sectors + 1)
    T, P = np.meshgrid(th, ph, indexing="ij")
    n = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], -1)
    uv = np.stack([P / (2 * np.pi) + 0.5, T / np.pi], -1)
    i, j = (k.ravel() for k in np.meshgrid(np.arange(rings), np.arange(sectors), indexing="ij"))
    # each quad's two triangles (a b c) and (a c d), a = (i, j), b = (i+1, j), c = (i+1, j+1), d = (i, j+1);
    # at a pole one of them has two corners on the pole: left out
    I = np.concatenate([np.stack([i, i + 1, i + 1], 1)[i != rings - 1], np.stack([i, i + 1, i], 1)[i != 0]])
    J = np.concatenate([np.stack([j, j, j + 1], 1)[i != rings - 1], np.stack([j, j + 1, j + 1], 1)[i != 0]])
    corner = np.stack([I.ravel(), J.ravel()], 1)
    nrm = n[corner[:, 0], corner[:, 1]]
    return np.concatenate([radius * nrm, nrm], axis=1), uv[corner[:, 0], corner[:, 1]]


def _ball_skin(model: Any, throw: Any) -> dict[int, list[Solid]]:
    """The foul-line ball as its video draws it: its texture (grip holes, pin dot, track) on a sphere."""
    from nbst.render.bowling.throw import ball_texture

    g = model.geom("ball").id
    rows, uv = uv_sphere(float(model.geom_size[g][0]))
    rows[:, :3] += np.asarray(model.geom_pos[g], float)
    return {int(model.geom_bodyid[g]): [Solid(rows, (1.0, 1.0, 1.0, 1.0), uv=uv, texture=ball_texture(throw))]}


def lane_motion(path: str | os.PathLike, *, fps: float = DEFAULT_FPS) -> BodyMotion:
    """A foul-line bowling throw file replayed as ``nbst bowl replay`` records it: the lane, ball and pins.

    Args:
        path: the throw file.
        fps: keyframes per second.

    Returns:
        every body of the frame's model.

    Raises:
        ThrowFileError: the file refused (or thrown on another scene); LaneError, FrameError,
            MujocoError: the replay refused.
    """
    from nbst.export.mjbodies import qpos_motion
    from nbst.models.bowling import lane, pinfall
    from nbst.models.bowling.lane import frame, throwfile
    from nbst.render.bowling.throw import record_throw

    fps = _check_fps(fps)
    d = throwfile.load(path)
    throwfile.replayable(d, path)
    ball, step = lane.Ball(**d["ball"]), float(d["outcome"]["timestep"])
    model = frame.frame_model(ball, timestep=step)
    th = record_throw(lane.Delivery(**d["delivery"]), throwfile.oil_of(d), ball,  # type: ignore[arg-type]
                      standing=d["standing"], timestep=step, model=model)
    m = th.motion
    q = _free_qpos(model, m.ball, m.pins, pinfall.pin_addresses(model))
    return _skinned(qpos_motion(model, q, m.times, fps), {**_pin_skins(model), **_ball_skin(model, th)})


def _vehicle_skins(model: Any, qpos0: np.ndarray, n: int) -> dict[int, list[Solid]]:
    """Each vehicle body's solids as the crash video draws them (``nbst.render.crash.scene.geom_solid``:
    the lower body with its wheel arches, the glazed cabin and its windscreen strip, tyres with two
    light spokes a face, the crush slabs), in the body's frame; a geom the video does not draw (a
    hub) is left out."""
    import mujoco

    from nbst.render.core import geoms as cg
    from nbst.render.crash import scene as cs

    data = mujoco.MjData(model)
    data.qpos[:] = qpos0   # the start: the arches sit over the wheels there, as in the video
    mujoco.mj_kinematics(model, data)
    out: dict[int, list[Solid]] = {}
    for i in range(n):
        for g in cs.vehicle_geoms(model, i):
            rows = cs.geom_solid(model, g, cs.vehicle_arches(model, data, i, g))
            if rows is not None:
                rows = cg.posed(np.asarray(rows, float), cg.quat_mat(model.geom_quat[g]), model.geom_pos[g])
                out.setdefault(int(model.geom_bodyid[g]), []).append(Solid.coloured(rows, float(model.geom_rgba[g][3])))
    return out


def crash_motion(path: str | os.PathLike, *, fps: float = DEFAULT_FPS) -> BodyMotion:
    """A crash file replayed (``nbst render``'s recording): the road and every vehicle's bodies.

    Args:
        path: the crash file (``nbst crash solve``).
        fps: keyframes per second.

    Returns:
        every body of the crash's model.

    Raises:
        CrashFileError: the file refused.
    """
    from nbst.export.mjbodies import qpos_motion
    from nbst.render.crash.video import load

    fps = _check_fps(fps)
    d, _, model, m = load(path)
    motion = _skinned(qpos_motion(model, m.qpos, m.times, fps), _vehicle_skins(model, m.qpos[0], len(d["vehicles"])))
    # the vehicles' bodies by the names the crash file, its replay and its video give them (A, A_wheel_fl)
    own = [(str(v["body"]), str(v["name"])) for v in d["vehicles"]]
    renamed = [next((name + b.name[len(body):] for body, name in own
                     if b.name == body or b.name.startswith(body + "_")), b.name) for b in motion.bodies]
    if len(set(renamed)) < len(renamed):  # a static body already called so: the model's names kept
        return motion
    return replace(motion, bodies=[replace(b, name=n) for b, n in zip(motion.bodies, renamed)])


def scene_motion(path: str | os.PathLike, *, fps: float = DEFAULT_FPS) -> BodyMotion:
    """A scene solution replayed with the plain ``mj_step`` loop of docs/scene.md: every body of the scene.

    Args:
        path: the scene solution (``nbst scene solve``).
        fps: keyframes per second.

    Returns:
        every body of the user's scene.

    Raises:
        SceneSolutionError: the file refused or its state does not fit the model; FatesError: its
            fates file or scene refused.
    """
    import mujoco

    from nbst.export.mjbodies import qpos_motion
    from nbst.scene.rollout import quiet_mujoco_warnings
    from nbst.scene.scenefile import load_fates
    from nbst.scene.solution import SceneSolutionError, read_solution

    fps = _check_fps(fps)
    doc = read_solution(path)
    fates, model = load_fates(doc.get("fates_file") or doc["fates"], scene=doc["scene"])
    model.opt.timestep = float(doc["timestep"])
    q0, v0 = np.asarray(doc["qpos0"], float), np.asarray(doc["qvel0"], float)
    if q0.shape != (model.nq,) or v0.shape != (model.nv,):
        raise SceneSolutionError(f"{path}: qpos0/qvel0: {q0.size} and {v0.size} values; the scene has {model.nq} "
                                 f"and {model.nv}")
    n = int(doc["nstep"])
    d = mujoco.MjData(model)
    if fates.keyframe is not None:   # as the search and nbst.scene.rollout.replay start
        mujoco.mj_resetDataKeyframe(model, d, int(mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_KEY, fates.keyframe)))
    d.qpos[:], d.qvel[:] = q0, v0
    q = np.empty((n + 1, model.nq))
    q[0] = d.qpos
    with quiet_mujoco_warnings():
        for k in range(n):
            mujoco.mj_step(model, d)
            q[k + 1] = d.qpos
    # a mocap body stays where the key put it (its mpos/mquat), as in the replay
    return qpos_motion(model, q, np.arange(n + 1) * float(model.opt.timestep), fps,
                       mocap=(d.mocap_pos.copy(), d.mocap_quat.copy()))


def file_motion(path: str | os.PathLike, *, problem: str | Path | None = None,
                fps: float = DEFAULT_FPS) -> tuple[str, BodyMotion]:
    """Any world's file replayed to body poses (:func:`file_kind` picks the world).

    Args:
        path: a 2D solution, a 5 m or foul-line bowling throw, a crash file or a scene solution.
        problem: a 2D solution's problem (default the one it names); refused for the other kinds.
        fps: keyframes per second.

    Returns:
        ``(kind, motion)``.

    Raises:
        InputError: the file or a field refused (one line naming the file and field); the
            replay's own errors (MujocoError and the rooms' InputErrors).
    """
    kind = file_kind(path)
    if problem is not None and kind != "disks":
        raise InputError(f"{path}: problem: only a 2D solution takes a problem; this is a {kind} file")
    if kind == "disks":
        return kind, disks_motion(path, problem=problem, fps=fps)
    run = {"scene": scene_motion, "crash": crash_motion, "deck": deck_motion, "lane": lane_motion}[kind]
    return kind, run(path, fps=fps)


