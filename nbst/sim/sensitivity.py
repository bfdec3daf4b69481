"""How small errors grow: amplification, velocity tolerance, and a fixed-step prediction.

Everything here is first order, read off the analytic tangent map that
``nbst.sim.jacobian`` carries through the exact event chain:

* **amplification**: J = d(final positions, 2N) / d(initial velocities of the
  cueable disks, 2C); its largest singular value (seconds: units per units/s)
  is the worst growth of a velocity error into a final-position error, and the
  largest singular value of disk i's two rows of J the same for disk i alone.
  A free disk that only meets walls has exactly t_final (a reflection keeps
  lengths).
* **velocity tolerance**: disk i ends d_i from its target; to first order a
  velocity error of 2-norm e moves it by at most sigma_i e, so it keeps its side
  of the target radius R (inside stays inside, outside stays outside) while
  e < |R - d_i| / sigma_i. The minimum over disks is the velocity accuracy that
  keeps the signature.
* **fixed-step prediction** (``timestep=h``): MuJoCo with a fixed step resolves
  every impact one step late (docs/mujoco.md, measured): it acts as if each
  contact surface were moved by one step of approach. A wall bounce comes h late,
  so the disk ends offset by -dv h (dv its velocity jump: 2 |v_n| h). A pair with
  approach speed u meets at contact distance s - u h: h late (each disk offset by
  -dv h) and along the normal of that overlapping configuration, turned by
  dn = h w_t / s (w_t the tangential relative velocity), which changes both
  velocities. Impact k's share of the final error is this perturbation carried
  through the rest of the event chain by the exact motion's transition map
  Phi(t_final <- t_k) (``nbst.sim.jacobian.carry_tangents``). Per disk the shares are
  summed as norms (worst case: ``predicted_error_per_disk``), in quadrature
  (``*_rss``: the typical size of independent errors) and as signed vectors
  (``*_linear``, ``predicted_offset``: the first-order prediction of MuJoCo - exact).

Measured against MuJoCo 4.0.0 (tests/test_sensitivity.py, h = 0.25 ms): wall
bounces match the signed prediction to 1e-8 units (diamond-s14: 15 bounces, final
errors up to 0.34 units). For one oblique pair impact (impact parameter 0.3-0.9 of
2r, 300 units/s) the normal's share matches at mid-step phase (the touch falls
half-way through a step) and is 0.79-1.40 times the model over the phase range
(where in its step the touch falls: unpredictable in practice), its direction off
by up to ~18% of the error; so the linear prediction takes the mid-step value and
the worst case adds ``PHASE_SPREAD`` (half) of the normal's share again.

Assumptions (beyond which the numbers are no prediction):

* first order: valid while the predicted error stays small against the disk
  radius and against the miss distance of every near-grazing pair; an error that
  changes the collision sequence (a contact gained or lost, a different order)
  is outside the model (``within_first_order`` flags errors below the smallest
  radius, a necessary condition only);
* each impact is one isolated contact, resolved within a step or two; contacts
  that overlap in time (a disk pressed against a wall and a disk at once, jams)
  and the energy a contact spring stores meanwhile are not modelled;
* only the motion's own impacts: MuJoCo's free flight, wall reflection and
  head-on impulses are exact (docs/mujoco.md), so no other error source enters.

Compute only: ``analyze`` returns a JSON-ready dict (plain floats, ints, bools,
lists; None where a number would be infinite or undefined).
"""
from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import njit

from nbst.errors import InputError
from nbst.problem import Problem
from nbst.sim.jacobian import carry_tangents, event_record, jacobian_from_events
from nbst.sim.primitives import IMPACT_NONE, IMPACT_PAIR, IMPACT_WALL, contact_normal, impulse_share, replay_event

__all__ = ["PHASE_SPREAD", "late_impact_errors", "analyze"]

#: Worst case: a pair's turned normal counts (1 + PHASE_SPREAD) times its mid-step share;
#: measured 0.79-1.40 times over the phase of the touch within its step (module docstring).
PHASE_SPREAD = 0.5


