"""The one error family: every error class nbst defines derives from nbst.NbstError, and the
command line turns any of them into one line and the class's exit status."""
import importlib
import inspect
import pkgutil
import types

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
