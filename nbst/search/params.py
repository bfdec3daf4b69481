"""The signature search's parameters: :class:`SearchParams` (every knob, the paper's
defaults), the variants A-H and nbst's, their checks, and what a progress callback sees.
The choices behind each default are listed in ``nbst.search``'s docstring and docs/search.md.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from enum import Enum
from typing import Callable

import numpy as np

from nbst.constants import MAX_EVENTS
from nbst.errors import SolveError
from nbst.problem import Problem, ProblemError
from nbst.search.loop import OP_NAMES as OP_NAMES_PAPER
from nbst.search.nbst_loop import OP_NAMES as OP_NAMES_NBST
from nbst.sim.primitives import images
from nbst.search.variants import DEFAULT_VARIANT, NBST_DEFAULTS, VARIANTS
from nbst.search.robust import ARCHIVE_SIZE as ROBUST_ARCHIVE, POLISH_TOP as ROBUST_POLISH, SAMPLES as ROBUST_SAMPLES, \
    SEARCH_SAMPLES as ROBUST_K, TIMESTEP as ROBUST_TIMESTEP

__all__ = ["ALGORITHM", "ALGORITHM_NBST", "SearchParams", "StopReason", "variant_params", "mirror_images",
           "SearchProgress", "ProgressCallback", "check_run"]

ALGORITHM = "paper-signature-search"
ALGORITHM_NBST = "nbst-signature-search"


@dataclass(frozen=True, kw_only=True)
class SearchParams:
    """Every knob of the signature search. Defaults are the paper's (A).

    The fields from ``polish`` to ``planner_weight`` are nbst's additions
    (``nbst.search.nbst_loop``; all off in A-H, on in variant "nbst"); those from ``robust`` on,
    robust mode's.

    Robust mode (``nbst.search.robust``; off in every variant, ``nbst solve --robust``): candidates are
    scored by their worst cost under small shifts of the start positions (signature: the disks
    acceptable under all of them), and the solution is the most robust of an archive of
    top-order members, rescored under fresh shifts.

    Args:
        variant: the variant these parameters are (``variant_params``), recorded in the result.
        pop_limit: population limit (paper: 200)
        sig_limit: members per signature (paper: 10)
        diversity: initialize until every disk is acceptable in this many members (paper: 5)
        init_max_tries: cap on initialize's trials if the diversity target is never met (open)
        init_population: > 0: initialize until the population has this many members instead (E: 60)
        signature_radius: R used for signatures, None = the problem's (E: the box width)
        max_bounces: uniform randomize reaches images with |kx| + |ky| <= this (paper: 5)
        creep_fraction: creep std per axis = creep_fraction * R / t_final, units/s (open)
        op_weights: (creep, directed, uniform, crossover) probabilities (paper: 1/4 each)
        p_directed_init: initialize's chance of directed (vs uniform) randomize per disk (paper: 1/2)
        senate: Senate-like parent selection (B: off, uniform over members)
        engineered: genetically engineered crossover (D: off)
        cull: "subsumed" (paper) or "worst" (F)
        elitism: the best member is never deleted (G: off)
        hard_limit: culling fallback: above this size the worst member goes (open)
        max_events: per-simulation event cap (a truncated run scores cost inf)
        polish: Levenberg-Marquardt polish of promising children
        polish_sims: simulation budget of one polish
        polish_ratio: polish children of the best order within this factor of the best cost
        bank_weight: generate probability weight of the bank-shot operator
        bank_bounces: bank shots use images with at most this many bounces
        strike_weight: weight of the strike operator (used only if some disk is noncueable)
        strike_bounces: strikes aim at images of the target with at most this many bounces
        adapt: adapt operator probabilities from their recent success
        adapt_rate: rate of the success moving average
        adapt_floor: least probability of an enabled operator
        straight_start: initialize's first trial sends every cueable disk straight at its target
        restart: re-initialize around the best after this many trials without a
            local improvement (0: never)
        planner: run the backward planner (``nbst.search.planner``) first when some disk is
            noncueable; its best candidates are initialize's first trials
        planner_trials: the planner's simulations, at most (and at most a quarter of max_trials);
            every one counts as a trial
        planner_chain: longest strike chain the planner builds (cue -> noncueable -> ...)
        planner_seeds: planner candidates handed to the search
        planner_polish_sims: polish budget of a planner candidate (instead of polish_sims)
        planner_weight: weight of the plan operator (the planner's routes; only after a planner run)
        robust: score every candidate under robust_k start shifts and choose the solution
            by its robust score instead of its cost
        robust_k: start shifts per candidate during the search (0: the search is plain and
            only the final choice is robust)
        robust_signature: "and": a disk counts as acceptable only if it is in every shifted run;
            "plain": the unshifted signature (only the cost is the worst-case one)
        robust_archive: top-order population members kept for the final choice (0: the choice
            is among the search's best alone)
        robust_samples: start shifts per candidate in the final choice (fresh draws)
        robust_timestep: the engine step h (s) to survive: start shifts of std 0.5 h x the
            fastest speed per axis (``nbst.search.robust.SHIFT_STEPS``)
        robust_polish: candidates polished towards their on-target disks' target centres (and
            rescored; ``nbst.search.robust.polish_on_target``)

    Returns:
        The parameters (frozen, each field checked: a bad one raises a SolveError naming it).
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

    def __post_init__(self) -> None:
        """Check every field on its own; a bad one raises SolveError naming it."""
        for name, ok, want in _FIELD_RULES:
            value = getattr(self, name)
            try:
                good = bool(ok(self, value))
            except (TypeError, ValueError):
                good = False
            if not good:
                raise SolveError(f"SearchParams.{name}: must be {want}, got {value!r}")

    @property
    def nbst_loop(self) -> bool:
        """Whether any of nbst's additions is on (they run in ``nbst.search.nbst_loop``'s loop)."""
        return (self.polish or self.bank_weight > 0 or self.strike_weight > 0 or self.adapt or self.planner
                or self.straight_start or self.restart > 0 or (self.robust and self.robust_k > 0))

    def to_dict(self) -> dict:
        d = dataclasses.asdict(self)
        d["op_weights"] = list(self.op_weights)
        return d


def _nonneg_int(_, v) -> bool:
    return isinstance(v, (int, np.integer)) and not isinstance(v, bool) and bool(v >= 0)


def _int_at_least(k: int):
    return lambda _, v: _nonneg_int(_, v) and v >= k


def _nonneg(_, v) -> bool:
    return isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool) and math.isfinite(v) \
        and bool(v >= 0)


