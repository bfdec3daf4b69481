"""MuJoCo rollouts on K threads, open loop or closed loop in chunks: :class:`Runner`.

A **rollout** starts from a full physics state (``mjSTATE_FULLPHYSICS``: time, qpos, qvel,
act, ...; :meth:`Runner.initial_state` makes one from qpos/qvel) and runs ``nstep`` steps of
the model. :meth:`Runner.run` takes a batch of initial states, (B, nstate), and returns
:class:`Rollouts`: the final states (B, nstate) in input order, and on request the controls
that were applied and the sensor data of every step.

* **Threads**: ``jobs`` threads, each with its own ``MjData`` and ``mujoco.rollout.Rollout``
  (``nthread=0``: it runs on the calling thread, which the bindings let run without the
  GIL). Before each rollout the thread's data is reset (``mj_resetData``), so a rollout's
  result depends on its initial state (and controls) only, never on which thread ran it
  or what ran there before: the same batch gives the same bits for any ``jobs``.
* **Open loop**: ``control``, (B, nstep, nu) or (nu,) for all (``mjSTATE_CTRL``).
* **Closed loop**: ``controller(i, step, data) -> (nu,)`` is called for rollout ``i`` at
  step 0 and then every ``chunk`` steps, with the thread's ``MjData`` at that step (its state
  set, ``mj_forward`` run, so positions, contacts and sensors are those of the state); the
  control it returns is held for the next chunk. Each chunk is one ``mujoco.rollout`` call
  from the state the last one ended in, with the last one's ``qacc_warmstart``: the result
  is the same, bit for bit, as one call with the controls it recorded
  (``Rollouts.control``), which is how a closed-loop run is replayed
  (tests/test_mjsearch.py checks it with warm-starting on and off). The controller must
  only read ``data`` and must depend only on what it is given (and its own per-rollout
  state keyed by ``i``) for a run to be reproducible.
* **Warnings**: MuJoCo's warnings (a diverging state) are counted in each data;
  :func:`mujoco_warnings_raise` and :func:`data_warnings` turn them into
  :class:`~nbst.errors.MujocoError` for the callers that step by hand; :func:`check_state`
  refuses a non-finite state before stepping.

Sleeping bodies: a model with ``<flag sleep="enable"/>`` keeps its sleep state in ``MjData``,
outside the full physics state; the reset before every rollout makes that harmless for one
call, and a chunked run continues in the same data. Warm-starting off
(``<flag warmstart="disable"/>``) and sleeping off make a closed-loop run independent of
the chunk size too (the crash's drivers; issue 32 measured chunk boundaries moving rest
positions by metres otherwise).

Compute only: no files, no printing. mujoco is imported when a Runner is made.
"""
from __future__ import annotations

import os
import threading
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Callable

import numpy as np

from nbst.errors import InputError, MujocoError

__all__ = ["Controller", "n_steps", "mujoco_warnings_raise", "data_warnings", "check_state", "Rollouts", "Runner"]

#: A closed-loop controller: (rollout index, step, MjData at that step) -> (nu,) control.
Controller = Callable[[int, int, object], np.ndarray]


def n_steps(model, duration: float) -> int:
    """Steps of ``model``'s timestep in ``duration`` seconds (rounded)."""
    return int(round(float(duration) / model.opt.timestep))


@contextmanager
def mujoco_warnings_raise():
    """While the block runs, MuJoCo's warnings are collected instead of printed and written to
    ``MUJOCO_LOG.TXT`` in the current folder; after it, the first one raises
    :class:`MujocoError`. (MuJoCo's warning hook is process-wide: the previous one is restored.)"""
    import mujoco

    got: list[str] = []
    old = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(lambda msg: got.append(str(msg).strip()))
    try:
        yield got
    finally:
        mujoco.set_mju_user_warning(old)
    if got:
        raise MujocoError(f"MuJoCo warned: {got[0].splitlines()[0] if got[0] else 'unknown warning'}")


def data_warnings(data) -> list[str]:
    """Names of the MuJoCo warnings that ``data`` recorded (``data.warning[k].number > 0``)."""
    import mujoco

    return [mujoco.mjtWarning(k).name for k in range(len(data.warning)) if data.warning[k].number > 0]


