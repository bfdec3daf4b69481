"""nbst.experiments.runs / nbst experiment: summaries, output files, resume, pool and Dask = in-process."""
from __future__ import annotations

import argparse
import csv
import json

import numpy as np
import pytest

from nbst.experiments import runs as X
from nbst.planted import planted
from nbst.problem import ProblemError, problem_from_dict

SWAP = {"name": "swap", "box": [400.0, 400.0], "t_final": 2.0, "target_radius": 30.0, "disks": [
    {"start": [100.0, 200.0], "target": [300.0, 200.0], "radius": 10.0},
    {"start": [300.0, 200.0], "target": [100.0, 200.0], "radius": 10.0}]}


@pytest.fixture(scope="module")
def swap():
    return problem_from_dict(SWAP)


def _same(a: dict, b: dict) -> None:
    """Two results of the same spec: equal except the wall time (bitwise determinism is the claim)."""
    for k in ("key", "cost", "signature", "order", "trials", "seed", "history", "velocities", "stopped"):
        assert a[k] == b[k], k


def _cli(argv, tmp_path):
    from nbst.cli.main import _Parser
    from nbst.cli.experiment import register

    parser = _Parser(prog="nbst")
    register(parser.add_subparsers(dest="command", parser_class=_Parser))
    args = parser.parse_args([*argv, "--out", str(tmp_path), "--workers", "1", "--quiet"])
    return args.func(args)


def _csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def test_entries():
    assert X.parse_entries("a, nbst,CMA,signature") == ("A", "nbst", "cma")
    with pytest.raises(ProblemError, match="unknown entry"):
        X.parse_entries("A,pso")


def test_best_so_far_and_curve_rows():
    assert X.best_so_far([[1, 10.0, 1], [5, 4.0, 2]], 9) == [(1, 10.0), (5, 4.0), (9, 4.0)]
    res = [{"key": {"entry": "A", "problem": "p"}, "seed": 3, "trials": 9, "history": [[1, 10.0, 1], [5, 4.0, 2]]},
           {"key": {"entry": "A", "problem": "p"}, "seed": 4, "trials": 9, "history": [[2, 8.0, 0], [9, 1.0, 2]]}]
    rows = X.curves_rows(res)
    assert [(r["run"], r["trial"], r["best_cost"], r["order"]) for r in rows] == [
        (1, 1, 10.0, 1), (1, 5, 4.0, 2), (1, 9, 4.0, 2), (2, 2, 8.0, 0), (2, 9, 1.0, 2)]


def test_ablation_and_compare_rows():
    def r(entry, cost, order, full, sha="x"):
        return {"key": {"entry": entry, "problem": "p", "problem_sha": sha, "trials": 100}, "cost": cost,
                "order": order, "n": 2, "trials": 100, "trials_per_s": 10.0, "first_full_order_trial": full,
                "history": [[full or 50, cost, order]]}
    res = [r("A", 1.0, 2, 7), r("A", 3.0, 1, None), r("cma", 5.0, 2, 20, "y")]
    rows = X.ablation_rows(res, ["A", "B", "cma"])
    assert [x["entry"] for x in rows] == ["A", "cma"]  # no runs of B: no row
    a = rows[0]
    assert (a["runs"], a["mean"], a["best"], a["worst"], a["full_order"]) == (2, 2.0, 1.0, 3.0, 1)
    rows = X.compare_rows(res, ["A", "cma"])
    assert (rows[0]["solved"], rows[0]["success_rate"], rows[0]["median_trials_to_solve"]) == (1, 0.5, 7)
    assert rows[0]["mean_trials_budget"] == (7 + 100) / 2  # a failure counts as its whole budget
    rows = X.compare_rows(res, ["A"], target_cost=2.0)
    assert rows[0]["solved"] == 1 and rows[0]["median_trials_to_solve"] == 7


def test_run_specs_writes_each_run_and_resumes(swap, tmp_path, monkeypatch):
    specs = X.make_specs([swap], ["A", "cma", "ga"], runs=2, trials=800, seed=5)
    assert len(specs) == 6 and {s.seed for s in specs} == {5, 6}
    first = X.run_specs(specs, tmp_path, workers=1, progress=False)
    files = sorted(tmp_path.glob("runs/swap/*/*.json"))
    assert len(files) == 6
    assert all(json.loads(f.read_text())["trials"] <= 800 for f in files)
    # rerun: nothing is run again
    monkeypatch.setattr(X, "run_one", lambda spec: pytest.fail(f"reran a finished run {spec}"))
    again = X.run_specs(specs, tmp_path, workers=1, progress=False)
    for a, b in zip(first, again):
        _same(a, b)
    # a lost file and a torn (unparsable) one are rerun; the rest are not
    lost, torn = tmp_path / specs[1].relpath(), tmp_path / specs[4].relpath()
    lost.unlink()
    torn.write_text("{\"kind\": \"nbst-exp")
    calls = []
    monkeypatch.undo()
    monkeypatch.setattr(X, "run_one", lambda spec, _r=X.run_one: calls.append(spec) or _r(spec))
    third = X.run_specs(specs, tmp_path, workers=1, progress=False)
    assert calls == [specs[1], specs[4]]
    for a, b in zip(first, third):
        _same(a, b)


