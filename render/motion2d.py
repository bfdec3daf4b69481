"""Motions for the 2D and 3D views, and their trails.

A motion is anything with ``at(t) -> (N, 2)``: an exact :class:`nbst.sim.Trajectory` (exact
positions at every frame, exact trail corners from its keyframes) or a :class:`SampledMotion`
(positions known at sample times, a MuJoCo rollout, linear in between). The trails follow each
disk's own events (:func:`trail_points`, :func:`trail_segments`) and are drawn as capsules
(:func:`trail_capsules`) by :mod:`nbst.render.scene2d` and :mod:`nbst.render.scene3d`.
"""
from __future__ import annotations

import numpy as np

from nbst.constants import EVENT_DISK
from nbst.errors import InputError

from nbst.render.core import style
from nbst.render.core.shapes import CAPSULE_DTYPE

__all__ = ["SampledMotion", "trail_capsules", "trail_points", "trail_segments"]

class SampledMotion:
    """Positions known at sample times: times (T,) increasing, positions (T, N, 2).

    ``at(t)`` is exact at the sample times and linear in between.
    """

    def __init__(self, times, positions):
        self.times = np.asarray(times, float)
        self.positions = np.asarray(positions, float)
        if self.positions.ndim != 3 or self.positions.shape[0] != self.times.shape[0]:
            raise InputError("positions must have shape (T, N, 2) matching times (T,)")

    def at(self, t):
        ts = np.asarray(t, float)
        k = np.clip(np.searchsorted(self.times, ts, side="right") - 1, 0, len(self.times) - 1)
        k1 = np.minimum(k + 1, len(self.times) - 1)
        span = self.times[k1] - self.times[k]
        w = np.where(span > 0, (ts - self.times[k]) / np.where(span > 0, span, 1.0), 0.0)
        w = np.clip(w, 0.0, 1.0)[..., None, None]
        return self.positions[k] * (1 - w) + self.positions[k1] * w


def trail_points(motion, t: float, seconds: float):
    """The path of every disk over [max(0, t - seconds), t]: points (M, N, 2), times (M,).

    For a Trajectory the points are its keyframes inside the window plus both
    ends, so the polyline is the exact path (straight between events). Otherwise,
    or when the window holds more than MAX_TRAIL_POINTS keyframes, uniform samples.
    """
    t0 = max(0.0, t - seconds)
    kt = getattr(motion, "times", None)
    kp = getattr(motion, "positions", None)
    if kt is not None and kp is not None and hasattr(motion, "velocities"):
        lo = int(np.searchsorted(kt, t0, side="right"))
        hi = int(np.searchsorted(kt, t, side="left"))
        if hi - lo <= style.MAX_TRAIL_POINTS:
            times = np.concatenate(([t0], kt[lo:hi], [t]))
            pts = np.concatenate((motion.at(t0)[None], kp[lo:hi], motion.at(t)[None]))
            return pts, times
    times = np.linspace(t0, t, min(style.MAX_TRAIL_POINTS, 64) + 1)
    return np.asarray(motion.at(times)), times


def _own_event_points(motion, t0: float, t: float):
    """Each disk's own corners in (t0, t) of an exact motion: (disk, time, point) arrays.

    Only an event a disk takes part in bends its path (a wall bounce of disk i, a
    collision of i and j), so the corners of disk i are its positions at its own events;
    between them it flies straight. The points come from the event record (each event's
    participants' states) where the motion keeps one, else from its keyframes; None when
    ``motion`` has neither (SampledMotion)."""
    ev = getattr(motion, "events", None)
    if ev is None:
        return None
    et = ev["time"]
    lo, hi = int(np.searchsorted(et, t0, side="right")), int(np.searchsorted(et, t, side="left"))
    e = np.arange(lo, hi)
    pair = e[ev["kind"][lo:hi] == EVENT_DISK]
    disk = np.concatenate((ev["i"][lo:hi], ev["j"][pair])).astype(np.int64)
    state = getattr(motion, "event_state", None)
    if state is not None and len(state) == len(ev):  # (E, 8): xi, yi, vxi, vyi, xj, yj, vxj, vyj after e
        pts = np.concatenate((state[lo:hi, 0:2], state[pair, 4:6]))
        return disk, np.concatenate((et[lo:hi], et[pair])), pts
    kt, kp = getattr(motion, "times", None), getattr(motion, "positions", None)
    if kt is None or kp is None or len(kt) != len(ev) + 1:
        return None
    k = np.concatenate((e, pair)) + 1  # keyframe k = e + 1 holds the state after event e
    return disk, et[k - 1], kp[k, disk]


