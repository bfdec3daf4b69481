"""Aiming: bank shots off the walls and strikes on noncueable disks (the paper's footnote 5).

Mirror images. Unfold the box: the image (kx, ky) of a point p is p reflected kx
times in x and ky times in y, so a disk that flies straight to the image of its
target bounces |kx| + |ky| times and lands on the target itself. A *bank shot*
is the straight velocity ``(image - start) / t_final``.

Path clearance. A bank shot is only as good as its path: ``path_conflicts``
counts the other disks that, on their current free flights (wall bounces, no
disk-disk contact), come within contact distance of it, exactly (piecewise-linear
between bounces, closed-form contact times); ``choose_bank`` prefers images with
the fewest conflicts.

Strikes. A cueable disk c can send a resting disk s towards a point T (a target
or an image of it) so that s arrives exactly at t_final: s leaves along the line
of centres n = (T - p_s) / |T - p_s| with speed D / (t_final - t_hit), D = |T - p_s|;
c must touch s at q = p_s - (r_c + r_s) n, arriving at t_hit with normal speed
u = (v_c . n) giving s the speed (2 m_c / (m_c + m_s)) u. With A = (q - p_c).n
(> 0 for c to approach from behind; then q is c's first contact with s):
t_hit = A t_final / (A + k D), k = (m_c + m_s) / (2 m_c), v_c = (q - p_c) / t_hit.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from .sim import pair_tau

@njit(cache=True, inline="always")
def mirror(u, k, lo, hi):
    """Coordinate of image k of u in [lo, hi] (k reflections)."""
    L = hi - lo
    if k % 2 == 0:
        return lo + k * L + (u - lo)
    return lo + k * L + (hi - u)


@njit(cache=True, inline="always")
def fold(x, lo, hi):
    """Where an unfolded coordinate x lands in [lo, hi]."""
    L = hi - lo
    u = (x - lo) % (2.0 * L)
    return lo + (u if u <= L else 2.0 * L - u)


@njit(cache=True)
def bank_velocity(start, target, r, W, H, t_final, kx, ky, out):
    """Velocity (into out[0:2]) that reaches ``target`` at t_final via image (kx, ky)."""
    out[0] = (mirror(target[0], kx, r, W - r) - start[0]) / t_final
    out[1] = (mirror(target[1], ky, r, H - r) - start[1]) / t_final


@njit(cache=True, error_model="numpy")
def _breaks(x0, v, lo, hi, t_final, out, m):
    """Append to out[m:] the times in (0, t_final) at which a free flight x0 + v t
    (folded into [lo, hi]) bounces; return the new count."""
    if v == 0.0:
        return m
    L = hi - lo
    x1 = x0 + v * t_final
    a = min(x0, x1)
    b = max(x0, x1)
    k0 = math.ceil((a - lo) / L)
    k1 = math.floor((b - lo) / L)
    for k in range(k0, k1 + 1):
        t = (lo + k * L - x0) / v
        if 0.0 < t < t_final and m < out.shape[0]:
            out[m] = t
            m += 1
    return m


@njit(cache=True, inline="always")
def _fold_state(x0, v, lo, hi, t, tm):
    """Folded position at t and folded velocity over (t, tm] of the free flight x0 + v t."""
    L = hi - lo
    u = (x0 + v * tm - lo) % (2.0 * L)
    sign = 1.0 if u <= L else -1.0
    return fold(x0 + v * t, lo, hi), sign * v


@njit(cache=True, error_model="numpy")
def flights_conflict(xi, yi, vxi, vyi, ri, xk, yk, vxk, vyk, rk, W, H, t_final):
    """Exactly: do two disks on free flights (wall bounces only, no disk-disk contact)
    come within contact distance at some t in [0, t_final]?

    Between consecutive bounces of either disk both move in straight lines, so each
    piece is checked with the closed-form contact time."""
    br = np.empty(64)
    m = 0
    m = _breaks(xi, vxi, ri, W - ri, t_final, br, m)
    m = _breaks(yi, vyi, ri, H - ri, t_final, br, m)
    m = _breaks(xk, vxk, rk, W - rk, t_final, br, m)
    m = _breaks(yk, vyk, rk, H - rk, t_final, br, m)
    br[m] = t_final
    m += 1
    br[:m].sort()
    s = ri + rk
    ta = 0.0
    for q in range(m):
        tb = br[q]
        if tb <= ta:
            continue
        tm = 0.5 * (ta + tb)
        pxi, uxi = _fold_state(xi, vxi, ri, W - ri, ta, tm)
        pyi, uyi = _fold_state(yi, vyi, ri, H - ri, ta, tm)
        pxk, uxk = _fold_state(xk, vxk, rk, W - rk, ta, tm)
        pyk, uyk = _fold_state(yk, vyk, rk, H - rk, ta, tm)
        dx = pxk - pxi
        dy = pyk - pyi
        if dx * dx + dy * dy < s * s:
            return True
        if pair_tau(dx, dy, uxk - uxi, uyk - uyi, s, tb - ta) < math.inf:
            return True
        ta = tb
    return False


@njit(cache=True, error_model="numpy")
def path_conflicts(i, vi, x0, V, radius, W, H, t_final):
    """How many other disks come within contact of disk i flying at vi, all on free
    (folded) flights with velocities V (disk-disk collisions ignored), over [0, t_final]."""
    count = 0
    for k in range(x0.shape[0]):
        if k != i and flights_conflict(x0[i, 0], x0[i, 1], vi[0], vi[1], radius[i], x0[k, 0], x0[k, 1],
                                       V[k, 0], V[k, 1], radius[k], W, H, t_final):
            count += 1
    return count


@njit(cache=True, error_model="numpy")
def choose_bank(i, x0, V, radius, target, W, H, t_final, max_bounces, out):
    """Bank shot for disk i (1..max_bounces bounces) whose path meets the fewest
    other disks' current paths; ties broken uniformly at random (numba's RNG).
    Writes the velocity to out; returns the number of conflicts of the chosen path."""
    best = 1 << 30
    nbest = 0
    v = np.empty(2)
    for kx in range(-max_bounces, max_bounces + 1):
        for ky in range(-max_bounces, max_bounces + 1):
            b = abs(kx) + abs(ky)
            if b == 0 or b > max_bounces:
                continue
            bank_velocity(x0[i], target[i], radius[i], W, H, t_final, kx, ky, v)
            c = path_conflicts(i, v, x0, V, radius, W, H, t_final)
            if c < best:
                best = c
                nbest = 1
                out[0] = v[0]
                out[1] = v[1]
            elif c == best:
                nbest += 1
                if np.random.random() * nbest < 1.0:  # reservoir: uniform among the ties
                    out[0] = v[0]
                    out[1] = v[1]
    return best


@njit(cache=True, error_model="numpy")
def strike_velocity(pc, rc, mc, ps, rs, ms, T, t_final, out):
    """Velocity of cue disk c (from pc) that strikes resting disk s (at ps) so that s
    flies straight to T and arrives at t_final. Returns t_hit, or -1 if impossible
    (c would have to approach from the far side)."""
    dx = T[0] - ps[0]
    dy = T[1] - ps[1]
    D = math.sqrt(dx * dx + dy * dy)
    if D == 0.0:
        return -1.0
    nx = dx / D
    ny = dy / D
    s = rc + rs
    qx = ps[0] - s * nx
    qy = ps[1] - s * ny
    A = (qx - pc[0]) * nx + (qy - pc[1]) * ny
    if A <= 0.0:
        return -1.0
    k = (mc + ms) / (2.0 * mc)
    t_hit = A * t_final / (A + k * D)
    out[0] = (qx - pc[0]) / t_hit
    out[1] = (qy - pc[1]) / t_hit
    return t_hit


def bank_shot(problem, i, kx, ky):
    """(2,) velocity that brings disk i to its target via mirror image (kx, ky)."""
    out = np.empty(2)
    bank_velocity(np.ascontiguousarray(problem.start[i]), np.ascontiguousarray(problem.target[i]),
                  float(problem.radius[i]), float(problem.box[0]), float(problem.box[1]),
                  float(problem.t_final), int(kx), int(ky), out)
    return out


def strike(problem, c, s, T=None):
    """(velocity (2,), t_hit) for cue disk c to send resting disk s straight to T
    (default: s's target) at t_final; raises ValueError when c is on the wrong side."""
    T = problem.target[s] if T is None else np.asarray(T, float)
    out = np.empty(2)
    t_hit = strike_velocity(np.ascontiguousarray(problem.start[c]), float(problem.radius[c]), float(problem.mass[c]),
                            np.ascontiguousarray(problem.start[s]), float(problem.radius[s]),
                            float(problem.mass[s]), np.ascontiguousarray(T, dtype=float),
                            float(problem.t_final), out)
    if t_hit < 0:
        raise ValueError(f"disk {c} cannot strike disk {s} towards {tuple(T)}: it would come from the far side")
    return out, t_hit
