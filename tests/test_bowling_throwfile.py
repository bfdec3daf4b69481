"""Throw files (models/bowling/throwfile.py): a frame from the foul line written by
``bowl frame -o``, read back through the shot-file gate, checked field by field, replayed by
``bowl replay``; the throw atlas and its lookup. Every refusal is one line naming the file and
the field, exit 2."""
from __future__ import annotations

import copy
import json
import math
import os
from pathlib import Path

import pytest

mujoco = pytest.importorskip("mujoco")

from nbst.models.bowling import lane  # noqa: E402
from nbst.models.bowling.lane import frame, noise, spares, throwfile

TYPICAL = lane.Delivery(board=20.0, at="foul", angle=2.82, rpm=350.0, rotation=45.0, tilt=12.0)


@pytest.fixture(scope="module")
def strike():
    """The typical release on a full rack, its 4-throw estimate and its ladder, as a throw dict."""
    r = frame.run_frame(TYPICAL)
    with frame.FrameRunner("house", jobs=1) as R:
        est, _ = noise.probability(TYPICAL, 4, 1, runner=R)
    lad = frame.ladder(TYPICAL, timesteps=(0.001, 0.0005))
    return r, throwfile.throw_dict(r, oil="house", ball=lane.Ball(), requested=1023, estimate=est, ladder=lad)


@pytest.fixture(scope="module")
def spare():
    """A 10-pin spare ball (no estimate, no ladder)."""
    d = spares.straight_at(*spares.aim_point((10,)))
    r = frame.run_frame(d, standing=[10])
    return r, throwfile.throw_dict(r, oil="house")


def _main(argv, capsys):
    from nbst.cli import main

    try:
        rc = main([str(a) for a in argv])
    except SystemExit as e:
        rc = e.code
    cap = capsys.readouterr()
    return rc, cap.out, [line for line in cap.err.strip().splitlines() if not line.startswith("nbst: note:")]


def _refused(argv, capsys, *needles):
    rc, _, err = _main(argv, capsys)
    assert rc == 2 and len(err) == 1, err
    assert "Traceback" not in err[0]
    for n in needles:
        assert n in err[0], err[0]
    return err[0]


# --- round trip ---------------------------------------------------------------------------------


def test_a_frame_written_loaded_and_replayed_gives_the_same_pins(strike, tmp_path):
    r, d = strike
    p = tmp_path / "throw.json"
    text = throwfile.dumps(d)
    p.write_text(text)
    back = throwfile.load(p)
    assert back == d and throwfile.dumps(back) == text  # exact floats, stable text
    assert back["standing"] == list(range(1, 11)) and back["outcome"]["leave"] == r.leave
    assert back["probability"]["n"] == 4 and back["probability"]["want"] == {"down": list(range(1, 11))}
    assert [x["timestep"] for x in back["ladder"]] == [0.001, 0.0005]
    d2, r2, ok = throwfile.replay_file(p)
    assert ok and r2.down == r.down and r2.leave == r.leave
    assert r2.settle_s == r.settle_s and r2.board_at_pins == r.board_at_pins  # the same frame, step for step


def test_a_spare_throw_replays_on_its_pins_standing(spare, tmp_path):
    r, d = spare
    assert d["standing"] == [10] and d["probability"] is None and d["ladder"] is None and d["requested"] is None
    p = tmp_path / "spare.json"
    p.write_text(throwfile.dumps(d))
    _, r2, ok = throwfile.replay_file(p)
    assert ok and r2.in_play == [10] and r2.leave == r.leave


def test_dumps_keeps_the_schema_order_and_ends_in_a_newline(strike):
    _, d = strike
    shuffled = dict(reversed(list(d.items())))
    text = throwfile.dumps(shuffled)
    assert text == throwfile.dumps(d) and text.endswith("}\n")
    assert list(json.loads(text)) == list(throwfile.THROW_KEYS)
    assert '"standing": [1, 2, 3, 4, 5, 6, 7, 8, 9, 10]' in text  # pins on one line, 2-space indent
    with pytest.raises(ValueError):
        throwfile.dumps({**d, "outcome": {**d["outcome"], "settle_s": math.nan}})


