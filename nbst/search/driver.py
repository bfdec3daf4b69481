"""The paper's signature search (Ngo & Marks style), its variants B-H, and ``solve``.

    from nbst import load_problem
    from nbst.search import solve
    sol = solve(load_problem("diamond-s14"), seed=1, max_trials=200_000)
    sol.velocities, sol.meta["cost"], sol.meta["order"]

Layout: operators in ``nbst.search_ops`` (small numba kernels, tested one by one
on hand-built populations), the compiled initialize / generate-insert loop in
``nbst.search_loop``, parameters, variants and the Python driver here.

Choices the paper leaves open (each is a :class:`SearchParams` field or a run
option; ``docs/search.md`` has the same list with the reasoning):

* creep: normal perturbation of one cueable disk's velocity, std per axis
  ``creep_fraction * R / t_final`` (default 0.1: the free-flight end point moves
  ~R/10 = 7.5 units per axis on the benchmark problems); R is the problem's, in
  every variant.
* uniform randomize: the free-flight end point is uniform over the box (centre
  region [r, W-r] x [r, H-r]) and the mirror image it is reached through is
  uniform over the 61 images with |kx| + |ky| <= ``max_bounces`` = 5, i.e. the
  unfolded end point is uniform over the union of those 61 image boxes.
* directed randomize is deterministic (the straight velocity is unique).
* within a signature, the parent is a uniformly chosen member.
* second crossover parent: never the first parent itself (its signature is
  allowed when another member holds it); Senate-like among the signatures that
  maximize popcount(s1 | s2).
* crossover with a single member is replaced by creep (never happens after a
  normal initialize).
* "best" means lowest L2 cost among accepted (order >= 1) solutions; an
  improvement is a strictly lower cost.
* generate rejects order-0 children too (Senate selection ranges over orders
  1..N, so the population holds none); truncated simulations (``max_events``)
  score cost inf, signature 0, and are rejected.
* initialize: the diversity criterion counts every disk (noncueable ones too),
  stops after ``init_max_tries`` = 1000 trials if unmet (and goes on past it until
  at least one solution is accepted); initialize's trials count towards the trial
  budget; elitism protects the best already during initialize.
* culling: among the subsumed solutions outside the best's signature, the lowest
  order is found and every subsumed solution of that order deleted (one round per
  insertion). If nothing is subsumed and the population exceeds ``hard_limit`` =
  400, the worst member outside the best's signature is deleted (counted in
  ``meta["fallback_deletions"]``).
* insert's per-signature limit is checked before the population limit; "worst"
  = highest cost, ties to the lowest index.
* stopping: ``patience`` K counts trials since the last improvement (default
  100,000; 0 disables), ``max_trials`` (default 1,000,000; includes initialize),
  ``target_cost`` (stop once the best cost <= C; default off).
* variants: B both parents uniform over members (second != first, no popcount
  rule); C weights 1/3 creep, directed, uniform; D crossover coin per disk; E
  signature radius = box width, initialize until 60 members, per-signature limit
  60 (else one signature could hold only 10); F after every addition the worst
  member is deleted (the per-signature limit still applies first); G no elitism
  anywhere (displacement, limits, culling); H initialize uses uniform randomize
  only and generate weights 1/3 creep, uniform, crossover.
* random numbers: xoshiro256** seeded from ``np.random.SeedSequence(seed)``.
* ``meta`` cost / signature / order use the problem's R (as ``nbst simulate``);
  ``search_signature``, history orders and ``first_full_order_trial`` use the
  search's R (they differ only in variant E).
"""
from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ._version import __version__
from .constants import MAX_EVENTS, ROUNDOFF_REL
from .problem import Problem, ProblemError
from .robust import ARCHIVE_SIZE as ROBUST_ARCHIVE, POLISH_TOP as ROBUST_POLISH, SAMPLES as ROBUST_SAMPLES, \
    SEARCH_SAMPLES as ROBUST_K, TIMESTEP as ROBUST_TIMESTEP

