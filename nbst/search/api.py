"""The one typed way into the search: :func:`solve` (and :func:`run_search`, which also returns the
final population) for a problem of any size.

Up to 63 disks the signature search runs (``nbst.search.driver``: nbst's search or the paper's
variants A-H); past that the many-body search (``nbst.search.many``). Which one is decided here
alone, by ``nbst.constants.many_body``. Every keyword is spelled out and passed on by name.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from nbst._version import __version__
from nbst.constants import GA_MAX_DISKS, many_body
from nbst.errors import SolveError
from nbst.problem import Problem
from nbst.search.driver import SearchRun
from nbst.search.driver import run_search as _signature_search
from nbst.search.many import ALGORITHM_MANY, ManyParams, run_many
from nbst.search.params import ProgressCallback, SearchParams, check_run
from nbst.search.variants import DEFAULT_MAX_TRIALS, DEFAULT_PATIENCE, DEFAULT_VARIANT, SolveRequest, roundoff_cost
from nbst.seeds import resolve_seed
from nbst.sim import evaluate
from nbst.solution import SolveResult, signature_string

__all__ = ["ALGORITHM_STRAIGHT", "run_many_search", "run_request", "run_search", "solve", "straight_start"]


def solve(problem: Problem, *, seed: int | None = None, max_trials: int = DEFAULT_MAX_TRIALS,
          patience: int = DEFAULT_PATIENCE, target_cost: float | None = None,
          variant: str = DEFAULT_VARIANT, params: SearchParams | None = None,
          robust: bool | None = None, jobs: int | None = None, callback: ProgressCallback | None = None,
          chunk: int = 2048, many: ManyParams | None = None) -> SolveResult:
    """Find initial velocities that bring every disk of ``problem`` to its target at t_final.

    One search in this process (``nbst.solvers.islands.solve_islands`` runs several on several cores).

    Args:
        problem: the problem (``nbst.load_problem``), any number of disks.
        seed: int >= 0; None draws one (recorded as ``result.seed``). The same seed and
            options give the same velocities, bit for bit (``chunk`` and ``jobs`` do not matter).
        max_trials: trial budget; one trial is one simulated candidate (initialize and the
            backward planner included; the many-body search counts a simulation of m of N disks
            as m / N).
        patience: stop after this many trials without improvement (0: never).
        target_cost: stop once the best cost (sum of squared distances to the targets, units^2)
            is <= this; None: never (the many-body search: at round-off level, ``roundoff_cost``).
        variant: a name of ``nbst.search.variants.VARIANTS``: "nbst" (nbst's search, the
            default), "nbst-noplan", "A" (the paper's full algorithm) .. "H" (its simplified
            variants). Past 63 disks: the variant of each conflict's sub-search.
        params: every knob of the signature search (``SearchParams``; default: the variant's).
            Up to 63 disks only.
        robust: True: return the most noise-robust top-order solution rather than the cheapest
            (``nbst.search.robust``); None: as ``params`` says. Up to 63 disks only.
        jobs: threads the many-body search simulates candidates on (None: every core; the
            result does not depend on it). The signature search runs on one core.
        callback: called with a ``SearchProgress`` after every chunk of trials (every round of
            the many-body search); a truthy return stops the search. Ctrl-C stops it too; the
            result is then the best so far, ``stopped == "interrupted"``.
        chunk: trials per compiled call of the signature search (progress and Ctrl-C granularity).
        many: the many-body search's choices (``ManyParams``). Past 63 disks only.

    Returns:
        A :class:`~nbst.solution.SolveResult`: ``velocities``, ``cost``, ``signature``,
        ``order``, ``trials``, ``seed``, ``stopped``, ``wall_time``, ``history``, ... and the
        solution file's ``meta`` (``result.to_solution()`` is what ``nbst solve`` writes).

    Raises:
        SolveError: an option that does not apply to this problem's search.
        InputError: a bad option (a negative budget, an unknown variant).
    """
    request = SolveRequest(seed=seed, max_trials=max_trials, patience=patience, target_cost=target_cost,
                           variant=variant, robust=robust, jobs=jobs)
    return run_request(problem, request, params=params, callback=callback, chunk=chunk, many=many).result


def run_search(problem: Problem, *, seed: int | None = None, max_trials: int = DEFAULT_MAX_TRIALS,
               patience: int = DEFAULT_PATIENCE, target_cost: float | None = None,
               variant: str = DEFAULT_VARIANT, params: SearchParams | None = None,
               robust: bool | None = None, jobs: int | None = None, callback: ProgressCallback | None = None,
               chunk: int = 2048, many: ManyParams | None = None, record_every: int = 0) -> SearchRun:
    """:func:`solve`, also returning the final population (for benchmarks and analysis).

    Args:
        problem, seed, max_trials, patience, target_cost, variant: as :func:`solve`.
        params, robust, jobs, callback, chunk, many: as :func:`solve`.
        record_every: k > 0 also returns the candidates of trials k, 2k, ... (the paper's loop
            only, up to 63 disks).

    Returns:
        A ``SearchRun``: ``result`` (the :class:`~nbst.solution.SolveResult`), the final
        population's ``velocities``, ``costs`` and ``signatures``, and ``recorded``. Past 63
        disks the population is the one solution.

    Raises:
        SolveError: an option that does not apply to this problem's search.
    """
    request = SolveRequest(seed=seed, max_trials=max_trials, patience=patience, target_cost=target_cost,
                           variant=variant, robust=robust, jobs=jobs)
    return run_request(problem, request, params=params, callback=callback, chunk=chunk, many=many,
                       record_every=record_every)


def run_request(problem: Problem, request: SolveRequest, *, params: SearchParams | None = None,
                callback: ProgressCallback | None = None, chunk: int = 2048, many: ManyParams | None = None,
                record_every: int = 0) -> SearchRun:
    """:func:`run_search` with its settings as one object: what the solvers' registry calls.

    Args:
        problem: the problem, any number of disks.
        request: seed, budget, patience, target cost, variant, robust mode and threads
            (:class:`~nbst.search.variants.SolveRequest`; a None patience or variant: the
            search's defaults).
        params, callback, chunk, many, record_every: as :func:`run_search`.

    Returns:
        A ``SearchRun``, as :func:`run_search`.

    Raises:
        SolveError: an option that does not apply to this problem's search.
    """
    robust, jobs = request.robust, request.jobs
    if not many_body(problem.n):
        if many is not None:
            raise SolveError(f"many (ManyParams) applies to problems of more than {GA_MAX_DISKS} disks; "
                             f"{problem.name!r} has {problem.n}")
        return _signature_search(problem, request, params=params, callback=callback, chunk=chunk,
                                 record_every=record_every)
    for name, given in (("params", params is not None), ("robust", bool(robust)), ("record_every", record_every > 0)):
        if given:
            raise SolveError(f"{name} applies to problems of at most {GA_MAX_DISKS} disks (the signature search); "
                             f"{problem.name!r} has {problem.n}: the many-body search runs, set it with many=")
    return run_many_search(problem, dataclasses.replace(request, jobs=jobs), callback=callback, many=many)


def run_many_search(problem: Problem, request: SolveRequest, *, callback: ProgressCallback | None = None,
                    many: ManyParams | None = None) -> SearchRun:
    """The many-body search (``nbst.search.many.run_many``) on ``problem``, any N, with the result a
    solution file records (:func:`run_search` runs it past 63 disks).

    Args:
        problem: the problem, any number of disks.
        request: as :func:`run_request`; its ``variant`` is that of each conflict's sub-search
            (ignored when ``many`` is given), its ``target_cost`` None means round-off level
            (``roundoff_cost``), its ``jobs`` the threads candidates are simulated on.
        callback, many: as :func:`solve`.

    Returns:
        A ``SearchRun`` whose population is the one solution; ``result.many`` holds the search's
        statistics (rounds, conflicts tried and solved, the largest conflict).
    """
    seed = resolve_seed(request.seed)
    max_trials, patience, target_cost = int(request.max_trials), request.patience_or_default, request.target_cost
    check_run(max_trials, patience, seed)
    prm = many or ManyParams(variant=request.variant_or_default)
    tc = roundoff_cost(problem) if target_cost is None else float(target_cost)
    run = run_many(problem, seed=seed, max_trials=max_trials, patience=patience, target_cost=tc,
                   callback=callback, params=prm, jobs=request.jobs)
    v = run.velocities
    _, c, sg = evaluate(problem, v[None], jobs=1)
    sig = int(sg[0])
    wall = run.wall_time
    full = {"algorithm": ALGORITHM_MANY, "cost": float(c[0]), "signature": signature_string(sig, problem.n),
            "order": sig.bit_count(), "trials": run.trials, "seed": seed, "variant": prm.variant,
            "params": dataclasses.asdict(prm),
            "max_trials": int(max_trials), "patience": int(patience), "target_cost": target_cost,
            "stopped": run.stopped, "wall_time": wall,
            "trials_per_s": run.trials / wall if wall > 0 else None, "nbst_version": __version__,
            "history": run.history, "many": run.stats}
    return SearchRun(result=SolveResult.from_meta(problem, v, full), velocities=v[None].copy(),
                     costs=np.array([float(c[0])]), signatures=np.array([sig], dtype=object),
                     recorded=np.zeros((0, problem.n, 2)))


#: ``result.algorithm`` of :func:`straight_start`'s result.
ALGORITHM_STRAIGHT = "straight-start"


def straight_start(problem: Problem, request: SolveRequest, *, stopped: str | None = None) -> SolveResult:
    """The motion every search starts from, as a result: each cueable disk straight at its target
    (``problem.straight_velocities()``), simulated once (no trial counted). What ``nbst solve``
    writes when it is stopped before a search has a result of its own (a signal during the
    numba load or the backward planner): the straight start is a motion too.

    Args:
        problem: the problem.
        request: the search's settings, recorded as a search's are (its ``seed``, the seed the
            search was or would have been run with, must be given; a None ``patience``: the
            signature search's default; ``variant`` as given: None for a solver without one).
        stopped: why no search result replaced it ("interrupted"), or None.

    Returns:
        A :class:`~nbst.solution.SolveResult` with ``trials`` 0 and an empty history.
    """
    v = np.array(problem.straight_velocities(), dtype=float)
    _, c, sg = evaluate(problem, v[None], jobs=1)
    sig = int(sg[0])
    meta = {"algorithm": ALGORITHM_STRAIGHT, "cost": float(c[0]), "signature": signature_string(sig, problem.n),
            "order": sig.bit_count(), "trials": 0, "seed": int(request.seed or 0), "variant": request.variant,
            "max_trials": int(request.max_trials), "patience": request.patience_or_default,
            "target_cost": request.target_cost,
            "stopped": stopped, "wall_time": 0.0, "trials_per_s": None, "nbst_version": __version__,
            "history": []}
    return SolveResult.from_meta(problem, v, meta)
