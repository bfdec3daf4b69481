"""Baselines behind the same problem model and trial accounting as ``nbst.search.solve``.

    from nbst import load_problem
    from nbst.solvers import solve_with
    result = solve_with("cma", load_problem("diamond-s14"), seed=1, max_trials=100_000)
    result.cost, result.trials, result.history

Every solver takes the keywords of :func:`nbst.search.solve` that apply to it (keyword-only
``seed``, ``max_trials``, ``patience``, ``target_cost``, ``callback``, then its own
options) and returns a :class:`~nbst.solution.SolveResult` (cost, signature, order, trials,
seed, algorithm, wall_time, stopped and history: (trial, cost, order) at every improvement
of the best cost; its ``meta`` adds nbst_version and the solver's parameters). The solvers
are registered by name in ``nbst.solvers.dispatch.SOLVERS``.

Accounting: one trial = one simulated candidate. All simulations go through
:func:`nbst.sim.evaluate` in batches, each batch cut to the remaining budget, so
``result.trials <= max_trials`` always (candidates cut off are never simulated
and never scored). Only the cueable disks' velocities are searched; noncueable
disks keep zero velocity. A truncated simulation (``max_events``) scores cost inf.

Choices (each a module constant with its why):

* ``cma``: pycma's ``CMAEvolutionStrategy`` ask/tell, IPOP restarts (population
  doubles per restart, from pycma's default 4 + 3 ln D), every restart from
  x0 = the straight-line velocities with sigma0 = ``CMA_SIGMA0_FRACTION * R / t_final``
  (default 3: one sigma moves a free-flight end point by 3R per axis, so the first
  generations reach past the target neighbourhoods to other bank shots and
  collisions; picked from a small probe, see the constant). pycma's
  own stopping rules end a restart; a generation is one ``evaluate`` batch.
  Random numbers: pycma's ``randn`` option is fed from the run's
  ``np.random.Generator`` (pycma's global-state seeding is off).
* ``ga``: a steady-state real-coded GA (the paper's point of comparison): population
  ``GA_POP`` initialised like the paper's initialize (each cueable disk directed or
  uniform randomize with probability 1/2), binary tournament selection, uniform
  crossover per disk (each disk's (vx, vy) from either parent), Gaussian mutation
  (each cueable disk with probability 1/n_cue, std ``GA_MUTATION_FRACTION * R / t_final``
  per axis), the child replaces the worst member if it is better. Children are made
  ``GA_BATCH`` at a time from the current population (one ``evaluate`` batch) and
  inserted one by one.
* ``de``: scipy's ``differential_evolution`` (best1bin, vectorized, deferred
  updating, no polish, tol = atol = 0 so it runs to the budget), bounds = velocities
  whose free flight ends within ``DE_BOUNCES`` mirror images of the box per axis,
  the initial population made like the GA's (directed / uniform randomize per disk,
  member 0 the straight-line velocities), clipped to the bounds. (scipy's default
  Latin-hypercube start never improved on the straight line in 400k trials on
  diamond-s14: the random members score ~1.1e6 against its 3.7e5.) scipy's
  ``maxfun`` does not bound evaluations exactly, so the objective itself counts and
  cuts: once the budget is spent, it returns inf without simulating and the
  generation callback stops the run.
* ``random``: each trial sets every cueable disk by directed randomize or uniform
  randomize (probability 1/2 each), i.e. the paper's initialize without a
  population; batches of ``RANDOM_BATCH``.

Length: four solvers over one budget (``_Budget``), one randomize and one result format; each
solver's Args are written out (the public entry points), and split they would share the rest.
"""
from __future__ import annotations

import contextlib
import math
import time
from typing import TYPE_CHECKING, Any

import numpy as np

from nbst._version import __version__
from nbst.problem import Problem, ProblemError
from nbst.seeds import resolve_seed
from nbst.solution import SolveResult, signature_string

if TYPE_CHECKING:
    from nbst.search.params import ProgressCallback