VARIANTS = {
    "A": "the full algorithm",
    "B": "uniform probability for parent selection",
    "C": "no crossover operation",
    "D": "no genetically engineered crossover",
    "E": "no signature information (R = box width, initial population 60)",
    "F": "no culling of subsumed solutions (delete the worst on every insertion)",
    "G": "no elitism",
    "H": "no directed randomization",
    "nbst": "nbst's default: the paper's search plus polish, bank shots, strikes, a straight start and the backward "
            "planner",
    "nbst-noplan": "nbst without the backward planner (ablation)",
}

ALGORITHM = "paper-signature-search"
ALGORITHM_NBST = "nbst-signature-search"


@dataclass(frozen=True, kw_only=True)
class SearchParams:
    """Every knob of the signature search. Defaults are the paper's (A).

    pop_limit        : population limit (paper: 200)
    sig_limit        : members per signature (paper: 10)
    diversity        : initialize until every disk is acceptable in this many members (paper: 5)
    init_max_tries   : cap on initialize's trials if the diversity target is never met (open)
    init_population  : > 0: initialize until the population has this many members instead (E: 60)
    signature_radius : R used for signatures, None = the problem's (E: the box width)
    max_bounces      : uniform randomize reaches images with |kx| + |ky| <= this (paper: 5)
    creep_fraction   : creep std per axis = creep_fraction * R / t_final, units/s (open)
    op_weights       : (creep, directed, uniform, crossover) probabilities (paper: 1/4 each)
    p_directed_init  : initialize's chance of directed (vs uniform) randomize per disk (paper: 1/2)
    senate           : Senate-like parent selection (B: off, uniform over members)
    engineered       : genetically engineered crossover (D: off)
    cull             : "subsumed" (paper) or "worst" (F)
    elitism          : the best member is never deleted (G: off)
    hard_limit       : culling fallback: above this size the worst member goes (open)
    max_events       : per-simulation event cap (a truncated run scores cost inf)

    nbst's additions (``nbst.search_nbst``; all off in A-H, on in variant "nbst"):
    polish           : Levenberg-Marquardt polish of promising children
    polish_sims      : simulation budget of one polish
    polish_ratio     : polish children of the best order within this factor of the best cost
    bank_weight      : generate probability weight of the bank-shot operator
    bank_bounces     : bank shots use images with at most this many bounces
    strike_weight    : weight of the strike operator (used only if some disk is noncueable)
    strike_bounces   : strikes aim at images of the target with at most this many bounces
    adapt            : adapt operator probabilities from their recent success
    adapt_rate       : rate of the success moving average
    adapt_floor      : least probability of an enabled operator
    straight_start   : initialize's first trial sends every cueable disk straight at its target
    restart          : re-initialize around the best after this many trials without a
                       local improvement (0: never)
    planner          : run the backward planner (``nbst.planner``) first when some disk is
                       noncueable; its best candidates are initialize's first trials
    planner_trials   : the planner's simulations, at most (and at most a quarter of max_trials);
                       every one counts as a trial
    planner_chain    : longest strike chain the planner builds (cue -> noncueable -> ...)
    planner_seeds    : planner candidates handed to the search
    planner_polish_sims : polish budget of a planner candidate (instead of polish_sims)
    planner_weight   : weight of the plan operator (the planner's routes; only after a planner run)

    Robust mode (``nbst.robust``; off in every variant, ``nbst solve --robust``): candidates are
    scored by their worst cost under small shifts of the start positions (signature: the disks
    acceptable under all of them), and the solution is the most robust of an archive of
    top-order members, rescored under fresh shifts.
    robust           : score every candidate under robust_k start shifts and choose the solution
                       by its robust score instead of its cost
    robust_k         : start shifts per candidate during the search (0: the search is plain and
                       only the final choice is robust)
    robust_signature : "and": a disk counts as acceptable only if it is in every shifted run;
                       "plain": the unshifted signature (only the cost is the worst-case one)
    robust_archive   : top-order population members kept for the final choice (0: the choice
                       is among the search's best alone)
    robust_samples   : start shifts per candidate in the final choice (fresh draws)
    robust_timestep  : the engine step h (s) to survive: start shifts of std 0.5 h x the
                       fastest speed per axis (``nbst.robust.SHIFT_STEPS``)
    robust_polish    : candidates polished towards their on-target disks' target centres (and
                       rescored; ``nbst.robust.polish_on_target``)
    """

    variant: str = "A"
    pop_limit: int = 200
    sig_limit: int = 10
    diversity: int = 5
    init_max_tries: int = 1000
    init_population: int = 0
    signature_radius: float | None = None
    max_bounces: int = 5
    creep_fraction: float = 0.1
    op_weights: tuple[float, float, float, float] = (0.25, 0.25, 0.25, 0.25)
    p_directed_init: float = 0.5
    senate: bool = True
    engineered: bool = True
    cull: str = "subsumed"
    elitism: bool = True
    hard_limit: int = 400
    max_events: int = MAX_EVENTS
    polish: bool = False
    polish_sims: int = 20
    polish_ratio: float = 2.0
    bank_weight: float = 0.0
    bank_bounces: int = 3
    strike_weight: float = 0.0
    strike_bounces: int = 1
    adapt: bool = False
    adapt_rate: float = 0.01
    adapt_floor: float = 0.03
    straight_start: bool = False
    restart: int = 0
    planner: bool = False
    planner_trials: int = 100_000
    planner_chain: int = 3
    planner_seeds: int = 16
    planner_polish_sims: int = 100
    planner_weight: float = 0.1
    robust: bool = False
    robust_k: int = ROBUST_K
    robust_signature: str = "and"
    robust_archive: int = ROBUST_ARCHIVE
    robust_samples: int = ROBUST_SAMPLES
    robust_timestep: float = ROBUST_TIMESTEP
    robust_polish: int = ROBUST_POLISH

    @property
    def nbst_loop(self) -> bool:
        """Whether any of nbst's additions is on (they run in ``search_nbst``'s loop)."""
        return (self.polish or self.bank_weight > 0 or self.strike_weight > 0 or self.adapt or self.planner
                or self.straight_start or self.restart > 0 or (self.robust and self.robust_k > 0))

    def to_dict(self) -> dict:
        d = dataclasses.asdict(self)
        d["op_weights"] = list(self.op_weights)
        return d


