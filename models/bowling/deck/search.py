"""Search the delivery space for a requested set of pins down.

The paper's crossover needs several velocity vectors; a bowling delivery is one (a single
block), so the signature (which pins fell) guides the search instead. The search is the
rollout room's engine (:class:`nbst.models.mjsearch.engine.Engine`) on the 5 m deliveries,
without its GA:

1. **explore**: ``explore`` deliveries drawn uniformly over :data:`.delivery.BOUNDS`
   (from the seeded Generator; capped at a quarter of the budget); every delivery enters
   the engine's **archive keyed by subset** (the first delivery that produced each subset
   is kept, and the lowest-cost one, its elite).
2. **restarts**: CMA-ES (pycma, population :data:`POPSIZE`) in the unit cube of delivery
   space, started from the **elite** of the subset **nearest** the request and not used
   yet. Nearest = lowest (Hamming distance, cost), then discovery order (a subset known
   only from a given ``archive``, e.g. the atlas's, ranks as its distance and the cost of a
   delivery with every pin half-way); when every subset has been a start, the cycle begins
   again. A restart ends after :data:`STALL_GENERATIONS` generations without a lower cost,
   and the next starts after :data:`EXPLORE_BETWEEN` more uniform deliveries; the steps
   alternate between :data:`SIGMA0` and a tenth of it (outcomes are chaotic: a near miss is
   often one millimetre away from a hit, or nowhere near).
3. stop at the first delivery whose subset is exactly the request, or at the budget; Ctrl-C
   stops too, and the best so far is returned (``stopped`` "interrupted").

Cost of a delivery = Hamming(subset, request) (or, with ``distance="geometry"``,
:func:`geometry_distance`) + :data:`SOFT_WEIGHT` x the soft distance
(sum over pins of |min(tilt / 45 deg, 1) - wanted|, off-deck pins count as 1): the
soft part only orders deliveries of equal Hamming distance, so CMA-ES sees pins that
almost fell.

Reproducible: the same seed gives the same throw for any number of jobs (batches do not
depend on the jobs; deliveries are independent; pycma gets a seed drawn from the
Generator, and nothing else touches numpy's global random state in between).
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from nbst.errors import InputError

from nbst.models.bowling import deck, geometry, pinfall, subsets

from nbst.models.mjsearch import archive as _archive
from nbst.models.mjsearch.engine import Engine

__all__ = ["EXPLORE_FIRST", "EXPLORE_BETWEEN", "BATCH", "POPSIZE", "SIGMA0", "STALL_GENERATIONS", "DEFAULT_MAX_ROLLOUTS",
           "SOFT_WEIGHT", "SCALES", "SPACE", "DeckProgress", "DeckResult", "to_unit", "from_unit", "hamming",
           "NEIGHBOUR_EXTRA", "geometry_distance", "soft_distance", "scorer", "solve", "ROBUSTNESS_STEPS",
           "ROBUSTNESS_ROLLOUTS", "robustness", "LADDER_LATERAL_M", "LADDER_SPEED_M_S", "robustness_ladder"]

#: Uniform deliveries before the first restart (capped at a quarter of the budget).
EXPLORE_FIRST = 200
#: Uniform deliveries after each restart (new subsets to restart from; a search never stops
#: exploring, so a subset that only random throws find is still found).
EXPLORE_BETWEEN = 16
#: Deliveries run per batch (fixed, so that results do not depend on --jobs).
BATCH = _archive.BATCH
#: CMA-ES: population, initial step (unit cube), generations without progress per restart.
POPSIZE = 8
SIGMA0 = 0.05
STALL_GENERATIONS = 6
#: The rollout budget of :func:`solve` when none is given (``nbst bowl solve --max-rollouts``'s default).
DEFAULT_MAX_ROLLOUTS = 3000
#: Weight of the soft distance (in Hamming units per pin): < 1/10, so it only breaks ties.
SOFT_WEIGHT = 0.05
#: Gaussian steps of an atlas child, in the unit cube (per coordinate): ~0.4 mm, 4 mm, 42 mm
#: sideways (the unit is 0.84 m of lateral range, 5 m/s of speed, 6 deg, 60 rad/s).
SCALES = (0.0005, 0.005, 0.05)
#: The 5 m delivery space (:data:`.delivery.BOUNDS` as a box of the rollout room).
SPACE = _archive.box_space(deck.LO, deck.HI, SCALES)


@dataclass
class DeckProgress:
    """What a search reports after each batch (to a progress bar)."""

    rollouts: int
    best_hamming: int
    best_mask: int
    subsets: int


@dataclass
class DeckResult:
    """Best delivery found for ``target`` (a 10-bit mask), and how the search went (``stopped``:
    "found" | "budget" | "interrupted"; ``archive``: mask -> (4,) delivery, the first that gave
    it, given ones first), with bowling's words for the engine's (``delivery``, ``mask``,
    ``hamming``)."""

    target: int
    x: np.ndarray
    signature: int
    distance: int
    cost: float
    rollouts: int
    restarts: int
    stopped: str                 # "found" | "budget" | "interrupted"
    seed: int
    wall_time: float
    archive: dict = field(default_factory=dict)   # mask -> the first delivery that gave it

    @property
    def delivery(self) -> np.ndarray:
        """(4,) y, speed, angle, spin, 5 m before the pins (``x``)."""
        return self.x

    @property
    def mask(self) -> int:
        """The pins it knocks down, a 10-bit mask (``signature``)."""
        return self.signature

    @property
    def hamming(self) -> int:
        """Pins off the request (``distance``, Hamming by default)."""
        return self.distance


def to_unit(delivery) -> np.ndarray:
    return SPACE.to_unit(delivery)


def from_unit(u) -> np.ndarray:
    return SPACE.from_unit(u)


#: Pins whose state differs between two masks (the shared definition).
hamming = subsets.hamming


#: Geometry-weighted distance (``distance="geometry"``): an extra pin down that neighbours a
#: wanted down pin on the triangle costs this instead of 1 (a falling neighbour takes it
#: along: 1-2-3-5 is nearer 1-2-3 than the empty set is).
NEIGHBOUR_EXTRA = 0.5


def geometry_distance(a, b) -> np.ndarray:
    """Distance from masks ``a`` to the request ``b`` (broadcast): 1 per wanted pin standing or
    unwanted pin down, but :data:`NEIGHBOUR_EXTRA` for an unwanted down pin whose neighbour on
    the triangle (12 in away) is a wanted down pin. 0 exactly when a == b."""
    adj = (geometry.neighbours().astype(np.int64) << np.arange(10)).sum(axis=1)   # (10,) neighbour masks
    a = np.asarray(a, dtype=np.int64)
    b = int(b)
    near_wanted = int(np.bitwise_or.reduce([adj[i] for i in range(10) if b >> i & 1], initial=0))
    extra = a & ~b
    missing = ~a & b & geometry.ALL_DOWN
    cheap = extra & near_wanted
    return hamming(missing | (extra & ~cheap), 0) + NEIGHBOUR_EXTRA * hamming(cheap, 0)


def soft_distance(model, final_qpos, target: int) -> np.ndarray:
    """(B,) sum over pins of |min(tilt/45deg, 1) - wanted| (off-deck pins count as down)."""
    cos_t = np.clip(pinfall.cos_tilt(pinfall.poses(model, final_qpos)), -1, 1)
    tilt = np.degrees(np.arccos(cos_t))
    soft = np.minimum(tilt / pinfall.DOWN_TILT_DEG, 1.0)
    down = pinfall.pins_down(model, final_qpos)
    soft = np.where(down, 1.0, soft)
    want = (target >> np.arange(10)) & 1
    return np.abs(soft - want).sum(axis=-1)


def scorer(runner: deck.DeliveryRunner, target: int, distance: str = "hamming"):
    """``evaluate(deliveries) -> (masks, Hamming distances, costs)`` of a batch, for the room's search."""
    if distance not in ("hamming", "geometry"):
        raise InputError(f"distance must be hamming or geometry, got {distance!r}")
    dist = hamming if distance == "hamming" else geometry_distance

    def evaluate(chunk):
        states = np.array([runner.initial_state(*deck.initial_qpos_qvel(runner.model, x)) for x in chunk])
        qpos = runner.final_qpos(runner.run_states(states))
        masks = pinfall.mask_of(pinfall.pins_down(runner.model, qpos))
        cost = dist(masks, target) + SOFT_WEIGHT * soft_distance(runner.model, qpos, target)
        return masks, hamming(masks, target), cost

    return evaluate, dist


