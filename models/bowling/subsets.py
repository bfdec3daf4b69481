"""Subsets of pins as 10-bit masks, and the archive both atlases keep of them.

A throw's **signature** is the set of pins it knocks down, a 10-bit mask (:mod:`.pinfall`).
This module holds what both halves do with masks: the Hamming distance between two of them
(:func:`hamming`: pins whose state differs), the size of a subset (pins down), and the
archive of the rollout room (:class:`nbst.models.mjsearch.archive.Archive`) keyed by subset,
with the bowling emitter's weights: a parent is drawn more often when few subsets of its
size are found yet (:func:`parent_weights`: the group gap of the room's weights, groups by
size, ``C(10, k)`` subsets of size k).
"""
from __future__ import annotations

import math

import numpy as np

from nbst.models.bowling import geometry
from nbst.models.mjsearch import archive as _archive

__all__ = ["N_SUBSETS", "ALL_DOWN", "SIZE_TOTAL", "SIZE_FLOOR", "HIT_BONUS", "size_of", "hamming", "SubsetArchive",
           "parent_weights", "emit", "size_table"]

N_SUBSETS = geometry.N_SUBSETS
ALL_DOWN = geometry.ALL_DOWN
#: Subsets of each size k = 0..10: C(10, k).
SIZE_TOTAL = np.array([math.comb(10, k) for k in range(11)])
#: Parent weight floor of a size whose subsets are all found (children land on other sizes).
SIZE_FLOOR = _archive.GROUP_FLOOR
#: Parent weight bonus per new subset its children found.
HIT_BONUS = _archive.HIT_BONUS

#: Pins down in a mask (one definition: the geometry's).
size_of = geometry.size_of


def hamming(a, b) -> np.ndarray:
    """Number of pins whose state differs between masks a and b (broadcast)."""
    x = np.bitwise_xor(np.asarray(a, dtype=np.int64), np.asarray(b, dtype=np.int64))
    return np.array([int(v).bit_count() for v in np.ravel(x)]).reshape(np.shape(x))


class SubsetArchive(_archive.Archive):
    """Subsets found so far (the rollout room's archive keyed by the mask of pins down): mask ->
    elite (the first delivery that gave it), how often seen, when found, and for the emitter how
    many children each parent had and how many found a new subset."""


def parent_weights(a: _archive.Archive, masks: list[int]) -> np.ndarray:
    """(P,) selection weights of the archived ``masks`` (sum 1).

    w = size gap x rarity x curiosity: size gap = share of the subsets of that size not
    found yet (at least :data:`SIZE_FLOOR`); rarity = 1 / sqrt(times seen); curiosity =
    (1 + HIT_BONUS x new subsets its children found) / sqrt(1 + children).
    """
    return _archive.parent_weights(a, masks, group=size_of, group_total=SIZE_TOTAL, floor=SIZE_FLOOR,
                                   bonus=HIT_BONUS)


def emit(a: _archive.Archive, rng: np.random.Generator, space: _archive.Space, n: int = _archive.BATCH, *,
         selection: str = "biased") -> tuple[np.ndarray, np.ndarray]:
    """One batch of the MAP-Elites emitter (:func:`nbst.models.mjsearch.archive.emit` with
    :func:`parent_weights`) in ``space``: ((n, D) deliveries, (n,) parent masks, -1 = uniform).
    ``selection``: "biased" or "uniform" (plain MAP-Elites, for the ablation)."""
    return _archive.emit(a, rng, space, n, selection=selection, weights=parent_weights)


def size_table(masks) -> list[tuple[int, int, int]]:
    """[(size, found, possible)] for sizes 1..10."""
    got = np.bincount([size_of(m) for m in masks if m], minlength=11)
    return [(k, int(got[k]), int(SIZE_TOTAL[k])) for k in range(1, 11)]
