"""The pins fitted for carry (issue 34): USBC's limits, the graded pin's mass properties, the pin-deck
start the fit replays from, and the fitted contacts' restitution (benchmarks/bench_carry_fit.py)."""
from __future__ import annotations

import copy
import importlib.util
from pathlib import Path

import numpy as np
import pytest

from nbst.models.bowling import pin, pinfall, scene
from nbst.models.bowling.lane import frame, profiles, spares

INCH = 0.0254


def _bench(name: str):
    path = Path(__file__).resolve().parents[1] / "benchmarks" / f"{name}.py"
    spec = importlib.util.spec_from_file_location(name, path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.fixture(scope="module")
def model():
    return frame.frame_model()


def test_the_lane_halfs_pins_are_inside_usbcs_limits(model):
    lo, hi = pin.COM_LIMITS_IN
    for n in scene.PIN_NUMBERS:
        b = model.body(f"pin{n}")
        assert pin.MASS_LIMITS[0] <= float(b.mass[0]) <= pin.MASS_LIMITS[1]  # 3 lb 6 oz .. 3 lb 10 oz
        assert lo * INCH - 1e-6 <= float(b.ipos[2]) <= hi * INCH + 1e-6  # 5 40/64 .. 5 60/64 in
        assert abs(float(b.ipos[0])) < 1e-12 and abs(float(b.ipos[1])) < 1e-12  # on the axis
        assert b.inertia[0] == b.inertia[1] > b.inertia[2] > 0  # a solid of revolution


def test_a_graded_pin_puts_its_centre_of_gravity_where_asked_and_keeps_the_uniform_one():
    com0, i0 = pin.mass_properties()
    geo = pin.geometry()
    assert np.array_equal(com0, geo.com) and np.allclose(i0, geo.inertia, rtol=1e-15)
    for c in (pin.COM_LIMITS_IN[0], 5.8, pin.COM_LIMITS_IN[1]):
        com, inertia = pin.mass_properties(pin.MASS, c)
        assert com[2] == pytest.approx(c * INCH, abs=1e-9)
    # a pin heavier at the top (higher centre) is harder to tip about its base's diameter and spins
    # the same within 3 % about its axis; mass scales every moment
    lo = pin.mass_properties(pin.MASS, pin.COM_LIMITS_IN[0])[1]
    hi = pin.mass_properties(pin.MASS, pin.COM_LIMITS_IN[1])[1]
    assert hi[0] > i0[0] > lo[0] and abs(hi[2] / lo[2] - 1) < 0.03
    heavy = pin.mass_properties(pin.MASS_LIMITS[1], 5.8)[1]
    assert np.allclose(heavy, pin.mass_properties(pin.MASS, 5.8)[1] * pin.MASS_LIMITS[1] / pin.MASS, rtol=1e-12)
    with pytest.raises(ValueError, match="centre of gravity"):
        pin.mass_properties(pin.MASS, 6.0)
    with pytest.raises(ValueError, match="pin mass"):
        pin.mass_properties(1.7, None)


def test_a_frame_from_its_deck_start_sees_the_same_ball(model):
    d = spares.straight_at(*spares.aim_point((10,)))  # a spare: one pin in play, a short pin action
    st = frame.deck_start(d, model=model, standing=(10,))
    full = frame.run_frame(d, model=model, standing=(10,))
    assert st.board == full.board_at_pins and st.angle == full.entry_angle_deg  # the same steps to the deck
    assert st.qpos[int(model.joint("ball_free").qposadr[0])] >= scene.DECK_FRONT_X and st.in_play == [10]
    again = frame.run_frame(d, model=model, start=st)
    assert again.board_at_pins == full.board_at_pins and again.in_play == [10]
    assert again.ball_at_pins_s == pytest.approx(full.ball_at_pins_s, abs=0.011)
    # the pin stood on its spot until the ball came
    p = pinfall.poses(model, st.qpos)[9]
    assert np.abs(p[:2] - scene.pin_spots()[9]).max() < 1e-4 and not pinfall.tilted(p[None])[0]


def test_the_fitted_contacts_restitution_is_inside_the_measured_band(model):
    # Newton's restitution of head-on collisions, averaged over the step phase and the pin's turn
    # (benchmarks/bench_bowling_contacts.py): real pins ~0.5-0.6; the scene's damping ratio sets it
    bench = _bench("bench_bowling_contacts")
    m = copy.copy(model)
    e_bp = bench.mean_restitution(m, "ball-pin")
    e_pp = bench.mean_restitution(m, "pin-pin")
    assert 0.45 <= e_bp <= 0.7 and 0.45 <= e_pp <= 0.7, (e_bp, e_pp)


def test_the_fit_model_with_the_scenes_values_is_the_scene(model):
    # the carry fit's copies change only what they are told: with the scene's values, the same numbers
    fit = _bench("bench_carry_fit")
    m = fit.pin_deck_model(model, {})
    for attr in ("body_mass", "body_ipos", "body_inertia", "geom_friction", "geom_solref"):
        assert np.allclose(getattr(m, attr), getattr(model, attr), rtol=1e-5, atol=1e-9), attr


def test_the_pin_scatter_moves_each_pin_on_the_deck_and_leaves_it_standing_still(model):
    # bench_pocket_angle's probe of a pinsetter's spotting error (--setting spot_mm=...): the pins
    # are moved where the ball reaches the deck, so they must stand there at rest, apart, as set
    import mujoco

    fit = _bench("bench_carry_fit")
    st = frame.deck_start(spares.straight_at(*spares.aim_point((10,))), model=model)  # a full rack
    before = st.qpos.copy()
    sigma = 0.006  # the probe's largest setting, 6 mm
    a, b = fit.scatter(model, st, sigma, 10_000), fit.scatter(model, st, sigma, 10_000)
    assert np.array_equal(a.qpos, b.qpos) and np.array_equal(st.qpos, before)  # seeded; the start kept
    p0, p1 = pinfall.poses(model, st.qpos), pinfall.poses(model, a.qpos)
    off = np.linalg.norm(p1[:, :2] - p0[:, :2], axis=1)
    assert np.all(off > 0) and off.max() < 5 * sigma * np.sqrt(2)  # every pin moved, none absurdly
    assert np.array_equal(p1[:, 2:], p0[:, 2:])  # its height and its turn kept: upright on the deck
    # the spots are 12 in apart and a pin's belly is 4.766 in across: no two pins touch
    gaps = [np.linalg.norm(p1[i, :2] - p1[j, :2]) for i in range(10) for j in range(i)]
    assert min(gaps) > 4.766 * INCH
    # with the ball out of reach, the moved pins stay where they were set, upright and at rest
    d = mujoco.MjData(model)
    d.qpos[:] = a.qpos
    bq = int(model.joint("ball_free").qposadr[0])
    d.qpos[bq:bq + 2] = (-10.0, 0.0)
    dof = [int(model.joint(f"pin{n}_free").dofadr[0]) for n in scene.PIN_NUMBERS]
    fastest = 0.0
    for _ in range(300):  # 0.3 s, longer than the ball takes from the deck front to the last row
        mujoco.mj_step(model, d)
        fastest = max(fastest, max(np.linalg.norm(d.qvel[v:v + 3]) for v in dof))
    p2 = pinfall.poses(model, d.qpos)
    assert fastest < 1e-3  # m/s: a pin set on the deck does not slide or rock
    assert np.abs(p2[:, :3] - p1[:, :3]).max() < 1e-4 and not pinfall.tilted(p2).any()


def test_a_ball_carried_sideways_on_the_deck_runs_the_same_path_a_board_over(model):
    # bench_pocket_angle --by-board (issue 48): the pro's ball moved onto another board where it reaches
    # the deck; the deck's friction is the same on every board, so the ball must run the same path,
    # moved sideways by exactly that many boards (to the bowler's left for a right-hander: board up)
    from nbst.models.bowling.lane.units import y_to_board

    bench = _bench("bench_pocket_angle")
    d = profiles.profile("pro").strike
    st = frame.deck_start(d, model=model, standing=(7,))  # the 7 alone: the pocket's line meets no pin
    bq = int(model.joint("ball_free").qposadr[0])

    def path(start):
        out = []
        frame.run_frame(d, model=model, start=start, record=lambda dd: out.append(dd.qpos[bq:bq + 2].copy()))
        return np.array(out[:400])  # the deck and the pit edge: 0.4 s

    for dboard in (1.0, -0.6):
        moved = bench.shifted(st, st.board + dboard, bq, d.hand)
        assert moved.board == st.board + dboard and np.array_equal(st.qpos[bq + 2:], moved.qpos[bq + 2:])
        a, b = path(st), path(moved)
        a, b = a[:len(b)], b[:len(a)]
        assert len(a) > 200
        assert np.abs(a[:, 0] - b[:, 0]).max() < 1e-9  # the same run down the deck
        assert np.abs(y_to_board(b[:, 1]) - y_to_board(a[:, 1]) - dboard).max() < 1e-6  # a board over
