"""nbst validate / nbst mjcf: cross-validation against the exact simulator, reports, CLI."""
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
from nbst.models.validate import validate  # noqa: E402


def _write_solution(path, problem, v):
    path.write_text(json.dumps({"problem": problem.name, "velocities": np.asarray(v).tolist()}))
    return str(path)


def _problem_file(path, problem):
    path.write_text(json.dumps(problem.to_dict()))
    return str(path)


def test_collision_free_solution_validates_within_a_tenth_of_a_unit():
    # four disks in free flight, one wall bounce at 80 units/s: MuJoCo's only error is the
    # bounce's one-step lag 2 v h = 0.04 units, so every disk must end within 0.1 units.
    p = make_problem([[100, 100], [300, 700], [600, 200], [700, 600]], 15.0, t_final=5.0)
    v = np.array([[60.0, 80.0], [50.0, -40.0], [-80.0, 20.0], [0.0, -60.0]])
    tr = simulate(p, v)
    assert tr.n_disk_disk == 0
    val = validate(p, v)
    assert val.final_error.max() < 0.1
    assert val.signatures_agree and val.diverge is None
    d = val.to_dict()
    assert d["events"]["matched"] == tr.n_wall and d["events"]["exact_only"] == 0 == d["events"]["mujoco_only"]
    # no contact-free step may lose kinetic energy beyond round-off (free flight and exact bounces)
    assert d["energy"]["drift_max_contact_free"] < 1e-9


def test_planted_overconstrained_motion_keeps_its_signature():
    # over5's own planted velocities are not stored, so build its kind by simulation
    # (nbst.planted: 5 disks of radius 10, 3 noncueable, each struck by a cueable disk; seed 4 has
    # 3 disk-disk collisions). The zero-cost motion must keep its full signature under MuJoCo and
    # every collision must be matched in order, within 2 ms (a few steps of lag).
    from nbst.planted import planted
    p, v = planted(5, noncue=3, radius=10.0, seed=4)
    tr = simulate(p, v)
    assert tr.order == 5 and tr.n_disk_disk >= 3 and tr.cost < 1e-12
    val = validate(p, v)
    assert val.mj_signature_string == "11111"
    off = val.matched_offsets
    assert len(val.matches) == len(tr.events) == len(val.mujoco.events)
    assert np.abs(off).max() < 2e-3
    assert val.final_error.max() < 5.0  # R = 75: far inside


def test_divergence_names_the_disk_and_event():
    # A 30-degree glancing collision errs ~0.1 deg; over 4 s of flight at 100 units/s the struck
    # disks part from their exact paths by about 1 unit: with tol = 0.2 the divergence must be
    # reported after the collision and blamed on it.
    p = make_problem([[300, 400], [500, 410]], 10.0, t_final=5.0)
    v = np.array([[100.0, 0], [0, 0]])
    val = validate(p, v, tol=0.2)
    assert val.diverge is not None
    assert val.diverge["time"] > val.exact.events["time"][0]
    assert "disks 0 and 1 collide" in val.diverge["cause"]


def test_cli_mjcf_and_validate_report(tmp_path, capsys):
    from nbst import load_problem
    p = load_problem("over5")
    sol = _write_solution(tmp_path / "s.json", p, p.straight_velocities())
    out = tmp_path / "scene.xml"
    assert main(["mjcf", "over5", sol, "-o", str(out)]) == 0
    m = mujoco.MjModel.from_xml_path(str(out))
    assert m.nkey == 1 and m.nbody == 1 + p.n
    rep = tmp_path / "rep"
    assert main(["validate", "over5", sol, "--report", str(rep), "--strict"]) in (0, 1)
    text = capsys.readouterr().out
    assert "signature" in text and "events" in text and "diverge" in text
    d = json.loads((rep / "report.json").read_text())
    assert d["problem"] == "over5" and len(d["final_error"]["per_disk"]) == p.n
    html = (rep / "report.html").read_text()
    assert html.count("data:image/png;base64,") == 3
    assert "http://" not in html and "https://" not in html  # self-contained


def test_cli_strict_exits_1_when_signature_differs(tmp_path, capsys):
    # one wall bounce at 300 units/s: MuJoCo ends 2 v h = 0.15 units off; a target radius of
    # 0.05 around the exact end makes the signatures 1 (exact) and 0 (MuJoCo)
    p0 = make_problem([[700.0, 400.0]], 10.0, t_final=1.0, name="strict")
    v = np.array([[300.0, 0.0]])
    end = simulate(p0, v).final_positions
    p = make_problem([[700.0, 400.0]], 10.0, t_final=1.0, name="strict", targets=end, R=0.05)
    prob = _problem_file(tmp_path / "p.json", p)
    sol = _write_solution(tmp_path / "s.json", p, v)
    assert main(["validate", prob, sol]) == 0
    assert main(["validate", prob, sol, "--strict"]) == 1
    assert "DIFFERENT" in capsys.readouterr().out