#: Variant "nbst": the paper's A plus every addition of ``nbst.search_nbst`` (see docs/search.md
#: and the ablation in docs/results.md for what each contributes).
NBST_DEFAULTS = dict(op_weights=(0.2, 0.1, 0.1, 0.2), bank_weight=0.3, strike_weight=0.1, polish=True,
                     straight_start=True, planner=True)
# The adaptive operator schedule (adapt=True) and restarts (restart=20_000) are built and
# measured but off: the ablation (docs/results.md) showed no gain from either.


def variant_params(variant: str = "nbst", problem: Problem | None = None) -> SearchParams:
    """nbst's search ("nbst"), the paper's variant A (full algorithm) or B-H (one simplification each).

    E needs ``problem`` (its signature radius is the box width)."""
    v = variant.lower() if variant.lower().startswith("nbst") else variant.upper()
    if v not in VARIANTS:
        raise ValueError(f"unknown variant {variant!r}; choose one of {', '.join(VARIANTS)}")
    if v == "nbst":
        return SearchParams(variant="nbst", **NBST_DEFAULTS)
    if v == "nbst-noplan":
        return SearchParams(variant=v, **{**NBST_DEFAULTS, "planner": False})
    base = SearchParams(variant=v)
    third = 1.0 / 3.0
    if v == "B":
        return dataclasses.replace(base, senate=False)
    if v == "C":
        return dataclasses.replace(base, op_weights=(third, third, third, 0.0))
    if v == "D":
        return dataclasses.replace(base, engineered=False)
    if v == "E":
        if problem is None:
            raise ValueError("variant E needs the problem (R = box width)")
        return dataclasses.replace(base, signature_radius=float(problem.width), init_population=60, sig_limit=60)
    if v == "F":
        return dataclasses.replace(base, cull="worst")
    if v == "G":
        return dataclasses.replace(base, elitism=False)
    if v == "H":
        return dataclasses.replace(base, op_weights=(third, 0.0, third, third), p_directed_init=0.0)
    return base


def mirror_images(max_bounces: int) -> np.ndarray:
    """(M, 2) int64 image indices (kx, ky) with |kx| + |ky| <= max_bounces (M = 61 for 5)."""
    b = int(max_bounces)
    return np.array([(kx, ky) for kx in range(-b, b + 1) for ky in range(-b, b + 1) if abs(kx) + abs(ky) <= b],
                    dtype=np.int64).reshape(-1, 2)