def check_state(qpos, qvel) -> None:
    """MujocoError unless every qpos/qvel entry is finite (MuJoCo steps NaN into a reset)."""
    for name, v in (("qpos", qpos), ("qvel", qvel)):
        v = np.asarray(v, dtype=float)
        if not np.isfinite(v).all():
            raise MujocoError(f"{name}[{int(np.flatnonzero(~np.isfinite(v))[0])}] is not finite; refused before "
                              f"stepping")


@dataclass
class Rollouts:
    """What :meth:`Runner.run` returns, rollouts in input order.

    Args:
        final: (nbatch, nstate) float64 array: full physics states after the last step.
        control: (nbatch, nstep, nu) float64 array: the controls applied (given or from the
            controller); None when neither.
        sensordata: (nbatch, nstep, nsensordata) float64 array after each step; None unless asked.

    Returns:
        The rollouts (frozen).
    """

    final: np.ndarray
    control: np.ndarray | None = None
    sensordata: np.ndarray | None = None


class Runner:
    """Rollouts of ``model`` on ``jobs`` threads (see the module docstring).

    Args:
        model: a compiled ``mujoco.MjModel`` (shared read-only by the threads).
        jobs: threads (default: all cores).
        duration: seconds per rollout (``nstep`` = duration / timestep), or
        nstep: steps per rollout (one of the two; ``run`` may override per call).

    Returns:
        The runner; ``run`` rolls out a batch, ``close`` ends the threads.

    Raises:
        InputError: neither or both of ``duration`` and ``nstep``.
    """

    def __init__(self, model, *, jobs: int | None = None, duration: float | None = None,
                 nstep: int | None = None):
        import mujoco

        if (duration is None) == (nstep is None):
            raise InputError("Runner: give duration or nstep (one of them)")
        self.model = model
        self.jobs = max(1, int(jobs or os.cpu_count() or 1))
        self.nstep = int(nstep) if nstep is not None else n_steps(model, duration)  # type: ignore[arg-type]
        self.duration = float(duration) if duration is not None else self.nstep * float(model.opt.timestep)
        self._spec = int(mujoco.mjtState.mjSTATE_FULLPHYSICS)
        self.nstate = mujoco.mj_stateSize(model, self._spec)
        self.nu = int(model.nu)
        self._local = threading.local()
        self._pool = ThreadPoolExecutor(max_workers=self.jobs) if self.jobs > 1 else None
        self._all: list = []

    # -- lifetime ------------------------------------------------------------------------
    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None
        for r in self._all:
            r.close()
        self._all = []

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    # -- states --------------------------------------------------------------------------
    def initial_state(self, qpos, qvel) -> np.ndarray:
        """(nstate,) full physics state of a fresh MjData with ``qpos``/``qvel`` set."""
        import mujoco

        d = mujoco.MjData(self.model)
        d.qpos[:] = qpos
        d.qvel[:] = qvel
        s = np.empty(self.nstate)
        mujoco.mj_getState(self.model, d, s, self._spec)
        return s

    def final_qpos(self, final_states: np.ndarray) -> np.ndarray:
        """(B, nq) qpos out of (B, nstate) full physics states (time first, then qpos)."""
        return final_states[:, 1:1 + self.model.nq]

    def final_qvel(self, final_states: np.ndarray) -> np.ndarray:
        """(B, nv) qvel out of (B, nstate) full physics states (after time and qpos)."""
        a = 1 + self.model.nq
        return final_states[:, a:a + self.model.nv]

    # -- running -------------------------------------------------------------------------
    def _worker(self):
        loc = self._local
        if not hasattr(loc, "data"):
            import mujoco
            from mujoco import rollout

            loc.data = mujoco.MjData(self.model)
            loc.rollout = rollout.Rollout(nthread=0)
            self._all.append(loc.rollout)
            loc.buffers = {}
        return loc

    @staticmethod
    def _buffer(w, key, shape) -> np.ndarray:
        b = w.buffers.get(key)
        if b is None or b.shape != shape:
            b = w.buffers[key] = np.empty(shape)
        return b

    def _open(self, state0, nstep: int, control, sensors: bool):
        """One open-loop rollout on this thread: (final state, sensordata or None)."""
        import mujoco

        w = self._worker()
        mujoco.mj_resetData(self.model, w.data)
        st = self._buffer(w, ("state", nstep), (1, nstep, self.nstate))
        sd = self._buffer(w, ("sensor", nstep), (1, nstep, self.model.nsensordata)) if sensors else None
        w.rollout.rollout(self.model, w.data, state0[None, :], None if control is None else control[None],
                          nstep=nstep, state=st, sensordata=sd)
        return st[0, -1].copy(), (None if sd is None else sd[0].copy())

    def _closed(self, i: int, state0, nstep: int, controller: Controller, chunk: int, sensors: bool):
        """One closed-loop rollout on this thread: (final state, controls (nstep, nu), sensordata)."""
        import mujoco

        w = self._worker()
        m, d = self.model, w.data
        mujoco.mj_resetData(m, d)
        ctrl = np.empty((nstep, self.nu))
        sdata = np.empty((nstep, m.nsensordata)) if sensors else None
        state, warm, n = np.asarray(state0, dtype=float), None, 0
        mujoco.mj_setState(m, d, state, self._spec)
        while n < nstep:
            c = min(int(chunk), nstep - n)
            if n:
                warm = d.qacc_warmstart.copy()  # before mj_forward touches nothing of it: kept exact
            mujoco.mj_forward(m, d)
            u = np.asarray(controller(i, n, d), dtype=float).reshape(self.nu)
            ctrl[n:n + c] = u
            st = self._buffer(w, ("state", c), (1, c, self.nstate))
            sd = self._buffer(w, ("sensor", c), (1, c, m.nsensordata)) if sensors else None
            w.rollout.rollout(m, d, state[None, :], ctrl[None, n:n + c], nstep=c,
                              initial_warmstart=None if warm is None else warm[None, :], state=st, sensordata=sd)
            state = st[0, -1].copy()
            if sdata is not None and sd is not None:  # sensors
                sdata[n:n + c] = sd[0]
            n += c
        return state, ctrl, sdata

    def run(self, states0, *, nstep: int | None = None, control=None, controller: Controller | None = None,
            chunk: int | None = None, sensors: bool = False) -> Rollouts:
        """Roll out (B, nstate) initial states; see the module docstring.

        Args:
            states0: (B, nstate) full physics states (:meth:`initial_state`).
            nstep: steps (default the runner's).
            control: open loop: (B, nstep, nu) or (nu,) controls; or
            controller: closed loop: ``controller(i, step, data) -> (nu,)``, every ``chunk`` steps.
            sensors: also return the sensor data of every step.

        Returns:
            :class:`Rollouts` in input order.
        """
        states0 = np.ascontiguousarray(states0, dtype=float).reshape(-1, self.nstate)
        nstep = self.nstep if nstep is None else int(nstep)
        B = len(states0)
        if controller is not None:
            if control is not None:
                raise InputError("run: give control (open loop) or controller (closed loop), not both")
            if not (isinstance(chunk, int) and chunk >= 1):
                raise InputError(f"run: a controller needs chunk, a whole number of steps >= 1, got {chunk!r}")
            jobs = [(i, s) for i, s in enumerate(states0)]

            def one(job):
                return self._closed(job[0], job[1], nstep, controller, chunk, sensors)
        else:
            if control is not None:
                control = np.asarray(control, dtype=float)
                control = np.ascontiguousarray(np.broadcast_to(control, (B, nstep, self.nu)) if control.ndim == 1
                                               else control.reshape(B, nstep, self.nu))
            jobs = [(i, s) for i, s in enumerate(states0)]

            def one(job):
                fin, sd = self._open(job[1], nstep, None if control is None else control[job[0]], sensors)
                return fin, None, sd
        out = [one(j) for j in jobs] if self._pool is None else list(self._pool.map(one, jobs))
        final = np.array([o[0] for o in out]).reshape(B, self.nstate)
        ctrl = control if controller is None else np.array([o[1] for o in out]).reshape(B, nstep, self.nu)
        sd = np.array([o[2] for o in out]).reshape(B, nstep, self.model.nsensordata) if sensors else None
        return Rollouts(final=final, control=ctrl, sensordata=sd)

    def run_states(self, states0: np.ndarray) -> np.ndarray:
        """(B, nstate) initial states -> (B, nstate) final states (open loop, no controls)."""
        return self.run(states0).final
