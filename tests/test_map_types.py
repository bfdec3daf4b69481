"""nbst ships its annotations (``nbst/py.typed``, PEP 561) and the annotated modules pass
mypy (in the fast tier): those listed in pyproject.toml's ``[tool.mypy] files``, one line per
room, checked with their imports followed silently (an error in a module not listed is not
reported), at least 60 % of the package's lines."""
import os
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _pyproject() -> dict:
    return tomllib.loads((ROOT / "pyproject.toml").read_text())


def test_py_typed_is_shipped():
    assert (ROOT / "nbst" / "py.typed").is_file()
    assert "py.typed" in _pyproject()["tool"]["setuptools"]["package-data"]["nbst"]


def test_mypy_is_a_test_tool_and_its_files_exist():
    test_extra = _pyproject()["project"]["optional-dependencies"]["test"]
    assert any(dep.startswith("mypy") for dep in test_extra)
    files = _pyproject()["tool"]["mypy"]["files"]
    assert "nbst/search/api.py" in files and "nbst/solution.py" in files
    assert [f for f in files if not (ROOT / f).is_file()] == []


def test_mypy_passes_on_the_annotated_public_api():
    """In the fast tier: mypy's own cache (.mypy_cache at the root, which mypy keeps out of git)
    makes a warm run about 1.5 s of CPU; a cold one about 10 s, once."""
    r = subprocess.run([sys.executable, "-m", "mypy", "--config-file", str(ROOT / "pyproject.toml"),
                        "--cache-dir", str(ROOT / ".mypy_cache"), "--no-error-summary"],
                       cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stdout[-4000:] + r.stderr[-2000:]


#: The share of the package's lines (every .py under nbst/, models/ and render/ through the
#: links) that the mypy file list must cover.
MYPY_SHARE = 0.60


def _package_lines() -> dict[Path, int]:
    """Lines of every .py file of the package, by real path (the links walked once)."""
    out = {}
    for folder, dirs, files in os.walk(ROOT / "nbst", followlinks=True):
        dirs[:] = [d for d in dirs if d != "__pycache__"]
        for f in files:
            if f.endswith(".py"):
                path = (Path(folder) / f).resolve()
                out[path] = path.read_text(encoding="utf-8").count("\n")
    return out


def test_mypy_covers_most_of_the_package():
    """The mypy file list covers at least MYPY_SHARE of the package's lines (each room adds its
    files on its own line of ``[tool.mypy] files``). Prints the share measured."""
    lines = _package_lines()
    checked = {(ROOT / f).resolve() for f in _pyproject()["tool"]["mypy"]["files"]}
    assert checked <= set(lines), sorted(str(f) for f in checked - set(lines))
    share = sum(n for f, n in lines.items() if f in checked) / sum(lines.values())
    print(f"mypy covers {share:.1%} of {sum(lines.values()):,} package lines ({len(checked)} of {len(lines)} files)")
    assert share >= MYPY_SHARE, f"mypy covers {share:.1%} of the package's lines, under {MYPY_SHARE:.0%}"


def test_every_public_function_of_nbst_and_nbst_search_is_fully_annotated():
    """Issue 33's target: the functions (and class constructors) of ``nbst.__all__`` and
    ``nbst.search.__all__`` annotate every parameter and, for functions, the return; mypy (above)
    then checks them in the modules of ``[tool.mypy] files``."""
    import enum
    import inspect

    import nbst
    import nbst.search

    bare = []
    for mod in (nbst, nbst.search):
        for name in mod.__all__:
            obj = getattr(mod, name)
            if inspect.isclass(obj) and issubclass(obj, enum.Enum):
                continue  # an enum's constructor is the enum machinery's
            fn = obj.__init__ if inspect.isclass(obj) else obj
            if not inspect.isfunction(fn):
                continue
            sig = inspect.signature(fn)
            missing = [p for p, v in sig.parameters.items() if p != "self" and v.annotation is inspect.Parameter.empty]
            if not inspect.isclass(obj) and sig.return_annotation is inspect.Signature.empty:
                missing.append("return")
            if missing:
                bare.append(f"{mod.__name__}.{name}: {', '.join(missing)}")
    assert not bare, bare