@njit(cache=True, error_model="numpy")
def late_impact_errors(v0, mass, t_final, h, n_ev, ev_t, ev_i, ev_j, ev_state, err, errn, impact):
    """Each impact's share of the final-position error if it is resolved h late.

    err    : (n_ev, N, 2) filled: row k = d final positions from impact k resolved h late
             (zero for an event that changed no velocity): its disks offset by -dv h and,
             for a pair, the impulse along the normal of the configuration h later
    errn   : (n_ev, N, 2) filled: the part of err due to that turned normal (0 for walls)
    impact : (n_ev,) int64 filled: 1 wall impact, 2 disk-disk impact, 0 no velocity change
    """
    n = v0.shape[0]
    V = v0.copy()
    Va = np.empty((n, 2))
    Vc = np.empty((n, 2))
    dQ = np.zeros((n, 2, 2))  # column 0: the whole late impact; column 1: its turned normal only
    dV = np.zeros((n, 2, 2))
    for k in range(n_ev):
        i = ev_i[k]
        j = ev_j[k]
        for a in range(n):
            Va[a, 0] = V[a, 0]
            Va[a, 1] = V[a, 1]
        impact[k] = replay_event(k, ev_i, ev_j, ev_state, Va)  # Va: the velocities after impact k
        for a in range(n):
            for c in range(2):
                err[k, a, c] = 0.0
                errn[k, a, c] = 0.0
        if impact[k] != IMPACT_NONE:
            for a in range(n):
                for c in range(2):
                    for q in range(2):
                        dQ[a, c, q] = 0.0
                        dV[a, c, q] = 0.0
            for a in (i, j):
                if a < 0:
                    continue
                dQ[a, 0, 0] = -(Va[a, 0] - V[a, 0]) * h  # one step late: the disk kept its old velocity for h
                dQ[a, 1, 0] = -(Va[a, 1] - V[a, 1]) * h
            if j >= 0:
                # a pair meets at contact distance s - u h: h late (the offsets above) and along
                # the normal of that overlapping configuration, turned by dn = h w_t / s
                nx, ny, s = contact_normal(ev_state, k)
                wx = V[j, 0] - V[i, 0]
                wy = V[j, 1] - V[i, 1]
                u = -(nx * wx + ny * wy)
                dnx = h * (wx + u * nx) / s
                dny = h * (wy + u * ny) / s
                du = -(wx * dnx + wy * dny)
                gx = du * nx + u * dnx
                gy = du * ny + u * dny
                tau = ev_t[k]
                dV[i, 0, 0] = -impulse_share(mass[j], mass[i]) * gx
                dV[i, 1, 0] = -impulse_share(mass[j], mass[i]) * gy
                dV[j, 0, 0] = impulse_share(mass[i], mass[j]) * gx
                dV[j, 1, 0] = impulse_share(mass[i], mass[j]) * gy
                for a in (i, j):
                    for c in range(2):
                        dV[a, c, 1] = dV[a, c, 0]
                        dQ[a, c, 1] = -dV[a, c, 0] * tau  # continuity at the contact: Q' = Q + (V - V') tau
                        dQ[a, c, 0] += dQ[a, c, 1]
            for a in range(n):
                Vc[a, 0] = Va[a, 0]
                Vc[a, 1] = Va[a, 1]
            carry_tangents(mass, k + 1, n_ev, ev_t, ev_i, ev_j, ev_state, Vc, dQ, dV)
            for a in range(n):
                for c in range(2):
                    err[k, a, c] = dQ[a, c, 0] + dV[a, c, 0] * t_final
                    errn[k, a, c] = dQ[a, c, 1] + dV[a, c, 1] * t_final
        for a in range(n):
            V[a, 0] = Va[a, 0]
            V[a, 1] = Va[a, 1]


def _num(x) -> float | None:
    """A JSON-ready float: None for inf / nan."""
    x = float(x)
    return x if math.isfinite(x) else None


def _sigma(M: np.ndarray) -> float:
    """Largest singular value (0 for an empty matrix)."""
    return float(np.linalg.svd(M, compute_uv=False)[0]) if M.size else 0.0


