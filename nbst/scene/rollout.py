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

**The rollout** (:meth:`SceneSim.rollout`) is a plain ``mj_step`` loop from that state, with
reads between the steps that change nothing in the simulation (positions of the fated bodies'
origins, ``MjData.xpos``, after each step, which are those of the state the step started from;
contacts listed by the step, for first touches; the final pose and velocities from a second
``MjData``). When no fate needs a step but the last (no ``at``, ``through``, ``still``, ``hits``
or ``never_hits``), the loop is one ``mj_step(model, data, nstep=n)`` call: the same steps, run in
C with the GIL released, so the threads of :meth:`SceneSim.run` run side by side. So :func:`replay` (the loop written in docs/scene.md) gives the same final state bit
for bit. A contact touches when its distance is <= 0.

**Threads**: :meth:`SceneSim.run` rolls a batch out on ``jobs`` threads, each with its own
``MjData``, reset before every rollout: the results do not depend on ``jobs``.

mujoco is imported when a :class:`SceneSim` is made.
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
            the world body goes by its own name, when it has one: ``"die1-floor"``).
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
        sequences: also record each rollout's contact sequence (:attr:`SceneRollout.sequence`;
            every step is then read).
    """

    def __init__(self, fates: Fates, model: Any, *, jobs: int = 1, sequences: bool = False):
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
        for i, f in enumerate(fates.fates):
            mine = np.flatnonzero(m.geom_bodyid == self.bodies[i])
            for name in (*f.hits, *f.never_hits):
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
        self.to_find = sum(len({*f.hits, *f.never_hits}) for f in fates.fates)
        # for the contact sequence: each geom's fated body index (-1: none) and the name it goes by
        self.fated_of = np.full(m.ngeom, -1, dtype=int)
        for i, b in enumerate(self.bodies):
            self.fated_of[m.geom_bodyid == b] = i
        self.touch_name = [m.body(int(m.geom_bodyid[g])).name if m.geom_bodyid[g] != 0 or not m.geom(g).name
                           else m.geom(g).name for g in range(m.ngeom)]
        #: the judge needs the path at every step (``at``, ``through``, ``still``), not only the end
        self.per_step = any(f.at or f.through or f.still for f in fates.fates)
        self._local = threading.local()
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

    def _reset(self, d: Any) -> None:
        import mujoco

        if self.key >= 0:
            mujoco.mj_resetDataKeyframe(self.model, d, self.key)
        else:
            mujoco.mj_resetData(self.model, d)

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
    def rollout(self, x: np.ndarray) -> SceneRollout:
        """Roll the controls vector ``x`` (D,) out and judge it."""
        import mujoco

        m = self.model
        d, s = self._data()
        qpos0, qvel0 = self.initial_state(x)
        self._reset(d)
        d.qpos[:] = qpos0
        d.qvel[:] = qvel0
        ids, pairs, n = self.bodies, self.pairs, self.nstep
        touches: list[dict[str, float]] = [{} for _ in ids]
        h = float(m.opt.timestep)
        seq: list[str] = []
        if not (self.per_step or pairs or self.sequences):  # only the end is judged: one call, the same steps in C
            s.qpos[:] = qpos0
            mujoco.mj_kinematics(m, s)
            first = s.xpos[ids].copy()
            mujoco.mj_step(m, d, nstep=n)
            pos = np.empty((2, len(ids), 3))
            pos[0] = first
            times = np.array([0.0, n * h])
        else:
            pos = np.empty((n + 1, len(ids), 3))
            times = np.arange(n + 1) * h
            involved, left, fated_of, names = self.involved, self.to_find, self.fated_of, self.touch_name
            seen: set[tuple[int, str]] = set()
            for k in range(n):
                mujoco.mj_step(m, d)
                pos[k] = d.xpos[ids]  # the state this step started from
                if self.sequences and d.ncon:
                    con = d.contact
                    geom = con.geom[:d.ncon]
                    for c in np.flatnonzero(((fated_of[geom[:, 0]] >= 0) | (fated_of[geom[:, 1]] >= 0))
                                            & (con.dist[:d.ncon] <= 0)):
                        for a, b in ((int(geom[c, 0]), int(geom[c, 1])), (int(geom[c, 1]), int(geom[c, 0]))):
                            i = int(fated_of[a])
                            if i >= 0 and (i, names[b]) not in seen and names[b] != self.fates.fates[i].body:
                                seen.add((i, names[b]))
                                seq.append(f"{self.fates.fates[i].body}-{names[b]}")
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
        s.qpos[:] = d.qpos
        s.qvel[:] = d.qvel
        s.time = d.time
        mujoco.mj_forward(m, s)
        pos[-1] = s.xpos[ids]
        vel = np.empty(6)
        lin, ang = np.empty((len(ids), 3)), np.empty((len(ids), 3))
        for i, b in enumerate(ids):
            mujoco.mj_objectVelocity(m, s, mujoco.mjtObj.mjOBJ_BODY, int(b), vel, 0)
            ang[i], lin[i] = vel[:3], vel[3:]
        rec = Recording(times=times, pos=pos, quat=s.xquat[ids].copy(), linvel=lin, angvel=ang,
                        touches=tuple(touches))
        warned = tuple(data_warnings(d))
        return SceneRollout(x=np.array(x, dtype=float), qpos0=qpos0, qvel0=qvel0, qpos=d.qpos.copy(),
                            qvel=d.qvel.copy(), judgement=judge(self.fates, rec), warnings=warned,
                            sequence=tuple(seq))

    def run(self, xs: np.ndarray) -> list[SceneRollout]:
        """Roll out (B, D) controls vectors on ``jobs`` threads: B rollouts, in input order."""
        xs = np.asarray(xs, dtype=float).reshape(-1, self.fates.dim)
        if self._pool is None:
            return [self.rollout(x) for x in xs]
        return list(self._pool.map(self.rollout, xs))


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
