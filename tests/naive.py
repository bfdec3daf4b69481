"""Slow, obviously-correct references for the simulator (no numba, no cleverness).

* ``naive_simulate``: event-driven, but every event rescans all pairs and walls
  from scratch, with the textbook quadratic formula; ties go to the lowest
  (time, i, j) with walls first.
* ``brute_force``: fixed small time steps, overlap detection, velocity flips;
  first-order accurate (error ~ speed * dt per contact).
* ``fold``: exact position of a lone disk bouncing between two walls.
* ``impulse``, ``mirror_image``: the textbook contact and reflection rules
  (references for ``nbst.sim.primitives``).
"""
from __future__ import annotations

import math

import numpy as np


def fold(x0, v, t, r, L):
    """Exact coordinate of a disk (radius r) moving at v between walls at 0 and L."""
    span = L - 2 * r
    u = (x0 - r + v * t) % (2 * span)
    return r + (u if u <= span else 2 * span - u)


def impulse(vi, vj, p_i, p_j, mi, mj):
    """Textbook frictionless elastic contact: the velocities after it (vectors), with the
    normal from the centres; a pair that is not approaching is left as it is."""
    vi, vj = np.array(vi, float), np.array(vj, float)
    nrm = (np.asarray(p_j, float) - np.asarray(p_i, float))
    nrm = nrm / np.linalg.norm(nrm)
    u = (vi - vj) @ nrm
    if u > 0:
        vi = vi - 2 * mj / (mi + mj) * u * nrm
        vj = vj + 2 * mi / (mi + mj) * u * nrm
    return vi, vj


def mirror_image(u, k, lo, hi):
    """Image k of coordinate u in [lo, hi], by reflecting |k| times in successive walls
    (lo + L, lo + 2L, ... for k > 0; lo, lo - L, ... for k < 0)."""
    L = hi - lo
    x = u
    for m in range(1, abs(k) + 1):
        wall = lo + m * L if k > 0 else lo - (m - 1) * L
        x = 2 * wall - x
    return x


def _pair_time(p1, v1, p2, v2, s):
    dp = p2 - p1
    dv = v2 - v1
    a = dv @ dv
    b = dp @ dv
    c = dp @ dp - s * s
    if b >= 0 or a == 0:
        return math.inf
    disc = b * b - a * c
    if disc < 0:
        return math.inf
    return max((-b - math.sqrt(disc)) / a, 0.0)


def _wall_time(p, v, r, W, H):
    best = (math.inf, -1)
    for axis, lo, hi, wlo, whi in ((0, r, W - r, 0, 1), (1, r, H - r, 2, 3)):
        if v[axis] > 0:
            best = min(best, (max((hi - p[axis]) / v[axis], 0.0), whi))
        elif v[axis] < 0:
            best = min(best, (max((lo - p[axis]) / v[axis], 0.0), wlo))
    return best


def next_event(p, v, radius, W, H):
    """The next event of a state (positions p, velocities v, both (N, 2)), rescanning every
    wall and every pair with the textbook formulas: (dt, i, j_or_wall_code) with the wall code
    -1 - wall, as ``nbst.sim.run`` records it; ties go to the lowest (dt, i), walls first.
    Vectorized over pairs with numpy, but no state carried between events."""
    n = len(p)
    walls = [_wall_time(p[i], v[i], radius[i], W, H) for i in range(n)]
    best = min((t, i, 0, -1 - w) for i, (t, w) in enumerate(walls))
    if n > 1:
        iu, ku = np.triu_indices(n, 1)
        dp = p[ku] - p[iu]
        dv = v[ku] - v[iu]
        a = (dv * dv).sum(axis=1)
        b = (dp * dv).sum(axis=1)
        c = (dp * dp).sum(axis=1) - (radius[iu] + radius[ku]) ** 2
        disc = b * b - a * c
        ok = (b < 0) & (a > 0) & (disc >= 0)
        t = np.full(len(iu), math.inf)
        t[ok] = np.maximum((-b[ok] - np.sqrt(disc[ok])) / a[ok], 0.0)
        m = int(np.argmin(t))
        best = min(best, (float(t[m]), int(iu[m]), 1, int(ku[m])))
    return best[0], best[1], best[3]


def naive_simulate(start, vel, radius, mass, W, H, t_final, max_events=100_000):
    """Returns (final positions, final velocities, events [(t, i, j_or_wall_code)])."""
    p = np.array(start, float)
    v = np.array(vel, float)
    n = len(p)
    t = 0.0
    events = []
    while len(events) < max_events:
        best = (math.inf, 0, 0, 0)  # time, i, kind (0 wall, 1 pair), other
        for i in range(n):
            tw, w = _wall_time(p[i], v[i], radius[i], W, H)
            best = min(best, (tw, i, 0, w))
            for k in range(i + 1, n):
                best = min(best, (_pair_time(p[i], v[i], p[k], v[k], radius[i] + radius[k]), i, 1, k))
        dt, i, kind, other = best
        if t + dt > t_final:
            break
        p += v * dt
        t += dt
        if kind == 0:
            axis = 0 if other in (0, 1) else 1
            v[i, axis] = -v[i, axis]
            events.append((t, i, -1 - other))
        else:
            k = other
            v[i], v[k] = impulse(v[i], v[k], p[i], p[k], mass[i], mass[k])
            events.append((t, i, k))
    p += v * (t_final - t)
    return p, v, events


def brute_force(start, vel, radius, mass, W, H, t_final, dt):
    """Small fixed steps; a contact is resolved on the step that first overlaps."""
    p = np.array(start, float)
    v = np.array(vel, float)
    r = np.asarray(radius, float)
    m = np.asarray(mass, float)
    n = len(p)
    steps = int(round(t_final / dt))
    iu, ku = np.triu_indices(n, 1)
    for _ in range(steps):
        p += v * dt
        lo = p < r[:, None]
        hi = p > np.array([W, H]) - r[:, None]
        v[lo & (v < 0)] *= -1
        v[hi & (v > 0)] *= -1
        if n > 1:
            d = p[ku] - p[iu]
            dist = np.sqrt((d ** 2).sum(axis=1))
            for idx in np.nonzero(dist < r[iu] + r[ku])[0]:
                i, k = iu[idx], ku[idx]
                nrm = d[idx] / dist[idx]
                u = (v[i] - v[k]) @ nrm
                if u > 0:
                    v[i] -= 2 * m[k] / (m[i] + m[k]) * u * nrm
                    v[k] += 2 * m[i] / (m[i] + m[k]) * u * nrm
    return p, v