@dataclass(frozen=True)
class SearchProgress:
    """What a callback sees after each chunk of trials."""

    trials: int
    best_cost: float
    best_order: int
    elapsed: float
    population: int
    phase: str


@dataclass
class _State:
    """The arrays a search carries between chunks (mutable by design: the kernel writes them)."""

    pop: tuple
    st: np.ndarray
    best_cost: np.ndarray
    best_v: np.ndarray
    rng: np.ndarray
    hist_t: np.ndarray
    hist_c: np.ndarray
    hist_o: np.ndarray
    op_count: np.ndarray = field(default_factory=lambda: np.zeros((4, 2), np.int64))


def _pack(problem: Problem, params: SearchParams, *, max_trials: int, patience: int, target_cost: float | None,
          record_every: int = 0):
    from . import search_loop as L

    pi = np.zeros(L.N_PI, np.int64)
    pi[L.PI_POP_LIMIT] = params.pop_limit
    pi[L.PI_SIG_LIMIT] = params.sig_limit
    pi[L.PI_DIVERSITY] = params.diversity
    pi[L.PI_INIT_MAX_TRIES] = params.init_max_tries
    pi[L.PI_INIT_POPULATION] = params.init_population
    pi[L.PI_SENATE] = int(params.senate)
    pi[L.PI_ENGINEERED] = int(params.engineered)
    pi[L.PI_CULL] = {"subsumed": 0, "worst": 1}[params.cull]
    pi[L.PI_ELITISM] = int(params.elitism)
    pi[L.PI_HARD_LIMIT] = params.hard_limit
    pi[L.PI_MAX_TRIALS] = max_trials
    pi[L.PI_PATIENCE] = patience
    pi[L.PI_MAX_EVENTS] = params.max_events
    pi[L.PI_RECORD_EVERY] = record_every
    pf = np.zeros(L.N_PF)
    pf[L.PF_R] = params.signature_radius if params.signature_radius is not None else problem.target_radius
    pf[L.PF_CREEP_SIGMA] = params.creep_fraction * problem.target_radius / problem.t_final
    pf[L.PF_TARGET_COST] = -math.inf if target_cost is None else target_cost
    pf[L.PF_P_DIRECTED_INIT] = params.p_directed_init
    w = np.asarray(params.op_weights, float)
    pf[L.PF_W_CREEP:L.PF_W_CROSSOVER + 1] = w / w.sum()
    return pi, pf


def _check(params: SearchParams, max_trials: int, patience: int) -> None:
    def bad(name, why):
        raise ProblemError("<search parameters>", name, why)

    if max_trials < 1:
        bad("max_trials", f"must be >= 1, got {max_trials}")
    if patience < 0:
        bad("patience", f"must be >= 0 (0 = no patience limit), got {patience}")
    if params.pop_limit < 2 or params.sig_limit < 1 or params.diversity < 1:
        bad("pop_limit", "pop_limit >= 2, sig_limit >= 1 and diversity >= 1 are required")
    if params.hard_limit < params.pop_limit:
        bad("hard_limit", f"must be >= pop_limit ({params.pop_limit})")
    if params.cull not in ("subsumed", "worst"):
        bad("cull", f"must be 'subsumed' or 'worst', got {params.cull!r}")
    w = np.asarray(params.op_weights, float)
    if w.shape != (4,) or np.any(w < 0) or w.sum() <= 0:
        bad("op_weights", "must be 4 non-negative weights (creep, directed, uniform, crossover), not all 0")
    if params.max_bounces < 0 or params.creep_fraction < 0:
        bad("max_bounces", "max_bounces and creep_fraction must be >= 0")
    if params.bank_weight < 0 or params.strike_weight < 0 or params.planner_weight < 0:
        bad("bank_weight", "bank_weight and strike_weight must be >= 0")
    if params.polish_sims < 2 or params.polish_ratio < 1 or params.bank_bounces < 0 or params.strike_bounces < 0:
        bad("polish_sims", "polish_sims >= 2, polish_ratio >= 1, bank_bounces >= 0 and strike_bounces >= 0 are required")
    if params.planner_trials < 0 or not 0 <= params.planner_chain <= 4 or params.planner_seeds < 0 \
            or params.planner_polish_sims < 2:
        bad("planner_trials", "planner_trials >= 0, 0 <= planner_chain <= 4, planner_seeds >= 0 and "
                              "planner_polish_sims >= 2 are required")
    if params.robust_signature not in ("and", "plain"):
        bad("robust_signature", f"must be 'and' or 'plain', got {params.robust_signature!r}")
    if params.robust_archive < 0 or params.robust_samples < 0 or params.robust_k < 0 or params.robust_polish < 0 \
            or not params.robust_timestep >= 0:
        bad("robust_archive", "robust_archive >= 0, robust_samples >= 0, robust_k >= 0, robust_polish >= 0 and "
                              "robust_timestep >= 0 are required")
    if not 0 < params.adapt_rate <= 1 or not 0 <= params.adapt_floor < 1.0 / 7 or params.restart < 0:
        bad("adapt_rate", "0 < adapt_rate <= 1, 0 <= adapt_floor < 1/7 and restart >= 0 are required")


