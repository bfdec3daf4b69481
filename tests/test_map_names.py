"""The written map names what exists: every dotted ``nbst.…`` name in docs/*.md, docs/results/*.md, README.md and
the docstrings of nbst, models/ and render/ (modules, classes, functions, and attribute
docstrings: a string after an assignment, or a ``#:`` comment) resolves to a module, or to an
attribute of one, or to a field of a class. A name that fails is fixed where it is written."""
import ast
import functools
import importlib
import inspect
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: A dotted name that starts with ``nbst``, not inside a path or a longer word.
NAME = re.compile(r"(?<![\w./-])nbst(?:\.[A-Za-z_]\w*)+")
#: File names that read like dotted names (``nbst.json`` in a command line).
FILE_SUFFIXES = {"json", "mp4", "gif", "png", "svg", "xml", "csv", "md", "html", "toml", "py", "txt", "npz", "log"}
SOURCES = ("nbst", "models", "render")


def _in_docs():
    docs = ROOT / "docs"
    for f in [*sorted(docs.glob("*.md")), *sorted((docs / "results").glob("*.md")), ROOT / "README.md"]:
        for i, line in enumerate(f.read_text(encoding="utf-8").splitlines(), 1):
            for m in NAME.finditer(line):
                yield m.group(0), f"{f.relative_to(ROOT)}:{i}"


def _python_files():
    for folder in SOURCES:
        for f in sorted((ROOT / folder).rglob("*.py")):
            rel = f.relative_to(ROOT)
            if folder == "nbst" and rel.parts[1] in ("models", "render"):
                continue  # the links: read once, under models/ and render/
            yield f, rel


def _in_docstrings():
    for f, rel in _python_files():
        text = f.read_text(encoding="utf-8")
        for node in ast.walk(ast.parse(text)):
            body = getattr(node, "body", None)
            if not isinstance(body, list):
                continue
            for k, st in enumerate(body):
                if not (isinstance(st, ast.Expr) and isinstance(st.value, ast.Constant)
                        and isinstance(st.value.value, str)):
                    continue
                own = k == 0 and isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef))
                attribute = k > 0 and isinstance(body[k - 1], (ast.Assign, ast.AnnAssign))
                if own or attribute:
                    for m in NAME.finditer(st.value.value):
                        yield m.group(0), f"{rel}:{st.lineno}"
        for i, line in enumerate(text.splitlines(), 1):
            if line.lstrip().startswith("#:"):
                for m in NAME.finditer(line):
                    yield m.group(0), f"{rel}:{i}"


@functools.cache
def written_names() -> dict[str, list[str]]:
    """Every dotted nbst name written in the docs and docstrings, with where it is written."""
    out: dict[str, list[str]] = {}
    for name, where in [*_in_docs(), *_in_docstrings()]:
        if name.rsplit(".", 1)[1] in FILE_SUFFIXES:
            continue
        out.setdefault(name, []).append(where)
    return out


def _is_field(cls, name: str) -> bool:
    """``name`` is a field of ``cls``: annotated in its body (a dataclass or NamedTuple field, a
    declared attribute) or set on ``self`` in its source."""
    for c in cls.__mro__:
        if name in getattr(c, "__annotations__", {}):
            return True
    try:
        src = inspect.getsource(cls)
    except (OSError, TypeError):
        return False
    return re.search(rf"self\.{name}\b\s*(:[^=\n]*)?=", src) is not None


def resolves(name: str) -> bool:
    """``name`` is a module, or a chain of attributes from the longest module prefix."""
    parts = name.split(".")
    for k in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:k]))
            break
        except ModuleNotFoundError:
            continue
    else:
        return False
    for a in parts[k:]:
        if hasattr(obj, a):
            obj = getattr(obj, a)
        elif inspect.isclass(obj) and _is_field(obj, a):
            return True  # an instance's field: nothing further to check
        else:
            return False
    return True


def test_the_scan_reads_docs_and_docstrings():
    names = written_names()
    places = {w.split(":")[0] for ws in names.values() for w in ws}
    assert "README.md" in places and "docs/architecture.md" in places
    assert any(p.startswith("models/") for p in places) and any(p.startswith("render/") for p in places)
    assert len(names) > 150, len(names)  # 2026-12-03: 220 names in 500+ places


def test_the_resolver_refuses_what_does_not_exist():
    assert resolves("nbst.search.solve") and resolves("nbst.models.bowling.lane.frame")
    assert resolves("nbst.solution.SolveResult.velocities")  # a dataclass field
    assert not resolves("nbst.experiments.runs.plots")
    assert not resolves("nbst.solvers.solve_islands")
    assert not resolves("nbst.search.nosuch")


@pytest.mark.filterwarnings("ignore::DeprecationWarning")  # nbst.baselines, the documented old path
def test_every_dotted_name_in_docs_and_docstrings_resolves():
    bad = [f"{name} (in {', '.join(where[:3])})" for name, where in sorted(written_names().items())
           if not resolves(name)]
    assert not bad, "names that do not exist:\n" + "\n".join(bad)
