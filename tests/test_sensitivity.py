"""nbst.sim.sensitivity: amplification against finite differences and closed forms; the
fixed-step prediction against closed forms and against MuJoCo itself."""
import json
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))
from conftest import make_problem  # noqa: E402

from nbst.sim.jacobian import final_jacobian, transition_jacobian  # noqa: E402
from nbst.sim.sensitivity import analyze  # noqa: E402
from nbst.sim import simulate  # noqa: E402

H = 0.00025


def _same_sequence(a, b):
    return len(a.events) == len(b.events) and np.array_equal(a.events[["kind", "i", "j"]], b.events[["kind", "i", "j"]])


def _fd_jacobian(p, v, step=1e-5):
    """Central differences of the final positions over the cueable velocity components (None at a
    change of collision sequence)."""
    tr = simulate(p, v)
    cols = []
    for i in np.flatnonzero(p.cueable):
        for c in range(2):
            dv = np.zeros_like(v)
            dv[i, c] = step
            tp, tm = simulate(p, v + dv), simulate(p, v - dv)
            if not (_same_sequence(tp, tr) and _same_sequence(tm, tr)):
                return None
            cols.append((tp.final_positions - tm.final_positions).ravel() / (2 * step))
    return np.array(cols).T


def _collision_problems(count):
    """Small random problems whose motion has at least one disk-disk collision."""
    rng = np.random.default_rng(7)
    while count:
        starts = []
        while len(starts) < 4:
            c = rng.uniform(30, 370, 2)
            if all(np.hypot(*(c - s)) >= 45 for s in starts):
                starts.append(c)
        p = make_problem(starts, 20.0, box=(400, 400), t_final=3.0, masses=rng.uniform(0.5, 2, 4),
                         cueable=[True, True, True, False], targets=rng.uniform(30, 370, (4, 2)), R=60.0)
        v = rng.uniform(-150, 150, (4, 2))
        v[3] = 0.0
        tr = simulate(p, v)
        if tr.n_disk_disk < 1 or len(tr.events) > 12:
            continue
        J = _fd_jacobian(p, v)
        if J is None:
            continue
        count -= 1
        yield p, v, J


def test_amplification_matches_finite_differences():
    for p, v, Jfd in _collision_problems(8):
        a = analyze(p, v)
        # central differences err by ~h^2 * curvature + round-off / h ~ 1e-8 of |J| here
        assert a["amplification"] == pytest.approx(np.linalg.svd(Jfd, compute_uv=False)[0], rel=1e-6)
        for i in range(p.n):
            assert a["per_disk"][i] == pytest.approx(np.linalg.svd(Jfd[2 * i:2 * i + 2], compute_uv=False)[0],
                                                     rel=1e-6, abs=1e-9)
        json.dumps(a, allow_nan=False)  # JSON-ready: no numpy types, no nan / inf


