"""Robust mode (``nbst.search.robust``, ``solve(..., robust=True)``, ``nbst solve --robust``): reproducible
from the seed, never worse than what it chose from, recorded in the file, and its score means what
it says (start shifts that are physical, a collision-free motion that no shift can spoil)."""
import dataclasses
import json

import numpy as np
import pytest

from nbst import load_problem
from nbst.cli import main
from nbst.search.robust import SHIFT_STEPS, TIMESTEP, draws, robust_score, score
from nbst.search import solve, variant_params
from nbst.sim import simulate

TRIALS = 30_000  # over5 at ~300k trials/s plain, ~100k robust: well under a second each


@pytest.fixture(scope="module")
def over5():
    return load_problem("over5")


@pytest.fixture(scope="module")
def robust_run(over5):
    return solve(over5, seed=2, max_trials=TRIALS, patience=0, robust=True)


def _key(row):
    return (-row["order"], row["worst_distance"])


def test_reproducible_from_the_seed(over5, robust_run):
    again = solve(over5, seed=2, max_trials=TRIALS, patience=0, robust=True)
    # bitwise: same seed, same draws, same search, same choice
    assert np.array_equal(again.velocities, robust_run.velocities)
    assert again.meta["robust"] == robust_run.meta["robust"]
    assert again.meta["history"] == robust_run.meta["history"]


def test_robust_k0_leaves_the_search_as_it_was(over5):
    # robust_k = 0: the search is the plain one (its own random numbers untouched); only the choice differs
    plain = solve(over5, seed=5, max_trials=TRIALS, patience=0)
    params = dataclasses.replace(variant_params("nbst"), robust=True, robust_k=0)
    rob = solve(over5, seed=5, max_trials=TRIALS, patience=0, params=params)
    assert rob.meta["history"] == plain.meta["history"]
    assert rob.meta["robust"]["search_best"]["cost"] == pytest.approx(plain.meta["cost"], rel=1e-12)


def test_choice_is_no_worse_than_the_search_best(robust_run):
    r = robust_run.meta["robust"]
    assert _key(r["score"]) <= _key(r["score_of_search_best"])
    assert r["candidates"] >= 1 and 0 <= r["chosen"] < r["candidates"]


def test_more_robust_than_the_plain_best(over5, robust_run):
    # fixed seed + threshold: scored under the same fresh shifts, the robust solution keeps at least
    # as many disks on target as the plain best, and here strictly more (the plain best is chaotic)
    plain = solve(over5, seed=2, max_trials=TRIALS, patience=0)
    sp = robust_score(over5, plain.velocities, seed=11)
    sr = robust_score(over5, robust_run.velocities, seed=11)
    assert _key(sr) <= _key(sp)
    assert sr["order"] > sp["order"]
    assert sr["order"] >= 3


def test_recorded_in_meta_and_file(over5, robust_run, tmp_path):
    back = json.loads(json.dumps(robust_run.to_dict()))  # what the file holds
    assert back["params"]["robust"] is True and back["robust"]["score"]["order"] >= 1
    m = robust_run.meta
    assert m["params"]["robust"] is True and m["params"]["robust_k"] >= 1
    assert m["robust"]["timestep"] == TIMESTEP and m["robust"]["samples"] >= 1
    assert m["robust_simulations"] > 0
    # cost, signature and order are those of the written velocities, as `nbst simulate` sees them
    tr = simulate(over5, robust_run.velocities)
    assert tr.cost == pytest.approx(m["cost"], rel=1e-12) and tr.signature_string == m["signature"]
    plain = solve(over5, seed=2, max_trials=2000, patience=0)
    assert plain.meta["params"]["robust"] is False and "robust" not in plain.meta


def test_cli_robust_flag(tmp_path, capsys):
    out = tmp_path / "sol.json"
    assert main(["solve", "over5", "-o", str(out), "--seed", "1", "--max-trials", "5000", "--robust", "-q"]) == 0
    d = json.loads(out.read_text())
    assert d["params"]["robust"] is True and d["robust"]["score"]["order"] >= 1
    assert main(["solve", "over5", "-o", str(tmp_path / "x.json"), "--algorithm", "cma", "--robust", "-q"]) == 2
    assert "--robust" in capsys.readouterr().err
    with pytest.raises(SystemExit) as e:
        main(["solve", "--help"])
    assert e.value.code == 0
    help_text = " ".join(capsys.readouterr().out.split())
    assert "--robust" in help_text and "MuJoCo" in help_text and "shifted" in help_text


