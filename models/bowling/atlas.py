"""The atlas: one launch per subset of pins down, for as many of the 1,023 subsets as a budget finds.

Three ways to spend a launch budget (``method``), all on one archive keyed by subset
(:class:`Archive`: the first launch that gave each subset is its **elite**):

* ``"uniform"``: launches uniform over :data:`shot.BOUNDS` (random search).
* ``"elites"`` (MAP-Elites style, the default): after :data:`EXPLORE` uniform launches
  when the archive is empty, each batch of :data:`search.BATCH` launches holds
  :data:`UNIFORM_PER_BATCH` uniform launches and children of archived elites: a parent
  is drawn with weight :func:`parent_weights` (subsets of sizes with low coverage, seen
  rarely, and whose children found new subsets before), and its launch moved by a
  Gaussian step in the unit cube of launch space at one of :data:`SCALES`, drawn per
  child (outcomes are chaotic: 1 mm sideways changes the pins down 35 % of the time,
  0.1 mm 20 %, so a parent's neighbourhood holds other, often rare, subsets).
* ``"targeted"``: the earlier atlas: a shared uniform exploration (a quarter of the
  budget, skipped when resuming), then :func:`search.solve` (``per_subset`` launches
  each, restarting from the archive) for the missing subsets nearest the archive first.

Reproducible from the seed for any number of threads: batches have a fixed size, every
random number comes from one ``np.random.Generator`` in a fixed order, and launches are
independent. Resuming: the archive starts from the shots already written (sorted by
mask), so the same folder and seed give the same run.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from nbst.models.bowling import geometry, search, shot

#: Uniform launches that start an empty archive before the emitter takes over.
EXPLORE = 256
#: Uniform launches in each batch of 16 of the emitter (keeps finding what no elite is near).
UNIFORM_PER_BATCH = 2
#: Gaussian steps of a child, in the unit cube (per coordinate): ~0.4 mm, 4 mm, 42 mm
#: sideways (the unit is 0.84 m of lateral range, 5 m/s of speed, 6 deg, 60 rad/s).
SCALES = (0.0005, 0.005, 0.05)
#: Parent weight floor of a size whose subsets are all found (children land on other sizes).
SIZE_FLOOR = 0.05
#: Parent weight bonus per new subset its children found.
HIT_BONUS = 3.0

N_SUBSETS = geometry.N_SUBSETS
SIZE_TOTAL = np.array([math.comb(10, k) for k in range(11)])


#: Pins down in a mask (one definition: the geometry's).
size_of = geometry.size_of


@dataclass
class Archive:
    """Subsets found so far: mask -> elite launch ((4,) array), how often seen, when found,
    and for the emitter how many children each parent had and how many found a new subset."""

    elite: dict = field(default_factory=dict)     # mask -> (4,) launch (the first that gave it)
    seen: dict = field(default_factory=dict)      # mask -> launches that gave it
    found_at: dict = field(default_factory=dict)  # mask -> rollouts spent when found (-1: given)
    children: dict = field(default_factory=dict)  # mask -> children launched from its elite
    hits: dict = field(default_factory=dict)      # mask -> children that found a new subset
    rollouts: int = 0
    uniform: list = field(default_factory=lambda: [0, 0])   # [launches, new subsets] of parentless launches
    curve: list = field(default_factory=list)     # (rollouts, subsets) after each batch

    @classmethod
    def from_launches(cls, launches: dict) -> Archive:
        a = cls()
        for m in sorted(launches):
            if m:
                a.elite[int(m)] = np.asarray(launches[m], dtype=float)
                a.seen[int(m)] = 1
                a.found_at[int(m)] = -1
        return a

    def __len__(self) -> int:
        return len(self.elite)

    def add(self, launches, masks, parents=None) -> list[int]:
        """Record a batch: (B, 4) launches, (B,) masks, (B,) parent masks (-1: none).
        Returns the new non-empty masks, in launch order."""
        new = []
        for i, (x, m) in enumerate(zip(launches, masks)):
            m = int(m)
            p = -1 if parents is None else int(parents[i])
            if p >= 0:
                self.children[p] = self.children.get(p, 0) + 1
            else:
                self.uniform[0] += 1
            if m == 0:
                continue
            self.seen[m] = self.seen.get(m, 0) + 1
            if m not in self.elite:
                self.elite[m] = np.array(x, dtype=float)
                self.found_at[m] = self.rollouts + i + 1
                new.append(m)
                if p >= 0:
                    self.hits[p] = self.hits.get(p, 0) + 1
                else:
                    self.uniform[1] += 1
        self.rollouts += len(masks)
        self.curve.append((self.rollouts, len(self.elite)))
        return new


def parent_weights(a: Archive, masks: list[int]) -> np.ndarray:
    """(P,) selection weights of the archived ``masks`` (sum 1).

    w = size gap x rarity x curiosity: size gap = share of the subsets of that size not
    found yet (at least :data:`SIZE_FLOOR`); rarity = 1 / sqrt(times seen); curiosity =
    (1 + HIT_BONUS x new subsets its children found) / sqrt(1 + children).
    """
    found = np.bincount([size_of(m) for m in a.elite], minlength=11)
    gap = np.maximum(1.0 - found / SIZE_TOTAL, SIZE_FLOOR)
    w = np.array([gap[size_of(m)] / math.sqrt(a.seen.get(m, 1))
                  * (1.0 + HIT_BONUS * a.hits.get(m, 0)) / math.sqrt(1.0 + a.children.get(m, 0))
                  for m in masks])
    return w / w.sum()


def emit(a: Archive, rng: np.random.Generator, n: int = search.BATCH, *,
         selection: str = "biased", space=None) -> tuple[np.ndarray, np.ndarray]:
    """One batch of the MAP-Elites emitter: ((n, D) launches, (n,) parent masks, -1 = uniform).
    The first :data:`UNIFORM_PER_BATCH` are uniform; each other is a parent's elite plus a
    Gaussian step at a scale drawn from the space's scales. Random numbers drawn in a fixed
    order. ``selection``: "biased" (:func:`parent_weights`) or "uniform" (every elite alike:
    plain MAP-Elites, for the ablation). ``space``: (D, to_unit, from_unit, scales) of the
    launch space; default the 5 m launches (4, :func:`search.to_unit`, :func:`search.from_unit`,
    :data:`SCALES`); the foul-line atlas passes its own."""
    dim, to_unit, from_unit, scales = space or (4, search.to_unit, search.from_unit, SCALES)
    masks = sorted(a.elite)
    k = min(UNIFORM_PER_BATCH, n) if masks else n
    u = rng.random((n, dim))                     # always drawn: the stream does not depend on the archive
    X = from_unit(u[:k])
    parents = np.full(n, -1, dtype=np.int64)
    if n > k:
        w = parent_weights(a, masks) if selection == "biased" else np.full(len(masks), 1.0 / len(masks))
        idx = rng.choice(len(masks), size=n - k, p=w)
        scale = np.asarray(scales)[rng.integers(0, len(scales), size=n - k)]
        step = rng.standard_normal((n - k, dim)) * scale[:, None]
        par = np.array([masks[i] for i in idx])
        base = np.array([to_unit(a.elite[m]) for m in par])
        X = np.concatenate([X, from_unit(base + step)])
        parents[k:] = par
    return X, parents


def run(launcher: shot.Launcher, archive: Archive, *, method: str, budget: int, seed: int,
        per_subset: int = 200, on_new=None, callback=None) -> Archive:
    """Spend ``budget`` launches growing ``archive`` with ``method`` ("elites", "uniform",
    "targeted", or "elites-plain": the emitter with uniform parent selection); ``on_new(masks)``
    after each batch that found new subsets (to save them), ``callback(archive)`` after each
    batch. KeyboardInterrupt propagates (what ran is kept)."""
    rng = np.random.default_rng(seed)
    end = archive.rollouts + int(budget)

    def run_batch(X, parents=None):
        X = X[: end - archive.rollouts]
        masks, _ = launcher.launch(X)
        new = archive.add(X, masks, parents)
        if new and on_new:
            on_new(new)
        if callback:
            callback(archive)

    if method == "uniform":
        while archive.rollouts < end:
            run_batch(search.from_unit(rng.random((search.BATCH, 4))))
    elif method in ("elites", "elites-plain"):
        sel = "biased" if method == "elites" else "uniform"
        n0 = min(EXPLORE, int(budget)) if not archive.elite else 0
        start = archive.rollouts
        while archive.rollouts < start + n0:
            run_batch(search.from_unit(rng.random((search.BATCH, 4))))
        while archive.rollouts < end:
            run_batch(*emit(archive, rng, selection=sel))
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
            near = {t: int(search.hamming(t, known).min()) if len(known) else 10 for t in todo}
            target = min(todo, key=lambda t: (near[t], t))
            tried.add(target)
            left = min(per_subset, end - archive.rollouts)
            seen_before = set(archive.elite)
            res = search.solve(target, seed=int(rng.integers(0, 2**31 - 1)), max_rollouts=left,
                               launcher=launcher, explore=0, archive=dict(archive.elite))
            # solve keeps the first launch of each subset it saw: the new ones join the archive
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
        raise ValueError(f"method must be elites, uniform or targeted, got {method!r}")
    return archive


def size_table(masks) -> list[tuple[int, int, int]]:
    """[(size, found, possible)] for sizes 1..10."""
    got = np.bincount([size_of(m) for m in masks if m], minlength=11)
    return [(k, int(got[k]), int(SIZE_TOTAL[k])) for k in range(1, 11)]
