"""Search for one signature: uniform exploration, then CMA-ES restarts from the nearest outcomes.

The paper's crossover needs several velocity vectors; a rollout search over a parameter
vector (a bowling launch, a set of driver intents) has one, so the **signature** of each
rollout guides the search instead. :func:`search` looks for a vector whose signature is
``target``:

1. **explore**: ``explore`` vectors drawn uniformly over the space (from the seeded
   Generator; capped at a quarter of the budget); every rollout enters an **archive keyed by
   signature** (the first vector that gave each one is kept).
2. **restarts**: CMA-ES (pycma) in the unit cube, started from the **elite** (the lowest-cost
   vector seen) of the signature **nearest** the target and not used yet, step size
   ``sigma0``. Nearest = lowest elite cost, then discovery order (a signature known only from
   a given archive ranks by ``prior(signature)``); when every signature has been a start, the
   cycle begins again. A restart ends after ``stall`` generations without a lower cost, and
   the next starts from the next-nearest, after ``explore_between`` more uniform vectors;
   each restart's sigma alternates between ``sigma0`` and a tenth of it (chaotic outcomes: a
   near miss is often a millimetre from a hit, or nowhere near).
3. stop at the first vector whose distance to the target is 0, or at the budget; Ctrl-C
   (KeyboardInterrupt) stops too, and the best so far is returned (``stopped``
   "interrupted").

The caller's ``evaluate(X) -> (signatures, distances, costs)`` runs a batch and scores it: the
distance is 0 exactly on the target (bowling: the Hamming distance between pin masks), the
cost orders rollouts (the distance plus a soft part that breaks ties).

Reproducible: batches have a fixed size, pycma gets a seed drawn from the Generator, and
nothing else touches numpy's global random state in between.

Compute only: no files, no printing.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from nbst.errors import SolveError
from nbst.models.mjsearch.archive import BATCH, Space

__all__ = ["EXPLORE_FIRST", "EXPLORE_BETWEEN", "POPSIZE", "SIGMA0", "STALL_GENERATIONS", "Progress", "Found",
           "Evaluator", "search"]

#: Uniform exploration before CMA-ES restarts (capped at a quarter of the budget).
EXPLORE_FIRST = 200
#: Uniform vectors after each restart (new signatures to restart from).
EXPLORE_BETWEEN = 16
#: CMA-ES: population, initial step (unit cube), generations without progress per restart.
POPSIZE = 8
SIGMA0 = 0.05
STALL_GENERATIONS = 6


@dataclass
class Progress:
    """What a search reports after each batch (to a progress bar)."""

    rollouts: int
    best_distance: int
    best_signature: int
    signatures: int


@dataclass
class Found:
    """The best vector for ``target`` and how the search went."""

    target: int
    x: np.ndarray
    signature: int
    distance: int
    cost: float
    rollouts: int
    restarts: int
    stopped: str                 # "found" | "budget" | "interrupted"
    seed: int
    wall_time: float
    archive: dict = field(default_factory=dict)   # signature -> the first vector that gave it


class Evaluator:
    """Runs vectors in batches, keeps the archive and the best vector for a target."""

    def __init__(self, evaluate: Callable, target: int, *, max_rollouts: int, callback=None,
                 clip: Callable | None = None, prior: Callable | None = None, batch: int = BATCH):
        self.evaluate, self.target = evaluate, int(target)
        self.max_rollouts = int(max_rollouts)
        self.callback, self.clip, self.prior, self.batch = callback, clip, prior, int(batch)
        self.rollouts = 0
        self.archive: dict[int, np.ndarray] = {}   # signature -> first vector that gave it
        self.order: dict[int, int] = {}   # signature -> discovery index (tie-break)
        self.elite: dict[int, tuple] = {}  # signature -> (cost, vector): the best of each for this target
        self.best: Any = None             # (cost, distance, signature, vector)

    @property
    def left(self) -> int:
        return self.max_rollouts - self.rollouts

    @property
    def found(self) -> bool:
        return self.best is not None and self.best[1] == 0

    def know(self, archive: dict) -> None:
        """Signatures known before the search ({signature: vector}), in discovery order."""
        for m, x in archive.items():
            self.archive[int(m)] = np.asarray(x, dtype=float)
            self.order[int(m)] = len(self.order)

    def __call__(self, X: np.ndarray) -> np.ndarray:
        """(B, D) vectors -> (B,) costs; stops early (returns what ran) at the budget or a hit."""
        X = np.atleast_2d(X)
        X = (self.clip(X) if self.clip is not None else X)[: max(0, self.left)]
        costs = []
        for i in range(0, len(X), self.batch):
            chunk = X[i:i + self.batch]
            sigs, dist, cost = self.evaluate(chunk)
            for x, m, h, c in zip(chunk, sigs, dist, cost):
                m = int(m)
                if m not in self.archive:
                    self.archive[m] = x.copy()
                    self.order[m] = len(self.order)
                if m not in self.elite or c < self.elite[m][0]:
                    self.elite[m] = (float(c), x.copy())
                if self.best is None or c < self.best[0]:
                    self.best = (float(c), int(h), m, x.copy())
            self.rollouts += len(chunk)
            costs.extend(np.asarray(cost).tolist())
            if self.callback:
                self.callback(Progress(self.rollouts, self.best[1], self.best[2], len(self.archive)))
            if self.found:
                break
        return np.array(costs)

    def nearest(self, exclude) -> list[int]:
        """Archived signatures, nearest the target first, without ``exclude``: by the cost of their
        elite, then discovery order; those known only from a given archive by ``prior``."""
        ms = [m for m in self.archive if m not in exclude]

        def key(m):
            c = self.elite[m][0] if m in self.elite else (float(self.prior(m)) if self.prior else math.inf)
            return (c, self.order[m])
        return sorted(ms, key=key)

    def start(self, sig: int) -> np.ndarray:
        """The vector a restart from ``sig`` begins at: its elite, else its archived vector."""
        return self.elite[sig][1] if sig in self.elite else self.archive[sig]


def search(evaluate: Callable, space: Space, target: int, *, seed: int, max_rollouts: int, archive: dict | None = None,
           prior: Callable | None = None, clip: Callable | None = None, callback=None, explore: int = EXPLORE_FIRST,
           explore_between: int = EXPLORE_BETWEEN, batch: int = BATCH, popsize: int = POPSIZE,
           sigma0: float = SIGMA0, stall: int = STALL_GENERATIONS) -> Found:
    """A vector whose signature is ``target``; see the module docstring.

    Args:
        evaluate: ``(B, D) -> (signatures (B,), distances (B,) int, costs (B,))``.
        space: the parameter space (the restarts work in its unit cube).
        target: the signature wanted.
        seed: seeds the Generator (exploration, CMA-ES seeds).
        max_rollouts: the budget.
        archive: signatures known before ({signature: vector}): restart points; a known
            target is confirmed with one rollout.
        prior: the cost of a signature known only from ``archive`` (ranks restarts).
        clip: applied to every batch before it runs (the space's limits).
        callback: ``callback(Progress)`` after each batch.

    Returns:
        :class:`Found`.
    """
    import cma

    rng = np.random.default_rng(seed)
    ev = Evaluator(evaluate, target, max_rollouts=max_rollouts, callback=callback, clip=clip, prior=prior,
                   batch=batch)
    ev.know(archive or {})
    t0 = time.perf_counter()
    if int(target) in ev.archive:  # known already: one rollout confirms it and makes it the best
        ev(ev.archive[int(target)][None, :])
    restarts = 0
    stopped = "budget"
    try:
        n0 = min(int(explore), max_rollouts // 4 if ev.archive else max(1, max_rollouts // 4))
        if not ev.found:
            ev(space.from_unit(rng.random((n0, space.dim))))
        used: set[int] = set()
        while not ev.found and ev.left > 0:
            order = ev.nearest(used)
            if not order and not ev.archive:  # nothing to start from: explore a little
                ev(space.from_unit(rng.random((popsize, space.dim))))
                continue
            if not order:
                used.clear()
                order = ev.nearest(used)
            start = order[0]
            used.add(start)
            sigma = sigma0 if restarts % 2 == 0 else sigma0 / 10
            restarts += 1
            es = cma.CMAEvolutionStrategy(space.to_unit(ev.start(start)).tolist(), sigma,
                                          {"bounds": [0.0, 1.0], "popsize": popsize, "verbose": -9,
                                           "seed": int(rng.integers(1, 2**31 - 1))})
            best_here, stalled = math.inf, 0
            while not ev.found and ev.left > 0 and stalled < stall:
                xs = es.ask()
                costs = ev(space.from_unit(np.array(xs)))
                if len(costs) < len(xs):
                    break
                es.tell(xs, costs.tolist())
                if costs.min() < best_here - 1e-12:
                    best_here, stalled = float(costs.min()), 0
                else:
                    stalled += 1
            if not ev.found and ev.left > 0 and explore_between:
                ev(space.from_unit(rng.random((explore_between, space.dim))))  # keep exploring: rare ones are found so
        if ev.found:
            stopped = "found"
    except KeyboardInterrupt:
        stopped = "interrupted"
    if ev.best is None:
        if stopped == "interrupted":
            raise KeyboardInterrupt
        raise SolveError("max_rollouts must allow at least one rollout")
    cost, dist, sig, x = ev.best
    return Found(target=int(target), x=x, signature=sig, distance=dist, cost=cost, rollouts=ev.rollouts,
                 restarts=restarts, stopped=stopped, seed=int(seed), wall_time=time.perf_counter() - t0,
                 archive=dict(ev.archive))
