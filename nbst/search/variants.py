"""The signature search's variants, registered once (nbst's search, the paper's A and its B-H), and
its run defaults.

Every place that offers a variant reads this list: ``nbst solve --variant`` and its help, the
experiments' entries (``nbst experiment ... --algorithms``), ``variant_params`` and the docs.
A variant is a description (written to a solution's ``variant_description``) and the
:class:`~nbst.search.params.SearchParams` fields it changes from the paper's defaults (A).

This module is light (no numba): the command line reads it to build its options.
"""
from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from nbst.constants import ROUNDOFF_REL
from nbst.errors import SolveError
from nbst.registry import Registry

if TYPE_CHECKING:
    from nbst.problem import Problem

__all__ = ["DEFAULT_MAX_TRIALS", "DEFAULT_PATIENCE", "DEFAULT_VARIANT", "NBST_DEFAULTS", "VARIANTS", "SolveRequest",
           "Variant", "roundoff_cost"]

#: The variant ``nbst.search.solve`` and ``nbst solve`` run unless told otherwise.
DEFAULT_VARIANT = "nbst"
#: The trial budget of ``nbst.search.solve`` and ``nbst solve`` unless told otherwise.
DEFAULT_MAX_TRIALS = 1_000_000
#: Trials without improvement after which ``nbst.search.solve`` and ``nbst solve`` stop, unless
#: told otherwise: the paper's searches settle well within it on the benchmark problems.
DEFAULT_PATIENCE = 100_000

#: Variant "nbst": the paper's A plus every addition of ``nbst.search.nbst_loop`` (see docs/search.md
#: and the ablation in docs/results/disks.md for what each contributes).
NBST_DEFAULTS: Mapping[str, Any] = dict(op_weights=(0.2, 0.1, 0.1, 0.2), bank_weight=0.3, strike_weight=0.1,
                                        polish=True, straight_start=True, planner=True)
# The adaptive operator schedule (adapt=True) and restarts (restart=20_000) are built and
# measured but off: the ablation (docs/results/disks.md) showed no gain from either.

_THIRD = 1.0 / 3.0


@dataclass(frozen=True)
class SolveRequest:
    """What one search is asked to do: the settings every hop passes on as one object
    (``nbst.search.solve`` builds it from its keywords; the islands, the solvers' registry and the
    experiments hand it down unchanged).

    Args:
        seed: int >= 0; None: the solver draws one (and records it)
        max_trials: trial budget (one trial = one simulated candidate)
        patience: stop after this many trials without improvement (0: never); None: the
            solver's default (``DEFAULT_PATIENCE`` for the signature search, none for a
            baseline)
        target_cost: stop once the best cost is <= this (None: never; the many-body search:
            round-off level)
        variant: the signature search's variant (``VARIANTS``); None: its default
            (``DEFAULT_VARIANT``). Solvers that take no variant refuse any other.
        robust: the signature search's robust mode (``nbst solve --robust``); None: as its
            ``SearchParams`` say
        jobs: threads of a search that runs in one process (the many-body search); None:
            every core

    Returns:
        The request (frozen); ``dataclasses.replace`` derives another.
    """

    seed: int | None = None
    max_trials: int = DEFAULT_MAX_TRIALS
    patience: int | None = None
    target_cost: float | None = None
    variant: str | None = None
    robust: bool | None = False
    jobs: int | None = None

    @property
    def patience_or_default(self) -> int:
        """``patience``, or the signature search's ``DEFAULT_PATIENCE`` where it is None."""
        return DEFAULT_PATIENCE if self.patience is None else int(self.patience)

    @property
    def variant_or_default(self) -> str:
        """``variant``, or ``DEFAULT_VARIANT`` where it is None (or empty)."""
        return self.variant or DEFAULT_VARIANT


def roundoff_cost(problem: Problem) -> float:
    """The cost of a solution whose every disk ends ROUNDOFF_REL x max(W, H) from its
    target: N (ROUNDOFF_REL max(W, H))^2, units^2. Below it a search has nothing left to
    gain (``nbst solve``'s default target cost).

    Args:
        problem: the problem.

    Returns:
        float: the cost, units^2.
    """
    return problem.n * (ROUNDOFF_REL * max(problem.box)) ** 2


@dataclass(frozen=True)
class Variant:
    """One variant: what it is, and the ``SearchParams`` fields it sets (``changes``, or
    ``changes_for(problem)`` where they depend on the problem).

    Args:
        description: one line, as ``nbst solve --help`` shows it.
        changes: ``SearchParams`` field -> value, over the paper's defaults (A).
        changes_for: ``changes_for(problem) -> changes`` where they depend on the problem
            (variant E), else None.

    Returns:
        The variant, to register in ``VARIANTS``.
    """

    description: str
    changes: Mapping[str, Any] = field(default_factory=dict)
    changes_for: Callable[[Problem | None], Mapping[str, Any]] | None = None


def _box_width(problem: Problem | None) -> Mapping[str, Any]:
    if problem is None:
        raise SolveError("variant E needs the problem (R = box width)")
    return {"signature_radius": float(problem.width), "init_population": 60, "sig_limit": 60}


VARIANTS: Registry[Variant] = Registry("variant")
for _name, _variant in (
    ("A", Variant("the full algorithm")),
    ("B", Variant("uniform probability for parent selection", {"senate": False})),
    ("C", Variant("no crossover operation", {"op_weights": (_THIRD, _THIRD, _THIRD, 0.0)})),
    ("D", Variant("no genetically engineered crossover", {"engineered": False})),
    ("E", Variant("no signature information (R = box width, initial population 60)", changes_for=_box_width)),
    ("F", Variant("no culling of subsumed solutions (delete the worst on every insertion)", {"cull": "worst"})),
    ("G", Variant("no elitism", {"elitism": False})),
    ("H", Variant("no directed randomization", {"op_weights": (_THIRD, 0.0, _THIRD, _THIRD), "p_directed_init": 0.0})),
    ("nbst", Variant("nbst's default: the paper's search plus polish, bank shots, strikes, a straight start and the "
                     "backward planner", NBST_DEFAULTS)),
    ("nbst-noplan", Variant("nbst without the backward planner (ablation)", {**NBST_DEFAULTS, "planner": False})),
):
    VARIANTS.register(_name, _variant, help=_variant.description)
