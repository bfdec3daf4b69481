"""The bowling scene's ball-pin and pin-pin contacts (issue 22): the restitution they give, and
the separation of the two that benchmarks/bench_bowling_contacts.py varies them with.

Restitution is measured as that benchmark does: a head-on collision in the frame model with
gravity off (ball at 7 m/s into a pin at its centre-of-mass height; pin at 3 m/s into a pin at
belly height), averaged over 4 yaws of the struck pin and 8 phases of the first touch within a
step (one collision alone moves by about 0.1 with the phase).
"""
from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from nbst.models.bowling import scene
from nbst.models.bowling.lane import frame, spares


@pytest.fixture(scope="module")
def bench():
    path = Path(__file__).resolve().parents[1] / "benchmarks" / "bench_bowling_contacts.py"
    spec = importlib.util.spec_from_file_location("bench_bowling_contacts", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.fixture(scope="module")
def base():
    return frame.frame_model()


def test_default_restitution_is_about_six_tenths(bench, base):
    # scene.SOLREF_BODY = (0.008, 0.2): measured 0.60 ball-pin and 0.58 pin-pin; a band of +-0.08
    m = bench.contact_model(base)
    e_bp = bench.restitutions(m, "ball-pin")
    e_pp = bench.restitutions(m, "pin-pin")
    assert 0.52 <= e_bp.mean() <= 0.68, e_bp.mean()
    assert 0.50 <= e_pp.mean() <= 0.66, e_pp.mean()
    assert (e_bp > 0.3).all() and (e_bp < 0.9).all() and (e_pp > 0.3).all() and (e_pp < 0.9).all()


@pytest.mark.parametrize("kind", ["ball-pin", "pin-pin"])
def test_restitution_falls_as_the_damping_ratio_rises(bench, base, kind):
    key = "bp_zeta" if kind == "ball-pin" else "pp_zeta"
    e = [bench.mean_restitution(bench.contact_model(base, **{key: z}), kind) for z in (0.1, 0.2, 0.3)]
    assert e[0] - e[1] > 0.05 and e[1] - e[2] > 0.05, e


def test_ball_pin_and_pin_pin_are_varied_apart(bench, base):
    m0 = bench.contact_model(base)
    e_bp0, e_pp0 = bench.mean_restitution(m0, "ball-pin"), bench.mean_restitution(m0, "pin-pin")
    ball = bench.contact_model(base, bp_zeta=0.3, bp_mu=0.18)  # the ball's contacts with pins only
    assert bench.mean_restitution(ball, "pin-pin") == e_pp0
    assert bench.mean_restitution(ball, "ball-pin") < e_bp0 - 0.05
    pins = bench.contact_model(base, pp_zeta=0.3, pp_mu=0.06)  # pin-pin only
    assert bench.mean_restitution(pins, "ball-pin") == e_bp0
    assert bench.mean_restitution(pins, "pin-pin") < e_pp0 - 0.05
    # the ball still rolls on the deck's friction, not its own: priority 2 surfaces over the ball's 1 (on the
    # lane before the deck its friction is Coulomb's, applied by hand: models/bowling/lane/friction.py)
    g = ball.geom("lane_deck").id
    assert ball.geom_priority[g] > ball.geom_priority[ball.geom("ball").id] > ball.geom_priority[bench.pin_geoms(ball)[0]]


def test_the_separated_copy_with_default_values_is_the_scene(bench, base):
    r0 = frame.run_frame(spares.STRIKE, model=base)
    r1 = frame.run_frame(spares.STRIKE, model=bench.contact_model(base))
    assert np.array_equal(r0.final_qpos, r1.final_qpos)
    # the scene's own (shared, cached) model is untouched by the copies
    assert base.geom_friction[base.geom("ball").id, 0] == scene.MU_BALL_PIN
    assert tuple(base.geom_solref[base.geom("ball").id]) == scene.SOLREF_BODY
    assert int(base.geom_priority.max()) == 1 and int(base.geom_priority[base.geom("ball").id]) == 0
