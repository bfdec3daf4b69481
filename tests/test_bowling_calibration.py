"""Bowling calibrated where nobody tuned it (issue 48): entry angles by style and by differential, the ball
alone on a fresh house shot; physical facts with stated tolerances. The carry, spare and leave-mix figures
on held-out seeds are benchmarks/bench_bowling_calibration.py's (samples of hundreds: no test)."""
from __future__ import annotations

import pytest

pytest.importorskip("mujoco")

from nbst.models.bowling import lane  # noqa: E402
from nbst.models.bowling.lane import phases, profiles  # noqa: E402


def _style(name: str) -> profiles.Profile:
    """A registered profile by name (the cranker is one since issue 48)."""
    return profiles.profile(name)


@pytest.mark.slow
def test_crankers_and_two_handers_enter_at_six_degrees_and_the_two_hander_at_least_the_cranker():
    """USBC's carry peaks near 6 deg of entry at board 17.5; high-rev styles get there from their usual lines
    (the cranker from board 26, the two-hander from board 30 at the foul line; measured 6.05 and 6.42 deg)."""
    got = {}
    for name in ("cranker", "twohander"):
        r = lane.throw(_style(name).strike, "house")
        assert r.board_at_pins == pytest.approx(17.5, abs=0.1)  # aimed at the pocket (phases.aim_angle, 0.05)
        assert 40.0 <= r.breakpoint_ft <= 45.0 and 4.0 <= r.breakpoint_board <= 9.0  # a house shot's breakpoint
        got[name] = r.entry_angle_deg
    assert got["cranker"] >= 6.0 and got["twohander"] >= 6.0
    assert got["twohander"] >= got["cranker"]
    # the league players' releases enter under them (measured: league200 4.65 deg, league150 3.12 deg)
    assert lane.throw(profiles.profile("league200").strike, "house").entry_angle_deg <= got["cranker"] - 1.0
    assert lane.throw(profiles.profile("league150").strike, "house").entry_angle_deg <= got["cranker"] - 2.5


@pytest.mark.parametrize("name", ["league200", "cranker"])
def test_a_higher_differential_hooks_more_and_enters_steeper_on_the_same_line(name):
    """Thrown on the same line (stance and launch angle), a 0.060 in differential flares more, hooks more
    and enters at a higher angle than a 0.040 in one (measured: league200 4.65 -> 4.80 deg, board 17.51 ->
    18.07; the cranker 6.05 -> 6.17 deg, board 17.53 -> 18.06)."""
    d = _style(name).strike
    a = lane.throw(d, "house", lane.Ball(diff=0.04))
    b = lane.throw(d, "house", lane.Ball(diff=0.06))
    assert b.flare_in >= a.flare_in + 1.0  # inches of arc
    assert b.board_at_pins >= a.board_at_pins + 0.2  # more hook: further left at the pins (boards)
    assert b.entry_angle_deg >= a.entry_angle_deg + 0.02


@pytest.mark.slow
@pytest.mark.parametrize("name", ["league200", "cranker"])
def test_a_higher_differential_re_aimed_to_the_pocket_from_the_same_board_enters_steeper(name):
    """Issue 48: "a higher differential raises entry angle at the same target". Each ball re-aimed to
    board 17.5 from the profile's board (its launch angle changed), a 0.060 in differential enters
    steeper than a 0.040 in one (measured: league200 4.65 -> 4.76 deg, the cranker 6.05 -> 6.15 deg)."""
    d = profiles.profile(name).strike
    _, a = phases.aim_angle(d, 17.5, "house", lane.Ball(diff=0.04))
    _, b = phases.aim_angle(d, 17.5, "house", lane.Ball(diff=0.06))
    for r in (a, b):
        assert r.board_at_pins == pytest.approx(17.5, abs=0.1)  # both at the pocket (aimed to 0.05 board)
    assert b.entry_angle_deg >= a.entry_angle_deg + 0.05  # degrees
