"""The one rollout-search engine (nbst.models.mjsearch.engine) on synthetic problems: no physics.

The problem: three blocks of two coordinates; block i meets its fate when its point lies within
0.03 of a hidden target (bit i of the signature); the distance is the number of blocks missed.
Claims: it solves, its stop reasons, the same seed gives the same points, Ctrl-C keeps the best
so far, crossover moves whole blocks (each from the parent that meets it), and the polishing
restarts leave a spent funnel.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from nbst.errors import InputError
from nbst.models.mjsearch.engine import Engine

TARGET = np.array([0.2, 0.7, 0.9, 0.1, 0.5, 0.5])
BLOCKS = [[0, 1], [2, 3], [4, 5]]


def blocks_problem(U):
    d = np.array([[np.linalg.norm(u[b] - TARGET[b]) for b in BLOCKS] for u in np.atleast_2d(U)])
    met = d < 0.03
    return (met * (1 << np.arange(3))).sum(axis=1), 3 - met.sum(axis=1), d.sum(axis=1)


def test_the_engine_solves_a_block_problem_and_says_why_it_stopped():
    """Seeds 1-3, 3,000 rollouts: every block within 0.03 of its target (a 1/350 chance per block
    for a uniform point) well inside the budget."""
    for seed in (1, 2, 3):
        r = Engine(6, seed=seed, max_rollouts=3000, blocks=BLOCKS).run(blocks_problem)
        assert r.stopped == {"solved": r.rollouts} and r.distance == 0 and r.signature == 0b111
        assert r.rollouts < 1500 and np.all(np.abs(r.x - TARGET) < 0.03)
        assert r.history[-1] == (r.rollouts, 0, r.cost) and r.best.index <= r.rollouts


def test_the_same_seed_gives_the_same_points_and_another_seed_others():
    a = Engine(6, seed=7, max_rollouts=400, blocks=BLOCKS).run(blocks_problem)
    b = Engine(6, seed=7, max_rollouts=400, blocks=BLOCKS).run(blocks_problem)
    c = Engine(6, seed=8, max_rollouts=400, blocks=BLOCKS).run(blocks_problem)
    assert np.array_equal(a.x, b.x) and a.rollouts == b.rollouts and a.history == b.history
    assert not np.array_equal(a.x, c.x)


def test_the_budget_is_kept_to_the_rollout_and_stop_says_so():
    """An impossible signature: the search spends exactly the budget (asks never pass what is
    left; a told batch's extra rollouts, as a ladder check's, count) and stops with "budget"."""
    def never(U):
        s, d, c = blocks_problem(U)
        return {"signatures": s * 0, "distances": d * 0 + 3, "costs": c, "rollouts": len(U) + 1}

    e = Engine(6, seed=1, max_rollouts=101, blocks=BLOCKS, batch=10)
    r = e.run(never)
    assert r.stopped == {"budget": 101} and 101 <= r.rollouts <= 101 + 10
    assert e.ask().shape == (0, 6) and r.distance == 3
    e2 = Engine(6, seed=1, max_rollouts=25, blocks=BLOCKS, batch=10)
    sizes = []
    while not e2.stop():
        U = e2.ask()
        sizes.append(len(U))
        e2.tell(U, *blocks_problem(U))
    assert sum(sizes) == e2.rollouts == 25 and max(sizes) <= 16


def test_ctrl_c_keeps_the_best_so_far_and_before_any_point_raises():
    calls = []

    def stop_second(U):
        calls.append(len(U))
        if len(calls) == 2:
            raise KeyboardInterrupt
        return blocks_problem(U)

    r = Engine(6, seed=1, max_rollouts=3000, blocks=BLOCKS).run(stop_second)
    assert r.stopped.get("interrupted") is True and r.rollouts == calls[0] == 16
    s, d, c = blocks_problem(r.x)
    assert (r.distance, r.cost) == (d[0], pytest.approx(c[0]))

    def stop_first(U):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        Engine(6, seed=1, max_rollouts=3000, blocks=BLOCKS).run(stop_first)


def test_crossover_moves_whole_blocks_from_the_parent_that_meets_them():
    """A population of two: A meets block 0 only, B block 1 only. Every child keeps at least one
    whole block of a parent (the others change one block), the engineered child A0|B1 appears,
    and B0|A1 (each block from the parent that misses it) never does."""
    e = Engine(4, seed=3, max_rollouts=10_000, blocks=[[0, 1], [2, 3]], batch=2, explore=2, cma=False)
    U = e.ask()
    e.tell(U, [0b01, 0b10], [1, 1], [1.0, 1.0])
    A, B = U
    kinds = set()
    for _ in range(200):
        for u in e.ask():  # the GA's children (not told: the population stays A and B)
            src = tuple("A" if np.array_equal(u[b], A[b]) else "B" if np.array_equal(u[b], B[b]) else "-"
                        for b in ([0, 1], [2, 3]))
            assert src.count("-") <= 1, u
            kinds.add(src)
    assert ("A", "B") in kinds and ("B", "A") not in kinds
    assert {("A", "-"), ("-", "A"), ("B", "-"), ("-", "B")} <= kinds


def test_polishing_restarts_leave_a_spent_funnel_for_a_far_fine_point():
    """With the best point fine, restarts start from it at sigma0, /3, /9; once ``spent`` of them
    in a row left its cost as it was (and the best is farther than ``hold_distance``), the next
    starts from the cheapest fine point at least one sigma0 step (sigma0 sqrt(dim)) from every
    start so far, at sigma0 (a near one is passed over); with none left, from the best again. A
    best at ``hold_distance`` is polished where it is. No rollout is run."""
    e = Engine(4, seed=0, max_rollouts=100, sigma0=0.1, spent=3)
    X = np.array([[0.5] * 4, [0.51] * 4, [0.95] * 4])
    e.tell(X, [1, 1, 1], [2, 2, 2], [1.0, 1.5, 3.0], fine=[True, True, True])
    best, near, far = (e.archive[1], *[m for m in e.right[1:]])
    assert e.best is best and np.array_equal(best.u, X[0])
    assert e.restart_point()[1:] == (0.1, best)
    assert e.restart_point()[1] == pytest.approx(0.1 / 3)
    e._spent = 3
    assert np.linalg.norm(near.u - best.u) < 0.1 * math.sqrt(4) <= np.linalg.norm(far.u - best.u)
    best.distance = 1  # at hold_distance: polished where it is
    u, sigma, m = e.restart_point()
    assert m is best and sigma == pytest.approx(0.1 / 9)
    best.distance = 2
    assert e.restart_point()[1:] == (0.1, far)
    assert e.restart_point()[2] is best  # every fine point is near a start now


def test_a_spent_funnel_with_no_other_fine_point_wanders_and_spent_gain_counts_small_gains_as_spent():
    """``wander``: the best's funnel spent and no other fine point far from every start, the next
    restart starts from the cheapest point told that is not fine and lies one sigma0 step
    (sigma0 sqrt(dim)) from every start, at sigma0, and with no member (a point near a start is
    passed over); without ``wander`` the best is polished again. ``spent_gain`` g: a polishing
    restart that lowered the best's cost by less than the fraction g counts as spent. No rollout."""
    X = np.array([[0.5] * 4, [0.51] * 4, [0.55] * 4, [0.9] * 4, [0.1] * 4])
    for wander in (False, True):
        e = Engine(4, seed=0, max_rollouts=100, sigma0=0.1, spent=1, hold_distance=0, wander=wander)
        e.tell(X, [3, 3, 1, 1, 0], [1, 1, 3, 3, 6], [10.0, 11.0, 0.5, 2.0, 1.0],
               fine=[True, True, False, False, False])
        assert e.restart_point()[2] is e.best
        e._spent = 1
        u, sigma, m = e.restart_point()
        if wander:  # [0.55]*4 is the cheaper but near the start; [0.9]*4 is far (distance 3 < 6)
            assert m is None and sigma == pytest.approx(0.1) and np.array_equal(u, X[3])
            assert np.array_equal(e.restart_point()[0], X[4])  # the next far one (it costs more)
            assert e.restart_point()[2] is e.best  # every point is near a start now
        else:
            assert m is e.best and sigma == pytest.approx(0.1 / 3)
    for gain, spent in ((0.0, 0), (0.5, 1)):
        e = Engine(4, seed=0, max_rollouts=100, spent_gain=gain)
        e.tell(X[:1], [3], [1], [10.0], fine=[True])
        e._es_state = {"polishing": True, "before": 10.0}
        e.best.cost = 9.0  # 10 % lower
        e._end_restart()
        assert e._spent == spent
    with pytest.raises(InputError):
        Engine(4, seed=0, max_rollouts=100, spent_gain=1.5)