__all__ = ["BASELINE_PATIENCE", "CMA_SIGMA0_FRACTION", "CMA_INCPOPSIZE", "GA_POP", "GA_TOURNAMENT",
           "GA_MUTATION_FRACTION", "GA_BATCH", "DE_BOUNCES", "DE_POPSIZE", "RANDOM_BATCH", "MAX_BOUNCES",
           "PROGRESS_EVERY", "BIG_COST", "solve_random", "solve_cma", "blas_single_thread", "solve_ga", "de_bounds",
           "solve_de"]

#: Patience of a baseline unless told otherwise: none (a baseline runs to its budget or target).
BASELINE_PATIENCE = 0

#: CMA-ES step size, as a fraction of R / t_final (units/s): 1 sigma moves an end point by 3R per axis
#: (probe on diamond-s14, 2 seeds x 100k trials: 0.3 -> 6564 / 18226, 1 -> 10960 / 11177, 3 -> 72 / 8587).
CMA_SIGMA0_FRACTION = 3.0
#: IPOP: population multiplier per restart (Auger & Hansen 2005 use 2).
CMA_INCPOPSIZE = 2
#: GA population size (half the paper's population limit: a plain GA has no culling).
GA_POP = 100
#: GA tournament size (binary tournament).
GA_TOURNAMENT = 2
#: GA mutation std per axis as a fraction of R / t_final: an end point moves ~0.3 R per axis
#: (3x the signature search's creep, since mutation is the GA's only local move).
GA_MUTATION_FRACTION = 0.3
#: GA children made per batch from the same population (one evaluate call; small vs GA_POP).
GA_BATCH = 16
#: DE bounds: free-flight end points within this many mirror images of the box per axis.
#: DE_BOUNCES and DE_POPSIZE from a probe (seed 1, 100k trials): diamond-s14 best1bin
#: bounces 0/1/2 x popsize 5: 16378 / 2136 / 223418; popsize 15: 25196 / 155951 / 368525.
DE_BOUNCES = 1
#: DE population size multiplier (scipy's popsize: popsize * D members).
DE_POPSIZE = 5
#: Random search: candidates per evaluate batch.
RANDOM_BATCH = 1024
#: Uniform randomize reaches images with |kx| + |ky| <= this (the paper's 5, as nbst.search).
MAX_BOUNCES = 5
#: The callback is called at most once per this many trials (as the search's chunk).
PROGRESS_EVERY = 2048
#: Finite stand-in for an inf cost (truncated simulation) where an optimizer needs one (CMA ranks only).
BIG_COST = 1e300