def test_cli_bad_input_exits_2(tmp_path, capsys):
    assert main(["validate", "over5", str(tmp_path / "missing.json")]) == 2
    with pytest.raises(SystemExit) as e:
        main(["mjcf", "over5", "--timestep", "-1"])
    assert e.value.code == 2


#: report.json's layout (golden): the keys at each level. A change here is a format change:
#: bump SCHEMA_VERSION in nbst/models/validate.py and say so in docs/mujoco.md.
REPORT_KEYS = {
    "": ["convergence", "convergence_order", "divergence", "energy", "events", "exact", "final_error", "mujoco",
         "mujoco_result", "n", "prediction_check", "problem", "schema_version", "sensitivity", "signatures_agree",
         "stepping", "t_final", "tolerance", "velocities"],
    "mujoco": ["steps", "timestep", "unit_m", "validate_wall_time_s", "version", "wall_time_s"],
    "stepping": ["cost", "mode", "reason", "record_stride", "requested", "stepping_wall_time_s", "steps", "timestep"],
    "prediction_check": ["fixed_run", "keeps_signature_measured", "keeps_signature_predicted",
                         "keeps_signature_predicted_rss", "measured_error_max", "measured_over_linear",
                         "predicted_error_linear_max", "predicted_error_max", "timestep", "verdict",
                         "within_first_order", "within_worst_case"],
    "final_error": ["exact_final", "max", "mean", "median", "mujoco_final", "per_disk", "worst"],
    "exact": ["cost", "disk_disk", "order", "signature", "truncated", "wall"],
    "mujoco_result": ["cost", "disk_disk", "order", "signature", "wall"],
    "events": ["exact", "exact_only", "first_mismatch", "matched", "mujoco", "mujoco_only", "offset_s",
               "offset_s_before_divergence"],
    "energy": ["drift_final", "drift_max_contact_free"],
}


def test_report_json_layout_is_golden():
    from nbst import load_problem
    from nbst.models.validate import SCHEMA_VERSION
    p = load_problem("over5")
    d = validate(p, p.straight_velocities(), timestep=1e-3).to_dict()
    assert d["schema_version"] == SCHEMA_VERSION == 4
    for level, keys in REPORT_KEYS.items():
        node = d if not level else d[level]
        assert sorted(node) == keys, level
    assert d["convergence"] is None and d["convergence_order"] is None  # only with convergence=True
    assert d["stepping"]["cost"] is None  # fixed stepping has no search cost
    json.dumps(d, allow_nan=False)  # plain JSON


def test_sensitivity_and_prediction_check_in_every_report():
    # diamond-s14-like wall-only motion: the fixed-step prediction is MuJoCo's own error to 1e-8
    # (nbst.sim.sensitivity's docstring), so the check must say "right" and measured/linear ~ 1
    p = make_problem([[100, 100], [600, 500]], 10.0, t_final=5.0)
    v = np.array([[300.0, 157.0], [-193.0, -131.0]])
    val = validate(p, v)
    pc = val.to_dict()["prediction_check"]
    assert pc["fixed_run"] == "this run" and pc["verdict"] == "right"
    assert abs(pc["measured_over_linear"] - 1) < 1e-6
    assert val.to_dict()["sensitivity"]["prediction"]["timestep"] == val.timestep
    assert "predicted" in val.summary()
    # aligned: the check uses an extra fixed-step run at the same h, with the same numbers
    al = validate(p, v, stepping="aligned").to_dict()
    assert al["prediction_check"]["fixed_run"] == "extra fixed-step run"
    assert abs(al["prediction_check"]["measured_error_max"] - pc["measured_error_max"]) < 1e-9
    assert al["final_error"]["max"] < 1e-6 and al["events"]["matched"] == 5


# --------------------------------------------------------------------------- many disks (issue 21)

from nbst.models.gas import gas_motion  # noqa: E402


def test_gas_motion_is_an_exact_solution_with_collisions_and_bounces():
    p, v = gas_motion(30, seed=2)
    tr = simulate(p, v)
    assert p.n == 30 and not tr.truncated
    assert np.abs(tr.final_positions - p.target).max() == 0.0  # targets are the exact ends
    assert tr.n_disk_disk >= 30 and tr.n_wall >= 10  # ~3 impacts per disk (fixed density)
    p2, v2 = gas_motion(30, seed=2)
    assert np.array_equal(v, v2) and np.array_equal(p.start, p2.start)  # reproducible from the seed


