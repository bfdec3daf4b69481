"""From a controls vector to an initial state, and the rollout that records what the judge needs.

**Controls -> state** (:meth:`SceneSim.initial_state`): the model is reset (to its keyframe when
the fates name one), then for each controlled body, whose first joint is free (qpos: position,
quaternion w x y z; qvel: linear velocity in the world frame, angular velocity in the BODY frame):

* ``pos``: the offsets are added to the joint's position;
* ``linvel``: the world-frame velocity goes to qvel[0:3] of the joint as it is;
* ``angvel``: the world-frame angular velocity w is turned into the body frame, R(q)^T w, for
  qvel[3:6] (tests/test_scene_rollout.py checks the physical fact: a free ball with no gravity
  spins about the commanded world axis at the commanded rate).

Anything not in the controls starts as in the model (or the keyframe).

**The rollout** (:meth:`SceneSim.rollout`) runs on ``mujoco.rollout`` (C, the GIL released:
the threads of :meth:`SceneSim.run` run side by side). What the judge needs between the steps is
recorded by sensors added to a copy of the scene (``mujoco.MjSpec``: the scene's file compiled
again, the model's ``opt`` copied over) and written by the rollout at every step:

* a ``framepos`` sensor of each fated body's frame (``xbody``) when a fate needs the path (``at``,
  ``through``, ``still``): the origin at the state each step starts from (``MjData.xpos``);
* a ``contact`` sensor (``data="found dist"``, ``reduce="mindist"``) per body and name of its
  ``hits``/``never_hits`` (body1 the fated body, body2 the named body or geom2 the named geom): a
  touch is a matching contact of distance <= 0 (found > 0, smallest distance <= 0); its time is
  the first step it shows in;
* with ``sequences=True``, such a sensor per fated body and each other named body (a geom of the
  world body by its own name): the contact sequence;
* a ``framepos`` sensor of each body in a ``hits`` pair (the fated body and each named body): how
  near a name never touched came (:func:`closest_approach`: the gap between the two bodies'
  bounding spheres, its least over the run and at the start), which the judge grades by.

The final pose and velocities are read from a second ``MjData``. Sensors only read the state, so
the copy steps as the scene does: when it is made, every array of the two models outside the
sensors and names is compared, and one rollout of each is compared bit for bit; if anything
differs (or ``loop=True``), the rollout is a plain ``mj_step`` loop in Python reading
``MjData.xpos`` and ``MjData.contact`` between the steps instead (:attr:`SceneSim.engine` says
which). Either way :func:`replay` (the loop written in docs/scene.md) gives the same final state
bit for bit. A rollout on which MuJoCo warned (``mujoco.rollout`` stops stepping at a warning) is
rolled out again by the loop, so that its final state too is the loop's.

**Threads**: :meth:`SceneSim.run` rolls a batch out on ``jobs`` threads, each with its own
``MjData`` (and ``mujoco.rollout.Rollout``), reset before every rollout: the results do not
depend on ``jobs``.

mujoco is imported when a :class:`SceneSim` is made.

Length: two rollout paths that must agree bit for bit (mujoco.rollout with sensors on a copy of
the scene, and the plain mj_step loop it falls back to) and the check between them live
together, so that one reading shows both.
"""
from __future__ import annotations

import threading
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any, Iterator

import numpy as np

from nbst.errors import SolveError
from nbst.models.mjsearch.runner import data_warnings
from nbst.scene.fates import Fates
from nbst.scene.judge import Judgement, Recording, judge, rotate
from nbst.scene.scenefile import body_radius

__all__ = ["SceneRollout", "SceneSim", "replay", "conjugate", "quiet_mujoco_warnings"]


@contextmanager
def quiet_mujoco_warnings() -> Iterator[None]:
    """While the block runs, MuJoCo's warnings (a diverging rollout) are neither printed nor
    written to ``MUJOCO_LOG.TXT`` in the current folder; each rollout still counts them in its
    ``MjData`` (:attr:`SceneRollout.warnings`). The process-wide hook is restored after."""
    import mujoco

    old = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(lambda msg: None)
    try:
        yield
    finally:
        mujoco.set_mju_user_warning(old)


