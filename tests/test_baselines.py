"""Baselines (nbst.solvers.baselines): exact trial accounting, improvement on a trivial problem,
cueable-only search, determinism, the dispatcher."""
from __future__ import annotations

import math

import numpy as np
import pytest

from nbst.errors import InputError
from nbst.solvers import SOLVERS, solve_cma, solve_with
from nbst.planted import planted
from nbst.problem import ProblemError, problem_from_dict

BASELINES = ("cma", "de", "ga", "random")

#: Two disks that must swap places: the straight paths meet head-on, so the
#: straight-line velocities score 96,800 (each disk bounces back), and order 0.
SWAP = {"name": "swap", "box": [400.0, 400.0], "t_final": 2.0, "target_radius": 30.0, "disks": [
    {"start": [100.0, 200.0], "target": [300.0, 200.0], "radius": 10.0},
    {"start": [300.0, 200.0], "target": [100.0, 200.0], "radius": 10.0}]}
SWAP_STRAIGHT_COST = 96_800.0


@pytest.fixture(scope="module")
def swap():
    return problem_from_dict(SWAP)


@pytest.fixture(scope="module")
def with_noncue():
    return planted(3, noncue=1, seed=5)[0]


@pytest.fixture
def sim_counter(monkeypatch):
    """Counts every candidate simulated through nbst.sim.evaluate."""
    import nbst.sim

    count = [0]
    real = nbst.sim.evaluate

    def counting(problem, V, **kw):
        count[0] += np.asarray(V).shape[0]
        return real(problem, V, **kw)

    monkeypatch.setattr(nbst.sim, "evaluate", counting)
    return count


@pytest.mark.parametrize("algorithm", BASELINES)
def test_budget_is_exact(algorithm, swap, sim_counter):
    # 1,003 is no multiple of any batch or population size: the last batch must be cut
    sol = solve_with(algorithm, swap, seed=1, max_trials=1003)
    m = sol.meta
    assert m["trials"] == 1003
    assert sim_counter[0] == 1003  # never simulates a candidate that is not counted
    assert m["stopped"] == "max_trials"
    assert all(1 <= t <= 1003 for t, _, _ in m["history"])


@pytest.mark.parametrize("algorithm", BASELINES)
def test_meta_and_history(algorithm, swap):
    m = solve_with(algorithm, swap, seed=2, max_trials=1500).meta
    for key in ("cost", "signature", "order", "trials", "seed", "algorithm", "wall_time", "nbst_version", "stopped",
                "history"):
        assert key in m
    assert m["seed"] == 2
    costs = [c for _, c, _ in m["history"]]
    trials = [t for t, _, _ in m["history"]]
    assert costs == sorted(costs, reverse=True) and len(set(costs)) == len(costs)  # strict improvements
    assert trials == sorted(trials)
    assert math.isclose(costs[-1], m["cost"])
    assert m["order"] == m["signature"].count("1") == m["history"][-1][2]


@pytest.mark.parametrize("algorithm", BASELINES)
def test_improves_on_a_trivial_problem(algorithm, swap):
    from nbst.sim import evaluate

    sol = solve_with(algorithm, swap, seed=3, max_trials=3000)
    # both disks within R, and at least 10x better than the straight-line start
    assert sol.meta["order"] == 2
    assert sol.meta["cost"] < SWAP_STRAIGHT_COST / 10
    _, cost, _ = evaluate(swap, sol.velocities[None])
    assert math.isclose(float(cost[0]), sol.meta["cost"], rel_tol=1e-12)  # the velocities give that cost


@pytest.mark.parametrize("algorithm", BASELINES)
def test_noncueable_disks_stay_at_rest(algorithm, with_noncue):
    sol = solve_with(algorithm, with_noncue, seed=4, max_trials=800)
    assert not with_noncue.cueable[2]
    assert np.all(sol.velocities[2] == 0.0)
    assert sol.meta["trials"] == 800


@pytest.mark.parametrize("algorithm", BASELINES)
def test_same_seed_same_result(algorithm, swap):
    a = solve_with(algorithm, swap, seed=7, max_trials=600)
    b = solve_with(algorithm, swap, seed=7, max_trials=600)
    assert np.array_equal(a.velocities, b.velocities)  # bitwise determinism is the claim
    assert a.meta["history"] == b.meta["history"]


@pytest.mark.parametrize("algorithm", BASELINES)
def test_stopping_rules(algorithm, swap):
    m = solve_with(algorithm, swap, seed=1, max_trials=100_000, target_cost=1e9).meta
    assert m["stopped"] == "target_cost" and m["trials"] <= 1024  # the first batch (generation) meets it
    m = solve_with(algorithm, swap, seed=1, max_trials=100_000, patience=300).meta
    assert m["stopped"] in ("patience", "converged") and m["trials"] < 100_000
    calls = []
    m = solve_with(algorithm, swap, seed=1, max_trials=100_000, callback=lambda p: calls.append(p.trials) or True).meta
    assert m["stopped"] == "callback" and len(calls) == 1 and m["trials"] == calls[0]


def test_dispatcher(swap):
    assert SOLVERS.names() == ("signature", "cma", "de", "ga", "random")
    r = solve_with("signature", swap, seed=1, max_trials=500, variant="A")
    assert r.variant == "A" and r.trials <= 500 and r.meta["variant"] == "A"
    with pytest.raises(InputError, match="unknown algorithm"):
        solve_with("pso", swap, seed=1, max_trials=10)
    with pytest.raises(ProblemError, match="variant"):
        solve_with("cma", swap, seed=1, max_trials=10, variant="B")
    with pytest.raises(ProblemError, match="robust"):
        solve_with("de", swap, seed=1, max_trials=10, robust=True)
    with pytest.raises(ProblemError, match="max_trials"):
        solve_with("ga", swap, seed=1, max_trials=0)


def test_cma_restarts_double_the_population(swap):
    # a restart is forced by a stopping rule we control (5 generations a restart), not by
    # pycma's own convergence tests, whose firing depends on the machine's float path
    m = solve_cma(swap, seed=1, max_trials=400, cma_options={"maxiter": 5}).meta
    ends = m["restart_ends"]
    pops = [e["population"] for e in ends]
    assert m["restarts"] == len(pops) - 1 >= 2
    assert pops == [pops[0] * 2**k for k in range(len(pops))]
    assert all("maxiter" in e["stop"] for e in ends[:-1])  # every finished restart ended by our rule
    # each finished restart used exactly 5 generations of its population
    used = np.diff([0] + [e["trials"] for e in ends[:-1]])
    assert list(used) == [5 * p for p in pops[:-1]]
    assert m["params"]["sigma0"] == pytest.approx(3.0 * 30.0 / 2.0)  # CMA_SIGMA0_FRACTION * R / t_final


def test_cli_solve_algorithm(tmp_path, capsys):
    import json

    from nbst.cli import main

    prob = tmp_path / "swap.json"
    prob.write_text(json.dumps(SWAP))
    out = tmp_path / "sol.json"
    assert main(["solve", str(prob), "-o", str(out), "--algorithm", "ga", "--max-trials", "500", "--seed", "3",
                 "--quiet"]) == 0
    d = json.loads(out.read_text())
    assert d["algorithm"] == "steady-state-ga" and d["trials"] == 500 and d["seed"] == 3
    assert main(["solve", str(prob), "-o", str(out), "--algorithm", "cma", "--variant", "B", "--quiet"]) == 2
    assert "--variant" in capsys.readouterr().err
