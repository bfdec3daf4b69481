"""A newcomer's first hour: the README's commands, the lock file, the one-time compile
message and the solve command's defaults."""
import json
import re
import subprocess
import sys
import textwrap
import tomllib
from pathlib import Path

import pytest

from nbst.cli import main

ROOT = Path(__file__).resolve().parents[1]


def _readme_commands() -> list[str]:
    text = (ROOT / "README.md").read_text()
    block = text.split("## Two commands", 1)[1].split("```bash", 1)[1].split("```", 1)[0]
    return [line.split("#", 1)[0].strip() for line in block.strip().splitlines()]


def test_ci_runs_the_readme_test_command_then_the_rest():
    """CI runs the README's test command (the fast tier, on every core), then the slow tier: the
    two marker expressions cover every test."""
    cmds = _readme_commands()
    assert len(cmds) == 2 and cmds[0].startswith("bash scripts/setup.sh && bash scripts/demo.sh")
    ci = [line.strip() for line in (ROOT / ".ci/run").read_text().splitlines()
          if line.strip() and not line.startswith("#") and not line.startswith(("set ", "cd "))]
    assert ci[0] == cmds[1] and len(ci) == 2
    assert "pytest" in cmds[1] and "-n auto" in cmds[1] and '-m "not slow"' in cmds[1]
    assert ci[1] == '.venv/bin/python -m pytest -q -n auto -m slow'



def _norm(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


def test_lock_pins_every_declared_dependency():
    meta = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    declared = meta["dependencies"] + meta["optional-dependencies"]["test"]
    names = {_norm(re.split(r"[\[<>=!~ ;]", d, maxsplit=1)[0]) for d in declared}
    pins = {}
    for line in (ROOT / "requirements.lock").read_text().splitlines():
        line = line.strip()
        if line and not line.startswith("#"):
            name, _, version = line.partition("==")
            assert version and re.fullmatch(r"[0-9][0-9A-Za-z.+!-]*", version), f"not an exact pin: {line!r}"
            pins[_norm(name)] = version
    assert names <= set(pins), f"declared but not locked: {sorted(names - set(pins))}"
    assert "nbst" not in pins  # the project itself is installed from the checkout


def test_is_cold_sees_numba_disk_cache(tmp_path):
    # a fresh cached kernel: cold before its first call, warm after it, and warm in a
    # new process that only has numba's on-disk cache
    (tmp_path / "kmod.py").write_text(textwrap.dedent("""
        from numba import njit

        @njit(cache=True)
        def twice(x):
            return 2.0 * x
    """))
    probe = textwrap.dedent("""
        import sys
        sys.path.insert(0, sys.argv[1])
        import kmod
        from nbst.warmup import is_cold
        before = is_cold(kmod.twice)
        if sys.argv[2] == "call":
            kmod.twice(1.5)
        print(before, is_cold(kmod.twice))
    """)

    def run(mode):
        r = subprocess.run([sys.executable, "-c", probe, str(tmp_path), mode], capture_output=True, text=True,
                           timeout=300)
        assert r.returncode == 0, r.stderr
        return r.stdout.split()

    assert run("call") == ["True", "False"]
    assert run("look") == ["False", "False"]


def test_solve_stops_at_roundoff_by_default(tmp_path, capsys):
    from nbst import load_problem
    from nbst.search import roundoff_cost

    out = tmp_path / "s.json"
    assert main(["solve", "diamond-s14-tiny", "-o", str(out), "--seed", "1", "--patience", "0"]) == 0
    d = json.loads(out.read_text())
    assert d["stopped"] == "target_cost"
    assert d["cost"] <= roundoff_cost(load_problem("diamond-s14-tiny"))
    assert d["trials"] < 1_000_000  # it did not run out the default budget
    err = capsys.readouterr().err
    assert "stopped: cost at round-off level" in err and f"wrote {out}" in err


def test_solve_quiet_is_silent(tmp_path, capsys):
    out = tmp_path / "s.json"
    assert main(["solve", "diamond-s14-tiny", "-o", str(out), "--seed", "1", "-q"]) == 0
    assert capsys.readouterr().err == ""
    assert out.exists()


def test_solve_help_lists_each_variant_once(capsys):
    with pytest.raises(SystemExit):
        main(["solve", "--help"])
    text = " ".join(capsys.readouterr().out.split())  # argparse wraps lines
    assert text.count("no culling of subsumed solutions") == 1
    assert "round-off" in text


_NO_NEW_COMPILE = textwrap.dedent("""
    import gc, json, os, sys
    from nbst.warmup import many_disks_problem, warm_all
    warm_all()
    from numba.core.registry import CPUDispatcher

    def compiled():
        return {f"{d.py_func.__module__}.{d.py_func.__qualname__}": set(map(str, d.signatures))
                for d in gc.get_objects() if isinstance(d, CPUDispatcher)}

    before = compiled()
    from nbst.cli import main
    os.chdir(sys.argv[1])
    m = many_disks_problem(150)
    json.dump(m.to_dict(), open("m.json", "w"))
    json.dump({"velocities": m.straight_velocities().tolist()}, open("ms.json", "w"))
    runs = [["solve", "over5", "-o", "s.json", "--seed", "1", "--max-trials", "2000", "--jobs", "1", "-q"],
            ["simulate", "over5", "s.json"], ["validate", "over5", "s.json", "--timestep", "0.002"],
            ["validate", "over5", "s.json", "--stepping", "aligned", "--convergence", "--timestep", "0.005"],
            ["simulate", "m.json", "ms.json"], ["validate", "m.json", "ms.json", "--timestep", "0.004"]]
    new = []
    for argv in runs:
        assert main(argv) in (0, 1), argv
        after = compiled()
        new += [f"{' '.join(argv[:2])}: {k} {sorted(v - before.get(k, set()))}" for k, v in after.items()
                if v - before.get(k, set())]
        before = after
    print("NEW " + json.dumps(new))
""")


@pytest.mark.slow
def test_the_commands_compile_nothing_after_the_warm_up(tmp_path):
    """After nbst.warmup, `nbst simulate` and `nbst validate` (read-only velocities from solution
    files; a built-in problem and a 150-disk file on the cell grid) run only kernels the warm-up
    compiled: numba adds no signature (issue 35: the warm-up passed writable arrays, the command
    line read-only ones, and the first validate counted the compile as MuJoCo time)."""
    r = subprocess.run([sys.executable, "-c", _NO_NEW_COMPILE, str(tmp_path)], capture_output=True, text=True,
                       timeout=900)
    assert r.returncode == 0, r.stderr[-2000:]
    new = json.loads(r.stdout.rsplit("NEW ", 1)[1])
    assert new == [], new
