"""Closed-loop crash rollouts: a batch of simulations of one script, drivers in the loop.

:class:`CrashRunner` compiles the script's scene from its XML text (:mod:`.scene`; the model every
rollout and replay runs on), and runs batches of driver intents (:mod:`.driver`) on a
``mujoco.batch.Batch`` of ``jobs`` threads. Each step is one ``Batch.step()`` for the whole
batch, after which the contact sensors are read (:class:`.outcome.Recorder`); every
:data:`.driver.PERIOD` the drivers of the whole batch set the controls, which then hold. The
controls each simulation received (its realised controls: one row per period, steps x
actuators in run-length form) are kept, so that a plain ``mj_step`` loop replays the rollout
bit for bit (warm-starting is off and the Batch's simulations are independent, so the thread
count changes nothing: tests/test_crash_run.py). The stepping itself is the rollout room's
(:class:`nbst.models.mjsearch.batch.BatchRunner`); this module gives it the drivers (its
controller) and the outcome recorder (its observer).

Compute only.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from nbst.cluster import connect
from nbst.errors import MujocoError
from nbst.models.crash import driver as drv
from nbst.models.crash import outcome as out_mod
from nbst.models.crash import scene as scene_mod
from nbst.models.crash.script import Script, script_from_dict
from nbst.models.mjsearch.batch import BatchRunner
from nbst.models.mjsearch.cluster import map_chunks

__all__ = ["BATCH", "TIMESTEP_LADDER", "scene_vehicles", "scene_text", "CrashRollouts", "CrashRunner",
           "CrashClusterRunner"]

#: Simulations per batch: a fixed number, so that a search's path does not depend on --jobs.
BATCH = 16
#: The timestep ladder (s): the crash's 2 ms, then halved twice. A crash is a result when its
#: outcome holds at every rung (:func:`.robust.ladder`); the search checks the finer rungs
#: (:data:`.search.LADDER_CHECK_TIMESTEPS`).
TIMESTEP_LADDER = (0.002, 0.001, 0.0005)


def scene_vehicles(script: Script) -> list[scene_mod.SceneVehicle]:
    return [scene_mod.SceneVehicle(scene_mod.vehicle_prefix(i), v.vtype, v.x, v.y, v.heading)
            for i, v in enumerate(script.vehicles)]


def scene_text(script: Script) -> str:
    """The script's scene as MJCF text (the model every rollout runs on)."""
    spec = scene_mod.build_spec(script.road, scene_vehicles(script), timestep=script.timestep, name=script.name)
    return scene_mod.scene_xml(spec)


@dataclass
class CrashRollouts:
    """A batch's results: outcomes (judged), the closest approach per pair (s, pairs), the initial
    states, the realised controls (s, periods, nu) and the final qpos (s, nq)."""

    outcomes: list
    min_dist: np.ndarray
    qpos0: np.ndarray
    qvel0: np.ndarray
    controls: np.ndarray
    final_qpos: np.ndarray


