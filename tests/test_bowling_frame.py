"""A frame from the foul line (issue 22): settled USBC pinfall, dead wood, release noise,
Wilson intervals, reproducibility (models/bowling/frame.py, noise.py, spares.py)."""
from __future__ import annotations

import math

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")

from nbst.models.bowling import lane, scene  # noqa: E402
from nbst.models.bowling.lane import frame, noise, spares
from nbst.models.bowling import pinfall

#: The league-200 release aimed at the pocket (tests/test_bowling_lane.py).
TYPICAL = lane.Delivery(board=20.0, at="foul", angle=2.82, rpm=350.0, rotation=45.0, tilt=12.0)


def test_the_typical_release_is_counted_when_the_pins_settle_or_at_the_pinsetters_sweep():
    r = frame.run_frame(TYPICAL)
    assert r.ball_at_pins_s is not None and r.settled != r.cap_hit
    end = r.ball_at_pins_s + frame.SWEEP_AFTER_PINS
    if r.settled:  # settled before the sweep: it holds 2 s longer
        assert r.ball_at_pins_s < r.settle_s <= end + frame.CHECK_EVERY
        longer = frame.run_frame(TYPICAL, extra_s=2.0)
        assert longer.leave == r.leave and longer.seconds == pytest.approx(r.seconds + 2.0, abs=1e-6)
    else:  # counted at the sweep, pins still moving: the sweep's time, within one check
        assert r.seconds == pytest.approx(end, abs=frame.CHECK_EVERY + 1e-6)


def test_a_spare_frame_settles_and_holds_2_s_longer():
    d = spares.straight_at(*spares.aim_point((10,)))
    r = frame.run_frame(d, standing=[10])
    assert r.in_play == [10] and r.settled
    assert frame.run_frame(d, standing=[10], extra_s=2.0).leave == r.leave


def test_the_frame_enters_where_the_ball_alone_does():
    """The ball's inertia set by turning its body (frame) matches lane.py's recompiled model."""
    r = frame.run_frame(TYPICAL)
    t = lane.throw(TYPICAL)
    assert r.board_at_pins == pytest.approx(t.board_at_pins, abs=0.1)  # boards


def _settle(model, qpos, seconds=0.6):
    d = mujoco.MjData(model)
    d.qpos[:] = qpos
    mujoco.mj_step(model, d, nstep=int(seconds / model.opt.timestep))
    return d


def _pin_qpos(model, n, x, y, z, tilt_deg, toward_y):
    """A pin's qpos with its base at (x, y, z), tilted about x by tilt_deg towards sign(toward_y)."""
    a = math.radians(tilt_deg) * (-np.sign(toward_y))  # rotating +z about +x by -a tips it towards +y
    q = np.array(model.qpos0, dtype=float)
    adr = pinfall.pin_addresses(model)[n - 1]
    q[adr:adr + 7] = [x, y, z, math.cos(a / 2), math.sin(a / 2), 0.0, 0.0]
    return q


def test_dead_wood_a_pin_leaning_on_the_kickback_counts_as_down():
    m = frame.frame_model()
    half = scene.LANE_WIDTH / 2
    spot = scene.pin_spots()[6]  # pin 7, back left
    q = _pin_qpos(m, 7, spot[0], half - 0.006, 0.0, 40.0, +1)
    # on lane-4's pin deck (the pins' friction 0.1) its base slides off the deck's edge into the gutter
    # and the pin falls back onto the kickback: still rocking at 0.6 s (tilt 10.9, 6.5 mm/s, off the
    # wall), at rest on it from 0.8 s (tilt 14.2-14.6 up to 3 s)
    d = _settle(m, q, seconds=1.0)
    adr = pinfall.pin_addresses(m)[6]
    p = d.qpos[adr:adr + 7]
    tilt = math.degrees(math.acos(1 - 2 * (p[4] ** 2 + p[5] ** 2)))
    knocked, off, partition = frame.settled_pinfall(m, d, [7])
    assert partition == [7], f"pin 7 at {tilt:.1f} deg, base y {p[1]:.3f}: not touching the kickback"
    assert tilt < pinfall.DOWN_TILT_DEG and knocked == []  # the 45-degree rule alone would call it standing
    assert not pinfall.pins_down(m, d.qpos)[6] or off  # the old rule: standing unless off the deck


def test_dead_wood_a_pin_lying_in_the_gutter_counts_as_down():
    m = frame.frame_model()
    y = scene.LANE_WIDTH / 2 + scene.GUTTER_WIDTH / 2
    spot = scene.pin_spots()[9]
    q = _pin_qpos(m, 10, spot[0], -y, 0.0, 90.0, -1)
    q[pinfall.pin_addresses(m)[9] + 2] = 0.02  # just above the gutter's bottom
    d = _settle(m, q)
    knocked, off, partition = frame.settled_pinfall(m, d, [10])
    assert off == [10]


def test_a_pin_at_rest_on_its_spot_is_standing():
    m = frame.frame_model()
    d = _settle(m, np.array(m.qpos0))
    assert frame.settled_pinfall(m, d, list(range(1, 11))) == ([], [], [])