def conjugate(quat: np.ndarray) -> np.ndarray:
    """The conjugate (inverse) of a unit quaternion (w, x, y, z)."""
    q = np.asarray(quat, dtype=float)
    return np.array([q[0], -q[1], -q[2], -q[3]])


def contact_sequence(firsts: list[tuple[int, str, str]]) -> list[str]:
    """The contact sequence from first touches ``(step, body, other)``: in time order, ``"BODY-OTHER"``,
    a touch of two fated bodies said once (from the side that sorts first), not from each; a touch in
    the first step (step 0: already there at the start, a die on the table, a stacked block on the
    one below) is not in it, as no choice of the search made it."""
    out: list[str] = []
    said: set[frozenset[str]] = set()
    for k, body, other in sorted(firsts):
        if k == 0:
            continue
        if (pair := frozenset((body, other))) not in said:
            said.add(pair)
            out.append(f"{body}-{other}")
    return out


def closest_approach(sim: SceneSim, npos: np.ndarray | None) -> tuple[dict[str, tuple[float, float]], ...]:
    """Per fated body, ``{name: (least gap, gap at the start)}`` (m) for each name of its ``hits``
    that is a body or a geom of the world (not a plane): the gap is the distance between the two
    origins less both bounding radii (a body's about its origin: each geom's offset plus its
    ``geom_rbound``; a world geom's about its centre), never below 0, over the steps recorded
    (``npos``: (T, K, 3), the origins of ``sim.near_bodies``)."""
    out: list[dict[str, tuple[float, float]]] = [{} for _ in sim.bodies]
    if npos is None or not len(npos):
        return tuple(out)
    for i, name, a, b, centre, ra, rb in sim.near:
        other = npos[:, b] if b >= 0 else centre
        gap = np.maximum(np.linalg.norm(npos[:, a] - other, axis=-1) - ra - rb, 0.0)
        out[i][name] = (float(gap.min()), float(gap[0]))
    return tuple(out)


@dataclass(frozen=True)
class SceneRollout:
    """One rollout: its controls, initial and final state, the judge's verdict.

    Args:
        x: (D,) the controls vector.
        qpos0: (nq,) initial qpos; qvel0: (nv,) initial qvel.
        qpos: (nq,) final qpos; qvel: (nv,) final qvel.
        judgement: the fates judged.
        warnings: MuJoCo's warnings during the rollout (a diverging state), by name.
        sequence: the contact sequence, when the sim records it (``sequences=True``): each fated
            body's first touch of each other body, in time order, as ``"BODY-OTHER"`` (a geom of
            the world body goes by its own name, when it has one: ``"die1-floor"``); two fated
            bodies' touch once (:func:`contact_sequence`).
    """

    x: np.ndarray
    qpos0: np.ndarray
    qvel0: np.ndarray
    qpos: np.ndarray
    qvel: np.ndarray
    judgement: Judgement
    warnings: tuple[str, ...]
    sequence: tuple[str, ...] = ()

    @property
    def cost(self) -> float:
        """The judgement's cost; infinite when MuJoCo warned."""
        return float("inf") if self.warnings else self.judgement.cost

    @property
    def signature(self) -> tuple[bool, ...]:
        return tuple(False for _ in self.judgement.signature) if self.warnings else self.judgement.signature


