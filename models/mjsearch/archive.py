"""An archive of outcomes keyed by signature, and the MAP-Elites emitter that grows it.

A rollout's **signature** is a small integer naming its outcome (bowling: the 10-bit mask of
the pins down; a crash: one bit per vehicle whose fates hold, or a code of the contact
sequence). The search lives in a **space** of parameter vectors (:class:`Space`: its
dimension, the maps to and from the unit cube, and the Gaussian step sizes of a child).

* :class:`Archive`: the first parameter vector that gave each signature is its **elite**;
  how often each signature was seen, when it was found, how many children each elite had
  and how many of them found a new signature, and the growth curve.
* :func:`parent_weights`: the emitter's bias. w = group gap x rarity x curiosity: group gap =
  the share of a signature's group not found yet (bowling: signatures with as many pins
  down; at least ``floor``), rarity = 1 / sqrt(times seen), curiosity = (1 + ``bonus`` x new
  signatures its children found) / sqrt(1 + children). Without groups the gap is 1.
* :func:`emit`: one batch: ``uniform`` uniform vectors, then children of elites drawn with
  those weights (or uniformly: plain MAP-Elites), each moved by a Gaussian step in the unit
  cube at one of the space's scales, drawn per child.
* :func:`grow`: spend a budget of rollouts: ``explore`` uniform vectors into an empty
  archive, then emitter batches; ``evaluate(X) -> signatures`` runs a batch.

Reproducible: every random number comes from the caller's ``np.random.Generator`` in a fixed
order (the uniform block is drawn even when unused, so the stream does not depend on the
archive), and batches have a fixed size.

Compute only: no files, no printing, no MuJoCo.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

__all__ = ["BATCH", "EXPLORE_EMPTY", "UNIFORM_PER_BATCH", "GROUP_FLOOR", "HIT_BONUS", "Space", "box_space", "Archive",
           "parent_weights", "emit", "grow"]

#: Vectors per batch (fixed, so that results do not depend on the threads that run them).
BATCH = 16
#: Uniform vectors that start an empty archive before the emitter takes over.
EXPLORE_EMPTY = 256
#: Uniform vectors in each emitter batch (keeps finding what no elite is near).
UNIFORM_PER_BATCH = 2
#: Parent weight floor of a group whose signatures are all found (children land in other groups).
GROUP_FLOOR = 0.05
#: Parent weight bonus per new signature its children found.
HIT_BONUS = 3.0


@dataclass(frozen=True)
class Space:
    """A parameter space, mapped to and from the unit cube.

    Args:
        dim: its coordinates, D.
        to_unit: (n, D) vectors -> (n, D) unit-cube coordinates.
        from_unit: (n, D) unit-cube coordinates -> (n, D) vectors, clipped into the space's limits.
        scales: (k,) float64 array: the standard deviations (in the unit cube, per coordinate) of
            a child's Gaussian step, one drawn per child.

    Returns:
        The space.
    """

    dim: int
    to_unit: Callable
    from_unit: Callable
    scales: tuple


def box_space(lo, hi, scales) -> Space:
    """The box [lo, hi] (per coordinate) as a :class:`Space`: unit = (x - lo) / (hi - lo).

    Args:
        lo, hi: (D,) float64 arrays: the box's corners.
        scales: the Gaussian steps' standard deviations in the unit cube.

    Returns:
        The :class:`Space`.
    """
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)

    def to_unit(x):
        return (np.asarray(x, dtype=float) - lo) / (hi - lo)

    def from_unit(u):
        return np.clip(lo + np.clip(np.asarray(u, dtype=float), 0.0, 1.0) * (hi - lo), lo, hi)

    return Space(len(lo), to_unit, from_unit, tuple(scales))


@dataclass
class Archive:
    """Signatures found so far: signature -> elite vector, how often seen, when found, and for
    the emitter how many children each parent had and how many found a new signature.

    Args:
        elite: signature -> (D,) float64 array, the first vector that gave it.
        seen: signature -> how many vectors gave it.
        found_at: signature -> rollouts spent when it was found (-1: given).
        children: signature -> children launched from its elite.
        hits: signature -> children of it that found a new signature.
        rollouts: rollouts run so far.
        uniform: [vectors, new signatures] of the parentless (uniform) ones.
        curve: (rollouts, signatures found) after each batch.

    Returns:
        The archive (empty by default; :meth:`from_elites` builds one).
    """

    elite: dict = field(default_factory=dict)     # signature -> (D,) vector (the first that gave it)
    seen: dict = field(default_factory=dict)      # signature -> vectors that gave it
    found_at: dict = field(default_factory=dict)  # signature -> rollouts spent when found (-1: given)
    children: dict = field(default_factory=dict)  # signature -> children launched from its elite
    hits: dict = field(default_factory=dict)      # signature -> children that found a new signature
    rollouts: int = 0
    uniform: list = field(default_factory=lambda: [0, 0])   # [vectors, new signatures] of parentless ones
    curve: list = field(default_factory=list)     # (rollouts, signatures) after each batch

    @classmethod
    def from_elites(cls, elites: dict) -> Archive:
        """An archive holding ``elites`` ({signature: vector}; signature 0 skipped), found before."""
        a = cls()
        for m in sorted(elites):
            if m:
                a.elite[int(m)] = np.asarray(elites[m], dtype=float)
                a.seen[int(m)] = 1
                a.found_at[int(m)] = -1
        return a

    def __len__(self) -> int:
        return len(self.elite)

    def add(self, vectors, signatures, parents=None) -> list[int]:
        """Record a batch: (B, D) vectors, (B,) signatures, (B,) parent signatures (-1: none).
        Signature 0 (nothing happened) is counted, never archived. Returns the new signatures,
        in batch order."""
        new = []
        for i, (x, m) in enumerate(zip(vectors, signatures)):
            m = int(m)
            p = -1 if parents is None else int(parents[i])
            if p >= 0:
                self.children[p] = self.children.get(p, 0) + 1
            else:
                self.uniform[0] += 1
            if m == 0:
                continue
            self.seen[m] = self.seen.get(m, 0) + 1
            if m not in self.elite:
                self.elite[m] = np.array(x, dtype=float)
                self.found_at[m] = self.rollouts + i + 1
                new.append(m)
                if p >= 0:
                    self.hits[p] = self.hits.get(p, 0) + 1
                else:
                    self.uniform[1] += 1
        self.rollouts += len(signatures)
        self.curve.append((self.rollouts, len(self.elite)))
        return new


def parent_weights(a: Archive, keys: list, *, group: Callable | None = None, group_total=None,
                   floor: float = GROUP_FLOOR, bonus: float = HIT_BONUS) -> np.ndarray:
    """(P,) selection weights of the archived signatures ``keys`` (sum 1); see the module
    docstring. ``group(signature) -> int`` and ``group_total`` ((G,) signatures per group)
    give the group gap; without them it is 1."""
    if group is None:
        gap = None
    else:
        total = np.asarray(group_total)
        found = np.bincount([group(m) for m in a.elite], minlength=len(total))
        gap = np.maximum(1.0 - found / total, floor)
    w = np.array([(1.0 if gap is None or group is None else gap[group(m)]) / math.sqrt(a.seen.get(m, 1))
                  * (1.0 + bonus * a.hits.get(m, 0)) / math.sqrt(1.0 + a.children.get(m, 0))
                  for m in keys])
    return w / w.sum()


def emit(a: Archive, rng: np.random.Generator, space: Space, n: int = BATCH, *, selection: str = "biased",
         weights: Callable | None = None, uniform: int = UNIFORM_PER_BATCH) -> tuple[np.ndarray, np.ndarray]:
    """One emitter batch. The first ``uniform`` are uniform (all n when the archive is empty);
    each other is a parent's elite plus a Gaussian step at a scale drawn from ``space.scales``.
    Random numbers drawn in a fixed order.

    Args:
        a: the archive.
        rng: the ``numpy.random.Generator``.
        space: the :class:`Space`.
        n: vectors in the batch.
        selection: "biased" (``weights(archive, keys)``, default :func:`parent_weights` without
            groups) or "uniform" (every elite alike: plain MAP-Elites).
        weights: the parent weights' function for "biased".
        uniform: uniform vectors in the batch.

    Returns:
        ((n, D) float64 array of vectors, (n,) parent signatures, -1 = uniform).
    """
    masks = sorted(a.elite)
    k = min(uniform, n) if masks else n
    u = rng.random((n, space.dim))               # always drawn: the stream does not depend on the archive
    X = space.from_unit(u[:k])
    parents = np.full(n, -1, dtype=np.int64)
    if n > k:
        if selection == "biased":
            w = (weights or parent_weights)(a, masks)
        else:
            w = np.full(len(masks), 1.0 / len(masks))
        idx = rng.choice(len(masks), size=n - k, p=w)
        scale = np.asarray(space.scales)[rng.integers(0, len(space.scales), size=n - k)]
        step = rng.standard_normal((n - k, space.dim)) * scale[:, None]
        par = np.array([masks[i] for i in idx])
        base = np.array([space.to_unit(a.elite[m]) for m in par])
        X = np.concatenate([X, space.from_unit(base + step)])
        parents[k:] = par
    return X, parents


def grow(evaluate: Callable, archive: Archive, rng: np.random.Generator, space: Space, *, budget: int,
         explore: int = EXPLORE_EMPTY, batch: int = BATCH, selection: str = "biased", weights: Callable | None = None,
         adopt: Callable | None = None, on_batch: Callable | None = None) -> Archive:
    """Spend ``budget`` rollouts growing ``archive``: ``explore`` uniform vectors (batches of
    ``batch``) when it is empty, then :func:`emit` batches. The last batch is cut to the budget.
    KeyboardInterrupt propagates; what ran is in ``archive``.

    Args:
        evaluate: ``evaluate((B, D) vectors) -> (B,) signatures`` runs a batch.
        archive: the :class:`Archive`, grown in place.
        rng: the ``numpy.random.Generator``.
        space: the :class:`Space`.
        budget: rollouts to spend.
        explore: uniform vectors into an empty archive.
        batch: vectors per batch.
        selection, weights: as :func:`emit`.
        adopt: ``adopt(X, parents, archive)`` may change a batch's children in place before it
            runs (e.g. keep a parent's discrete coordinate); None.
        on_batch: ``on_batch(archive, new_signatures)`` after each batch; None.

    Returns:
        The archive.
    """
    end = archive.rollouts + int(budget)
    n0 = min(int(explore), int(budget)) if not archive.elite else 0
    start = archive.rollouts
    while archive.rollouts < end:
        if archive.rollouts < start + n0:
            X, parents = space.from_unit(rng.random((batch, space.dim))), None
        else:
            X, parents = emit(archive, rng, space, batch, selection=selection, weights=weights)
            if adopt is not None:
                adopt(X, parents, archive)
        X = X[: end - archive.rollouts]
        sigs = evaluate(X)
        new = archive.add(X, sigs, None if parents is None else parents[: len(X)])
        if on_batch is not None:
            on_batch(archive, new)
    return archive