class CrashRunner:
    """Runs batches of intents for ``script`` (see the module docstring); ``timestep`` overrides
    the script's (the ladder), ``xml`` reuses a scene text (a result file's), ``edit`` changes
    the compiled model before the batch is made from it (a parameter's sensitivity: the batch
    copies the model when made, so a change made to ``model`` after that reaches no rollout)."""

    def __init__(self, script: Script, *, jobs: int = 1, timestep: float | None = None, xml: str | None = None,
                 batch: int = BATCH, edit: Callable | None = None):
        self.script = script
        self.xml = scene_text(script) if xml is None else xml
        self.model = scene_mod.model_from_xml(self.xml)
        if timestep is not None:
            self.model.opt.timestep = float(timestep)
        if edit is not None:
            edit(self.model)
        self.dt = float(self.model.opt.timestep)
        self.vehicles = scene_vehicles(script)
        self.L = scene_mod.layout(self.model, script.n)
        self.fleet = drv.Fleet.of([v.vtype for v in script.vehicles], [v.driver.waypoints for v in script.vehicles],
                                  [-1 if v.driver.follow is None else v.driver.follow for v in script.vehicles])
        self.nstep = int(round(script.duration / self.dt))
        self.period = max(1, int(round(drv.PERIOD / self.dt)))
        self.periods = -(-self.nstep // self.period)
        self.jobs = max(1, int(jobs))
        self.size = int(batch)
        self.stepper = BatchRunner(self.model, jobs=self.jobs, size=self.size)
        self.names = script.names()

    def initial(self, intents: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(qpos (s, nq), qvel (s, nv)) of each intent's start (the intent's speed)."""
        q, v = [], []
        for row in intents:
            a, b = scene_mod.initial_state(self.model, self.vehicles, row[:, drv.IX["speed"]])
            q.append(a)
            v.append(b)
        return np.array(q), np.array(v)

    def run(self, intents: np.ndarray) -> CrashRollouts:
        """Run intents (s, n, len(INTENT)) in batches of ``batch``; results in order."""
        intents = np.asarray(intents, dtype=float).reshape(-1, self.script.n, len(drv.INTENT))
        parts = [self._batch(intents[k:k + self.size]) for k in range(0, len(intents), self.size)]
        return CrashRollouts(outcomes=[o for p in parts for o in p.outcomes],
                             min_dist=np.concatenate([p.min_dist for p in parts]),
                             qpos0=np.concatenate([p.qpos0 for p in parts]),
                             qvel0=np.concatenate([p.qvel0 for p in parts]),
                             controls=np.concatenate([p.controls for p in parts]),
                             final_qpos=np.concatenate([p.final_qpos for p in parts]))

    def _batch(self, intents: np.ndarray) -> CrashRollouts:
        L, m = self.L, self.model
        s = len(intents)
        qpos0, qvel0 = self.initial(intents)
        rec = out_mod.Recorder(L, s, self.dt)
        rec.begin(qpos0)
        state = drv.DriverState.start(s, L.n, self.periods)
        touched = np.zeros((s, L.n), bool)
        vi = L.qvel[:, None] + np.arange(2)
        pi, qi, vel = L.qpos[:, None] + np.arange(3), L.qpos[:, None] + np.arange(3, 7), L.qvel[:, None] + np.arange(3)
        pxy = L.qpos[:, None] + np.arange(2)
        vel0 = [qvel0[:, vi], qpos0[:, pxy]]

        def controller(v):
            u = drv.controls(v.t, self.fleet, intents, state, v.qpos[:, pi], v.qpos[:, qi], v.qvel[:, vel],
                             v.qvel[:, L.spin[:, 2:4]], touched)
            row = np.zeros((s, m.nu))
            row[:, L.ctrl] = u
            touched[:] = False
            if v.step:
                rec.period(v.qpos)
            return row

        def observer(v):
            touched[:] |= rec.step(v.t, v.sensordata, vel0[0], vel0[1])
            vel0[0], vel0[1] = v.qvel[:, vi], v.qpos[:, pxy]  # copies (fancy indexing): the state before the next step

        out = self.stepper.run(qpos0, qvel0, self.nstep, period=self.period, controller=controller, observer=observer)
        if not np.isfinite(out.final_qpos).all():
            bad = int((~np.isfinite(out.final_qpos).all(axis=1)).sum())
            raise MujocoError(f"the simulation diverged (non-finite state) in {bad} of {s} rollouts")
        rec.finish(out.final_qpos, out.final_qvel)
        outs = out_mod.outcomes(rec, self.names, L.mass)
        for o, md in zip(outs, rec.min_dist):
            out_mod.judge(o, self.script, md)
        return CrashRollouts(outcomes=outs, min_dist=rec.min_dist.copy(), qpos0=qpos0, qvel0=qvel0,
                             controls=out.controls, final_qpos=out.final_qpos)

    def close(self) -> None:
        self.stepper.close()


#: Per worker process: (scene text, timestep) -> a one-thread CrashRunner of the script (built on first use).
_WORKER_RUNNERS: dict = {}


def _run_on_worker(intents: list, raw: dict, xml: str, timestep: float) -> list:
    """On a Dask worker: the rollouts of ``intents`` (a list of (n, len(INTENT)) arrays), as
    per-rollout tuples (outcome, min_dist, qpos0, qvel0, controls, final_qpos)."""
    key = (xml, timestep)
    R = _WORKER_RUNNERS.get(key)
    if R is None:
        R = _WORKER_RUNNERS[key] = CrashRunner(script_from_dict(raw), jobs=1, xml=xml, timestep=timestep)
    r = R.run(np.array(intents))
    return list(zip(r.outcomes, r.min_dist, r.qpos0, r.qvel0, r.controls, r.final_qpos))


class CrashClusterRunner(CrashRunner):
    """A :class:`CrashRunner` whose batches run on the workers of a Dask scheduler (``--cluster``):
    each batch is cut into one chunk per worker (:func:`nbst.models.mjsearch.cluster.map_chunks`),
    every worker runs its chunk with a one-thread CrashRunner of the same scene text, and the results
    come back in order: the same bits as ``--jobs K`` (a rollout depends on its intents only)."""

    def __init__(self, script: Script, address: str, **kw):
        super().__init__(script, jobs=1, **kw)
        self.client = connect(address)

    def _batch(self, intents: np.ndarray) -> CrashRollouts:
        got = map_chunks(self.client, _run_on_worker, list(intents), self.script.raw, self.xml, self.dt)
        o, md, q0, v0, c, q = zip(*got)
        return CrashRollouts(outcomes=list(o), min_dist=np.array(md), qpos0=np.array(q0), qvel0=np.array(v0),
                             controls=np.array(c), final_qpos=np.array(q))

    def close(self) -> None:
        super().close()
        if self.client is not None:
            self.client.close()
            self.client = None
