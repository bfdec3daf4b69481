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
t_hit = A t_final / (A + k D), k = (m_c + m_s) / (2 m_c) (``nbst.sim.primitives.strike_ratio``), v_c = (q - p_c) / t_hit.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from nbst.errors import SolveError
from nbst.search.ops import rng_uniform
from nbst.sim.primitives import fold, images, mirror, pair_tau, strike_ratio

__all__ = ["MAX_PIECES", "alloc_clearance", "all_pieces", "bank_shot", "bank_velocity", "chain_strike_velocity",
           "choose_bank", "count_conflicts", "pair_contact", "flight_pieces", "flights_conflict", "fold", "mirror", "path_conflicts",
           "pieces_conflict", "strike", "strike_velocity"]

@njit(cache=True)
def bank_velocity(start, target, r, W, H, t_final, kx, ky, out):
    """Velocity (into out[0:2]) that reaches ``target`` at t_final via image (kx, ky)."""
    out[0] = (mirror(target[0], kx, r, W - r) - start[0]) / t_final
    out[1] = (mirror(target[1], ky, r, H - r) - start[1]) / t_final


#: Most pieces (straight stretches between bounces) a free flight may have in
#: clearance checks; a faster flight is treated as conflicting with everything.
MAX_PIECES = 64


@njit(cache=True, error_model="numpy")
def flight_pieces(x0, y0, vx, vy, r, W, H, t_final, pt, ps):
    """Split a free flight (wall bounces only) into straight pieces.

    Writes piece start times to pt[0:m] (pt[0] = 0; pt[m] = t_final) and the
    state at each start (x, y, vx, vy) to ps[0:m]; returns m, or -1 if the
    flight has more than MAX_PIECES - 1 pieces."""
    m = 1
    pt[0] = 0.0
    for axis in range(2):
        p0 = x0 if axis == 0 else y0
        v = vx if axis == 0 else vy
        lo = r
        hi = (W if axis == 0 else H) - r
        if v == 0.0:
            continue
        L = hi - lo
        p1 = p0 + v * t_final
        k0 = math.ceil((min(p0, p1) - lo) / L)
        k1 = math.floor((max(p0, p1) - lo) / L)
        for k in range(k0, k1 + 1):
            t = (lo + k * L - p0) / v
            if 0.0 < t < t_final:
                if m >= pt.shape[0] - 1:
                    return -1
                q = m  # insertion into the sorted list
                while q > 0 and pt[q - 1] > t:
                    pt[q] = pt[q - 1]
                    q -= 1
                pt[q] = t
                m += 1
    pt[m] = t_final
    for q in range(m):
        ta = pt[q]
        tm = 0.5 * (ta + pt[q + 1])
        for axis in range(2):
            p0 = x0 if axis == 0 else y0
            v = vx if axis == 0 else vy
            lo = r
            L = (W if axis == 0 else H) - r - lo
            u = (p0 + v * tm - lo) % (2.0 * L)
            ps[q, axis] = fold(p0 + v * ta, lo, lo + L)
            ps[q, 2 + axis] = v if u <= L else -v
    return m


@njit(cache=True, error_model="numpy")
def pieces_conflict(ti, si, mi, tk, sk, mk, s):
    """Do two piecewise-straight flights come within distance s? (exact, closed form per overlap)"""
    a = 0
    b = 0
    ta = 0.0
    while a < mi and b < mk:
        tb = min(ti[a + 1], tk[b + 1])
        if tb > ta:
            dti = ta - ti[a]
            dtk = ta - tk[b]
            dx = (sk[b, 0] + sk[b, 2] * dtk) - (si[a, 0] + si[a, 2] * dti)
            dy = (sk[b, 1] + sk[b, 3] * dtk) - (si[a, 1] + si[a, 3] * dti)
            if dx * dx + dy * dy < s * s:
                return True
            if pair_tau(dx, dy, sk[b, 2] - si[a, 2], sk[b, 3] - si[a, 3], s, tb - ta) < math.inf:
                return True
            ta = tb
        if ti[a + 1] <= tb:
            a += 1
        if tk[b + 1] <= tb:
            b += 1
    return False


