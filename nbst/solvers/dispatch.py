"""Every solver, registered once by name: ``solve_with("cma", problem, seed=1, max_trials=100_000)``.

``SOLVERS`` is the one list of solvers: ``nbst solve --algorithm`` and its help, the islands
(``nbst solve --jobs``), the experiments' entries (``nbst experiment ... --algorithms``) and the
docs read it. A new solver is a function ``run(problem, request, callback) -> SolveResult``
(:class:`Solver`) registered here or from anywhere with :func:`register_solver`::

    from nbst.solvers import SolveRequest, register_solver

    def my_solver(problem, request: SolveRequest, callback) -> SolveResult: ...
    register_solver("mine", my_solver, help="what it does, in one line")

"signature" is the signature search (``nbst.search.solve``; ``variant`` picks nbst's search,
A-H, ...); "cma", "de", "ga" and "random" are the baselines of ``nbst.solvers.baselines``.

This module stays light (no numba at import): the command line reads ``SOLVERS`` to build its
options; the signature search is imported when it runs.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

from nbst.constants import many_body
from nbst.problem import Problem, ProblemError
from nbst.registry import Registry
from nbst.search.variants import DEFAULT_VARIANT, SolveRequest
from nbst.solution import SolveResult
from nbst.solvers.baselines import BASELINE_PATIENCE, solve_cma, solve_de, solve_ga, solve_random

if TYPE_CHECKING:
    from nbst.search.params import ProgressCallback

__all__ = ["SOLVERS", "SIGNATURE", "SolveRequest", "Solver", "SolverInfo", "register_solver", "run_solver",
           "solve_with"]

#: The signature search's name among the solvers.
SIGNATURE = "signature"


class Solver(Protocol):
    """A solver: the best velocities it finds for ``problem`` within ``request``; it calls
    ``callback`` with a ``SearchProgress`` every few thousand trials (a truthy return stops it)
    and returns its best so far when interrupted (``stopped == "interrupted"``).

    Args:
        problem: the problem.
        request: seed, budget and stopping rules (:class:`~nbst.search.variants.SolveRequest`).
        callback: None, or called with a ``SearchProgress``; a truthy return stops the search.

    Returns:
        The :class:`~nbst.solution.SolveResult`.
    """

    def __call__(self, problem: Problem, request: SolveRequest,
                 callback: ProgressCallback | None) -> SolveResult: ...


def _never(problem: Problem) -> bool:
    return False


@dataclass(frozen=True)
class SolverInfo:
    """A registered solver.

    Args:
        run: the solver (:class:`Solver`).
        variants: whether it takes ``variant`` and ``robust`` (the signature search).
        one_process: problems on which it runs one search in this process, using ``jobs`` as its
            own threads, instead of ``--jobs`` islands (the many-body search).

    Returns:
        The entry ``SOLVERS`` holds under the solver's name.
    """

    run: Solver
    variants: bool = False
    one_process: Callable[[Problem], bool] = _never


SOLVERS: Registry[SolverInfo] = Registry("algorithm")


def register_solver(name: str, run: Solver, *, help: str, variants: bool = False,
                    one_process: Callable[[Problem], bool] = _never) -> None:
    """Add a solver to ``SOLVERS`` (see :class:`SolverInfo`).

    Args:
        name: its name (``nbst solve --algorithm NAME``).
        run: the solver (:class:`Solver`).
        help: its one line in ``nbst solve --help`` and the experiments' docs.
        variants, one_process: as :class:`SolverInfo`.

    Returns:
        None.

    Raises:
        InputError: the name is empty or already registered.
    """
    SOLVERS.register(name, SolverInfo(run, variants, one_process), help=help)


def run_solver(algorithm: str, problem: Problem, request: SolveRequest,
               callback: ProgressCallback | None = None) -> SolveResult:
    """Run the registered solver ``algorithm`` (any case) on ``problem`` as ``request`` says.

    Args:
        algorithm: a name of ``SOLVERS`` (any case).
        problem: the problem.
        request: seed, budget and stopping rules (:class:`~nbst.search.variants.SolveRequest`).
        callback: None, or called with a ``SearchProgress``; a truthy return stops the search.

    Returns:
        The solver's :class:`~nbst.solution.SolveResult`.

    Raises:
        InputError: an unknown algorithm, or a variant or robust mode for a solver without them.
    """
    name = SOLVERS.parse(algorithm, source="<search parameters>", field="algorithm")
    info = SOLVERS[name]
    if not info.variants:
        for field, given in (("variant", request.variant not in (None, "", _default_variant())),
                             ("robust", request.robust)):
            if given:
                raise ProblemError("<search parameters>", field,
                                   f"applies to the signature search only, not to {name}")
    return info.run(problem, request, callback)


def solve_with(algorithm: str, problem: Problem, *, seed: int | None = None, max_trials: int = 1_000_000,
               patience: int | None = None, target_cost: float | None = None, variant: str | None = None,
               robust: bool = False, jobs: int | None = None,
               callback: ProgressCallback | None = None) -> SolveResult:
    """Run a solver by name: "signature" (``nbst.search.solve``), "cma", "de", "ga", "random", or any
    other of ``SOLVERS``.

    Args:
        algorithm: a name of ``SOLVERS`` (any case).
        problem: the problem.
        seed, max_trials, patience, target_cost, variant, robust, jobs: as :class:`SolveRequest`.
        callback: called with a ``SearchProgress`` every chunk of trials; a truthy return stops it.

    Returns:
        The solver's :class:`~nbst.solution.SolveResult`.
    """
    request = SolveRequest(seed=seed, max_trials=max_trials, patience=patience, target_cost=target_cost,
                           variant=variant, robust=robust, jobs=jobs)
    return run_solver(algorithm, problem, request, callback)


def _default_variant() -> str:
    return DEFAULT_VARIANT


# --------------------------------------------------------------------------- the registered solvers

def _signature(problem: Problem, request: SolveRequest, callback: ProgressCallback | None) -> SolveResult:
    """``nbst.search.solve``: its defaults apply where the request leaves a choice open."""
    from nbst.search.api import run_request

    return run_request(problem, request, callback=callback).result


def _patience(request: SolveRequest) -> int:
    return BASELINE_PATIENCE if request.patience is None else request.patience


def _baseline(solve: Callable[..., SolveResult]) -> Solver:
    """A baseline of ``nbst.solvers.baselines`` as a registered solver: the request's settings,
    its patience ``BASELINE_PATIENCE`` where the request leaves it open."""

    def run(problem: Problem, request: SolveRequest, callback: ProgressCallback | None) -> SolveResult:
        return solve(problem, seed=request.seed, max_trials=request.max_trials, patience=_patience(request),
                     target_cost=request.target_cost, callback=callback)

    return run


def _many_body(problem: Problem) -> bool:
    return many_body(problem.n)


register_solver(SIGNATURE, _signature, variants=True, one_process=_many_body,
                help="nbst's signature search (the default; --variant picks nbst's search, the paper's A or its "
                     "variants B-H; past 63 disks the many-body search, one process)")
register_solver("cma", _baseline(solve_cma), help="CMA-ES (pycma), IPOP restarts from the straight-line velocities")
register_solver("de", _baseline(solve_de), help="differential evolution (scipy, best1bin)")
register_solver("ga", _baseline(solve_ga), help="a standard steady-state real-coded GA")
register_solver("random", _baseline(solve_random), help="random search: directed or uniform randomize per disk")
