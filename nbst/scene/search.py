"""The paper's per-body signature search, carried to the free bodies of any scene, on the one
rollout-search engine (``nbst.models.mjsearch.engine.Engine``: pycma's ask/tell).

A trial is a controls vector, kept in the unit cube (coordinate k maps to ``lo[k] + u[k] (hi[k] -
lo[k])``), cut into **blocks**, one per controlled body. Its **signature** holds one bit per body
with fates: set when all of that body's fates are met (``nbst.scene.judge``). This module knows the
scene; the engine does the rest, as in the paper (docs/scene.md, "The search"). Length: the scene's
moves (each aim beside the others) and the search's set-up are one account of the paper's algorithm
on a scene; split, an aim would be read apart from the move that draws it.

* **initialize** (the engine's exploring phase): random trials (each block by *directed* or
  *uniform randomize*, even odds) until every bit is set in at least :data:`INIT_PER_BIT` members,
  or after :data:`INIT_MAX` rollouts (a tenth of the budget at most);
* **generate** (the engine's GA): *creep* (one block perturbed by a normal step of sigma 0.01,
  0.04 or 0.15 of the range), *directed randomize* (this module's aim), *uniform randomize*,
  *crossover* of whole per-body blocks; Senate-like parents (the better of two members drawn from
  the signature chosen); a changed block is an unmet body's
  half the time, and a randomizing child of a parent that misses two or more bodies redraws all of
  them (:data:`REDRAW_UNMET`; the paper changes one disk: independent bodies are searched side by
  side, each rollout a try for each);
* **insert**: the paper's elitism, :data:`PER_SIGNATURE` members per signature, subsumed signatures
  culled past :data:`POPULATION`;
* **one controlled body** (one block: crossover has nothing to swap, and the GA's uniform
  randomize of the only block is a fresh random trial): no GA; :data:`ONE_BODY_EXPLORE` exploring
  trials (the first in batches of :data:`ONE_BODY_EXPLORE_BATCHES`: the search stops at the
  first batch that holds a solution, and a scene whose random trial often solves it, as
  dominoes, should not roll out 8 to find one), then the engine's CMA-ES restarts (population
  :data:`ONE_BODY_POPSIZE`) from the best
  trial, each generation ranked by (distance, cost) (the engine's ``cma_by_key``); a trial that
  meets every fate at h is *fine* (only the ladder is left): restarts then polish the best, and
  once three in a row leave it not kept on the ladder (:data:`ONE_BODY_SPENT_GAIN`: a lower
  graded cost of its rungs is not progress), start from the cheapest other such trial in
  another funnel, or, with none, from the cheapest trial not met at h that lies one step
  from every polishing start (a new funnel looked for; the engine's polishing,
  ``hold_distance=0``, ``wander``: a best met at h but not kept on the ladder is not polished
  for ever);
* **fixed coordinates** (a range of one value, as a rolling ball's vertical speed ``[0, 0]``) are
  not searched: the engine's cube has one dimension per live coordinate;
* the engine's **distance** of a trial is 3 per unmet bit plus, with a ladder (finer timesteps,
  h/2 and h/4), 1 when a trial that meets every fate misses them there (:func:`ladder_check`: h/2,
  then h/4 only if it held at h/2; those rollouts counted); its **cost** the judge's graded cost
  plus :data:`LADDER_PENALTY` per rung missed and each rung's own graded cost (at most
  :data:`LADDER_FAR`, and that for a rung not rolled out: how far the finer step is from meeting
  them, so that the search is drawn to motions that hold): the best is the lowest (distance,
  cost), and the search stops when it is 0 (every fate met, and kept on the ladder), or at the
  rollout budget. Asked for several answers, it goes on until that many
  rollouts meet every fate (and hold), each with a contact sequence of its own (Chenney & Forsyth
  2000: the animator chooses).

*Directed randomize* aims a body that has a place to be (``rest_in`` or ``at``) and may fly (no
component of its ``linvel`` held fixed): the velocity that would carry its origin ballistically
(the model's gravity, no contacts) to a point of the region in a random flight time (``at``: its
time). A body that may not fly (a ball rolling on a table, a pushed domino) and must hit something
is aimed in a straight line through its free components at a point within the two bounding radii
of its first ``hits`` name, at a speed its ranges allow. A body that may fly and must first hit
another body that may fly is aimed with it: both blocks redrawn, the two origins carried
ballistically to one point at one time (:meth:`_Scene._aim_meet`); such a pair is one block of the
engine's for creep, randomize and crossover (a nudge to one moves where both go after the touch),
and the GA's batches alternate with CMA-ES restarts from the best (ranked by distance, then cost). Half the time (and always for a body with
neither aim) it instead takes the block of the member whose body is nearest its fates and creeps it
(sigma 0.04), or, with no members yet, draws the block uniformly.

Children are made :data:`BATCH` at a time from one generator stream (``nbst.seeds``) and rolled out
on ``jobs`` threads: the result depends on the seed alone, never on ``jobs``. Ctrl-C stops the
search: the best trial so far is returned (``stopped="interrupted"``).
"""
from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from nbst.models.mjsearch.engine import Engine
from nbst.models.mjsearch.probability import Probability, normal_draws, perturb
from nbst.scene.aim import Pair, land_pair, pair_of
from nbst.scene.judge import signature_text
from nbst.scene.rollout import SceneRollout, SceneSim