def test_a_run_file_for_other_settings_is_not_reused(swap, tmp_path):
    spec = X.make_specs([swap], ["random"], runs=1, trials=300)[0]
    X.run_specs([spec], tmp_path, workers=1, progress=False)
    path = tmp_path / spec.relpath()
    d = json.loads(path.read_text())
    d["key"]["problem_sha"] = "changed"
    path.write_text(json.dumps(d))
    assert X._load_finished(path, spec) is None


def test_process_pool_equals_in_process(swap, tmp_path):
    specs = X.make_specs([swap], ["A", "random"], runs=1, trials=600, seed=2)
    local = X.run_specs(specs, tmp_path / "a", workers=1, progress=False)
    pooled = X.run_specs(specs, tmp_path / "b", workers=2, progress=False)
    for a, b in zip(local, pooled):
        _same(a, b)


def test_dask_cluster_equals_local(swap, tmp_path):
    from dask.distributed import Client, LocalCluster

    problem2 = planted(3, noncue=1, seed=5)[0]
    specs = X.make_specs([swap, problem2], ["A", "cma", "de"], runs=1, trials=700, seed=3)
    local = X.run_specs(specs, tmp_path / "local", workers=1, progress=False)
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        remote = X.run_specs(specs, tmp_path / "dask", cluster=client, progress=False)
    for a, b in zip(local, remote):
        _same(a, b)
    assert len(list((tmp_path / "dask").glob("runs/*/*/*.json"))) == len(specs)


def test_cli_curves_outputs(swap, tmp_path, capsys):
    prob = tmp_path / "swap.json"
    prob.write_text(json.dumps(SWAP))
    assert _cli(["experiment", "curves", str(prob), "--runs", "2", "--trials", "500", "--algorithms", "A,random"],
                tmp_path) == 0
    rows = _csv(tmp_path / "curves-swap.csv")
    assert list(rows[0]) == ["problem", "entry", "run", "seed", "trial", "best_cost", "order"]
    assert {(r["entry"], r["run"]) for r in rows} == {("A", "1"), ("A", "2"), ("random", "1"), ("random", "2")}
    for key in {(r["entry"], r["run"]) for r in rows}:
        mine = [r for r in rows if (r["entry"], r["run"]) == key]
        costs = [float(r["best_cost"]) for r in mine]
        assert costs == sorted(costs, reverse=True) and int(mine[-1]["trial"]) == 500
    for ext in ("png", "svg"):
        assert (tmp_path / f"curves-swap.{ext}").stat().st_size > 1000
    assert "| entry | seed |" in capsys.readouterr().out


def test_cli_ablation_outputs(tmp_path, capsys):
    prob = tmp_path / "swap.json"
    prob.write_text(json.dumps(SWAP))
    entries = "A,B,E,nbst,cma,de,ga,random"
    assert _cli(["experiment", "ablation", str(prob), "--runs", "2", "--trials", "400", "--algorithms", entries],
                tmp_path) == 0
    rows = _csv(tmp_path / "ablation-swap.csv")
    assert [r["entry"] for r in rows] == entries.split(",")
    assert list(rows[0])[:7] == ["entry", "runs", "mean", "best", "worst", "full_order", "median_trials_per_s"]
    for r in rows:
        assert r["runs"] == "2" and float(r["best"]) <= float(r["mean"]) <= float(r["worst"])
    md = (tmp_path / "ablation-swap.md").read_text()
    assert md.count("\n| ") == len(rows) + 1  # header + one line per entry (after the separator)
    assert (tmp_path / "ablation-swap.png").exists() and (tmp_path / "ablation-swap.svg").exists()


def test_cli_compare_outputs(tmp_path):
    folder = tmp_path / "planted"
    folder.mkdir()
    for s in (1, 2):
        p = planted(2, seed=s)[0]
        (folder / f"p{s}.json").write_text(json.dumps(p.to_dict()))
    assert _cli(["experiment", "compare", str(folder), "--trials", "1500", "--algorithms", "nbst,ga",
                 "--target-cost", "1.0"], tmp_path) == 0
    rows = _csv(tmp_path / "compare-compare.csv")
    assert [r["entry"] for r in rows] == ["nbst", "ga"]
    assert all(r["problems"] == "2" and r["runs"] == "2" for r in rows)
    nbst = rows[0]
    assert float(nbst["success_rate"]) == 1.0  # 2 planted disks: nbst's search solves both quickly
    runs = _csv(tmp_path / "compare-compare-runs.csv")
    assert len(runs) == 4
    for r in runs:
        if r["solved_at"]:
            assert float(r["cost"]) <= 1.0 and int(r["solved_at"]) <= int(r["trials"])


