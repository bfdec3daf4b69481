"""nbst: N-body spacetime constraints.

Find the initial velocities that bring N frictionless elastic disks in a box to
their targets at ``t_final``; check the motion in MuJoCo; render it to video.

``import nbst`` stays light: it imports numpy and the problem model only. The
simulator (numba), MuJoCo and moderngl load on first use.
"""
from __future__ import annotations

import importlib
import importlib.abc
import importlib.machinery
import sys
from pathlib import Path

from nbst._version import __version__
from nbst.problem import Problem, ProblemError, builtin_names, load_problem
from nbst.solution import Solution, load_solution, save_solution

__all__ = [
    "__version__",
    "Problem",
    "ProblemError",
    "Solution",
    "builtin_names",
    "load_problem",
    "load_solution",
    "save_solution",
    "simulate",
    "evaluate",
    "Trajectory",
]

_LAZY = {"simulate": "nbst.sim", "evaluate": "nbst.sim", "Trajectory": "nbst.sim"}


def __getattr__(name):
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'nbst' has no attribute {name!r}")


class _CheckoutFinder(importlib.abc.MetaPathFinder):
    """Maps nbst.models -> models/ and nbst.render -> render/ in a source checkout.

    Installed (``pip install .`` or ``-e .``), setuptools' ``package-dir`` mapping
    does this; this finder only serves ``python cli.py`` and tests run from a
    checkout whose ``nbst/`` shadows the installed package.
    """

    def __init__(self, root: Path):
        self.root = str(root)

    def find_spec(self, fullname, path=None, target=None):
        if fullname in ("nbst.models", "nbst.render"):
            return importlib.machinery.PathFinder.find_spec(fullname, [self.root])
        return None


def _install_checkout_finder() -> None:
    here = Path(__file__).resolve().parent
    root = here.parent
    if (here / "models").is_dir():  # an installed wheel: mapping already done
        return
    pyproject = root / "pyproject.toml"
    if not (pyproject.is_file() and (root / "models" / "__init__.py").is_file()):
        return
    if 'name = "nbst"' not in pyproject.read_text(encoding="utf-8"):
        return
    if not any(isinstance(f, _CheckoutFinder) for f in sys.meta_path):
        sys.meta_path.append(_CheckoutFinder(root))


_install_checkout_finder()