__all__ = ["DEFAULT_MAX_ROLLOUTS", "BATCH", "POPULATION", "PER_SIGNATURE", "INIT_PER_BIT", "INIT_MAX", "CREEP",
           "LADDER_PENALTY", "LADDER_FAR", "ONE_BODY_EXPLORE", "ONE_BODY_EXPLORE_BATCHES", "ONE_BODY_POPSIZE",
           "ONE_BODY_SPENT_GAIN",
           "SceneProgress",
           "SceneSearchResult", "signature_search", "noisy_probability",
           "distance_of", "ladder_check"]

#: Draws of a meeting point and time for two bodies that must hit each other (``_Scene._aim_meet``).
MEET_DRAWS = 20
#: The rollout budget when none is given (the CLI's --max-rollouts default too).
DEFAULT_MAX_ROLLOUTS = 3000
#: Children made and rolled out together (fixed, so the result does not depend on the threads).
BATCH = 8
#: Members kept before the culling of subsumed signatures (the paper: 200).
POPULATION = 60
#: Members kept per signature (the paper: 10).
PER_SIGNATURE = 10
#: The cost added to a trial that meets every fate for each finer step (the ladder) where it does not.
LADDER_PENALTY = 0.01
#: A rung's graded cost counts at most this much in the cost of a trial that meets every fate at h.
LADDER_FAR = 10.0
#: The initialisation ends when every bit is set in this many members (the paper: 5) ...
INIT_PER_BIT = 3
#: ... or after this many rollouts (and at most a tenth of the budget).
INIT_MAX = 160
#: The creep's normal steps (unit cube), one drawn per child.
CREEP = (0.01, 0.04, 0.15)
#: Of the GA's randomizing children (directed or uniform), the share that redraw every block of an
#: unmet body of their parent, where it has two or more, in place of one (the paper changes one disk):
#: bodies that do not meet each other are searched side by side (the engine's ``redraw_unmet``).
REDRAW_UNMET = 1.0
#: One controlled body (one block: crossover has nothing to swap): exploring trials before the
#: engine's CMA-ES restarts, and their population.
ONE_BODY_EXPLORE, ONE_BODY_POPSIZE = 16, 12
#: One controlled body: the sizes of the first exploring batches (then :data:`BATCH`). The search
#: has no population to draw from while it explores, so the trials are those of batches of 8, in
#: the same order: a search not solved among them rolls out the same trials as with batches of 8.
ONE_BODY_EXPLORE_BATCHES = (1, 1, 2, 4)
#: One controlled body: a polishing restart that does not make the best hold on the ladder counts
#: as spent (the engine's ``spent_gain``: 1, only a solution is progress; the rungs' graded costs
#: fall by a few percent from restart to restart without a trial that holds).
ONE_BODY_SPENT_GAIN = 1.0


@dataclass(frozen=True)
class SceneProgress:
    """Where a search stands: rollouts so far, the best cost and signature, the population, and
    the phase (``"search"``; after it, what :func:`nbst.scene.solve` does next, in words: the
    probability's noisy rollouts, the robust maximiser)."""

    rollouts: int
    best_cost: float
    best_signature: str
    population: int
    signatures: int
    phase: str = "search"