def test_cli_bad_input(tmp_path):
    from nbst.problem import ProblemError

    with pytest.raises(ProblemError, match="unknown entry"):
        _cli(["experiment", "curves", "over5", "--algorithms", "A,xyz"], tmp_path)
    with pytest.raises(ProblemError, match="no such file"):
        _cli(["experiment", "compare", str(tmp_path / "nope.json")], tmp_path)
    with pytest.raises(SystemExit):
        _cli(["experiment", "curves", "over5", "--runs", "0"], tmp_path)


@pytest.mark.parametrize("damage", ["missing history", "history of strings", "not JSON", "foreign kind", "a folder"])
def test_a_damaged_or_foreign_run_file_is_reported_and_rerun(swap, tmp_path, capsys, damage):
    spec = X.make_specs([swap], ["random"], runs=1, trials=300)[0]
    first = X.run_specs([spec], tmp_path, workers=1, progress=False)[0]
    path = tmp_path / spec.relpath()
    d = json.loads(path.read_text())
    if damage == "missing history":
        del d["history"]
    elif damage == "history of strings":
        d["history"] = ["x", "y"]
    elif damage == "foreign kind":
        d = {"kind": "something else", "key": d["key"]}
    if damage == "not JSON":
        path.write_text("{not json")
    elif damage == "a folder":
        path.unlink()
        path.mkdir()
    else:
        path.write_text(json.dumps(d))
    capsys.readouterr()
    if damage == "a folder":  # reported, then the write refused: one line, no traceback
        with pytest.raises(Exception) as e:
            X.run_specs([spec], tmp_path, workers=1, progress=False)
        assert type(e.value).__name__ == "OutputError"
        return
    again = X.run_specs([spec], tmp_path, workers=1, progress=False)[0]
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(path) in err[0] and "running it again" in err[0], err
    _same(first, again)
    assert X._load_finished(path, spec) is not None  # rewritten whole
    X.curves_rows([again])  # the summaries read it


@pytest.mark.parametrize("field, value", [
    ("trials_per_s", float("inf")),  # a JSON Infinity: the table once failed on it (TypeError)
    ("cost", float("-inf")),  # once accepted, and printed as the best cost
    ("cost", float("nan")),
    ("cost", float("inf")),  # nbst writes an infinite cost as "inf", never as Infinity
    ("cost", -1.0),
    ("order", 3),  # 2 disks
    ("trials", -5),
    ("seed", 99),  # not the run's seed
    ("history", [[1, float("-inf"), 1]]),
    ("history", [[10**9, 1.0, 1]]),  # an improvement after the last trial
    ("velocities", [[float("nan"), 0.0], [0.0, 0.0]]),
    ("wall_time", float("inf")),
    ("first_full_order_trial", 0),
])
def test_a_run_file_with_a_number_out_of_bounds_is_reported_and_rerun(swap, tmp_path, capsys, field, value):
    """Run files pass the input gate every input passes: finite and bounded numbers, or one line
    and the run is done again (issue 35, round-4 audit)."""
    spec = X.make_specs([swap], ["random"], runs=1, trials=300)[0]
    first = X.run_specs([spec], tmp_path, workers=1, progress=False)[0]
    path = tmp_path / spec.relpath()
    d = json.loads(path.read_text())
    d[field] = value
    path.write_text(json.dumps(d))  # Python's json writes Infinity / NaN literals, as a hand edit might
    capsys.readouterr()
    why = X.check_run_file(path, spec)[1]
    assert why and repr(field) in why, why
    again = X.run_specs([spec], tmp_path, workers=1, progress=False)[0]
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(path) in err[0] and "running it again" in err[0], err
    _same(first, again)
    rows = X.compare_rows([again], ["random"]) + X.ablation_rows([again], ["random"])
    assert all(X.fmt(v) for r in rows for v in r.values())  # the tables print


@pytest.mark.parametrize("name", ["..", ".", "../../escape", "/abs", "a/../../b", ".hidden", "é" * 200, ""])
def test_run_files_stay_inside_runs(swap, tmp_path, name):
    d = dict(SWAP, name=name)
    spec = X.make_specs([problem_from_dict(d)], ["random"], runs=1, trials=50)[0]
    out = tmp_path / "out"
    X.run_specs([spec], out, workers=1, progress=False)
    files = [p for p in tmp_path.rglob("*") if p.is_file()]
    assert len(files) == 1 and (out / "runs") in files[0].parents, files
    part = files[0].relative_to(out / "runs").parts[0]
    assert not part.startswith(".") and part.isascii() and len(part) <= X.MAX_NAME_PART + 9, part
    # two names that sanitize alike still get two files
    assert X.safe_name("a b") != X.safe_name("a_b") and X.safe_name("a?b") != X.safe_name("a*b")
