"""nbst solve --jobs K: independent islands in lockstep, reproducible for a given (seed, K)."""
import json

import numpy as np
import pytest

from nbst import load_problem
from nbst.cli import main
from nbst import simulate
from nbst.solvers.islands import PORTFOLIO, island_seeds, portfolio_for, solve_islands
from nbst.search import roundoff_cost, solve


def test_one_job_is_the_plain_search():
    """Without a portfolio (all-cueable problem, another variant, or portfolio=False) --jobs 1 is solve()."""
    for name, kw in (("diamond-s14", {}), ("over5", {"portfolio": False}), ("over5", {"variant": "nbst-noplan"})):
        p = load_problem(name)
        a = solve_islands(p, jobs=1, seed=4, max_trials=3000, patience=0, **kw)
        b = solve(p, seed=4, max_trials=3000, patience=0, variant=kw.get("variant", "nbst"))
        assert np.array_equal(a.velocities, b.velocities) and a.meta["trials"] == b.meta["trials"]
        assert "portfolio" not in a.meta and a.meta["variant"] == b.meta["variant"]


def test_islands_are_reproducible_and_count_every_trial():
    p = load_problem("over5")
    runs = [solve_islands(p, jobs=2, seed=9, max_trials=20_000, patience=0) for _ in range(2)]
    a, b = runs
    assert np.array_equal(a.velocities, b.velocities)
    assert a.meta["island"] == b.meta["island"] and a.meta["cost"] == b.meta["cost"]
    isl = a.meta["islands"]
    assert [e["seed"] for e in isl] == island_seeds(9, 2) and len(set(island_seeds(9, 2))) == 2
    assert a.meta["trials"] == sum(e["trials"] for e in isl)
    assert all(e["trials"] == 10_000 for e in isl)  # each island: 1/K of the budget, all spent
    # the written solution is the best island's, and it is what that island's own search gives
    k = a.meta["island"]
    alone = solve(p, seed=island_seeds(9, 2)[k], max_trials=10_000, patience=0, variant=a.meta["configuration"])
    assert np.array_equal(alone.velocities, a.velocities)
    assert a.meta["cost"] == min(e["cost"] for e in isl)


def test_all_islands_stop_when_one_reaches_the_target():
    p = load_problem("diamond-s14")
    s = solve_islands(p, jobs=2, seed=5, max_trials=2_000_000, patience=0, target_cost=roundoff_cost(p))
    assert s.meta["cost"] <= roundoff_cost(p) and s.meta["stopped"] == "target_cost"
    assert s.meta["trials"] < 100_000  # both stopped within a round or so, far from their budgets
    assert all(e["stopped"] in ("target_cost", "callback") for e in s.meta["islands"])


def test_cli_jobs(tmp_path, capsys):
    out = tmp_path / "s.json"
    assert main(["solve", "over5", "-o", str(out), "--seed", "2", "--max-trials", "4000", "--jobs", "2"]) == 0
    d = json.loads(out.read_text())
    assert d["jobs"] == 2 and d["seed"] == 2 and d["trials"] == 4000
    assert "best of 2 islands" in capsys.readouterr().err
    with pytest.raises(SystemExit) as e:  # argparse: usage error, exit 2
        main(["solve", "over5", "-o", str(out), "--jobs", "0"])
    assert e.value.code == 2


def test_evaluate_on_threads_gives_the_same_results():
    from nbst.constants import PARALLEL_BATCH
    from nbst.sim import evaluate_events

    p = load_problem("diamond-s14")
    V = p.straight_velocities() + np.random.default_rng(0).normal(0, 50, (2 * PARALLEL_BATCH + 7, 14, 2))
    one = evaluate_events(p, V, jobs=1)
    two = evaluate_events(p, V, jobs=2)
    for a, b in zip(one, two):
        assert np.array_equal(a, b)  # each candidate is simulated alone: bit-identical


def test_islands_on_a_dask_cluster_give_the_local_solution(tmp_path):
    """solve --cluster: islands 1..K-1 run as Dask tasks, talking through named queues; the
    rounds are the same, so the written solution and every island's count match --jobs K."""
    from dask.distributed import LocalCluster

    args = ["solve", "over5", "--seed", "3", "--max-trials", "20000", "--patience", "0", "--jobs", "2", "-q"]
    assert main([*args, "-o", str(tmp_path / "here.json")]) == 0
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None) as cluster:
        assert main([*args, "-o", str(tmp_path / "dask.json"), "--cluster", cluster.scheduler_address]) == 0
    here, dask = (json.loads((tmp_path / f).read_text()) for f in ("here.json", "dask.json"))
    assert here["velocities"] == dask["velocities"]
    isl = [[(i["trials"], i["cost"]) for i in d["islands"]] for d in (here, dask)]
    assert isl[0] == isl[1] and sum(t for t, _ in isl[0]) == 20000
    assert all(t > 0 for t, _ in isl[1])  # island 1 ran (on the cluster's worker)


# --------------------------------------------------------------------------- the portfolio