def trail_segments(motion, t: float, seconds: float):
    """The path of every disk over [max(0, t - seconds), t] as straight segments:
    p0, p1 (S, 2) world points, ta, tb (S,) their times, disk (S,) whose path.

    For an exact motion (a Trajectory with its events) the corners are each disk's own
    events, so the segments are the exact path and their count is N plus twice the
    events in the window: the work per frame grows with the disks and events on screen,
    never with N x events. Otherwise (SampledMotion) every disk is sampled uniformly at
    TRAIL_SAMPLES(N) times (fewer per disk for many disks, a bounded total)."""
    n = motion.at(0.0).shape[0] if not hasattr(motion, "problem") else motion.problem.n
    t0 = max(0.0, t - seconds)
    own = _own_event_points(motion, t0, t)
    if own is not None:
        ed, etime, epts = own
        idx = np.arange(n)
        disk = np.concatenate((idx, ed, idx))
        times = np.concatenate((np.full(n, t0), etime, np.full(n, t)))
        seq = np.concatenate((np.zeros(n), np.ones(len(ed)), np.full(n, 2.0)))  # start, corners, end at ties
        pts = np.concatenate((np.asarray(motion.at(t0), float), epts, np.asarray(motion.at(t), float)))
        order = np.lexsort((seq, times, disk))
        disk, times, pts = disk[order], times[order], pts[order]
        same = disk[1:] == disk[:-1]
        return pts[:-1][same], pts[1:][same], times[:-1][same], times[1:][same], disk[:-1][same]
    m = style.trail_samples(n)
    times = np.linspace(t0, t, m + 1)
    pts = np.asarray(motion.at(times), float)  # (m + 1, N, 2)
    disk = np.tile(np.arange(n), m)
    return (pts[:-1].reshape(-1, 2), pts[1:].reshape(-1, 2), np.repeat(times[:-1], n), np.repeat(times[1:], n),
            disk)


def trail_capsules(motion, t: float, half, colors, *, to_view=None, min_step: float) -> np.ndarray:
    """The trails at time ``t`` as capsule instances (CAPSULE_DTYPE): one per straight step of
    every disk's path over the last TRAIL_SECONDS (``trail_segments``), mapped by ``to_view``
    (default: world units kept), alpha fading with age; steps shorter than ``min_step`` (disks
    at rest) are left out. ``half`` and ``colors``: per-disk half width and colour."""
    a, b, ta, tb, disk = trail_segments(motion, t, style.TRAIL_SECONDS)
    if to_view is not None:
        a, b = to_view(a), to_view(b)
    keep = ((b - a) ** 2).sum(axis=1) > min_step * min_step
    a, b, ta, tb, disk = a[keep], b[keep], ta[keep], tb[keep], disk[keep]
    fade = lambda tt: np.clip(1.0 - (t - tt) / style.TRAIL_SECONDS, 0.0, 1.0) * style.TRAIL_ALPHA  # noqa: E731
    data = np.empty(len(disk), CAPSULE_DTYPE)
    data["p0"] = a
    data["p1"] = b
    data["alpha"][:, 0] = fade(ta)
    data["alpha"][:, 1] = fade(tb)
    data["half"] = np.asarray(half)[disk]
    data["color"] = np.asarray(colors)[disk]
    return data