def solve(target: int, *, seed: int, max_rollouts: int = DEFAULT_MAX_ROLLOUTS, jobs: int | None = None,
          runner: deck.DeliveryRunner | None = None, callback=None, explore: int = EXPLORE_FIRST,
          archive: dict | None = None, explore_between: int = EXPLORE_BETWEEN,
          distance: str = "hamming") -> DeckResult:
    """Search for a delivery that knocks down exactly the pins of ``target`` (a 10-bit mask).

    Stops at the first exact hit or after ``max_rollouts`` deliveries; Ctrl-C
    (KeyboardInterrupt) stops too, and the best so far is returned (``stopped``
    "interrupted").

    Args:
        target: the pins to knock down, a 10-bit mask (bit k: pin k + 1), 1..1023.
        seed: the seed; the same seed gives the same delivery whatever ``jobs``.
        max_rollouts: the budget, in deliveries run.
        jobs: threads of the runner made here (None: every core).
        runner: a ``deck.DeliveryRunner`` to reuse (its jobs then apply), or None.
        callback: None, or called with a :class:`DeckProgress` after each batch.
        explore: uniform deliveries before the CMA-ES restarts (capped at a quarter of the budget).
        archive: deliveries already known by subset (mask -> (4,) delivery; e.g. the atlas's),
            used as restart points; with ``explore=0`` the search starts from them directly.
        explore_between: uniform deliveries after each restart.
        distance: "hamming" or "geometry" (:func:`geometry_distance`) in the cost.

    Returns:
        A :class:`DeckResult`: the best delivery (y, speed, angle, spin 5 m before the pins),
        the pins it knocks down, its Hamming distance to ``target``, the rollouts and restarts
        used, ``stopped`` ("found", "budget" or "interrupted"), the seed, the wall time and the
        archive.

    Raises:
        InputError: ``target`` is not a subset of the 10 pins (1..1023), or ``distance`` is unknown.
    """
    if not 0 < int(target) <= geometry.N_SUBSETS:
        raise InputError(f"target must be a non-empty subset of the 10 pins (1..{geometry.N_SUBSETS}), got {target}")
    target = int(target)
    own = runner is None
    L = deck.DeliveryRunner(jobs=jobs) if runner is None else runner
    t0 = time.perf_counter()
    try:
        evaluate, dist = scorer(L, target, distance)

        def run(U):
            return evaluate(deck.clamp(SPACE.from_unit(U)))

        eng = Engine(SPACE.dim, seed=seed, max_rollouts=max_rollouts, batch=BATCH, explore=explore, ga_batches=0,
                     popsize=POPSIZE, sigma0=SIGMA0, stall=STALL_GENERATIONS,
                     schedule=(("cell", 1.0), ("cell", 0.1)), explore_between=explore_between)
        known = {int(m): np.asarray(x, dtype=float) for m, x in (archive or {}).items()}
        eng.know({m: to_unit(x) for m, x in known.items()},
                 prior=lambda m: (int(hamming(m, target)), float(dist(m, target)) + SOFT_WEIGHT * 10))
        if target in known:  # known already: one rollout confirms it and makes it the best
            U = to_unit(known[target])[None, :]
            eng.tell(U, *run(U))

        def progress(e: Engine) -> None:
            if callback is not None and e.best is not None:
                callback(DeckProgress(e.rollouts, e.best.distance, e.best.signature, len(set(known) | set(e.first))))

        r = eng.run(run, progress)
    finally:
        if own:
            L.close()
    stopped = "interrupted" if "interrupted" in r.stopped else "found" if "solved" in r.stopped else "budget"
    seen = dict(known)
    for m, u in r.first.items():
        seen.setdefault(int(m), deck.clamp(SPACE.from_unit(u)))
    return DeckResult(target=target, x=deck.clamp(SPACE.from_unit(r.x)), signature=r.signature, distance=r.distance,
                      cost=r.cost, rollouts=r.rollouts, restarts=r.restarts, stopped=stopped, seed=int(seed),
                      wall_time=time.perf_counter() - t0, archive=seen)