@njit(cache=True, error_model="numpy")
def flights_conflict(xi, yi, vxi, vyi, ri, xk, yk, vxk, vyk, rk, W, H, t_final):
    """Exactly: do two disks on free flights (wall bounces only, no disk-disk contact)
    come within contact distance at some t in [0, t_final]?

    Between consecutive bounces of either disk both move in straight lines, so each
    piece is checked with the closed-form contact time."""
    ti = np.empty(MAX_PIECES)
    si = np.empty((MAX_PIECES, 4))
    tk = np.empty(MAX_PIECES)
    sk = np.empty((MAX_PIECES, 4))
    mi = flight_pieces(xi, yi, vxi, vyi, ri, W, H, t_final, ti, si)
    mk = flight_pieces(xk, yk, vxk, vyk, rk, W, H, t_final, tk, sk)
    if mi < 0 or mk < 0:
        return True
    return pieces_conflict(ti, si, mi, tk, sk, mk, ri + rk)


@njit(cache=True)
def alloc_clearance(n):
    """Scratch for ``choose_bank`` / ``count_conflicts``: every disk's pieces, plus one candidate's."""
    return (np.empty((n, MAX_PIECES)), np.empty((n, MAX_PIECES, 4)), np.empty(n, np.int64),
            np.empty(MAX_PIECES), np.empty((MAX_PIECES, 4)))


@njit(cache=True, error_model="numpy")
def all_pieces(x0, V, radius, W, H, t_final, scr):
    """Precompute every disk's free-flight pieces (for ``count_conflicts``)."""
    PT, PS, PM, _, _ = scr
    for k in range(x0.shape[0]):
        PM[k] = flight_pieces(x0[k, 0], x0[k, 1], V[k, 0], V[k, 1], radius[k], W, H, t_final, PT[k], PS[k])


@njit(cache=True, error_model="numpy")
def count_conflicts(i, vi, x0, radius, W, H, t_final, scr, limit):
    """Conflicts of disk i flying at vi with every other disk's pieces (from
    ``all_pieces``); stops counting above ``limit``."""
    PT, PS, PM, ct, cs = scr
    mi = flight_pieces(x0[i, 0], x0[i, 1], vi[0], vi[1], radius[i], W, H, t_final, ct, cs)
    if mi < 0:
        return 1 << 30
    count = 0
    for k in range(x0.shape[0]):
        if k == i:
            continue
        if PM[k] < 0 or pieces_conflict(ct, cs, mi, PT[k], PS[k], PM[k], radius[i] + radius[k]):
            count += 1
            if count > limit:
                return count
    return count


@njit(cache=True, error_model="numpy")
def path_conflicts(i, vi, x0, V, radius, W, H, t_final):
    """How many other disks come within contact of disk i flying at vi, all on free
    (folded) flights with velocities V (disk-disk collisions ignored), over [0, t_final]."""
    scr = alloc_clearance(x0.shape[0])
    all_pieces(x0, V, radius, W, H, t_final, scr)
    return count_conflicts(i, vi, x0, radius, W, H, t_final, scr, 1 << 30)


@njit(cache=True, error_model="numpy")
def choose_bank(i, x0, V, radius, target, W, H, t_final, min_bounces, max_bounces, scr, rng, out):
    # Thirteen parameters on purpose: an operator over flat arrays (numba), also tested alone.
    """Bank shot for disk i (min_bounces..max_bounces bounces) whose path meets the
    fewest other disks' current free flights (velocities V), chosen uniformly at
    random among the best (``rng``: a xoshiro256** state, ``nbst.search.ops.seed_state``).
    ``scr`` from ``alloc_clearance(N)``. Writes the velocity to out; returns the
    number of conflicts of the chosen path.

    The images are scanned in random order and the first conflict-free one is
    taken at once (uniform among the conflict-free images, as a full scan with
    random tie-breaking would choose, at a fraction of the cost)."""
    all_pieces(x0, V, radius, W, H, t_final, scr)
    cand = images(min_bounces, max_bounces)
    m = cand.shape[0]
    best = 1 << 30
    nbest = 0
    v = np.empty(2)
    for q in range(m):
        r = q + int(rng_uniform(rng) * (m - q))  # Fisher-Yates: a uniformly random unseen image
        kx = cand[r, 0]
        ky = cand[r, 1]
        cand[r, 0] = cand[q, 0]
        cand[r, 1] = cand[q, 1]
        bank_velocity(x0[i], target[i], radius[i], W, H, t_final, kx, ky, v)
        c = count_conflicts(i, v, x0, radius, W, H, t_final, scr, best)
        if c < best:
            best = c
            nbest = 1
            out[0] = v[0]
            out[1] = v[1]
            if c == 0:
                break
        elif c == best:
            nbest += 1
            if rng_uniform(rng) * nbest < 1.0:  # reservoir: uniform among the ties
                out[0] = v[0]
                out[1] = v[1]
    return best