def test_auto_stepping_is_fixed_up_to_63_disks_and_aligned_above():
    from nbst.models.validate import AUTO_FIXED_MAX_N, choose_stepping

    small, _ = gas_motion(AUTO_FIXED_MAX_N)
    big, vb = gas_motion(AUTO_FIXED_MAX_N + 1)
    ex = simulate(big, vb)
    assert choose_stepping(small, simulate(small, _), 0.00025)[0] == "fixed"
    mode, why = choose_stepping(big, ex, 0.00025)
    assert mode == "aligned" and why.startswith("auto:")
    assert choose_stepping(big, ex, 0.00025, "fixed") == ("fixed", "--stepping fixed requested")

    class Busy:  # a motion with far more impacts than steps: the cost guard picks fixed
        events = np.zeros(10 ** 6)
    assert choose_stepping(big, Busy(), 0.00025)[0] == "fixed"


def test_positions_recorded_with_a_stride_end_where_every_step_does():
    from nbst.models.mjrun import run_mujoco
    p, v = gas_motion(10, t_final=0.5)
    full = run_mujoco(p, v)
    thin = run_mujoco(p, v, record_floats=2000)  # 2,001 steps x 20 numbers: every 21st step kept
    assert full.stride == 1 and thin.stride > 1 and thin.times.size < full.times.size / 10
    assert thin.steps == full.steps and thin.energy.size == full.energy.size
    assert np.array_equal(thin.final_positions, full.final_positions)  # the same MuJoCo steps
    assert np.array_equal(thin.events, full.events)
    t = thin.times[5]
    assert np.array_equal(thin.at(t), full.at(t))  # a recorded step is the step


@pytest.mark.slow
def test_mjcf_of_1000_disks_loads_with_every_body_at_full_precision():
    from nbst.models.scene import scene_xml
    p, v = gas_motion(1000)
    m = mujoco.MjModel.from_xml_string(scene_xml(p, v))
    assert m.nbody == 1001 and m.njnt == 2000  # the world and one body (two slide joints) per disk
    assert np.array_equal(m.key_qvel[0], (v * 1e-3).reshape(-1))  # the keyframe, bit for bit
    assert m.npair == 0 and m.nexclude == 0  # no pair lists: MuJoCo's broadphase finds the contacts


@pytest.mark.slow
def test_300_disks_validate_aligned_by_default_and_agree_with_the_exact_simulator():
    # 300 disks at area fraction 0.08, 784 collisions and 132 wall bounces in 2 s: aligned stepping (the
    # default above 63 disks) ends every disk within 0.01 units of the exact simulator (measured 4e-4;
    # fixed steps of 0.25 ms end ~400 units off on the same motion), with every event matched in order
    p, v = gas_motion(300)
    val = validate(p, v, sensitivity=False)
    d = val.to_dict()
    assert d["stepping"]["mode"] == "aligned" and d["stepping"]["requested"] == "auto"
    assert "above 63 disks" in d["stepping"]["reason"]
    assert val.final_error.max() < 0.01
    assert val.signatures_agree and d["exact"]["order"] == 300 == d["mujoco_result"]["order"]
    assert d["events"]["exact_only"] == 0 == d["events"]["mujoco_only"]
    assert abs(val.energy_drift_final) < 1e-9
    s = val.summary()
    assert "stepping   aligned: auto" in s and "order 300 of 300 disks on target" in s
    assert "1" * 300 not in s  # counts, not 300-character strings

    from nbst.render.report import EVENT_ROWS, WORST_ROWS, report_html
    page = report_html(val)
    assert "aligned stepping" in page and "Why this stepping: auto" in page
    assert page.count("<tr>") < 2 * EVENT_ROWS + WORST_ROWS + 40  # bounded: not one row per disk or event
    assert len(page) < 3_000_000


@pytest.mark.slow
def test_cli_validate_of_many_disks_shows_progress_and_q_silences_it(tmp_path, capsys):
    p, v = gas_motion(100)
    prob = _problem_file(tmp_path / "p.json", p)
    sol = _write_solution(tmp_path / "s.json", p, v)
    assert main(["validate", prob, sol, "--stepping", "fixed", "--sensitivity", "off"]) == 0
    out, err = capsys.readouterr()
    assert "nbst validate: MuJoCo, fixed steps: 8,000/8,000 steps (100%)" in err
    assert "stepping   fixed: --stepping fixed requested" in out
    assert main(["validate", prob, sol, "--stepping", "fixed", "--sensitivity", "off", "-q"]) == 0
    out, err = capsys.readouterr()
    assert out == "" and err == ""