def _op_weights_ok(_, w) -> bool:
    a = np.asarray(w, float)
    return a.shape == (len(OP_NAMES_PAPER),) and bool(np.all(np.isfinite(a))) and bool(np.all(a >= 0)) and a.sum() > 0


#: (field, test, what it must be): ``SearchParams.__post_init__`` checks each field on its own.
_FIELD_RULES = (
    ("variant", lambda _, v: isinstance(v, str), "a string"),
    ("pop_limit", _int_at_least(2), "an integer >= 2"),
    ("sig_limit", _int_at_least(1), "an integer >= 1"),
    ("diversity", _int_at_least(1), "an integer >= 1"),
    ("init_max_tries", _int_at_least(1), "an integer >= 1"),
    ("init_population", _nonneg_int, "an integer >= 0"),
    ("signature_radius", lambda _, v: v is None or (_nonneg(_, v) and v > 0), "None or a finite number > 0"),
    ("max_bounces", _nonneg_int, "an integer >= 0"),
    ("creep_fraction", _nonneg, "a finite number >= 0"),
    ("op_weights", _op_weights_ok, f"{len(OP_NAMES_PAPER)} finite weights >= 0 ({', '.join(OP_NAMES_PAPER)}), "
                                   f"not all 0"),
    ("p_directed_init", lambda _, v: _nonneg(_, v) and v <= 1, "a probability in [0, 1]"),
    ("senate", lambda _, v: isinstance(v, bool), "True or False"),
    ("engineered", lambda _, v: isinstance(v, bool), "True or False"),
    ("cull", lambda _, v: v in ("subsumed", "worst"), "'subsumed' or 'worst'"),
    ("elitism", lambda _, v: isinstance(v, bool), "True or False"),
    ("hard_limit", lambda p, v: _nonneg_int(p, v) and v >= p.pop_limit, "an integer >= pop_limit"),
    ("max_events", _int_at_least(1), "an integer >= 1"),
    ("polish", lambda _, v: isinstance(v, bool), "True or False"),
    ("polish_sims", _int_at_least(2), "an integer >= 2"),
    ("polish_ratio", lambda _, v: _nonneg(_, v) and v >= 1, "a finite number >= 1"),
    ("bank_weight", _nonneg, "a finite number >= 0"),
    ("bank_bounces", _nonneg_int, "an integer >= 0"),
    ("strike_weight", _nonneg, "a finite number >= 0"),
    ("strike_bounces", _nonneg_int, "an integer >= 0"),
    ("adapt", lambda _, v: isinstance(v, bool), "True or False"),
    ("adapt_rate", lambda _, v: _nonneg(_, v) and 0 < v <= 1, "a number in (0, 1]"),
    ("adapt_floor", lambda _, v: _nonneg(_, v) and v < 1.0 / len(OP_NAMES_NBST),
     f"a number in [0, 1/{len(OP_NAMES_NBST)}) (one floor per operator must leave room)"),
    ("straight_start", lambda _, v: isinstance(v, bool), "True or False"),
    ("restart", _nonneg_int, "an integer >= 0 (0: never)"),
    ("planner", lambda _, v: isinstance(v, bool), "True or False"),
    ("planner_trials", _nonneg_int, "an integer >= 0"),
    ("planner_chain", lambda _, v: _nonneg_int(_, v) and v <= 4, "an integer in [0, 4]"),
    ("planner_seeds", _nonneg_int, "an integer >= 0"),
    ("planner_polish_sims", _int_at_least(2), "an integer >= 2"),
    ("planner_weight", _nonneg, "a finite number >= 0"),
    ("robust", lambda _, v: isinstance(v, bool), "True or False"),
    ("robust_k", _nonneg_int, "an integer >= 0"),
    ("robust_signature", lambda _, v: v in ("and", "plain"), "'and' or 'plain'"),
    ("robust_archive", _nonneg_int, "an integer >= 0"),
    ("robust_samples", _nonneg_int, "an integer >= 0"),
    ("robust_timestep", _nonneg, "a finite number >= 0"),
    ("robust_polish", _nonneg_int, "an integer >= 0"),
)


