"""The bowler's interface (issue 34): names of hits and leaves from their definitions, the
stance/target line, any leave in ``bowl spares``, ``--bowler`` on the throwing commands, the
advisor, and one-line errors (exit 2) for bad leaves, bowlers and stances."""
from __future__ import annotations

import json
from dataclasses import replace

import pytest

from nbst.models.bowling.lane import names

FULL = list(range(1, 11))


def _main(argv, capsys):
    from nbst.cli import main

    rc = main([str(a) for a in argv])
    cap = capsys.readouterr()
    return rc, cap.out, cap.err


def _one_line(rc, err, *words):
    assert rc == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    for w in words:
        assert w in lines[0], (w, lines[0])


# --------------------------------------------------------------------------- names


@pytest.mark.parametrize("leave", ["7-10", "3-10", "2-7", "4-6", "7-9", "4-9", "5-7", "2-10", "4-6-7-10",
                                   "4-6-7-8-10", "6-7-10", "8-10"])
def test_usbc_a_pin_down_between_two_standing_is_a_split(leave):
    assert names.is_split([int(p) for p in leave.split("-")])


@pytest.mark.parametrize("leave", ["5-6", "9-10", "2-3", "4-5", "8-9", "7-8"])
def test_usbc_a_pin_down_just_ahead_of_two_standing_is_a_split(leave):
    assert names.is_split([int(p) for p in leave.split("-")])


@pytest.mark.parametrize("leave", ["2-8", "3-9", "2-4-5-8", "3-6-10", "1-2-4", "1-3-6", "10", "7", "3-5", "2-5",
                                   "4-7", "6-10", "1-2-10", "1-2-4-10"])
def test_no_gap_or_the_head_pin_standing_is_not_a_split(leave):
    """The sleepers (2-8, 3-9) hide one pin behind another; the bucket and the clusters touch; a
    leave with the head pin up is never a split (USBC) -- the 1-2-10 is a washout instead."""
    pins = [int(p) for p in leave.split("-")]
    assert not names.is_split(pins)
    assert names.is_washout(pins) == (leave in ("1-2-10", "1-2-4-10"))


def test_a_left_handers_leave_is_named_in_the_mirror():
    assert names.leave_names(FULL, [2, 4, 5, 8]) == ["bucket"]
    assert names.leave_names(FULL, [3, 5, 6, 9], hand="left") == ["bucket"]
    assert names.is_split([4, 7, 10]) and names.is_split([6, 7, 10], hand="left")
    assert names.leave_names(FULL, [7], 17.5, 5.0, "left") == ["solid 7"]


@pytest.mark.parametrize("board,hit", [(12.0, "light, missed the head pin"), (15.5, "light"), (17.0, "pocket"),
                                       (17.5, "pocket"), (18.0, "pocket"), (18.6, "high"), (20.4, "nose"),
                                       (22.5, "Brooklyn"), (27.0, "Brooklyn, missed the head pin")])
def test_the_hit_is_named_by_its_board_at_the_head_pin(board, hit):
    assert names.hit_name(board) == hit


def test_the_head_pin_reach_is_ball_radius_plus_pin_radius_in_boards():
    assert names.HEAD_PIN_REACH * 41.5 / 39 == pytest.approx(4.25 + 4.766 / 2, abs=1e-9)   # inches


def test_a_lone_10_is_flat_solid_or_ringing_by_angle_and_hit():
    assert names.leave_names(FULL, [10], 17.5, 3.0) == ["flat 10"]    # came in flat: below 4 deg
    assert names.leave_names(FULL, [10], 17.5, 5.5) == ["solid 10"]   # the pocket, with angle
    assert names.leave_names(FULL, [10], 16.2, 5.0) == ["ringing 10"]   # light, with angle
    assert names.leave_names(FULL, [4], 17.6, 5.0) == ["solid 4"]
    assert names.leave_names(FULL, [4], 19.0, 5.0) == ["4 pin"]
    assert names.text(names.names(FULL, [10], 16.2, 5.0)) == "light, ringing 10"
    assert names.leave_names(FULL, []) == ["strike"] and names.leave_names([3, 10], []) == ["converted"]
    assert names.leave_names(FULL, [7, 10]) == ["split", "bedposts"]
    assert names.leave_names(FULL, [4, 6, 7, 9, 10]) == ["split", "greek church"]


