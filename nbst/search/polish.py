"""Local polish: Levenberg-Marquardt on the initial velocities, with the analytic
Jacobian of ``nbst.sim.jacobian``.

Each step linearizes the final positions within the current collision sequence,
solves ``(J^T J + lam (diag(J^T J) + eps)) d = -J^T r`` (r = final - target), and
is accepted only if the *true* simulated cost drops; otherwise lam grows and the
step shrinks. So polish never returns a worse solution, and a step that changes
the collision sequence is kept only when it helps. Every simulation it runs is
counted (``n_sims``), so a search can charge polish as the trials it costs.

A disk that meets nothing moves as a fold of a straight line: its block of J is
+-t_final I, and the first accepted step aims it exactly.
"""
from __future__ import annotations

import math
from enum import IntEnum
from typing import NamedTuple

import numpy as np
from numba import njit

from nbst.errors import InputError
from nbst.problem import Problem
from nbst.search.ops import limit_crossings
from nbst.sim import STATUS_OK, alloc_work, cost_signature, run
from nbst.sim.jacobian import jacobian_from_events

#: Initial damping, relative to diag(J^T J).
LAMBDA0 = 1e-3
#: Damping bounds: below, steps are Gauss-Newton; above, give up (no descent found).
LAMBDA_MIN, LAMBDA_MAX = 1e-12, 1e10
#: Ridge added to the damped diagonal, relative to its largest entry (keeps
#: columns of disks that influence nothing from making the system singular).
RIDGE = 1e-12
#: Event buffer for polish runs; a candidate that needs more is rejected.
POLISH_EVENT_CAP = 4096
#: Damping factor after a rejected step: lam *= LAMBDA_UP (a shorter, more gradient-like step).
LAMBDA_UP = 4.0
#: Damping factor when the damped system is not positive definite: a larger jump than
#: LAMBDA_UP, since no step can even be computed at this damping.
LAMBDA_UP_SINGULAR = 10.0
#: Damping divisor after an accepted step: lam /= LAMBDA_DOWN (towards Gauss-Newton). Down by
#: 3, up by 4: the classic asymmetric Levenberg-Marquardt schedule, so an accept-reject cycle
#: ends with more damping than it started with and the damping cannot oscillate.
LAMBDA_DOWN = 3.0


class PolishStop(IntEnum):
    """Why ``polish_kernel`` stopped."""

    TOLERANCE = 0  # the cost reached tol
    BUDGET = 1  # max_sims simulations were run
    NO_DESCENT = 2  # no damped step lowered the cost (lam reached LAMBDA_MAX, or J is zero)
    INFEASIBLE = 3  # the starting velocities do not simulate within POLISH_EVENT_CAP events


@njit(cache=True, error_model="numpy")
def _cholesky_solve(A, b, out):
    """Solve A x = b for symmetric positive definite A (P x P); False if not SPD."""
    P = A.shape[0]
    L = np.zeros((P, P))
    for i in range(P):
        for j in range(i + 1):
            s = A[i, j]
            for k in range(j):
                s -= L[i, k] * L[j, k]
            if i == j:
                if s <= 0.0:
                    return False
                L[i, i] = math.sqrt(s)
            else:
                L[i, j] = s / L[j, j]
    y = np.empty(P)
    for i in range(P):
        s = b[i]
        for k in range(i):
            s -= L[i, k] * y[k]
        y[i] = s / L[i, i]
    for i in range(P - 1, -1, -1):
        s = y[i]
        for k in range(i + 1, P):
            s -= L[k, i] * out[k]
        out[i] = s / L[i, i]
    return True


class PolishScratch(NamedTuple):
    """Scratch of ``polish_kernel``: the event records of the current velocities (``cur_*``)
    and of a candidate step (``new_*``; the two swap on an accepted step), and the linear
    algebra (P = 2 x cueable disks)."""

    cur_t: np.ndarray  # (cap,) event times
    cur_i: np.ndarray  # (cap,) int64 first disk
    cur_j: np.ndarray  # (cap,) int64 second disk, or -1 - wall
    cur_state: np.ndarray  # (cap, 8) participants' state after the event
    new_t: np.ndarray
    new_i: np.ndarray
    new_j: np.ndarray
    new_state: np.ndarray
    J: np.ndarray  # (2N, P) Jacobian of the final positions
    A: np.ndarray  # (P, P) J^T J
    g: np.ndarray  # (P,) J^T r
    d: np.ndarray  # (P,) the step
    final: np.ndarray  # (N, 2) final positions of the current velocities
    fvel: np.ndarray  # (N, 2) final velocities (unused, the kernel writes them)
    vnew: np.ndarray  # (N, 2) the candidate velocities
    fnew: np.ndarray  # (N, 2) their final positions


@njit(cache=True)
def alloc_polish(n, n_cue, cap):
    """Scratch for ``polish_kernel``: a :class:`PolishScratch`."""
    return PolishScratch(np.empty(cap), np.empty(cap, np.int64), np.empty(cap, np.int64), np.empty((cap, 8)),
                         np.empty(cap), np.empty(cap, np.int64), np.empty(cap, np.int64), np.empty((cap, 8)),
                         np.empty((2 * n, 2 * n_cue)), np.empty((2 * n_cue, 2 * n_cue)), np.empty(2 * n_cue),
                         np.empty(2 * n_cue), np.empty((n, 2)), np.empty((n, 2)), np.empty((n, 2)), np.empty((n, 2)))