def analyze(problem: Problem, velocities, *, timestep: float | None = None) -> dict:
    """Sensitivity of the exact motion of ``velocities`` (N, 2, units/s); JSON-ready dict.

    Keys (units in brackets):

    * ``amplification`` [s]: largest singular value of J = d final positions (2N) /
      d cueable initial velocities (2C); ``per_disk`` [s] (N): of disk i's rows;
    * ``distance_per_disk`` [units]: exact final distance to the target; ``on_target``
      (N bools): within R (the signature); ``margin_per_disk`` [units]: |R - d_i|;
    * ``velocity_tolerance`` [units/s]: the largest velocity error (2-norm over all cueable
      components) that keeps every disk on its side of R to first order:
      min_i |R - d_i| / per_disk[i]; ``velocity_tolerance_per_disk`` (N; None for a
      disk no initial velocity moves); None if no disk responds;
    * with ``timestep`` h [s]: ``prediction`` = {``timestep``, ``impacts`` (wall +
      disk-disk velocity jumps), ``wall_impacts``, ``disk_impacts``, ``predicted_error_max``
      and ``predicted_error_per_disk`` [units] (worst case: sum of norms),
      ``predicted_error_rss_max`` / ``_per_disk`` (root-sum-square),
      ``predicted_error_linear_max`` / ``_per_disk`` and ``predicted_offset`` (N x [dx, dy]:
      the signed first-order MuJoCo - exact), ``keeps_signature_predicted`` (worst case:
      every disk stays on its side of R), ``keeps_signature_predicted_rss``,
      ``within_first_order`` (worst-case error below the smallest disk radius)}.

    RuntimeError if the motion needs more events than the simulator's cap.
    """
    v0 = np.ascontiguousarray(velocities, dtype=np.float64)
    n = problem.n
    if v0.shape != (n, 2):
        raise InputError(f"velocities must have shape ({n}, 2), got {v0.shape}")
    ka = problem.kernel_arrays()
    mass = ka.mass
    cue = np.flatnonzero(problem.cueable).astype(np.int64)
    t_final = ka.t_final
    final, n_ev, ev_t, ev_i, ev_j, ev_s = event_record(problem, v0)
    J = np.empty((2 * n, 2 * cue.size))
    jacobian_from_events(ka.start, v0, mass, t_final, cue, n_ev, ev_t, ev_i, ev_j, ev_s, J)

    R = float(problem.target_radius)
    d = np.hypot(*(final - np.asarray(problem.target, dtype=float)).T)
    on = d * d <= R * R  # as nbst.sim.cost_signature
    margin = np.abs(R - d)
    per_disk = np.array([_sigma(J[2 * i:2 * i + 2]) for i in range(n)])
    tol = [float(margin[i] / per_disk[i]) if per_disk[i] > 0.0 else None for i in range(n)]
    finite = [t for t in tol if t is not None]
    out: dict[str, Any] = {
        "amplification": _num(_sigma(J)),
        "per_disk": [_num(x) for x in per_disk],
        "distance_per_disk": [_num(x) for x in d],
        "on_target": [bool(x) for x in on],
        "margin_per_disk": [_num(x) for x in margin],
        "velocity_tolerance": min(finite) if finite else None,
        "velocity_tolerance_per_disk": tol,
    }
    if timestep is None:
        return out
    h = float(timestep)
    if not (math.isfinite(h) and h > 0.0):
        raise InputError(f"timestep must be a finite number > 0, got {timestep!r}")
    err = np.empty((n_ev, n, 2))
    errn = np.empty((n_ev, n, 2))
    impact = np.empty(n_ev, np.int64)
    late_impact_errors(v0, mass, t_final, h, n_ev, ev_t, ev_i, ev_j, ev_s, err, errn, impact)
    share = np.hypot(err[..., 0], err[..., 1])  # (n_ev, N)
    # a pair's turned normal depends on the unknown phase of the touch: the worst case adds
    # PHASE_SPREAD of its share again
    worst = (share + PHASE_SPREAD * np.hypot(errn[..., 0], errn[..., 1])).sum(axis=0)
    rss = np.sqrt((share * share).sum(axis=0))
    offset = err.sum(axis=0)
    linear = np.hypot(offset[:, 0], offset[:, 1])

    def keeps(e):
        return bool(np.all(np.where(on, d + e <= R, d - e > R)))

    out["prediction"] = {
        "timestep": h,
        "impacts": int(np.count_nonzero(impact)),
        "wall_impacts": int(np.count_nonzero(impact == IMPACT_WALL)),
        "disk_impacts": int(np.count_nonzero(impact == IMPACT_PAIR)),
        "predicted_error_max": _num(worst.max()) if n else 0.0,
        "predicted_error_per_disk": [_num(x) for x in worst],
        "predicted_error_rss_max": _num(rss.max()) if n else 0.0,
        "predicted_error_rss_per_disk": [_num(x) for x in rss],
        "predicted_error_linear_max": _num(linear.max()) if n else 0.0,
        "predicted_error_linear_per_disk": [_num(x) for x in linear],
        "predicted_offset": [[_num(x), _num(y)] for x, y in offset],
        "keeps_signature_predicted": keeps(worst),
        "keeps_signature_predicted_rss": keeps(rss),
        "within_first_order": bool(worst.max() < float(np.min(problem.radius))) if n else True,
    }
    return out