def _changed_blocks(u, parent, blocks):
    return tuple(i for i, b in enumerate(blocks) if not np.array_equal(u[b], parent[b]))


@pytest.mark.parametrize("redraw", [0.0, 1.0])
def test_redraw_unmet_redraws_every_unmet_block_of_the_parent_and_no_met_one(redraw):
    """A population of one, P, meeting block 0 of three. The paper's children change one block;
    with ``redraw_unmet=1`` the randomizing ones redraw blocks 1 and 2 together (independent bodies
    searched side by side) and never touch block 0, which only creep may move, alone."""
    blocks = [[0, 1], [2, 3], [4, 5]]
    e = Engine(6, seed=5, max_rollouts=10_000, blocks=blocks, batch=1, explore=1, cma=False, redraw_unmet=redraw)
    U = e.ask()
    e.tell(U, [0b001], [2], [1.0])
    P = U[0]
    kinds = set()
    for _ in range(300):
        for u in e.ask():  # not told: the population stays P
            kinds.add(_changed_blocks(u, P, blocks))
    if redraw:
        assert (1, 2) in kinds
        assert all(k == (1, 2) or len(k) <= 1 for k in kinds), kinds
    else:
        assert all(len(k) <= 1 for k in kinds) and {(0,), (1,), (2,)} <= kinds, kinds