class _Budget:
    """Counts trials, keeps the best, the history and the stopping rules.

    ``evaluate(X)``: X (B, D) cueable velocity components -> costs (b,) for the first
    b = min(B, remaining) rows (only those are simulated and counted).
    """

    def __init__(self, problem: Problem, *, max_trials: int, patience: int, target_cost: float | None,
                 callback: ProgressCallback | None, phase: str = ""):
        from nbst.sim import evaluate

        self._evaluate = evaluate
        self.problem = problem
        self.cue = np.flatnonzero(problem.cueable)
        self.dim = 2 * self.cue.size
        self.max_trials, self.patience, self.target_cost = max_trials, patience, target_cost
        self.callback = callback
        self.trials = 0
        self.best_cost = math.inf
        self.best_sig = 0
        self.best_x = self.x0 = problem.straight_velocities()[self.cue].ravel()
        self.best_trial = 0
        self.full = (1 << problem.n) - 1
        self.first_full: int | None = None
        self.history: list[list] = []
        self.stopped: str | None = None
        self.phase = phase
        self.population = 0
        self._last_progress = 0
        self.t0 = time.perf_counter()

    @property
    def remaining(self) -> int:
        return self.max_trials - self.trials

    def velocities(self, X: np.ndarray) -> np.ndarray:
        """Velocity sets (B, N, 2) of the rows of X, each kept inside the accepted domain
        (``nbst.search.ops.limit_crossings``: a legal problem never yields a refused solution)."""
        from nbst.search.ops import limit_crossings

        V = np.zeros((X.shape[0], self.problem.n, 2))
        V[:, self.cue] = X.reshape(X.shape[0], self.cue.size, 2)
        if np.all(np.isfinite(V)):
            ka = self.problem.kernel_arrays()
            cue = self.cue.astype(np.int64)
            for b in range(V.shape[0]):
                limit_crossings(V[b], cue, ka.radius, ka.W, ka.H, ka.t_final)
        return V

    def evaluate(self, X) -> np.ndarray:
        X = np.asarray(X, dtype=float).reshape(-1, self.dim)
        b = min(X.shape[0], self.remaining)
        if b <= 0:
            self.stopped = self.stopped or "max_trials"
            return np.empty(0)
        X = X[:b]
        if not np.all(np.isfinite(X)):  # never simulated with bad numbers: score as a failed run
            X = np.where(np.isfinite(X), X, 0.0)
        _, cost, sig = self._evaluate(self.problem, self.velocities(X))
        start = self.trials
        self.trials += b
        if self.first_full is None:
            hit = np.flatnonzero(sig == self.full)
            if hit.size:
                self.first_full = start + int(hit[0]) + 1
        k = int(np.argmin(cost))
        if cost[k] < self.best_cost:
            self.best_cost, self.best_sig, self.best_x = float(cost[k]), int(sig[k]), X[k].copy()
            self.best_trial = start + k + 1
            self.history.append([self.best_trial, self.best_cost, _popcount(self.best_sig)])
        self._check()
        return cost

    def _check(self) -> None:
        if self.stopped is not None:
            return
        if self.target_cost is not None and self.best_cost <= self.target_cost:
            self.stopped = "target_cost"
        elif self.trials >= self.max_trials:
            self.stopped = "max_trials"
        elif self.patience > 0 and self.trials - self.best_trial >= self.patience:
            self.stopped = "patience"

    def progress(self) -> None:
        """Call the callback (once per generation / batch); a truthy return stops the run."""
        if self.callback is None or (self.trials - self._last_progress < PROGRESS_EVERY and self.stopped is None):
            return
        self._last_progress = self.trials
        from nbst.search import SearchProgress

        prog = SearchProgress(trials=self.trials, best_cost=self.best_cost, best_order=_popcount(self.best_sig),
                              elapsed=time.perf_counter() - self.t0, population=self.population, phase=self.phase)
        if self.callback(prog) and self.stopped is None:
            self.stopped = "callback"


def _check_args(max_trials: int, patience: int, seed) -> int:
    if int(max_trials) < 1:
        raise ProblemError("<search parameters>", "max_trials", f"must be >= 1, got {max_trials}")
    if int(patience) < 0:
        raise ProblemError("<search parameters>", "patience", f"must be >= 0 (0 = no patience limit), got {patience}")
    return resolve_seed(seed)


def _finish(problem: Problem, b: _Budget, *, algorithm: str, seed: int, params: dict,
            extra: dict[str, Any] | None = None) -> SolveResult:
    """The result of a baseline: its best (or the straight-line start if nothing finite was
    simulated), with ``meta`` in the file's order (``extra`` keys last)."""
    wall = time.perf_counter() - b.t0
    if b.trials == 0 or not math.isfinite(b.best_cost):
        x = b.x0  # nothing finite simulated: report the straight-line start (one check simulation, not a trial)
        _, c, s = b._evaluate(problem, b.velocities(x[None]))
        cost, sig, xbest = float(c[0]), int(s[0]), x
    else:
        cost, sig, xbest = b.best_cost, b.best_sig, b.best_x
    meta = {
        "algorithm": algorithm,
        "cost": cost,
        "signature": signature_string(sig, problem.n),
        "order": _popcount(sig),
        "trials": b.trials,
        "seed": seed,
        "variant": None,
        "params": params,
        "max_trials": b.max_trials,
        "patience": b.patience,
        "target_cost": b.target_cost,
        "stopped": b.stopped,
        "wall_time": wall,
        "trials_per_s": b.trials / wall if wall > 0 else None,
        "nbst_version": __version__,
        "first_full_order_trial": b.first_full,
        "history": b.history,
        **(extra or {}),
    }
    return SolveResult.from_meta(problem, b.velocities(np.asarray(xbest)[None])[0], meta)


