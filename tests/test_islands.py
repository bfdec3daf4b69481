"""nbst solve --jobs K: independent islands in lockstep, reproducible for a given (seed, K)."""
import json

import numpy as np
import pytest

from nbst import load_problem
from nbst.cli import main
from nbst.solvers.islands import island_seeds, solve_islands
from nbst.search import roundoff_cost, solve


def test_one_job_is_the_plain_search():
    p = load_problem("over5")
    a = solve_islands(p, jobs=1, seed=4, max_trials=3000, patience=0)
    b = solve(p, seed=4, max_trials=3000, patience=0)
    assert np.array_equal(a.velocities, b.velocities) and a.meta["trials"] == b.meta["trials"]


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
    alone = solve(p, seed=island_seeds(9, 2)[k], max_trials=10_000, patience=0)
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
