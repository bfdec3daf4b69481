"""Search the launch space for a requested set of pins down.

The paper's crossover needs several velocity vectors; a bowling shot has one, so the
signature (which pins fell) guides the search instead:

1. **explore**: ``explore`` launches drawn uniformly over :data:`shot.BOUNDS`
   (from the seeded Generator); every launch enters an **archive keyed by subset**
   (MAP-Elites style: the first launch that produced each subset is kept; the archive
   is also what ``nbst bowl atlas`` collects).
2. **restarts**: CMA-ES (pycma) in the unit cube of launch space, started from the
   **elite** (the lowest-cost launch seen) of the subset **nearest** the request and not
   used yet, step size :data:`SIGMA0`. Nearest = lowest elite cost (Hamming distance
   between the 10-bit masks plus the soft distance below), then discovery order; when
   every subset has been a start, the cycle begins again. A restart ends after
   :data:`STALL_GENERATIONS` generations without a nearer subset, and the next starts
   from the next-nearest archived launch, after :data:`EXPLORE_BETWEEN` more uniform
   launches; each restart's sigma alternates between
   :data:`SIGMA0` and a tenth of it (outcomes are chaotic: a near miss is often one
   millimetre away from a hit, or nowhere near).
3. stop at the first launch whose subset is exactly the request, or at the budget.

Cost of a launch = Hamming(subset, request) (or, with ``distance="geometry"``,
:func:`geometry_distance`) + :data:`SOFT_WEIGHT` x the soft distance
(sum over pins of |min(tilt / 45 deg, 1) - wanted|, off-deck pins count as 1): the
soft part only orders launches of equal Hamming distance, so CMA-ES sees pins that
almost fell.

Reproducible: the same seed gives the same shot for any number of jobs (batches do not
depend on the jobs; launches are independent; pycma gets a seed drawn from the
Generator, and nothing else touches numpy's global random state in between).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from nbst.models.bowling import geometry, shot

#: Uniform exploration launches before CMA-ES restarts (capped at a quarter of the budget).
EXPLORE = 200
#: Uniform launches after each restart (new subsets to restart from; a search never stops
#: exploring, so a subset that only random throws find is still found).
EXPLORE_BETWEEN = 16
#: Launches run per batch (fixed, so that results do not depend on --jobs).
BATCH = 16
#: CMA-ES: population, initial step (unit cube), generations without progress per restart.
POPSIZE = 8
SIGMA0 = 0.05
STALL_GENERATIONS = 6
#: Weight of the soft distance (in Hamming units per pin): < 1/10, so it only breaks ties.
SOFT_WEIGHT = 0.05


@dataclass
class Progress:
    """What a search reports after each batch (to a progress bar)."""

    rollouts: int
    best_hamming: int
    best_mask: int
    subsets: int


@dataclass
class SearchResult:
    """Best launch found for ``target`` (a 10-bit mask), and how the search went."""

    target: int
    launch: np.ndarray           # (4,) y, speed, angle, spin
    mask: int
    hamming: int
    cost: float
    rollouts: int
    restarts: int
    stopped: str                 # "found" | "budget" | "interrupted"
    seed: int
    wall_time: float
    archive: dict = field(default_factory=dict)   # mask -> (4,) launch


def to_unit(launch) -> np.ndarray:
    return (np.asarray(launch, dtype=float) - shot.LO) / (shot.HI - shot.LO)


def from_unit(u) -> np.ndarray:
    return shot.clamp(shot.LO + np.clip(np.asarray(u, dtype=float), 0.0, 1.0) * (shot.HI - shot.LO))


def hamming(a, b) -> np.ndarray:
    """Number of pins whose state differs between masks a and b (broadcast)."""
    x = np.bitwise_xor(np.asarray(a, dtype=np.int64), np.asarray(b, dtype=np.int64))
    return np.array([int(v).bit_count() for v in np.ravel(x)]).reshape(np.shape(x))


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
    adr = shot.pin_addresses(model)
    p = np.asarray(final_qpos)[:, adr[:, None] + np.arange(7)]
    qw, qx, qy, qz = p[..., 3], p[..., 4], p[..., 5], p[..., 6]
    cos_t = np.clip(1.0 - 2.0 * (qx**2 + qy**2) / (qw**2 + qx**2 + qy**2 + qz**2), -1, 1)
    tilt = np.degrees(np.arccos(cos_t))
    soft = np.minimum(tilt / shot.DOWN_TILT_DEG, 1.0)
    down = shot.pins_down(model, final_qpos)
    soft = np.where(down, 1.0, soft)
    want = (target >> np.arange(10)) & 1
    return np.abs(soft - want).sum(axis=-1)


class Evaluator:
    """Runs launches in batches, keeps the archive and the best launch for a target."""

    def __init__(self, launcher: shot.Launcher, target: int, *, max_rollouts: int, callback=None,
                 distance: str = "hamming"):
        if distance not in ("hamming", "geometry"):
            raise ValueError(f"distance must be hamming or geometry, got {distance!r}")
        self.distance = hamming if distance == "hamming" else geometry_distance
        self.L = launcher
        self.target = int(target)
        self.max_rollouts = int(max_rollouts)
        self.callback = callback
        self.rollouts = 0
        self.archive: dict[int, np.ndarray] = {}   # mask -> first launch that gave it (the atlas's)
        self.order: dict[int, int] = {}   # mask -> discovery index (tie-break)
        self.elite: dict[int, tuple] = {}  # mask -> (cost, launch): the best launch of each subset for this target
        self.best = None                  # (cost, hamming, mask, launch)

    @property
    def left(self) -> int:
        return self.max_rollouts - self.rollouts

    @property
    def found(self) -> bool:
        return self.best is not None and self.best[1] == 0

    def __call__(self, launches: np.ndarray) -> np.ndarray:
        """(B, 4) launches -> (B,) costs; stops early (returns what ran) at the budget or a hit."""
        launches = shot.clamp(np.atleast_2d(launches))[: max(0, self.left)]
        costs = []
        for i in range(0, len(launches), BATCH):
            chunk = launches[i:i + BATCH]
            states = np.array([self.L.initial_state(*shot.initial_qpos_qvel(self.L.model, x)) for x in chunk])
            qpos = self.L.final_qpos(self.L.run_states(states))
            masks = shot.mask_of(shot.pins_down(self.L.model, qpos))
            ham = hamming(masks, self.target)
            cost = self.distance(masks, self.target) + SOFT_WEIGHT * soft_distance(self.L.model, qpos, self.target)
            for x, m, h, c in zip(chunk, masks, ham, cost):
                m = int(m)
                if m not in self.archive:
                    self.archive[m] = x.copy()
                    self.order[m] = len(self.order)
                if m not in self.elite or c < self.elite[m][0]:
                    self.elite[m] = (float(c), x.copy())
                if self.best is None or c < self.best[0]:
                    self.best = (float(c), int(h), m, x.copy())
            self.rollouts += len(chunk)
            costs.extend(cost.tolist())
            if self.callback:
                self.callback(Progress(self.rollouts, self.best[1], self.best[2], len(self.archive)))
            if self.found:
                break
        return np.array(costs)

    def nearest(self, exclude) -> list[int]:
        """Archived masks, nearest the target first, without ``exclude``: by the cost of their
        elite (Hamming distance + the soft part), then discovery order; masks known only from a
        given archive (no elite yet) by their Hamming distance."""
        ms = [m for m in self.archive if m not in exclude]

        def key(m):
            c = self.elite[m][0] if m in self.elite else float(self.distance(m, self.target)) + SOFT_WEIGHT * 10
            return (c, self.order[m])
        return sorted(ms, key=key)

    def start(self, mask: int) -> np.ndarray:
        """The launch a restart from ``mask`` begins at: its elite, else its archived launch."""
        return self.elite[mask][1] if mask in self.elite else self.archive[mask]


def solve(target: int, *, seed: int, max_rollouts: int = 3000, jobs: int | None = None,
          launcher: shot.Launcher | None = None, callback=None, explore: int = EXPLORE,
          archive: dict | None = None, explore_between: int = EXPLORE_BETWEEN,
          distance: str = "hamming") -> SearchResult:
    """Search for a launch that knocks down exactly the pins of ``target`` (a 10-bit mask).

    Stops at the first exact hit or after ``max_rollouts`` launches; Ctrl-C
    (KeyboardInterrupt) stops too, and the best so far is returned (``stopped``
    "interrupted"). ``launcher``: reuse one (its jobs then apply). ``archive``: launches
    already known by subset (mask -> (4,) launch; e.g. the atlas's), used as restart
    points; with ``explore=0`` the search starts from them directly. ``distance``: "hamming"
    or "geometry" (:func:`geometry_distance`) in the cost.
    """
    import cma

    if not 0 < int(target) <= geometry.N_SUBSETS:
        raise ValueError(f"target must be a non-empty subset of the 10 pins (1..{geometry.N_SUBSETS}), got {target}")
    own = launcher is None
    L = shot.Launcher(jobs=jobs) if own else launcher
    rng = np.random.default_rng(seed)
    ev = Evaluator(L, target, max_rollouts=max_rollouts, callback=callback, distance=distance)
    for m, x in (archive or {}).items():
        ev.archive[int(m)] = np.asarray(x, dtype=float)
        ev.order[int(m)] = len(ev.order)
    t0 = time.perf_counter()
    if int(target) in ev.archive:  # known already: one launch confirms it and makes it the best
        ev(ev.archive[int(target)][None, :])
    restarts = 0
    stopped = "budget"
    try:
        n0 = min(int(explore), max_rollouts // 4 if ev.archive else max(1, max_rollouts // 4))
        if not ev.found:
            ev(from_unit(rng.random((n0, 4))))
        used: set[int] = set()
        while not ev.found and ev.left > 0:
            order = ev.nearest(used)
            if not order and not ev.archive:  # nothing to start from: explore a little
                ev(from_unit(rng.random((POPSIZE, 4))))
                continue
            if not order:
                used.clear()
                order = ev.nearest(used)
            start = order[0]
            used.add(start)
            sigma = SIGMA0 if restarts % 2 == 0 else SIGMA0 / 10
            restarts += 1
            es = cma.CMAEvolutionStrategy(to_unit(ev.start(start)).tolist(), sigma,
                                          {"bounds": [0.0, 1.0], "popsize": POPSIZE, "verbose": -9,
                                           "seed": int(rng.integers(1, 2**31 - 1))})
            best_here, stall = math.inf, 0
            while not ev.found and ev.left > 0 and stall < STALL_GENERATIONS:
                xs = es.ask()
                costs = ev(from_unit(np.array(xs)))
                if len(costs) < len(xs):
                    break
                es.tell(xs, costs.tolist())
                if costs.min() < best_here - 1e-12:
                    best_here, stall = float(costs.min()), 0
                else:
                    stall += 1
            if not ev.found and ev.left > 0 and explore_between:
                ev(from_unit(rng.random((explore_between, 4))))  # keep exploring: rare subsets are found so
        if ev.found:
            stopped = "found"
    except KeyboardInterrupt:
        stopped = "interrupted"
    finally:
        if own:
            L.close()
    if ev.best is None:
        if stopped == "interrupted":
            raise KeyboardInterrupt
        raise ValueError("max_rollouts must allow at least one launch")
    cost, ham, mask, launch = ev.best
    return SearchResult(target=int(target), launch=launch, mask=mask, hamming=ham, cost=cost,
                        rollouts=ev.rollouts, restarts=restarts, stopped=stopped, seed=int(seed),
                        wall_time=time.perf_counter() - t0, archive=dict(ev.archive))


def robustness(launcher: shot.Launcher, launch, mask: int, *, lateral_max: float = 0.05,
               speed_max: float = 0.5, steps: int = 10) -> dict:
    """Largest lateral (m) and speed (m/s) changes that keep ``mask``, by bisection.

    A change d passes when the launches at -d, -d/2, +d/2 and +d all give ``mask``
    (4 rollouts). Bisection on [0, max] for ``steps`` rounds (outcomes are chaotic, so
    the answer is "these 4 probes keep it", not "every smaller change keeps it").
    """
    launch = np.asarray(launch, dtype=float)
    out = {}
    for key, col, hi in (("lateral_m", 0, lateral_max), ("speed_m_s", 1, speed_max)):
        lo_ok, hi_bad = 0.0, hi
        probes_run = 0

        def keeps(d):
            xs = np.repeat(launch[None, :], 4, axis=0)
            xs[:, col] += np.array([-d, -d / 2, d / 2, d])
            sig, _ = launcher.launch(xs)
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


def robustness_ladder(launcher: shot.Launcher, launch, mask: int, *, lateral=LADDER_LATERAL_M,
                      speed=LADDER_SPEED_M_S) -> dict:
    """Cheap robustness for the atlas: the largest rung d of a doubling ladder at which the
    launches at -d and +d both keep ``mask``, by binary search over the rungs (4 checks of 2
    rollouts for 11 rungs: 8 rollouts an axis, 16 a shot; resolution a factor of 2).

    0.0 means even the smallest rung fails. Outcomes are chaotic: "these probes keep it",
    not "every smaller change keeps it" (a rung that passes can sit above one that fails).
    """
    launch = np.asarray(launch, dtype=float)
    out = {}
    for key, col, rungs in (("lateral_m", 0, np.asarray(lateral, float)), ("speed_m_s", 1, np.asarray(speed, float))):
        lo, hi, runs = -1, len(rungs), 0   # rung lo passes (-1: none), rung hi fails (len: beyond the top)
        while hi - lo > 1:
            mid = (lo + hi) // 2
            xs = np.repeat(launch[None, :], 2, axis=0)
            xs[:, col] += np.array([-rungs[mid], rungs[mid]])
            sig, _ = launcher.launch(xs)
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

