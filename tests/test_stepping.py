"""Aligned stepping (nbst.models.stepping) against the exact simulator; convergence; report keys.

Every tolerance below is stated against what fixed stepping does on the same case (an impact
one step late: |dv| h, 0.15 units for a 300 units/s wall bounce at h = 0.25 ms) and what aligned
stepping is built to reach (an impact late by overlap / speed: ~1e-12 units at the default tol;
coupled contacts of one instant go one micro-step after another, the later one deepening by
u h_c meanwhile, ~1e-8 units).
"""
import json
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))
from conftest import make_problem  # noqa: E402

mujoco = pytest.importorskip("mujoco")

from nbst import simulate  # noqa: E402
from nbst.cli import main  # noqa: E402
from nbst.models.scene import build_model, scene_xml  # noqa: E402
from nbst.models.stepping import step_aligned  # noqa: E402

UNIT = 1e-3  # metres per problem unit in the scenes


def _aligned(p, v, *, h=0.00025, model=None):
    """Final positions and velocities (problem units) after aligned stepping, the stats and the events."""
    m = model if model is not None else build_model(p, v, timestep=h)
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    events = []
    stats = step_aligned(m, d, p.t_final, on_event=lambda *a: events.append(a))
    pos = np.asarray(p.start) + d.qpos.reshape(-1, 2) / UNIT
    vel = d.qvel.reshape(-1, 2) / UNIT
    return pos, vel, stats, events, d


def _energy(p, v):
    return 0.5 * float((np.asarray(p.mass)[:, None] * np.asarray(v) ** 2).sum())


def test_two_disks_five_wall_bounces_exact_to_1e6_units():
    # the calibration case: fixed steps miss the exact end by ~0.3 units; aligned must
    # be within 1e-6 (measured 2e-10) and keep the kinetic energy to 1e-9 (measured 1e-14)
    p = make_problem([[100, 100], [600, 500]], 10.0, t_final=5.0)
    v = np.array([[300.0, 157.0], [-193.0, -131.0]])
    tr = simulate(p, v)
    assert tr.n_wall == 5 and tr.n_disk_disk == 0
    pos, vel, stats, events, d = _aligned(p, v)
    assert abs(d.time - p.t_final) < 1e-12
    assert np.abs(pos - tr.final_positions).max() < 1e-6
    assert abs(_energy(p, vel) / _energy(p, v) - 1) < 1e-9
    assert stats.impacts == 5 == len(events)
    assert np.allclose(sorted(e[0] for e in events), tr.events["time"], atol=1e-9)
    from nbst.models.mjrun import run_final
    fixed, _, _ = run_final(p, v, timestep=0.00025)
    assert np.abs(fixed - tr.final_positions).max() > 0.05  # what aligned stepping removes


def test_model_fields_are_restored():
    p = make_problem([[100, 100]], 10.0, t_final=1.0)
    v = np.array([[-200.0, 50.0]])
    m = build_model(p, v)
    before = [m.opt.timestep, m.geom_solref.copy(), m.geom_margin.copy(), m.geom_contype.copy(),
              m.geom_conaffinity.copy()]
    _aligned(p, v, model=m)
    after = [m.opt.timestep, m.geom_solref, m.geom_margin, m.geom_contype, m.geom_conaffinity]
    assert before[0] == after[0]
    for a, b in zip(before[1:], after[1:]):
        assert np.array_equal(a, b)


def test_corner_hit_is_two_walls_at_one_instant():
    # aimed exactly at the corner: both walls at t = 1.8 s. Their impulses do not couple
    # (perpendicular normals), so one micro-step resolves both (measured 1.4e-13 units; one
    # after the other, the second overlap would grow by u h_c meanwhile: 1e-8)
    p = make_problem([[100, 100]], 10.0, t_final=3.0)
    v = np.array([[-50.0, -50.0]])
    tr = simulate(p, v)
    assert tr.n_wall == 2 and tr.events["time"][0] == tr.events["time"][1]
    pos, vel, stats, events, _ = _aligned(p, v)
    assert stats.impacts == 2 and stats.simultaneous == 1
    assert np.abs(pos - tr.final_positions).max() < 1e-6
    assert np.allclose(vel, tr.final_velocities, atol=1e-8)