class SceneSim:
    """Rollouts of one scene with its fates (see the module docstring).

    Args:
        fates: the checked fates.
        model: the compiled ``mujoco.MjModel`` (``nbst.scene.scenefile.load_fates`` gives both).
        jobs: threads for :meth:`run` (1: the calling thread).
        sequences: also record each rollout's contact sequence (:attr:`SceneRollout.sequence`).
        loop: roll out with the plain ``mj_step`` loop in Python (reads between the steps)
            rather than ``mujoco.rollout`` (the reference the tests compare with).
    """

    def __init__(self, fates: Fates, model: Any, *, jobs: int = 1, sequences: bool = False, loop: bool = False):
        import mujoco

        self.fates, self.model, self.jobs = fates, model, max(1, int(jobs))
        self.sequences = bool(sequences)
        m = model
        self.nstep = int(round(fates.duration / m.opt.timestep))
        self.key = (-1 if fates.keyframe is None
                    else int(mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_KEY, fates.keyframe)))

        def bid(name: str) -> int:
            return int(mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, name))

        self.adr = []
        for c in fates.controls:
            j = int(m.body_jntadr[bid(c.body)])
            self.adr.append((int(m.jnt_qposadr[j]), int(m.jnt_dofadr[j])))
        self.bodies = np.array([bid(f.body) for f in fates.fates], dtype=int)
        # contact pairs of interest: (geom a, geom b) sorted -> [(fated body index, name), ...]
        self.pairs: dict[tuple[int, int], list[tuple[int, str]]] = {}
        #: (fated body index, name) of each hits/never_hits name, in order (the sensors' order)
        self.named: list[tuple[int, str]] = []
        for i, f in enumerate(fates.fates):
            mine = np.flatnonzero(m.geom_bodyid == self.bodies[i])
            for name in dict.fromkeys((*f.hits, *f.never_hits)):
                self.named.append((i, name))
                b = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, name)
                theirs = (np.flatnonzero(m.geom_bodyid == b) if b >= 0
                          else [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, name)])
                for g1 in mine:
                    for g2 in theirs:
                        key = (int(min(g1, g2)), int(max(g1, g2)))
                        self.pairs.setdefault(key, []).append((i, name))
        #: geoms in some pair of interest (a cheap test of each step's contacts), and the first
        #: touches to find (once all are found, the contacts are read no more)
        self.involved = np.zeros(m.ngeom, dtype=bool)
        for a, b in self.pairs:
            self.involved[a] = self.involved[b] = True
        self.to_find = len(self.named)
        # for the contact sequence: each geom's fated body index (-1: none) and the name it goes by
        self.fated_of = np.full(m.ngeom, -1, dtype=int)
        for i, b in enumerate(self.bodies):
            self.fated_of[m.geom_bodyid == b] = i
        self.touch_name = [m.body(int(m.geom_bodyid[g])).name if m.geom_bodyid[g] != 0 or not m.geom(g).name
                           else m.geom(g).name for g in range(m.ngeom)]
        #: per ``hits`` name: (fated body index, name, slot of the fated body, slot of the other or -1
        #: for a static geom, the other's fixed centre, the two bounding radii) with ``near_bodies``
        #: the bodies whose origins are recorded at every step (:func:`closest_approach`)
        self.near: list[tuple[int, str, int, int, np.ndarray, float, float]] = []
        self.near_bodies: list[int] = []

        def slot(b: int) -> int:
            if b not in self.near_bodies:
                self.near_bodies.append(b)
            return self.near_bodies.index(b)

        for i, f in enumerate(fates.fates):
            me = int(self.bodies[i])
            for name in dict.fromkeys(f.hits):
                b = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, name)
                if b > 0:
                    self.near.append((i, name, slot(me), slot(b), np.zeros(3),
                                      body_radius(m, me),
                                      body_radius(m, b)))
                elif b < 0:
                    g = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, name)
                    if m.geom_bodyid[g] == 0 and m.geom_type[g] != mujoco.mjtGeom.mjGEOM_PLANE:
                        self.near.append((i, name, slot(me), -1, np.array(m.geom_pos[g], dtype=float),
                                          body_radius(m, me), float(m.geom_rbound[g])))
        #: the judge needs the path at every step (``at``, ``through``, ``still``), not only the end
        self.per_step = any(f.at or f.through or f.still for f in fates.fates)
        self._local = threading.local()
        self._rec: _Recorder | None = None
        if not loop:
            self._rec = _Recorder.make(self)
        #: how the rollouts run: ``"mujoco.rollout"`` or ``"mj_step loop"`` (see the module docstring)
        self.engine = "mujoco.rollout" if self._rec is not None else "mj_step loop"
        self._pool = ThreadPoolExecutor(max_workers=self.jobs) if self.jobs > 1 else None

    # -- lifetime --------------------------------------------------------------------------
    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None

    def __enter__(self) -> SceneSim:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- states ----------------------------------------------------------------------------
    def _data(self) -> tuple[Any, Any]:
        loc = self._local
        if not hasattr(loc, "data"):
            import mujoco

            loc.data, loc.scratch = mujoco.MjData(self.model), mujoco.MjData(self.model)
        return loc.data, loc.scratch

    def _reset(self, d: Any, model: Any = None) -> None:
        import mujoco

        m = self.model if model is None else model
        if self.key >= 0:
            mujoco.mj_resetDataKeyframe(m, d, self.key)
        else:
            mujoco.mj_resetData(m, d)

    def initial_state(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The initial ``(qpos (nq,), qvel (nv,))`` of the controls vector ``x`` (D,)."""
        d, _ = self._data()
        self._reset(d)
        qpos, qvel = d.qpos.copy(), d.qvel.copy()
        x = np.asarray(x, dtype=float)
        for c, sl, (qa, da) in zip(self.fates.controls, self.fates.blocks(), self.adr):
            v = x[sl]
            for k, (part, _) in enumerate(c.parts()):
                u = v[3 * k:3 * k + 3]
                if part == "pos":
                    qpos[qa:qa + 3] = qpos[qa:qa + 3] + u
                elif part == "linvel":
                    qvel[da:da + 3] = u
                else:  # angvel: world frame -> the free joint's body frame
                    qvel[da + 3:da + 6] = rotate(conjugate(qpos[qa + 3:qa + 7]), u)
        return qpos, qvel

    # -- rolling out -----------------------------------------------------------------------
    def rollout(self, x: np.ndarray, state: tuple[np.ndarray, np.ndarray] | None = None) -> SceneRollout:
        """Roll the controls vector ``x`` (D,) out and judge it; from ``state`` (qpos0, qvel0) when given (a
        solution file's stored state, which an edited scene would not give again from ``x``)."""
        if self._rec is None:
            return self._loop(x, state)
        qpos0, qvel0 = self.initial_state(x) if state is None else (np.array(state[0], float), np.array(state[1], float))
        got = self._rec.run(qpos0, qvel0)
        if got is None:  # MuJoCo warned: the loop's final state, its warnings
            return self._loop(x, state)
        qpos, qvel, time, pos, touches, seq, npos = got
        return self._finish(x, qpos0, qvel0, qpos, qvel, time, pos, touches, seq, (), npos)

    def _finish(self, x, qpos0, qvel0, qpos, qvel, time, pos, touches, seq, warned, npos=None) -> SceneRollout:
        """Judge a rollout: ``pos`` (T+1, B, 3) with its last row filled here from the final state."""
        import mujoco

        m, ids = self.model, self.bodies
        _, s = self._data()
        s.qpos[:] = qpos
        s.qvel[:] = qvel
        s.time = time
        mujoco.mj_forward(m, s)
        pos[-1] = s.xpos[ids]
        h = float(m.opt.timestep)
        times = np.arange(len(pos)) * h if len(pos) > 2 else np.array([0.0, self.nstep * h])
        vel = np.empty(6)
        lin, ang = np.empty((len(ids), 3)), np.empty((len(ids), 3))
        for i, b in enumerate(ids):
            mujoco.mj_objectVelocity(m, s, mujoco.mjtObj.mjOBJ_BODY, int(b), vel, 0)
            ang[i], lin[i] = vel[:3], vel[3:]
        rec = Recording(times=times, pos=pos, quat=s.xquat[ids].copy(), linvel=lin, angvel=ang,
                        touches=tuple(touches), near=closest_approach(self, npos))
        return SceneRollout(x=np.array(x, dtype=float), qpos0=qpos0, qvel0=qvel0, qpos=np.array(qpos, dtype=float),
                            qvel=np.array(qvel, dtype=float), judgement=judge(self.fates, rec),
                            warnings=tuple(warned), sequence=tuple(seq))

    def _loop(self, x: np.ndarray, state: tuple[np.ndarray, np.ndarray] | None = None) -> SceneRollout:
        """The rollout as a plain ``mj_step`` loop in Python, reading between the steps."""
        import mujoco

        m = self.model
        d, s = self._data()
        qpos0, qvel0 = self.initial_state(x) if state is None else (np.array(state[0], float), np.array(state[1], float))
        self._reset(d)
        d.qpos[:] = qpos0
        d.qvel[:] = qvel0
        ids, pairs, n = self.bodies, self.pairs, self.nstep
        touches: list[dict[str, float]] = [{} for _ in ids]
        h = float(m.opt.timestep)
        seq: list[tuple[int, str, str]] = []
        npos = np.empty((n, len(self.near_bodies), 3))
        if not (self.per_step or pairs or self.sequences or self.near):  # only the end is judged: one call, in C
            s.qpos[:] = qpos0
            mujoco.mj_kinematics(m, s)
            first = s.xpos[ids].copy()
            mujoco.mj_step(m, d, nstep=n)
            pos = np.empty((2, len(ids), 3))
            pos[0] = first
        else:
            pos = np.empty((n + 1, len(ids), 3))
            involved, left, fated_of, names = self.involved, self.to_find, self.fated_of, self.touch_name
            seen: set[tuple[int, str]] = set()
            for k in range(n):
                mujoco.mj_step(m, d)
                pos[k] = d.xpos[ids]  # the state this step started from
                npos[k] = d.xpos[self.near_bodies]
                if self.sequences and d.ncon:
                    con = d.contact
                    geom = con.geom[:d.ncon]
                    for c in np.flatnonzero(((fated_of[geom[:, 0]] >= 0) | (fated_of[geom[:, 1]] >= 0))
                                            & (con.dist[:d.ncon] <= 0)):
                        for a, b in ((int(geom[c, 0]), int(geom[c, 1])), (int(geom[c, 1]), int(geom[c, 0]))):
                            i = int(fated_of[a])
                            if i >= 0 and (i, names[b]) not in seen and names[b] != self.fates.fates[i].body:
                                seen.add((i, names[b]))
                                seq.append((k, self.fates.fates[i].body, names[b]))
                if left and d.ncon:
                    con = d.contact
                    geom = con.geom[:d.ncon]
                    near = np.flatnonzero(involved[geom[:, 0]] & involved[geom[:, 1]] & (con.dist[:d.ncon] <= 0))
                    for c in near:
                        g0, g1 = int(geom[c, 0]), int(geom[c, 1])
                        for i, name in pairs.get((min(g0, g1), max(g0, g1)), ()):
                            if name not in touches[i]:
                                touches[i][name] = k * h
                                left -= 1
        return self._finish(x, qpos0, qvel0, d.qpos.copy(), d.qvel.copy(), d.time, pos, touches,
                            contact_sequence(seq), data_warnings(d), npos)

    def run(self, xs: np.ndarray) -> list[SceneRollout]:
        """Roll out (B, D) controls vectors on ``jobs`` threads: B rollouts, in input order."""
        xs = np.asarray(xs, dtype=float).reshape(-1, self.fates.dim)
        if self._pool is None:
            return [self.rollout(x) for x in xs]
        return list(self._pool.map(self.rollout, xs))


#: Model attributes that adding sensors (and their names) changes; every other one must be equal.
_SENSOR_ATTRS = ("sensor", "name", "nbuffer", "signature")


class _Recorder:
    """The scene's copy with the sensors of the judge, rolled out by ``mujoco.rollout`` (module docstring)."""

    def __init__(self, sim: SceneSim, model: Any, pos_adr: np.ndarray | None, named_adr: list[int],
                 seq: list[tuple[int, str, int]], near_adr: np.ndarray | None = None):
        import mujoco

        self.sim, self.model = sim, model
        self.pos_adr, self.named_adr, self.seq = pos_adr, np.array(named_adr, dtype=int), seq
        self.near_adr = near_adr
        self.spec = int(mujoco.mjtState.mjSTATE_FULLPHYSICS)
        self.nstate = mujoco.mj_stateSize(model, self.spec)
        # what a key sets beyond the physics state (controls, mocap, equality activity), which
        # mujoco.rollout would otherwise reset: given to it as constant controls
        m0 = sim.model
        self.cspec, self.control = 0, None
        if sim.key >= 0 and (m0.nu or m0.nmocap or m0.neq):
            import mujoco as mj

            self.cspec = int(mj.mjtState.mjSTATE_CTRL | mj.mjtState.mjSTATE_MOCAP_POS | mj.mjtState.mjSTATE_MOCAP_QUAT
                             | mj.mjtState.mjSTATE_EQ_ACTIVE)
            d = mj.MjData(model)
            sim._reset(d, model)
            u = np.empty(mj.mj_stateSize(model, self.cspec))
            mj.mj_getState(model, d, u, self.cspec)
            self.control = np.ascontiguousarray(np.broadcast_to(u, (1, sim.nstep, len(u))))
        self._local = threading.local()

    @staticmethod
    def make(sim: SceneSim) -> _Recorder | None:
        """The recorder of ``sim``'s scene, or None when its copy does not step as the scene does."""
        import mujoco

        m, f = sim.model, sim.fates
        need_pos = sim.per_step
        if not (need_pos or sim.named or sim.sequences):  # the end alone: the scene itself, no sensors added
            return _Recorder(sim, m, None, [], [])
        try:
            spec = mujoco.MjSpec.from_file(str(f.scene))
            taken = {s.name for s in spec.sensors}
            names: list[str] = []

            def add(**kw: Any) -> str:
                name = f"nbst_{len(names)}"
                while name in taken:
                    name = "_" + name
                names.append(name)
                spec.add_sensor(name=name, **kw)
                return name

            pos_names = [add(type=mujoco.mjtSensor.mjSENS_FRAMEPOS, objtype=mujoco.mjtObj.mjOBJ_XBODY,
                             objname=fa.body) for fa in f.fates] if need_pos else []

            def touch(body: str, other: str, is_body: bool) -> str:
                return add(type=mujoco.mjtSensor.mjSENS_CONTACT, objtype=mujoco.mjtObj.mjOBJ_BODY, objname=body,
                           reftype=mujoco.mjtObj.mjOBJ_BODY if is_body else mujoco.mjtObj.mjOBJ_GEOM, refname=other,
                           intprm=[_FOUND_DIST, _MINDIST, 1])

            named_names = [touch(f.fates[i].body, name, mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, name) >= 0)
                           for i, name in sim.named]
            near_names = [add(type=mujoco.mjtSensor.mjSENS_FRAMEPOS, objtype=mujoco.mjtObj.mjOBJ_XBODY,
                              objname=m.body(b).name) for b in sim.near_bodies]
            others = []
            if sim.sequences:
                # every other named body (the world's geoms by their own names)
                targets = [(m.body(b).name, True) for b in range(1, m.nbody) if m.body(b).name]
                targets += [(m.geom(g).name, False) for g in range(m.ngeom) if m.geom_bodyid[g] == 0 and m.geom(g).name]
                if any(m.geom_bodyid[g] == 0 and not m.geom(g).name for g in range(m.ngeom)):
                    targets.append((m.body(0).name, True))  # the world's unnamed geoms go by "world"
                for i, fa in enumerate(f.fates):
                    for other, is_body in targets:
                        if other != fa.body:
                            others.append((i, other, touch(fa.body, other, is_body)))
            copy = spec.compile()
        except Exception:  # the scene's file cannot be compiled again here: the loop then
            return None
        _copy_option(m, copy)
        if not _same_physics(m, copy):
            return None

        def adr(name: str) -> int:
            return int(copy.sensor_adr[copy.sensor(name).id])

        pos_adr = np.array([[adr(n) + k for k in range(3)] for n in pos_names], dtype=int) if need_pos else None
        near_adr = (np.array([[adr(n) + k for k in range(3)] for n in near_names], dtype=int) if near_names
                    else None)
        rec = _Recorder(sim, copy, pos_adr, [adr(n) for n in named_names], [(i, o, adr(n)) for i, o, n in others],
                        near_adr)
        # one rollout of each, compared bit for bit (the middle of the ranges, at most 200 steps)
        if not rec.agrees():
            return None
        return rec

    def _worker(self) -> Any:
        loc = self._local
        if not hasattr(loc, "data"):
            import mujoco
            from mujoco import rollout

            loc.data = mujoco.MjData(self.model)
            loc.rollout = rollout.Rollout(nthread=0)
            loc.state0 = np.empty((1, self.nstate))
            loc.sensordata = (np.empty((1, self.sim.nstep, self.model.nsensordata)) if self.model.nsensordata
                              else None)
        return loc

    def _step(self, qpos0: np.ndarray, qvel0: np.ndarray, nstep: int) -> Any:
        import mujoco

        w = self._worker()
        d = w.data
        self.sim._reset(d, self.model)
        d.qpos[:] = qpos0
        d.qvel[:] = qvel0
        mujoco.mj_getState(self.model, d, w.state0[0], self.spec)
        sd = (w.sensordata if nstep == self.sim.nstep or w.sensordata is None
              else np.empty((1, nstep, self.model.nsensordata)))
        ctrl = None if self.control is None else self.control[:, :nstep]
        w.rollout.rollout([self.model], [d], w.state0, ctrl, control_spec=self.cspec, skip_checks=True, nstep=nstep,
                          sensordata=sd)
        return w, d, sd

    def agrees(self) -> bool:
        """One rollout of the copy and of the scene itself give the same final state, bit for bit."""
        import mujoco

        lo, hi = self.sim.fates.bounds()
        qpos0, qvel0 = self.sim.initial_state((lo + hi) / 2)
        n = min(self.sim.nstep, 200)
        _, d, _ = self._step(qpos0, qvel0, n)
        ref = mujoco.MjData(self.sim.model)
        self.sim._reset(ref)
        ref.qpos[:] = qpos0
        ref.qvel[:] = qvel0
        for _ in range(n):
            mujoco.mj_step(self.sim.model, ref)
        return bool(d.qpos.tobytes() == ref.qpos.tobytes() and d.qvel.tobytes() == ref.qvel.tobytes())

    def run(self, qpos0: np.ndarray, qvel0: np.ndarray) -> tuple | None:
        """(final qpos, qvel, time, pos (T+1, B, 3) or (2, B, 3), touches, sequence, the origins of
        ``sim.near_bodies`` (T, K, 3) or None) of one rollout, or None when MuJoCo warned."""
        import mujoco

        sim = self.sim
        n = sim.nstep
        w, d, sd = self._step(qpos0, qvel0, n)
        if any(d.warning[k].number > 0 for k in range(len(d.warning))):
            return None
        B = len(sim.bodies)
        if self.pos_adr is not None:
            pos = np.empty((n + 1, B, 3))
            pos[:n] = sd[0][:, self.pos_adr]
        else:
            pos = np.empty((2, B, 3))
            s = sim._data()[1]
            s.qpos[:] = qpos0
            mujoco.mj_kinematics(sim.model, s)
            pos[0] = s.xpos[sim.bodies]
        h = float(sim.model.opt.timestep)
        touches: list[dict[str, float]] = [{} for _ in range(B)]
        if len(self.named_adr):
            hit = (sd[0][:, self.named_adr] > 0) & (sd[0][:, self.named_adr + 1] <= 0)
            for j, (i, name) in enumerate(sim.named):
                k = np.flatnonzero(hit[:, j])
                if len(k):
                    touches[i][name] = int(k[0]) * h
        seq: list[tuple[int, str, str]] = []
        if self.seq:
            a = np.array([s for _, _, s in self.seq], dtype=int)
            hit = (sd[0][:, a] > 0) & (sd[0][:, a + 1] <= 0)
            first = np.where(hit.any(axis=0), hit.argmax(axis=0), -1)
            for (i, other, _), k in zip(self.seq, first):
                if k >= 0:
                    seq.append((int(k), sim.fates.fates[i].body, other))
        npos = None if self.near_adr is None else sd[0][:, self.near_adr]
        return d.qpos.copy(), d.qvel.copy(), d.time, pos, touches, contact_sequence(seq), npos


#: The contact sensor's data "found dist" (mjCONDATA_FOUND, mjCONDATA_DIST bits) and reduce "mindist".
_FOUND_DIST, _MINDIST = (1 << 0) | (1 << 3), 1


def _copy_option(src: Any, dst: Any) -> None:
    """Every field of ``src.opt`` onto ``dst.opt`` (a timestep, integrator, solver or cone changed)."""
    for a in dir(src.opt):
        if a.startswith("_"):
            continue
        v = getattr(src.opt, a)
        if callable(v):
            continue
        if isinstance(v, np.ndarray):
            getattr(dst.opt, a)[...] = v
        else:
            setattr(dst.opt, a, v)


def _same_physics(a: Any, b: Any) -> bool:
    """Every array and number of two models equal, the sensors and names apart (and ``opt`` too)."""
    for name in dir(a):
        if name.startswith("_") or any(s in name for s in _SENSOR_ATTRS):
            continue
        try:
            x, y = getattr(a, name), getattr(b, name)
        except Exception:
            continue
        if isinstance(x, np.ndarray):
            if not isinstance(y, np.ndarray) or x.shape != y.shape or x.tobytes() != y.tobytes():
                return False
        elif isinstance(x, (int, float)) and not isinstance(x, bool) and x != y:
            return False
    for name in dir(a.opt):
        if name.startswith("_"):
            continue
        x, y = getattr(a.opt, name), getattr(b.opt, name)
        if callable(x):
            continue
        if np.asarray(x).tobytes() != np.asarray(y).tobytes():
            return False
    return True


def replay(model: Any, qpos0: np.ndarray, qvel0: np.ndarray, nstep: int, *, key: int = -1) -> tuple[np.ndarray,
                                                                                                       np.ndarray]:
    """The plain ``mj_step`` loop of docs/scene.md: the final ``(qpos, qvel)`` from an initial state.

    Args:
        model: the compiled ``mujoco.MjModel`` (its timestep set as the fates say).
        qpos0: (nq,) initial qpos; qvel0: (nv,) initial qvel.
        nstep: steps.
        key: the keyframe reset to first (-1: none), as the search did.

    Returns:
        ``(qpos (nq,), qvel (nv,))`` after ``nstep`` steps.

    Raises:
        SolveError: the state does not fit the model.
    """
    import mujoco

    d = mujoco.MjData(model)
    if key >= 0:
        mujoco.mj_resetDataKeyframe(model, d, key)
    if len(qpos0) != model.nq or len(qvel0) != model.nv:
        raise SolveError(f"the state has {len(qpos0)} qpos and {len(qvel0)} qvel; the model has {model.nq} and "
                         f"{model.nv}")
    d.qpos[:] = qpos0
    d.qvel[:] = qvel0
    for _ in range(int(nstep)):
        mujoco.mj_step(model, d)
    return d.qpos.copy(), d.qvel.copy()
