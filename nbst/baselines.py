"""Deprecated import path: the baselines moved to :mod:`nbst.solvers` (``solve_with``,
``solve_cma``, ``solve_de``, ``solve_ga``, ``solve_random``, ``SOLVERS``). This shim
keeps the documented ``from nbst.baselines import solve_with`` working, with a warning.
"""
from __future__ import annotations

import warnings

from nbst.solvers import SOLVERS, solve_cma, solve_de, solve_ga, solve_random, solve_with

__all__ = ["SOLVERS", "solve_cma", "solve_de", "solve_ga", "solve_random", "solve_with"]

warnings.warn("nbst.baselines is deprecated; import from nbst.solvers", DeprecationWarning, stacklevel=2)
