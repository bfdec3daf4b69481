"""The atlas from the foul line: one bowler's delivery per subset of pins down, found by search,
each with the probability of its subset under the release noise.

* **Delivery space**: a delivery of :mod:`.lane` in a bowler's units, over the ranges of
  :data:`BOUNDS` (board at the foul line, launch angle, speed, rev rate, axis rotation, axis
  tilt), and the hand (a 7th coordinate: below 1/2 right, else left); the default ball and
  the atlas's oil pattern. A left-hander's lane is a right-hander's mirrored (:mod:`.lane`),
  so a left-handed throw reaches the mirror images of what right-handed throws reach.
* **Search** (:func:`grow`): the 5 m atlas's MAP-Elites emitter (:func:`.atlas.emit`, with
  this space): :data:`nbst.models.mjsearch.archive.EXPLORE_EMPTY` uniform throws into an empty archive, then batches of
  :data:`._archive.BATCH` holding 2 uniform throws and children of archived elites, a child
  moved from its parent by a Gaussian step in the unit cube at one of :data:`SCALES`. Every
  throw is a settled USBC frame (:func:`.frame.run_frame`); its subset is the pins down.
  The first throw that gave a subset is its elite. A child keeps its parent's hand; uniform
  throws are either hand, half and half.
* **Mirror step** (:func:`mirror_step`): for each elite whose mirrored subset (pins 2-3,
  4-6, 7-10 and 8-9 swapped) is not archived yet, the same delivery with the other hand;
  each is a frame like any other and its own outcome is what is archived.
* **Probability** (:func:`probabilities`): each elite thrown ``n`` times under the release
  noise (:mod:`.noise`); the probability is the share of noisy throws whose pins down are
  exactly the subset, with a 95 % Wilson interval. A subset that one of these noisy throws
  knocks down and the archive lacks joins it with that throw as its elite (:func:`harvest`),
  and gets its own probability. An elite is the first throw found, not
  the most repeatable one: ``nbst bowl solve --robust`` maximises the probability of one
  subset (:mod:`.robust`).

Reproducible from the seed for any number of processes: batches have a fixed size, every
random number comes from one generator in a fixed order, and each frame depends on its
delivery only. Resuming from elites already found continues the archive (not the same run
as one without a stop).

Compute only, but for the search's checkpoint (:func:`archive_doc` / :func:`archive_from_doc`:
a dict to and from JSON, checked as hostile input). No printing.
"""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import cast

import numpy as np

from nbst.models.bowling import files, lane, pinfall, subsets
from nbst.models.bowling.lane import frame, noise
from nbst.models.mjsearch import archive as _archive

__all__ = ["OIL", "SHIPPED", "ARCHIVE_FORMAT", "ARCHIVE_VERSION", "BOUNDS", "KEYS", "DIM", "LO", "HI",
           "MIRROR_PIN", "SCALES", "to_unit", "from_unit", "SPACE", "hand_of", "delivery_of", "point_of", "mirror",
           "throw_masks", "grow", "probabilities", "harvest", "NEAREST", "seek", "archive_doc", "archive_from_doc",
           "rethrow", "mirror_step"]

#: The oil pattern of the shipped atlas (the default ball), and the shipped atlas itself.
OIL = "house"
SHIPPED = Path(__file__).with_name("foul_atlas.json")
#: The search's checkpoint (``archive.json`` beside an atlas): its format tag and version.
ARCHIVE_FORMAT = "nbst-bowling-foul-archive"
ARCHIVE_VERSION = 1

#: The delivery space (board at the foul line): the ranges a bowler throws.
#: Boards 3-37 keep the ball's centre on the lane; -3..+4 deg covers crossing the lane both
#: ways (+ is out toward board 1); 13-23 mph; up to 500 rpm (a power player); rotation
#: 0 (end over end) to 90 deg (all side spin); tilt up to 30 deg.
BOUNDS = {"board": (3.0, 37.0), "angle": (-3.0, 4.0), "mph": (13.0, 23.0), "rpm": (0.0, 500.0),
          "rotation": (0.0, 90.0), "tilt": (0.0, 30.0)}
