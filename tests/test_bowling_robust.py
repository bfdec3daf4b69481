"""Throws that hold up (issue 22): the probability of an exact outcome, and robust.maximise
(models/bowling/noise.py, robust.py)."""
from __future__ import annotations

from dataclasses import replace

import pytest

mujoco = pytest.importorskip("mujoco")

from nbst.models.bowling import lane  # noqa: E402
from nbst.models.bowling.lane import frame, noise, robust, spares

#: The 2-8 leave from the 3-6-9 line (it converts about 3 throws in 4 under the default noise,
#: docs/bowling.md) moved a board off it, so a small search has failures to work on.
LEAVE = [2, 8]
START = replace(spares.system_369("2-8"), board=spares.system_369("2-8").board - 1.0)
BUDGET, N, SEED = 60, 8, 3


def _result(down, in_play=tuple(range(1, 11))) -> frame.FrameResult:
    down = sorted(down)
    return frame.FrameResult(delivery={}, oil="house", timestep=0.001, in_play=list(in_play), down=down,
                             leave=[p for p in in_play if p not in down], knocked=down, off_deck=[], partition=[],
                             ball_left_lane=False, ball_at_pins_s=2.0, board_at_pins=17.5, entry_angle_deg=5.0,
                             settled=True, settle_s=5.0, cap_hit=False, seconds=5.0)


def test_the_estimate_with_want_counts_exact_outcomes_only():
    rs = [_result([2, 8]), _result([2]), _result([2, 8, 9]), _result([8, 2]), _result(range(1, 11))]
    e = noise.estimate(rs, 1, want=[8, 2])
    assert (e.k, e.n) == (2, 5)  # [2, 8] twice; a subset or a superset is not the outcome
    assert noise.estimate(rs, 1).k == 1  # the default: every pin in play down (the strike)
    assert noise.estimate(rs, 1, want=list(range(1, 11))).k == 1
    assert noise.estimate(rs, 1, want=[]).k == 0
    with pytest.raises(ValueError, match="want"):
        noise.estimate(rs, 1, want=[0, 3])


def test_probability_with_want_on_real_frames_matches_the_frames():
    with frame.FrameRunner(jobs=1) as R:
        e, rs = noise.probability(START, 6, 5, runner=R, standing=LEAVE, want=[2])
        e_all, _ = noise.probability(START, 6, 5, runner=R, standing=LEAVE)
        e_same, _ = noise.probability(START, 6, 5, runner=R, standing=LEAVE, want=LEAVE)
    assert e.k == sum(1 for r in rs if r.down == [2])
    assert e_all.k == sum(1 for r in rs if not r.leave)
    assert e_same.to_dict() == e_all.to_dict()  # on a leave, want = every pin in play is the default


@pytest.fixture(scope="module")
def one():
    with frame.FrameRunner(jobs=1) as R:
        return robust.maximise(START, standing=LEAVE, runner=R, budget=BUDGET, seed=SEED, n=N)


def test_maximise_is_reproducible_from_its_seed_on_1_and_2_processes(one):
    with frame.FrameRunner(jobs=2) as R:
        two = robust.maximise(START, standing=LEAVE, runner=R, budget=BUDGET, seed=SEED, n=N)
    assert one.to_dict() == two.to_dict()


def test_maximise_is_never_worse_on_its_screen_than_its_start(one):
    assert one.screen.n == one.start_screen.n and one.screen.seed == one.start_screen.seed
    assert one.screen.k >= one.start_screen.k
    ks = [h["incumbent"] for h in one.history]
    assert ks == sorted(ks)  # the incumbent's (outcomes, pins right) on the common throws only rises
    assert one.frames <= BUDGET + N + 3 * robust.LADDER_TRIES * len(frame.LADDER)


def test_maximise_carries_a_fresh_seed_estimate_and_a_ladder(one):
    assert (one.estimate.n, one.estimate.seed) == (N, SEED)
    assert one.screen.seed != SEED  # the search ran on other throws than the measure
    with frame.FrameRunner(jobs=1) as R:
        again, _ = noise.probability(one.delivery, N, SEED, runner=R, standing=LEAVE)
    assert again.to_dict() == one.estimate.to_dict()  # a plain measure, not the search's score
    assert [row[0] for row in one.ladder] == list(frame.LADDER)
    if one.ladder_holds:
        assert all(row[1] == [] for row in one.ladder)
    assert one.delivery.hand == START.hand and one.delivery.at == "foul"


def test_maximise_with_want_climbs_towards_an_exact_outcome_and_keeps_it_on_the_ladder():
    # on the 2-8, knock down the 2 only; start from the throw that converts it (both down)
    with frame.FrameRunner(jobs=1) as R:
        r = robust.maximise(START, standing=LEAVE, want=[2], runner=R, budget=40, seed=2, n=4)
    assert r.want == [2]
    assert r.screen.k >= r.start_screen.k
    if r.ladder_holds:
        assert all(row[2] == [2] for row in r.ladder)


def test_ctrl_c_keeps_the_best_so_far():
    count = [0]

    def stop():
        count[0] += 1
        if count[0] == 15:
            raise KeyboardInterrupt

    with frame.FrameRunner(jobs=1) as R:
        with pytest.raises(robust.Interrupted) as ex:
            robust.maximise(START, standing=LEAVE, runner=R, budget=BUDGET, seed=SEED, on_done=stop)
    assert isinstance(ex.value, KeyboardInterrupt)
    assert isinstance(ex.value.best, lane.Delivery)


def test_bad_input_is_one_line():
    with frame.FrameRunner(jobs=1) as R:
        for kw, word in (({"budget": 0}, "budget"), ({"want": [3]}, "want"), ({"n": 0}, "n:")):
            args = {"standing": LEAVE, "runner": R, "budget": 10, "seed": 1, **kw}
            with pytest.raises(ValueError, match=word) as ex:
                robust.maximise(START, **args)
            assert "\n" not in str(ex.value)
        with pytest.raises(ValueError, match="starts"):
            robust.maximise([], runner=R, budget=10, seed=1)
