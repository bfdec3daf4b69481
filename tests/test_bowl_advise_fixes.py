"""An auditor's defects in the bowling advice (coach4): the move after a spare frame and after a
gutter ball, the line called "the most pins", honest names far from the head pin, one --leave
parser, a pick that converts none of its measured throws, and the 3-6-9 comparison's release.

Physics facts used (house shot, the ball alone, h = 1 ms): a straight spare ball (17 mph, 200 rpm,
end over end) from board 34 at the foul line 2.51 deg out meets the head pin's line on board
~4.4 heading -2.3 deg (it takes the 10); 1.6 deg out, on board ~15.1 heading -1.8 deg (it passes
the 10 on board ~14, 11 boards left of it); league200's release at 150 rpm (board 20, 3.179 deg
out) goes into the right gutter ~37 ft out."""
from __future__ import annotations

import json
from types import SimpleNamespace

import pytest

from nbst.models.bowling import lane
from nbst.models.bowling.lane import advise, frame, names, spares

SPARE = dict(board=34.0, at="foul", mph=17.0, rpm=200.0, rotation=0.0, tilt=0.0)
GUTTER = lane.Delivery(board=20.0, at="foul", angle=3.179, mph=17.0, rpm=150.0, rotation=55.0, tilt=12.0)


def _doc(d: lane.Delivery, standing, leave, board, entry) -> dict:
    return {"delivery": d.to_dict(), "standing": list(standing),
            "outcome": {"leave": list(leave), "board_at_pins": board, "entry_angle_deg": entry}}


# --------------------------------------------------------------------------- 1. a spare frame's move


def test_a_converted_spare_says_stay_not_a_move_to_the_pocket():
    """`frame --leave 10 --board 34 --angle 2.51` converts the 10; the advice said "move 7 right"
    (the strike ball's 2-and-1 move towards the pocket)."""
    d = lane.Delivery(angle=2.51, **SPARE)
    r = lane.throw(d)
    mv = advise.move_after(_doc(d, [10], [], r.board_at_pins, r.entry_angle_deg))
    assert mv.direction == "stay" and mv.steps == 0 and mv.text.startswith("converted: stay")
    assert mv.new_target_board == mv.target_board and mv.new_stance_board == mv.stance_board


def test_a_missed_spare_is_aimed_at_the_leaves_pins_never_the_pocket():
    """The same line 1.6 deg out misses the 10 left; the advice re-aimed at the pocket (board 17.1).
    Now: where the ball passed the 10 against its board, the eyes moved right with the feet kept,
    and the moved line, thrown, passes the 10 within half a board."""
    d = lane.Delivery(angle=1.6, **SPARE)
    r = lane.throw(d)
    mv = advise.move_after(_doc(d, [10], [10], r.board_at_pins, r.entry_angle_deg))
    key, x, aim_b = advise.spare_aim([10])
    assert key == (10,) and mv.aim_board == pytest.approx(aim_b) and aim_b < 4.0   # the 10's spot, not 17.5
    assert mv.board_at_aim - aim_b > 8.0 and mv.direction == "right"            # passed it well left
    assert mv.new_stance_board == mv.stance_board and mv.new_target_board < mv.target_board   # eyes right
    assert abs(mv.new_board_at_aim - aim_b) < 0.5
    assert "pocket" not in mv.text + mv.check_text and "the 10 pin" in mv.text


# --------------------------------------------------------------------------- 3. a gutter ball


def test_a_gutter_ball_gets_a_move_away_from_the_gutter_not_a_refusal():
    """`advise --after gut.json` (a right-gutter ball at a full rack) exited 2 "no phases to report".
    Now the 2-and-1 move towards the hand (a right-hander's right: the ball stays left), checked."""
    full = range(1, 11)
    mv = advise.move_after(_doc(GUTTER, full, full, None, None))
    assert mv.gutter["side"] == "right" and mv.direction == "right" and mv.steps >= 1
    assert mv.new_stance_board - mv.stance_board == pytest.approx(2 * (mv.new_target_board - mv.target_board))
    assert mv.new_board_at_pins is not None and abs(mv.new_board_at_pins - 17.5) < 3.0
    assert mv.text.startswith("a gutter ball (the right gutter")