KEYS = tuple(BOUNDS)
#: A point of the delivery space: the values of KEYS, then the hand (0 right, 1 left).
DIM = len(KEYS) + 1
LO = np.array([BOUNDS[k][0] for k in KEYS] + [0.0])
HI = np.array([BOUNDS[k][1] for k in KEYS] + [1.0])
#: Pins swapped by the mirror across the middle board (USBC numbers).
MIRROR_PIN = {1: 1, 2: 3, 3: 2, 4: 6, 5: 5, 6: 4, 7: 10, 8: 9, 9: 8, 10: 7}
#: A child's Gaussian step in the unit cube, per coordinate: 0.1, 0.5 and 2 boards at the
#: foul line (about 0.2, 1 and 4 noise sigmas), and the same shares of the other ranges.
SCALES = (0.003, 0.015, 0.06)


def to_unit(x) -> np.ndarray:
    return (np.asarray(x, dtype=float) - LO) / (HI - LO)


def from_unit(u) -> np.ndarray:
    x = LO + np.clip(np.asarray(u, dtype=float), 0.0, 1.0) * (HI - LO)
    x[..., len(KEYS)] = np.round(x[..., len(KEYS)])  # the hand: 0 right, 1 left
    return x


SPACE = _archive.Space(DIM, to_unit, from_unit, SCALES)


def hand_of(x) -> str:
    return "left" if float(x[len(KEYS)]) >= 0.5 else "right"


def delivery_of(x) -> lane.Delivery:
    """The delivery at a point ``x`` of the delivery space ((7,): :data:`KEYS`, then the hand)."""
    return lane.Delivery(hand=hand_of(x), at="foul", **{k: float(v) for k, v in zip(KEYS, x)})


def point_of(d: lane.Delivery) -> np.ndarray:
    """The point of the delivery space of a delivery (its board carried to the foul line)."""
    d = replace(d, board=d.foul_board(), at="foul")
    return np.array([float(getattr(d, k)) for k in KEYS] + [1.0 if d.hand == "left" else 0.0])


def mirror(mask: int) -> int:
    """The subset mirrored across the middle board (a left-hander's view of a right-hander's)."""
    return sum(1 << (MIRROR_PIN[n] - 1) for n in range(1, 11) if mask >> (n - 1) & 1)


def throw_masks(runner: frame.FrameRunner, X) -> tuple[list[int], list[frame.FrameResult]]:
    """The subsets (masks of pins down; 0 for a ball that leaves the lane) of throws ``X``."""
    results = runner.map([delivery_of(x) for x in X])
    return [pinfall.mask_from_pins(r.down) for r in results], results


def grow(runner: frame.FrameRunner, archive: subsets.SubsetArchive, *, budget: int, seed: int,
         on_batch=None) -> subsets.SubsetArchive:
    """Spend ``budget`` frames growing ``archive`` (elites are (7,) points: :data:`KEYS`, hand)
    with the rollout room's MAP-Elites loop (:func:`nbst.models.mjsearch.archive.grow`); a
    child keeps its parent's hand. ``on_batch(archive, new_masks)`` after each batch
    (progress, checkpoints). KeyboardInterrupt propagates; what ran is in ``archive``."""
    def adopt(X, parents, a):
        kids = parents >= 0
        X[kids, len(KEYS)] = [a.elite[int(p)][len(KEYS)] for p in parents[kids]]  # the parent's hand

    grown = _archive.grow(lambda X: throw_masks(runner, X)[0], archive, np.random.default_rng(seed), SPACE,
                          budget=budget, explore=_archive.EXPLORE_EMPTY, batch=_archive.BATCH, weights=subsets.parent_weights,
                          adopt=adopt, on_batch=on_batch)
    return cast(subsets.SubsetArchive, grown)


def probabilities(runner: frame.FrameRunner, elites: dict, *, n: int, seed: int, nz: noise.Noise = noise.DEFAULT,
                  on_done=None, frames: bool = False):
    """{mask: noise.Estimate} for each elite ({mask: (7,) point}): ``n`` noisy throws of it
    (the same ``seed`` for every elite), the outcome counted is exactly its subset. With
    ``frames``: (that dict, the noisy deliveries, their frames)."""
    masks = sorted(elites)
    throws = []
    for m in masks:
        throws.extend(noise.sample(delivery_of(elites[m]), n, seed, nz))
    results = runner.map(throws, on_done=on_done)
    out = {}
    for i, m in enumerate(masks):
        out[m] = noise.estimate(results[i * n:(i + 1) * n], seed, nz, want=pinfall.pins_of(m))
    return (out, throws, results) if frames else out


