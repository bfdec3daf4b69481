"""Bowler profiles (issue 34): the correlated release noise and each profile's strike ball."""
from __future__ import annotations

import json
import subprocess
import sys
from dataclasses import replace

import numpy as np
import pytest

from nbst.models.bowling import lane
from nbst.models.bowling.lane import noise, profiles, throwfile


def test_the_correlated_draws_have_the_stated_sigmas_and_correlations():
    nz = profiles.PRO_NOISE
    base = lane.Delivery(board=20, at="foul", angle=0.0, mph=17, rpm=350, rotation=45, tilt=12)
    xs = noise.sample(base, 4000, 7, nz)
    a = np.array([[getattr(d, k) for k in noise.KEYS] for d in xs])
    sd = a.std(axis=0)
    for k, s in zip(noise.KEYS, sd):  # within 4 standard errors (se of a sd: sigma / sqrt(2n))
        assert abs(s - getattr(nz, k)) <= 4 * getattr(nz, k) / np.sqrt(2 * 4000) + 1e-12, k
    c = np.corrcoef(a.T)
    i, j, r = noise.KEYS.index("mph"), noise.KEYS.index("rpm"), noise.KEYS.index("rotation")
    assert c[i, j] == pytest.approx(0.5, abs=0.05) and c[r, j] == pytest.approx(-0.3, abs=0.05)
    assert abs(c[0, 1]) < 0.05  # board and launch angle stay independent


def test_independent_noise_draws_and_writes_as_before():
    base = lane.Delivery(board=20, at="foul", angle=1.0)
    draws = np.random.default_rng(3).standard_normal((5, 6))
    assert noise.DEFAULT.mix(draws) is draws  # no correlation: the draws untouched, bit for bit
    assert set(noise.DEFAULT.to_dict()) == set(noise.KEYS)  # the files of before
    assert noise.sample(base, 3, 1) == noise.sample(base, 3, 1, replace(noise.DEFAULT, corr_mph_rpm=0.0))
    with pytest.raises(lane.LaneError, match="noise.corr_mph_rpm"):
        replace(noise.DEFAULT, corr_mph_rpm=0.95).check()
    with pytest.raises(ValueError, match="noise.corr_rotation_rpm"):
        replace(noise.DEFAULT, corr_mph_rpm=0.8, corr_rotation_rpm=0.7).check()
    d = profiles.PRO_NOISE.to_dict()
    assert throwfile.check_noise(d, "t.json") == profiles.PRO_NOISE


@pytest.mark.parametrize("name", profiles.NAMES)
def test_each_profiles_strike_ball_reaches_the_pocket_board_on_the_house_shot(name):
    r = lane.throw(profiles.profile(name).strike, "house")
    assert r.board_at_pins == pytest.approx(17.5, abs=0.1)  # boards (aimed to 0.05 by phases.aim_angle)
    assert 1.5 <= r.entry_angle_deg <= 6.5
    # skid, hook, roll: the ball turns (its breakpoint) no sooner than its hook starts (issue 48: the
    # stroker's farthest board, 29.9 ft, came before its 43.1 ft hook start)
    assert r.skid_ft is not None and r.breakpoint_ft is not None and r.skid_ft <= r.breakpoint_ft


def test_the_default_release_is_a_typical_house_bowlers():
    """``bowl throw`` without --bowler throws the house profile's strike ball: on the fresh house
    shot it breaks at 40-45 ft on boards 5-8, where a house shot's players break (issue 48's typical
    house bowler; coaching sites' figure for house shots), and reaches the pocket."""
    from nbst.cli.bowl import args as bowl_args
    from nbst.cli.main import build_parser

    d = bowl_args.delivery_of(build_parser().parse_args(["bowl", "throw"]))
    assert d == profiles.house_release() == profiles.profile(profiles.HOUSE_PROFILE).strike
    r = lane.throw(d, "house")
    assert 40.0 <= r.breakpoint_ft <= 45.0 and 5.0 <= r.breakpoint_board <= 8.0, (r.breakpoint_ft,
                                                                                   r.breakpoint_board)
    assert r.board_at_pins == pytest.approx(17.5, abs=0.1)


def test_the_cli_knows_the_profiles_and_a_delivery_flag_beside_one_overrides_that_part():
    from nbst.cli.bowl import args as bowl_args
    from nbst.cli.main import build_parser

    assert bowl_args.bowlers() == profiles.NAMES == profiles.PROFILES.names()   # read from the registry
    parse = build_parser().parse_args
    pro = profiles.profile("pro").strike
    d, nz = bowl_args.bowler_of(parse(["bowl", "frame", "--bowler", "pro"]))
    assert d == pro and nz == profiles.PRO_NOISE
    d, _ = bowl_args.bowler_of(parse(["bowl", "frame", "--bowler", "pro", "--rpm", "300", "--board", "20", "--at",
                                      "foul"]))
    assert (d.rpm, d.board, d.at) == (300.0, 20.0, "foul") and (d.mph, d.angle) == (pro.mph, pro.angle)
    d, _ = bowl_args.bowler_of(parse(["bowl", "throw", "--bowler", "league150", "--board", "12"]))
    assert (d.board, d.at) == (12.0, "arrows")   # a --board without --at is at the arrows, its default
    _, nz = bowl_args.bowler_of(parse(["bowl", "frame", "--bowler", "pro", "--noise-scale", "0"]))
    assert nz.board == 0.0 and nz.rpm == 0.0
    with pytest.raises(lane.LaneError, match="amateur") as ex:   # a LaneError is a ValueError, as it was
        profiles.profile("amateur")
    assert "--bowler" not in str(ex.value) and isinstance(ex.value, ValueError)   # the library names no flag