@njit(cache=True, inline="always", error_model="numpy")
def _strike_point(p, r_sum, T):
    """Where a striker must touch a resting disk at p (contact distance r_sum) to send it
    straight at T: (D = |T - p|, the unit direction n = (T - p) / D, q = p - r_sum n);
    D = 0 (and n = 0, q = p) when p is at T."""
    dx = T[0] - p[0]
    dy = T[1] - p[1]
    D = math.sqrt(dx * dx + dy * dy)
    if D == 0.0:
        return 0.0, 0.0, 0.0, p[0], p[1]
    nx = dx / D
    ny = dy / D
    return D, nx, ny, p[0] - r_sum * nx, p[1] - r_sum * ny


@njit(cache=True, error_model="numpy")
def strike_velocity(pc, rc, mc, ps, rs, ms, T, t_final, out):
    """Velocity of cue disk c (from pc) that strikes resting disk s (at ps) so that s
    flies straight to T and arrives at t_final. Returns t_hit, or -1 if impossible
    (c would have to approach from the far side)."""
    D, nx, ny, qx, qy = _strike_point(ps, rc + rs, T)
    if D == 0.0:
        return -1.0
    A = (qx - pc[0]) * nx + (qy - pc[1]) * ny
    if A <= 0.0:
        return -1.0
    k = strike_ratio(mc, ms)
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
    (default: s's target) at t_final; raises SolveError when c is on the wrong side."""
    T = problem.target[s] if T is None else np.asarray(T, float)
    out = np.empty(2)
    t_hit = strike_velocity(np.ascontiguousarray(problem.start[c]), float(problem.radius[c]), float(problem.mass[c]),
                            np.ascontiguousarray(problem.start[s]), float(problem.radius[s]),
                            float(problem.mass[s]), np.ascontiguousarray(T, dtype=float),
                            float(problem.t_final), out)
    if t_hit < 0:
        raise SolveError(f"disk {c} cannot strike disk {s} towards {tuple(T)}: it would come from the far side")
    return out, t_hit


@njit(cache=True, error_model="numpy")
def chain_strike_velocity(pc, rc, mc, p1, r1, m1, p2, r2, m2, T, t_final, out):
    """Velocity of cue disk c that strikes resting disk 1 so that disk 1, flying
    straight, strikes resting disk 2, which then flies straight to T arriving at
    t_final. Returns the time disk 1 strikes disk 2, or -1 if impossible.

    Disk 2 must leave along n2 = (T - p2)/|T - p2| with speed D2/(t_final - t2):
    disk 1 touches it at q2 = p2 - (r1 + r2) n2 moving along d = (q2 - p1)/L2 at
    speed sigma with sigma (d.n2) k2 = D2/(t_final - t2); c touches disk 1 at
    q1 = p1 - (rc + r1) d with normal speed sigma k1 at t1 = A1/(sigma k1),
    A1 = (q1 - pc).d; and t2 = t1 + L2/sigma. With G = A1/k1 + L2 and c2 = d.n2
    these solve to t2 = G c2 t_final / (G c2 + k2 D2), sigma = G / t2.
    (k = (m_a + m_b) / (2 m_a) = ``strike_ratio(m_a, m_b)`` for striker a and struck b.)"""
    D2, n2x, n2y, q2x, q2y = _strike_point(p2, r1 + r2, T)
    if D2 == 0.0:
        return -1.0
    ex = q2x - p1[0]
    ey = q2y - p1[1]
    L2 = math.sqrt(ex * ex + ey * ey)
    if L2 == 0.0:
        return -1.0
    ddx = ex / L2
    ddy = ey / L2
    c2 = ddx * n2x + ddy * n2y
    if c2 <= 0.0:
        return -1.0
    q1x = p1[0] - (rc + r1) * ddx
    q1y = p1[1] - (rc + r1) * ddy
    A1 = (q1x - pc[0]) * ddx + (q1y - pc[1]) * ddy
    if A1 <= 0.0:
        return -1.0
    k1 = strike_ratio(mc, m1)
    k2 = strike_ratio(m1, m2)
    G = A1 / k1 + L2
    t2 = G * c2 * t_final / (G * c2 + k2 * D2)
    sigma = G / t2
    t1 = A1 / (sigma * k1)
    out[0] = (q1x - pc[0]) / t1
    out[1] = (q1y - pc[1]) / t1
    return t2


# --------------------------------------------------------------------------- two disks, one contact

@njit(cache=True, inline="always", error_model="numpy")
def _pair_residual(sg, tc, D0x, D0y, DTx, DTy, s, T):
    """f(tc) of ``pair_contact`` for contact normal sign sg: (f, nx, ny, D0 . n)."""
    f1 = tc / T
    lx = D0x * (1.0 - f1) + DTx * f1
    ly = D0y * (1.0 - f1) + DTy * f1
    L = math.sqrt(lx * lx + ly * ly)
    if L == 0.0:
        return math.nan, 0.0, 0.0, 0.0
    nx = sg * lx / L
    ny = sg * ly / L
    d0n = D0x * nx + D0y * ny
    return sg * T * L - s * tc - (T - tc) * (2.0 * d0n - s), nx, ny, d0n


@njit(cache=True, error_model="numpy")
def pair_contact(a0, b0, aT, bT, ma, mb, ra, rb, W, H, T, samples, out):
    """Every exact two-disk motion with one contact: disks a and b leave a0 and b0, touch once,
    and are at aT and bT at time T (straight flights, no wall bounce). Writes (vax, vay, vbx, vby,
    tc) per solution into out (K, 5); returns how many (at most K).

    The centre of mass moves uniformly, so at the contact time tc the contact points are
    c(tc) -+ (m_other / M) s n (s = ra + rb). The relative position D goes straight from
    D0 = b0 - a0 to s n, its velocity w reflects in the tangent (w' = w - 2 (w.n) n), then it
    goes straight to DT = bT - aT. Eliminating w and w':  tc DT + (T - tc) D0 = n (s (2 tc - T)
    + 2 (T - tc) D0.n), so n is parallel to D_lin(tc) = D0 + (DT - D0) tc / T (sign sg = +-1)
    and one scalar equation in tc remains: sg T |D_lin| = s (2 tc - T) + 2 (T - tc) D0.n. Its
    roots are bracketed on ``samples`` points of (0, T) and bisected to round-off. A root is
    kept if the pair approaches (D0.n > s: the relative path, straight, then only gets closer
    before the contact and only farther after it, so there is no other contact) and both
    contact points lie in the box."""
    D0x = b0[0] - a0[0]
    D0y = b0[1] - a0[1]
    DTx = bT[0] - aT[0]
    DTy = bT[1] - aT[1]
    s = ra + rb
    M = ma + mb
    k = 0
    for q in range(2):
        sg = 1.0 if q == 0 else -1.0
        t_prev = 0.0
        f_prev = math.nan
        for m in range(1, samples + 1):
            t = T * m / (samples + 1)
            f, _, _, _ = _pair_residual(sg, t, D0x, D0y, DTx, DTy, s, T)
            if m > 1 and f_prev * f < 0.0 and k < out.shape[0]:
                lo = t_prev
                hi = t
                flo = f_prev
                for _ in range(80):
                    mid = 0.5 * (lo + hi)
                    fm, _, _, _ = _pair_residual(sg, mid, D0x, D0y, DTx, DTy, s, T)
                    if (fm < 0.0) == (flo < 0.0):
                        lo = mid
                        flo = fm
                    else:
                        hi = mid
                tc = 0.5 * (lo + hi)
                _, nx, ny, d0n = _pair_residual(sg, tc, D0x, D0y, DTx, DTy, s, T)
                if d0n > s:
                    cx = (ma * (a0[0] + (aT[0] - a0[0]) * tc / T) + mb * (b0[0] + (bT[0] - b0[0]) * tc / T)) / M
                    cy = (ma * (a0[1] + (aT[1] - a0[1]) * tc / T) + mb * (b0[1] + (bT[1] - b0[1]) * tc / T)) / M
                    pax = cx - mb / M * s * nx
                    pay = cy - mb / M * s * ny
                    pbx = cx + ma / M * s * nx
                    pby = cy + ma / M * s * ny
                    if ra <= pax <= W - ra and ra <= pay <= H - ra and rb <= pbx <= W - rb and rb <= pby <= H - rb:
                        out[k, 0] = (pax - a0[0]) / tc
                        out[k, 1] = (pay - a0[1]) / tc
                        out[k, 2] = (pbx - b0[0]) / tc
                        out[k, 3] = (pby - b0[1]) / tc
                        out[k, 4] = tc
                        k += 1
            t_prev = t
            f_prev = f
    return k
