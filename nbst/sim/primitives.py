"""The physics rules of frictionless elastic disks in a box, each written once.

Every module that needs one of these rules calls it from here: the event kernel
(``nbst.sim.kernel``), the Jacobian (``nbst.sim.jacobian``), the sensitivity report
(``nbst.sim.sensitivity``), and the search's aiming and planner (``nbst.search.aim``,
``nbst.search.planner``). They are small ``njit(inline="always")`` functions over scalars
and arrays, so inlining them costs nothing and keeps each caller's floating-point
operations exactly as they were (the search's results are bit-for-bit those of the
copies they replace).

* **contact times**: :func:`pair_tau` (two disks on straight paths), :func:`wall_tau`
  (a disk and the wall it moves towards);
* **the elastic impulse**: :func:`impulse_share` (the fraction of the normal approach
  speed a disk loses, 2 m_partner / (m_i + m_j)) and :func:`elastic_impulse` (both
  post-contact velocities);
* **event replay**: :func:`replay_event` (the velocity change of one recorded event, as
  the kernel made it) and :func:`contact_normal` (the unit normal of a recorded contact);
* **mirror images**: :func:`mirror` (image k of a coordinate), :func:`fold` (where an
  unfolded coordinate lands), :func:`images` (every image (kx, ky) within a bounce count).

``tests/test_primitives.py`` compares each with the slow reference of ``tests/naive.py``.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from nbst.constants import WALL_BOTTOM, WALL_LEFT, WALL_RIGHT, WALL_TOP

__all__ = ["INF", "IMPACT_NONE", "IMPACT_WALL", "IMPACT_PAIR", "pair_tau", "axis_tau", "wall_tau", "wall_axis",
           "impulse_share", "transferred_speed", "strike_ratio", "elastic_impulse", "contact_normal", "replay_event",
           "mirror", "fold", "images"]

INF = math.inf

#: ``replay_event`` outcomes: the event changed no velocity (a touch without approach),
#: it was a wall bounce, or a disk-disk impulse.
IMPACT_NONE, IMPACT_WALL, IMPACT_PAIR = 0, 1, 2


# --------------------------------------------------------------------------- contact times

@njit(cache=True, inline="always", error_model="numpy")
def pair_tau(dx, dy, dvx, dvy, s, h):
    """Time until two disks touch, if it is at most h; else inf.

    inf if they never touch within h (or are separating); 0 if round-off already
    has them overlapping and approaching. The horizon test needs no square root.
    The root is the numerically stable ``c / (-b + sqrt(b^2 - a c))`` of
    ``|dp + dv tau|^2 = s^2``.

    Args:
        dx, dy: pk - pi, units.
        dvx, dvy: vk - vi, units/s.
        s: the contact distance (the sum of the radii), units.
        h: the horizon, seconds.

    Returns:
        float: the time to contact, seconds (inf: none within h).
    """
    b = dx * dvx + dy * dvy
    if b >= 0.0:
        return INF
    a = dvx * dvx + dvy * dvy
    c = dx * dx + dy * dy - s * s
    if c <= 0.0:
        return 0.0
    if a * h <= -b:
        # closest approach lies beyond h: contact within h iff the gap closes by h
        if c + h * (2.0 * b + a * h) > 0.0:
            return INF
    disc = b * b - a * c
    if disc < 0.0:
        return INF
    return c / (-b + math.sqrt(disc))


@njit(cache=True, inline="always", error_model="numpy")
def axis_tau(x, v, r, L, wall_lo, wall_hi):
    """(time until a disk at coordinate x moving at v touches the wall it moves towards on one
    axis of length L, which wall): wall_lo at x = r, wall_hi at x = L - r; (inf, -1) at rest."""
    if v > 0.0:
        return (L - r - x) / v, wall_hi
    if v < 0.0:
        return (r - x) / v, wall_lo
    return INF, -1


@njit(cache=True, inline="always", error_model="numpy")
def wall_tau(x, y, vx, vy, r, W, H):
    """The next wall contact of one disk; x walls win ties.

    Only the wall a disk moves towards is predicted; a time that round-off makes
    negative is clamped to 0 ("now").

    Args:
        x, y: the disk's centre, units.
        vx, vy: its velocity, units/s.
        r: its radius, units.
        W, H: the box, units.

    Returns:
        (time until the disk touches a wall in seconds, inf if never; which wall: 0 left,
        1 right, 2 bottom, 3 top).
    """
    tx, wx = axis_tau(x, vx, r, W, WALL_LEFT, WALL_RIGHT)
    ty, wy = axis_tau(y, vy, r, H, WALL_BOTTOM, WALL_TOP)
    if ty < tx:
        return (ty if ty > 0.0 else 0.0), wy
    return (tx if tx > 0.0 else 0.0), wx


@njit(cache=True, inline="always")
def wall_axis(w):
    """The velocity component a bounce off wall w flips: 0 (x) for left/right, 1 (y) for bottom/top."""
    return 0 if w <= WALL_RIGHT else 1


# --------------------------------------------------------------------------- the elastic impulse

@njit(cache=True, inline="always", error_model="numpy")
def impulse_share(m_partner, m_self):
    """2 m_partner / (m_self + m_partner): how much of the normal approach speed u a disk
    loses in a frictionless elastic contact (its velocity changes by -share u n). Head-on,
    a disk at rest struck with speed u leaves with ``impulse_share(m_striker, m_struck) u``."""
    return 2.0 * m_partner / (m_self + m_partner)


@njit(cache=True, inline="always", error_model="numpy")
def transferred_speed(u, m_striker, m_struck):
    """Head-on, a disk at rest struck with normal speed u leaves with u 2 m_striker /
    (m_striker + m_struck) (``impulse_share(m_striker, m_struck) u``, evaluated in this order,
    which the planner's closed forms use)."""
    return u * 2.0 * m_striker / (m_striker + m_struck)


@njit(cache=True, inline="always", error_model="numpy")
def strike_ratio(m_striker, m_struck):
    """(m_striker + m_struck) / (2 m_striker) = 1 / ``impulse_share(m_striker, m_struck)``: the
    normal speed a striker needs per unit of speed it gives a resting disk (the aiming closed
    forms divide by the transfer this way)."""
    return (m_striker + m_struck) / (2.0 * m_striker)


@njit(cache=True, inline="always", error_model="numpy")
def elastic_impulse(vxi, vyi, vxj, vyj, nx, ny, mi, mj):
    """Velocities of disks i and j after a frictionless elastic contact along the unit
    normal (nx, ny) from i to j: (vxi', vyi', vxj', vyj'). A pair that is not approaching
    (u = (vi - vj).n <= 0) is left as it is. Momentum and kinetic energy are conserved."""
    u = (vxi - vxj) * nx + (vyi - vyj) * ny  # > 0: approaching
    if u > 0.0:
        fi = impulse_share(mj, mi) * u
        fj = impulse_share(mi, mj) * u
        return vxi - fi * nx, vyi - fi * ny, vxj + fj * nx, vyj + fj * ny
    return vxi, vyi, vxj, vyj


# --------------------------------------------------------------------------- event replay

@njit(cache=True, inline="always", error_model="numpy")
def contact_normal(ev_state, e):
    """(nx, ny, s) of recorded disk-disk event e: the unit normal from its disk i to its
    disk j and their centre distance, from the recorded post-event positions (positions
    are continuous, so these are the contact's)."""
    Dx = ev_state[e, 4] - ev_state[e, 0]
    Dy = ev_state[e, 5] - ev_state[e, 1]
    s = np.sqrt(Dx * Dx + Dy * Dy)
    return Dx / s, Dy / s, s


@njit(cache=True, inline="always", error_model="numpy")
def replay_event(e, ev_i, ev_j, ev_state, V):
    """Apply recorded event e (a record of ``nbst.sim.kernel.run``) to the velocities V (N, 2)
    just before it; returns IMPACT_WALL, IMPACT_PAIR or IMPACT_NONE.

    A wall event flips one component; a disk-disk event takes the recorded post-event
    velocities if the pair was approaching along the contact normal (else the kernel
    changed nothing, and neither does this)."""
    i = ev_i[e]
    j = ev_j[e]
    if j < 0:
        c = wall_axis(-1 - j)
        V[i, c] = -V[i, c]
        return IMPACT_WALL
    nx, ny, _ = contact_normal(ev_state, e)
    if nx * (V[j, 0] - V[i, 0]) + ny * (V[j, 1] - V[i, 1]) >= 0.0:
        return IMPACT_NONE
    V[i, 0] = ev_state[e, 2]
    V[i, 1] = ev_state[e, 3]
    V[j, 0] = ev_state[e, 6]
    V[j, 1] = ev_state[e, 7]
    return IMPACT_PAIR


# --------------------------------------------------------------------------- mirror images

@njit(cache=True, inline="always")
def mirror(u, k, lo, hi):
    """Coordinate of image k of u in [lo, hi] (k reflections): a disk flying straight to it
    from inside [lo, hi] bounces |k| times and lands on u."""
    L = hi - lo
    if k % 2 == 0:
        return lo + k * L + (u - lo)
    return lo + k * L + (hi - u)


@njit(cache=True, inline="always")
def fold(x, lo, hi):
    """Where an unfolded coordinate x lands in [lo, hi] (the inverse of ``mirror``)."""
    L = hi - lo
    u = (x - lo) % (2.0 * L)
    return lo + (u if u <= L else 2.0 * L - u)


@njit(cache=True)
def images(min_bounces, max_bounces):
    """(M, 2) int64: every mirror image (kx, ky) with min_bounces <= |kx| + |ky| <= max_bounces,
    kx ascending, then ky ascending (M = 61 for 0..5)."""
    b = max_bounces
    out = np.empty(((2 * b + 1) ** 2 if b >= 0 else 0, 2), np.int64)
    m = 0
    for kx in range(-b, b + 1):
        for ky in range(-b, b + 1):
            k = abs(kx) + abs(ky)
            if min_bounces <= k <= b:
                out[m, 0] = kx
                out[m, 1] = ky
                m += 1
    return out[:m].copy()
