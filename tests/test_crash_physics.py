"""The crash vehicles against published physics (docs/crash.md has the figures and sources).

Every test asserts a physical fact with its tolerance and the reason for it; the experiments
live in nbst.models.crash.checks (compute only)."""
import math

import pytest

from nbst.models.crash import checks, vehicle

G = vehicle.G


def _all_types():
    """Every registered vehicle type, in registration order."""
    return [vehicle.VEHICLE_TYPES[name] for name in vehicle.VEHICLE_TYPES]


@pytest.mark.parametrize("type_name", sorted(vehicle.VEHICLE_TYPES))
@pytest.mark.parametrize("speed", [20.0, 30.0])
@pytest.mark.parametrize("mu", [0.8, 0.5], ids=["dry", "wet"])
def test_braking_distance_is_v2_over_2_mu_g(type_name, speed, mu):
    # locked wheels slide with Coulomb friction: the stopping distance is v^2 / (2 mu g) whatever
    # the pitch and the load transfer (the normal forces sum to m g). 3 %: the brakes take a few
    # steps to lock the wheels and the tyres settle into the road (the tolerance).
    d = checks.braking_distance(type_name, speed, mu)
    assert d == pytest.approx(speed ** 2 / (2 * mu * G), rel=0.03)


def test_ssf_is_track_over_twice_the_cg_height():
    for vt in _all_types():
        assert vt.track / (2 * vt.cg_height) == pytest.approx(vt.ssf, rel=1e-12)


def test_the_scene_carries_the_vehicles_mass():
    from nbst.models.crash import road, scene

    vs = [scene.SceneVehicle(f"v{i}", vt, 10.0 * i, 0.0, 0.0) for i, vt in enumerate(_all_types())]
    m = scene.build_spec(road.Road(layout="straight"), vs, timestep=0.002).compile()
    L = scene.layout(m, len(vs))
    for mass, vt in zip(L.mass, _all_types()):
        assert mass == pytest.approx(vt.mass, rel=1e-9)  # body + 4 corners: exact by construction


@pytest.mark.slow
@pytest.mark.parametrize("type_name", sorted(vehicle.VEHICLE_TYPES))
def test_tilt_table_tips_at_the_static_stability_factor(type_name):
    # a rigid vehicle tips when the resultant of gravity passes over the low wheels: tan = SSF.
    # 2 degrees (the tolerance): the springs let the body roll and rise a little first.
    r = checks.tilt_angle(type_name)
    rigid = math.degrees(math.atan(vehicle.VEHICLE_TYPES[type_name].ssf))
    assert abs(r.tip_deg - rigid) <= 2.0, (r, rigid)
    assert r.lift_deg <= r.tip_deg + checks.TILT_RESOLUTION  # the uphill wheels lift before it tips


@pytest.mark.parametrize("speed_kmh", [15.0, 30.0, 60.0])
def test_momentum_is_conserved_through_the_impact(speed_kmh):
    # over the contact window the tyres (wheels free) pass on almost no force: the two vehicles'
    # momentum along the impact is conserved within 5 % (the tolerance; ~0.01 % here)
    r = checks.impact("sedan", speed_kmh)
    assert r.momentum_after == pytest.approx(r.momentum_before, rel=0.05)
    # and the impulse the contact sensor integrates is the struck car's delta-V (the tyres'
    # rolling and the suspension's swing account for the rest: 5 %)
    assert r.delta_v_impulse_kmh == pytest.approx(r.delta_v_kmh, rel=0.05)


def test_restitution_falls_with_impact_speed_inside_the_published_band():
    curve = checks.restitution_curve("sedan", checks.RESTITUTION_SPEEDS)
    for v, e in curve:
        lo, hi = checks.restitution_band(v)
        assert lo <= e <= hi, (v, e, lo, hi)
    e = curve[:, 1]
    # falling with speed: each point at most 0.005 above the one before (step noise), and the
    # whole curve down by at least 0.05 from 15 to 60 km/h
    assert (e[1:] <= e[:-1] + 0.005).all(), curve
    assert e[0] - e[-1] >= 0.05, curve


@pytest.mark.parametrize("type_name", sorted(vehicle.VEHICLE_TYPES))
def test_ncap_frontal_pulse_in_the_published_range(type_name):
    r = checks.barrier(type_name, 56.0)
    lo, hi = checks.NCAP_DURATION_S
    assert lo <= r.duration <= hi, r
    lo, hi = checks.NCAP_MEAN_G
    assert lo <= r.mean_g <= hi, r
    assert r.restitution < 0.2, r  # a barrier crash at 56 km/h is nearly plastic (SAE 931842: ~0.1)
