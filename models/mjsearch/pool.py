"""Worker processes that die with their parent: :class:`WorkerPool`.

For rollouts that cannot go through ``mujoco.rollout`` (a loop of ``mj_step`` with checks
between steps holds the GIL in the Python bindings, so threads do not help), work goes to
``jobs`` processes. Each is started with the ``spawn`` method (numba's compiled state and
``fork`` do not mix), runs ``initializer(*initargs)`` once (build the model there), and
then the calls it is given. Results come back in input order, so a batch gives the same
results for any ``jobs`` when each call depends on its arguments only.

The workers leave Ctrl-C, SIGTERM and SIGHUP to the parent (no traceback per worker) and
die with it, even when it is killed by SIGKILL (:func:`nbst.outputs.die_with_parent`:
``PR_SET_PDEATHSIG`` on Linux, a ``getppid`` watchdog everywhere); the stop signals are
blocked while workers start, so none reaches a worker before it has set that up.

Compute only: no files, no printing.
"""
from __future__ import annotations

import os
from typing import Callable, Sequence

from nbst.outputs import die_with_parent, signals_blocked


__all__ = ["WorkerPool"]


def _init(parent_pid: int, initializer, initargs) -> None:
    """Worker setup: die with the parent, ignore the stop signals, then the caller's setup."""
    die_with_parent(parent_pid)
    if initializer is not None:
        initializer(*initargs)


class WorkerPool:
    """``jobs`` spawned processes, each set up by ``initializer(*initargs)``; :meth:`map` runs
    calls on them in input order.

    Args:
        jobs: processes.
        initializer: a module-level, picklable function, called once in each process.
        initargs: its arguments.

    Returns:
        The pool; ``close`` ends the processes.
    """

    def __init__(self, jobs: int, initializer: Callable | None = None, initargs: tuple = ()):
        self.jobs = max(1, int(jobs))
        self._init = (initializer, tuple(initargs))
        self._pool = None

    def _get(self):
        if self._pool is None:
            import multiprocessing as mp
            from concurrent.futures import ProcessPoolExecutor

            self._pool = ProcessPoolExecutor(max_workers=self.jobs, mp_context=mp.get_context("spawn"),
                                             initializer=_init, initargs=(os.getpid(), *self._init))
        return self._pool

    def map(self, fn: Callable, calls: Sequence[tuple], on_done: Callable[[], None] | None = None) -> list:
        """``[fn(*c) for c in calls]`` on the workers, in input order; ``on_done()`` after each
        result arrives (progress). An exception (or Ctrl-C) cancels the calls not started and
        propagates."""
        from concurrent.futures import as_completed

        pool = self._get()
        with signals_blocked():  # workers start on submit: no stop signal before they ignore it
            futs = {pool.submit(fn, *c): i for i, c in enumerate(calls)}
        out: list = [None] * len(futs)
        try:
            for f in as_completed(futs):
                out[futs[f]] = f.result()
                if on_done is not None:
                    on_done()
        except BaseException:
            for f in futs:
                f.cancel()
            raise
        return out

    def pids(self) -> list[int]:
        """The worker processes' ids (started so far)."""
        return [] if self._pool is None else [p.pid for p in getattr(self._pool, "_processes", {}).values()]

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
