"""The map checks itself: every package of nbst says what it exports (``__all__``), every
exported name resolves, and the package map stays light to import.

The packages are found by walking ``nbst/`` (through its links to ``models/`` and ``render/``),
so a new package is checked without being listed here."""
import ast
import importlib
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
HEAVY = ("numba", "mujoco", "moderngl")
#: The one package whose ``__init__`` may load a heavy module: the simulator is numba.
HEAVY_PACKAGES = {"nbst.sim"}


def packages() -> list[str]:
    """Every package under nbst/ (models/ and render/ through their links), as dotted names."""
    out = []
    for folder, dirs, files in os.walk(ROOT / "nbst", followlinks=True):
        dirs[:] = sorted(d for d in dirs if d != "__pycache__")
        if "__init__.py" in files:
            out.append(".".join(Path(folder).relative_to(ROOT).parts))
    return sorted(out)


def declared_all(package: str) -> list[str] | None:
    """The names of ``package``'s ``__all__`` as written in its ``__init__`` (a list of string
    literals, or lists joined with ``+`` / ``*`` unpacking of other ``__all__``s resolved at import),
    or None when it declares none."""
    init = ROOT.joinpath(*package.split("."), "__init__.py")
    for node in ast.parse(init.read_text(encoding="utf-8")).body:
        targets = node.targets if isinstance(node, ast.Assign) else [node.target] if isinstance(node, ast.AnnAssign) else []
        if any(isinstance(t, ast.Name) and t.id == "__all__" for t in targets):
            return list(importlib.import_module(package).__all__)
    return None


def test_the_walk_finds_the_packages_of_models_and_render():
    found = packages()
    assert {"nbst", "nbst.search", "nbst.models", "nbst.models.bowling.lane", "nbst.models.crash",
            "nbst.render"} <= set(found)
    assert len(found) >= 14


def test_every_package_declares_all():
    missing = [p for p in packages() if declared_all(p) is None]
    assert not missing, f"packages without __all__: {missing}"


def public_modules() -> list[str]:
    """Every public module under nbst/ (models/ and render/ through their links), as dotted names:
    each package and each .py file whose name does not start with ``_`` (``__main__`` is a
    script), inside packages none of whose names start with ``_`` either."""
    out = []
    for p in packages():
        folder = ROOT.joinpath(*p.split("."))
        if any(part.startswith("_") for part in p.split(".")):
            continue
        out.append(p)
        out += [f"{p}.{f.stem}" for f in sorted(folder.glob("*.py")) if not f.name.startswith("_")]
    return out


def _module_file(module: str) -> Path:
    path = ROOT.joinpath(*module.split("."))
    return path / "__init__.py" if path.is_dir() else path.with_suffix(".py")


def _declares_all(module: str) -> bool:
    for node in ast.parse(_module_file(module).read_text(encoding="utf-8")).body:
        targets = node.targets if isinstance(node, ast.Assign) else [node.target] if isinstance(node, ast.AnnAssign) else []
        if any(isinstance(t, ast.Name) and t.id == "__all__" for t in targets):
            return True
    return False


def test_every_public_module_declares_all():
    """Not only the packages: every public module says what it exports (``__all__``), so a reader,
    a star import and the docs' tools see one list. Prints each module without one."""
    modules = public_modules()
    assert len(modules) > 100 and "nbst.search.driver" in modules and "nbst.models.mjsearch.runner" in modules
    missing = [m for m in modules if not _declares_all(m)]
    print("\n".join(f"{_module_file(m).relative_to(ROOT)}: no __all__" for m in missing))
    assert not missing, f"{len(missing)} public modules without __all__: {missing}"


def test_every_name_in_every_all_resolves():
    """``from package import name`` works for every name of every ``__all__`` (a lazy name loads its
    module; a submodule named there is imported), and no name is listed twice."""
    bad, count = [], 0
    for p in packages():
        names = declared_all(p) or []
        assert len(names) == len(set(names)), f"{p}.__all__ lists a name twice"
        for name in names:
            count += 1
            try:
                exec(f"from {p} import {name}", {})
            except Exception as e:  # noqa: BLE001 - every failure is reported by name
                bad.append(f"{p}.{name}: {type(e).__name__}: {e}")
    assert not bad, "\n".join(bad)
    assert count > 150, count  # 2026-12-03: 14 packages, 200+ names


def test_import_nbst_and_its_package_map_stay_light():
    """``import nbst`` and every package ``__init__`` but the simulator's load neither numba, MuJoCo
    nor moderngl (the names of their ``__all__`` load those on first use)."""
    light = [p for p in packages() if p not in HEAVY_PACKAGES]
    code = (f"import sys\nfor p in {light!r}:\n    __import__(p)\n"
            f"    heavy = [m for m in {HEAVY!r} if m in sys.modules]\n"
            "    if heavy: print(p, heavy); sys.exit(1)\n")
    r = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stdout + r.stderr[-2000:]