def test_portfolio_runs_both_configurations_and_keeps_the_best():
    """over5 (noncueable disks): island k runs PORTFOLIO[k % 2]; each island's cost is what its own
    configuration gives from its seed (and not what the other one gives); the written solution is
    the cheapest island's and says which configuration produced it."""
    p = load_problem("over5")
    assert portfolio_for(p) == PORTFOLIO == ("nbst", "nbst-noplan")
    s = solve_islands(p, jobs=3, seed=11, max_trials=24_000, patience=0)
    m = s.meta
    assert m["portfolio"] == ["nbst", "nbst-noplan", "nbst"] and m["variant"] == "nbst"
    isl = m["islands"]
    for e in isl:
        other = "nbst-noplan" if e["variant"] == "nbst" else "nbst"
        own = solve(p, seed=e["seed"], max_trials=8000, patience=0, variant=e["variant"]).meta["cost"]
        not_own = solve(p, seed=e["seed"], max_trials=8000, patience=0, variant=other).meta["cost"]
        assert e["trials"] == 8000 and e["cost"] == own != not_own
    assert m["cost"] == min(e["cost"] for e in isl)
    k = min(range(3), key=lambda i: (isl[i]["cost"], i))
    assert m["island"] == k and m["configuration"] == isl[k]["variant"]
    assert m["params"]["planner"] == (m["configuration"] == "nbst")  # the winner's own parameters
    assert simulate(p, s.velocities).cost == m["cost"]


def test_portfolio_on_one_job_takes_turns_and_is_reproducible():
    """--jobs 1: the portfolio's two islands in threads of one process: the same seed gives the same
    velocities, and the same solution as --jobs 2 (same islands, same rounds)."""
    p = load_problem("over5")
    one = [solve_islands(p, jobs=1, seed=6, max_trials=30_000, patience=0) for _ in range(2)]
    two = solve_islands(p, jobs=2, seed=6, max_trials=30_000, patience=0)
    assert np.array_equal(one[0].velocities, one[1].velocities)
    assert np.array_equal(one[0].velocities, two.velocities)
    for a in (one[0], two):
        assert a.meta["portfolio"] == ["nbst", "nbst-noplan"] and a.meta["trials"] == 30_000
        assert [(e["seed"], e["trials"], e["cost"]) for e in a.meta["islands"]] == \
            [(e["seed"], e["trials"], e["cost"]) for e in two.meta["islands"]]
    assert one[0].meta["jobs"] == 1 and two.meta["jobs"] == 2


def test_portfolio_on_one_job_stops_together():
    """A callback that says stop ends both threads at the same round; nothing hangs."""
    p = load_problem("over5")
    seen = []

    def cb(prog):
        seen.append(prog.trials)
        return prog.trials >= 20_000

    s = solve_islands(p, jobs=1, seed=2, max_trials=400_000, patience=0, callback=cb)
    assert s.meta["stopped"] == "callback" and 20_000 <= s.meta["trials"] < 40_000
    assert all(e["trials"] < 200_000 and e["stopped"] in ("callback", "max_trials") for e in s.meta["islands"])


def test_no_portfolio_where_the_configurations_coincide():
    """All-cueable problems (the planner never runs), other variants, baselines and robust mode:
    every island runs the requested search."""
    p, s14 = load_problem("over5"), load_problem("diamond-s14")
    assert portfolio_for(s14) is None
    assert portfolio_for(p, variant="A") is None and portfolio_for(p, "cma") is None
    assert portfolio_for(p, robust=True) is None
    m = solve_islands(s14, jobs=2, seed=3, max_trials=4000, patience=0).meta
    assert "portfolio" not in m and "configuration" not in m and m["variant"] == "nbst"


def test_a_portfolio_island_restarts_when_its_patience_runs_out():
    """A portfolio island whose search stops by patience starts the next configuration from a fresh
    seed with the budget left; the island's result is its best run, reproducible from the seed."""
    from nbst.solvers import SolveRequest
    from nbst.solvers.islands import IslandTask, restart_seed, run_island

    p = load_problem("over5")
    task = IslandTask("signature", SolveRequest(seed=5, max_trials=30_000, patience=2000, variant="nbst"), PORTFOLIO)
    a, b = run_island(task, p), run_island(task, p)
    assert np.array_equal(a.velocities, b.velocities)
    runs = a.meta["runs"]
    assert len(runs) >= 2 and a.meta["trials"] == sum(r["trials"] for r in runs) <= 30_000
    assert [r["variant"] for r in runs] == [PORTFOLIO[j % 2] for j in range(len(runs))]
    assert [r["seed"] for r in runs] == [restart_seed(5, j) for j in range(len(runs))] and runs[0]["seed"] == 5
    assert all(r["stopped"] == "patience" for r in runs[:-1])
    assert a.meta["cost"] == min(r["cost"] for r in runs) and a.meta["cost"] == runs[a.meta["run"]]["cost"]
    j = a.meta["run"]  # the best run alone, from its seed and with the budget it had, gives the same velocities
    alone = solve(p, seed=runs[j]["seed"], max_trials=30_000 - sum(r["trials"] for r in runs[:j]), patience=2000,
                  variant=runs[j]["variant"])
    assert np.array_equal(alone.velocities, a.velocities)
    # through solve_islands: the written solution names the search that produced it
    s = solve_islands(p, jobs=2, seed=5, max_trials=60_000, patience=2000)
    k, isl = s.meta["island"], s.meta["islands"]
    assert all(len(e["runs"]) >= 2 for e in isl) and s.meta["trials"] == sum(e["trials"] for e in isl) <= 60_000
    best = min((r for r in isl[k]["runs"]), key=lambda r: r["cost"])
    assert s.meta["search_seed"] == best["seed"] and s.meta["configuration"] == best["variant"]
    assert s.meta["cost"] == best["cost"] == min(e["cost"] for e in isl)