@dataclass(frozen=True, eq=False)
class SearchRun:
    """A finished search: the best solution and the final population.

    velocities : (P, N, 2) float, units/s; costs : (P,) float; signatures : (P,) int64 bitmasks
    """

    solution: object
    velocities: np.ndarray
    costs: np.ndarray
    signatures: np.ndarray
    recorded: np.ndarray  # (M, N, 2) candidates of every record_every-th trial (empty unless asked)


def roundoff_cost(problem: Problem) -> float:
    """The cost of a solution whose every disk ends ROUNDOFF_REL x max(W, H) from its
    target: N (ROUNDOFF_REL max(W, H))^2, units^2. Below it a search has nothing left to
    gain (``nbst solve``'s default target cost)."""
    return problem.n * (ROUNDOFF_REL * max(problem.box)) ** 2


def solve(problem: Problem, *, seed: int | None = None, max_trials: int = 1_000_000, patience: int = 100_000,
          target_cost: float | None = None, variant: str = "nbst", params: SearchParams | None = None,
          callback: Callable[[SearchProgress], bool | None] | None = None, chunk: int = 2048,
          robust: bool | None = None):
    """Run the signature search on ``problem``; return the best :class:`~nbst.solution.Solution`.

    seed        : int >= 0; None draws one (recorded in ``meta["seed"]``). Same seed, same
                  parameters -> the same solution, bit for bit (chunking does not matter).
    max_trials  : trial budget (one trial = one simulated candidate, initialize included)
    patience    : stop after this many trials without improvement (0: never)
    target_cost : stop once the best cost is <= this (None: never)
    variant     : "nbst" (nbst's search, the default), "A" (the paper's full algorithm) .. "H"
                  (its simplified variants); ignored when ``params`` is given
    callback    : called with a :class:`SearchProgress` after every chunk; a truthy return
                  stops the search. A KeyboardInterrupt (Ctrl-C, or raised by the callback)
                  stops it too: ``solve`` then returns the best so far with
                  ``meta["stopped"] == "interrupted"``.
    chunk       : trials per compiled call (progress / Ctrl-C granularity only; in robust mode
                  also the archive's cadence, so a robust result is reproducible for one chunk)
    robust      : True: write the most noise-robust top-order solution found rather than the
                  cheapest (``nbst.robust``; sets ``params.robust``); None: as ``params`` says

    ``meta`` holds cost, signature, order, trials, seed, variant, params, wall_time,
    nbst_version, history ([trial, cost, order] per improvement) and run statistics.
    """
    return run_search(problem, seed=seed, max_trials=max_trials, patience=patience, target_cost=target_cost,
                      variant=variant, params=params, callback=callback, chunk=chunk, robust=robust).solution