def test_throw_dict_refuses_a_frame_run_past_its_settle_and_a_wrong_oil(spare):
    r, _ = spare
    longer = frame.run_frame(lane.Delivery(**r.delivery), standing=[10], extra_s=0.1)
    with pytest.raises(ValueError, match="extra_s"):
        throwfile.throw_dict(longer, oil="house")
    with pytest.raises(ValueError, match="oil"):
        throwfile.throw_dict(r, oil="sport")


# --- the atlas ----------------------------------------------------------------------------------


def test_an_atlas_round_trips_and_looks_up_a_down_set_on_a_full_rack(strike, spare, tmp_path):
    r, d = strike
    _, s = spare
    a = throwfile.atlas_dict([d, s], oil="house")
    p = tmp_path / "atlas.json"
    p.write_text(throwfile.dumps(a))
    back = throwfile.load_atlas(p)
    assert back == a
    assert throwfile.lookup(back, r.down) == d
    assert throwfile.lookup(back, sum(1 << (n - 1) for n in r.down)) == d  # a mask names the same set
    assert throwfile.lookup(back, [10]) is None  # the spare's down set, but not on a full rack
    assert throwfile.lookup(back, [1, 2]) is None
    rack = copy.deepcopy(d)
    rack["standing"] = rack["standing"][::-1]  # the same rack in another order
    assert throwfile.lookup(throwfile.check_atlas({**a, "throws": [rack]}, "a"), r.down) == rack
    with pytest.raises(throwfile.ThrowFileError, match="same pins standing and down"):
        throwfile.check_atlas({**a, "throws": [d, rack]}, "a")


@pytest.mark.parametrize("mutate, field", [
    (lambda a: a["throws"].append(copy.deepcopy(a["throws"][0])), "throws[2].outcome.down"),
    (lambda a: a["throws"][1].update(oil="sport"), "throws[1].oil"),
    (lambda a: a["throws"][1]["ball"].update(rg=2.6), "throws[1].ball"),
    (lambda a: a["throws"][1]["ball"].update(rg=3.0), "throws[1].ball.rg"),
    (lambda a: a["throws"][0]["probability"]["noise"].update(rpm=30.0), "throws[0].probability.noise"),
    (lambda a: a.update(noise={**a["noise"], "mph": -1}), "noise.mph"),
    (lambda a: a.pop("throws"), "throws"),
])
def test_a_bad_atlas_is_refused_naming_the_throw_and_field(strike, spare, tmp_path, mutate, field):
    a = copy.deepcopy(throwfile.atlas_dict([strike[1], spare[1]], oil="house"))
    mutate(a)
    p = tmp_path / "atlas.json"
    p.write_text(json.dumps(a))
    with pytest.raises(throwfile.ThrowFileError) as e:
        throwfile.load_atlas(p)
    msg = str(e.value)
    assert msg.startswith(f"{p}: {field}") and "\n" not in msg, msg


# --- hostile throw files: one line naming the file and the field, exit 2 -----------------------


def _set(path, value):
    def f(d):
        *head, last = path
        for k in head:
            d = d[k]
        d[last] = value
    return f


def _drop(*path):
    def f(d):
        *head, last = path
        for k in head:
            d = d[k]
        del d[last]
    return f


