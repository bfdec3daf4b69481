"""The scene's rollouts on a Dask cluster (``nbst scene solve --cluster ADDRESS``): :class:`ClusterSceneSim`.

A :class:`~nbst.scene.rollout.SceneSim` whose :meth:`~ClusterSceneSim.run` sends each batch to the
workers of a Dask scheduler, cut into one contiguous chunk per worker
(``nbst.models.mjsearch.cluster.map_chunks``); each worker process compiles the scene once from
the fates (the scene's files must be at the same path there, with the same nbst and MuJoCo) and
rolls its chunk out with a one-thread SceneSim of its own. Everything else (the search, its random
numbers, the ladder's rollouts) stays in the calling process, so a seed gives the same solution as
with ``jobs`` threads: a rollout depends on its controls alone.

The connection goes through :func:`nbst.cluster.connect` (its timeout, its one-line errors).
"""
from __future__ import annotations

import hashlib
import pickle
from typing import Any

import numpy as np

from nbst.cluster import connect
from nbst.models.mjsearch.cluster import map_chunks
from nbst.scene.fates import Fates
from nbst.scene.rollout import SceneRollout, SceneSim, quiet_mujoco_warnings

__all__ = ["ClusterSceneSim"]

#: Per worker process: (the fates' digest, timestep, sequences) -> its SceneSim (built on first use).
_WORKER_SIMS: dict = {}


def _run_chunk(xs: list, fates: Fates, timestep: float, sequences: bool) -> list[SceneRollout]:
    """On a worker: the rollouts of the controls vectors ``xs``."""
    from nbst.scene.scenefile import compile_scene

    key = (hashlib.sha256(pickle.dumps(fates)).hexdigest(), float(timestep), bool(sequences))
    sim = _WORKER_SIMS.get(key)
    if sim is None:
        model = compile_scene(fates)
        model.opt.timestep = float(timestep)
        sim = _WORKER_SIMS[key] = SceneSim(fates, model, sequences=sequences)
    with quiet_mujoco_warnings():
        return sim.run(np.array(xs, dtype=float).reshape(-1, fates.dim))


class ClusterSceneSim(SceneSim):
    """A SceneSim whose batches run on the workers of a Dask ``client`` (module docstring).

    Args:
        fates: the checked fates.
        model: the compiled model (its timestep set; single rollouts run here).
        client: a ``dask.distributed.Client``, or a scheduler address (connected here and closed by
            :meth:`close`; an InputError, one line, when it cannot be reached).
        sequences: record contact sequences (as :class:`SceneSim`).

    Returns:
        The sim.
    """

    def __init__(self, fates: Fates, model: Any, client: Any, *, sequences: bool = False):
        super().__init__(fates, model, jobs=1, sequences=sequences)
        self._own = isinstance(client, str)
        self.client = connect(client) if self._own else client

    def run(self, xs: np.ndarray) -> list[SceneRollout]:
        """Roll out (B, D) controls vectors on the cluster's workers: B rollouts, in input order."""
        xs = np.asarray(xs, dtype=float).reshape(-1, self.fates.dim)
        return map_chunks(self.client, _run_chunk, list(xs), self.fates, float(self.model.opt.timestep),
                          self.sequences)

    def close(self) -> None:
        super().close()
        if self._own and self.client is not None:
            self.client.close()
            self.client = None