def _popcount(x: int) -> int:
    return int(x).bit_count()


def _randomize(problem: Problem, rng: np.random.Generator, B: int, *, p_directed: float = 0.5,
               max_bounces: int = MAX_BOUNCES) -> np.ndarray:
    """(B, 2 n_cue) candidates: each cueable disk directed (straight) or uniform randomize.

    Uniform randomize as ``nbst.search.ops.uniform_velocity``: the free-flight end point
    is uniform over the box's centre region reached through a mirror image drawn
    uniformly from those with |kx| + |ky| <= max_bounces."""
    from nbst.search import mirror_images

    cue = np.flatnonzero(problem.cueable)
    x0 = problem.start[cue]
    r = problem.radius[cue]
    W, H = problem.box
    T = problem.t_final
    images = mirror_images(max_bounces)
    m = rng.integers(images.shape[0], size=(B, cue.size))
    u = rng.random((B, cue.size, 2))
    ex = r + (images[m, 0] + u[..., 0]) * (W - 2 * r)
    ey = r + (images[m, 1] + u[..., 1]) * (H - 2 * r)
    V = np.stack([(ex - x0[:, 0]) / T, (ey - x0[:, 1]) / T], axis=-1)
    directed = rng.random((B, cue.size)) < p_directed
    V[directed] = problem.straight_velocities()[cue][np.nonzero(directed)[1]]
    return V.reshape(B, 2 * cue.size)


# --------------------------------------------------------------------------- solvers

def solve_random(problem: Problem, *, seed: int | None = None, max_trials: int = 1_000_000,
                 patience: int = BASELINE_PATIENCE, target_cost: float | None = None,
                 callback: ProgressCallback | None = None,
                 p_directed: float = 0.5) -> SolveResult:
    """Random search: independent candidates from directed / uniform randomize (see module doc).

    Args:
        problem: the problem.
        seed: int >= 0; None draws one (recorded in the result).
        max_trials: trial budget (one trial = one simulated candidate).
        patience: stop after this many trials without improvement (0: never).
        target_cost: stop once the best cost is <= this, units^2 (None: never).
        callback: None, or called with a ``SearchProgress``; a truthy return stops the search.
        p_directed: each disk's chance of directed (vs uniform) randomize.

    Returns:
        The :class:`~nbst.solution.SolveResult` (its best so far when interrupted).

    Raises:
        InputError: a budget, patience or seed out of range.
    """
    seed = _check_args(max_trials, patience, seed)
    rng = np.random.default_rng(seed)
    b = _Budget(problem, max_trials=int(max_trials), patience=int(patience), target_cost=target_cost,
                callback=callback, phase="sample")
    try:
        while b.stopped is None:
            b.evaluate(_randomize(problem, rng, min(RANDOM_BATCH, b.remaining), p_directed=p_directed))
            b.progress()
    except KeyboardInterrupt:
        b.stopped = "interrupted"
    return _finish(problem, b, algorithm="random-search", seed=seed,
                   params={"p_directed": p_directed, "max_bounces": MAX_BOUNCES, "batch": RANDOM_BATCH})


