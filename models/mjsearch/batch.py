"""Closed-loop rollouts of many simulations at once: :class:`BatchRunner` on a ``mujoco.batch.Batch``.

Where :class:`~.runner.Runner` calls a controller per rollout, this one steps a whole batch of
simulations together and calls the caller's **controller once per period for the whole batch**
(numpy over the batch: cheap in Python), and an **observer after every step** (contact sensors
read every step: impulses, first contacts). The controls a simulation received are recorded per
period (steps x actuators, run-length coded), so one plain ``mj_step`` loop replays it:

    for k, row in enumerate(controls[i]):
        data.ctrl[:] = row
        mujoco.mj_step(model, data, nstep=min(period, nstep - k * period))

gives the same final state, bit for bit, when the model disables warm-starting and sleeping (a
``Batch`` row carries the integration state between calls, so it equals one MjData stepping on;
its simulations are independent, so the thread count changes no bit: tests/test_mjsearch.py).

Compute only: no files, no printing. mujoco is imported when a BatchRunner is made.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from nbst.errors import InputError


__all__ = ["Views", "BatchRollouts", "BatchRunner"]


@dataclass
class Views:
    """The running batch as the controller and the observer see it: ``s`` simulations, their
    ``qpos`` (s, nq), ``qvel`` (s, nv) and ``sensordata`` (s, nsensordata) (live views: read,
    never write), the ``step`` just done (0 before the first) and the time ``t`` (s)."""

    s: int
    qpos: np.ndarray
    qvel: np.ndarray
    sensordata: np.ndarray
    step: int
    t: float


@dataclass
class BatchRollouts:
    """Controls applied (s, periods, nu), one row per period, and the final qpos (s, nq) and qvel."""

    controls: np.ndarray
    final_qpos: np.ndarray
    final_qvel: np.ndarray


class BatchRunner:
    """Runs batches of at most ``size`` simulations of ``model`` on ``jobs`` threads.

    Args:
        model: a compiled ``mujoco.MjModel``.
        jobs: threads.
        size: the most simulations in one batch.

    Returns:
        The runner; ``run`` simulates a batch.
    """

    def __init__(self, model, *, jobs: int = 1, size: int = 16):
        from mujoco import batch as mjbatch

        self.model = model
        self.size = int(size)
        self.jobs = max(1, int(jobs))
        self.batch = mjbatch.Batch(model, nsim=self.size, nthread=self.jobs)

    def run(self, qpos0: np.ndarray, qvel0: np.ndarray, nstep: int, *, period: int,
            controller: Callable[[Views], np.ndarray], observer: Callable[[Views], None] | None = None
            ) -> BatchRollouts:
        """Run ``len(qpos0)`` (<= size) simulations from (qpos0, qvel0) for ``nstep`` steps:
        ``controller(views) -> (s, nu)`` at steps 0, period, 2 period, ... (the controls hold in
        between); ``observer(views)`` after every step."""
        import mujoco

        B, m = self.batch, self.model
        s = len(qpos0)
        if s > self.size:
            raise InputError(f"run: {s} simulations; this runner holds {self.size}")
        ids = None if s == self.size else np.arange(s)
        B.reset(ids, stage=mujoco.mjtStage.mjSTAGE_NONE.value)
        qpos, qvel, ctrl, sensordata = B.qpos, B.qvel, B.ctrl, B.sensordata
        qpos[:s] = qpos0
        qvel[:s] = qvel0
        ctrl[:s] = 0.0
        periods = -(-int(nstep) // int(period))
        controls = np.zeros((s, periods, m.nu))
        dt = float(m.opt.timestep)
        v = Views(s=s, qpos=qpos[:s], qvel=qvel[:s], sensordata=sensordata[:s], step=0, t=0.0)
        for k in range(int(nstep)):
            if k % period == 0:
                v.step, v.t = k, k * dt
                u = np.asarray(controller(v), dtype=float).reshape(s, m.nu)
                ctrl[:s] = u
                controls[:, k // period] = u
            B.step(ids)
            if observer is not None:
                v.step, v.t = k + 1, (k + 1) * dt
                observer(v)
        return BatchRollouts(controls=controls, final_qpos=np.array(qpos[:s]), final_qvel=np.array(qvel[:s]))

    def close(self) -> None:
        self.batch = None
