"""A newcomer's first hour: the README's commands, the lock file, the one-time compile
message and the solve command's defaults."""
import itertools
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
    assert ci[1] == 'bash scripts/test-packages.sh && .venv/bin/python -m pytest -q -n auto -m slow'



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


def test_both_paths_of_the_warm_up_run_every_group(monkeypatch):
    """One list, two paths: on one process the warm-up runs FIRST then every group of GROUPS here,
    in order; on more, it runs FIRST here, then hands every group of GROUPS to the workers and runs
    here any that a worker failed (issue 45: the warm-up compiles in parallel across cores)."""
    from nbst import warmup

    ran = []
    for g in (warmup.FIRST, *warmup.GROUPS):
        monkeypatch.setattr(warmup, g.function, lambda f=g.function: ran.append(f))
    names = [g.function for g in warmup.GROUPS]
    lines = []
    warmup.warm_all(lines.append)
    assert ran == [warmup.FIRST.function, *names]
    assert [s.split(" ready (")[0] for s in lines] == [warmup.FIRST.name, *(g.name for g in warmup.GROUPS)]

    handed = []

    def workers(groups, n, done):
        handed.extend(groups)
        for g in groups[1:]:
            done(g, 1.0)
        return list(groups[:1])  # the first one "failed" in its worker

    monkeypatch.setattr(warmup, "_in_workers", workers)
    ran.clear()
    lines.clear()
    warmup.warm_all(lines.append, jobs=8)
    assert handed == list(warmup.GROUPS)
    assert ran == [warmup.FIRST.function, names[0]]  # the failed group, here
    everyone = [warmup.FIRST.name, *(g.name for g in warmup.GROUPS)]
    assert sorted(s.split(" ready (")[0] for s in lines) == sorted(everyone)


def test_the_groups_are_distinct_functions_of_the_warm_up():
    from nbst import warmup

    groups = (warmup.FIRST, *warmup.GROUPS)
    assert len({g.function for g in groups}) == len(groups) and len({g.name for g in groups}) == len(groups)
    assert all(callable(getattr(warmup, g.function)) and g.function in warmup.__all__ for g in groups)


def test_the_workers_run_groups_in_fresh_processes():
    """The pool itself (spawned processes that import nbst.warmup and look the group up by name):
    a group that runs is reported with its seconds, one that fails comes back to be run here."""
    from nbst import warmup

    done = []
    groups = [warmup.KernelGroup("message", "compile_message"), warmup.KernelGroup("none", "no_such_function")]
    failed = warmup._in_workers(groups, 2, lambda g, secs: done.append((g.name, secs)))
    assert [name for name, _ in done] == ["message"] and 0.0 <= done[0][1] < 60.0
    assert [g.name for g in failed] == ["none"]


_TYPED = textwrap.dedent("""
    import gc, json, sys
    from numba.core import compiler, typed_passes
    from numba.core.caching import NullCache
    from numba.core.registry import CPUDispatcher
    from nbst import warmup

    class TypeOnly(compiler.CompilerBase):
        # numba's own pipeline, up to type inference: typing a kernel types its callees, which
        # compiles them, from the cache when it holds them, with the signatures that a cold compile
        # of the kernel gives them (inline="always" callees are inlined first, as in a compile)
        def define_pipelines(self):
            pm = compiler.DefaultPassBuilder.define_untyped_pipeline(self.state, "untyped")
            pm.add_pass(typed_passes.NopythonTypeInference, "type inference")
            pm.finalize()
            self.state.cr = True  # typing is all that is asked: stop after this pipeline
            return [pm]

    def kernels():  # the dispatchers that have an on-disk index: njit(cache=True)
        return [d for d in gc.get_objects() if isinstance(d, CPUDispatcher)
                and not isinstance(getattr(d, "_cache", None) or NullCache(), NullCache)]

    name = lambda d: f"{d.py_func.__module__}.{d.py_func.__qualname__}"
    base = {tuple(x) for x in json.loads(sys.argv[2])}
    getattr(warmup, sys.argv[1])()
    typed = set(base)
    while True:  # every signature run or loaded, and its callees', to the fixed point
        todo = [(d, sig) for d in kernels() for sig in list(d.overloads) if (name(d), str(sig)) not in typed]
        if not todo:
            break
        for d, sig in todo:
            typed.add((name(d), str(sig)))
            flags = compiler.Flags()
            d.targetdescr.options.parse_as_flags(flags, d.targetoptions)
            compiler.compile_extra(d.targetdescr.typing_context, d.targetdescr.target_context, d.py_func, sig,
                                   None, flags, d.locals, pipeline_class=TypeOnly)
    print("SIGS " + json.dumps(sorted(typed - base)))
""")


def _signatures(function: str, base: list) -> list:
    """(kernel, signature) pairs that warm-up group ``function`` run alone compiles beyond ``base``."""
    r = subprocess.run([sys.executable, "-c", _TYPED, function, json.dumps(base)], capture_output=True, text=True,
                       timeout=1500)
    assert r.returncode == 0, r.stderr[-2000:]
    return [tuple(x) for x in json.loads(r.stdout.rsplit("SIGS ", 1)[1])]


@pytest.mark.slow
def test_the_groups_compile_no_kernel_in_common():
    """Each group run alone after FIRST: no two groups add signatures to one kernel (numba's index of
    a kernel is one file, read, extended and written back: two processes adding to it at once lose
    one's addition, and may give two signatures one data file). What a group adds is found as numba
    finds it on a cold cache, without the cold compile (minutes of LLVM): every kernel signature the
    group runs, and every callee signature that typing those kernels compiles, beyond FIRST's."""
    from concurrent.futures import ThreadPoolExecutor

    from nbst import warmup

    base = _signatures(warmup.FIRST.function, [])
    assert any(k.endswith("sim.kernel.run") for k, _ in base)  # the event kernel
    with ThreadPoolExecutor(2) as pool:
        sigs = dict(zip(warmup.GROUPS, pool.map(lambda g: _signatures(g.function, base), warmup.GROUPS)))
    added = {g.name: {k for k, _ in sigs[g]} for g in warmup.GROUPS}
    for g in warmup.GROUPS:
        assert added[g.name], g.name  # each group compiles something
    for a, b in itertools.combinations(added, 2):
        assert not added[a] & added[b], (a, b, sorted(added[a] & added[b]))