def solve_cma(problem: Problem, *, seed: int | None = None, max_trials: int = 1_000_000,
              patience: int = BASELINE_PATIENCE, target_cost: float | None = None,
              callback: ProgressCallback | None = None,
              sigma0_fraction: float = CMA_SIGMA0_FRACTION, incpopsize: int = CMA_INCPOPSIZE,
              cma_options: dict | None = None) -> SolveResult:
    """CMA-ES (pycma) with IPOP restarts from the straight-line velocities (see module doc).

    sigma0 = sigma0_fraction * R / t_final units/s; population 4 + 3 ln D, times
    ``incpopsize`` per restart. ``result.meta["restarts"]`` counts the restarts begun.

    Args:
        problem: the problem.
        seed: int >= 0; None draws one (recorded in the result).
        max_trials: trial budget (one trial = one simulated candidate).
        patience: stop after this many trials without improvement (0: never).
        target_cost: stop once the best cost is <= this, units^2 (None: never).
        callback: None, or called with a ``SearchProgress``; a truthy return stops the search.
        sigma0_fraction: the initial step as a fraction of R / t_final.
        incpopsize: the population's factor per restart.
        cma_options: extra pycma options for every restart (e.g. ``{"maxiter": 5}``, a stopping
            rule that ends each restart after 5 generations).

    Returns:
        The :class:`~nbst.solution.SolveResult` (its best so far when interrupted).

    Raises:
        InputError: a budget, patience or seed out of range.
    """
    import cma

    seed = _check_args(max_trials, patience, seed)
    rng = np.random.default_rng(seed)
    b = _Budget(problem, max_trials=int(max_trials), patience=int(patience), target_cost=target_cost,
                callback=callback)
    sigma0 = sigma0_fraction * problem.target_radius / problem.t_final
    D = b.dim
    lam0 = int(4 + 3 * math.log(D))
    ends: list = []

    def randn(*shape):
        return rng.standard_normal(shape)

    try:
        with blas_single_thread():
            _cma_loop(b, cma, sigma0, lam0, incpopsize, randn, ends, dict(cma_options or {}))
    except KeyboardInterrupt:
        b.stopped = "interrupted"
    return _finish(problem, b, algorithm="cma-es-ipop", seed=seed,
                   params={"sigma0": sigma0, "sigma0_fraction": sigma0_fraction, "popsize0": lam0,
                           "incpopsize": incpopsize, "x0": "straight-line velocities", "dimension": D},
                   extra={"restarts": len(ends) - 1, "restart_ends": ends})


def _cma_loop(b: _Budget, cma, sigma0: float, lam: int, incpopsize: int, randn, ends: list, extra: dict) -> None:
    """IPOP: restarts of CMA-ES from b.x0 until the budget (or another rule) stops the run."""
    while b.stopped is None:
        b.phase = f"restart {len(ends)}"
        b.population = lam
        opts = {"popsize": lam, "seed": np.nan, "randn": randn, "verbose": -9, "verb_log": 0, "verb_disp": 0,
                "verb_filenameprefix": "", "maxfevals": math.inf, **extra}
        es = cma.CMAEvolutionStrategy(b.x0, sigma0, opts)
        while b.stopped is None and not es.stop():
            X = np.asarray(es.ask())
            f = b.evaluate(X)
            if f.shape[0] < X.shape[0]:  # the budget cut this generation: it is not told
                break
            es.tell(list(X), [c if math.isfinite(c) else BIG_COST for c in f])
            b.progress()
        ends.append({"population": lam, "trials": b.trials,
                     "stop": {k: _jsonable(v) for k, v in es.stop().items()}})
        lam *= incpopsize


