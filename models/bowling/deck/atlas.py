"""The atlas: one delivery per subset of pins down, for as many of the 1,023 subsets as a budget finds.

Three ways to spend a delivery budget (``method``), all on one archive keyed by subset
(:class:`SubsetArchive`, the rollout room's :mod:`nbst.models.mjsearch.archive`: the first delivery
that gave each subset is its **elite**):

* ``"uniform"``: deliveries uniform over :data:`.delivery.BOUNDS` (random search).
* ``"elites"`` (MAP-Elites style, the default): after :data:`nbst.models.mjsearch.archive.EXPLORE_EMPTY` uniform deliveries
  when the archive is empty, each batch of :data:`search.BATCH` deliveries holds
  :data:`UNIFORM_PER_BATCH` uniform deliveries and children of archived elites: a parent
  is drawn with weight :func:`parent_weights` (subsets of sizes with low coverage, seen
  rarely, and whose children found new subsets before), and its delivery moved by a
  Gaussian step in the unit cube of delivery space at one of :data:`SCALES`, drawn per
  child (outcomes are chaotic: 1 mm sideways changes the pins down 35 % of the time,
  0.1 mm 20 %, so a parent's neighbourhood holds other, often rare, subsets).
* ``"targeted"``: the earlier atlas: a shared uniform exploration (a quarter of the
  budget, skipped when resuming), then :func:`search.solve` (``per_subset`` deliveries
  each, restarting from the archive) for the missing subsets nearest the archive first.

Reproducible from the seed for any number of threads: batches have a fixed size, every
random number comes from one ``np.random.Generator`` in a fixed order, and deliveries are
independent. Resuming: the archive starts from the throws already written (sorted by
mask), so the same folder and seed give the same run.
"""
from __future__ import annotations

import numpy as np

from nbst.errors import InputError

from nbst.models.bowling import deck, subsets
from nbst.models.bowling.deck import search
from nbst.models.bowling.subsets import N_SUBSETS, SubsetArchive, parent_weights, size_table  # noqa: F401 (the atlas's names)
from nbst.models.mjsearch import archive as _archive

__all__ = ["PER_SUBSET", "DEFAULT_BUDGET", "UNIFORM_PER_BATCH", "SCALES", "emit", "run", "N_SUBSETS", "SubsetArchive",
           "parent_weights", "size_table"]

#: The rollout budget of each targeted solve (``method="targeted"``; ``nbst bowl atlas --per-subset``'s default).
PER_SUBSET = 200
#: The search budget of ``nbst bowl atlas`` when none is given (rollouts; robustness probes not counted).
DEFAULT_BUDGET = 20_000
#: Uniform deliveries in each batch of 16 of the emitter (keeps finding what no elite is near).
UNIFORM_PER_BATCH = _archive.UNIFORM_PER_BATCH
#: Gaussian steps of a child, in the unit cube (per coordinate): ~0.4 mm, 4 mm, 42 mm
#: sideways (the unit is 0.84 m of lateral range, 5 m/s of speed, 6 deg, 60 rad/s).
SCALES = search.SCALES


def emit(a: SubsetArchive, rng: np.random.Generator, n: int = search.BATCH, *,
         selection: str = "biased") -> tuple[np.ndarray, np.ndarray]:
    """One batch of the MAP-Elites emitter (:func:`.subsets.emit`) in the 5 m delivery space:
    ((n, 4) deliveries, (n,) parent masks, -1 = uniform)."""
    return subsets.emit(a, rng, search.SPACE, n, selection=selection)


def run(runner: deck.DeliveryRunner, archive: SubsetArchive, *, method: str, budget: int, seed: int,
        per_subset: int = PER_SUBSET, on_new=None, callback=None) -> SubsetArchive:
    """Spend ``budget`` deliveries growing ``archive`` with ``method`` ("elites", "uniform",
    "targeted", or "elites-plain": the emitter with uniform parent selection); ``on_new(masks)``
    after each batch that found new subsets (to save them), ``callback(archive)`` after each
    batch. KeyboardInterrupt propagates (what ran is kept).

    Args:
        runner: the :class:`.delivery.DeliveryRunner` (or the cluster's) that throws the deliveries.
        archive: the :class:`SubsetArchive` to grow (resumed as it is).
        method: "elites", "elites-plain", "uniform" or "targeted".
        budget: deliveries to spend on top of ``archive.rollouts``.
        seed: the seed of every random number.
        per_subset: rollouts of each targeted solve.
        on_new: called with the new masks after a batch that found any.
        callback: called with the archive after each batch.

    Returns:
        ``archive``, grown.

    Raises:
        InputError: an unknown ``method``.
    """
    rng = np.random.default_rng(seed)
    end = archive.rollouts + int(budget)

    def run_batch(X, parents=None):
        X = X[: end - archive.rollouts]
        masks, _ = runner.throw(X)
        new = archive.add(X, masks, parents)
        if new and on_new:
            on_new(new)
        if callback:
            callback(archive)

    if method == "uniform":
        while archive.rollouts < end:
            run_batch(search.from_unit(rng.random((search.BATCH, 4))))
    elif method in ("elites", "elites-plain"):
        def on_batch(a, new):
            if new and on_new:
                on_new(new)
            if callback:
                callback(a)

        _archive.grow(lambda X: runner.throw(X)[0], archive, rng, search.SPACE, budget=budget, explore=_archive.EXPLORE_EMPTY,
                      batch=search.BATCH, selection="biased" if method == "elites" else "uniform",
                      weights=parent_weights, on_batch=on_batch)
    elif method == "targeted":
        n0 = int(budget) // 4 if not archive.elite else 0
        start = archive.rollouts
        while archive.rollouts < start + n0:
            run_batch(search.from_unit(rng.random((min(search.BATCH, start + n0 - archive.rollouts), 4))))
        tried: set[int] = set()
        while archive.rollouts < end:
            todo = [t for t in range(1, N_SUBSETS + 1) if t not in archive.elite and t not in tried]
            if not todo:
                break
            known = np.array(sorted(archive.elite), dtype=np.int64)
            near = {t: int(subsets.hamming(t, known).min()) if len(known) else 10 for t in todo}
            target = min(todo, key=lambda t: (near[t], t))
            tried.add(target)
            left = min(per_subset, end - archive.rollouts)
            seen_before = set(archive.elite)
            res = search.solve(target, seed=int(rng.integers(0, 2**31 - 1)), max_rollouts=left,
                               runner=runner, explore=0, archive=dict(archive.elite))
            # solve keeps the first delivery of each subset it saw: the new ones join the archive
            new = [m for m in res.archive if m and m not in seen_before]
            for m in sorted(new, key=lambda m: list(res.archive).index(m)):
                archive.elite[m] = np.asarray(res.archive[m], dtype=float)
                archive.seen[m] = 1
                archive.found_at[m] = archive.rollouts + res.rollouts
            archive.rollouts += res.rollouts
            archive.curve.append((archive.rollouts, len(archive.elite)))
            if new and on_new:
                on_new(new)
            if callback:
                callback(archive)
    else:
        raise InputError(f"method must be elites, uniform or targeted, got {method!r}")
    return archive
