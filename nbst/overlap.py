"""Overlapping disks, found in O(N log N): the check every problem's starts pass.

``first_overlap(start, radius)`` names the overlapping pair with the least index (then the least
partner), as the plain pairwise rule would, without comparing every pair: a 90,000-disk problem
whose last disk overlaps another is refused in a fraction of a second (the pairwise check was
still running after a minute). Arrays in, a pair out; this module sits in the lowest layer.
"""
from __future__ import annotations

import numpy as np

from nbst.constants import OVERLAP_RTOL

__all__ = ["first_overlap"]


#: A cell of the overlap grid (side 2 r_max of a radius class, whose radii lie within a factor 2)
#: holds at most 9 disks of that class that do not overlap (centres >= r_max apart); more than
#: this, and two of them overlap (the check then looks no further than that cell).
OVERLAP_CELL_MAX = 16
#: Candidate pairs the overlap check tests at once (its memory: ~100 bytes a pair).
OVERLAP_CHUNK = 1_000_000


def first_overlap(start: np.ndarray, radius: np.ndarray, tol: float = OVERLAP_RTOL) -> tuple[int, int] | None:
    """(i, j), i < j, of the overlapping starts with the least i (then j), or None. Disks overlap
    when their centres are closer than (r_i + r_j)(1 - tol).

    O(N log N) whatever N (a 90,000-disk problem in a fraction of a second): the disks are put in
    radius classes (radii within a factor 2), each class on a grid of cells as wide as two of its
    largest radii, and only disks in neighbouring cells are compared. Non-overlapping disks of a
    class fill a cell with at most 9 (:data:`OVERLAP_CELL_MAX`), so the candidates stay a few per
    disk; a fuller cell holds an overlap, which is reported from that cell (the least pair there)."""
    n = radius.shape[0]
    if n < 2:
        return None
    cls = np.floor(np.log2(radius / radius.min())).astype(np.int64)
    groups = [np.flatnonzero(cls == k) for k in np.unique(cls)]
    found: list[tuple[int, int]] = []
    for g in groups:  # within each class first: a dense cell is an overlap, found at once
        reach = 2.0 * float(radius[g].max())
        dense = _dense_cell(start, g, reach)
        if dense is not None:
            return _least_overlap(start, radius, dense, dense, tol, same=True)
        found += _near_overlaps(start, radius, g, g, reach, tol, same=True)
    for a in range(len(groups)):  # then across classes (each class's cells are now known to be sparse)
        for b in range(a + 1, len(groups)):
            reach = float(radius[groups[a]].max() + radius[groups[b]].max())
            found += _near_overlaps(start, radius, groups[a], groups[b], reach, tol, same=False)
    return min(found) if found else None


def _cells(start: np.ndarray, idx: np.ndarray, reach: float) -> np.ndarray:
    """The grid cell (a number) of each disk ``idx``: cells of side ``reach``."""
    c = np.floor(start[idx] / reach).astype(np.int64)
    return c[:, 0] * (int(start[:, 1].max() / reach) + 3) + c[:, 1]


def _dense_cell(start, idx, reach):
    """The first OVERLAP_CELL_MAX + 1 disks (by index) of the fullest cell, if it holds more than that."""
    keys = _cells(start, idx, reach)
    uk, inverse, counts = np.unique(keys, return_inverse=True, return_counts=True)
    if counts.max() <= OVERLAP_CELL_MAX:
        return None
    return np.sort(idx[inverse == int(np.argmax(counts))])[:OVERLAP_CELL_MAX + 1]


def _least_overlap(start, radius, ia, ib, tol, same):
    found = _test_pairs(start, radius, np.repeat(ia, len(ib)), np.tile(ib, len(ia)), tol, same)
    return min(found) if found else None


def _test_pairs(start, radius, i, j, tol, same) -> list:
    """The overlapping pairs among candidates (i[k], j[k]), each as (least, greatest) index."""
    if same:
        keep = i < j
        i, j = i[keep], j[keep]
    d2 = ((start[i] - start[j]) ** 2).sum(axis=1)
    bad = d2 < ((radius[i] + radius[j]) * (1.0 - tol)) ** 2
    lo, hi = np.minimum(i[bad], j[bad]), np.maximum(i[bad], j[bad])
    return list(zip(lo.tolist(), hi.tolist()))


def _near_overlaps(start, radius, ia, ib, reach, tol, same) -> list:
    """Overlapping pairs of a disk of ``ia`` and one of ``ib`` in neighbouring cells of side ``reach``."""
    ka = _cells(start, ia, reach)
    order = np.argsort(ka, kind="stable")
    sa, ka = ia[order], ka[order]
    uk, first, counts = np.unique(ka, return_index=True, return_counts=True)
    kb = _cells(start, ib, reach)
    m = int(start[:, 1].max() / reach) + 3
    found = []
    for dx in (-1, 0, 1):
        for dy in (-1, 0, 1):
            key = kb + dx * m + dy
            pos = np.clip(np.searchsorted(uk, key), 0, len(uk) - 1)
            hit = np.flatnonzero(uk[pos] == key)
            if not hit.size:
                continue
            step = max(1, OVERLAP_CHUNK // int(counts[pos[hit]].max()))
            for lo in range(0, hit.size, step):  # chunks of at most ~OVERLAP_CHUNK candidates
                h = hit[lo:lo + step]
                c = counts[pos[h]]
                # candidate t of run q is the (t - offset_q)-th disk of its cell, whose first is first_q
                a = sa[np.repeat(first[pos[h]] - (np.cumsum(c) - c), c) + np.arange(int(c.sum()))]
                found += _test_pairs(start, radius, a, np.repeat(ib[h], c), tol, same)
    return found