@contextlib.contextmanager
def blas_single_thread():
    """Run the block with OpenBLAS limited to one thread, then restore its count.

    pycma decomposes a D x D covariance (D = 2 n_cue, e.g. 28) every few generations;
    multi-threaded OpenBLAS on such small matrices is ~10x slower than one thread
    (0.75 ms vs 0.08 ms per 28 x 28 eigh, and far worse on a loaded machine). Best
    effort (what threadpoolctl does): finds the loaded OpenBLAS libraries of numpy and
    scipy by their exported ``*openblas_set_num_threads*`` symbols; does nothing elsewhere.
    """
    import ctypes

    saved = []
    try:
        with open("/proc/self/maps", encoding="utf-8") as f:
            libs = sorted({line.split()[-1] for line in f if "openblas" in line.lower() and ".so" in line})
    except OSError:
        libs = []
    for path in libs:
        try:
            lib = ctypes.CDLL(path)
        except OSError:
            continue
        for suffix in ("", "64_"):
            for prefix in ("scipy_openblas", "openblas"):
                get = getattr(lib, f"{prefix}_get_num_threads{suffix}", None)
                put = getattr(lib, f"{prefix}_set_num_threads{suffix}", None)
                if get is not None and put is not None:
                    saved.append((put, int(get())))
                    put(1)
                    break
    try:
        yield
    finally:
        for put, n in saved:
            put(n)


def _jsonable(v):
    if isinstance(v, (int, float, str, bool)) or v is None:
        return v
    try:
        return float(v)
    except (TypeError, ValueError):
        return str(v)


def solve_ga(problem: Problem, *, seed: int | None = None, max_trials: int = 1_000_000,
             patience: int = BASELINE_PATIENCE, target_cost: float | None = None,
             callback: ProgressCallback | None = None, pop_size: int = GA_POP,
             mutation_fraction: float = GA_MUTATION_FRACTION, batch: int = GA_BATCH) -> SolveResult:
    """A standard steady-state real-coded GA (see module doc).

    Args:
        problem: the problem.
        seed: int >= 0; None draws one (recorded in the result).
        max_trials: trial budget (one trial = one simulated candidate).
        patience: stop after this many trials without improvement (0: never).
        target_cost: stop once the best cost is <= this, units^2 (None: never).
        callback: None, or called with a ``SearchProgress``; a truthy return stops the search.
        pop_size: the population.
        mutation_fraction: the mutation's step, times R / t_final (units/s).
        batch: children simulated per batch.

    Returns:
        The :class:`~nbst.solution.SolveResult` (its best so far when interrupted).

    Raises:
        InputError: a budget, patience or seed out of range.
    """
    seed = _check_args(max_trials, patience, seed)
    rng = np.random.default_rng(seed)
    b = _Budget(problem, max_trials=int(max_trials), patience=int(patience), target_cost=target_cost,
                callback=callback, phase="initialize")
    nc = b.cue.size
    sigma = mutation_fraction * problem.target_radius / problem.t_final
    b.population = pop_size
    try:
        X = _randomize(problem, rng, pop_size)
        f = b.evaluate(X)
        X, f = X[:f.shape[0]], np.where(np.isfinite(f), f, math.inf)
        b.phase = "generate"
        b.progress()
        while b.stopped is None:
            k = min(batch, b.remaining)
            P = X.shape[0]
            # binary tournaments: the lower cost of GA_TOURNAMENT uniform draws, two parents per child
            cand = rng.integers(P, size=(k, 2, GA_TOURNAMENT))
            parents = np.take_along_axis(cand, np.argmin(f[cand], axis=-1)[..., None], axis=-1)[..., 0]
            A = X[parents[:, 0]].reshape(k, nc, 2)
            Bp = X[parents[:, 1]].reshape(k, nc, 2)
            take_b = rng.random((k, nc)) < 0.5
            C = np.where(take_b[..., None], Bp, A)
            mut = rng.random((k, nc)) < 1.0 / nc
            C = C + mut[..., None] * rng.normal(0.0, sigma, (k, nc, 2))
            C = C.reshape(k, 2 * nc)
            fc = b.evaluate(C)
            for j in range(fc.shape[0]):  # steady state: replace the worst if better
                w = int(np.argmax(f))
                if fc[j] < f[w]:
                    X[w], f[w] = C[j], fc[j]
            b.progress()
    except KeyboardInterrupt:
        b.stopped = "interrupted"
    return _finish(problem, b, algorithm="steady-state-ga", seed=seed,
                   params={"pop_size": pop_size, "tournament": GA_TOURNAMENT, "crossover": "uniform per disk",
                           "mutation_sigma": sigma, "mutation_fraction": mutation_fraction,
                           "mutation_rate": "1/n_cue per disk", "batch": batch,
                           "init": "directed/uniform randomize, p = 1/2"})