def test_simultaneous_three_disk_contact_follows_the_exact_order():
    # disk 0 moves up into disks 1 and 2 (side by side, touching), meeting both at one instant.
    # nbst.sim resolves them one at a time (pair 0-1, then 0-2); aligned stepping must do the
    # same, and end within 1e-6 units (measured 2e-8) and 1e-6 units/s of the exact motion
    p = make_problem([[400, 300], [390, 500], [410, 500]], 10.0, t_final=3.0)
    v = np.array([[0.0, 100.0], [0, 0], [0, 0]])
    tr = simulate(p, v)
    assert tr.n_disk_disk == 2 and tr.events["time"][0] == tr.events["time"][1]
    pos, vel, stats, events, _ = _aligned(p, v)
    assert stats.impacts == 2
    assert np.abs(pos - tr.final_positions).max() < 1e-6
    assert np.abs(vel - tr.final_velocities).max() < 1e-6


def test_newton_cradle_passes_the_impulse_along():
    # disk 0 strikes a touching row (masses 1, 2, 1, 3): each impact hands the motion on at the
    # same instant; resting contacts (distance ~0, no approach) must not count as impacts
    p = make_problem([[200, 400], [400, 400], [420, 400], [440, 400]], 10.0, t_final=3.0, masses=[1, 2, 1, 3])
    v = np.array([[100.0, 0], [0, 0], [0, 0], [0, 0]])
    tr = simulate(p, v)
    pos, vel, stats, events, _ = _aligned(p, v)
    assert stats.impacts == tr.n_disk_disk + tr.n_wall
    assert np.abs(pos - tr.final_positions).max() < 1e-6
    assert np.abs(vel - tr.final_velocities).max() < 1e-6


@pytest.mark.parametrize("x0", [200.031, 200.05])
def test_graze_inside_one_step_is_found(x0):
    # a pass with miss distance 5e-6 units inside the sum of radii: the overlap lasts ~0.04 units
    # of travel, less than one 0.25 ms step at 300 units/s, so both step ends are apart; the
    # graze check must find it (measured error 1.6e-8 units; the exact deflection changes the
    # struck disk's velocity by ~0.4 units/s, 0.8 units by t_final)
    p = make_problem([[x0, 400], [500, 400 + 19.999995]], 10.0, t_final=2.0)
    v = np.array([[300.0, 0], [0, 0]])
    tr = simulate(p, v)
    assert tr.n_disk_disk == 1
    pos, vel, stats, events, _ = _aligned(p, v)
    assert stats.graze_checks >= 1
    assert stats.impacts == len(tr.events)
    assert np.abs(pos - tr.final_positions).max() < 1e-6


def test_exactly_tangent_contact_terminates():
    # touching with zero normal speed: no impulse to give; it must neither loop nor deflect
    p = make_problem([[200, 400], [500, 420]], 10.0, t_final=2.0)
    v = np.array([[300.0, 0], [0, 0]])
    tr = simulate(p, v)
    pos, vel, stats, events, _ = _aligned(p, v)
    assert stats.impacts <= len(tr.events)
    assert np.abs(pos - tr.final_positions).max() < 1e-6


def test_scene_loaded_from_mjcf_text():
    # the recipe of docs/mujoco.md: a scene written by `nbst mjcf`, plain mujoco, step_aligned
    p = make_problem([[100, 100], [600, 500]], 10.0, t_final=2.0)
    v = np.array([[300.0, 157.0], [-193.0, -131.0]])
    m = mujoco.MjModel.from_xml_string(scene_xml(p, v))
    pos, vel, stats, events, _ = _aligned(p, v, model=m)
    assert np.abs(pos - simulate(p, v).final_positions).max() < 1e-6


