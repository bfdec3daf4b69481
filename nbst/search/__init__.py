"""The signature search: the paper's (Ngo & Marks style), its variants B-H, and ``solve``.

    from nbst import load_problem
    from nbst.search import solve
    result = solve(load_problem("diamond-s14"), seed=1, max_trials=200_000)
    result.velocities, result.cost, result.order, result.to_solution()

Layout: the one way in (``nbst.search.api``: :func:`solve`, :func:`run_search`), the variants
(``nbst.search.variants``, registered once), the parameters (``nbst.search.params``), the
Python driver (``nbst.search.driver``), the many-body search past 63 disks
(``nbst.search.many``), nbst's loop and its refinements, the compiled initialize /
generate-insert loop (``nbst.search.loop``) and its operators (``nbst.search.ops``, small
numba kernels, tested one by one on hand-built populations).

Importing this package is light: its names load their modules (and numba) on first use, so
the command line can read the variants without compiling anything.

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
  ``result.meta["fallback_deletions"]``).
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

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from nbst.search.api import run_many_search, run_request, run_search, solve, straight_start
    from nbst.search.driver import SearchRun
    from nbst.search.params import (ALGORITHM, ALGORITHM_NBST, ProgressCallback, SearchParams, SearchProgress,
                                    StopReason, mirror_images, variant_params)
    from nbst.search.variants import (DEFAULT_MAX_TRIALS, DEFAULT_PATIENCE, DEFAULT_VARIANT, NBST_DEFAULTS, VARIANTS,
                                      SolveRequest, Variant, roundoff_cost)

#: Each public name and the module it is defined in (loaded on first use).
_HOMES = {
    "solve": "api", "run_search": "api", "run_request": "api", "run_many_search": "api", "straight_start": "api",
    "SearchRun": "driver", "roundoff_cost": "variants",
    "ALGORITHM": "params", "ALGORITHM_NBST": "params", "ProgressCallback": "params", "SearchParams": "params",
    "SearchProgress": "params", "StopReason": "params", "mirror_images": "params", "variant_params": "params",
    "DEFAULT_MAX_TRIALS": "variants", "DEFAULT_PATIENCE": "variants", "DEFAULT_VARIANT": "variants", "NBST_DEFAULTS": "variants", "VARIANTS": "variants", "Variant": "variants",
    "SolveRequest": "variants",
}

__all__ = sorted(_HOMES)


def __getattr__(name: str) -> Any:
    home = _HOMES.get(name)
    if home is None:
        raise AttributeError(f"module 'nbst.search' has no attribute {name!r}")
    value = getattr(importlib.import_module(f"nbst.search.{home}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_HOMES))