@dataclass(frozen=True)
class SceneSearchResult:
    """What :func:`signature_search` returns.

    Args:
        best: the best rollout (all fates met when ``stopped == "met"``).
        rollouts: rollouts spent.
        stopped: ``"met"``, ``"budget"`` or ``"interrupted"``.
        wall_time: seconds.
        signatures: distinct signatures seen.
        answers: rollouts that meet every fate, each with a contact sequence of its own, in the
            order found (with ``answers`` > 1; else the best alone when it meets them).
        best_held: with a ladder, whether the best also meets every fate at the finer steps (None:
            no ladder, or the best does not meet them).
    """

    best: SceneRollout
    rollouts: int
    stopped: str
    wall_time: float
    signatures: int
    answers: tuple[SceneRollout, ...] = ()
    best_held: bool | None = None


def distance_of(r: SceneRollout, ladder_misses: int = 0) -> int:
    """The engine's distance of a rollout: 3 per unmet signature bit (every bit unmet when MuJoCo
    warned), plus 1 when a rollout that meets every fate misses them on the ladder (its misses
    and how far each rung is from meeting them go in the cost)."""
    return 3 * sum(1 for b in r.signature if not b) + (1 if ladder_misses else 0)


def ladder_check(x: np.ndarray, ladder: tuple[SceneSim, ...]) -> tuple[int, float, int]:
    """The ladder of a trial that meets every fate at h: its controls rolled out at each finer step
    in turn (h/2, then h/4 only if every fate held at h/2: a rung after a miss is not rolled out).

    Args:
        x: (D,) the controls vector.
        ladder: the sims at the finer steps, coarsest first.

    Returns:
        (misses, far, rollouts): the rungs missed (one not rolled out counts as missed), how far
        they are from meeting every fate (each rung's graded cost, at most :data:`LADDER_FAR`;
        ``LADDER_FAR`` for a rung not rolled out), and the rollouts spent.
    """
    far = 0.0
    for k, s in enumerate(ladder):
        q = s.rollout(x)
        far += min(q.cost, LADDER_FAR)
        if not (q.judgement.met and not q.warnings):
            rest = len(ladder) - k - 1
            return 1 + rest, far + LADDER_FAR * rest, k + 1
    return 0, far, len(ladder)