HOSTILE = [
    (_drop("outcome"), "outcome", "missing"),
    (_drop("delivery", "rpm"), "delivery.rpm", "missing"),
    (_set(("delivery", "rpm"), math.nan), "delivery.rpm", "finite"),
    (_set(("delivery", "mph"), "fast"), "delivery.mph", "must be a number"),
    (_set(("delivery", "hand"), 3), "delivery.hand", "string"),
    (_set(("delivery", "spin"), 1.0), "delivery.spin", "unknown field"),
    (_set(("standing",), [1, 2, 11]), "standing", "1..10"),
    (_set(("standing",), [1, 1, 2]), "standing", "twice"),
    (_set(("standing",), True), "standing", "pin numbers"),
    (_set(("outcome", "down"), [11]), "outcome.down", "1..10"),
    (_set(("outcome", "leave"), [10]), "outcome.leave", "split"),
    (_set(("outcome", "settled"), 1), "outcome.settled", "true or false"),
    (lambda d: d["outcome"].__setitem__("cap_hit", d["outcome"]["settled"]), "outcome.cap_hit", "differ"),
    (_set(("outcome", "timestep"), 1.0), "outcome.timestep", "outside"),
    (_set(("outcome", "entry_angle_deg"), 1e300), "outcome.entry_angle_deg", "outside"),
    (_set(("oil",), "wet"), "oil", "not the name of its oil_pattern"),
    (lambda d: (d.pop("oil_pattern"), d.__setitem__("oil", "wet")), "oil", "no oil pattern"),
    (_set(("oil_pattern", "forward", "volume_ml"), -1), "oil_pattern: forward.volume_ml", "[0"),
    (_set(("oil_pattern", "forward", "units"), [1.0]), "oil_pattern: forward.units", "39 numbers"),
    (_set(("scene",), "lane-9"), "scene", "unknown lane scene"),
    (_set(("ball", "rg"), 2.9), "ball.rg", "USBC"),
    (_set(("ball", "diff"), 0.07), "ball.diff", "USBC"),
    (_set(("ball", "friction"), 0.5), "ball.friction", "USBC"),
    (_set(("ball", "weight_lb"), True), "ball.weight_lb", "finite number"),
    (_set(("format",), "nbst-bowling-shot"), "", "not an nbst bowling"),
    (_set(("version",), 2), "version", "version 1"),
    (_set(("requested",), {"down": [0]}), "requested.down", "1..10"),
    (_set(("probability", "p"), 0.99), "probability.p", "interval"),
    (_set(("probability", "lo"), -0.1), "probability.lo", "outside"),
    (_set(("probability", "k"), 5), "probability.k", "at most n"),
    (_set(("probability", "n"), 4.0), "probability.n", "whole number"),
    (_set(("probability", "seed"), -1), "probability.seed", "outside"),
    (_set(("probability", "noise", "rpm"), 300.0), "probability.noise.rpm", "standard deviation"),
    (_set(("probability", "leaves"), {"": 1}), "probability.leaves", "add up"),
    (_set(("probability", "leaves"), {"x": 4}), 'probability.leaves["x"]', "joined by '-'"),
    (lambda d: d["probability"].__setitem__("leaves", {"": (d["probability"]["k"] + 1) % 5,
                                                        "9": 4 - (d["probability"]["k"] + 1) % 5}),
     "probability.k", "leaves give"),
    (_drop("probability", "want"), "probability.want", "missing"),
    (_set(("ladder",), [{"timestep": 0.001}]), "ladder[0].leave", "missing"),
    (_set(("ladder",), []), "ladder", "list of 1.."),
    # every recorded output to its domain, as the replayed fields (issue 45: a 320-digit settle_s replayed, exit 0)
    (_set(("outcome", "settle_s"), int("7" * 320)), "outcome.settle_s", "too large (320 digits)"),
    (_set(("outcome", "settle_s"), 10 ** 300), "outcome.settle_s", "outside"),
    (_set(("outcome", "settle_s"), 1e300), "outcome.settle_s", "outside"),
    (_set(("outcome", "settle_s"), -0.5), "outcome.settle_s", "outside"),
    (_set(("outcome", "board_at_pins"), int("7" * 320)), "outcome.board_at_pins", "too large (320 digits)"),
    (_set(("outcome", "board_at_pins"), 10 ** 300), "outcome.board_at_pins", "outside"),
    (_set(("outcome", "entry_angle_deg"), -10 ** 300), "outcome.entry_angle_deg", "outside"),
    (_set(("outcome", "timestep"), int("7" * 320)), "outcome.timestep", "too large (320 digits)"),
    (_set(("outcome", "timestep"), 10 ** 300), "outcome.timestep", "outside"),
    (_set(("probability", "seed"), int("7" * 320)), "probability.seed", "too large (320 digits)"),
    (_set(("probability", "seed"), 2 ** 64), "probability.seed", "outside"),
    (_set(("probability", "hi"), 10 ** 300), "probability.hi", "outside"),
    (_set(("ladder", 0, "timestep"), 10 ** 300), "ladder[0].timestep", "outside"),
]