def test_transition_from_an_intermediate_time_is_the_jacobian_of_the_rest():
    # Phi(t_final <- t): its velocity columns are the final Jacobian of the motion restarted at t,
    # its position columns finite differences of the restarted motion's starts
    for p, v, _ in _collision_problems(3):
        tr = simulate(p, v)
        t = 0.5 * (tr.events["time"][0] + (tr.events["time"][1] if len(tr.events) > 1 else p.t_final))
        Phi = transition_jacobian(p, v, t)
        assert Phi.shape == (2 * p.n, 4 * p.n)
        x_t, v_t = tr.at(t), tr.velocity_at(t)
        q = make_problem(x_t, p.radius, box=p.box, t_final=p.t_final - t, masses=p.mass, cueable=[True] * p.n)
        _, Jq = final_jacobian(q, v_t)
        # the same tangent map from two starts: only round-off of the time shift separates them
        assert np.abs(Phi[:, 2 * p.n:] - Jq).max() <= 1e-9 * max(1.0, np.abs(Jq).max())
        ref = simulate(q, v_t)
        step = 1e-5
        for k in range(2 * p.n):
            dx = np.zeros((p.n, 2))
            dx[k // 2, k % 2] = step
            qp = make_problem(x_t + dx, p.radius, box=p.box, t_final=q.t_final, masses=p.mass, cueable=[True] * p.n)
            qm = make_problem(x_t - dx, p.radius, box=p.box, t_final=q.t_final, masses=p.mass, cueable=[True] * p.n)
            tp, tm = simulate(qp, v_t), simulate(qm, v_t)
            assert _same_sequence(tp, ref) and _same_sequence(tm, ref)
            col = (tp.final_positions - tm.final_positions).ravel() / (2 * step)
            assert np.abs(Phi[:, k] - col).max() <= 1e-5 * max(1.0, np.abs(col).max())
    # at t = 0 the cueable velocity columns are final_jacobian's J
    p, v, _ = next(_collision_problems(1))
    _, J = final_jacobian(p, v)
    cols = [2 * p.n + 2 * i + c for i in np.flatnonzero(p.cueable) for c in range(2)]
    assert np.array_equal(transition_jacobian(p, v, 0.0)[:, cols], J)


def test_a_lone_disk_between_walls_amplifies_by_t_final():
    # a free particle: d x / d v = t; each wall bounce is a reflection (|.| kept), so sigma = t_final
    p = make_problem([[400, 300]], 10.0, box=(800, 600), t_final=5.0, targets=[[100, 100]])
    v = np.array([[537.0, -311.0]])
    tr = simulate(p, v)
    assert tr.n_wall >= 6
    a = analyze(p, v)
    assert a["amplification"] == pytest.approx(5.0, rel=1e-9)
    assert a["per_disk"][0] == pytest.approx(5.0, rel=1e-9)


def test_velocity_tolerance_is_where_the_disk_leaves_its_target():
    # lone disk, no bounce, ends at x = 500, d = 30 past its target (R = 75): tolerance
    # (R - d) / t_final = 11.25 units/s; a velocity error of 0.99 of it straight away from the
    # target keeps it inside, 1.01 takes it out
    p = make_problem([[100, 300]], 10.0, box=(800, 600), t_final=4.0, targets=[[470, 300]], R=75.0)
    v = np.array([[100.0, 0.0]])
    a = analyze(p, v)
    assert a["velocity_tolerance"] == pytest.approx(45.0 / 4.0, rel=1e-12)
    assert a["on_target"] == [True]
    away = np.array([[1.0, 0.0]])
    assert simulate(p, v + 0.99 * a["velocity_tolerance"] * away).signature == 1
    assert simulate(p, v + 1.01 * a["velocity_tolerance"] * away).signature == 0
    # a noncueable disk nobody strikes does not respond: no tolerance of its own
    q = make_problem([[100, 300], [600, 500]], 10.0, box=(800, 600), t_final=4.0, cueable=[True, False],
                     targets=[[470, 300], [600, 500]])
    b = analyze(q, np.array([[100.0, 0.0], [0.0, 0.0]]))
    assert b["velocity_tolerance_per_disk"][1] is None
    assert b["velocity_tolerance"] == pytest.approx(45.0 / 4.0, rel=1e-12)


def test_one_wall_bounce_predicts_twice_the_normal_speed_times_h():
    # one bounce off the right wall: MuJoCo's one-step delay offsets the disk by 2 |v_n| h, and the
    # rest of the motion (free flight) carries it unchanged
    p = make_problem([[600, 300]], 10.0, box=(800, 600), t_final=1.5, targets=[[600, 300]])
    v = np.array([[333.0, 47.0]])
    tr = simulate(p, v)
    assert tr.n_wall == 1
    pr = analyze(p, v, timestep=H)["prediction"]
    assert pr["impacts"] == pr["wall_impacts"] == 1
    for key in ("predicted_error_max", "predicted_error_rss_max", "predicted_error_linear_max"):
        assert pr[key] == pytest.approx(2 * 333.0 * H, rel=1e-9)
    assert pr["predicted_offset"][0] == pytest.approx([2 * 333.0 * H, 0.0], rel=1e-9, abs=1e-15)
    assert pr["timestep"] == H and pr["within_first_order"]


def test_prediction_against_fixed_step_mujoco():
    pytest.importorskip("mujoco")
    from nbst.models.mjrun import run_mujoco

    # walls only: MuJoCo's bounce is exact and exactly one step late, so the signed first-order
    # offset is MuJoCo's own to round-off over 20,000 steps (measured 1e-8 units on diamond-s14)
    p = make_problem([[150, 200], [500, 420]], 10.0, box=(800, 600), t_final=5.0)
    v = np.array([[431.0, 173.0], [-260.0, -345.0]])
    tr = simulate(p, v)
    assert tr.n_disk_disk == 0 and tr.n_wall >= 8
    pr = analyze(p, v, timestep=H)["prediction"]
    run = run_mujoco(p, v, timestep=H)
    assert np.abs(run.final_positions - tr.final_positions - np.array(pr["predicted_offset"])).max() < 1e-6

    # two disks, 5 wall bounces and one oblique collision each (measured: MuJoCo / linear prediction
    # 0.86-1.24 per disk; MuJoCo / worst case 0.08-0.49: the worst case adds norms that partly cancel,
    # and spreads the pair's normal over the unknown phase, which itself moves the error by
    # 0.79-1.40x). Bounds: measured <= worst case, and within [0.7, 1.4] of the linear prediction
    p = make_problem([[100, 120], [280, 260]], 15.0, box=(400, 400), t_final=3.0)
    for v in ([[-202.9, -33.4], [-10.5, -170.1]], [[164.9, 78.8], [91.4, 160.0]],
              [[-106.4, -169.6], [123.0, 91.7]]):
        v = np.array(v)
        tr = simulate(p, v)
        assert (tr.n_wall, tr.n_disk_disk) == (5, 1)
        pr = analyze(p, v, timestep=H)["prediction"]
        run = run_mujoco(p, v, timestep=H)
        meas = np.hypot(*(run.final_positions - tr.final_positions).T)
        assert np.all(meas <= np.array(pr["predicted_error_per_disk"]))
        ratio = meas / np.array(pr["predicted_error_linear_per_disk"])
        assert np.all((0.7 <= ratio) & (ratio <= 1.4)), ratio


def test_worst_case_bounds_the_others_and_big_errors_are_flagged():
    # per disk: sum of norms >= root-sum-square and >= |signed sum| (triangle inequality)
    for p, v, _ in _collision_problems(4):
        pr = analyze(p, v, timestep=H)["prediction"]
        w = np.array(pr["predicted_error_per_disk"])
        assert np.all(w >= np.array(pr["predicted_error_rss_per_disk"]) * (1 - 1e-12))
        assert np.all(w >= np.array(pr["predicted_error_linear_per_disk"]) * (1 - 1e-12))
    # a fast disk with many bounces at a coarse step: errors past the disk radius are flagged
    p = make_problem([[400, 300]], 10.0, box=(800, 600), t_final=5.0)
    pr = analyze(p, np.array([[2537.0, -1311.0]]), timestep=0.01)["prediction"]
    assert pr["impacts"] > 20 and pr["predicted_error_max"] > 10.0 and not pr["within_first_order"]


def test_a_strict_validation_that_fails_names_the_amplification_and_robust_mode(capsys):
    """Issue 35, item 6: where ``validate --strict`` fails on a chaotic motion, its message says how
    chaotic (the amplification, from this module) and what to do (``nbst solve --robust``)."""
    pytest.importorskip("mujoco")
    import re
    from pathlib import Path

    from nbst.cli import main
    from nbst.problem import load_problem
    from nbst.solution import load_solution

    f = Path(__file__).resolve().parents[1] / "models" / "scenes" / "over5" / "solution.json"
    assert main(["validate", "over5", str(f), "--strict", "-q"]) == 1  # this stored motion is chaotic
    err = capsys.readouterr().err
    m = re.search(r"amplification is ([0-9.e+]+) s", err)
    assert m and "nbst solve over5 --robust" in err, err
    p = load_problem("over5")
    amp = analyze(p, load_solution(f, p).velocities)["amplification"]
    assert float(m.group(1)) == pytest.approx(amp, rel=1e-3)  # printed to 4 digits
