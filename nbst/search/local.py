"""The local pieces of a whole motion, for the many-body search (``nbst.search.many``): a subset of
disks as a problem of its own (:func:`subproblem`), the collision components of a motion, the
conflicts (components that hold a disk off its target: :func:`conflicts`) and the disks nearest a
group (:func:`nearest`).

Plain functions over a problem and a simulated motion (``nbst.sim.Trajectory``); no search state.
"""
from __future__ import annotations

import math

import numpy as np

from nbst.problem import Problem

__all__ = ["components", "conflicts", "labels", "must_be_struck", "nearest", "subproblem"]


def subproblem(problem: Problem, idx: np.ndarray, name: str, *, margin: float | None = None) -> Problem:
    """The disks ``idx`` of ``problem`` as a problem of their own (same t_final and R).

    margin : None: the same box. A length: a window of the box around the disks' starts and
             targets, that much wider on each side (clipped to the box), with coordinates
             relative to its corner. Velocities mean the same in both (the motion is
             translation invariant) as long as no disk touches a side of the window that is
             not a wall of the box; a search inside it draws paths of the window's size, not
             the box's, so its solutions stay among the disks they concern.
    """
    def ro(a):
        a = np.ascontiguousarray(a, dtype=bool if a.dtype == bool else np.float64)
        a.setflags(write=False)
        return a

    start, target, box = problem.start[idx], problem.target[idx], problem.box
    if margin is not None:
        pts = np.concatenate([start, target])
        lo = np.maximum(pts.min(axis=0) - margin, 0.0)
        hi = np.minimum(pts.max(axis=0) + margin, np.array(problem.box))
        lo = np.where(lo < 2 * margin, 0.0, lo)  # near a wall: use the wall itself
        hi = np.where(np.array(problem.box) - hi < 2 * margin, np.array(problem.box), hi)
        start, target, box = start - lo, target - lo, (float(hi[0] - lo[0]), float(hi[1] - lo[1]))
    return Problem(name=name, box=box, t_final=problem.t_final, target_radius=min(problem.target_radius,
                                                                                   math.hypot(*box)),
                   start=ro(start), target=ro(target), radius=ro(problem.radius[idx]),
                   mass=ro(problem.mass[idx]), cueable=ro(problem.cueable[idx]),
                   description=f"disks {idx.tolist()} of {problem.name}", source=problem.source)


def labels(tr) -> np.ndarray:
    """The collision components of a motion: a label per disk (``components`` of its
    disk-disk events)."""
    dd = tr.events["kind"] == 0
    return components(tr.problem.n, tr.events["i"][dd].astype(np.int64), tr.events["j"][dd].astype(np.int64))


def components(n: int, ev_i: np.ndarray, ev_j: np.ndarray) -> np.ndarray:
    """Connected components of the disk-disk event graph: a label per disk (union-find)."""
    parent = np.arange(n)

    def find(a):
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    for a, b in zip(ev_i.tolist(), ev_j.tolist()):
        ra, rb = find(a), find(b)
        if ra != rb:
            parent[max(ra, rb)] = min(ra, rb)
    return np.array([find(a) for a in range(n)])


def nearest(problem: Problem, centre: np.ndarray, exclude: np.ndarray, k: int, cueable_only: bool) -> np.ndarray:
    """The k disks (not in ``exclude``) whose starts are nearest any start in ``centre``."""
    ok = np.ones(problem.n, bool)
    ok[exclude] = False
    if cueable_only:
        ok &= problem.cueable
    cand = np.flatnonzero(ok)
    if cand.size == 0 or k <= 0:
        return np.empty(0, np.int64)
    d = np.full(cand.size, np.inf)
    for c in centre:
        d = np.minimum(d, np.hypot(*(problem.start[cand] - problem.start[c]).T))
    return cand[np.argsort(d, kind="stable")[:k]]


def conflicts(problem: Problem, tr, miss2: float, strikers: int = 3) -> list[np.ndarray]:
    """The conflicts of a whole motion: for each collision component holding a disk whose
    squared miss exceeds ``miss2``, its disks (sorted); a resting disk that must move and met
    nobody comes with its ``strikers`` nearest cueable disks."""
    err2 = np.sum((np.asarray(tr.final_positions) - problem.target) ** 2, axis=1)
    missing = err2 > miss2
    label = labels(tr)
    out = []
    done = set()
    for d in np.flatnonzero(missing):
        lab = label[d]
        if lab in done:
            continue
        done.add(lab)
        idx = np.flatnonzero(label == lab)
        if not problem.cueable[idx].any():
            idx = np.union1d(idx, nearest(problem, idx, idx, strikers, True))
        out.append(idx.astype(np.int64))
    return out


def must_be_struck(problem: Problem) -> bool:
    """Whether some resting (noncueable) disk has a target other than its start."""
    rest = ~problem.cueable
    return bool(np.any(np.hypot(*(problem.target[rest] - problem.start[rest]).T) > 0.0))