class _Scene:
    """What the engine asks of the scene: the unit cube, the aim, the rollouts and their verdicts."""

    def __init__(self, sim: SceneSim, want: int, ladder: tuple[SceneSim, ...]):
        f = sim.fates
        self.sim, self.fates, self.want, self.ladder = sim, f, want, ladder
        self.lo, self.hi = f.bounds()
        self.span = self.hi - self.lo
        self.blocks = f.blocks()
        #: the coordinates searched: those whose range is more than one value (the engine's unit
        #: cube has one dimension per live coordinate; a fixed one, as a planar shot's vertical
        #: speed ``[0, 0]``, is its value in every trial)
        self.live = np.flatnonzero(self.span > 0)
        pos = {int(k): j for j, k in enumerate(self.live)}
        #: per block: its live coordinates, as indices of the engine's cube
        self.engine_blocks = [[pos[k] for k in range(b.start, b.stop) if k in pos] for b in self.blocks]
        fated = [fa.body for fa in f.fates]
        #: per block: the signature bit of its body (None: the body has no fates)
        self.bit = [fated.index(c.body) if c.body in fated else None for c in f.controls]
        #: per block: its body may be aimed ballistically (every component of its linvel has a
        #: range: one held fixed, as a rolling ball's vertical speed [0, 0], forbids a flight)
        self.free_flight = []
        #: per block: where its linvel starts in the controls vector (None: no linvel controlled)
        self.linvel_at: list[int | None] = []
        for c, b in zip(f.controls, self.blocks):
            parts = [p for p, _ in c.parts()]
            a = b.start + 3 * parts.index("linvel") if "linvel" in parts else None
            self.linvel_at.append(a)
            self.free_flight.append(a is not None and bool(np.all(self.span[a:a + 3] > 0)))
        self.answers: dict[tuple[str, ...], SceneRollout] = {}
        self.pairs: dict[tuple[int, int], Pair] = {}  # (block, block) -> the pair that must meet
        self.held: dict[int, bool] = {}  # id(rollout) -> kept on the ladder
        self.seen: set[tuple[bool, ...]] = set()
        mid = (self.lo + self.hi) / 2
        q0, _ = sim.initial_state(mid)
        self.origin = [q0[qa:qa + 3].copy() for qa, _da in sim.adr]  # (the middle of a pos range is added)
        self.gravity = np.array(sim.model.opt.gravity, dtype=float)
        #: per block of a body that may not fly (a ball rolling on a table, a pushed domino): where the first
        #: name of its ``hits`` is at the start, and the sum of the two bounding radii (None: no ``hits``, a
        #: plane, or a body that may fly): the aim of directed randomize
        self.hit_target: list[tuple[np.ndarray, float] | None] = [None] * len(self.blocks)
        #: per block of a body that may fly whose first ``hits`` name is another body that may fly: that
        #: body's block (None: not so): directed randomize aims the two at one point at one time
        self.meet: list[int | None] = [None] * len(self.blocks)
        block_of = {c.body: k for k, c in enumerate(f.controls)}
        for i, bit in enumerate(self.bit):
            if bit is not None and f.fates[bit].hits and self.free_flight[i]:
                j = block_of.get(f.fates[bit].hits[0])
                if j is not None and j != i and self.free_flight[j]:
                    self.meet[i] = j
        for i, j in enumerate(self.meet):  # a pair that must meet is crept, redrawn and crossed over together
            if j is not None:
                both = sorted(set(self.engine_blocks[i]) | set(self.engine_blocks[j]))
                self.engine_blocks[i] = self.engine_blocks[j] = both
        if sim.near:
            import mujoco

            d = mujoco.MjData(sim.model)
            sim._reset(d)  # the keyframe's mocap poses too
            d.qpos[:] = q0
            mujoco.mj_kinematics(sim.model, d)
            for i, bit in enumerate(self.bit):
                if bit is None or not f.fates[bit].hits or f.controls[i].linvel is None or self.free_flight[i]:
                    continue
                for j, name, _a, other, centre, ra, rb in sim.near:
                    if j == bit and name == f.fates[bit].hits[0]:
                        at = d.xpos[sim.near_bodies[other]] if other >= 0 else centre
                        self.hit_target[i] = (np.array(at, dtype=float), float(ra + rb))

    def full(self, v: np.ndarray) -> np.ndarray:
        """The whole unit point of an engine point (a fixed coordinate at 0.5: its one value)."""
        u = np.full(len(self.lo), 0.5)
        u[self.live] = v
        return u

    def x_of(self, v: np.ndarray) -> np.ndarray:
        """The controls vector of an engine point (its live coordinates)."""
        return self.x_full(self.full(v))

    def x_full(self, u: np.ndarray) -> np.ndarray:
        """The controls vector of a whole unit point."""
        return self.lo + np.clip(u, 0.0, 1.0) * self.span

    def u_of(self, x: np.ndarray) -> np.ndarray:
        with np.errstate(divide="ignore", invalid="ignore"):
            u = np.where(self.span > 0, (x - self.lo) / np.where(self.span > 0, self.span, 1.0), 0.5)
        return np.asarray(np.clip(u, 0.0, 1.0))

    # -- the moves --------------------------------------------------------------------
    def directed(self, eng: Engine, v: np.ndarray, i: int) -> None:
        """Directed randomize of block ``i`` of the engine point ``v`` (in place; the module docstring)."""
        u = self.full(v)
        self._directed(eng, u, i)
        v[:] = u[self.live]

    def _directed(self, eng: Engine, u: np.ndarray, i: int) -> None:
        """Directed randomize of block ``i`` of the whole unit point ``u`` (in place)."""
        rng: np.random.Generator = eng.rng  # type: ignore[has-type]
        c, b = self.fates.controls[i], self.bit[i]
        fate = None if b is None else self.fates.fates[b]
        place = (fate is not None and c.linvel is not None and (fate.rest_in is not None or fate.at)
                 and self.free_flight[i])
        hit = self.hit_target[i]
        meet = self.meet[i]
        aimable = place or hit is not None or meet is not None
        sl = self.blocks[i]
        pop = eng.population
        if pop and (not aimable or rng.random() < 0.5):
            if b is not None:
                donor = min(pop, key=lambda m: m.payload.judgement.bodies[b].cost)
            else:
                donor = min(pop, key=lambda m: m.key)
            u[sl] = self.full(donor.u)[sl]
            u[sl] = np.clip(u[sl] + 0.04 * rng.standard_normal(sl.stop - sl.start), 0.0, 1.0)
            return
        u[sl] = rng.random(sl.stop - sl.start)
        if not aimable:
            return
        assert fate is not None
        a = self.linvel_at[i]
        assert a is not None
        if meet is not None and (not place or rng.random() < 0.5):
            self._aim_meet(rng, u, i, meet)
            return
        if hit is not None and (not place or rng.random() < 0.5):
            v = self._aim_hit(rng, i, a, *hit)
            if v is None:
                return
        else:
            v = self._aim_place(rng, i, fate)
        x = self.x_full(u)
        x[a:a + 3] = v
        u[a:a + 3] = self.u_of(x)[a:a + 3]

    def _aim_hit(self, rng: np.random.Generator, i: int, a: int, at: np.ndarray, radii: float) -> np.ndarray | None:
        """A velocity of block ``i`` (its linvel at ``a``; a body that may not fly) that carries its origin
        in a straight line through its free components towards a point within the two bounding radii of
        its first ``hits`` name (at ``at``), at a speed drawn from those its ranges allow in that direction
        (None: no such speed)."""
        point = at + 0.8 * radii * rng.uniform(-1, 1, 3)
        lo, hi = self.lo[a:a + 3], self.hi[a:a + 3]
        live = hi > lo
        d = np.where(live, point - self.origin[i], 0.0)
        n = float(np.linalg.norm(d))
        if n == 0.0:
            return None
        d = d / n
        s_lo, s_hi = 0.0, np.inf
        for j in np.flatnonzero(live):
            if d[j] == 0.0:
                if not lo[j] <= 0.0 <= hi[j]:
                    return None
                continue
            e1, e2 = sorted((lo[j] / d[j], hi[j] / d[j]))
            s_lo, s_hi = max(s_lo, e1), min(s_hi, e2)
        if not s_lo < s_hi:
            return None
        return np.where(live, float(rng.uniform(s_lo, s_hi)) * d, lo)

    def _aim_meet(self, rng: np.random.Generator, u: np.ndarray, i: int, j: int) -> None:
        """Blocks ``i`` and ``j`` of the whole unit point ``u`` (in place): the ballistic velocities
        (:meth:`_ballistic`) that bring both origins to one point at one time, drawn: a point between
        the two starts (a random fraction of the way, 0.25-0.75), moved across by up to half their
        distance apart and raised by up to all of it, the time :meth:`_flight_time`'s; the first of
        :data:`MEET_DRAWS` draws whose two velocities lie in their ranges (else the last, clipped)."""
        oi, oj = self.origin[i], self.origin[j]
        gap = float(np.linalg.norm(oj - oi))
        a, b = self.linvel_at[i], self.linvel_at[j]
        assert a is not None and b is not None
        u[self.blocks[j]] = rng.random(self.blocks[j].stop - self.blocks[j].start)
        x = self.x_full(u)
        for _ in range(MEET_DRAWS):
            point = (oi + rng.uniform(0.25, 0.75) * (oj - oi)
                     + gap * np.array([rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5), rng.uniform(0.0, 1.0)]))
            t = self._flight_time(rng)
            x[a:a + 3], x[b:b + 3] = self._ballistic(i, point, t), self._ballistic(j, point, t)
            if all(np.all((self.lo[k:k + 3] <= x[k:k + 3]) & (x[k:k + 3] <= self.hi[k:k + 3])) for k in (a, b)):
                break
        fi, fj = (self.fates.fates[self.bit[k]] for k in (i, j))  # type: ignore[index]
        if fi.rest_in is not None and fj.rest_in is not None and rng.random() < 0.5:
            # half the time each then falls into its own region: the landing aim (nbst.scene.aim)
            ta, tb = (self._region_point(rng, f.rest_in) for f in (fi, fj))
            lo, hi = np.r_[self.lo[a:a + 3], self.lo[b:b + 3]], np.r_[self.hi[a:a + 3], self.hi[b:b + 3]]
            v = land_pair(self._pair(i, j), x[a:a + 3], x[b:b + 3], (ta, tb), lo, hi)
            x[a:a + 3], x[b:b + 3] = v[:3], v[3:]
        u[a:a + 3] = self.u_of(x)[a:a + 3]
        u[b:b + 3] = self.u_of(x)[b:b + 3]

    def _pair(self, i: int, j: int) -> Pair:
        """Blocks ``i`` and ``j``'s bodies as a :class:`~nbst.scene.aim.Pair` (their restitution measured
        once, on first use)."""
        if (i, j) not in self.pairs:
            m = self.sim.model
            bi, bj = (m.body(self.fates.controls[k].body).id for k in (i, j))
            self.pairs[(i, j)] = pair_of(m, bi, bj, self.origin[i], self.origin[j], self.fates.duration)
        return self.pairs[(i, j)]

    @staticmethod
    def _region_point(rng: np.random.Generator, region: Any) -> np.ndarray:
        """A point of ``region`` near its middle: a ball's within half its radius, a box's within a
        quarter of its size, each way."""
        if region.center is not None:
            return region.mid() + region.radius * 0.5 * rng.uniform(-1, 1, 3)
        return region.mid() + 0.25 * (np.asarray(region.hi) - np.asarray(region.lo)) * rng.uniform(-1, 1, 3)

    def _flight_time(self, rng: np.random.Generator) -> float:
        """A random flight time (s) for a ballistic aim: 0.1 s to half the duration, at most 1 s."""
        return float(rng.uniform(0.1, max(0.2, min(1.0, 0.5 * self.fates.duration))))

    def _ballistic(self, i: int, point: np.ndarray, t: float) -> np.ndarray:
        """The velocity carrying block ``i``'s origin to ``point`` in ``t`` s (the model's gravity, no contacts)."""
        return (point - self.origin[i] - 0.5 * self.gravity * t * t) / t

    def _aim_place(self, rng: np.random.Generator, i: int, fate: Any) -> np.ndarray:
        """The ballistic velocity of block ``i`` to a point of its region (``at`` or ``rest_in``)."""
        if fate.at and (fate.rest_in is None or rng.random() < 0.5):
            t, region = fate.at[int(rng.integers(len(fate.at)))]
            t = max(t, 1e-3)
        else:
            assert fate.rest_in is not None
            region = fate.rest_in
            t = self._flight_time(rng)
        return self._ballistic(i, self._region_point(rng, region), t)

    def init(self, eng: Engine) -> np.ndarray:
        """A random trial: each block by directed or uniform randomize, even odds."""
        rng: np.random.Generator = eng.rng  # type: ignore[has-type]
        u = rng.random(len(self.lo))
        for i in range(len(self.blocks)):
            if rng.random() < 0.5:
                self._directed(eng, u, i)
        return u[self.live]

    def init_done(self, eng: Engine) -> bool:
        return all(sum(1 for m in eng.population if m.signature >> b & 1) >= INIT_PER_BIT
                   for b in range(len(self.fates.fates)))

    # -- rollouts ---------------------------------------------------------------------
    def evaluate(self, U: np.ndarray) -> dict[str, Any]:
        outs = self.sim.run(np.array([self.x_of(u) for u in U]))
        spent = len(outs)
        dist, cost = [], []
        for r in outs:
            self.seen.add(r.signature)
            met = r.judgement.met and not r.warnings
            misses, far = 0, 0.0
            if met and self.ladder:  # the finer steps: a miss there costs, and keeps the search going
                misses, far, n = ladder_check(r.x, self.ladder)
                spent += n
                self.held[id(r)] = misses == 0
            if met and misses == 0 and r.sequence not in self.answers and len(self.answers) < self.want:
                self.answers[r.sequence] = r
            dist.append(distance_of(r, misses))
            cost.append(r.cost + LADDER_PENALTY * misses + far)
        sigs = [sum(1 << k for k, b in enumerate(r.signature) if b) for r in outs]
        fine = [bool(r.judgement.met and not r.warnings) for r in outs]  # met at h: the ladder left
        return {"signatures": sigs, "distances": dist, "costs": cost, "payloads": outs, "rollouts": spent,
                "fine": fine}

    def done(self, eng: Engine) -> bool:
        if self.want > 1:
            return len(self.answers) >= self.want
        return eng.best is not None and eng.best.distance == 0