@pytest.mark.slow
def test_bowl_frame_throws_the_profiles_strike_ball_and_records_its_noise(tmp_path):
    out = subprocess.run([sys.executable, "-m", "nbst.cli", "bowl", "frame", "--bowler", "pro", "--probability", "2",
                          "--jobs", "1", "-o", "t.json"], capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    d = throwfile.load(tmp_path / "t.json")
    assert lane.Delivery(**d["delivery"]) == profiles.profile("pro").strike
    assert d["probability"]["noise"] == profiles.PRO_NOISE.to_dict()


def test_a_profile_carries_its_board_and_scale_and_is_one_registry_entry_and_one_file(tmp_path):
    """The profiles are a registry of objects read from data files: each carries its foul-line board and
    its noise scale; a new profile is one file and one entry (issue 45)."""
    for name in profiles.NAMES:
        p = profiles.PROFILES[name]
        assert p.foul_board == p.strike.board and p.strike.at == "foul"
        assert p.noise == profiles.scaled(profiles.NOISE_SHAPE, p.noise_scale)
        assert (profiles.PROFILES_DIR / f"{name}.json").is_file()
    for name in profiles.NAMES:   # the file's numbers, as written (calibrations change them: issue 48)
        raw = json.loads((profiles.PROFILES_DIR / f"{name}.json").read_text())
        p = profiles.PROFILES[name]
        assert (p.foul_board, p.noise_scale, p.strike.mph, p.strike.rpm) == (raw["foul_board"], raw["noise_scale"],
                                                                              raw["mph"], raw["rpm"])
    assert not hasattr(profiles, "FOUL_BOARDS") and not hasattr(profiles, "LEAGUE_SCALE")
    doc = json.loads((profiles.PROFILES_DIR / "league150.json").read_text())
    f = tmp_path / "novice.json"
    f.write_text(json.dumps({**doc, "name": "novice", "mph": 13.0, "noise_scale": 4.0}))
    novice = profiles.load_profile(f)
    profiles.PROFILES.register("novice", novice, help=novice.description)
    try:
        assert profiles.profile("novice").strike.mph == 13.0 and "novice" in profiles.PROFILES.names()
    finally:
        profiles.PROFILES.unregister("novice")
    f.write_text(json.dumps({**doc, "mph": float("nan")}))
    with pytest.raises(lane.LaneError, match="mph"):
        profiles.load_profile(f)


def test_reading_the_lane_is_a_profile_option_off_unless_its_file_says_true(tmp_path):
    """``"reads_lane"`` (issue 48): optional, false where a file leaves it out, a boolean or refused
    naming the file and the field; the lineup's bowlers carry it."""
    from nbst.models.bowling.lane import transition as T

    doc = json.loads((profiles.PROFILES_DIR / "pro.json").read_text())
    f = tmp_path / "reader.json"
    f.write_text(json.dumps({**doc, "reads_lane": True}))
    assert profiles.load_profile(f).reads_lane is True
    f.write_text(json.dumps({**doc, "reads_lane": "yes"}))
    with pytest.raises(lane.LaneError, match="reader.json: reads_lane"):
        profiles.load_profile(f)
    for name in profiles.NAMES:
        raw = json.loads((profiles.PROFILES_DIR / f"{name}.json").read_text())
        assert profiles.PROFILES[name].reads_lane is raw.get("reads_lane", False)
        assert T.lineup(name)[0].reads_lane is profiles.PROFILES[name].reads_lane


def test_the_cranker_is_a_registered_profile_read_from_its_file():
    """Issue 48's one-handed cranker is a profile like the others: registered, its file's numbers,
    the pro's noise sizes, and the CLI's ``--bowler`` knows it."""
    from nbst.cli.bowl import args as bowl_args

    assert "cranker" in profiles.NAMES and "cranker" in bowl_args.bowlers()
    p = profiles.profile("cranker")
    assert p == profiles.load_profile(profiles.PROFILES_DIR / "cranker.json")
    assert (p.noise_scale, p.spare_noise_scale) == (profiles.PRO_SCALE, profiles.PRO_SPARE_SCALE)
    assert p.strike.rotation > profiles.profile("pro").strike.rotation   # more side roll: a higher entry angle


def test_the_balls_are_a_registry_and_the_cli_reads_its_defaults():
    from nbst.cli.main import build_parser
    from nbst.cli.bowl import args as bowl_args

    assert lane.BALLS[lane.DEFAULT_BALL] == lane.Ball()   # the default ball, field for field
    args = build_parser().parse_args(["bowl", "throw"])
    assert args.ball == lane.DEFAULT_BALL and bowl_args.ball_of(args) == lane.Ball()
    args = build_parser().parse_args(["bowl", "throw", "--rg", "2.6"])
    assert bowl_args.ball_of(args) == replace(lane.Ball(), rg=2.6)
