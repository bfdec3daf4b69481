"""The layer contract (pyproject.toml's [tool.importlinter], docs/architecture.md) holds:
imports point down only, no cycles anywhere (function-local imports included), and every
room of nbst has its place in the contract.

nbst.models and nbst.render live in models/ and render/ at the top of the checkout (the design
card); nbst/models and nbst/render are symbolic links to them, so the checkout's import tree is
the installed one and import-linter (grimp) reads the checkout as it is. A test that plants an
import works on a copy (the links copied as folders)."""
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
LINT = Path(sys.executable).with_name("lint-imports")


def _copy(dest: Path) -> Path:
    """A copy of the package to plant imports in (the links to models/ and render/ become folders)."""
    ignore = shutil.ignore_patterns("__pycache__", "*.nbi", "*.nbc", "*.json")
    shutil.copytree(ROOT / "nbst", dest / "nbst", ignore=ignore)
    return dest


def _lint(tree: Path) -> subprocess.CompletedProcess:
    return subprocess.run([str(LINT), str(ROOT / "pyproject.toml"), "--no-cache"], cwd=tree,
                          env={"PYTHONPATH": str(tree), "PATH": "/usr/bin:/bin"},
                          capture_output=True, text=True, timeout=300)


def _contracts() -> list[dict]:
    return tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["importlinter"]["contracts"]


def test_every_contract_is_kept():
    out = _lint(ROOT)  # the checkout as it is
    assert out.returncode == 0, out.stdout[-4000:] + out.stderr[-2000:]
    assert f"{len(_contracts())} kept, 0 broken" in out.stdout


@pytest.mark.parametrize("module, line, broken", [
    # the simulator may not reach up into the search, even inside a function
    ("nbst/sim/api.py", "def _upward():\n    from nbst.search import solve\n", "nbst.sim.api -> nbst.search"),
    # the paper's loop may not import nbst's loop above it
    ("nbst/search/loop.py", "def _upward():\n    from nbst.search import nbst_loop\n", "nbst.search.loop -> nbst.search.nbst_loop"),
    # a MuJoCo model may not import the command line
    ("models/scene.py", "import nbst.cli.args\n", "nbst.models.scene -> nbst.cli.args"),
])
def test_an_upward_import_breaks_the_contract(tmp_path, module, line, broken):
    t = _copy(tmp_path)
    f = t / ("nbst/" + module if not module.startswith("nbst/") else module)
    f.write_text(f.read_text() + "\n\n" + line)
    out = _lint(t)
    assert out.returncode != 0
    assert broken in out.stdout and "BROKEN" in out.stdout


def test_an_import_graph_tool_sees_inside_models_and_render():
    """grimp (import-linter's graph) on the checkout, with no finder hook: the imports inside
    nbst.models and nbst.render are seen, as installed."""
    code = ("import grimp; g = grimp.build_graph('nbst', cache_dir=None);"
            "print(g.direct_import_exists(importer='nbst.models.bowling.lane.frame', imported='nbst.models.bowling.scene'),"
            " g.direct_import_exists(importer='nbst.render.core.video', imported='nbst.render.core.gl'),"
            " len([m for m in g.modules if m.startswith(('nbst.models.', 'nbst.render.'))]) > 20)")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"},
                         capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.split() == ["True", "True", "True"]


def _children(folder: Path) -> set[str]:
    return {p.stem if p.suffix == ".py" else p.name for p in folder.iterdir()
            if (p.suffix == ".py" and p.stem != "__init__") or (p.is_dir() and (p / "__init__.py").is_file())}


def test_the_contract_lists_every_room():
    """Every module and subpackage of nbst sits in a layer (a new room must be placed)."""
    layers = next(c for c in _contracts() if c["id"] == "layers")["layers"]
    listed = {m.strip() for layer in layers for m in layer.split("|")}
    rooms = {f"nbst.{c}" for c in _children(ROOT / "nbst") | {"models", "render"} if c != "__main__"}
    assert rooms - listed == set(), "rooms missing from [tool.importlinter] layers"
    assert listed - rooms == set(), "layers naming no room"
    for c in _contracts():
        if c.get("containers"):
            (pkg,) = c["containers"]
            inner = {m.strip() for layer in c["layers"] for m in layer.split("|")}
            assert inner == _children(ROOT / pkg.replace(".", "/")), f"{pkg}: its layers must list every module"


def test_bowling_its_halves_and_the_rollout_room_have_inner_contracts():
    """Every package of nbst.models.bowling (the two halves included) and the rollout room is the
    container of a layers contract (a new half or subpackage must be placed, module by module)."""
    contained = {c["containers"][0] for c in _contracts() if c.get("containers")}
    packages = set()
    for top in ("bowling", "mjsearch"):
        for init in (ROOT / "models" / top).rglob("__init__.py"):
            packages.add("nbst.models." + ".".join(init.parent.relative_to(ROOT / "models").parts))
    assert {"nbst.models.bowling", "nbst.models.bowling.deck", "nbst.models.bowling.lane"} <= packages
    assert packages - contained == set(), "packages without an inner layers contract"


def test_the_documented_old_baselines_path_still_works_with_a_warning():
    import importlib
    import sys as _sys

    _sys.modules.pop("nbst.baselines", None)
    with pytest.warns(DeprecationWarning, match="nbst.solvers"):
        old = importlib.import_module("nbst.baselines")
    import nbst.solvers as new

    assert old.solve_with is new.solve_with and old.solve_cma is new.solve_cma


def test_public_names_keep_working():
    import nbst
    import nbst.models
    import nbst.render
    from nbst.search import solve
    from nbst.sim import simulate

    assert nbst.simulate is simulate and callable(nbst.evaluate) and callable(nbst.load_problem)
    assert callable(solve)
    assert nbst.models.__name__ == "nbst.models" and nbst.render.__name__ == "nbst.render"
    out = subprocess.run([sys.executable, str(ROOT / "cli.py"), "problems"], capture_output=True, text=True,
                         timeout=120)
    assert out.returncode == 0 and "over5" in out.stdout


def test_a_module_past_500_lines_says_why():
    """The house's ~500-line module: a longer one states its reason ("Length:") in its
    opening docstring."""
    import ast

    long = []
    for folder in ("nbst", "models", "render"):
        for f in sorted((ROOT / folder).rglob("*.py")):
            text = f.read_text(encoding="utf-8")
            if text.count("\n") > 510:
                doc = ast.get_docstring(ast.parse(text)) or ""
                if "Length:" not in doc:
                    long.append(f"{f.relative_to(ROOT)} ({text.count(chr(10))} lines)")
    assert not long, long