def harvest(archive: subsets.SubsetArchive, throws, results) -> list[int]:
    """Subsets that noisy throws (of :func:`probabilities`) knocked down and the archive lacks:
    each joins with its throw as the elite, when that delivery lies inside the delivery space's
    ranges (the noise may carry it out). The frames have run already: the archive's frame
    count is unchanged. Returns the new masks, in throw order."""
    new = []
    for d, r in zip(throws, results):
        m = pinfall.mask_from_pins(r.down)
        if not m or m in archive.elite:
            continue
        x = point_of(d)
        if np.all(x >= LO) and np.all(x <= HI):
            archive.elite[m] = x
            archive.seen[m] = 1
            archive.found_at[m] = archive.rollouts
            new.append(m)
    return new


#: :func:`seek`: parents are drawn among this many archived subsets nearest the request.
NEAREST = 8


def seek(runner: frame.FrameRunner, elites: dict, target: int, *, budget: int, seed: int,
         on_batch=None, trusted: bool = False) -> tuple[np.ndarray | None, dict, int]:
    """A throw whose pins down are exactly ``target`` (a mask), from the archive ``elites``
    ({mask: (7,) point}): batches of :data:`._archive.BATCH` children of the :data:`NEAREST`
    subsets nearest the request (Hamming distance; nearer ones drawn more often: weight
    1 / (1 + distance)^2), each moved by a Gaussian step at one of :data:`SCALES`; every new
    subset seen joins the archive. Stops at the first exact hit or after ``budget`` frames. A
    request the archive holds is its answer with no frame when ``trusted`` (an archive grown on
    this lane scene: a frame is deterministic), else confirmed with one frame first (an archive
    grown on another lane scene holds starts, not answers): if that frame gives something else,
    the search runs.
    Returns (the point or None, the grown archive, frames run); ``on_batch(frames, best
    distance)`` after each batch. An empty archive starts from uniform throws."""
    rng = np.random.default_rng(seed)
    arch = {int(m): np.asarray(x, dtype=float) for m, x in elites.items() if m}
    frames = 0
    if trusted and target in arch:
        return arch[target], arch, 0
    if target in arch:  # confirmed with one frame: an archive of another scene holds starts, not answers
        x = arch.pop(target)
        got, _ = throw_masks(runner, x[None])
        frames = 1
        if int(got[0]) == target:
            arch[target] = x
            return x, arch, frames
        if got[0] and int(got[0]) not in arch:
            arch[int(got[0])] = x
    while frames < budget:
        n = min(_archive.BATCH, budget - frames)
        if arch:
            masks = np.array(sorted(arch), dtype=np.int64)
            dist = subsets.hamming(target, masks)
            order = np.argsort(dist, kind="stable")[:NEAREST]
            w = 1.0 / (1.0 + dist[order]) ** 2
            pick = order[rng.choice(len(order), size=n, p=w / w.sum())]
            scale = np.asarray(SCALES)[rng.integers(0, len(SCALES), size=n)]
            base = np.array([to_unit(arch[int(masks[i])]) for i in pick])
            X = from_unit(base + rng.standard_normal((n, DIM)) * scale[:, None])
            X[:, len(KEYS)] = base[:, len(KEYS)]  # the parent's hand
        else:
            X = from_unit(rng.random((n, DIM)))
        got, _ = throw_masks(runner, X)
        frames += n
        for x, m in zip(X, got):
            if m and m not in arch:
                arch[m] = np.array(x, dtype=float)
        if on_batch is not None:
            on_batch(frames, int(subsets.hamming(target, np.array(sorted(arch), dtype=np.int64)).min()) if arch else 10)
        if target in arch:
            return arch[target], arch, frames
    return None, arch, frames


