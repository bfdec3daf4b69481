"""nbst: N-body spacetime constraints.

Find the initial velocities that bring N frictionless elastic disks in a box to
their targets at ``t_final``; check the motion in MuJoCo; render it to video.

``import nbst`` stays light: it imports numpy and the problem model only. The
simulator (numba), MuJoCo and moderngl load on first use.
"""
from __future__ import annotations

import importlib

from nbst._version import __version__
from nbst.errors import InputError, MujocoError, NbstError, OutputError, RenderError, SolveError
from nbst.problem import Problem, ProblemError, builtin_names, load_problem
from nbst.solution import Solution, load_solution, save_solution

__all__ = [
    "__version__",
    "NbstError",
    "InputError",
    "OutputError",
    "SolveError",
    "MujocoError",
    "RenderError",
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
