"""Every solver behind one call, and K of them on K cores.

* ``nbst.solvers.dispatch``: ``SOLVERS``, the one list of solvers (the signature search,
  ``nbst.search.solve``, and the baselines), :func:`solve_with` / :func:`run_solver` that run one
  by name, and :func:`register_solver` that adds one;
* ``nbst.solvers.baselines``: CMA-ES, differential evolution, a GA and random search,
  with the signature search's trial accounting;
* ``nbst.solvers.islands``: ``nbst solve --jobs K``: K independent searches of any
  registered solver in lockstep, reproducible for the same seed and K (``solve_islands``).

Layer: above ``nbst.search`` (it calls the signature search as one solver among others),
below the experiments and the command line. Importing this package is light (no numba): the
command line reads ``SOLVERS``; the islands are imported where they run.
"""
from __future__ import annotations

from nbst.solvers.baselines import solve_cma, solve_de, solve_ga, solve_random
from nbst.solvers.dispatch import (SIGNATURE, SOLVERS, SolveRequest, Solver, SolverInfo, register_solver, run_solver,
                                   solve_with)

__all__ = ["SIGNATURE", "SOLVERS", "SolveRequest", "Solver", "SolverInfo", "register_solver", "run_solver",
           "solve_cma", "solve_de", "solve_ga", "solve_random", "solve_with"]
