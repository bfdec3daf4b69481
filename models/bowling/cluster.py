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

from . import shot

#: Per worker process: duration -> a one-thread Launcher (built on first use).
_WORKER_LAUNCHERS: dict = {}


def _run_chunk(states0: np.ndarray, duration: float) -> np.ndarray:
    """On a worker: final states of ``states0`` (B, nstate)."""
    L = _WORKER_LAUNCHERS.get(duration)
    if L is None:
        L = _WORKER_LAUNCHERS[duration] = shot.Launcher(jobs=1, duration=duration)
    return L.run_states(states0)


def connect(address: str, *, timeout: str = "20s"):
    """A ``dask.distributed.Client`` for ``address``; ValueError (one line) if unreachable."""
    try:
        from dask.distributed import Client

        return Client(address, timeout=timeout)
    except (OSError, TimeoutError, ValueError) as e:
        raise ValueError(f"cannot reach a Dask scheduler at {address!r} ({e}); start one with `dask scheduler` "
                         f"and workers with `dask worker ADDRESS`") from None


class ClusterLauncher(shot.Launcher):
    """A Launcher whose ``run_states`` runs on the workers of a Dask ``client`` (or address)."""

    def __init__(self, client, *, duration: float = shot.DURATION):
        super().__init__(jobs=1, duration=duration)
        self._own = isinstance(client, str)
        self.client = connect(client) if self._own else client

    def workers(self) -> int:
        return max(1, len(self.client.scheduler_info().get("workers", {})))

    def run_states(self, states0: np.ndarray) -> np.ndarray:
        states0 = np.asarray(states0, dtype=float).reshape(-1, self.nstate)
        if not len(states0):
            return states0.copy()
        chunks = [c for c in np.array_split(states0, min(self.workers(), len(states0))) if len(c)]
        futures = self.client.map(_run_chunk, chunks, [self.duration] * len(chunks), pure=False)
        out = np.concatenate(self.client.gather(futures)).reshape(len(states0), self.nstate)
        return out

    def close(self) -> None:
        super().close()
        if self._own and self.client is not None:
            self.client.close()
            self.client = None