def test_advise_after_a_gutter_ball_prints_the_move(tmp_path, capsys):
    from nbst.cli.main import main

    f = tmp_path / "gut.json"
    argv = ["bowl", "frame", "--board", "20", "--at", "foul", "--angle", "3.179", "--rpm", "150", "-o", str(f), "-q"]
    assert main(argv) == 0
    capsys.readouterr()
    assert main(["bowl", "advise", "--after", str(f)]) == 0
    out = capsys.readouterr().out
    assert "a gutter ball" in out and "move" in out and "check:" in out and "--leave 1,2,3" not in out


# --------------------------------------------------------------------------- 4. names far from the head pin


@pytest.mark.parametrize("board,hand,hit", [
    (38.1, "right", "wide left, missed the head pin and the 2 pin"),
    (33.6, "right", "wide left, missed the head pin and the 2 pin"),
    (1.0, "right", "wide right, missed the head pin and the 3 pin"),
    (1.0, "left", "wide left, missed the head pin and the 2 pin"),
    (45.0, "right", "missed the pins left"),
    (27.0, "right", "Brooklyn, missed the head pin"), (12.0, "right", "light, missed the head pin"),
    (15.5, "right", "light"), (22.5, "right", "Brooklyn")])
def test_a_ball_past_the_front_pins_is_named_wide_not_brooklyn_or_light(board, hand, hit):
    assert names.hit_name(board, hand) == hit


def test_the_wide_limits_come_from_the_pin_spots_and_the_radii():
    reach = (4.25 + 4.766 / 2) / (41.5 / 39)   # ball radius + the pin's widest, in boards
    assert names.FRONT_REACH == pytest.approx(reach + 6.0 / (41.5 / 39))     # the 2/3 pin, half a spacing out
    assert names.PINS_REACH == pytest.approx(reach + 18.0 / (41.5 / 39))     # the corner pins
    assert 20 + names.PINS_REACH > 39.5 and 20 - names.PINS_REACH < 0.5      # off the lane: a ball on it meets one


# --------------------------------------------------------------------------- 5. one --leave parser


def test_frame_and_advise_read_a_leave_alike():
    from nbst.cli.bowl.advise import leaves_of
    from nbst.cli.bowl.args import pin_list

    assert pin_list("3 10", "--leave") == pin_list("3,10") == pin_list("3, 10") == pin_list("3-10")
    assert leaves_of(SimpleNamespace(leave="3 10", leaves=None)) == ["3-10"]
    assert leaves_of(SimpleNamespace(leave="4, 9", leaves=None)) == ["4-9"]


def test_a_strike_written_x_is_refused_in_the_same_words_by_frame_and_advise(capsys):
    from nbst.cli.main import main

    errs = []
    for argv in (["bowl", "frame", "--leave", "x"], ["bowl", "advise", "--leave", "x"]):
        try:
            rc = main(argv)
        except SystemExit as e:
            rc = e.code
        err = capsys.readouterr().err.strip()
        assert rc == 2 and len(err.splitlines()) == 1 and "Traceback" not in err, err
        errs.append(err.split("error: ", 1)[1])
    assert errs[0] == errs[1] and errs[0].startswith("--leave: 'x' is a strike"), errs


# --------------------------------------------------------------------------- 2 and 6. the line said


def _fake(monkeypatch, lines, measured: dict, screening: dict):
    """test_bowling_advice's stand-in lines (their noisy frames take the pins of ``measured[board]``,
    the screening's ``screening[board]``), the ball alone a stub too. No physics."""
    from tests.test_bowling_advice import _fake as stand_in

    runner = stand_in(monkeypatch, measured, lines=tuple(lines), screening=screening)
    monkeypatch.setattr(lane, "throw", lambda d, oil="house", ball=None: SimpleNamespace(
        board_at_foul_line=d.board, board_at_arrows=d.board))
    return runner