def test_nothing_to_search_is_one_point_and_bad_settings_are_refused():
    e = Engine(0, seed=1, max_rollouts=10)
    U = e.ask()
    assert U.shape == (1, 0)
    e.tell(U, [0], [1], [0.5])
    assert e.stop() == {"nothing_to_search": True} and e.result.rollouts == 1
    for kw in ({"max_rollouts": 0}, {"max_rollouts": 5, "blocks": [[0, 7]]}, {"max_rollouts": 5, "bits": [0, 1]},
               {"max_rollouts": 5, "schedule": (("nowhere", 1.0),)}, {"max_rollouts": 5, "redraw_unmet": 1.5}):
        with pytest.raises(InputError):
            Engine(3, seed=1, **kw)
    e = Engine(3, seed=1, max_rollouts=5)
    with pytest.raises(InputError):
        e.tell(e.ask(), [0], [1], [1.0])


def test_cma_by_key_follows_the_distance_where_the_cost_misleads():
    """Four coordinates; the distance is 0 within 0.05 of a hidden point and grows by 1 per 0.05
    farther, while the cost (-|u - c|) prefers the far corners. Ranked by (distance, cost)
    (``cma_by_key``), the CMA-ES restarts reach distance 0 within 300 rollouts at seeds 1-3;
    ranked by the cost alone (the default) each generation runs to the corners, and only the
    restarts from the best point get there, later (384 to 1,824 rollouts at these seeds)."""
    c = np.array([0.3, 0.6, 0.4, 0.7])

    def misleading(U):
        d = np.linalg.norm(np.atleast_2d(U) - c, axis=1)
        return np.zeros(len(d), dtype=int), np.ceil(np.maximum(d - 0.05, 0.0) / 0.05).astype(int), -d

    for seed in (1, 2, 3):
        kw = dict(seed=seed, max_rollouts=300, explore=16, ga_batches=0, cma=True)
        by_key = Engine(4, cma_by_key=True, **kw).run(misleading)
        by_cost = Engine(4, **kw).run(misleading)
        assert "solved" in by_key.stopped and np.linalg.norm(by_key.x - c) < 0.05
        assert by_cost.stopped == {"budget": 300} and by_cost.distance > 0


def test_explore_batches_ask_small_first_batches_of_the_same_points_and_stop_at_the_first_that_solves():
    """``explore_batches=(1, 1, 2, 4)``: the exploring phase asks 1, 1, 2, 4, then ``batch`` points,
    the same points in the same order as batches of 8 (no population is drawn from while
    exploring); a problem whose third uniform point solves it stops after the batch of 2 that
    holds it (4 rollouts), where batches of 8 roll out 8. Sizes under 1 are refused."""
    def sizes_and_points(**kw):
        e = Engine(2, seed=4, max_rollouts=100, batch=8, explore=16, ga_batches=0, cma=True, **kw)
        sizes, pts = [], []
        while e._phase == "explore" and not e.stop():
            U = e.ask()
            if e._pending[1] != "explore":
                break
            sizes.append(len(U))
            pts.append(U)
            e.tell(U, [0] * len(U), [1] * len(U), [1.0] * len(U))
        return sizes, np.vstack(pts)

    small, p_small = sizes_and_points(explore_batches=(1, 1, 2, 4))
    eight, p_eight = sizes_and_points()
    assert small == [1, 1, 2, 4, 8] and eight == [8, 8]
    assert np.array_equal(p_small, p_eight)
    third = p_eight[2]

    def solved_at_third(U):
        hit = np.all(np.isclose(np.atleast_2d(U), third), axis=1)
        return np.zeros(len(hit), dtype=int), np.where(hit, 0, 1), np.where(hit, 0.0, 1.0)

    kw = dict(seed=4, max_rollouts=100, batch=8, explore=16, ga_batches=0, cma=True)
    assert Engine(2, explore_batches=(1, 1, 2, 4), **kw).run(solved_at_third).rollouts == 4
    assert Engine(2, **kw).run(solved_at_third).rollouts == 8
    with pytest.raises(InputError):
        Engine(2, seed=1, max_rollouts=5, explore_batches=(1, 0))
