"""A scene solution replayed for its pictures: every geom's pose at each frame's time, the
model's cameras, and the fated bodies' first touches (the impacts drawn).

:func:`record` rolls the solution's initial state (``qpos0``, ``qvel0``, from the model's key when
the fates name one) out with the plain ``mj_step`` loop of docs/scene.md (``nbst.scene.rollout
.replay``'s), reading between the steps and changing nothing: so it ends in the solution's final
state bit for bit (:attr:`SceneMotion.same` says whether it did). A frame at time t shows the state
after round(t / h) steps. A first touch is what the rollout's contact record counts (a contact of
distance <= 0 between a fated body's geom and another body, or a named geom of the world), at
the state its step started from; its point is MuJoCo's contact position; the other goes by the
name the body's ``hits`` or ``never_hits`` gives it (a geom's own name there), else its body's.

Compute only (MuJoCo, numpy).
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any

import numpy as np

from nbst.scene.fates import Fates
from nbst.scene.judge import Judgement
from nbst.scene.scenefile import geoms_named, load_fates
from nbst.scene.solution import _floats, read_solution, replay_solution

__all__ = ["Touch", "SceneMotion", "record", "load_solution_scene"]


@dataclass(frozen=True)
class Touch:
    """A fated body's first touch of another: when (s), where (world, m), who."""

    t: float
    pos: tuple[float, float, float]
    body: str
    other: str


@dataclass(frozen=True)
class SceneMotion:
    """The recorded frames of a solution (F frames, G geoms, B bodies, C cameras).

    Args:
        times: (F,) each frame's time (s).
        geom_xpos: (F, G, 3) geom positions; geom_xmat: (F, G, 3, 3) geom orientations.
        body_xpos: (F, B, 3) body origins; body_xmat: (F, B, 3, 3) body orientations.
        cam_xpos: (F, C, 3) camera positions; cam_xmat: (F, C, 3, 3) camera frames.
        touches: the first touches, in time order.
        duration: the motion's seconds (nstep x h).
        same: the loop ended in the solution's final state bit for bit.
        judgement: the fates judged on the replay (``nbst.scene.solution.replay_solution``'s).
        tendon_segs: (F, S, 2, 3) the spatial tendons' segments between wrap points (NaN: none in
            that slot at that frame), or None without a spatial tendon of width > 0.
        tendon_slots: (tendon index, width) of each of the S slots.
    """

    times: np.ndarray
    geom_xpos: np.ndarray
    geom_xmat: np.ndarray
    body_xpos: np.ndarray
    body_xmat: np.ndarray
    cam_xpos: np.ndarray
    cam_xmat: np.ndarray
    touches: tuple[Touch, ...]
    duration: float
    same: bool
    judgement: Judgement
    tendon_segs: np.ndarray | None = None
    tendon_slots: tuple[tuple[int, float], ...] = ()

    def index(self, t: float) -> int:
        """The frame nearest time ``t``."""
        return int(np.argmin(np.abs(self.times - float(t))))


def load_solution_scene(path: str | os.PathLike) -> tuple[dict, Fates, Any]:
    """(the solution's JSON, its checked fates, the compiled model at the solution's timestep).

    Raises:
        SceneSolutionError: the solution file is refused.
        FatesError: its fates file or scene is refused.
    """
    doc = read_solution(path)
    fates, model = load_fates(doc.get("fates_file") or doc["fates"], scene=doc["scene"])
    model.opt.timestep = float(doc["timestep"])
    return doc, fates, model