class StopReason(str, Enum):
    """Why a search stopped: ``meta["stopped"]`` holds the value (the file format's strings)."""

    MAX_TRIALS = "max_trials"
    PATIENCE = "patience"
    TARGET_COST = "target_cost"
    CALLBACK = "callback"
    INTERRUPTED = "interrupted"


def variant_params(variant: str = DEFAULT_VARIANT, problem: Problem | None = None) -> SearchParams:
    """The parameters of a registered variant (``nbst.search.variants.VARIANTS``): nbst's search
    ("nbst"), the paper's variant A (full algorithm) or B-H (one simplification each).

    Args:
        variant: a name of ``VARIANTS`` (any case).
        problem: the problem; variant E needs it (its signature radius is the box width).

    Returns:
        The variant's :class:`SearchParams`.

    Raises:
        InputError: an unknown name (the message lists the variants).
        SolveError: variant E without a problem.
    """
    name = VARIANTS.parse(variant, source="<search parameters>", field="variant")
    v = VARIANTS[name]
    changes = v.changes_for(problem) if v.changes_for is not None else v.changes
    return SearchParams(variant=name, **changes)


def mirror_images(max_bounces: int) -> np.ndarray:
    """The mirror images a uniform randomize or a bank shot may aim at.

    Args:
        max_bounces: the most wall bounces, |kx| + |ky|.

    Returns:
        (M, 2) int64 array of image indices (kx, ky) with |kx| + |ky| <= max_bounces (M = 61 for 5).
    """
    return images(0, int(max_bounces))


@dataclass(frozen=True)
class SearchProgress:
    """What a callback sees after each chunk of trials.

    Args:
        trials: trials spent so far (the islands: their sum).
        best_cost: the best cost so far, units^2 (inf before the first trial).
        best_order: how many disks the best candidate brings within R.
        elapsed: seconds since the search started.
        population: members in the population.
        phase: "initialize", "generate", or the stage of another solver ("start", "sample", ...).
        stall: None, or what a solver reports of its stall (the many-body search: idle rounds, limit).

    Returns:
        The progress record (frozen); a callback returning a truthy value stops the search.
    """

    trials: int
    best_cost: float
    best_order: int
    elapsed: float
    population: int
    phase: str
    #: The many-body search: (rounds since the whole motion last got better, the rounds after
    #: which it stops); None for the other searches. Its stop is set by this, not by the trial
    #: budget, so a progress bar shows this instead of an ETA over ``max_trials``.
    stall: tuple | None = None


#: What a search calls after every chunk of trials; a truthy return stops the search.
ProgressCallback = Callable[[SearchProgress], "bool | None"]


def check_run(max_trials: int, patience: int, seed: int | None = None) -> None:
    """The run options of a search (the parameters check themselves: ``SearchParams.__post_init__``);
    a bad one raises a one-line ProblemError naming it, as the command line reports it."""
    def bad(name, why):
        raise ProblemError("<search parameters>", name, why)

    if max_trials < 1:
        bad("max_trials", f"must be >= 1, got {max_trials}")
    if patience < 0:
        bad("patience", f"must be >= 0 (0 = no patience limit), got {patience}")
    if seed is not None and seed < 0:
        bad("seed", f"must be >= 0, got {seed}")