def archive_doc(a: subsets.SubsetArchive, seed: int) -> dict:
    """The search's state as a JSON-able dict (elites as points of :data:`KEYS`)."""
    return {"format": ARCHIVE_FORMAT, "version": ARCHIVE_VERSION, "seed": int(seed), "keys": [*KEYS, "hand"],
            "rollouts": int(a.rollouts),
            "elites": {str(m): [float(v) for v in a.elite[m]] for m in sorted(a.elite)},
            "seen": {str(m): int(a.seen.get(m, 1)) for m in sorted(a.elite)},
            "found_at": {str(m): int(a.found_at.get(m, -1)) for m in sorted(a.elite)}}


def archive_from_doc(doc, src) -> subsets.SubsetArchive:
    """An archive from :func:`archive_doc`'s dict; BowlingFileError (one line naming ``src`` and the
    field) on anything else: a mask outside 1..1023, a point that is not 6 finite numbers in
    :data:`BOUNDS`, counts that are not whole numbers >= -1."""
    import math

    def fail(field, why):
        raise files.BowlingFileError(f"{src}: {field}: {why}")

    if not isinstance(doc, dict) or doc.get("format") != ARCHIVE_FORMAT:
        fail("format", f"must be {ARCHIVE_FORMAT!r}")
    if doc.get("version") != ARCHIVE_VERSION:
        fail("version", f"must be {ARCHIVE_VERSION}")
    if doc.get("keys") != [*KEYS, "hand"]:
        fail("keys", f"must be {[*KEYS, 'hand']}")
    n = doc.get("rollouts")
    if not isinstance(n, int) or isinstance(n, bool) or not 0 <= n <= 10**9:
        fail("rollouts", "must be a whole number in [0, 1e9]")
    a = subsets.SubsetArchive(rollouts=n)
    el = doc.get("elites")
    if not isinstance(el, dict) or len(el) > subsets.N_SUBSETS:
        fail("elites", "must be an object of at most 1,023 subsets")
    for key, x in el.items():
        if not key.isdigit() or not 1 <= int(key) <= subsets.N_SUBSETS:
            fail(f"elites.{key}", "a subset is a mask 1..1023")
        if (not isinstance(x, list) or len(x) != DIM
                or not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in x)
                or not all(lo <= v <= hi for v, lo, hi in zip(x, LO, HI))):
            fail(f"elites.{key}", f"must be {DIM} finite numbers within {BOUNDS} and the hand in [0, 1]")
        m = int(key)
        a.elite[m] = np.array(x, dtype=float)
        for name, lo in (("seen", 1), ("found_at", -1)):
            v = doc.get(name, {}).get(key, lo) if isinstance(doc.get(name), dict) else lo
            if not isinstance(v, int) or isinstance(v, bool) or not lo <= v <= 10**9:
                fail(f"{name}.{key}", f"must be a whole number >= {lo}")
            getattr(a, name)[m] = v
    return a


def rethrow(runner: frame.FrameRunner, archive: subsets.SubsetArchive, X, on_done=None) -> list[int]:
    """Throw each point of ``X`` ((n, 7)) once on this scene and archive it by what it knocks
    down here (parentless, like a uniform throw; the first throw of a subset is its elite): an
    atlas grown on another lane scene is a set of deliveries, not of answers. Returns the new
    masks; the frames count in the archive's rollouts."""
    X = np.asarray(X, dtype=float).reshape(-1, DIM)
    if not len(X):
        return []
    masks = [pinfall.mask_from_pins(r.down) for r in runner.map([delivery_of(x) for x in X], on_done=on_done)]
    return archive.add(X, masks, None)


def mirror_step(runner: frame.FrameRunner, archive: subsets.SubsetArchive) -> list[int]:
    """For each elite whose mirrored subset is not archived, its delivery with the other hand:
    one frame each, archived by its own outcome (parentless). Returns the new masks."""
    todo = [m for m in sorted(archive.elite) if mirror(m) not in archive.elite]
    if not todo:
        return []
    X = np.array([archive.elite[m] for m in todo], dtype=float)
    X[:, len(KEYS)] = 1.0 - np.round(X[:, len(KEYS)])
    masks, _ = throw_masks(runner, X)
    return archive.add(X, masks, None)