# --------------------------------------------------------------------------- one-line errors


@pytest.mark.parametrize("argv,words", [
    (["bowl", "spares", "--leave", "3,11"], ("--leave", "1..10")),
    (["bowl", "spares", "--leave", "0"], ("--leave", "1..10")),
    (["bowl", "spares", "--leave", "strike"], ("--leave", "strike")),
    (["bowl", "spares", "--leaves", "10,none"], ("--leaves", "strike")),
    (["bowl", "spares", "--leave", "1,2,3,4,5,6,7,8,9,10"], ("--leave", "all ten")),
    (["bowl", "spares", "--leave", "10", "--bowler", "amateur"], ("--bowler", "amateur")),
    (["bowl", "advise", "--leave", "3,x"], ("--leave", "1..10")),
    (["bowl", "advise", "--leave", "10", "--bowler", "pba"], ("--bowler",)),
    (["bowl", "throw", "--stance", "25"], ("--stance", "--target")),
    (["bowl", "throw", "--target", "2nd-arrow"], ("--stance", "--target")),
    (["bowl", "throw", "--stance", "25", "--target", "9th-arrow"], ("--target",)),
    (["bowl", "throw", "--stance", "25", "--target", "2nd-arrow", "--angle", "2"], ("--angle",)),
    (["bowl", "throw", "--stance", "5", "--target", "2nd-arrow"], ("--stance", "off the lane")),
    (["bowl", "throw", "--stance", "41", "--target", "6th-arrow"], ("--stance", "39")),   # the approach's boards
    (["bowl", "frame", "--bowler", "amateur"], ("--bowler",)),
    (["bowl", "pocket", "-o", "p.png", "--bowler", "x"], ("--bowler",)),
    (["bowl", "solve", "--leave", "10", "-o", "t.json", "--bowler", "pro"], ("--bowler", "--foul-line")),
    (["bowl", "atlas", "--out-dir", "a", "--bowler", "pro"], ("--bowler", "--foul-line")),
    (["bowl", "throw", "--camera", "deck"], ("--camera", "--video or --still")),
    (["bowl", "throw", "--camera", "top", "--still", "a.png"], ("--camera",)),
])
def test_bad_leaves_bowlers_and_stances_are_one_line_exit_2(argv, words, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    try:
        rc, _, err = _main(argv, capsys)
    except SystemExit as e:   # argparse's own refusals
        rc, err = e.code, capsys.readouterr().err
    _one_line(rc, err, *words)


def test_the_parser_defaults_only_what_is_not_given():
    from nbst.cli.bowl import args as bowl_args
    from nbst.cli.main import build_parser
    from nbst.models.bowling.lane import advise

    assert not hasattr(bowl_args, "STANCE_SEP")   # one value, the library's: the CLI reads advise.STANCE_SEP
    args = build_parser().parse_args(["bowl", "throw", "--stance", "27", "--target", "2nd-arrow", "--rpm", "350"])
    assert bowl_args.stance_target(args) == (27.0 - advise.STANCE_SEP, 10.0) == (20.0, 10.0)
    d = bowl_args.delivery_of(args)
    assert (d.board, d.at, d.rpm, d.mph) == (20.0, "foul", 350.0, bowl_args.delivery_defaults()["mph"])
    assert [bowl_args.target_board(t) for t in ("1st-arrow", "2nd arrow", "4th", "12.5")] == [5.0, 10.0, 20.0, 12.5]


def test_any_leave_has_an_aim_and_a_3_6_9_move_from_its_pins():
    from nbst.models.bowling.lane import profiles, spares

    assert spares.leave_spec("7") == spares.LEAVES["7"]
    assert spares.leave_spec("3-10") == ((3, 10), -6)     # the mean of the 3 and 10: 2 half spacings right
    assert spares.leave_spec("4-6") == ((4, 6), 0)        # the middle
    assert spares.leave_spec("2-7") == ((2, 7), 6)
    pro = profiles.profile("pro").strike
    d = spares.system_369("3-10", pro)
    assert d.foul_board() == pytest.approx(pro.foul_board() + 6) and (d.mph, d.rpm) == (pro.mph, pro.rpm)


# --------------------------------------------------------------------------- the line


@pytest.mark.slow
def test_the_target_is_where_the_real_path_crosses_the_arrows():
    """A 500 rpm ball leaves the straight line before the arrows: the straight line's launch angle
    misses the target board there by more than 0.3 board, aim_target's crosses it within its
    0.05-board tolerance, and the line reads the crossing back."""
    import math

    from nbst.models.bowling import lane
    from nbst.models.bowling.lane import advise

    d0 = lane.Delivery(board=22.0, at="foul", angle=0.0, mph=17.0, rpm=500.0, rotation=60.0, tilt=10.0)
    straight = math.degrees(math.atan((22.0 - 15.0) * lane.BOARD_WIDTH / (15 * lane.FT)))
    naive = advise.line_of(lane.throw(replace(d0, angle=straight)))
    assert abs(naive["target_board"] - 15.0) > 0.3
    ln = advise.line_of(lane.throw(advise.aim_target(d0, 15.0)))
    assert ln["target_board"] == pytest.approx(15.0, abs=0.05)   # boards (aim_target's tolerance)
    assert ln["stance_board"] == pytest.approx(22.0 + advise.STANCE_SEP, abs=1e-9)
    assert ln["target"].endswith("(3rd arrow)")


# --------------------------------------------------------------------------- the advisor


def _frame_doc(d, r) -> dict:
    return {"delivery": d.to_dict(), "standing": FULL,
            "outcome": {"leave": [10], "board_at_pins": r.board_at_pins, "entry_angle_deg": r.entry_angle_deg}}


@pytest.mark.parametrize("angle,way", [(3.1, "right"), (2.5, "left")])
def test_the_move_follows_the_miss_and_brings_the_ball_back_to_the_pocket(angle, way):
    """The typical release thrown light (3.1 deg out: board ~15.5) and high (2.5 deg: ~20.4), the
    ball alone: the advice moves the way of the miss (light: right, towards the hand; high:
    left), and the moved line, thrown, meets the pins nearer the pocket's middle."""
    from nbst.models.bowling import lane
    from nbst.models.bowling.lane import advise, spares

    d = replace(spares.STRIKE, angle=angle)
    r = lane.throw(d)
    mv = advise.move_after(_frame_doc(d, r))
    assert mv.direction == way and mv.steps >= 1
    assert mv.new_stance_board - mv.stance_board == pytest.approx(2 * (mv.new_target_board - mv.target_board))
    assert abs(mv.new_board_at_pins - 17.5) < abs(mv.board_at_pins - 17.5) - 1.0   # boards nearer the pocket
    left = replace(d, hand="left")
    assert advise.move_after(_frame_doc(left, lane.throw(left)), check=False).direction == (
        "left" if way == "right" else "right")   # a left-hander's hand side is the left


def test_a_pocket_hit_says_stay():
    from nbst.models.bowling import lane
    from nbst.models.bowling.lane import advise, spares

    r = lane.throw(spares.STRIKE)
    mv = advise.move_after(_frame_doc(spares.STRIKE, r))
    assert names.hit_name(r.board_at_pins) == "pocket" and mv.steps == 0 and mv.text.startswith("pocket")


@pytest.mark.slow
def test_the_advisors_line_at_the_10_converts_it_without_noise(capsys):
    """``bowl advise --bowler league200 --leave 10`` (a small run): its line, thrown without noise,
    converts the 10; the readout gives stance, target, probability and the sample note."""
    from nbst.models.bowling import lane
    from nbst.models.bowling.lane import frame

    rc, out, err = _main(["bowl", "advise", "--bowler", "league200", "--leave", "10", "--samples", "4", "--screen",
                          "2", "--jobs", "1", "--json", "-q"], capsys)
    assert rc == 0, err
    doc = json.loads(out)
    assert doc["bowler"] == "league200" and "sample" in doc["note"] and doc["estimate"]["n"] == 4
    r = frame.run_frame(lane.Delivery(**doc["delivery"]), "house", standing=[10])
    assert r.converted
    assert 1 <= doc["stance_board"] <= 46 and 1 <= doc["target_board"] <= 39


@pytest.mark.slow
def test_bowl_frame_records_the_bowler_the_line_the_names_and_the_note(tmp_path, capsys):
    """``--bowler pro --rpm 400``: the pro's line at 400 rpm (the flag overrides), and the throw
    file says so: bowler, line (stance = release board + 7), names, the sample note; it replays."""
    from nbst.models.bowling.lane import advise, profiles, throwfile

    out = tmp_path / "t.json"
    rc, text, err = _main(["bowl", "frame", "--bowler", "pro", "--rpm", "400", "-o", out], capsys)
    assert rc == 0, err
    d = throwfile.load(out)
    raw = json.loads(out.read_text())
    pro = profiles.profile("pro").strike
    assert d["delivery"]["rpm"] == 400.0 and d["delivery"]["mph"] == pro.mph and raw["bowler"] == "pro"
    assert raw["line"]["stance_board"] == pytest.approx(d["delivery"]["board"] + advise.STANCE_SEP)
    o = d["outcome"]
    assert raw["names"] == names.names(d["standing"], o["leave"], o["board_at_pins"], o["entry_angle_deg"])
    assert raw["names"]["hit"] == names.hit_name(o["board_at_pins"]) is not None
    assert "sample" in raw["note"] and "named" in text and "sample" in text
    rc, text, err = _main(["bowl", "replay", out], capsys)
    assert rc == 0 and "named" in text, err


def test_spare_commands_throw_with_the_profiles_spare_noise():
    """--bowler on a spare command takes the profile's spare noise; on a strike ball its strike noise."""
    import argparse

    from nbst.cli.bowl.args import bowler_of
    from nbst.models.bowling.lane import profiles

    args = argparse.Namespace(bowler="pro")
    pro = profiles.profile("pro")
    assert bowler_of(args)[1] == pro.noise
    assert bowler_of(args, spare=True)[1] == pro.spare()
    assert pro.spare() != pro.noise  # the pro's spare noise is fitted on its own


# --------------------------------------------------------------------------- a gutter ball is a result


def test_a_gutter_ball_is_a_result_not_an_error(tmp_path, capsys):
    """Released on board 3 angled out, the ball leaves the lane within the first feet: ``throw``
    says so (exit 0, no phases) and ``frame`` counts it as USBC does, all ten pins standing and
    no pinfall (rule 6b.1), in a throw file that replays."""
    out = tmp_path / "t.json"
    rc, text, err = _main(["bowl", "throw", "--board", "3", "--at", "foul", "--angle", "3", "-o", out], capsys)
    assert rc == 0, err
    assert "gutter ball" in text and "right gutter" in text and "Traceback" not in err
    doc = json.loads(out.read_text())
    assert doc["gutter"]["side"] == "right" and 0.0 < doc["gutter"]["ft"] < 60.0
    f = tmp_path / "f.json"
    rc, text, err = _main(["bowl", "frame", "--board", "3", "--at", "foul", "--angle", "3", "-o", f, "--json"], capsys)
    assert rc == 0, err
    fr = json.loads(text)["frame"]
    assert fr["ball_left_lane"] and fr["down"] == [] and fr["leave"] == FULL
    assert json.loads(text)["line"] is None          # no line to the pins: none is made up
    rc, text, err = _main(["bowl", "replay", f], capsys)
    assert rc == 0 and "match" in text, (text, err)


def test_an_unknown_flag_points_at_the_commands_own_help(capsys):
    """A coach's `bowl advise --leave 10 --mph 19` was told to see `nbst --help`, which lists
    commands, not advise's flags; and the --bowler help promised delivery flags advise has not."""
    with pytest.raises(SystemExit) as ex:    # argparse's usage error: exit 2
        _main(["bowl", "advise", "--leave", "10", "--mph", "19"], capsys)
    _one_line(ex.value.code, capsys.readouterr().err, "unrecognized arguments: --mph 19",
              "(see `nbst bowl advise --help`)")
    from nbst.cli.main import build_parser

    adv = build_parser()._subparsers._group_actions[0].choices["bowl"]._subparsers._group_actions[0].choices["advise"]
    bowler = next(a for a in adv._actions if "--bowler" in a.option_strings)
    assert "overrides that part of the release" not in bowler.help and "takes no delivery flags" in bowler.help


def test_a_leave_is_taken_as_bowlers_write_it_with_dashes():
    """A coach's `frame --leave 10-7` was refused where advise and spares take it."""
    from nbst.cli.bowl.args import pin_list

    assert pin_list("10-7") == pin_list("7,10") and pin_list("4-7-10") == pin_list("4,7,10")
    for bad in ("4--7", "4-7,10", "10-10", "-3"):
        with pytest.raises(Exception):
            pin_list(bad, "--leave")


def test_the_target_is_said_as_boards_inside_or_outside_an_arrow():
    """A coach read '3rd arrow -1.6' as signed arithmetic; a coach says '1.6 boards outside the 3rd arrow'."""
    from nbst.models.bowling.lane.advise import arrow_text

    assert arrow_text(13.4) == "board 13.4 (1.6 boards outside the 3rd arrow)"
    assert arrow_text(11.0) == "board 11.0 (1.0 board inside the 2nd arrow)"
    assert arrow_text(15.02) == "board 15.0 (3rd arrow)"


def test_a_3_6_9_line_that_goes_in_the_gutter_says_so():
    """A second coach read the 3-6-9 line's '0%' at the 10 (league200's release) as a line that
    misses the pin: its noise-free ball went in the right gutter at 27 ft. The line now says so."""
    from types import SimpleNamespace

    from nbst.cli.bowl.advise import spare_doc, spare_line
    from nbst.models.bowling import lane

    gutter = lane.Delivery(board=3, at="foul", angle=3.0).to_dict()
    est = {"p": 0.0, "k": 0, "n": 4, "lo": 0.0, "hi": 0.49}
    doc = {"leave": "10", "system_369": gutter, "system_369_estimate": est, "estimate": est,
           "best": gutter, "best_label": "straight", "ladder": [[0.001, [10]]], "converts": True}
    d = spare_doc(SimpleNamespace(leave="10", to_dict=lambda: dict(doc)), oil="house")
    assert d["system_369_gutter"]["side"] == "right" and 0 < d["system_369_gutter"]["ft"] < 60
    assert "a gutter ball without noise: the right gutter at" in spare_line(d)
    d = spare_doc(SimpleNamespace(leave="10", to_dict=lambda: {**doc, "system_369": lane.Delivery().to_dict()}),
                  oil="house")
    assert "system_369_gutter" not in d


def test_a_left_handers_spare_lines_are_the_right_handers_mirrored():
    """Two coaches asked for --hand on advise and spares. A left-hander's leave is worked out as its
    mirror image on the mirrored lane: the 6-8 as the 4-9, its labels in the left-hander's pins, its
    deliveries left-handed (the same boards, counted from the left-hander's gutter)."""
    from nbst.models.bowling.lane import spares

    assert spares.mirrored("6-8") == "4-9" and spares.mirrored("7") == "10" and spares.mirrored("1-2-4-7") == "1-3-6-10"
    right = [lbl for lbl, *_ in spares._plan("4-9")]
    left = [lbl for lbl, *_ in spares._plan("4-9", mirror=True)]
    assert "slide the 4 into the 9" in right and "slide the 6 into the 8" in left and "the 8 alone" in left
    assert len(left) == len(right)
    d = {"leave": "4-9", "ladder": [[0.001, [9]], ["+2 s", [4, 9]]], "best": {"hand": "right", "board": 30.0},
         "system_369": {"hand": "right", "board": 20.0}, "screened": {"label": "x", "delivery": {"hand": "right"}},
         "most_pins": None}
    m = spares.mirror_doc(d)
    assert m["leave"] == "6-8" and m["ladder"] == [[0.001, [8]], ["+2 s", [6, 8]]]
    assert m["best"] == {"hand": "left", "board": 30.0} and m["screened"]["delivery"]["hand"] == "left"


def test_hand_left_is_refused_on_a_pattern_that_is_not_mirror_symmetric(tmp_path, capsys):
    """On a lopsided sheet a left-hander's lane is not a right-hander's mirrored: one line, exit 2."""
    sheet = {"format": "nbst-oil-pattern", "version": 2, "name": "lopsided", "description": "oil on the left only",
             "rows": [{"pass": "forward", "boards": "2L-15L", "loads": 3, "ul": 50, "speed": 14, "start_ft": 0,
                       "end_ft": 35}]}
    f = tmp_path / "lopsided.json"
    f.write_text(json.dumps(sheet))
    rc, _, err = _main(["bowl", "advise", "--leave", "7", "--hand", "left", "--oil", f, "--samples", "2"], capsys)
    _one_line(rc, err, "--hand left", "not mirror-symmetric")


@pytest.mark.slow
def test_advise_a_left_handers_7_as_a_right_handers_10(capsys):
    """`advise --leave 7 --hand left` stands and looks where `--leave 10` does (boards from the
    bowler's own gutter), with the same probability, its delivery left-handed."""
    out = {}
    for hand, leave in (("left", "7"), ("right", "10")):
        rc, text, err = _main(["bowl", "advise", "--leave", leave, "--hand", hand, "--samples", "4", "--screen", "1",
                               "--polish", "0", "--jobs", "1", "--json"], capsys)
        assert rc == 0, err
        out[hand] = json.loads(text)
    L, R = out["left"], out["right"]
    assert L["leave"] == "7" and R["leave"] == "10" and L["hand"] == "left" and L["delivery"]["hand"] == "left"
    assert (L["stance_board"], L["target_board"], L["estimate"]["k"]) == (R["stance_board"], R["target_board"],
                                                                         R["estimate"]["k"])


def test_a_release_speed_no_bowler_throws_gets_a_note_of_km_per_hour(capsys):
    """`--mph 30` ran silently into the gutter; 30 is most likely km/h (18.6 mph). Now a note says so;
    a typical speed gets none."""
    from nbst.cli.bowl.args import FAST_MPH, delivery_of
    from types import SimpleNamespace

    keys = dict(hand=None, board=None, at=None, angle=None, rpm=None, rotation=None, tilt=None, stance=None, target=None)
    delivery_of(SimpleNamespace(mph=30.0, **keys))
    err = capsys.readouterr().err
    assert "--mph 30" in err and "30 km/h is 18.6 mph" in err, err
    delivery_of(SimpleNamespace(mph=FAST_MPH, **keys))
    delivery_of(SimpleNamespace(mph=30.0, quiet=True, **keys))
    assert capsys.readouterr().err == ""


def test_bowl_frame_has_no_samples_flag_it_never_read(capsys):
    """`bowl frame --samples 5` was taken and ignored (its throws are --probability N's): a coach
    thought 5 noisy throws were run. The flag is gone from frame, and refused in one line."""
    from nbst.cli.main import main

    with pytest.raises(SystemExit) as e:
        main(["bowl", "frame", "--samples", "5"])
    assert e.value.code == 2 and "unrecognized arguments: --samples 5" in capsys.readouterr().err
