"""Advice that takes the count (issue 48): at a split the spare tool tries the slide (the front pin
driven into the one behind it) and each pin alone; where no line converts, the pick is the line
that takes the most pins, and the advice says so with that figure.

Physics facts on the house shot, noise-free, h = 1 ms: the slide lines of the 4-9 and the 2-10
convert (measured: on the spot and 1/2 board either side, from across the lane and straight
down the boards, all six convert each leave, 2026-12-06), a straight ball at the 4 of the big
four takes the 4 and the 7 behind it, and at the 6 the 6 and the 10. The 7-9 cannot be taken by
one ball: its pins are farther apart than a ball touching both could be."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from nbst.models.bowling import lane, scene
from nbst.models.bowling.lane import advise, frame, noise, spares


def _frame(leave: str, x: float, y: float, foul=None):
    return frame.run_frame(spares.straight_at(x, y, foul=foul), "house", standing=spares.leave_pins(leave))


def test_the_slide_spot_is_where_the_line_of_centres_points_at_the_back_pin():
    spots = scene.pin_spots()
    for front, back in ((4, 9), (2, 10), (6, 7)):
        c = np.array(spares.slide_at(front, back))
        a, b = spots[front - 1], spots[back - 1]
        assert np.linalg.norm(a - c) == pytest.approx(spares.CONTACT_REACH, abs=1e-12)   # touching the front pin
        u, w = (a - c) / np.linalg.norm(a - c), (b - a) / np.linalg.norm(b - a)
        assert float(u @ w) == pytest.approx(1.0, abs=1e-12)                             # driven at the back pin
    # ball radius 4.25 in and the pin's 4.71 in across at that height (USBC profile): 6.60 in, +-0.02
    assert spares.CONTACT_REACH / 0.0254 == pytest.approx(6.60, abs=0.02)


@pytest.mark.slow
@pytest.mark.parametrize("leave,front,back", [("4-9", 4, 9), ("2-10", 2, 10)])
def test_the_slide_converts_the_split_without_noise(leave, front, back):
    labels = [lbl for lbl, *_ in spares._plan(leave)]
    assert f"slide the {front} into the {back}" in labels
    r = _frame(leave, *spares.slide_at(front, back))
    assert r.converted, r.leave


def test_the_7_9_cannot_be_converted_by_one_ball_so_each_pin_is_tried_alone():
    spots = scene.pin_spots()
    gap = float(np.linalg.norm(spots[6] - spots[8]))
    assert gap > 2 * spares.CONTACT_REACH + 0.2          # m: no ball touches both (0.61 m against 0.34 m)
    labels = [lbl for lbl, *_ in spares._plan("7-9")]
    assert not any(lbl.startswith("slide") for lbl in labels)   # side by side: nothing to slide into
    assert "the 7 alone" in labels and "the 9 alone" in labels


@pytest.mark.slow
def test_the_big_four_is_shot_for_the_count_two_pins_a_side():
    labels = [lbl for lbl, *_ in spares._plan("4-6-7-10")]
    assert {f"slide the {a} into the {b}" for a, b in ((4, 7), (4, 10), (6, 7), (6, 10))} <= set(labels)
    for pin, both in ((4, [4, 7]), (6, [6, 10])):
        r = _frame("4-6-7-10", *spares.aim_point((pin,)))
        assert r.down == both, (pin, r.down)


# --------------------------------------------------------------------------- the pick


def _fake(monkeypatch, outcomes: dict, lines=(("3-6-9", 1.0), ("the 7 alone", 2.0), ("slide", 3.0)),
          screening: dict | None = None):
    """best_spare over stand-in ``lines`` (label, board) whose noisy frames take the pins
    ``outcomes[board]`` (one list of pins down per throw, cycled), or in the screening (its seeds
    are seed + 1000 + c and seed + 2000 + c) ``screening[board]`` where given; no physics."""
    monkeypatch.setattr(spares, "candidates", lambda name, **kw: [(lbl, lane.Delivery(board=b, at="foul"))
                                                                   for lbl, b in lines])

    def probability(d, n, seed, *, runner, standing, noise=None, on_done=None, want=None):
        seq = (screening or {}).get(d.board, outcomes[d.board]) if seed >= 1000 else outcomes[d.board]
        rs = [SimpleNamespace(down=seq[i % len(seq)], leave=[p for p in standing if p not in seq[i % len(seq)]],
                              converted=set(seq[i % len(seq)]) == set(standing), timestep=0.001) for i in range(n)]
        return estimate(rs, seed, noise or default), rs

    estimate, default = noise.estimate, noise.DEFAULT
    monkeypatch.setattr(noise, "probability", probability)
    monkeypatch.setattr(frame, "ladder", lambda d, oil, ball, standing: probability(d, 3, 0, runner=None,
                                                                                    standing=standing)[1])
    monkeypatch.setattr(frame, "run_frame", lambda d, oil, ball, standing, extra_s=0.0: probability(
        d, 1, 0, runner=None, standing=standing)[1][0])
    return SimpleNamespace(oil="house", ball=None)


def test_where_no_line_converts_the_pick_takes_the_most_pins(monkeypatch):
    R = _fake(monkeypatch, {1.0: [[]], 2.0: [[7]], 3.0: [[], [9], []]})
    res = spares.best_spare("7-9", 8, 1, runner=R, screen=4, polish=0)
    assert not res.converts and res.best_label == "the 7 alone"
    assert res.pins["mean"] == 1.0 and res.pins["counts"] == {"1": 8} and res.most_pins["label"] == "the 7 alone"


def test_a_line_that_converts_is_the_pick_and_the_count_is_given_beside_it(monkeypatch):
    R = _fake(monkeypatch, {1.0: [[]], 2.0: [[4]], 3.0: [[4, 9], [], [], []]})
    res = spares.best_spare("4-9", 8, 1, runner=R, screen=4, polish=0)
    assert res.converts and res.best_label == "slide" and res.estimate["k"] == 2
    assert res.pins["mean"] == pytest.approx(0.5) and res.most_pins["label"] == "the 7 alone"
    assert res.most_pins["pins"]["mean"] == 1.0


def test_the_pins_interval_holds_the_mean_and_stays_on_the_rack():
    rs = [SimpleNamespace(down=d) for d in ([4], [4], [4, 9], [])]
    p = spares.pins_estimate(rs, [4, 9])
    assert p["mean"] == 1.0 and p["lo"] < 1.0 < p["hi"] <= 2 and p["counts"] == {"2": 1, "1": 2, "0": 1}
    same = spares.pins_estimate([SimpleNamespace(down=[7])] * 12, [7, 9])
    lo = noise.wilson(12, 12)[0]
    assert (same["lo"], same["hi"]) == pytest.approx((lo, 1 + (1 - lo)))   # all 12 took 1: Wilson's range


def test_the_stance_at_the_far_edge_stays_on_the_numbered_boards():
    assert advise.stance_text(20.0) == f"stand on {20 + advise.STANCE_SEP:.1f}"
    t = advise.stance_text(34.0)
    assert t.startswith("stand on 39 ") and "5.0 boards" in t


@pytest.mark.slow
def test_the_advice_json_stands_on_the_numbered_boards_as_its_text(capsys):
    """A coach's 10-pin advice read 'stand on 39 (the last board; ...)' while its JSON said
    stance_board 41, off the approach; the JSON now stands where the text does."""
    import json

    from nbst.cli.main import main

    assert main(["bowl", "advise", "--leave", "10", "--samples", "2", "--screen", "1", "--polish", "0", "--jobs", "1",
                 "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["stance_board"] <= lane.N_BOARDS and d["text"].startswith("leave 10 (10 pin): stand on 39 ")


def test_a_straight_line_is_labelled_with_boards_not_a_bare_number():
    """'straight 17 mph from 34.0 at 3.1' read to a coach as an angle of 3.1; the label names boards."""
    labels = [lbl for lbl, _ in spares.candidates("10")][1:]
    assert labels and all(" from board " in s and " aimed at board " in s for s in labels), labels


def test_a_pick_the_fresh_throws_find_weaker_than_a_sure_pin_gets_the_count_line(monkeypatch):
    """A coach's 4-9: the slide converted 9 of 12 screening throws, then 8 of 20 fresh ones, taking
    0.95 pins a throw, where the 4 alone and the 9 alone each took 1.0 in the screening; no count
    line was given (the pick had taken the most pins in the screening). Its fresh throws taking
    fewer than the next line's screening did, that line is measured on the same fresh throws."""
    R = _fake(monkeypatch, {1.0: [[]], 2.0: [[4]], 3.0: [[4, 9], [], [], []]},
              lines=[("3-6-9", 1.0), ("the 4 alone", 2.0), ("slide", 3.0)], screening={3.0: [[4, 9], [4, 9], [4, 9], []]})
    res = spares.best_spare("4-9", 8, 1, runner=R, screen=4, polish=0)
    assert res.converts and res.best_label == "slide" and res.pins["mean"] == pytest.approx(0.5)
    assert res.most_pins["label"] == "the 4 alone" and res.most_pins["pins"]["mean"] == 1.0


def test_a_line_lucky_in_a_short_screening_does_not_hide_the_sure_pin(monkeypatch):
    """A third coach's 4-10 at --screen 2: a second slide took 1.5 pins a throw over its 6 screening
    throws and 0.2 on the 20 fresh ones, fewer than the pick's 0.4; it was the one line measured for
    the count, so no count line was given, where the 4 alone takes 1.0 every throw. Now the two best
    other lines and the best one-pin line are all measured on the fresh throws."""
    R = _fake(monkeypatch, {1.0: [[]], 2.0: [[4, 10], [], [4], [], []], 3.0: [[4]], 4.0: [[4], [], [], [], []]},
              lines=[("3-6-9", 1.0), ("slide", 2.0), ("the 4 alone", 3.0), ("lucky", 4.0)],
              screening={4.0: [[4], [4], [4], [4, 10], [4], [4]]})
    res = spares.best_spare("4-10", 20, 1, runner=R, screen=2, polish=0)
    assert res.converts and res.best_label == "slide" and res.pins["mean"] == pytest.approx(0.6)
    assert res.most_pins["label"] == "the 4 alone" and res.most_pins["pins"]["mean"] == 1.0