@njit(cache=True, error_model="numpy")
def polish_kernel(x0, v, radius, mass, target, W, H, t_final, R, cue, max_sims, tol, work, scratch):
    # Fourteen parameters on purpose: called by nbst's loop and by the ``polish`` wrapper with the
    # problem's flat arrays (numba); the scratch is one PolishScratch.
    """Polish ``v`` (N, 2) in place. Returns (cost, signature, simulations run, PolishStop).

    Stops when the cost is <= tol, after max_sims simulations, or when no damped
    step lowers the cost.
    """
    (ct, ci, cj, cs, nt, ni, nj, ns, J, A, g, d, final, fvel, vnew, fnew) = scratch
    n = x0.shape[0]
    C = cue.shape[0]
    P = 2 * C
    cap = ct.shape[0]
    st, n_ev, _, _ = run(x0, v, radius, mass, W, H, t_final, work, final, fvel, cap, ct, ci, cj, cs)
    sims = 1
    cost, sig = cost_signature(final, target, R)
    if st != STATUS_OK:
        return math.inf, np.int64(0), sims, PolishStop.INFEASIBLE
    lam = LAMBDA0
    why = PolishStop.BUDGET
    while sims < max_sims and cost > tol:
        jacobian_from_events(x0, v, mass, t_final, cue, n_ev, ct, ci, cj, cs, J)
        # A = J^T J, g = J^T r
        for p in range(P):
            acc = 0.0
            for r in range(2 * n):
                acc += J[r, p] * (final[r // 2, r % 2] - target[r // 2, r % 2])
            g[p] = acc
            for q in range(p + 1):
                acc = 0.0
                for r in range(2 * n):
                    acc += J[r, p] * J[r, q]
                A[p, q] = acc
                A[q, p] = acc
        dmax = 0.0
        for p in range(P):
            dmax = max(dmax, A[p, p])
        if dmax == 0.0:
            why = PolishStop.NO_DESCENT
            break
        accepted = False
        while sims < max_sims and lam < LAMBDA_MAX:
            M = A.copy()
            for p in range(P):
                M[p, p] += lam * A[p, p] + RIDGE * dmax * (1.0 + lam)
            for p in range(P):
                g[p] = -g[p]
            ok = _cholesky_solve(M, g, d)
            for p in range(P):
                g[p] = -g[p]
            if not ok:
                lam *= LAMBDA_UP_SINGULAR
                continue
            for i in range(n):
                vnew[i, 0] = v[i, 0]
                vnew[i, 1] = v[i, 1]
            for k in range(C):
                vnew[cue[k], 0] += d[2 * k]
                vnew[cue[k], 1] += d[2 * k + 1]
            limit_crossings(vnew, cue, radius, W, H, t_final)  # a step never leaves the accepted domain
            st2, n_ev2, _, _ = run(x0, vnew, radius, mass, W, H, t_final, work, fnew, fvel, cap, nt, ni, nj, ns)
            sims += 1
            c2 = math.inf
            s2 = np.int64(0)
            if st2 == STATUS_OK:
                c2, s2 = cost_signature(fnew, target, R)
            if c2 < cost:
                accepted = True
                cost = c2
                sig = s2
                n_ev = n_ev2
                for i in range(n):
                    v[i, 0] = vnew[i, 0]
                    v[i, 1] = vnew[i, 1]
                    final[i, 0] = fnew[i, 0]
                    final[i, 1] = fnew[i, 1]
                ct, nt = nt, ct
                ci, ni = ni, ci
                cj, nj = nj, cj
                cs, ns = ns, cs
                lam = max(lam / LAMBDA_DOWN, LAMBDA_MIN)
                break
            lam *= LAMBDA_UP
        if not accepted:
            if sims < max_sims:
                why = PolishStop.NO_DESCENT
            break
    if cost <= tol:
        why = PolishStop.TOLERANCE
    return cost, sig, sims, why


def polish(problem: Problem, velocities, *, max_sims: int = 100, tol: float = 0.0):
    """Polish one velocity set. Returns (velocities (N, 2), cost, signature, simulations).

    The result's cost is never above the input's (simulated, not linearized).
    """
    v = np.array(velocities, dtype=np.float64, order="C")
    if v.shape != (problem.n, 2):
        raise InputError(f"velocities have shape {v.shape}; expected ({problem.n}, 2)")
    cue = np.flatnonzero(problem.cueable).astype(np.int64)
    n = problem.n
    scratch = alloc_polish(n, cue.size, POLISH_EVENT_CAP)
    ka = problem.kernel_arrays()
    cost, sig, sims, _ = polish_kernel(ka.start, v, ka.radius, ka.mass, ka.target, ka.W, ka.H, ka.t_final, ka.R, cue,
                                       int(max_sims), float(tol), alloc_work(n), scratch)
    return v, float(cost), int(sig), int(sims)


__all__ = ["POLISH_EVENT_CAP", "PolishScratch", "PolishStop", "alloc_polish", "polish", "polish_kernel"]
