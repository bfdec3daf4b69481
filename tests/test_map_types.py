"""nbst ships its annotations (``nbst/py.typed``, PEP 561) and the annotated public API passes
mypy: the modules listed in pyproject.toml's ``[tool.mypy] files`` (the search's and the
solvers' way in, the registry, the solution, the errors), checked with their imports followed
silently (an error in a module not listed is not reported)."""
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


@pytest.mark.slow  # a cold mypy run: 8 s of CPU, 20+ s at load
def test_mypy_passes_on_the_annotated_public_api(tmp_path):
    r = subprocess.run([sys.executable, "-m", "mypy", "--config-file", str(ROOT / "pyproject.toml"),
                        "--cache-dir", str(tmp_path / "cache"), "--no-error-summary"],
                       cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stdout[-4000:] + r.stderr[-2000:]


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