def de_bounds(problem: Problem, bounces: int | None = None) -> list[tuple[float, float]]:
    """Per cueable component (vx, vy, ...): velocities whose free flight ends within
    ``bounces`` mirror images of the box on each side."""
    bounces = DE_BOUNCES if bounces is None else bounces
    out = []
    T = problem.t_final
    for i in np.flatnonzero(problem.cueable):
        r = problem.radius[i]
        for axis, L in ((0, problem.box[0]), (1, problem.box[1])):
            span = L - 2 * r
            lo, hi = r - bounces * span, r + (bounces + 1) * span
            x = problem.start[i, axis]
            out.append(((lo - x) / T, (hi - x) / T))
    return out


def solve_de(problem: Problem, *, seed: int | None = None, max_trials: int = 1_000_000,
             patience: int = BASELINE_PATIENCE, target_cost: float | None = None,
             callback: ProgressCallback | None = None, popsize: int = DE_POPSIZE,
             strategy: str = "best1bin") -> SolveResult:
    """Differential evolution (scipy), exact trial accounting (see module doc).

    Args:
        problem: the problem.
        seed: int >= 0; None draws one (recorded in the result).
        max_trials: trial budget (one trial = one simulated candidate).
        patience: stop after this many trials without improvement (0: never).
        target_cost: stop once the best cost is <= this, units^2 (None: never).
        callback: None, or called with a ``SearchProgress``; a truthy return stops the search.
        popsize: scipy's population multiplier.
        strategy: scipy's strategy ("best1bin").

    Returns:
        The :class:`~nbst.solution.SolveResult` (its best so far when interrupted).

    Raises:
        InputError: a budget, patience or seed out of range.
    """
    from scipy.optimize import differential_evolution

    seed = _check_args(max_trials, patience, seed)
    b = _Budget(problem, max_trials=int(max_trials), patience=int(patience), target_cost=target_cost,
                callback=callback, phase="generation")
    D = b.dim
    b.population = popsize * D

    def objective(x):  # vectorized: x (D, S) -> (S,)
        X = np.asarray(x).T
        out = np.full(X.shape[0], math.inf)
        if b.stopped is None:
            f = b.evaluate(X)
            out[:f.shape[0]] = f
        return out

    def on_generation(*_args, **_kw):
        b.progress()
        return b.stopped is not None

    import inspect

    gen = np.random.default_rng(seed)
    bounds = np.array(de_bounds(problem))
    # initial population as the GA's (the paper's initialize): directed / uniform randomize per disk,
    # member 0 all straight; clipped to the bounds (uniform randomize reaches up to 5 images)
    init = np.clip(_randomize(problem, gen, popsize * D), bounds[:, 0], bounds[:, 1])
    init[0] = np.clip(b.x0, bounds[:, 0], bounds[:, 1])
    rng_kw = {"rng": gen} if "rng" in inspect.signature(differential_evolution).parameters else {"seed": gen}
    try:
        differential_evolution(objective, bounds, strategy=strategy, maxiter=10**9, popsize=popsize,
                               tol=0.0, atol=0.0, callback=on_generation, **rng_kw, init=init,
                               polish=False, vectorized=True, updating="deferred")
    except KeyboardInterrupt:
        b.stopped = "interrupted"
    if b.stopped is None:
        b.stopped = "converged"
    return _finish(problem, b, algorithm="differential-evolution", seed=seed,
                   params={"strategy": strategy, "popsize": popsize, "members": popsize * D, "bounces": DE_BOUNCES,
                           "mutation": [0.5, 1.0], "recombination": 0.7,
                           "init": "directed/uniform randomize, p = 1/2, member 0 straight; clipped to the bounds"})
