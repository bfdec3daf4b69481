"""The exact simulator: frictionless elastic disks in a box, event to event.

* ``nbst.sim.primitives``: the physics rules, each written once (contact times, the elastic
  impulse, event replay, mirror images);
* ``nbst.sim.kernel``: the compiled event kernel (numba, arrays only);
* ``nbst.sim.api``: :func:`evaluate` (a batch of candidates: final positions, cost,
  signature) and :func:`simulate` (one motion with its events, a :class:`Trajectory`);
* ``nbst.sim.jacobian``: the analytic Jacobian of the final state, carried through the events;
* ``nbst.sim.sensitivity``: how a velocity error grows into a final error, and what that
  predicts for a fixed-step engine.

Layer: above the problem model (``nbst.problem``, ``nbst.solution``, ``nbst.constants``),
below the search. Nothing here imports the search, MuJoCo or the renderer.
"""
from __future__ import annotations

from nbst.sim.api import EVENT_DTYPE, Trajectory, evaluate, evaluate_events, simulate
from nbst.sim.kernel import (STATUS_OK, STATUS_OVERFLOW, STATUS_STALLED, STATUS_TRUNCATED, SimStatus, alloc_work,
                             cost_signature, evaluate_kernel, run)
from nbst.sim.primitives import INF, pair_tau, wall_tau

__all__ = ["EVENT_DTYPE", "INF", "STATUS_OK", "STATUS_OVERFLOW", "STATUS_STALLED", "STATUS_TRUNCATED", "SimStatus",
           "Trajectory",
           "alloc_work", "cost_signature", "evaluate", "evaluate_events", "evaluate_kernel", "pair_tau", "run", "simulate", "wall_tau"]