def test_convergence_errors_fall_with_h():
    # one wall bounce at 300 units/s and one collision, 1 s at h = 1 ms: the fixed-step error is
    # first order (|dv| h per impact), so h/32 must be ~32x below h; aligned far below both
    from nbst.models.convergence import CONVERGENCE_LADDER, convergence_study, fit_order
    p = make_problem([[700, 400], [300, 400]], 10.0, t_final=1.0)
    v = np.array([[300.0, 0.0], [150.0, 30.0]])
    ex = simulate(p, v)
    conv = convergence_study(p, v, ex, timestep=1e-3, unit=UNIT, max_steps=10**6)
    fixed = [e for e in conv if e["stepping"] == "fixed"]
    assert [e["divisor"] for e in fixed] == list(CONVERGENCE_LADDER)
    assert fixed[-1]["max_error"] < fixed[0]["max_error"] / 10
    aligned = [e for e in conv if e["stepping"] == "aligned"]
    assert len(aligned) == 1 and aligned[0]["h"] is None and aligned[0]["max_error"] < 1e-6
    assert aligned[0]["stats"]["impacts"] >= 1
    fit = fit_order(conv, p)
    assert 0.8 < fit["order"] < 1.2 and len(fit["points_h"]) >= 2


def test_convergence_skips_step_sizes_over_max_steps():
    from nbst.models.convergence import convergence_study
    p = make_problem([[700, 400]], 10.0, t_final=1.0)
    v = np.array([[300.0, 0.0]])
    conv = convergence_study(p, v, simulate(p, v), timestep=1e-3, unit=UNIT, max_steps=5000)
    skipped = [e for e in conv if e["skipped"]]
    assert [e["divisor"] for e in skipped] == [8, 16, 32]  # 8000+ steps
    assert all(e["max_error"] is None for e in skipped)


def test_cli_aligned_convergence_report(tmp_path, capsys):
    p = make_problem([[700, 400], [300, 400]], 10.0, t_final=1.0, name="conv")
    prob = tmp_path / "p.json"
    prob.write_text(json.dumps(p.to_dict()))
    sol = tmp_path / "s.json"
    sol.write_text(json.dumps({"problem": "conv", "velocities": [[300.0, 0.0], [150.0, 30.0]]}))
    rep = tmp_path / "rep"
    assert main(["validate", str(prob), str(sol), "--stepping", "aligned", "--convergence", "--timestep", "0.001",
                 "--report", str(rep)]) == 0
    out = capsys.readouterr().out
    assert "stepping   aligned" in out and "predicted" in out and "converge" in out
    d = json.loads((rep / "report.json").read_text())
    assert d["stepping"]["mode"] == "aligned"
    for k in ("steps", "bisections", "impacts", "wall_time"):
        assert k in d["stepping"]["cost"]
    assert d["mujoco"]["version"] == mujoco.__version__ and d["mujoco"]["timestep"] == 0.001
    assert len(d["convergence"]) == 7 and d["convergence_order"]["order"] is not None
    assert d["sensitivity"]["amplification"] > 0
    pc = d["prediction_check"]
    assert pc["verdict"] in ("right", "conservative", "wrong") and pc["measured_error_max"] > 0
    assert d["final_error"]["max"] < 1e-6
    html = (rep / "report.html").read_text()
    assert html.count("data:image/png;base64,") == 4  # + the convergence plot
    assert "Convergence" in html and "Sensitivity" in html and "Stepping: aligned" in html
    assert "http://" not in html and "https://" not in html


def test_cli_help_explains_the_new_flags(capsys):
    with pytest.raises(SystemExit):
        main(["validate", "--help"])
    text = capsys.readouterr().out
    assert "--stepping" in text and "aligned" in text and "--convergence" in text


def test_cli_rejects_unknown_stepping(capsys):
    with pytest.raises(SystemExit) as e:
        main(["validate", "over5", "x.json", "--stepping", "exact"])
    assert e.value.code == 2