def run_search(problem: Problem, *, seed: int | None = None, max_trials: int = 1_000_000, patience: int = 100_000,
               target_cost: float | None = None, variant: str = "nbst", params: SearchParams | None = None,
               callback: Callable[[SearchProgress], bool | None] | None = None, chunk: int = 2048,
               record_every: int = 0, robust: bool | None = None) -> SearchRun:
    """:func:`solve`, also returning the final population (for benchmarks and analysis) and, with
    ``record_every`` = k > 0, the candidate velocities of trials k, 2k, ... (the loop's exact mix)."""
    from . import search_loop as L
    from .search_ops import SIZE, new_population, seed_state
    from .solution import make_solution, signature_string

    if params is None:
        params = variant_params(variant, problem)
    if robust is not None:
        params = dataclasses.replace(params, robust=bool(robust))
    max_trials, patience = int(max_trials), int(patience)
    _check(params, max_trials, patience)
    if seed is None:
        seed = int(np.random.default_rng().integers(2**63))
    seed = int(seed)
    if seed < 0:
        raise ProblemError("<search parameters>", "seed", f"must be >= 0, got {seed}")
    pi, pf = _pack(problem, params, max_trials=max_trials, patience=patience, target_cost=target_cost,
                   record_every=int(record_every))
    n = problem.n
    x0 = np.ascontiguousarray(problem.start, dtype=np.float64)
    target = np.ascontiguousarray(problem.target, dtype=np.float64)
    radius = np.ascontiguousarray(problem.radius, dtype=np.float64)
    mass = np.ascontiguousarray(problem.mass, dtype=np.float64)
    cue_idx = np.flatnonzero(problem.cueable).astype(np.int64)
    images = mirror_images(params.max_bounces)
    W, H = (float(x) for x in problem.box)
    cap = params.hard_limit + 2
    st = np.zeros(L.N_ST, np.int64)
    st[L.ST_FIRST_FULL] = -1
    s = _State(pop=new_population(cap, n), st=st, best_cost=np.array([np.inf]), best_v=np.zeros((n, 2)),
               rng=seed_state(seed), hist_t=np.zeros(1024, np.int64), hist_c=np.zeros(1024),
               hist_o=np.zeros(1024, np.int64))
    rec_v = np.zeros((max_trials // record_every if record_every > 0 else 0, n, 2))
    advance = _nbst_stepper(problem, params, s, pi, pf, seed) if params.nbst_loop else None
    archive = None
    if params.robust:
        from .robust import Archive

        archive = Archive(n, params.robust_archive)  # size 0 keeps nothing: the search's best alone
    if advance is not None and record_every > 0:
        raise ValueError("record_every is supported by the paper's loop only (variants A-H)")
    stopped = None
    t0 = time.perf_counter()
    reasons = {L.RC_MAX_TRIALS: "max_trials", L.RC_PATIENCE: "patience", L.RC_TARGET_COST: "target_cost"}
    try:
        while stopped is None:
            if advance is not None:
                rc = advance(int(chunk))
            else:
                rc = L.run_chunk(x0, target, radius, mass, cue_idx, W, H, float(problem.t_final), images, pi, pf,
                                 s.pop, s.st, s.best_cost, s.best_v, s.rng, s.hist_t, s.hist_c, s.hist_o,
                                 s.op_count, rec_v, int(chunk))
            if rc == L.RC_HISTORY_FULL:
                k = len(s.hist_t)
                s.hist_t = np.concatenate([s.hist_t, np.zeros(k, np.int64)])
                s.hist_c = np.concatenate([s.hist_c, np.zeros(k)])
                s.hist_o = np.concatenate([s.hist_o, np.zeros(k, np.int64)])
                continue
            if archive is not None:
                size = int(s.pop[5][SIZE])
                archive.add(s.pop[0][:size], s.pop[1][:size], s.pop[2][:size])
            stopped = reasons.get(rc)
            if callback is not None:
                prog = SearchProgress(trials=int(s.st[L.ST_TRIALS]), best_cost=float(s.best_cost[0]),
                                      best_order=_popcount(int(s.st[L.ST_BEST_SIG])),
                                      elapsed=time.perf_counter() - t0, population=int(s.pop[5][SIZE]),
                                      phase="initialize" if s.st[L.ST_PHASE] == L.PHASE_INIT else "generate")
                if callback(prog) and stopped is None:
                    stopped = "callback"
    except KeyboardInterrupt:
        stopped = "interrupted"
    wall = time.perf_counter() - t0

    st = s.st
    best_v = s.best_v.copy()
    cost = float(s.best_cost[0])
    sig = int(st[L.ST_BEST_SIG])
    from .sim import evaluate

    if not math.isfinite(cost):  # nothing accepted yet: report the motionless start
        best_v = np.zeros((n, 2))
    robust_info = None
    if archive is not None and math.isfinite(cost):
        best_v, robust_info = _robust_choice(problem, params, archive, best_v, cost, sig, seed)
    # cost, signature and order as `nbst simulate` sees them (the problem's R, also for variant E)
    search_sig = sig
    _, c, sg = evaluate(problem, best_v[None], max_events=params.max_events)
    cost, sig = float(c[0]), int(sg[0])
    if robust_info is not None:  # the written velocities are the choice's, not the search's best
        search_sig = sig
    nh = int(st[L.ST_NHIST])
    trials = int(st[L.ST_TRIALS])
    op_names = advance.op_names if advance is not None else L.OP_NAMES
    meta = {
        "algorithm": ALGORITHM_NBST if advance is not None else ALGORITHM,
        "cost": cost,
        "signature": signature_string(sig, n),
        "order": _popcount(sig),
        "trials": trials,
        "init_trials": int(st[L.ST_INIT_TRIALS]),
        "seed": seed,
        "search_signature": signature_string(search_sig, n),
        "variant": params.variant,
        "variant_description": VARIANTS.get(params.variant, ""),
        "params": params.to_dict(),
        "max_trials": max_trials,
        "patience": patience,
        "target_cost": target_cost,
        "stopped": stopped,
        "wall_time": wall,
        "trials_per_s": trials / wall if wall > 0 else None,
        "nbst_version": __version__,
        "first_full_order_trial": int(st[L.ST_FIRST_FULL]) if st[L.ST_FIRST_FULL] >= 0 else None,
        "max_order_seen": int(st[L.ST_MAX_ORDER]),
        "population_size": int(s.pop[5][SIZE]),
        "rejected_order0": int(st[L.ST_REJECTED]),
        "truncated_runs": int(st[L.ST_TRUNCATED]),
        "cull_rounds": int(st[L.ST_CULLS]),
        "fallback_deletions": int(st[L.ST_FALLBACK]),
        "operators": {name: {"children": int(s.op_count[k, 0]), "improvements": int(s.op_count[k, 1])}
                      for k, name in enumerate(op_names)},
        "history": [[int(s.hist_t[k]), float(s.hist_c[k]), int(s.hist_o[k])] for k in range(nh)],
    }
    if advance is not None:
        meta.update(advance.stats())
    if params.robust:
        meta["robust"] = robust_info
    size = int(s.pop[5][SIZE])
    return SearchRun(solution=make_solution(problem, best_v, **meta), velocities=s.pop[0][:size].copy(),
                     costs=s.pop[1][:size].copy(), signatures=s.pop[2][:size].copy(),
                     recorded=rec_v[:trials // record_every] if record_every > 0 else rec_v)


def _robust_choice(problem: Problem, params: SearchParams, archive, best_v, best_cost: float, best_sig: int,
                   seed: int):
    """Robust mode's pick: the search's best first, then the archive; see ``nbst.robust``."""
    from .robust import choose

    V = np.concatenate([best_v[None], archive.V]) if archive.V.shape[0] else best_v[None]
    v, info = choose(problem, V, seed=seed, samples=params.robust_samples, timestep=params.robust_timestep,
                     polish_top=params.robust_polish)
    info["archive_order"] = int(archive.order)
    info["archive_seen"] = int(archive.seen)
    info["search_best"] = {"cost": best_cost, "order": _popcount(best_sig)}
    return v, info


def _nbst_stepper(problem: Problem, params: SearchParams, s: _State, pi, pf, seed: int):
    """A chunk-advancing closure over ``search_nbst.run_chunk_nbst`` and its extra state."""
    from . import search_nbst as S
    from . import search_loop as L

    qi = np.zeros(S.N_QI, np.int64)
    qi[S.QI_POLISH] = int(params.polish)
    qi[S.QI_POLISH_SIMS] = params.polish_sims
    qi[S.QI_BANK_BOUNCES] = params.bank_bounces
    qi[S.QI_ADAPT] = int(params.adapt)
    qi[S.QI_STRAIGHT_START] = int(params.straight_start)
    qi[S.QI_STRIKE_BOUNCES] = params.strike_bounces
    qi[S.QI_RESTART] = params.restart
    qi[S.QI_ROBUST] = (1 if params.robust_signature == "and" else 2) if params.robust and params.robust_k > 0 else 0
    qi[S.QI_SEED_POLISH_SIMS] = params.planner_polish_sims
    qf = np.zeros(S.N_QF)
    qf[S.QF_POLISH_RATIO] = params.polish_ratio
    qf[S.QF_ADAPT_RATE] = params.adapt_rate
    qf[S.QF_ADAPT_FLOOR] = params.adapt_floor
    from .robust import SEARCH_STREAM, SHIFT_STEPS, draws

    qf[S.QF_ROBUST_SHIFT] = SHIFT_STEPS * params.robust_timestep
    zeta, smax = draws(problem, np.random.default_rng([seed, SEARCH_STREAM]), params.robust_k if qi[S.QI_ROBUST] else 0)
    qs = np.zeros(S.N_QS, np.int64)
    non_idx = np.flatnonzero(~problem.cueable).astype(np.int64)
    s.op_count = np.zeros((S.N_OPS, 2), np.int64)
    s.best_cost = np.array([np.inf, np.inf])  # [overall, since the last restart]
    seeds = np.zeros((0, problem.n, 2))
    routes = (np.zeros(0, np.int64), np.zeros((0, 2)), np.zeros(0, np.int64))
    planned = None
    if params.planner and non_idx.size:
        from .planner import plan

        planned = plan(problem, budget=min(params.planner_trials, int(pi[L.PI_MAX_TRIALS]) // 4),
                       max_chain=params.planner_chain, seeds=params.planner_seeds, sig_limit=params.sig_limit,
                       max_events=params.max_events, target_cost=float(pf[L.PF_TARGET_COST]))
        seeds = np.ascontiguousarray(planned.velocities)
        routes = (planned.route_cue, planned.route_v, planned.route_mask)
        s.st[L.ST_TRIALS] += planned.trials  # every planner simulation is a trial
        s.st[L.ST_SINCE] += planned.trials
        qs[S.QS_SIMS] += planned.trials
    w_plan = params.planner_weight if len(routes[0]) else 0.0
    base = np.array([*params.op_weights, params.bank_weight, params.strike_weight if non_idx.size else 0.0, w_plan])
    base = base / base.sum()
    weights, reward = base.copy(), base.copy()
    args = (np.ascontiguousarray(problem.start, dtype=np.float64), np.ascontiguousarray(problem.target, dtype=np.float64),
            np.ascontiguousarray(problem.radius, dtype=np.float64), np.ascontiguousarray(problem.mass, dtype=np.float64),
            np.flatnonzero(problem.cueable).astype(np.int64), non_idx, float(problem.box[0]), float(problem.box[1]),
            float(problem.t_final), mirror_images(params.max_bounces), pi, pf, qi, qf)

    def advance(n_steps: int) -> int:
        return S.run_chunk_nbst(*args, s.pop, s.st, qs, s.best_cost, s.best_v, s.rng, s.hist_t, s.hist_c, s.hist_o,
                                s.op_count, weights, base, reward, zeta, smax, seeds, *routes, n_steps)

    def stats() -> dict:
        return {"polish": {"runs": int(qs[S.QS_POLISH_RUNS]), "simulations": int(qs[S.QS_POLISH_SIMS]),
                           "improved": int(qs[S.QS_POLISH_GAINS])},
                "restarts": int(qs[S.QS_RESTARTS]),
                "simulations": int(qs[S.QS_SIMS]),
                **({"planner": {"trials": planned.trials, "seeds": int(len(planned.costs)),
                                "best_cost": float(planned.costs[0]) if len(planned.costs) else None,
                                **planned.stats}} if planned is not None else {}),
                **({"robust_simulations": int(qs[S.QS_ROBUST_SIMS])} if qi[S.QI_ROBUST] else {}),
                "operator_probabilities": {name: float(w) for name, w in zip(S.OP_NAMES, weights)}}

    advance.op_names = S.OP_NAMES
    advance.stats = stats
    return advance


def _popcount(x: int) -> int:
    return bin(x).count("1")
