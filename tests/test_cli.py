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


@pytest.mark.parametrize("cmd", [
    ["solve", "over5", "-o", "{bad}/s.json", "--max-trials", "100", "--quiet"],
    ["generate", "--planted", "5", "--seed", "1", "-o", "{bad}/p.json"],
    ["generate", "--planted", "5", "--seed", "1", "-o", "{ok}/p.json", "--solution", "{bad}/s.json"],
    ["mjcf", "over5", "{sol}", "-o", "{bad}/scene.xml"],
    ["validate", "over5", "{sol}", "--report", "{bad}/report"],
    ["render", "over5", "{sol}", "-o", "{bad}/v.mp4"],
    ["render", "over5", "{sol}", "--still", "1", "-o", "{bad}/f.png"],
    ["plot", "problem", "over5", "-o", "{bad}/f.png"],
    ["experiment", "compare", "over5", "--runs", "1", "--trials", "100", "--algorithms", "random",
     "--out", "{bad}/exp", "--quiet"],
    ["gallery", "over5", "--no-search", "--dir", "{bad}/gallery"],
], ids=lambda c: " ".join(c[:2]))
def test_unwritable_output_exits_2_before_the_work(cmd, over5_solution, tmp_path, capsys):
    # {bad} is a path under a regular file: no folder can be made there, even by root
    (tmp_path / "file").write_text("x")
    bad = tmp_path / "file" / "sub"
    args = [a.format(bad=bad, ok=tmp_path, sol=over5_solution[2]) for a in cmd]
    assert main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err and err[-1].startswith("nbst: error: ") and str(bad) in err[-1] and "cannot write there" in err[-1]
    assert "Traceback" not in "\n".join(err)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file", "sol.json"]  # nothing else was written


def test_output_that_is_a_folder_is_refused(tmp_path, capsys):
    assert main(["solve", "over5", "-o", str(tmp_path), "--max-trials", "10", "--quiet"]) == 2
    assert "is a folder; expected a file name" in capsys.readouterr().err


def test_writers_name_the_command_that_wrote(tmp_path, capsys):
    """generate and mjcf say which nbst command wrote what, like solve and plot do."""
    prob, sol, xml = tmp_path / "p.json", tmp_path / "s.json", tmp_path / "scene.xml"
    assert main(["generate", "--planted", "3", "--seed", "2", "-o", str(prob), "--solution", str(sol)]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith(f"nbst generate: wrote {prob}:") and out[1] == f"nbst generate: wrote {sol}: the planted velocities"
    assert main(["mjcf", str(prob), str(sol), "-o", str(xml)]) == 0
    assert capsys.readouterr().err.startswith(f"nbst mjcf: wrote {xml} (3 disks;")


def test_an_option_must_be_spelled_out(capsys, tmp_path):
    """``--max-trial`` is not taken for ``--max-trials`` (argparse's prefix matching is off, in every
    parser nbst builds: the CLI's and the scripts')."""
    with pytest.raises(SystemExit) as e:
        main(["solve", "over5", "-o", str(tmp_path / "s.json"), "--max-trial", "10"])
    assert e.value.code == 2
    err = capsys.readouterr().err
    assert "--max-trial" in err and "unrecognized" in err and err.count("\n") == 1
    assert not (tmp_path / "s.json").exists()
    import re

    root = Path(__file__).resolve().parents[1]
    missing = [f"{f.relative_to(root)}:{text[:m.start()].count(chr(10)) + 1}"
               for folder in ("nbst", "models", "render", "benchmarks", "scripts")
               for f in sorted((root / folder).rglob("*.py"))
               for text in [f.read_text(encoding="utf-8")]
               for m in re.finditer(r"argparse\.ArgumentParser\(", text)
               if "allow_abbrev=False" not in text[m.end():m.end() + 200]]
    assert not missing, missing


def test_plot_subcommands_explain_themselves(capsys):
    for what in ("problem", "trajectories"):
        with pytest.raises(SystemExit):
            main(["plot", what, "--help"])
        text = " ".join(capsys.readouterr().out.split())
        assert "Figures" in text and "legend" in text and ".svg" in text
