"""The one rollout-search engine: the paper's signature search, an archive, CMA-ES restarts.

Every search over rollouts in nbst (bowling's deck, the crash, a user's scene) is this one
object, in the shape of pycma's ask/tell::

    eng = Engine(dim, seed=1, max_rollouts=3000, blocks=[[0, 1, 2], [3, 4, 5]])
    while not eng.stop():
        U = eng.ask()                                # (B, dim) points of the unit cube
        sig, dist, cost = evaluate(U)                # the caller rolls them out and scores them
        eng.tell(U, sig, dist, cost)
    r = eng.result                                   # the best point, its signature, distance, ...

(:meth:`Engine.run` is that loop, with Ctrl-C caught.) The engine knows no physics: the caller
maps a unit-cube point to its problem (a delivery, driver intents, a body's initial velocity),
rolls it out and tells three numbers per point:

* the **signature** (int): what happened, one bit per *block* when the problem has per-body
  fates (the paper's i-acceptable: bit i set when body i meets its fates; the crash: one bit
  per vehicle), or any small integer naming the outcome (bowling: the mask of the pins down);
* the **distance** (int >= 0): 0 exactly when the point solves the problem; the best point is
  the one of lowest (distance, cost);
* the **cost** (float): orders points of equal distance (a soft part that sees near misses).

Optionally also a **cell** per point (the archive's key; default the signature: the crash
keys its archive by contact sequence), whether the point is **fine** (only fine-tuning is
left: the crash's contacts are right), a **payload** (anything: kept with the point and given
back in the result), and the **rollouts** the batch cost (ladder checks count).

What the engine does with them, in a fixed cycle:

1. **explore**: ``explore`` points (at most a quarter of the budget, at least one batch when the
   GA is on), each from ``init(engine)`` (default: uniform in the cube), in batches of
   ``batch`` (the first ones of ``explore_batches`` points each, when given: a problem whose
   first random point often solves it asks for one); ``init_done(engine)`` may end this phase
   early.
2. **the paper's GA** (when ``ga_batches`` > 0): ``ga_batches`` batches of children
   (``ga_fine`` when the best point is fine). A child comes from one of four operations,
   equally likely: *creep* (one block moved by a Gaussian step, its sigma drawn from
   ``creep``), *directed randomize* (``moves["directed"](engine, u, block)``, the problem's
   aim; uniform when none is given), *uniform randomize* (one block drawn anew), and
   *crossover*: the second parent is the one (Senate-like among those) whose signature ORed
   with the first's sets the most bits, and the child takes each **whole block** from the
   parent that meets that block's bit when exactly one does, else from either at random (the
   paper's "genetically engineered" child). Parents are chosen Senate-like: every order
   (bits set) alike, every signature of that order alike, then a member (the best of
   ``tournament`` drawn from it; default 1: any member). A changed block is
   one whose bit the parent misses, half the time, when ``prefer_unmet``.
   **Insert**: a child with the signature of a parent replaces it, unless that parent is the
   best of its signature and the child is no better; else it joins, the worst of its signature
   leaving past ``per_signature``; past ``population`` the lowest-order signatures subsumed by
   higher-order ones are culled (never the best's), then the worst.
3. **one CMA-ES restart** (pycma, when ``cma``; imported when the first restart starts),
   population ``popsize``, in the unit cube, ending after ``stall`` generations without a lower
   cost. Where it starts and its step:

   * the best point is **fine** (polishing): from the best, at ``sigma0`` times ``polish[k]``
     in turn; once ``spent`` polishing restarts in a row left the best's cost as it was, and
     the best is farther than ``hold_distance`` (a best that near is polished where it is: the
     crash's met-but-fragile trial), from the cheapest other fine point at least one ``sigma0``
     step (``sigma0 sqrt(dim)``) from every polishing start so far (another funnel), at
     ``sigma0``; with none and ``wander``, from the cheapest point told that is not fine and
     lies that far from every polishing start (a new funnel is looked for), at ``sigma0``.
     With ``spent_gain`` g, a polishing restart counts as spent unless it lowered the best's
     cost below (1 - g) times what it was (g = 0: any lowering is progress; g = 1: only a
     solution is);
   * else ``schedule[k]`` in turn, each ``(source, factor)``: source ``"best"`` (the best
     point) or ``"cell"`` (the elite, lowest (distance, cost), of the archive's cell nearest
     the goal and not a start yet; once every cell has been one, the cycle begins again),
     step ``sigma0 * factor``. Nearest = lowest ``rank(cell)`` (default 0), then the elite's
     (distance, cost), then discovery order; a cell known only from :meth:`Engine.know` ranks
     by its ``prior(cell)``, a stand-in (distance, cost).

   Its points join the population too (with the start as their parent).
4. ``explore_between`` uniform points, then the cycle begins again at 2.

The **archive** keys every point told by its cell: the first point that gave it and its elite.
The search stops (:meth:`Engine.stop`, pycma's shape: a dict of reasons, empty while it goes
on) when ``done(engine)`` holds (default: the best point's distance is 0) -> ``"solved"``; at
the budget -> ``"budget"``; after Ctrl-C in :meth:`Engine.run` (or :meth:`Engine.interrupt`)
-> ``"interrupted"``; with nothing to search (``dim`` 0, one point told) -> ``"nothing_to_search"``.

Reproducible: every random number comes from one ``numpy.random.Generator`` (``nbst.seeds``)
in a fixed order, pycma gets seeds drawn from it, and batches have sizes that depend on the
engine's state alone (never on threads): the same seed and the same answers give the same
points.

Compute only: no files, no printing, no MuJoCo.

Length: the one rollout-search engine (exploration, the block GA, the archive and the CMA-ES
restart phase) in one ask/tell object, by design: the rule is that no second loop exists
anywhere.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Callable, Hashable, Sequence

import numpy as np

from nbst.errors import InputError, SolveError
from nbst.seeds import check_random_state

__all__ = ["BATCH", "EXPLORE", "GA_BATCHES", "GA_FINE", "POPULATION", "PER_SIGNATURE", "CREEP", "SIGMA0", "STALL",
           "SCHEDULE", "POLISH", "SPENT", "RIGHT_KEPT", "Member", "EngineResult", "Engine", "evolution_strategy"]

#: Points per batch (fixed: results do not depend on the threads that run them).
BATCH = 16
#: Points of the first, exploring phase (at most a quarter of the budget).
EXPLORE = 64
#: GA batches between CMA-ES restarts, and when the best point is fine (only fine-tuning left).
GA_BATCHES, GA_FINE = 3, 1
#: The paper's limits: members past which subsumed signatures are culled, members per signature.
POPULATION, PER_SIGNATURE = 64, 8
#: Creep: the Gaussian steps (unit cube) of one block, one drawn per child.
CREEP = (0.05,)
#: CMA-ES: initial step (unit cube), generations without a lower cost that end a restart.
SIGMA0, STALL = 0.12, 6
#: Restarts while the best point is not fine: (source, factor of sigma0), in turn.
SCHEDULE = (("best", 1.0), ("cell", 1.0 / 3.0))
#: Polishing restarts (the best point fine): factors of sigma0, in turn.
POLISH = (1.0, 1.0 / 3.0, 1.0 / 9.0)
#: Polishing restarts in a row that leave the best's cost as it was before one starts in another
#: funnel, and the fine points kept as such starts (the cheapest).
SPENT, RIGHT_KEPT = 3, 256


def evolution_strategy(x0, sigma0: float, *, popsize: int, seed: int, stds=None):
    """A CMA-ES in pycma's ask/tell shape (``ask``, ``tell``, ``result``), started as the rooms'
    stages that climb a noisy score start it (the crash's soft climb, :mod:`.crash.slack`): pycma
    is imported here, in the engine, and nowhere else in the rollout rooms.

    Args:
        x0: the starting mean.
        sigma0: the initial step.
        popsize: candidates per generation.
        seed: pycma's seed (a whole number >= 1).
        stds: per-coordinate scales of the step (pycma's ``CMA_stds``), or None.

    Returns:
        A ``cma.CMAEvolutionStrategy``.
    """
    import cma

    opts = {"popsize": int(popsize), "seed": int(seed), "verbose": -9}
    if stds is not None:
        opts["CMA_stds"] = stds
    return cma.CMAEvolutionStrategy(x0, sigma0, opts)


def _order(sig: int) -> int:
    return int(sig).bit_count()


@dataclass(eq=False)
class Member:
    """A point told to the engine, with what the caller said of it.

    Args:
        u: (dim,) float64, the unit-cube point.
        signature: its signature.
        distance: its distance (0: solves).
        cost: its cost.
        cell: its archive key.
        fine: only fine-tuning left.
        payload: the caller's object (a rollout, a trial), or None.
        index: the rollouts spent when it was told (1-based: the first point is 1).
    """

    u: np.ndarray
    signature: int
    distance: int
    cost: float
    cell: Hashable
    fine: bool = False
    payload: Any = field(default=None, repr=False)
    index: int = 0

    @property
    def key(self) -> tuple[int, float]:
        """The order of points: (distance, cost), lower is better."""
        return (self.distance, self.cost)


@dataclass
class EngineResult:
    """What the search found and how it went (:attr:`Engine.result`).

    Args:
        best: the best :class:`Member` (lowest (distance, cost)); None before any point was told.
        rollouts: rollouts spent (what ``tell`` was told they cost).
        restarts: CMA-ES restarts begun.
        stopped: :meth:`Engine.stop`'s reasons ({} while it goes on).
        archive: cell -> its elite :class:`Member`, in discovery order.
        first: cell -> the first unit point that gave it.
        history: (rollouts, best distance, best cost) after each ``tell``.

    Returns:
        The result (``x``, ``signature``, ``distance``, ``cost``, ``payload``: the best's).
    """

    best: Member | None
    rollouts: int
    restarts: int
    stopped: dict
    archive: dict
    first: dict
    history: list

    @property
    def x(self) -> np.ndarray:
        """The best unit-cube point."""
        return self._best().u

    @property
    def signature(self) -> int:
        return self._best().signature

    @property
    def distance(self) -> int:
        return self._best().distance

    @property
    def cost(self) -> float:
        return self._best().cost

    @property
    def payload(self) -> Any:
        return self._best().payload

    def _best(self) -> Member:
        if self.best is None:
            raise SolveError("the search told no point yet: it has no best")
        return self.best


class Engine:
    """The rollout search (module docstring): ask for points, tell their outcomes, stop, result.

    Args:
        dim: coordinates of the unit cube (0: nothing to search; one point is asked).
        seed: an integer seed or a ``numpy.random.Generator`` (``nbst.seeds.check_random_state``).
        max_rollouts: the budget, in rollouts (>= 1).
        blocks: the coordinates of each block (default: one block of all ``dim``): crossover
            swaps whole blocks, creep and randomize change one block.
        bits: the signature bit of each block (None: the block's body has none); default: bit
            i for block i.
        batch: points per batch.
        explore: points of the exploring phase (capped at a quarter of the budget).
        explore_batches: the sizes of the exploring phase's first batches, in turn (each at most
            ``batch``), then ``batch`` (default (): every batch ``batch``).
        init: ``init(engine) -> (dim,) unit point`` for the exploring phase (default: uniform).
        init_done: ``init_done(engine) -> bool`` ends the exploring phase early (default: never).
        ga_batches, ga_fine: GA batches per cycle (0: no GA, no population), and when the best
            point is fine.
        moves: the problem's moves by name; ``"directed"``: ``move(engine, u, block)`` changes
            the block of the (dim,) unit point ``u`` in place (the paper's directed randomize).
        creep: the creep's Gaussian steps (unit cube), one drawn per child.
        prefer_unmet: a child changes a block whose bit its parent misses, half the time.
        redraw_unmet: the share of randomizing children (directed or uniform) that redraw every
            block whose bit their parent misses, when it misses two or more, instead of one block:
            bodies that do not meet each other are then searched side by side, each rollout a
            try for each (default 0: one block, the paper's rule).
        population, per_signature: the GA's limits.
        cma: CMA-ES restarts (pycma) in each cycle.
        popsize: the CMA-ES population (default ``batch``).
        sigma0, stall, schedule, polish, spent, right_kept, hold_distance, spent_gain, wander:
            the restarts (module docstring; ``spent_gain`` 0 and ``wander`` False: a spent
            funnel with no other fine point is polished again).
        explore_between: uniform points after each restart.
        rank: ``rank(cell) -> float``: how far a cell is from the goal (lower first), or None.
        done: ``done(engine) -> bool``: the search is over (default: the best's distance is 0).
        tournament: a parent is the best (lowest ``key``) of this many members drawn from its
            signature (default 1: one member at random; the scene's search uses 2).
        cma_by_key: CMA-ES ranks a generation by (distance, cost), the engine's order, instead of
            by cost alone, and a restart stalls on that order (default False: by cost; the scene's
            search of one block uses True).

    Returns:
        The engine, before its first ``ask``.

    Raises:
        InputError: ``max_rollouts`` under 1, ``dim`` negative, a block naming a coordinate out
            of range, ``bits`` not one per block, an empty ``schedule``/``polish``, a source other
            than "best" or "cell", or a seed that is not one.
    """

    def __init__(self, dim: int, *, seed: int | np.random.Generator, max_rollouts: int,
                 blocks: Sequence[Sequence[int]] | None = None, bits: Sequence[int | None] | None = None,
                 batch: int = BATCH, explore: int = EXPLORE, explore_batches: Sequence[int] = (),
                 init: Callable[[Engine], np.ndarray] | None = None,
                 init_done: Callable[[Engine], bool] | None = None, ga_batches: int = GA_BATCHES,
                 ga_fine: int = GA_FINE, moves: dict[str, Callable] | None = None,
                 creep: Sequence[float] = CREEP, prefer_unmet: bool = False, redraw_unmet: float = 0.0,
                 population: int = POPULATION,
                 per_signature: int = PER_SIGNATURE, cma: bool = True, popsize: int | None = None,
                 sigma0: float = SIGMA0, stall: int = STALL, schedule: Sequence[tuple[str, float]] = SCHEDULE,
                 polish: Sequence[float] = POLISH, spent: int = SPENT, right_kept: int = RIGHT_KEPT,
                 hold_distance: int = 1, spent_gain: float = 0.0, wander: bool = False, explore_between: int = 0,
                 rank: Callable[[Hashable], float] | None = None,
                 done: Callable[[Engine], bool] | None = None, tournament: int = 1, cma_by_key: bool = False):
        if isinstance(max_rollouts, bool) or not isinstance(max_rollouts, (int, np.integer)) or max_rollouts < 1:
            raise InputError(f"max_rollouts must be a whole number of at least 1, got {max_rollouts!r}")
        if isinstance(dim, bool) or not isinstance(dim, (int, np.integer)) or dim < 0:
            raise InputError(f"dim must be a whole number of at least 0, got {dim!r}")
        self.dim, self.max_rollouts = int(dim), int(max_rollouts)
        self.rng = check_random_state(seed)
        self.blocks = [np.arange(self.dim)] if blocks is None else [np.asarray(b, dtype=np.int64) for b in blocks]
        for b in self.blocks:
            if b.size and (b.min() < 0 or b.max() >= self.dim):
                raise InputError(f"blocks must name coordinates 0..{self.dim - 1}, got {b.tolist()}")
        self.bits = list(range(len(self.blocks))) if bits is None else list(bits)
        if len(self.bits) != len(self.blocks):
            raise InputError(f"bits must give one bit (or None) per block: {len(self.blocks)} blocks, "
                             f"{len(self.bits)} bits")
        if not schedule or not polish:
            raise InputError("schedule and polish must each hold at least one entry")
        for src, _ in schedule:
            if src not in ("best", "cell"):
                raise InputError(f"a schedule's source must be 'best' or 'cell', got {src!r}")
        self.batch, self.explore = int(batch), int(explore)
        if any(int(k) < 1 for k in explore_batches):
            raise InputError(f"explore_batches must be whole numbers of at least 1, got {list(explore_batches)!r}")
        self._explore_sizes = [min(int(k), self.batch) for k in explore_batches]
        self.init, self.init_done = init, init_done
        self.ga_batches, self.ga_fine = int(ga_batches), int(ga_fine)
        self.moves = dict(moves or {})
        self.creep, self.prefer_unmet = tuple(float(c) for c in creep), bool(prefer_unmet)
        if not 0.0 <= float(redraw_unmet) <= 1.0:
            raise InputError(f"redraw_unmet must be in [0, 1], got {redraw_unmet!r}")
        self.redraw_unmet = float(redraw_unmet)
        self.population_max, self.per_signature = int(population), int(per_signature)
        self.use_cma, self.popsize = bool(cma), int(popsize or batch)
        self.sigma0, self.stall = float(sigma0), int(stall)
        self.schedule, self.polish = [(s, float(f)) for s, f in schedule], [float(f) for f in polish]
        self.spent_max, self.right_kept, self.hold_distance = int(spent), int(right_kept), int(hold_distance)
        if not 0.0 <= float(spent_gain) <= 1.0:
            raise InputError(f"spent_gain must be in [0, 1], got {spent_gain!r}")
        self.spent_gain, self.wander = float(spent_gain), bool(wander)
        self.explore_between = int(explore_between)
        self.rank, self.done = rank, done
        self.tournament = max(1, int(tournament))
        self.cma_by_key = bool(cma_by_key)
        # state
        self.rollouts = 0
        self.restarts = 0
        self.population: list[Member] = []
        self.best: Member | None = None
        self.archive: dict[Hashable, Member] = {}     # cell -> elite
        self.first: dict[Hashable, np.ndarray] = {}   # cell -> first unit point
        self.known: dict[Hashable, tuple[np.ndarray, tuple]] = {}  # cell -> (unit point, prior key): know()
        self.order: dict[Hashable, int] = {}          # cell -> discovery index
        self.history: list[tuple[int, int, float]] = []
        self.right: list[Member] = []                 # fine points (the cheapest right_kept)
        self.wrong: list[tuple[tuple, np.ndarray]] = []  # with wander: (key, unit point) of every point not fine
        self._starts: list[np.ndarray] = []           # polishing restarts' starts
        self._spent = 0
        self._polishes = 0
        self._used: set = set()                       # cells that started a restart this cycle of cells
        self._interrupted = False
        n0 = min(self.explore, self.max_rollouts // 4)
        if self.ga_batches > 0 and self.dim > 0:
            n0 = max(n0, min(self.batch, self.max_rollouts))
        self._explore_left = n0 if self.dim > 0 else 1
        self._phase = "explore"
        self._ga_left = 0
        self._between_left = 0
        self._es: Any = None
        self._es_state: dict = {}
        self._pending: tuple[np.ndarray, str, list] | None = None

    # -- the problem's view -----------------------------------------------------------
    @property
    def left(self) -> int:
        """Rollouts left in the budget."""
        return self.max_rollouts - self.rollouts

    def know(self, cells: dict, prior: Callable[[Hashable], tuple[float, float]] | None = None) -> None:
        """Cells known before the search ({cell: (dim,) unit point}, e.g. an atlas's): restart
        points, ranked among the told cells as if their elite's (distance, cost) were
        ``prior(cell)`` (default (inf, inf): after every told cell), until a point of theirs is told.

        Args:
            cells: cell -> (dim,) unit point, in discovery order.
            prior: a known cell's stand-in (distance, cost).

        Returns:
            None.
        """
        for c, u in cells.items():
            if c not in self.known and c not in self.archive:
                key = (math.inf, math.inf) if prior is None else tuple(float(v) for v in prior(c))
                self.known[c] = (np.asarray(u, dtype=float).copy(), key)
                self.order.setdefault(c, len(self.order))

    def interrupt(self) -> None:
        """Mark the search interrupted (Ctrl-C): :meth:`stop` says so from now on."""
        self._interrupted = True

    # -- ask --------------------------------------------------------------------------
    def ask(self) -> np.ndarray:
        """The next batch of points to roll out.

        Returns:
            (B, dim) float64 unit-cube points, 1 <= B <= ``batch`` (``popsize`` in a CMA-ES
            generation), never more than the budget left; (0, dim) once :meth:`stop` says stop.
        """
        if self.stop():
            return np.zeros((0, self.dim))
        n = min(self.batch, self.left)
        if self.dim == 0:
            return self._asked(np.zeros((1, 0)), "explore", [None])
        while True:
            if self._phase == "explore":
                if self._explore_left > 0:
                    k = min(self._explore_sizes.pop(0) if self._explore_sizes else n, n, self._explore_left)
                    U = np.array([self._init_point() for _ in range(k)]) if self.init is not None \
                        else self.rng.random((k, self.dim))
                    return self._asked(U, "explore", [None] * k)
                self._next_cycle()
                continue
            if self._phase == "ga":
                if self._ga_left > 0 and self.population:
                    kids = [self._child() for _ in range(n)]
                    return self._asked(np.array([k[0] for k in kids]), "ga", [k[1] for k in kids])
                if not self.population and self._ga_left > 0:  # nothing to breed: explore a batch
                    self._ga_left -= 1
                    return self._asked(self.rng.random((n, self.dim)), "explore", [None] * n)
                self._phase = "cma" if self.use_cma else "between"
                if self.use_cma and not self._start_restart():
                    self._phase = "between"
                continue
            if self._phase == "cma":
                xs = np.clip(np.asarray(self._es.ask(), dtype=np.float64), 0.0, 1.0)
                self._es_state["asked"] = xs
                return self._asked(xs[:self.left], "cma", [self._es_state["start"]] * min(len(xs), self.left))
            if self._phase == "between":
                if self._between_left > 0:
                    k = min(n, self._between_left)
                    return self._asked(self.rng.random((k, self.dim)), "between", [None] * k)
                self._next_cycle()
                continue
            raise SolveError(f"the engine is in no known phase: {self._phase!r}")  # pragma: no cover

    def _asked(self, U: np.ndarray, phase: str, parents: list) -> np.ndarray:
        U = np.asarray(U, dtype=float)
        self._pending = (U.copy(), phase, parents)
        return U

    def _init_point(self) -> np.ndarray:
        assert self.init is not None
        return np.clip(np.asarray(self.init(self), dtype=float), 0.0, 1.0)

    def _next_cycle(self) -> None:
        """Start a cycle: the GA's batches (or straight to a restart without a GA)."""
        if self.ga_batches > 0:
            self._phase = "ga"
            self._ga_left = self.ga_fine if (self.best is not None and self.best.fine) else self.ga_batches
        elif self.use_cma:
            self._phase = "cma"
            if not self._start_restart():
                self._phase = "between"
                self._between_left = max(self.explore_between, self.popsize)
        else:
            self._phase = "between"
            self._between_left = max(self.explore_between, self.batch)

    # -- the paper's GA ---------------------------------------------------------------
    def _senate(self, pool: list[Member]) -> Member:
        orders = sorted({_order(m.signature) for m in pool})
        o = orders[int(self.rng.integers(len(orders)))]
        sigs = sorted({m.signature for m in pool if _order(m.signature) == o})
        s = sigs[int(self.rng.integers(len(sigs)))]
        members = [m for m in pool if m.signature == s]
        if self.tournament > 1:  # the best of a few drawn from the signature
            return min((members[int(k)] for k in self.rng.integers(len(members), size=self.tournament)),
                       key=lambda m: m.key)
        return members[int(self.rng.integers(len(members)))]

    def _met(self, m: Member, i: int) -> bool:
        b = self.bits[i]
        return b is not None and bool(m.signature >> b & 1)

    def _block_to_change(self, parent: Member) -> int:
        if self.prefer_unmet:
            unmet = [i for i in range(len(self.blocks)) if not self._met(parent, i)]
            if unmet and self.rng.random() < 0.5:
                return unmet[int(self.rng.integers(len(unmet)))]
        return int(self.rng.integers(len(self.blocks)))

    def _child(self) -> tuple[np.ndarray, list[Member]]:
        op = int(self.rng.integers(4))
        a = self._senate(self.population)
        u = a.u.copy()
        if op == 3 and len(self.population) > 1:
            others = [m for m in self.population if m is not a]
            best_or = max(_order(a.signature | m.signature) for m in others)
            b = self._senate([m for m in others if _order(a.signature | m.signature) == best_or])
            for i, blk in enumerate(self.blocks):
                ma, mb = self._met(a, i), self._met(b, i)
                src = a if ma and not mb else b if mb and not ma else (a if self.rng.random() < 0.5 else b)
                u[blk] = src.u[blk]
            return u, [a, b]
        if op in (1, 2) and self.redraw_unmet > 0.0:
            unmet = [i for i in range(len(self.blocks)) if self.bits[i] is not None and not self._met(a, i)]
            if len(unmet) > 1 and self.rng.random() < self.redraw_unmet:
                for i in unmet:
                    self._randomize(u, i, op)
                return np.clip(u, 0.0, 1.0), [a]
        i = self._block_to_change(a)
        if op in (1, 2):
            self._randomize(u, i, op)
        else:  # creep (and crossover with one member)
            blk = self.blocks[i]
            s = self.creep[int(self.rng.integers(len(self.creep)))] if len(self.creep) > 1 else self.creep[0]
            u[blk] += s * self.rng.standard_normal(len(blk))
        return np.clip(u, 0.0, 1.0), [a]

    def _randomize(self, u: np.ndarray, i: int, op: int) -> None:
        """Block ``i`` of ``u`` in place: the problem's directed randomize (op 1, where it has one), else
        uniform randomize."""
        if op == 1 and "directed" in self.moves:
            self.moves["directed"](self, u, i)
        else:
            blk = self.blocks[i]
            u[blk] = self.rng.random(len(blk))

    def _insert(self, child: Member, parents: list[Member]) -> None:
        same = [p for p in parents if p.signature == child.signature and any(p is m for m in self.population)]
        if same:
            p = same[0] if len(same) == 1 else same[int(self.rng.integers(len(same)))]
            best_of = min((m for m in self.population if m.signature == p.signature), key=lambda m: m.key)
            if not (p is best_of and child.key >= p.key):
                self.population[next(k for k, m in enumerate(self.population) if m is p)] = child
                return
        self.population.append(child)
        mine = [m for m in self.population if m.signature == child.signature]
        if len(mine) > self.per_signature:
            worst = max((m for m in mine if m is not self.best), key=lambda m: m.key, default=None)
            if worst is not None:
                self.population = [m for m in self.population if m is not worst]
        if len(self.population) > self.population_max:
            self._cull()

    def _cull(self) -> None:
        keep = self.best.signature if self.best is not None else None
        sigs = sorted({m.signature for m in self.population}, key=_order)
        for s in sigs:
            if s == keep:
                continue
            covered = 0
            for h in sigs:
                if _order(h) > _order(s):
                    covered |= h
            if s & ~covered == 0:
                self.population = [m for m in self.population if m.signature != s]
                if len(self.population) <= self.population_max:
                    return
        if len(self.population) > self.population_max:  # nothing subsumed left: the worst go
            self.population.sort(key=lambda m: (m is not self.best, -_order(m.signature), m.key))
            del self.population[self.population_max:]

    # -- CMA-ES restarts --------------------------------------------------------------
    def nearest(self) -> list:
        """Archived and known cells, nearest the goal first (``rank``, the elite's (distance,
        cost), discovery order), without those that started a restart in this cycle of cells."""
        def key(c):
            r = float(self.rank(c)) if self.rank is not None else 0.0
            e = self.archive.get(c)
            k = e.key if e is not None else self.known[c][1]
            return (r, k, self.order[c])
        cells = [c for c in list(self.archive) + [c for c in self.known if c not in self.archive]
                 if c not in self._used]
        return sorted(cells, key=key)

    def _cell_start(self, c) -> np.ndarray:
        e = self.archive.get(c)
        return e.u if e is not None else self.known[c][0]

    def restart_point(self) -> tuple[np.ndarray, float, Member | None]:
        """Where the next CMA-ES restart starts and its step (module docstring), and the member
        it starts from (None: a known cell's point). Advances the schedule.

        Returns:
            ((dim,) unit point, sigma, member or None).
        """
        best = self.best
        if best is not None and best.fine:
            sigma = self.sigma0 * self.polish[self._polishes % len(self.polish)]
            start: Member | None = best
            if self._spent >= self.spent_max and best.distance > self.hold_distance:
                spread = self.sigma0 * math.sqrt(self.dim)
                far = [m for m in sorted(self.right, key=lambda m: m.key)
                       if all(np.linalg.norm(m.u - p) >= spread for p in self._starts)]
                if far:
                    start, sigma = far[0], self.sigma0
                elif self.wander:  # no other funnel known: look for one from the cheapest point far from them
                    out = [(k, u) for k, u in self.wrong if all(np.linalg.norm(u - p) >= spread for p in self._starts)]
                    if out:
                        u = min(out, key=lambda t: t[0])[1]
                        self._starts.append(u)
                        self._polishes += 1
                        return u, self.sigma0, None
            assert start is not None
            self._starts.append(start.u)
            self._polishes += 1
            return start.u, sigma, start
        src, factor = self.schedule[self.restarts % len(self.schedule)]
        if src == "cell":
            order = self.nearest()
            if not order and self._used:
                self._used.clear()
                order = self.nearest()
            if order:
                c = order[0]
                self._used.add(c)
                return self._cell_start(c), self.sigma0 * factor, self.archive.get(c)
        if best is None:
            raise SolveError("a CMA-ES restart needs a point to start from: none was told")
        return best.u, self.sigma0 * factor, best

    def _start_restart(self) -> bool:
        """Begin a CMA-ES restart; False when there is nothing to start from."""
        if self.best is None and not self.known:
            return False
        import cma

        u, sigma, start = self.restart_point()
        polishing = self.best is not None and self.best.fine
        self._es = cma.CMAEvolutionStrategy(np.asarray(u, dtype=float).tolist(), sigma,
                                            {"bounds": [0.0, 1.0], "popsize": self.popsize, "verbose": -9,
                                             "seed": int(self.rng.integers(1, 2**31 - 1))})
        self._es_state = {"start": start, "best_here": math.inf, "stalled": 0, "polishing": polishing,
                          "before": self.best.cost if self.best is not None else math.inf}
        self.restarts += 1
        return True

    def _end_restart(self) -> None:
        st = self._es_state
        if st.get("polishing") and self.best is not None:
            lowered = self.best.cost < (1.0 - self.spent_gain) * st["before"] - 1e-9 if self.spent_gain < 1.0 else False
            self._spent = 0 if lowered else self._spent + 1
        self._es = None
        self._phase = "between"
        self._between_left = self.explore_between

    # -- tell -------------------------------------------------------------------------
    def tell(self, X, signatures, distances, costs, *, cells: Sequence | None = None, fine: Sequence | None = None,
             payloads: Sequence | None = None, rollouts: int | None = None) -> list[Member]:
        """Tell the outcomes of points (those asked last, or any others: they join as parentless).

        Args:
            X: (B, dim) unit-cube points, B >= 0: the last ``ask``'s (or a prefix of them).
            signatures: (B,) ints.
            distances: (B,) ints >= 0 (0: solves).
            costs: (B,) floats.
            cells: (B,) hashable archive keys (default: the signatures).
            fine: (B,) bools: only fine-tuning left (default: False).
            payloads: (B,) objects kept with the points (default: None).
            rollouts: the rollouts these cost (default B; ladder checks add to it).

        Returns:
            The B :class:`Member` made, in order.

        Raises:
            InputError: the arrays disagree in length, or a point is not (dim,).
        """
        X = np.asarray(X, dtype=float)
        X = X.reshape(len(X), self.dim) if X.ndim == 2 else X.reshape(-1, self.dim)
        B = len(X)
        sigs, dist, cost = list(signatures), list(distances), list(costs)
        cells = sigs if cells is None else list(cells)
        fine = [False] * B if fine is None else list(fine)
        payloads = [None] * B if payloads is None else list(payloads)
        if not all(len(a) == B for a in (sigs, dist, cost, cells, fine, payloads)):
            raise InputError(f"tell needs one signature, distance, cost (and cell, fine, payload) per point: "
                             f"{B} points")
        phase, parents = "told", [None] * B
        if self._pending is not None:
            P, ph, par = self._pending
            if B <= len(P) and np.array_equal(X, P[:B]):
                phase, parents = ph, par[:B]
            self._pending = None
        spent = B if rollouts is None else int(rollouts)
        made = []
        for i in range(B):
            m = Member(u=X[i].copy(), signature=int(sigs[i]), distance=int(dist[i]), cost=float(cost[i]),
                       cell=cells[i], fine=bool(fine[i]), payload=payloads[i],
                       index=self.rollouts + i + 1)
            made.append(m)
            c = m.cell
            if c not in self.first:
                self.first[c] = m.u.copy()
                self.order.setdefault(c, len(self.order))
            if c not in self.archive or m.key < self.archive[c].key:
                self.archive[c] = m
            if m.fine:
                self.right.append(m)
            elif self.wander:
                self.wrong.append((m.key, m.u))
            if self.best is None or m.key < self.best.key:
                self.best = m
        self.rollouts += spent
        if len(self.right) > 2 * self.right_kept:
            self.right.sort(key=lambda m: m.key)
            del self.right[self.right_kept:]
        if self.ga_batches > 0:
            for m, p in zip(made, parents):
                if phase == "ga" and p is not None:
                    self._insert(m, list(p))
                elif phase == "cma" and p is not None:
                    self._insert(m, [p])
                else:
                    self._insert(m, [])
        if B and self.best is not None:
            self.history.append((self.rollouts, self.best.distance, self.best.cost))
        self._advance(phase, made)
        return made

    def _advance(self, phase: str, made: list[Member]) -> None:
        B = len(made)
        if phase == "explore" and self._phase == "explore":
            self._explore_left -= B
            if self.init_done is not None and self._explore_left > 0 and self.init_done(self):
                self._explore_left = 0
        elif phase == "ga" and self._phase == "ga":
            self._ga_left -= 1
        elif phase == "between" and self._phase == "between":
            self._between_left -= B
        elif phase == "cma" and self._phase == "cma" and self._es is not None:
            st = self._es_state
            asked = st.get("asked")
            if asked is None or B < len(asked):  # cut by the budget: not told to pycma
                self._end_restart()
                return
            if self.cma_by_key:  # pycma ranks its generation: tell it the ranks of (distance, cost)
                order = sorted(range(B), key=lambda k: made[k].key)
                ranks = [0.0] * B
                for r, k in enumerate(order):
                    ranks[k] = float(r)
                self._es.tell(asked.tolist(), ranks)
                low = made[order[0]].key
                bh = st["best_here"]
                if bh == math.inf or low[0] < bh[0] or (low[0] == bh[0] and low[1] < bh[1] - 1e-9):
                    st["best_here"], st["stalled"] = low, 0
                else:
                    st["stalled"] += 1
            else:
                costs = [m.cost for m in made]
                self._es.tell(asked.tolist(), costs)
                if min(costs) < st["best_here"] - 1e-9:
                    st["best_here"], st["stalled"] = min(costs), 0
                else:
                    st["stalled"] += 1
            if st["stalled"] >= self.stall:
                self._end_restart()

    # -- stop, result, run ------------------------------------------------------------
    def stop(self) -> dict:
        """Why the search is over, pycma's way: {} while it goes on, else the reasons, any of
        ``"solved"`` (rollouts when it was), ``"budget"`` (the budget), ``"interrupted"`` (True),
        ``"nothing_to_search"`` (``dim`` 0 and its one point told).

        Returns:
            dict of reasons.
        """
        out: dict[str, Any] = {}
        if self.best is not None:
            if self.done(self) if self.done is not None else self.best.distance == 0:
                out["solved"] = self.rollouts
        if self.rollouts >= self.max_rollouts:
            out["budget"] = self.max_rollouts
        if self._interrupted:
            out["interrupted"] = True
        if self.dim == 0 and self.best is not None:
            out["nothing_to_search"] = True
        return out

    @property
    def result(self) -> EngineResult:
        """The best point so far and how the search went (:class:`EngineResult`)."""
        return EngineResult(best=self.best, rollouts=self.rollouts, restarts=self.restarts, stopped=self.stop(),
                            archive=dict(self.archive), first=dict(self.first), history=list(self.history))

    def run(self, evaluate: Callable[[np.ndarray], Any], callback: Callable[[Engine], object] | None = None) \
            -> EngineResult:
        """Ask, evaluate, tell until :meth:`stop`; Ctrl-C (KeyboardInterrupt) stops it with the
        best so far (``"interrupted"``).

        Args:
            evaluate: ``evaluate((B, dim) unit points)`` -> ``(signatures, distances, costs)``,
                or a dict of :meth:`tell`'s arguments (``signatures``, ``distances``, ``costs``
                and any of ``cells``, ``fine``, ``payloads``, ``rollouts``).
            callback: None, or ``callback(engine)`` after each ``tell``.

        Returns:
            :attr:`result`.

        Raises:
            KeyboardInterrupt: Ctrl-C before any point was told (there is no best to return).
        """
        try:
            while not self.stop():
                U = self.ask()
                out = evaluate(U)
                if isinstance(out, dict):
                    self.tell(U, **out)
                else:
                    self.tell(U, *out)
                if callback is not None:
                    callback(self)
        except KeyboardInterrupt:
            self.interrupt()
            if self.best is None:
                raise
        return self.result
