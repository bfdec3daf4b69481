"""Run bowling launches on a Dask cluster (``nbst bowl solve|atlas --cluster ADDRESS``).

:class:`ClusterLauncher` is a :class:`~.shot.Launcher` whose rollouts go out to the
cluster's workers: each batch of launch states is cut into one contiguous chunk per
worker, each worker runs its chunk with a one-thread :class:`~.shot.Launcher` of its own
(built once per worker process from the same MjSpec scene, so the model is the same),
and the final states come back in order. Everything else (the batches, the archive, the
random numbers) stays in this process, so a run gives the same shots as ``--jobs K``
for the same seed: a launch's outcome depends on its initial state only.

Start a cluster with ``dask scheduler`` and ``dask worker tcp://HOST:8786`` on each
machine (the same nbst and MuJoCo versions everywhere).
"""
from __future__ import annotations

import numpy as np

from nbst.cluster import connect

from nbst.models.bowling import shot

#: Per worker process: duration -> a one-thread Launcher (built on first use).
_WORKER_LAUNCHERS: dict = {}


def _run_chunk(states0: np.ndarray, duration: float) -> np.ndarray:
    """On a worker: final states of ``states0`` (B, nstate)."""
    L = _WORKER_LAUNCHERS.get(duration)
    if L is None:
        L = _WORKER_LAUNCHERS[duration] = shot.Launcher(jobs=1, duration=duration)
    return L.run_states(states0)


class ClusterLauncher(shot.Launcher):
    """A Launcher whose ``run_states`` runs on the workers of a Dask ``client`` (or address)."""

    def __init__(self, client, *, duration: float = shot.DURATION):
        super().__init__(jobs=1, duration=duration)
        self._own = isinstance(client, str)
        self.client = connect(client) if self._own else client
        # chunks per batch: the workers there at the start (asked once, not per batch; a worker
        # that joins later still takes chunks, as the scheduler hands them out)
        self.workers = max(1, len(self.client.scheduler_info().get("workers", {})))

    def run_states(self, states0: np.ndarray) -> np.ndarray:
        states0 = np.asarray(states0, dtype=float).reshape(-1, self.nstate)
        if not len(states0):
            return states0.copy()
        chunks = np.array_split(states0, min(self.workers, len(states0)))
        futures = self.client.map(_run_chunk, chunks, [self.duration] * len(chunks), pure=False)
        return np.concatenate(self.client.gather(futures)).reshape(len(states0), self.nstate)

    def close(self) -> None:
        super().close()
        if self._own and self.client is not None:
            self.client.close()
            self.client = None