#: Bisection rounds of :func:`robustness` per axis, and the rollouts it spends: on each of 2 axes, 4 at
#: the largest change and, when that fails, ``ROBUSTNESS_STEPS`` rounds of 4 (fewest, most).
ROBUSTNESS_STEPS = 10
ROBUSTNESS_ROLLOUTS = (2 * 4, 2 * (4 + ROBUSTNESS_STEPS * 4))


def robustness(runner: deck.DeliveryRunner, delivery, mask: int, *, lateral_max: float = 0.05,
               speed_max: float = 0.5, steps: int = ROBUSTNESS_STEPS) -> dict:
    """Largest lateral (m) and speed (m/s) changes that keep ``mask``, by bisection.

    A change d passes when the deliveries at -d, -d/2, +d/2 and +d all give ``mask``
    (4 rollouts). Bisection on [0, max] for ``steps`` rounds (outcomes are chaotic, so
    the answer is "these 4 probes keep it", not "every smaller change keeps it").
    """
    delivery = np.asarray(delivery, dtype=float)
    out: dict[str, Any] = {}
    for key, col, hi in (("lateral_m", 0, lateral_max), ("speed_m_s", 1, speed_max)):
        lo_ok, hi_bad = 0.0, hi
        probes_run = 0

        def keeps(d):
            xs = np.repeat(delivery[None, :], 4, axis=0)
            xs[:, col] += np.array([-d, -d / 2, d / 2, d])
            sig, _ = runner.throw(xs)
            return bool(np.all(sig == mask))

        if keeps(hi):
            lo_ok = hi
            probes_run += 4
        else:
            probes_run += 4
            for _ in range(steps):
                mid = 0.5 * (lo_ok + hi_bad)
                probes_run += 4
                if keeps(mid):
                    lo_ok = mid
                else:
                    hi_bad = mid
        out[key] = lo_ok
        out[f"{key}_rollouts"] = probes_run
    out["method"] = (f"bisection ({steps} rounds) on [0, max]; a change d passes when launches at -d, -d/2, "
                     f"+d/2, +d all keep the subset; max {lateral_max} m and {speed_max} m/s")
    return out