def record(path: str | os.PathLike, times: np.ndarray) -> tuple[SceneMotion, Fates, Any]:
    """Replay the solution file ``path`` and record its frames at ``times`` (s; clipped to the motion).

    Args:
        path: the scene solution file.
        times: (F,) the frames' times, e.g. ``nbst.render.core.times.frame_times(duration, fps)``.

    Returns:
        (the :class:`SceneMotion`, the fates, the ``mujoco.MjModel``).

    Raises:
        SceneSolutionError: the file is refused, or its state does not fit the model.
        FatesError: its fates file or scene is refused.
    """
    import mujoco

    from nbst.scene.rollout import quiet_mujoco_warnings

    doc, fates, m = load_solution_scene(path)
    nq, nv = int(m.nq), int(m.nv)
    q0, v0 = _floats(doc, "qpos0", nq, str(path)), _floats(doc, "qvel0", nv, str(path))
    qf, vf = _floats(doc, "final.qpos", nq, str(path)), _floats(doc, "final.qvel", nv, str(path))
    nstep = int(doc["nstep"])
    h = float(m.opt.timestep)
    times = np.asarray(times, float)
    steps = np.clip(np.round(times / h).astype(np.int64), 0, nstep)
    F, G, B, C = len(times), int(m.ngeom), int(m.nbody), int(m.ncam)
    gx, gm = np.empty((F, G, 3)), np.empty((F, G, 3, 3))
    bx, bm = np.empty((F, B, 3)), np.empty((F, B, 3, 3))
    cx, cm = np.empty((F, C, 3)), np.empty((F, C, 3, 3))
    key = -1 if fates.keyframe is None else int(mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_KEY, fates.keyframe))
    d, s = mujoco.MjData(m), mujoco.MjData(m)
    if key >= 0:
        mujoco.mj_resetDataKeyframe(m, d, key)
    d.qpos[:] = q0
    d.qvel[:] = v0
    s.mocap_pos[:], s.mocap_quat[:] = d.mocap_pos, d.mocap_quat  # drawn where the key holds them
    # the fated bodies' geoms, and the name each other geom goes by (its body's; a world geom's own),
    # or, to a fated body, the name its hits or never_hits gives it (a body's, else a geom's: "tg")
    fated = {int(mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, f.body)): f.body for f in fates.fates}
    owner = [fated.get(int(m.geom_bodyid[g])) for g in range(G)]
    names = [m.body(int(m.geom_bodyid[g])).name if m.geom_bodyid[g] != 0 or not m.geom(g).name else m.geom(g).name
             for g in range(G)]
    called: dict[tuple[str, int], str] = {}
    for f in fates.fates:
        for n in (*f.hits, *f.never_hits):
            for g in geoms_named(m, n):
                called[(f.body, int(g))] = n
    seen: set[tuple[str, str]] = set()
    touches: list[Touch] = []
    # the spatial tendons MuJoCo's viewer draws: each has up to 2 wrap points per wrap object
    spatial = [i for i in range(int(m.ntendon)) if float(m.tendon_width[i]) > 0
               and any(int(m.wrap_type[j]) != mujoco.mjtWrap.mjWRAP_JOINT
                       for j in range(int(m.tendon_adr[i]), int(m.tendon_adr[i]) + int(m.tendon_num[i])))]
    slots = tuple((i, float(m.tendon_width[i])) for i in spatial for _ in range(2 * int(m.tendon_num[i])))
    tseg = np.full((F, len(slots), 2, 3), np.nan) if slots else None

    def grab(k: int) -> None:
        rows = np.flatnonzero(steps == k)
        if not len(rows):
            return
        s.qpos[:] = d.qpos
        mujoco.mj_kinematics(m, s)
        mujoco.mj_comPos(m, s)
        mujoco.mj_camlight(m, s)
        gx[rows], gm[rows] = s.geom_xpos, s.geom_xmat.reshape(G, 3, 3)
        bx[rows], bm[rows] = s.xpos, s.xmat.reshape(B, 3, 3)
        cx[rows], cm[rows] = s.cam_xpos, s.cam_xmat.reshape(C, 3, 3)
        if tseg is not None:
            mujoco.mj_tendon(m, s)
            obj, xp = np.asarray(s.wrap_obj).ravel(), np.asarray(s.wrap_xpos).reshape(-1, 3)   # the points in order
            at = 0
            for i in spatial:
                a, n = int(s.ten_wrapadr[i]), int(s.ten_wrapnum[i])
                for j in range(a, a + n - 1):   # as mjv_updateScene: no segment across a pulley (-2)
                    if obj[j] != -2 and obj[j + 1] != -2 and at + j - a < len(slots):
                        tseg[rows, at + j - a] = xp[j], xp[j + 1]
                at += 2 * int(m.tendon_num[i])

    with quiet_mujoco_warnings():
        grab(0)
        for k in range(nstep):
            mujoco.mj_step(m, d)
            for c in range(int(d.ncon)):
                con = d.contact[c]
                if con.dist > 0:
                    continue
                for a, b in ((int(con.geom[0]), int(con.geom[1])), (int(con.geom[1]), int(con.geom[0]))):
                    who = owner[a]
                    other = called.get((who, b), names[b]) if who is not None else ""
                    if who is not None and names[b] != who and (who, other) not in seen:
                        seen.add((who, other))
                        touches.append(Touch(k * h, tuple(float(p) for p in con.pos), who, other))  # type: ignore[arg-type]
            grab(k + 1)
    same = d.qpos.tobytes() == qf.tobytes() and d.qvel.tobytes() == vf.tobytes()
    judged = replay_solution(path).judgement
    return (SceneMotion(times=times, geom_xpos=gx, geom_xmat=gm, body_xpos=bx, body_xmat=bm, cam_xpos=cx,
                        cam_xmat=cm, touches=tuple(touches), duration=nstep * h, same=same, judgement=judged,
                        tendon_segs=tseg, tendon_slots=slots),
            fates, m)
