"""Rollouts on a Dask cluster: :class:`ClusterRunner` (``--cluster ADDRESS``).

A :class:`~.runner.Runner` whose :meth:`~.runner.Runner.run` sends the batch to the workers
of a Dask scheduler: the batch is cut into one contiguous chunk per worker, each worker runs
its chunk with a one-thread Runner of its own (built once per worker process from the
caller's ``factory``, a module-level function returning the compiled model, so the model is
the same), and the results come back in order. Everything else (the batches, the archive, the
random numbers) stays in the calling process, so a run gives the same bits as ``--jobs K``
for the same seed: a rollout depends on its initial state (and controls) only.

:func:`map_chunks` is the same cut for any function of a list (the crash's batch runner uses it).

The connection goes through :func:`nbst.cluster.connect` (the one place for ``--cluster``:
its timeout, its one-line errors). Start a cluster with ``dask scheduler`` and ``dask worker
tcp://HOST:8786`` on each machine (the same nbst and MuJoCo versions everywhere).
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from nbst.cluster import connect
from nbst.models.mjsearch.runner import Rollouts, Runner

__all__ = ["ClusterRunner", "map_chunks"]

#: Per worker process: (factory, nstep) -> a one-thread Runner (built on first use).
_WORKER_RUNNERS: dict = {}


class _Offset:
    """A controller seen from a chunk: rollout i of the chunk is rollout ``start + i`` of the batch."""

    def __init__(self, controller, start: int):
        self.controller, self.start = controller, start

    def __call__(self, i, step, data):
        return self.controller(self.start + i, step, data)


def _run_chunk(states0: np.ndarray, factory: Callable, nstep: int, kw: dict) -> Rollouts:
    """On a worker: the rollouts of ``states0`` (B, nstate)."""
    R = _WORKER_RUNNERS.get((factory, nstep))
    if R is None:
        R = _WORKER_RUNNERS[(factory, nstep)] = Runner(factory(), jobs=1, nstep=nstep)
    return R.run(states0, **kw)


class ClusterRunner(Runner):
    """A Runner whose rollouts run on the workers of a Dask ``client`` (or address).

    Args:
        client: a ``dask.distributed.Client``, or a scheduler address (connected here and
            closed by :meth:`close`; an InputError, one line, when it cannot be reached).
        factory: a picklable function returning the compiled model (called here and once per
            worker process).
        duration, nstep: as :class:`~.runner.Runner`.

    Returns:
        The runner; ``run`` sends each batch to the workers, ``close`` ends them.
    """

    def __init__(self, client, factory: Callable, *, duration: float | None = None, nstep: int | None = None):
        super().__init__(factory(), jobs=1, duration=duration, nstep=nstep)
        self.factory = factory
        self._own = isinstance(client, str)
        self.client = connect(client) if self._own else client
        # chunks per batch: the workers there at the start (asked once, not per batch; a worker
        # that joins later still takes chunks, as the scheduler hands them out)
        self.workers = max(1, len(self.client.scheduler_info().get("workers", {})))

    def run(self, states0, *, nstep: int | None = None, control=None, controller=None, chunk: int | None = None,
            sensors: bool = False) -> Rollouts:
        states0 = np.asarray(states0, dtype=float).reshape(-1, self.nstate)
        nstep = self.nstep if nstep is None else int(nstep)
        B = len(states0)
        if not B:
            return Rollouts(final=states0.copy())
        if control is not None:
            control = np.asarray(control, dtype=float)
            control = np.broadcast_to(control, (B, nstep, self.nu)) if control.ndim == 1 else \
                control.reshape(B, nstep, self.nu)
        parts = np.array_split(np.arange(B), min(self.workers, B))
        kws = [{"control": None if control is None else np.ascontiguousarray(control[p]),
                "controller": None if controller is None else _Offset(controller, int(p[0])),
                "chunk": chunk, "sensors": sensors} for p in parts]
        futures = self.client.map(_run_chunk, [states0[p] for p in parts], [self.factory] * len(parts),
                                  [nstep] * len(parts), kws, pure=False)
        got = self.client.gather(futures)
        final = np.concatenate([g.final for g in got]).reshape(B, self.nstate)
        ctrl = None if got[0].control is None else np.concatenate([g.control for g in got])
        sd = None if not sensors else np.concatenate([g.sensordata for g in got])
        return Rollouts(final=final, control=ctrl, sensordata=sd)

    def close(self) -> None:
        super().close()
        if self._own and self.client is not None:
            self.client.close()
            self.client = None


def map_chunks(client, fn: Callable, items, *args) -> list:
    """``fn(chunk, *args)`` on the workers of ``client``, ``items`` cut into one contiguous chunk
    per worker; the results' lists joined in the items' order. For runners that are not a
    :class:`~.runner.Runner` (e.g. the crash's batch runner): ``fn`` builds (and caches, per
    worker process) what it needs from ``args``, which must pickle."""
    items = list(items)
    if not items:
        return []
    workers = max(1, len(client.scheduler_info().get("workers", {})))
    parts = np.array_split(np.arange(len(items)), min(workers, len(items)))
    futures = client.map(fn, [[items[i] for i in p] for p in parts], *[[a] * len(parts) for a in args], pure=False)
    out: list = []
    for got in client.gather(futures):
        out += list(got)
    return out