#: The atlas's cheaper probe: a ladder of changes, doubling from the smallest, and checks at
#: -d and +d only (2 rollouts). 11 rungs each: 0.05 mm .. 51.2 mm and 0.5 mm/s .. 512 mm/s.
LADDER_LATERAL_M = 0.05e-3 * 2.0 ** np.arange(11)
LADDER_SPEED_M_S = 0.5e-3 * 2.0 ** np.arange(11)


def robustness_ladder(runner: deck.DeliveryRunner, delivery, mask: int, *, lateral=LADDER_LATERAL_M,
                      speed=LADDER_SPEED_M_S) -> dict:
    """Cheap robustness for the atlas: the largest rung d of a doubling ladder at which the
    deliveries at -d and +d both keep ``mask``, by binary search over the rungs (4 checks of 2
    rollouts for 11 rungs: 8 rollouts an axis, 16 a throw; resolution a factor of 2).

    0.0 means even the smallest rung fails. Outcomes are chaotic: "these probes keep it",
    not "every smaller change keeps it" (a rung that passes can sit above one that fails).
    """
    delivery = np.asarray(delivery, dtype=float)
    out: dict[str, Any] = {}
    for key, col, rungs in (("lateral_m", 0, np.asarray(lateral, float)), ("speed_m_s", 1, np.asarray(speed, float))):
        lo, hi, runs = -1, len(rungs), 0   # rung lo passes (-1: none), rung hi fails (len: beyond the top)
        while hi - lo > 1:
            mid = (lo + hi) // 2
            xs = np.repeat(delivery[None, :], 2, axis=0)
            xs[:, col] += np.array([-rungs[mid], rungs[mid]])
            sig, _ = runner.throw(xs)
            runs += 2
            if np.all(sig == mask):
                lo = mid
            else:
                hi = mid
        out[key] = float(rungs[lo]) if lo >= 0 else 0.0
        out[f"{key}_rollouts"] = runs
    out["method"] = (f"ladder: binary search over {len(lateral)} doubling rungs "
                     f"({lateral[0] * 1e3:g} .. {lateral[-1] * 1e3:g} mm sideways, "
                     f"{speed[0] * 1e3:g} .. {speed[-1] * 1e3:g} mm/s); a change d passes when launches at "
                     f"-d and +d both keep the subset; 0 = the smallest rung fails")
    return out