def test_the_most_pins_is_ranked_on_the_measured_throws_it_prints(monkeypatch):
    """`advise --leave 7,9 --screen 2`: "the most pins: the 7 alone: 0.88 of 2", then "for the count:
    the 9 alone: 1.00 of 2" -- the label ranked on the screening. Now the line said is the measured best."""
    from nbst.cli.bowl.advise import spare_doc, spare_line

    R = _fake(monkeypatch, [("3-6-9", 1.0), ("the 7 alone", 2.0), ("the 9 alone", 3.0)],
              measured={1.0: [[]], 2.0: [[7], [7], [7], []], 3.0: [[9]]},
              screening={2.0: [[7]], 3.0: [[9], []]})
    adv = advise.advise_leave("7-9", 8, 1, runner=R, screen=4, polish=0)
    assert adv.spare["best_label"] == "the 7 alone" and not adv.converts   # the screening's pick
    assert adv.label == "the 9 alone" and adv.pins["mean"] == 1.0 and "the most pins" in adv.text
    assert "the 9 alone" in adv.text and "the 7 alone" not in adv.text and not adv.count_text
    assert adv.delivery["board"] == 3.0 and adv.estimate["k"] == 0
    row = spare_line({**spare_doc(SimpleNamespace(leave="7-9", to_dict=adv.spare.copy))})
    assert "the most pins: the 9 alone" in row and "1.00 of 2 pins" in row


def test_a_pick_that_converts_none_of_its_measured_throws_is_not_said_to_convert(monkeypatch):
    """`advise --leave "4, 9" --samples 2 --screen 1` printed the pick as "converts 0% (0/2)"."""
    R = _fake(monkeypatch, [("3-6-9", 1.0), ("the 4 alone", 2.0), ("slide", 3.0)],
              measured={1.0: [[]], 2.0: [[4]], 3.0: [[]]}, screening={3.0: [[4, 9]], 2.0: [[4]]})
    adv = advise.advise_leave("4-9", 2, 1, runner=R, screen=1, polish=0)
    assert adv.spare["best_label"] == "slide" and adv.spare["converts"]       # it converted in the screening
    assert "converts 0%" not in adv.text and "no line converted in the 2 measured throws" in adv.text
    assert adv.label == "the 4 alone" and "the most pins: " in adv.text and not adv.converts


# --------------------------------------------------------------------------- 7. the 3-6-9 comparison


@pytest.mark.parametrize("cmd", ["spares", "advise"])
def test_the_3_6_9_line_is_built_from_the_default_release(cmd, monkeypatch, capsys):
    """Without --bowler the 3-6-9 line came from issue 22's strike ball (2.82 deg, rotation 45),
    not the documented default release every command throws (league200's)."""
    from nbst.cli.main import main
    from nbst.models.bowling.lane import profiles

    seen = {}

    class Stop(Exception):
        pass

    def best_spare(name, n, seed, **kw):
        seen["strike"] = kw.get("strike")
        raise Stop

    class Runner:
        def __init__(self, *a, **k):
            self.oil, self.ball = "house", None

        def __enter__(self):
            return self

        def __exit__(self, *a):
            return False

    monkeypatch.setattr(spares, "best_spare", best_spare)
    monkeypatch.setattr(frame, "FrameRunner", Runner)
    with pytest.raises(Stop):
        main(["bowl", cmd, "--leave", "10", "--samples", "1", "--screen", "1", "--jobs", "1", "-q"])
    assert seen["strike"] == profiles.house_release() != spares.STRIKE


def test_a_3_6_9_line_that_gutters_is_said_plainly_not_as_a_0_percent_row():
    from nbst.cli.bowl.advise import spare_doc, spare_line

    gutter = lane.Delivery(board=29.0, at="foul", angle=6.21, mph=17, rpm=350, rotation=55, tilt=12).to_dict()
    est = {"p": 0.0, "k": 0, "n": 4, "lo": 0.0, "hi": 0.49}
    doc = {"leave": "10", "system_369": gutter, "system_369_estimate": est, "estimate": est,
           "best": gutter, "best_label": "straight", "ladder": [[0.001, [10]]], "converts": True}
    line = spare_line(spare_doc(SimpleNamespace(leave="10", to_dict=lambda: json.loads(json.dumps(doc))),
                                oil="house"))
    col = line.split("3-6-9 line (board 29.0): ", 1)[1]
    assert col.startswith("a gutter ball without noise: the right gutter at") and "0%" not in col