@pytest.mark.parametrize("mutate, field, needle", HOSTILE, ids=[f"{h[1] or 'format'}-{h[2]}" for h in HOSTILE])
def test_a_hostile_throw_file_is_one_line_naming_the_field(strike, tmp_path, capsys, mutate, field, needle):
    d = copy.deepcopy(strike[1])
    mutate(d)
    p = tmp_path / "throw.json"
    p.write_text(json.dumps(d))  # NaN is written as NaN, as Python's json does
    msg = _refused(["bowl", "replay", p], capsys, needle)
    assert f"{p}: {field}:" in msg if field else f"{p}:" in msg, msg


def test_a_fifo_a_folder_and_a_huge_file_are_refused_unopened(tmp_path, capsys):
    fifo = tmp_path / "fifo.json"
    os.mkfifo(fifo)
    _refused(["bowl", "replay", fifo], capsys, str(fifo), "not a regular file")  # would block if opened
    (tmp_path / "dir.json").mkdir()
    _refused(["bowl", "replay", tmp_path / "dir.json"], capsys, "directory")
    huge = tmp_path / "huge.json"
    with open(huge, "wb") as f:
        f.truncate(65 * 1024 * 1024)  # sparse: larger than the reader's cap, nothing written
    _refused(["bowl", "replay", huge], capsys, str(huge), "larger than")
    with pytest.raises(throwfile.ThrowFileError, match="not a regular file"):
        throwfile.load(fifo)
    _refused(["bowl", "replay", tmp_path / "missing.json"], capsys, "no such file")


def test_an_unknown_format_is_neither_a_shot_nor_a_throw(tmp_path, capsys):
    p = tmp_path / "x.json"
    p.write_text('{"format": "nbst-bowling-frame"}')
    _refused(["bowl", "replay", p], capsys, "not an nbst bowling throw file")


# --- the CLI ------------------------------------------------------------------------------------


def test_bowl_frame_o_writes_the_throw_with_its_probability_and_replay_checks_it(tmp_path, capsys):
    out = tmp_path / "sub" / "throw.json"
    rc, stdout, err = _main(["bowl", "frame", "--leave", "10", "--board", "34", "--at", "foul", "--angle", "2.32",
                             "--rpm", "200", "--rotation", "0", "--tilt", "0", "--probability", "4", "--jobs", "1",
                             "--timesteps", "-q", "-o", out], capsys)
    assert rc == 0, err
    assert f"throw file    {out}" in stdout
    d = throwfile.load(out)
    assert d["standing"] == [10] and d["probability"]["n"] == 4 and d["probability"]["want"] == {"down": [10]}
    assert d["delivery"]["board"] == 34 and d["delivery"]["at"] == "foul"
    assert [x["timestep"] for x in d["ladder"]] == list(frame.LADDER)
    rc, stdout, _ = _main(["bowl", "replay", out, "--json"], capsys)
    doc = json.loads(stdout)
    assert rc == 0 and doc["match"] and doc["down"] == d["outcome"]["down"]
    # a file whose outcome the replay does not give: exit 1, not 2
    wrong = copy.deepcopy(d)
    down = d["outcome"]["down"]
    wrong["outcome"]["down"], wrong["outcome"]["leave"] = d["outcome"]["leave"], down
    for x in wrong["ladder"]:  # the ladder's kept flags follow the outcome, or the file is refused (exit 2)
        x["kept"] = sorted(x["leave"]) == sorted(wrong["outcome"]["leave"])
    bad = tmp_path / "wrong.json"
    bad.write_text(throwfile.dumps(wrong))
    rc, stdout, _ = _main(["bowl", "replay", bad], capsys)
    assert rc == 1 and "DIFFERENT" in stdout


