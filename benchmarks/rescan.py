"""A plain event-driven kernel that rescans every pair and wall after each event
(O(N^2) per event): the baseline that ``bench_sim.py`` compares nbst's kernel with.
Same closed forms as nbst.sim, no caching of predictions."""
import math

import numpy as np
from numba import njit

from nbst.sim import cost_signature, pair_tau, wall_tau


@njit(cache=True, error_model="numpy")
def run_rescan(x0, v0, radius, mass, W, H, t_final, out_final):
    n = x0.shape[0]
    p = x0.copy()
    v = v0.copy()
    t = 0.0
    n_ev = 0
    while True:
        best = math.inf
        bi = -1
        bj = -1
        bw = -1
        for i in range(n):
            tw, w = wall_tau(p[i, 0], p[i, 1], v[i, 0], v[i, 1], radius[i], W, H)
            if tw < best:
                best, bi, bj, bw = tw, i, -1, w
            for k in range(i + 1, n):
                tk = pair_tau(p[k, 0] - p[i, 0], p[k, 1] - p[i, 1], v[k, 0] - v[i, 0], v[k, 1] - v[i, 1],
                              radius[i] + radius[k], math.inf)
                if tk < best:
                    best, bi, bj = tk, i, k
        if t + best > t_final:
            break
        for i in range(n):
            p[i, 0] += v[i, 0] * best
            p[i, 1] += v[i, 1] * best
        t += best
        n_ev += 1
        if bj < 0:
            if bw <= 1:
                v[bi, 0] = -v[bi, 0]
            else:
                v[bi, 1] = -v[bi, 1]
        else:
            nx = p[bj, 0] - p[bi, 0]
            ny = p[bj, 1] - p[bi, 1]
            d = math.sqrt(nx * nx + ny * ny)
            nx /= d
            ny /= d
            u = (v[bi, 0] - v[bj, 0]) * nx + (v[bi, 1] - v[bj, 1]) * ny
            if u > 0.0:
                fi = 2.0 * mass[bj] / (mass[bi] + mass[bj]) * u
                fj = 2.0 * mass[bi] / (mass[bi] + mass[bj]) * u
                v[bi, 0] -= fi * nx
                v[bi, 1] -= fi * ny
                v[bj, 0] += fj * nx
                v[bj, 1] += fj * ny
    for i in range(n):
        out_final[i, 0] = p[i, 0] + v[i, 0] * (t_final - t)
        out_final[i, 1] = p[i, 1] + v[i, 1] * (t_final - t)
    return n_ev


@njit(cache=True, error_model="numpy")
def evaluate_rescan(x0, V, radius, mass, target, W, H, t_final, R, final, cost, sig, n_events):
    for b in range(V.shape[0]):
        n_events[b] = run_rescan(x0, V[b], radius, mass, W, H, t_final, final[b])
        c, s = cost_signature(final[b], target, R)
        cost[b] = c
        sig[b] = s
