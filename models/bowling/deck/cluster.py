"""Throw the deck half's deliveries on a Dask cluster (``nbst bowl solve|atlas --cluster ADDRESS``).

:class:`DeliveryClusterRunner` is the rollout room's :class:`~nbst.models.mjsearch.cluster.ClusterRunner`
with the deliveries of :mod:`.delivery`: each batch of initial states is cut into one
contiguous chunk per worker, each worker runs its chunk with a one-thread runner of its own
(built once per worker process from the same MjSpec scene, :func:`nbst.models.bowling.scene.build_model`,
so the model is the same), and the final states come back in order. Everything else (the
batches, the archive, the random numbers) stays in this process, so a run gives the same
throws as ``--jobs K`` for the same seed: a throw depends on its delivery only. The connection
goes through :func:`nbst.cluster.connect` (its timeout and one-line errors).

Start a cluster with ``dask scheduler`` and ``dask worker tcp://HOST:8786`` on each
machine (the same nbst and MuJoCo versions everywhere).
"""
from __future__ import annotations

from nbst.models.bowling import scene
from nbst.models.bowling.deck.delivery import DURATION, Deliveries
from nbst.models.mjsearch import cluster

__all__ = ["DeliveryClusterRunner"]


class DeliveryClusterRunner(Deliveries, cluster.ClusterRunner):
    """A deck runner whose rollouts run on the workers of a Dask ``client`` (or address)."""

    def __init__(self, client, *, duration: float = DURATION):
        cluster.ClusterRunner.__init__(self, client, scene.build_model, duration=duration)
