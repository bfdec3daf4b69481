"""Pick a solver by name: ``solve_with("cma", problem, seed=1, max_trials=100_000)``.

"signature" is the signature search (``nbst.search.solve``, ``variant=`` picks A-H or
nbst's); "cma", "de", "ga" and "random" are the baselines of ``nbst.solvers.baselines``.
"""
from __future__ import annotations

from nbst.problem import Problem, ProblemError
from nbst.search import solve
from nbst.solvers.baselines import ALGORITHMS, solve_cma, solve_de, solve_ga, solve_random


def solve_signature(problem: Problem, **kw):
    """``nbst.search.solve`` (the signature search), unchanged: its defaults apply (patience
    100,000, variant "nbst"); ``variant=`` picks A-H."""
    return solve(problem, **kw)


SOLVERS = {"signature": solve_signature, "cma": solve_cma, "de": solve_de, "ga": solve_ga, "random": solve_random}


def solve_with(algorithm: str, problem: Problem, **kw):
    """Dispatch to a solver by name: "signature" (``nbst.search.solve``; ``variant=`` picks
    the variant), "cma", "de", "ga", "random". Keywords as :func:`nbst.search.solve`."""
    a = algorithm.strip().lower()
    if a not in SOLVERS:
        raise ProblemError("<search parameters>", "algorithm",
                           f"unknown algorithm {algorithm!r}; choose one of {', '.join(ALGORITHMS)}")
    if a != "signature" and kw.get("variant") not in (None, "", "nbst"):
        raise ProblemError("<search parameters>", "variant",
                           f"a variant ({kw['variant']}) applies to the signature search only, not to {a}")
    if a != "signature":
        kw.pop("variant", None)
    return SOLVERS[a](problem, **kw)