def test_bowl_frame_throws_the_ball_of_its_flags_and_the_file_records_it(tmp_path, capsys):
    argv = ["bowl", "frame", "--leave", "10", "--board", "34", "--at", "foul", "--angle", "2.32", "--rpm", "200",
            "--rotation", "30", "--tilt", "0", "-q"]
    ball = lane.Ball(rg=2.70, diff=0.055, friction=0.30)
    out = tmp_path / "throw.json"
    rc, stdout, err = _main(argv + ["--rg", "2.70", "--diff", "0.055", "--cover", "0.30", "--json", "-o", out], capsys)
    assert rc == 0, err
    got = json.loads(stdout)["frame"]
    d = lane.Delivery(board=34.0, at="foul", angle=2.32, rpm=200.0, rotation=30.0, tilt=0.0)
    mine, default = frame.run_frame(d, ball=ball, standing=[10]), frame.run_frame(d, standing=[10])
    # the flags' ball is the one thrown: its entry board is the direct run's, and not the default ball's
    assert got["board_at_pins"] == pytest.approx(mine.board_at_pins, abs=1e-9)
    assert abs(mine.board_at_pins - default.board_at_pins) > 0.05
    assert throwfile.load(out)["ball"] == lane.Ball(rg=2.70, diff=0.055, friction=0.30).to_dict()
    rc, stdout, _ = _main(["bowl", "replay", out, "--json"], capsys)
    assert rc == 0 and json.loads(stdout)["match"]
    _refused(argv + ["--rg", "2.9"], capsys, "--rg 2.9", "2.46")


def test_bowl_frame_o_refuses_a_folder_before_throwing(tmp_path, capsys):
    _refused(["bowl", "frame", "-q", "-o", tmp_path], capsys, "-o", "folder")


def test_an_interrupted_estimate_still_writes_the_frame(tmp_path, capsys, monkeypatch):
    def interrupted(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(noise, "probability", interrupted)
    out = tmp_path / "throw.json"
    rc, _, err = _main(["bowl", "frame", "--leave", "10", "--board", "34", "--at", "foul", "--angle", "2.32",
                        "--rpm", "200", "--rotation", "0", "--tilt", "0", "--probability", "4", "-q", "-o", out],
                       capsys)
    assert rc == 130 and any("interrupted" in line for line in err)
    d = throwfile.load(out)
    assert d["probability"] is None and d["standing"] == [10]


def test_the_shot_files_still_replay_as_before(tmp_path, capsys):
    """A 5 m shot file (the shipped atlas's 7-10 leave, beside its scene) takes the old path."""
    import shutil

    from nbst.models.bowling.deck import throwfile as deckfile

    shipped = Path(deckfile.SHIPPED_ATLAS)
    atlas = json.loads(shipped.read_text())
    s = next(x for x in atlas["shots"] if x["down"] == [1, 2, 3, 4, 5, 6, 8, 9])
    shutil.copyfile(shipped.with_name("scene.xml"), tmp_path / "scene.xml")
    (tmp_path / "shot.json").write_text(json.dumps(s))
    rc, stdout, _ = _main(["bowl", "replay", tmp_path / "shot.json", "--json"], capsys)
    assert rc == 0 and json.loads(stdout) == {"throw": str(tmp_path / "shot.json"), "down": s["down"],
                                              "expected": s["down"], "match": True}
