"""One list of each choice (nbst.registry): a solver registered once reaches every place that offers
solvers, the variants and built-in problems are read from their registries, and the typed result
converts to and from the solution file."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from nbst.errors import InputError
from nbst.problem import load_problem, problem_from_dict
from nbst.registry import Registry
from nbst.solution import SolveResult, load_solution

SWAP = {"name": "swap", "box": [800.0, 800.0], "t_final": 5.0, "target_radius": 30.0, "disks": [
    {"start": [200.0, 400.0], "target": [600.0, 400.0], "radius": 20.0},
    {"start": [600.0, 200.0], "target": [200.0, 600.0], "radius": 20.0}]}


def test_a_registry_keeps_each_name_once_and_parses_any_case():
    r: Registry[int] = Registry("colour")
    r.register("Red", 1, help="warm", aliases=("rouge",))
    r.register("blue", 2)
    assert r.names() == ("Red", "blue") and len(r) == 2 and list(r) == ["Red", "blue"]
    assert r.parse(" RED ") == "Red" and r.parse("Rouge") == "Red" and r["rouge"] == 1
    assert "BLUE" in r and "green" not in r and 3 not in r
    with pytest.raises(ValueError, match="already registered"):
        r.register("red", 3)
    with pytest.raises(InputError, match=r"<arguments>: --colour: unknown colour 'green'; choose one of Red, blue"):
        r.parse("green", field="--colour")
    assert r.help_text() == "Red: warm; blue"
    r.unregister("Red")
    assert r.names() == ("blue",) and "rouge" not in r


def test_variants_and_problems_are_read_from_their_registries(capsys):
    from nbst.cli import main
    from nbst.problems import PROBLEMS
    from nbst.search import VARIANTS, variant_params

    files = sorted(p.name for p in (Path(__file__).parents[1] / "nbst" / "problems").glob("*.json"))
    assert sorted(PROBLEMS[n] for n in PROBLEMS) == files  # every file shipped is registered, once
    for name in PROBLEMS:
        assert load_problem(name).name == name
    with pytest.raises(SystemExit):
        main(["solve", "--help"])
    help_text = " ".join(capsys.readouterr().out.split())
    for name in VARIANTS:
        assert variant_params(name, load_problem("over5")).variant == name
        assert f"{name}: {VARIANTS.entry(name).help}" in help_text


def _dummy_solver(problem, request, callback):
    """A solver that tries the straight-line velocities once and says so."""
    from nbst._version import __version__
    from nbst.search import SearchProgress
    from nbst.sim import evaluate
    from nbst.solution import signature_string

    v = problem.straight_velocities()
    _, cost, sig = evaluate(problem, v[None], jobs=1)
    if callback is not None:
        callback(SearchProgress(trials=1, best_cost=float(cost[0]), best_order=int(sig[0]).bit_count(), elapsed=0.0,
                                population=1, phase="dummy"))
    meta = {"algorithm": "dummy-straight", "cost": float(cost[0]), "signature": signature_string(int(sig[0]), problem.n),
            "order": int(sig[0]).bit_count(), "trials": 1, "seed": int(request.seed or 0), "variant": None,
            "stopped": "max_trials", "wall_time": 0.0, "nbst_version": __version__,
            "history": [[1, float(cost[0]), int(sig[0]).bit_count()]]}
    return SolveResult.from_meta(problem, v, meta)


@pytest.fixture
def dummy():
    from nbst.solvers import SOLVERS, register_solver

    register_solver("dummy", _dummy_solver, help="straight at every target, once (a test's solver)")
    yield "dummy"
    SOLVERS.unregister("dummy")


def test_a_registered_solver_reaches_solve_the_islands_and_the_experiments(tmp_path, capsys, dummy):
    from nbst.cli import main

    prob = tmp_path / "swap.json"
    prob.write_text(json.dumps(SWAP))
    p = problem_from_dict(SWAP)
    with pytest.raises(SystemExit):
        main(["solve", "--help"])
    assert "dummy: straight at every target, once" in " ".join(capsys.readouterr().out.split())
    out = tmp_path / "sol.json"
    # one process
    assert main(["solve", str(prob), "-o", str(out), "--algorithm", "DUMMY", "--jobs", "1", "--seed", "4", "-q"]) == 0
    d = json.loads(out.read_text())
    assert d["algorithm"] == "dummy-straight" and d["seed"] == 4
    assert np.array_equal(load_solution(out, p).velocities, p.straight_velocities())
    # two islands: the second runs in a forked worker, which sees the same registry
    assert main(["solve", str(prob), "-o", str(out), "--algorithm", "dummy", "--jobs", "2", "--seed", "4", "-q"]) == 0
    d = json.loads(out.read_text())
    assert d["jobs"] == 2 and [e["stopped"] for e in d["islands"]] == ["max_trials", "max_trials"]
    assert d["trials"] == 2  # one trial per island, summed
    # the experiments take it as an entry
    exp = tmp_path / "exp"
    assert main(["experiment", "compare", str(prob), "--algorithms", "dummy,A", "--max-trials", "200",
                 "--jobs", "1", "-q", "--out-dir", str(exp), "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert [r["entry"] for r in rows] == ["dummy", "A"]
    assert (exp / "runs" / "swap" / "dummy" / "t200-s1.json").is_file()
    # and a variant or --robust is refused for it, as for any solver that takes none
    assert main(["solve", str(prob), "-o", str(out), "--algorithm", "dummy", "--robust", "-q"]) == 2
    assert "--robust" in capsys.readouterr().err


def test_the_typed_result_is_the_file(tmp_path):
    from nbst.search import solve
    from nbst.solution import save_solution

    p = load_problem("diamond-s14")
    r = solve(p, seed=3, max_trials=3000, patience=0, variant="A")
    assert isinstance(r, SolveResult)
    assert (r.cost, r.order, r.trials, r.seed, r.variant, r.stopped) == \
        (r.meta["cost"], r.meta["order"], r.meta["trials"], 3, "A", "max_trials")
    assert r.history[-1][1] == r.cost and len(r.signature) == p.n
    f = tmp_path / "s.json"
    save_solution(f, r.to_solution())
    back = SolveResult.from_solution(load_solution(f, p))
    assert np.array_equal(back.velocities, r.velocities) and back.cost == r.cost and back.history == r.history
    assert json.loads(f.read_text()) == json.loads(json.dumps(r.to_dict()))
    import dataclasses

    with pytest.raises(ValueError, match="meta"):  # the attributes and the file cannot drift apart
        dataclasses.replace(r, cost=0.0)
    assert r.with_meta({"cost": 0.0}).cost == 0.0
    with pytest.raises(InputError, match="history"):
        SolveResult.from_solution(load_solution(f, p).__class__(p.name, r.velocities, {**r.meta, "history": 7}))