def test_the_noise_draws_have_the_stated_sigmas():
    n = 4000
    base = lane.Delivery(board=20.0, at="foul", angle=0.0, mph=17.0, rpm=300.0, rotation=45.0, tilt=15.0)
    draws = noise.sample(base, n, seed=3)
    for key in ("board", "angle", "mph", "rpm", "rotation"):
        v = np.array([getattr(d, key) for d in draws])
        sd = getattr(noise.DEFAULT, key)
        # the sample sd of n normals has a standard error of sd / sqrt(2 n): 4 of them
        assert v.std(ddof=1) == pytest.approx(sd, abs=4 * sd / math.sqrt(2 * n)), key
        assert v.mean() == pytest.approx(getattr(base, key), abs=4 * sd / math.sqrt(n)), key
    assert all(d.tilt == 15.0 for d in draws)


def test_noise_draws_are_reproducible_and_the_arrows_board_becomes_the_foul_board():
    a = noise.sample(TYPICAL, 5, seed=7)
    assert a == noise.sample(TYPICAL, 5, seed=7) and a != noise.sample(TYPICAL, 5, seed=8)
    assert all(d.at == "foul" for d in a)
    assert np.mean([d.board for d in noise.sample(TYPICAL, 2000, seed=1)]) == pytest.approx(TYPICAL.foul_board(),
                                                                                           abs=0.05)


def test_wilson_interval_known_values():
    # Wilson (1927) / Newcombe (1998), 95 %: 81 of 263 -> 0.2553 .. 0.3662; 0 of 10 -> 0 .. 0.2775
    lo, hi = noise.wilson(81, 263)
    assert (lo, hi) == (pytest.approx(0.2553, abs=1e-4), pytest.approx(0.3662, abs=1e-4))
    lo, hi = noise.wilson(0, 10)
    assert lo == 0.0 and hi == pytest.approx(0.2775, abs=1e-4)
    with pytest.raises(ValueError):
        noise.wilson(3, 2)


def test_wilson_ends_are_exact_at_none_and_all():
    """At 0 of n the interval starts at 0 and at n of n it ends at 1, exactly (a throw file checks
    lo <= p <= hi; rounding once put 0 of 24 at lo = 1.4e-17)."""
    for n in range(1, 500):
        assert noise.wilson(0, n)[0] == 0.0 and noise.wilson(n, n)[1] == 1.0


def test_a_noisy_estimate_is_reproducible_from_its_seed_on_any_number_of_processes():
    with frame.FrameRunner(jobs=1) as one, frame.FrameRunner(jobs=2) as two:
        e1, r1 = noise.probability(TYPICAL, 4, 11, runner=one)
        e2, r2 = noise.probability(TYPICAL, 4, 11, runner=two)
    assert [r.leave for r in r1] == [r.leave for r in r2]
    assert [r.final_qpos.tolist() for r in r1] == [r.final_qpos.tolist() for r in r2]
    assert e1.to_dict() == e2.to_dict()


def test_the_ladder_runs_each_timestep():
    rs = frame.ladder(spares.straight_at(*spares.aim_point((7,))), standing=[7], timesteps=(0.001, 0.0005))
    assert [r.timestep for r in rs] == [0.001, 0.0005]
    assert all(r.settled for r in rs)


def test_bad_input_is_one_line():
    with pytest.raises(frame.FrameError, match="standing"):
        frame.run_frame(TYPICAL, standing=[11])
    with pytest.raises(frame.FrameError, match="timestep"):
        frame.frame_model(timestep=0.01)
    with pytest.raises(ValueError, match="noise.rpm"):
        noise.sample(TYPICAL, 2, 1, noise.Noise(rpm=-1))


def test_the_369_line_keeps_the_strike_lines_target_arrow():
    for name, (_, move) in spares.LEAVES.items():
        d = spares.system_369(name)
        assert d.board == pytest.approx(spares.STRIKE_FOUL - move)
        at_arrows = d.board - math.tan(math.radians(d.angle)) * lane.ARROWS_FT * lane.FT / lane.BOARD_WIDTH
        assert at_arrows == pytest.approx(spares.STRIKE_ARROW, abs=1e-9), name


def test_a_straight_spare_ball_crosses_where_it_was_aimed():
    x, y = spares.aim_point((10,))
    d = spares.straight_at(x, y)
    t = lane.throw(d)
    y_f = float(lane.board_to_y(d.board))
    want = float(lane.y_to_board(y_f + (y - y_f) * (-lane.FOUL_LINE_X) / (x - lane.FOUL_LINE_X)))
    # one correction on lane.throw: within a board (the board at the pins jitters by ~0.2 board
    # between launch angles 0.02 deg apart, the soft contact crossing the oil cells)
    assert t.board_at_pins == pytest.approx(want, abs=1.0)
    assert abs(t.entry_angle_deg) < 3.0  # straight: the lane's geometry only


def _cli(*args):
    import subprocess
    import sys

    return subprocess.run([sys.executable, "-m", "nbst.cli", "bowl", *args], capture_output=True, text=True,
                          timeout=120)


def test_bowl_spares_is_reproducible_from_its_seed_and_refuses_bad_input_in_one_line():
    a = _cli("spares", "--leaves", "7", "--samples", "2", "--screen", "1", "--seed", "5", "--jobs", "1", "--json")
    b = _cli("spares", "--leaves", "7", "--samples", "2", "--screen", "1", "--seed", "5", "--jobs", "2", "--json")
    assert a.returncode == 0 and a.stdout == b.stdout and '"leave": "7"' in a.stdout
    bad = _cli("spares", "--leaves", "7-7")
    assert bad.returncode == 2 and len(bad.stderr.strip().splitlines()) == 1 and "Traceback" not in bad.stderr
