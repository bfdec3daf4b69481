"""How many cores this process may use (shared by the simulator's batches, the islands
of ``solve --jobs`` and the bowling rollouts: it lives here, below all of them)."""
from __future__ import annotations

import os


__all__ = ["JOBS_MAX", "default_jobs"]

#: The most threads or processes one command or call may ask for (each a full search or worker).
JOBS_MAX = 256


def default_jobs() -> int:
    """Every core this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not Linux
        return max(1, os.cpu_count() or 1)
