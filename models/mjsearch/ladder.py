"""The timestep ladder: does an outcome survive a finer step?

A rollout's outcome is only a result if the integrator did not make it: the same initial
state run at h, h/2 and h/4 (or any ladder) must give the same outcome. :func:`climb` runs
``run(h)`` at each timestep and reads each result's outcome; :class:`Ladder` says which
timesteps keep the outcome wanted (by default the first rung's) and whether all do.

Compute only: no files, no printing, no MuJoCo (the caller's ``run`` builds and steps).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable


__all__ = ["Ladder", "climb", "kept_text"]


@dataclass
class Ladder:
    """A timestep ladder's outcome.

    Args:
        timesteps: (s) each rung's timestep.
        outcomes: each rung's outcome.
        wanted: the wanted outcome.
        results: the raw results of ``run``.

    Returns:
        The ladder; ``holds`` says whether every rung gave the wanted outcome.
    """

    timesteps: list
    outcomes: list
    wanted: Any
    results: list = field(default_factory=list, repr=False)

    @property
    def kept(self) -> list:
        """The timesteps whose outcome is the wanted one."""
        return [h for h, o in zip(self.timesteps, self.outcomes) if o == self.wanted]

    @property
    def holds(self) -> bool:
        """Every timestep gives the wanted outcome."""
        return len(self.kept) == len(self.timesteps)


def climb(run: Callable[[float], Any], timesteps, *, outcome: Callable[[Any], Any] = lambda r: r,
          wanted: Any = None) -> Ladder:
    """Run ``run(h)`` for each ``h`` of ``timesteps`` (in order) and read ``outcome(result)``.

    Args:
        run: ``run(h) -> result``.
        timesteps: the rungs, seconds.
        outcome: ``outcome(result) -> outcome``.
        wanted: the wanted outcome; None: the first rung's.

    Returns:
        The :class:`Ladder`.
    """
    results = [run(float(h)) for h in timesteps]
    outs = [outcome(r) for r in results]
    return Ladder(timesteps=[float(h) for h in timesteps], outcomes=outs,
                  wanted=outs[0] if wanted is None and outs else wanted, results=results)


def kept_text(timesteps, kept, unit: float = 1e-3, name: str = "ms") -> str:
    """A one-line account of which timesteps keep an outcome: "kept at h = 1, 0.5 and 0.25 ms",
    "kept at h = 1 ms only; changes at 0.5 and 0.25 ms", "kept at no timestep (1, 0.5, 0.25 ms)"."""
    def fmt(hs):
        v = [f"{h / unit:g}" for h in hs]
        return v[0] if len(v) == 1 else ", ".join(v[:-1]) + " and " + v[-1]

    lost = [h for h in timesteps if h not in kept]
    if not kept:
        return f"kept at no timestep ({fmt(timesteps)} {name})"
    if not lost:
        return f"kept at h = {fmt(kept)} {name}"
    return f"kept at h = {fmt(kept)} {name} only; changes at {fmt(lost)} {name}"