def test_draws_keep_starts_apart_and_inside(over5):
    zeta, smax = draws(over5, np.random.default_rng(0), 32)
    assert zeta.shape == (32, over5.n, 2) and np.all(smax > 0)
    r = over5.radius
    for q in range(32):
        x = over5.start + smax[q] * zeta[q]
        # inside the box (closed: a disk may touch a wall) and no pair overlapping, with round-off slack
        assert np.all(x >= r[:, None] - 1e-9) and np.all(x <= np.asarray(over5.box) - r[:, None] + 1e-9)
        d = np.hypot(*(x[:, None] - x[None]).transpose(2, 0, 1)) + np.eye(over5.n) * 1e9
        assert np.all(d >= (r[:, None] + r[None]) - 1e-9)


def test_touching_starts_are_never_shifted():
    from conftest import make_problem

    p = make_problem([(100, 100), (120, 100), (400, 400)], targets=[(50, 50), (700, 100), (400, 700)])
    _, smax = draws(p, np.random.default_rng(1), 8)
    assert np.all(smax == 0.0)


def test_free_flight_score_is_the_shift():
    # the tiny diamond's straight velocities meet nothing: every disk lands exactly on its target, and a
    # start shift moves the final position by exactly the shift (no collision to amplify it)
    p = load_problem("diamond-s14-tiny")
    v = p.straight_velocities()
    assert simulate(p, v).cost < 1e-12 and simulate(p, v).n_disk_disk == 0
    zeta, smax = draws(p, np.random.default_rng(3), 16)
    sc = score(p, v, zeta, smax, quantile=1.0)
    sigma = np.minimum(SHIFT_STEPS * TIMESTEP * np.hypot(*v.T).max(), smax)
    expect = max(np.hypot(*(sigma[q] * zeta[q]).T).max() for q in range(16))
    assert sc.order[0] == p.n and sc.kept[0] == 1.0
    assert sc.worst[0] == pytest.approx(expect, rel=1e-6, abs=1e-9)  # unfolded free flight: exact to round-off


def test_polish_on_target_keeps_the_disks_and_lowers_the_margin_objective(over5):
    from nbst.search.robust import MARGIN_POWER, polish_on_target

    # a plain order-5 solution: every disk on target, none exactly at its centre (cost ~ 1e4)
    v = solve(over5, seed=3, max_trials=TRIALS, patience=0).velocities
    d0 = np.hypot(*(simulate(over5, v).final_positions - over5.target).T)
    on = d0 <= over5.target_radius
    v2, sims = polish_on_target(over5, v, max_sims=40)
    d2 = np.hypot(*(simulate(over5, v2).final_positions - over5.target).T)
    assert 1 <= sims <= 40
    assert np.all(d2[on] <= over5.target_radius)  # no on-target disk lost
    assert ((d2[on] / 75) ** MARGIN_POWER).sum() <= ((d0[on] / 75) ** MARGIN_POWER).sum()  # accepted steps only
    assert np.all(v2[~over5.cueable] == 0.0)


def test_robust_eval_is_the_worst_cost_and_the_and_over_the_shifted_runs(over5):
    """The compiled robust score against a plain Python loop over the same shifted starts."""
    from nbst.search.loop import loop_scratch, problem_arrays
    from nbst.search.robust import RobustDraws, robust_eval, shift_sigma
    from nbst.sim import evaluate_kernel

    sol = solve(over5, seed=1, max_trials=5000, patience=0)
    v = np.ascontiguousarray(sol.velocities)
    pa = problem_arrays(over5, np.zeros((0, 2), np.int64))
    zeta, smax = draws(over5, np.random.default_rng(3), 6)
    rd = RobustDraws(zeta, smax)
    shift = SHIFT_STEPS * TIMESTEP * 40  # a shift large enough to lose disks in some draws
    R = float(over5.target_radius)
    f = np.empty((1, over5.n, 2))
    c0, s0, ne = np.empty(1), np.empty(1, np.int64), np.empty(1, np.int64)
    evaluate_kernel(pa.x0, v[None], pa.radius, pa.mass, pa.target, pa.W, pa.H, pa.t_final, R, 200_000, f, c0, s0, ne)
    sigma = shift_sigma(v, pa.cue_idx, shift)
    costs, sigs = [c0[0]], [int(s0[0])]
    for k in range(len(smax)):
        x0 = np.ascontiguousarray(pa.x0 + min(sigma, smax[k]) * zeta[k])
        evaluate_kernel(x0, v[None], pa.radius, pa.mass, pa.target, pa.W, pa.H, pa.t_final, R, 200_000, f, c0, s0, ne)
        costs.append(c0[0])
        sigs.append(int(s0[0]))
    ref_sig = 0 if not sigs else sigs[0]
    for s in sigs:
        ref_sig &= s
    c, s, sims = robust_eval(pa, v, R, 200_000, rd, shift, costs[0], sigs[0], False, np.empty((over5.n, 2)),
                             loop_scratch(over5.n, 1))
    assert sims == len(smax)
    assert c == max(costs) and s == ref_sig
    assert max(costs) > costs[0]  # the shifts matter here