def signature_search(sim: SceneSim, *, rng: np.random.Generator, max_rollouts: int = DEFAULT_MAX_ROLLOUTS,
                     answers: int = 1, ladder: tuple[SceneSim, ...] = (),
                     callback: Callable[[SceneProgress], None] | None = None) -> SceneSearchResult:
    """Search the controls with the paper's signature search on the engine (module docstring).

    Args:
        sim: the scene's rollouts (its ``jobs`` threads roll each batch out).
        rng: the one random stream (``nbst.seeds.check_random_state(seed)``).
        max_rollouts: the rollout budget (>= 1).
        answers: go on after every fate is met until this many rollouts meet them, each with a
            contact sequence of its own (the animator's choice, after Chenney & Forsyth 2000; the
            sim must record sequences, ``SceneSim(sequences=True)``), or the budget is spent.
        ladder: sims of the same scene at finer timesteps (h/2, h/4): a trial that meets every fate
            is rolled out on each in turn while it holds (:func:`ladder_check`; those rollouts count
            in the budget), and is an answer only if it meets them there as well; a miss adds 1 to
            its distance and :data:`LADDER_PENALTY` per rung to its cost.
        callback: called with a :class:`SceneProgress` after each batch.

    Returns:
        the :class:`SceneSearchResult` (the best rollout, also when interrupted).
    """
    S = _Scene(sim, answers, ladder)
    blocks = S.engine_blocks
    if len(blocks) > 1:  # the paper's GA: crossover of whole per-body blocks
        how: dict[str, Any] = dict(explore=max(2 * BATCH, min(max_rollouts // 10, INIT_MAX)), init_done=S.init_done,
                                   ga_batches=1, ga_fine=1, cma=False, redraw_unmet=REDRAW_UNMET)
        if any(j is not None for j in S.meet):  # bodies that must meet: CMA-ES restarts between GA batches too
            how.update(cma=True, popsize=ONE_BODY_POPSIZE, cma_by_key=True)
    else:  # one controlled body: nothing to cross over; CMA-ES restarts after one exploring batch or two
        how = dict(explore=ONE_BODY_EXPLORE, explore_batches=ONE_BODY_EXPLORE_BATCHES, ga_batches=0, cma=True,
                   popsize=ONE_BODY_POPSIZE, cma_by_key=True,
                   hold_distance=0,  # a trial met at h but not kept on the ladder: polished, then other funnels
                   spent_gain=ONE_BODY_SPENT_GAIN, wander=True)  # ... and new funnels looked for
    eng = Engine(len(S.live), seed=rng, max_rollouts=max_rollouts, blocks=blocks, bits=S.bit, batch=BATCH, init=S.init,
                 moves={"directed": S.directed}, creep=CREEP, prefer_unmet=True, population=POPULATION,
                 per_signature=PER_SIGNATURE, done=S.done, tournament=2, **how)
    t0 = time.perf_counter()

    def tell() -> None:
        b = eng.best
        if callback is not None and b is not None:
            callback(SceneProgress(int(eng.rollouts), b.cost,  # type: ignore[has-type]
                                   signature_text(b.payload.signature), len(eng.population), len(S.seen)))

    try:
        while not eng.stop():
            U = eng.ask()
            eng.tell(U, **S.evaluate(U))
            tell()
    except KeyboardInterrupt:
        eng.interrupt()
    reasons = eng.stop()
    stopped = "met" if "solved" in reasons else "interrupted" if "interrupted" in reasons else "budget"
    if eng.best is None:  # interrupted before the first batch came back: roll out the middle of the ranges
        best = sim.rollout(S.x_of(np.full(len(S.live), 0.5)))
    else:
        best = eng.best.payload
    return SceneSearchResult(best=best, rollouts=int(eng.rollouts),  # type: ignore[has-type]
                              stopped=stopped, wall_time=time.perf_counter() - t0,
                             signatures=len(S.seen), answers=tuple(S.answers.values()),
                             best_held=S.held.get(id(best)))


def noisy_probability(sim: SceneSim, x: np.ndarray, *, n: int, seed: int) -> Probability:
    """How often the controls ``x`` meet every fate under the fates' noise, with its 95 % Wilson interval.

    ``n`` copies of ``x``, each coordinate plus sigma times a standard normal draw (the fates'
    ``"noise"``, or the defaults), clipped into the ranges (the rollout room's
    ``normal_draws``/``perturb``: the draws of ``seed``, common random numbers), rolled out.

    Args:
        sim: the scene's rollouts.
        x: (D,) the controls vector.
        n: noisy copies, >= 1.
        seed: the draws' seed.

    Returns:
        the ``nbst.models.mjsearch.probability.Probability`` (k of n met).
    """
    f = sim.fates
    lo, hi = f.bounds()
    xs = perturb(x, f.noise(), normal_draws(seed, n, f.dim), lo, hi)
    outs = sim.run(xs)
    return Probability.of(sum(1 for r in outs if r.judgement.met and not r.warnings), n)
