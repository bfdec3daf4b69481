"""Derivatives of the final positions with respect to the initial velocities.

Within a fixed sequence of collisions the final positions are a smooth function
of the initial velocities; this module carries the tangent map through the event
chain in closed form (no finite differences), over the events ``nbst.sim.run``
records.

Each disk's motion between its events is written in *intercept form*
``p_i(t) = Q_i + V_i t`` (Q_i: where the current straight line was at t = 0).
Per parameter theta we carry dQ_i and dV_i:

* start: Q_i = start_i, V_i = v0_i, so dQ = 0 and dV_i = e_theta for the
  cueable components;
* wall bounce (x wall): V_x' = -V_x and, by continuity at the bounce,
  Q_x' = 2 (W - r) - Q_x (or -Q_x at x = r, up to a constant): so
  dQ_x' = -dQ_x and dV_x' = -dV_x, whatever the bounce time;
* disk-disk contact of i and j at tau: with D = Q_j - Q_i + (V_j - V_i) tau,
  |D| = s gives d tau = -n.(dDQ + tau dDV) / (n.w), n = D / s, w = V_j - V_i;
  the normal turns by dn = (dDQ + tau dDV + w d tau) / s; the impulse
  u = (V_i - V_j).n changes by du = -(dw.n + w.dn); then
  V_i' = V_i - (2 m_j / M) u n,  V_j' = V_j + (2 m_i / M) u n, and continuity
  Q' = Q + (V - V') tau gives dQ' = dQ + (dV - dV') tau + (V - V') d tau;
* end: d final_i = dQ_i + dV_i t_final.

The same carry from an intermediate time gives the state-transition matrix of
the exact motion: a perturbation (dp, dv) of a disk at time t0 is, in intercept
form, dQ = dp - t0 dv, dV = dv, carried through the events after t0
(``carry_tangents`` from event e0; ``transition_jacobian``).

Kernels take arrays (numba); ``final_jacobian(problem, velocities)`` and
``transition_jacobian(problem, velocities, t)`` are the Python wrappers,
``event_record`` the simulation they share.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from nbst.errors import InputError, SolveError
from nbst.problem import Problem
from nbst.sim.kernel import STATUS_OK, alloc_work, run
from nbst.sim.primitives import contact_normal, impulse_share, replay_event, wall_axis


__all__ = ["carry_tangents", "jacobian_from_events", "velocities_before", "transition_from_events", "event_record",
           "final_jacobian", "transition_jacobian"]


@njit(cache=True, error_model="numpy")
def carry_tangents(mass, e0, n_ev, ev_t, ev_i, ev_j, ev_state, V, dQ, dV):
    """Carry intercept-form tangents dQ, dV (N, 2, P) through events e0 .. n_ev - 1, in place.

    V : (N, 2) the velocities just before event e0 (updated in place to those after the last)
    ev_* : the event record of ``run`` (see ``jacobian_from_events``)
    """
    P = dQ.shape[2]
    dDQ = np.empty((2, P))
    dDV = np.empty((2, P))
    dn = np.empty((2, P))
    for e in range(e0, n_ev):
        i = ev_i[e]
        j = ev_j[e]
        tau = ev_t[e]
        if j < 0:
            c = wall_axis(-1 - j)
            for q in range(P):
                dQ[i, c, q] = -dQ[i, c, q]
                dV[i, c, q] = -dV[i, c, q]
            replay_event(e, ev_i, ev_j, ev_state, V)
            continue
        nx, ny, s = contact_normal(ev_state, e)
        wx = V[j, 0] - V[i, 0]
        wy = V[j, 1] - V[i, 1]
        nw = nx * wx + ny * wy  # < 0: approaching
        if nw >= 0.0:
            continue  # a touch without approach: the simulator changed nothing
        u = -nw
        share_i = impulse_share(mass[j], mass[i])
        share_j = impulse_share(mass[i], mass[j])
        for c in range(2):
            for q in range(P):
                dDQ[c, q] = dQ[j, c, q] - dQ[i, c, q]
                dDV[c, q] = dV[j, c, q] - dV[i, c, q]
        for q in range(P):
            # d tau
            a0 = dDQ[0, q] + tau * dDV[0, q]
            a1 = dDQ[1, q] + tau * dDV[1, q]
            dtau = -(nx * a0 + ny * a1) / nw if nw != 0.0 else 0.0
            dn[0, q] = (a0 + wx * dtau) / s
            dn[1, q] = (a1 + wy * dtau) / s
            du = -(dDV[0, q] * nx + dDV[1, q] * ny + wx * dn[0, q] + wy * dn[1, q])
            for c in range(2):
                nc = nx if c == 0 else ny
                Vic = V[i, c]
                Vjc = V[j, c]
                Vi2 = Vic - share_i * u * nc
                Vj2 = Vjc + share_j * u * nc
                dVi2 = dV[i, c, q] - share_i * (du * nc + u * dn[c, q])
                dVj2 = dV[j, c, q] + share_j * (du * nc + u * dn[c, q])
                dQ[i, c, q] = dQ[i, c, q] + (dV[i, c, q] - dVi2) * tau + (Vic - Vi2) * dtau
                dQ[j, c, q] = dQ[j, c, q] + (dV[j, c, q] - dVj2) * tau + (Vjc - Vj2) * dtau
                dV[i, c, q] = dVi2
                dV[j, c, q] = dVj2
        # the velocities after the event (as the simulator computed them)
        replay_event(e, ev_i, ev_j, ev_state, V)


@njit(cache=True, error_model="numpy")
def jacobian_from_events(x0, v0, mass, t_final, cue, n_ev, ev_t, ev_i, ev_j, ev_state, J):
    """Fill J (2N, 2C) with d final[i, c] / d v0[cue[k], d] (row 2i + c, column 2k + d).

    cue : (C,) int64 indices of the cueable disks (the parameters)
    ev_* : the event record of ``run`` for these velocities (n_ev events)
    """
    n = x0.shape[0]
    P = 2 * cue.shape[0]
    dQ = np.zeros((n, 2, P))
    dV = np.zeros((n, 2, P))
    V = v0.copy()
    for k in range(cue.shape[0]):
        dV[cue[k], 0, 2 * k] = 1.0
        dV[cue[k], 1, 2 * k + 1] = 1.0
    carry_tangents(mass, 0, n_ev, ev_t, ev_i, ev_j, ev_state, V, dQ, dV)
    for i in range(n):
        for c in range(2):
            for q in range(P):
                J[2 * i + c, q] = dQ[i, c, q] + dV[i, c, q] * t_final


@njit(cache=True, error_model="numpy")
def velocities_before(v0, e_stop, ev_i, ev_j, ev_state, V):
    """Fill V (N, 2) with the velocities just before event ``e_stop`` (after events 0 .. e_stop - 1).

    Replays the event record with ``nbst.sim.primitives.replay_event``, as ``carry_tangents``
    does, so the two agree bit for bit.
    """
    for i in range(v0.shape[0]):
        V[i, 0] = v0[i, 0]
        V[i, 1] = v0[i, 1]
    for e in range(e_stop):
        replay_event(e, ev_i, ev_j, ev_state, V)


@njit(cache=True, error_model="numpy")
def transition_from_events(v0, mass, t_final, e0, t0, n_ev, ev_t, ev_i, ev_j, ev_state, Phi):
    """Fill Phi (2N, 4N): d final positions / d (positions, velocities) at time t0.

    The perturbation is applied at t0, after events 0 .. e0 - 1 and before event e0
    (t0 between their times); column 2i + c perturbs disk i's position component c,
    column 2N + 2i + c its velocity component c. In intercept form a perturbation
    (dp, dv) at t0 is dQ = dp - t0 dv, dV = dv.
    """
    n = v0.shape[0]
    P = 4 * n
    dQ = np.zeros((n, 2, P))
    dV = np.zeros((n, 2, P))
    for i in range(n):
        for c in range(2):
            dQ[i, c, 2 * i + c] = 1.0
            dQ[i, c, 2 * n + 2 * i + c] = -t0
            dV[i, c, 2 * n + 2 * i + c] = 1.0
    V = np.empty((n, 2))
    velocities_before(v0, e0, ev_i, ev_j, ev_state, V)
    carry_tangents(mass, e0, n_ev, ev_t, ev_i, ev_j, ev_state, V, dQ, dV)
    for i in range(n):
        for c in range(2):
            for q in range(P):
                Phi[2 * i + c, q] = dQ[i, c, q] + dV[i, c, q] * t_final


def event_record(problem: Problem, velocities, *, max_events: int = 100_000):
    """Simulate and keep every event: (final (N, 2), n_ev, ev_t, ev_i, ev_j, ev_state).

    The arrays are ``run``'s record (ev_j = -1 - wall for a wall event; ev_state the
    state of the participants after the event), trimmed to n_ev events.
    RuntimeError if the motion needs more than ``max_events`` events.
    """
    v0 = np.ascontiguousarray(velocities, dtype=np.float64)
    ka = problem.kernel_arrays()
    n = problem.n
    cap = 4096
    while True:
        ev_t = np.empty(cap)
        ev_i = np.empty(cap, np.int64)
        ev_j = np.empty(cap, np.int64)
        ev_s = np.empty((cap, 8))
        final = np.empty((n, 2))
        fvel = np.empty((n, 2))
        st, n_ev, _, _ = run(ka.start, v0, ka.radius, ka.mass, ka.W, ka.H, ka.t_final, alloc_work(n), final, fvel,
                             max_events, ev_t, ev_i, ev_j, ev_s)
        if st == STATUS_OK:
            break
        if n_ev < cap:  # truncated by max_events (or stalled), not by the buffer
            raise SolveError("the motion needs more events than max_events (or jams); no Jacobian")
        cap *= 4
    return final, n_ev, ev_t[:n_ev].copy(), ev_i[:n_ev].copy(), ev_j[:n_ev].copy(), ev_s[:n_ev].copy()


def final_jacobian(problem: Problem, velocities, *, max_events: int = 100_000):
    """(final positions (N, 2), J (2N, 2C)) for the cueable velocity components.

    Row 2i + c is final coordinate c of disk i; column 2k + d is component d of
    the k-th cueable disk's initial velocity. Exact for the collision sequence
    these velocities produce (one-sided at a change of sequence).
    """
    v0 = np.ascontiguousarray(velocities, dtype=np.float64)
    ka = problem.kernel_arrays()
    cue = np.flatnonzero(problem.cueable).astype(np.int64)
    final, n_ev, ev_t, ev_i, ev_j, ev_s = event_record(problem, v0, max_events=max_events)
    J = np.empty((2 * problem.n, 2 * cue.size))
    jacobian_from_events(ka.start, v0, ka.mass, ka.t_final, cue, n_ev, ev_t, ev_i, ev_j, ev_s, J)
    return final, J


def transition_jacobian(problem: Problem, velocities, t: float, *, max_events: int = 100_000):
    """Phi (2N, 4N) = d final positions / d (positions, velocities) at time t of the exact motion.

    Column 2i + c: disk i's position component c at t; column 2N + 2i + c: its velocity
    component c. An event at exactly t counts as before the perturbation. Phi at t = 0
    restricted to the cueable velocity columns is ``final_jacobian``'s J.
    """
    t = float(t)
    if not 0.0 <= t <= float(problem.t_final):
        raise InputError(f"t must lie in [0, t_final = {problem.t_final}], got {t}")
    v0 = np.ascontiguousarray(velocities, dtype=np.float64)
    ka = problem.kernel_arrays()
    _, n_ev, ev_t, ev_i, ev_j, ev_s = event_record(problem, v0, max_events=max_events)
    e0 = int(np.searchsorted(ev_t, t, side="right"))
    Phi = np.empty((2 * problem.n, 4 * problem.n))
    transition_from_events(v0, ka.mass, ka.t_final, e0, t, n_ev, ev_t, ev_i, ev_j, ev_s, Phi)
    return Phi
