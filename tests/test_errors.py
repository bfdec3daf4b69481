"""The one error family: every error class nbst defines derives from nbst.NbstError, and the
command line turns any of them into one line and the class's exit status."""
import ast
import importlib
import inspect
import pkgutil
import types
from pathlib import Path

import pytest

import nbst
from nbst.errors import InputError, MujocoError, NbstError, OutputError, RenderError, SolveError


def _modules():
    """Every module of the installed package (models and render included), imported."""
    seen = []
    for pkg in ("nbst", "nbst.models", "nbst.render"):
        mod = importlib.import_module(pkg)
        seen.append(mod)
        for info in pkgutil.walk_packages(mod.__path__, prefix=pkg + "."):
            if info.name.endswith("__main__"):
                continue
            seen.append(importlib.import_module(info.name))
    return seen


def test_every_public_error_class_is_an_nbst_error():
    strays = []  # Exception only: a KeyboardInterrupt subclass carrying the best so far is control flow
    for mod in _modules():
        for name, obj in vars(mod).items():
            if (inspect.isclass(obj) and issubclass(obj, Exception) and obj.__module__ == mod.__name__
                    and not name.startswith("_")):
                if not issubclass(obj, NbstError):
                    strays.append(f"{mod.__name__}.{name}")
    assert not strays, f"error classes outside the family: {strays}"


def test_the_family_is_exported_and_keeps_its_old_bases():
    for cls in (NbstError, InputError, OutputError, SolveError, MujocoError, RenderError):
        assert getattr(nbst, cls.__name__) is cls
    # callers that caught ValueError for bad input (and RuntimeError for rendering) still do
    assert issubclass(nbst.ProblemError, InputError) and issubclass(InputError, ValueError)
    assert issubclass(RenderError, RuntimeError)
    assert not issubclass(MujocoError, ValueError)  # a simulation that blew up is not bad input


@pytest.mark.parametrize("cls", [InputError, OutputError, SolveError, MujocoError, RenderError])
def test_the_command_line_prints_any_member_as_one_line(cls, capsys):
    from nbst.cli.main import _run

    def boom(args):
        raise cls("thing.json: field: the reason\nsecond line")

    assert _run(types.SimpleNamespace(func=boom)) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("nbst: error: thing.json: field: the reason")


# --------------------------------------------------------------------------- the tree, read as text

_ROOT = Path(__file__).resolve().parent.parent
_BARE = {"ValueError", "RuntimeError"}


def _package_files():
    """Every .py file of the package as a user imports it: nbst/, and models/ and render/ (the
    targets of the nbst/models and nbst/render links), each once."""
    for top in ("nbst", "models", "render"):
        for path in sorted((_ROOT / top).rglob("*.py")):
            rel = path.relative_to(_ROOT)
            if rel.parts[:2] in (("nbst", "models"), ("nbst", "render")):  # the links: walked as models/, render/
                continue
            yield rel, ast.parse(path.read_text(encoding="utf-8"), filename=str(rel))


def _raised_name(node: ast.Raise) -> str | None:
    """``ValueError`` for ``raise ValueError(...)`` and ``raise ValueError`` alike (else None)."""
    exc = node.exc.func if isinstance(node.exc, ast.Call) else node.exc
    return exc.id if isinstance(exc, ast.Name) else None


def _caught_names(handler: ast.ExceptHandler) -> set[str]:
    kinds = handler.type.elts if isinstance(handler.type, ast.Tuple) else [handler.type]
    return {k.id for k in kinds if isinstance(k, ast.Name)}


def test_library_code_raises_no_bare_value_or_runtime_error():
    """Library code raises the family (InputError, SolveError, MujocoError, ...), never a bare
    ValueError/RuntimeError: a library caller can rely on catching NbstError."""
    offenders = [f"{rel}:{node.lineno}: raise {_raised_name(node)}"
                 for rel, tree in _package_files() for node in ast.walk(tree)
                 if isinstance(node, ast.Raise) and node.exc is not None and _raised_name(node) in _BARE]
    print("\n".join(offenders))
    assert not offenders, f"{len(offenders)} bare raises in library code:\n" + "\n".join(offenders)


def test_the_command_line_catches_no_value_error():
    """The CLI lets the library's NbstError through to main's one handler: no ``except ValueError``
    (alone or in a tuple) in nbst/cli."""
    offenders = [f"{rel}:{node.lineno}: except ValueError"
                 for rel, tree in _package_files() if rel.parts[:2] == ("nbst", "cli")
                 for node in ast.walk(tree)
                 if isinstance(node, ast.ExceptHandler) and node.type is not None
                 and "ValueError" in _caught_names(node)]
    print("\n".join(offenders))
    assert not offenders, f"{len(offenders)} except ValueError in nbst/cli:\n" + "\n".join(offenders)


def test_the_walk_sees_the_whole_package():
    """The walk reads models/ and render/ (through the links) and nbst/cli, so a green run means
    something."""
    tops = {rel.parts[0] for rel, _ in _package_files()}
    assert tops == {"nbst", "models", "render"}
    assert any(rel.parts[:2] == ("nbst", "cli") for rel, _ in _package_files())
