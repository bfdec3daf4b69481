"""Closed-loop crash rollouts: a batch of simulations of one script, drivers in the loop.

:class:`Runner` compiles the script's scene from its XML text (:mod:`.scene`; the model every
rollout and replay runs on), and runs batches of driver intents (:mod:`.driver`) on a
``mujoco.batch.Batch`` of ``jobs`` threads. Each step is one ``Batch.step()`` for the whole
batch, after which the contact sensors are read (:class:`.outcome.Recorder`); every
:data:`.driver.PERIOD` the drivers of the whole batch set the controls, which then hold. The
controls each simulation received (its realised controls: one row per period, steps x
actuators in run-length form) are kept, so that a plain ``mj_step`` loop replays the rollout
bit for bit (warm-starting is off and the Batch's simulations are independent, so the thread
count changes nothing: tests/test_crash_run.py).

Compute only.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from nbst.models.crash import driver as drv
from nbst.models.crash import outcome as out_mod
from nbst.models.crash import scene as scene_mod
from nbst.models.crash.script import Script

#: Simulations per batch: a fixed number, so that a search's path does not depend on --jobs.
BATCH = 16


def scene_vehicles(script: Script) -> list[scene_mod.SceneVehicle]:
    return [scene_mod.SceneVehicle(scene_mod.vehicle_prefix(i), v.vtype, v.x, v.y, v.heading)
            for i, v in enumerate(script.vehicles)]


def scene_text(script: Script) -> str:
    """The script's scene as MJCF text (the model every rollout runs on)."""
    spec = scene_mod.build_spec(script.road, scene_vehicles(script), timestep=script.timestep, name=script.name)
    return scene_mod.scene_xml(spec)


@dataclass
class Rollouts:
    """A batch's results: outcomes (judged), the closest approach per pair (s, pairs), the initial
    states, the realised controls (s, periods, nu) and the final qpos (s, nq)."""

    outcomes: list
    min_dist: np.ndarray
    qpos0: np.ndarray
    qvel0: np.ndarray
    controls: np.ndarray
    final_qpos: np.ndarray


class Runner:
    """Runs batches of intents for ``script`` (see the module docstring); ``timestep`` overrides
    the script's (the ladder), ``xml`` reuses a scene text (a result file's)."""

    def __init__(self, script: Script, *, jobs: int = 1, timestep: float | None = None, xml: str | None = None,
                 batch: int = BATCH):
        from mujoco import batch as mjbatch

        self.script = script
        self.xml = scene_text(script) if xml is None else xml
        self.model = scene_mod.model_from_xml(self.xml)
        if timestep is not None:
            self.model.opt.timestep = float(timestep)
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
        self.batch = mjbatch.Batch(self.model, nsim=self.size, nthread=self.jobs)
        self.names = script.names()

    def initial(self, intents: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(qpos (s, nq), qvel (s, nv)) of each intent's start (the intent's speed)."""
        q, v = [], []
        for row in intents:
            a, b = scene_mod.initial_state(self.model, self.vehicles, row[:, drv.IX["speed"]])
            q.append(a)
            v.append(b)
        return np.array(q), np.array(v)

    def run(self, intents: np.ndarray) -> Rollouts:
        """Run intents (s, n, len(INTENT)) in batches of ``batch``; results in order."""
        intents = np.asarray(intents, dtype=float).reshape(-1, self.script.n, len(drv.INTENT))
        parts = [self._batch(intents[k:k + self.size]) for k in range(0, len(intents), self.size)]
        return Rollouts(outcomes=[o for p in parts for o in p.outcomes],
                        min_dist=np.concatenate([p.min_dist for p in parts]),
                        qpos0=np.concatenate([p.qpos0 for p in parts]), qvel0=np.concatenate([p.qvel0 for p in parts]),
                        controls=np.concatenate([p.controls for p in parts]),
                        final_qpos=np.concatenate([p.final_qpos for p in parts]))

    def _batch(self, intents: np.ndarray) -> Rollouts:
        import mujoco

        B, L, m = self.batch, self.L, self.model
        s = len(intents)
        ids = None if s == self.size else np.arange(s)
        qpos0, qvel0 = self.initial(intents)
        B.reset(ids, stage=mujoco.mjtStage.mjSTAGE_NONE.value)
        qpos, qvel, ctrl, sensordata = B.qpos, B.qvel, B.ctrl, B.sensordata
        qpos[:s] = qpos0
        qvel[:s] = qvel0
        ctrl[:s] = 0.0
        rec = out_mod.Recorder(L, s, self.dt)
        rec.begin(qpos[:s])
        state = drv.DriverState.start(s, L.n, self.periods)
        controls = np.zeros((s, self.periods, m.nu))
        touched = np.zeros((s, L.n), bool)
        vi = L.qvel[:, None] + np.arange(2)
        for k in range(self.nstep):
            if k % self.period == 0:
                p = k // self.period
                u = drv.controls(k * self.dt, self.fleet, intents, state, qpos[:s][:, L.qpos[:, None] + np.arange(3)],
                                 qpos[:s][:, L.qpos[:, None] + np.arange(3, 7)], qvel[:s][:, L.qvel[:, None] + np.arange(3)],
                                 qvel[:s][:, L.spin[:, 2:4]], touched)
                row = np.zeros((s, m.nu))
                row[:, L.ctrl] = u
                ctrl[:s] = row
                controls[:, p] = row
                touched[:] = False
                if p:
                    rec.period(qpos[:s])
            speed = np.hypot(*np.moveaxis(qvel[:s][:, vi], -1, 0))
            B.step(ids)
            touched |= rec.step((k + 1) * self.dt, sensordata[:s], speed)
        rec.finish(qpos[:s], qvel[:s])
        outs = out_mod.outcomes(rec, self.names, L.mass)
        for o, md in zip(outs, rec.min_dist):
            out_mod.judge(o, self.script, md)
        bad = [i for i in range(s) if not np.isfinite(qpos[i]).all()]
        if bad:
            from nbst.errors import MujocoError

            raise MujocoError(f"the simulation diverged (non-finite state) in {len(bad)} of {s} rollouts")
        return Rollouts(outcomes=outs, min_dist=rec.min_dist.copy(), qpos0=qpos0, qvel0=qvel0, controls=controls,
                        final_qpos=np.array(qpos[:s]))

    def close(self) -> None:
        self.batch = None
