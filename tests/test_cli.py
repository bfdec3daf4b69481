"""The core command line: tables, JSON output, one-line errors with exit code 2."""
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from nbst import load_problem
from nbst.cli import main
from nbst.sim import simulate
from nbst.solution import make_solution, save_solution

ROOT = Path(__file__).resolve().parents[1]


def run(*args, cwd=None):
    return subprocess.run([sys.executable, str(ROOT / "cli.py"), *args], capture_output=True, text=True,
                          cwd=cwd, timeout=300)


@pytest.fixture
def over5_solution(tmp_path):
    p = load_problem("over5")
    v = np.zeros((5, 2))
    v[0] = [-90.0, 30.0]
    v[1] = [70.0, 5.0]
    f = tmp_path / "sol.json"
    save_solution(f, make_solution(p, v, cost=0.0, signature="11111", order=5))  # lies, recomputed
    return p, v, f


def test_version_and_help(capsys):
    with pytest.raises(SystemExit) as e:
        main(["--version"])
    assert e.value.code == 0
    assert capsys.readouterr().out.startswith("nbst ")
    for cmd in (["--help"], ["problems", "--help"], ["simulate", "--help"]):
        with pytest.raises(SystemExit) as e:
            main(cmd)
        assert e.value.code == 0
        assert "usage: nbst" in capsys.readouterr().out


def test_problems_table_and_show(capsys):
    assert main(["problems"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0].split()[:4] == ["name", "disks", "cueable", "radius"]
    rows = {line.split()[0]: line.split() for line in out[1:]}
    assert rows["over5"][1:4] == ["5", "2", "10"]
    assert rows["diamond-s14"][1:4] == ["14", "14", "20"]
    assert main(["problems", "show", "over5"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["name"] == "over5" and len(d["disks"]) == 5


def test_simulate_json_recomputes(over5_solution, capsys):
    p, v, f = over5_solution
    assert main(["simulate", "over5", str(f), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    tr = simulate(p, v)
    assert set(out) >= {"final", "cost", "signature", "order", "events"}
    assert out["cost"] == tr.cost and out["cost"] > 0  # the file's cost 0.0 was not trusted
    assert out["signature"] == tr.signature_string and out["order"] == tr.order
    assert out["events"] == {"disk_disk": tr.n_disk_disk, "wall": tr.n_wall}
    np.testing.assert_array_equal(out["final"], tr.final_positions)
    assert main(["simulate", "over5", str(f)]) == 0
    text = capsys.readouterr().out
    assert f"signature  {tr.signature_string}" in text


@pytest.mark.parametrize("args, needle", [
    (["simulate", "diamond-s41", "x.json"], "did you mean diamond-s14"),
    (["simulate", "over5", "missing.json"], "missing.json: no such file"),
    (["problems", "show", "nope"], "no built-in problem"),
    (["simulate"], "the following arguments are required"),
    (["frobnicate"], "invalid choice"),
])
def test_bad_input_exits_2_one_line_no_traceback(args, needle, tmp_path):
    r = run(*args, cwd=tmp_path)
    assert r.returncode == 2
    assert needle in r.stderr
    assert "Traceback" not in r.stderr
    assert r.stderr.strip().splitlines()[-1].startswith(("nbst: error:", "nbst simulate: error:", "nbst: error"))


def test_bad_solution_file_exit_2(tmp_path):
    f = tmp_path / "s.json"
    f.write_text('{"velocities": [[1, 0], [0, 0], [3, 0], [0, 0], [0, 0]]}')
    r = run("simulate", "over5", str(f))
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "velocities[2]" in lines[0] and "noncueable" in lines[0]


def test_checkout_shim_runs(over5_solution, tmp_path):
    _, _, f = over5_solution
    r = run("simulate", "over5", str(f), "--json", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout)["order"] >= 0
