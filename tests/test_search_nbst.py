"""nbst's search (variant "nbst"): it solves what the paper's search cannot, and each addition
can be switched off on its own."""
import dataclasses

import numpy as np
import pytest

from nbst import load_problem
from nbst.planted import planted
from nbst.search import solve, variant_params
from nbst.sim import simulate


@pytest.fixture(scope="module")
def s14():
    return load_problem("diamond-s14")


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_diamond_s14_solved_exactly(s14, seed):
    # threshold with a margin, not one lucky seed: seeds 1-8 needed 842-3,276 trials (median ~1,500;
    # measured after issue 24), the budget is 6x the worst; the paper's A is still at ~11,000 after 200,000
    sol = solve(s14, seed=seed, max_trials=20_000, target_cost=1e-6)
    m = sol.meta
    assert m["stopped"] == "target_cost" and m["cost"] < 1e-6 and m["order"] == 14
    assert simulate(s14, sol.velocities).cost == m["cost"]
    assert m["polish"]["runs"] > 0 and m["operators"]["bank"]["children"] > 0


def test_tiny_solved_by_the_straight_start():
    sol = solve(load_problem("diamond-s14-tiny"), seed=0, max_trials=1000, target_cost=1e-6)
    assert sol.meta["cost"] < 1e-6 and sol.meta["trials"] <= 30


def test_planted_instance_recovered(tmp_path):
    p, _ = planted(12, seed=21)
    sol = solve(p, seed=3, max_trials=50_000, target_cost=1e-6)
    assert sol.meta["cost"] < 1e-6


def test_noncueable_disks_stay_at_rest_and_strikes_run():
    # seeds 1-5 all reach order 5 with ~1,000-2,000 strike children in this budget: order >= 3 is the margin
    p = load_problem("over5")
    sol = solve(p, seed=2, max_trials=30_000, patience=0)
    assert np.all(sol.velocities[~p.cueable] == 0.0)
    assert sol.meta["operators"]["strike"]["children"] > 0
    assert sol.meta["order"] >= 3


@pytest.mark.parametrize("off, check", [
    ({"polish": False}, lambda m: m["polish"]["runs"] == 0),
    ({"bank_weight": 0.0}, lambda m: m["operators"]["bank"]["children"] == 0),
    ({"adapt": True}, lambda m: m["operator_probabilities"]["bank"] != pytest.approx(0.3 / 0.9)),
    ({"restart": 500}, lambda m: m["restarts"] >= 1),
])
def test_each_addition_switches_alone(s14, off, check):
    params = dataclasses.replace(variant_params("nbst"), **off)
    m = solve(s14, seed=4, max_trials=4000, patience=0, params=params).meta
    assert check(m)
    full = variant_params("nbst")
    changed = {k for k, v in dataclasses.asdict(params).items() if dataclasses.asdict(full)[k] != v}
    assert changed == set(off)


def test_defaults_have_fixed_probabilities_and_strikes_only_with_noncueable_disks(s14):
    m = solve(s14, seed=6, max_trials=6000, patience=0).meta
    assert m["restarts"] == 0
    assert m["operator_probabilities"]["bank"] == pytest.approx(0.3 / 0.9)  # strike's 0.1 dropped, renormalized
    assert m["operators"]["strike"]["children"] == 0  # diamond-s14 has no noncueable disk


@pytest.mark.parametrize("variant, problem", [("A", "diamond-s14"), ("B", "over5"), ("F", "diamond-s14")])
def test_nbst_loop_with_every_addition_off_is_the_papers_loop(variant, problem):
    """Both loops share their common steps (nbst.search.loop): nbst's with every addition off
    draws the same random numbers and makes the same population, bit for bit."""
    from nbst.search import driver as D

    p = load_problem(problem)
    params = variant_params(variant, p)
    assert not params.nbst_loop  # every addition is off in the paper's variants
    runs = []
    for stepper in ("paper", "nbst"):
        prm = D._pack(p, params, max_trials=6000, patience=0, target_cost=None)
        s = D._new_state(p, params, seed=5)
        step = D._PaperStepper(p, params, s, prm, np.zeros((0, p.n, 2))) if stepper == "paper" \
            else D._NbstStepper(p, params, s, prm, seed=5)
        while (rc := step(1000)) != D.ChunkResult.MAX_TRIALS:
            if rc == D.ChunkResult.HISTORY_FULL:
                s.grow_history()
        runs.append(s)
    a, b = runs
    np.testing.assert_array_equal(a.st, b.st)
    np.testing.assert_array_equal(a.best_v, b.best_v)
    assert a.best_cost[0] == b.best_cost[0] and np.isfinite(a.best_cost[0])
    np.testing.assert_array_equal(a.rng, b.rng)
    for x, y in zip(a.pop, b.pop):
        np.testing.assert_array_equal(x, y)
    np.testing.assert_array_equal(a.op_count, b.op_count[:4])
    assert not b.op_count[4:].any()
    nh = int(a.st[D._L.ST_NHIST])
    for x, y in ((a.hist_t, b.hist_t), (a.hist_c, b.hist_c), (a.hist_o, b.hist_o)):
        np.testing.assert_array_equal(x[:nh], y[:nh])


def test_schedule_kernels_against_their_definitions():
    """_pick_op draws operator k with probability weights[k] / sum (never a zero weight);
    _pick_disk prefers a non-acceptable disk half of the time; _adapt keeps every enabled
    operator at or above the floor and the probabilities summing to 1."""
    from nbst.search.nbst_loop import N_OPS, _adapt, _pick_disk, _pick_op
    from nbst.search.ops import seed_state

    rng = seed_state(11)
    w = np.array([0.2, 0.1, 0.0, 0.2, 0.3, 0.2, 0.0])
    T = 40_000
    counts = np.bincount([_pick_op(rng, w) for _ in range(T)], minlength=N_OPS)
    assert counts[2] == 0 and counts[6] == 0
    # binomial std <= sqrt(T / 4) = 100 draws: 5 sigma
    np.testing.assert_allclose(counts / T, w / w.sum(), atol=500 / T)
    idx = np.arange(6, dtype=np.int64)
    sig = np.int64(0b110111)  # disk 3 alone is not acceptable
    picks = np.array([_pick_disk(idx, sig, rng, True) for _ in range(T)])
    assert abs((picks == 3).mean() - (0.5 + 0.5 / 6)) < 500 / T
    picks = np.array([_pick_disk(idx, sig, rng, False) for _ in range(T)])
    assert abs((picks == 3).mean() - 1 / 6) < 500 / T
    base = w / w.sum()
    weights, reward = base.copy(), base.copy()
    for k in range(2000):
        _adapt(weights, base, reward, k % N_OPS if base[k % N_OPS] > 0 else 0, k % 3 == 0, 0.05, 0.03)
    on = base > 0
    assert np.all(weights[on] >= 0.03 - 1e-12) and np.all(weights[~on] == 0.0)
    assert weights.sum() == pytest.approx(1.0, rel=1e-12)


def test_cost_signature_is_the_sum_of_squares_and_the_within_r_mask():
    from nbst.sim import cost_signature

    rng = np.random.default_rng(4)
    for n in (1, 7, 63):
        final, target = rng.uniform(0, 100, (n, 2)), rng.uniform(0, 100, (n, 2))
        R = 40.0
        c, s = cost_signature(final, target, R)
        d2 = ((final - target) ** 2).sum(axis=1)
        assert c == pytest.approx(d2.sum(), rel=1e-12)
        assert s == sum(1 << i for i in range(n) if d2[i] <= R * R)
