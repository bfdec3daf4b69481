"""The simulator at its edges: degenerate (pinned) contacts and truncated runs.

A disk exactly as wide as its box, or a row of touching disks spanning it, is pinned
between opposite walls: rigid elastic disks would bounce infinitely often at one
instant. The kernel must not spend its whole event cap there (it stops the run as
stalled after ``STALL_EVENTS_PER_DISK`` events per disk), and a run that stops early
must keep every disk inside the box (positions held at its last event, never
extrapolated through the walls).

Problems are built with the ``Problem`` constructor, not the loader: the loader may
refuse such starts, and the kernel must be safe even for inputs it never sees.
"""
from __future__ import annotations

import numpy as np

from nbst.constants import STALL_EVENTS_PER_DISK
from nbst.problem import Problem
from nbst.sim import evaluate, evaluate_events, simulate

#: Positions on a wall are set exactly (W - r); round-off of free flight is far below this.
INSIDE_ATOL = 1e-9


def _problem(box, starts, radii, t_final=1.0) -> Problem:
    starts = np.array(starts, float)
    n = len(starts)
    return Problem(name="edge", box=(float(box[0]), float(box[1])), t_final=float(t_final), target_radius=1.0,
                   start=starts, target=starts.copy(), radius=np.full(n, float(radii)), mass=np.ones(n),
                   cueable=np.ones(n, bool))


def _inside(problem: Problem, pos) -> bool:
    pos = np.asarray(pos, float)
    r = problem.radius
    W, H = problem.box
    x, y = pos[..., 0], pos[..., 1]
    return bool(np.all((x >= r - INSIDE_ATOL) & (x <= W - r + INSIDE_ATOL)
                       & (y >= r - INSIDE_ATOL) & (y <= H - r + INSIDE_ATOL)))


def _check_stalled(problem: Problem, v) -> None:
    tr = simulate(problem, v)
    # stopped as a jam, long before the 200,000-event cap, at t = 0 where it began
    assert tr.truncated and tr.stalled
    assert len(tr.events) <= STALL_EVENTS_PER_DISK * problem.n + 1
    assert tr.end_time == 0.0 and np.isinf(tr.cost)
    assert _inside(problem, tr.final_positions)
    assert _inside(problem, tr.at(np.linspace(0.0, problem.t_final, 11)))
    final, cost, _, n_ev = evaluate_events(problem, np.asarray(v, float)[None])
    assert np.isinf(cost[0]) and n_ev[0] <= STALL_EVENTS_PER_DISK * problem.n + 1
    assert _inside(problem, final[0])


def test_disk_exactly_fitting_its_box_stalls_fast_and_stays_inside():
    p = _problem((40.0, 200.0), [[20.0, 100.0]], 20.0)
    _check_stalled(p, [[3.0, 5.0]])   # was: 200,000 wall events at t = 0, final x = 23 (outside)
    _check_stalled(p, [[3.0, 0.0]])


def test_disk_exactly_fitting_moves_freely_along_its_free_axis():
    # no velocity across the pinned axis: no wall contact is ever predicted there
    p = _problem((40.0, 200.0), [[20.0, 100.0]], 20.0)
    tr = simulate(p, [[0.0, 5.0]])
    assert not tr.truncated and len(tr.events) == 0
    assert np.allclose(tr.final_positions, [[20.0, 105.0]])


def test_grid_of_touching_disks_filling_the_box_stalls_fast_and_stays_inside():
    p = _problem((40.0, 40.0), [[10.0, 10.0], [30.0, 10.0], [10.0, 30.0], [30.0, 30.0]], 10.0)
    _check_stalled(p, [[3.0, 1.0], [0.0, 0.0], [0.0, 0.0], [0.0, 0.0]])


def test_touching_chain_not_spanning_the_box_is_no_jam():
    # Newton's cradle: 5 touching disks struck at t = 0; a finite cascade at one instant
    p = _problem((400.0, 100.0), [[100.0 + 20.0 * k, 50.0] for k in range(5)], 10.0, t_final=1.0)
    v = np.zeros((5, 2))
    v[0] = (50.0, 0.0)
    tr = simulate(p, v)
    assert not tr.truncated and not tr.stalled
    assert np.allclose(tr.final_velocities[-1], [50.0, 0.0]) and np.allclose(tr.final_velocities[:-1], 0.0)


def test_truncated_run_holds_positions_inside_the_box():
    # a disk bouncing between walls for a long time; the event cap stops it early
    p = _problem((100.0, 100.0), [[50.0, 50.0]], 10.0, t_final=1e6)
    v = [[37.0, 23.0]]
    tr = simulate(p, v, max_events=7)
    assert tr.truncated and not tr.stalled and len(tr.events) == 7
    assert tr.end_time == tr.events["time"][-1] < p.t_final
    # was: straight flight to t_final, ~3.7e7 units outside the box
    assert _inside(p, tr.final_positions)
    ts = np.linspace(0.0, p.t_final, 101)
    assert _inside(p, tr.at(ts))
    held = tr.at(np.array([tr.end_time, 0.5 * (tr.end_time + p.t_final), p.t_final]))
    assert np.array_equal(held[0], held[1]) and np.array_equal(held[0], held[2])
    assert np.allclose(tr.final_positions, held[0], atol=INSIDE_ATOL)
    final, cost, _ = evaluate(p, np.array([v], float), max_events=7)
    assert np.isinf(cost[0]) and _inside(p, final[0])
