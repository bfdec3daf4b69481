"""Connecting to a Dask scheduler: the one place for ``--cluster ADDRESS``
(``nbst experiment``, ``nbst solve``, ``nbst bowl solve|atlas``)."""
from __future__ import annotations


def connect(address: str, *, timeout: str = "20s"):
    """A ``dask.distributed.Client`` for ``address``; ValueError (one line) if unreachable."""
    try:
        from dask.distributed import Client

        return Client(address, timeout=timeout)
    except (OSError, TimeoutError, ValueError) as e:
        raise ValueError(f"cannot reach a Dask scheduler at {address!r} ({e}); start one with `dask scheduler` "
                         f"and workers with `dask worker ADDRESS`") from None
