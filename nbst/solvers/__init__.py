"""Every solver behind one call, and K of them on K cores.

* ``nbst.solvers.baselines``: CMA-ES, differential evolution, a GA and random search,
  with the signature search's trial accounting;
* ``nbst.solvers.dispatch``: :func:`solve_with` picks a solver by name ("signature" is
  ``nbst.search.solve``);
* ``nbst.solvers.islands``: ``nbst solve --jobs K``: K independent searches of any
  algorithm in lockstep, reproducible for the same seed and K.

Layer: above ``nbst.search`` (it calls the signature search as one solver among others),
below the experiments and the command line.
"""
from __future__ import annotations

from nbst.solvers.baselines import ALGORITHMS, solve_cma, solve_de, solve_ga, solve_random
from nbst.solvers.dispatch import solve_with

__all__ = ["ALGORITHMS", "solve_cma", "solve_de", "solve_ga", "solve_random", "solve_with"]
