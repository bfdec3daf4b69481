"""The crash search: the paper's signature idea carried to vehicles.

A trial solution is one driver intent per vehicle (:mod:`.space`: one **block** of unit-cube
coordinates per vehicle). Its **signature** has one bit per vehicle, set when every fate of
that vehicle holds (the paper's i-acceptable). Around the paper's population:

* **initialize**: ``explore`` rollouts, half *uniform randomize* (every block uniform) and half
  *directed randomize* (:func:`directed`: each vehicle aims where its first victim will be at
  its arrival time, or at its rest region);
* **generate** (the paper's four operations, equally likely): *creep* (one vehicle's block
  moved by a small Gaussian step), *directed randomize* or *uniform randomize* of one
  vehicle's block, and *crossover*: the second parent is chosen, Senate-like, among those
  whose signature ORed with the first's sets the most bits, and the child takes each
  vehicle's whole block from the parent that is acceptable for that vehicle when exactly one
  is, else from either at random (the paper's "genetically engineered" child). Parents are
  chosen Senate-like: every signature order (bits set) alike, every signature of an order
  alike, then a member;
* **insert**: a child with the signature of exactly one parent replaces it (unless that
  parent is the best and the child is not better); otherwise it joins, replacing the worst of
  its signature past :data:`PER_SIGNATURE`; past :data:`POPULATION` the lowest-order
  signatures subsumed by higher-order ones are culled (never the best's signature);
* a **MAP-Elites archive keyed by the contact sequence** (the vehicle pairs in the order they
  first touch) keeps the best trial of every sequence seen;
* **CMA-ES restarts** (pycma) in the unit cube, every :data:`GA_BATCHES` batches of the paper's
  operations (every batch once the best trial's contacts are right), ending after :data:`STALL`
  generations without a lower cost: from the best trial and from the archive's sequences nearest
  the script's in turn while the contacts are wrong; from the best trial at steps of
  :data:`SIGMA0`, a third and a ninth of it once they are right (fine-tuning rest poses), and,
  once :data:`SPENT` of those in a row left its cost as it was, from the cheapest other trial
  with the contacts right away from every start so far (another funnel: near a planted script's
  hidden answer the met region is a narrow funnel, and a search polishing one spent funnel
  stalls there for thousands of rollouts).

The search stops at the first trial that meets the script (every bit set and the global
order) and keeps meeting it at 1 and 0.5 ms (the **ladder**: a crash that only the 2 ms step
makes is no result; such a trial costs :data:`FRAGILE` more and the search goes on), at the
budget, or on Ctrl-C (the best so far is returned, ``stopped`` "interrupted").
Cost: :func:`.outcome.judge` (a few hundredths when met: its centring term).

Reproducible: batches have a fixed size (:data:`.run.BATCH`), every random number comes from
the seeded Generator in a fixed order, pycma gets seeds drawn from it; the rollouts do not
depend on the number of threads, so ``--jobs`` changes nothing.

Compute only.
"""
from __future__ import annotations

import math
import numbers
import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from nbst.errors import InputError
from nbst.models.crash import driver as drv
from nbst.models.crash import outcome as out_mod
from nbst.models.crash.run import BATCH, TIMESTEP_LADDER, CrashRunner
from nbst.models.crash.script import Script
from nbst.models.crash.space import CrashSpace, space_of
from nbst.seeds import check_seed

__all__ = ["DEFAULT_MAX_ROLLOUTS", "CRASH_EXPLORE", "PER_SIGNATURE", "POPULATION", "CREEP", "GA_BATCHES",
           "LADDER_CHECK_TIMESTEPS", "FRAGILE", "SIGMA0", "STALL", "SPENT", "RIGHT_KEPT", "Trial",
           "CrashProgress", "CrashResult", "directed", "ladder_check", "solve"]

#: The search's budget when none is given, in rollouts (ladder checks included): ``nbst crash
#: solve``'s and ``reconstruct``'s ``--max-rollouts`` default, and the budget of docs/crash.md's figures.
DEFAULT_MAX_ROLLOUTS = 3000
#: Rollouts of the initial population (capped at a quarter of the budget).
CRASH_EXPLORE = 64
#: The paper's limits: trials per signature, and the population past which culling starts.
PER_SIGNATURE, POPULATION = 8, 64
#: Creep: the Gaussian step (unit cube) of one vehicle's block.
CREEP = 0.05
#: Batches of the paper's operations between CMA-ES restarts.
GA_BATCHES = 3
#: The finer rungs of :data:`.run.TIMESTEP_LADDER` (s) a trial that meets the script at its own
#: step must also meet (one rollout each), and the cost added to one that does not (it meets the
#: script only at its own step: search on).
LADDER_CHECK_TIMESTEPS = TIMESTEP_LADDER[1:]
FRAGILE = 0.1  # small: a fragile crash stays a parent (its neighbours may hold on the ladder)
#: CMA-ES: initial step (unit cube), generations without a lower cost that end a restart.
SIGMA0, STALL = 0.12, 6
#: Polishing (the best trial's contacts right): restarts in a row that leave the best's cost as it
#: was (the best not met at its own step) before the next restart starts from another trial with
#: the contacts right, at least one SIGMA0 step's length (SIGMA0 x sqrt(dim), unit cube) from
#: every polishing restart's start so far; RIGHT_KEPT such trials are kept (the cheapest).
SPENT, RIGHT_KEPT = 3, 256


@dataclass(eq=False)
class Trial:
    """A trial solution: its unit-cube point, outcome, signature, cost and contact sequence."""

    u: np.ndarray
    outcome: out_mod.Outcome
    controls: np.ndarray | None = field(repr=False, default=None)
    qpos0: np.ndarray | None = field(repr=False, default=None)
    qvel0: np.ndarray | None = field(repr=False, default=None)
    final_qpos: np.ndarray | None = field(repr=False, default=None)
    holds: bool | None = None   # the ladder's verdict on a trial that meets the script (None: not asked)

    @property
    def signature(self) -> int:
        return self.outcome.signature

    @property
    def cost(self) -> float:
        """The search's cost: the outcome's, plus :data:`FRAGILE` when the ladder lost it."""
        return self.outcome.cost + (FRAGILE if self.holds is False else 0.0)

    @property
    def accepted(self) -> bool:
        """Meets the script, and keeps meeting it on the ladder (when asked)."""
        return self.outcome.solved and self.holds is not False


@dataclass
class CrashProgress:
    """What the search reports after each batch."""

    rollouts: int
    best_cost: float
    best_signature: str
    solved: bool
    sequences: int


@dataclass
class CrashResult:
    """What :func:`solve` returns: the best trial, how the search went and the archive (contact
    sequence -> best cost)."""

    best: Trial
    rollouts: int
    restarts: int
    stopped: str            # "found" | "budget" | "interrupted"
    seed: int
    wall_time: float        # s
    archive: dict[tuple, float]
    history: list[tuple[int, float]]  # (rollouts, best cost) after each batch
    first_met: int | None = None  # rollouts when a trial first met the script at its own step


def _order_bits(sig: int) -> int:
    return bin(sig).count("1")


class _Search:
    def __init__(self, space: CrashSpace, runner, rng: np.random.Generator, max_rollouts: int, callback, keep=None,
                 check=None):
        self.S, self.R, self.rng = space, runner, rng
        self.max_rollouts, self.callback, self.keep, self.check = int(max_rollouts), callback, keep, check
        self.rollouts = 0
        self.pop: list[Trial] = []
        self.archive: dict = {}          # contact sequence -> best Trial
        self.best: Trial | None = None
        self.history: list = []
        self.first_met: int | None = None
        self.full = (1 << space.n) - 1
        self.right: list[Trial] = []     # trials with the contacts right (the cheapest RIGHT_KEPT)
        self.starts: list[np.ndarray] = []  # where the polishing restarts started
        self.spent = 0                   # polishing restarts in a row that left the best's cost as it was

    @property
    def left(self) -> int:
        return self.max_rollouts - self.rollouts

    @property
    def solved(self) -> bool:
        return self.best is not None and self.best.accepted

    @property
    def top(self) -> Trial:
        """The best trial so far (there is one from the first rollout on)."""
        assert self.best is not None, "no rollout yet"
        return self.best

    def evaluate(self, U: np.ndarray) -> list[Trial]:
        U = np.clip(np.atleast_2d(U), 0.0, 1.0)[: max(0, self.left)]
        trials: list[Trial] = []
        for k in range(0, len(U), BATCH):
            chunk = U[k:k + BATCH]
            res = self.R.run(self.S.intents(chunk))
            for i, (u, o) in enumerate(zip(chunk, res.outcomes)):
                t = Trial(u=u.copy(), outcome=o, controls=res.controls[i], qpos0=res.qpos0[i], qvel0=res.qvel0[i],
                          final_qpos=res.final_qpos[i])
                trials.append(t)
                if o.solved and self.first_met is None:
                    self.first_met = self.rollouts + i + 1
                if o.solved and self.check is not None:
                    t.holds = bool(self.check(t))
                    self.rollouts += len(LADDER_CHECK_TIMESTEPS)  # counted: the ladder's rollouts are rollouts too
                if self.keep is not None:
                    self.keep(t)
                if self.contacts_right(t):
                    self.right.append(t)
                cur = self.archive.get(o.sequence)
                if cur is None or t.cost < cur.cost:
                    self.archive[o.sequence] = t
                if self.best is None or (t.accepted, t.outcome.solved, -t.cost) > \
                        (self.best.accepted, self.best.outcome.solved, -self.best.cost):
                    self.best = t
            self.rollouts += len(chunk)
            if len(self.right) > 2 * RIGHT_KEPT:
                self.right.sort(key=lambda t: t.cost)
                del self.right[RIGHT_KEPT:]
            self.history.append((self.rollouts, float(self.top.cost)))
            if self.callback:
                self.callback(CrashProgress(self.rollouts, self.top.cost, self.top.outcome.signature_text(self.S.n),
                                            self.solved, len(self.archive)))
            if self.solved:
                break
        return trials

    # -- the paper's population ------------------------------------------------------------
    def senate(self, pool: list[Trial]) -> Trial:
        """A member chosen Senate-like: orders alike, signatures of an order alike, then members."""
        orders = sorted({_order_bits(t.signature) for t in pool})
        o = orders[self.rng.integers(len(orders))]
        sigs = sorted({t.signature for t in pool if _order_bits(t.signature) == o})
        s = sigs[self.rng.integers(len(sigs))]
        members = [t for t in pool if t.signature == s]
        return members[self.rng.integers(len(members))]

    def insert(self, child: Trial, parents: list[Trial]) -> None:
        same = [p for p in parents if p.signature == child.signature and p in self.pop]
        if same:
            p = same[0] if len(same) == 1 else same[self.rng.integers(len(same))]
            if not (p is self.best and child.cost >= p.cost):
                self.pop[self.pop.index(p)] = child
                return
        self.pop.append(child)
        mine = [t for t in self.pop if t.signature == child.signature]
        if len(mine) > PER_SIGNATURE:
            worst = max((t for t in mine if t is not self.best), key=lambda t: t.cost)
            self.pop.remove(worst)
        if len(self.pop) > POPULATION:
            self.cull()

    def cull(self) -> None:
        """Delete the lowest-order signature subsumed by higher-order ones (not the best's)."""
        sigs = sorted({t.signature for t in self.pop}, key=_order_bits)
        keep = self.best.signature if self.best else -1
        for s in sigs:
            if s == keep:
                continue
            higher = [h for h in sigs if _order_bits(h) > _order_bits(s)]
            covered = 0
            for h in higher:
                covered |= h
            if s & ~covered == 0:
                self.pop = [t for t in self.pop if t.signature != s]
                if len(self.pop) <= POPULATION:
                    return
        if len(self.pop) > POPULATION:  # nothing subsumed: the worst go
            self.pop.sort(key=lambda t: (t is not self.best, t.cost))
            del self.pop[POPULATION:]

    def child(self) -> tuple[np.ndarray, list[Trial]]:
        """One child of the paper's generate operation: (unit point, parents)."""
        op = self.rng.integers(4)
        a = self.senate(self.pop)
        u = a.u.copy()
        v = int(self.rng.integers(self.S.n))
        blk = list(self.S.blocks[v])
        if op == 0:
            u[blk] += CREEP * self.rng.standard_normal(len(blk))
            return u, [a]
        if op == 1:
            u[blk] = directed(self.S, self.rng, u)[blk]
            return u, [a]
        if op == 2:
            u[blk] = self.rng.random(len(blk))
            return u, [a]
        # crossover: the second parent maximises the bits of sig_a | sig_b, Senate-like among those
        best_or = max(_order_bits(a.signature | t.signature) for t in self.pop)
        pool = [t for t in self.pop if _order_bits(a.signature | t.signature) == best_or] or [a]
        b = self.senate(pool)
        for i, blk in enumerate(self.S.blocks):
            ai, bi = a.signature >> i & 1, b.signature >> i & 1
            src = a if ai and not bi else b if bi and not ai else (a if self.rng.random() < 0.5 else b)
            u[list(blk)] = src.u[list(blk)]
        return u, [a, b]

    def generation(self) -> None:
        kids = [self.child() for _ in range(BATCH)]
        trials = self.evaluate(np.array([k[0] for k in kids]))
        for t, (_, parents) in zip(trials, kids):
            self.insert(t, parents)

    # -- CMA-ES restarts -------------------------------------------------------------------
    def contacts_right(self, t: Trial) -> bool:
        """Whether a trial has every vehicle's hits and the global order right (what is left is
        fine-tuning: rest poses, speeds, attitudes)."""
        o, sc = t.outcome, self.S.script
        if sc.order is not None and not o.order_ok:
            return False
        return all(v.fate.hits is None or vo.fates.get("hits", True) for v, vo in zip(sc.vehicles, o.vehicles))

    def restart_point(self, k: int) -> tuple[Trial, float]:
        """The k-th restart's start and step: from the best trial when its contacts are right,
        at steps of SIGMA0, SIGMA0 / 3 and SIGMA0 / 9 in turn (fine-tuning); once :data:`SPENT`
        such restarts in a row have left the best's cost as it was (its funnel spent) and the best
        does not meet the script at its own step (one that does, fragile on the ladder, is
        polished where it is), from the cheapest other trial with the contacts right at least one
        SIGMA0 step (SIGMA0 x sqrt(dim)) from every polishing start so far, at SIGMA0 (another
        funnel; the best again when there is none); else
        alternately from the best (SIGMA0) and from the archive's contact sequences nearest the
        script's (SIGMA0 / 3), in turn."""
        if self.contacts_right(self.top):
            start, sigma = self.top, SIGMA0 / (3 ** (k % 3))
            if self.spent >= SPENT and not self.top.outcome.solved:
                spread = SIGMA0 * math.sqrt(self.S.dim)
                far = [t for t in sorted(self.right, key=lambda t: t.cost)
                       if all(np.linalg.norm(t.u - p) >= spread for p in self.starts)]
                if far:
                    start, sigma = far[0], SIGMA0
            self.starts.append(start.u)
            return start, sigma
        if k % 2 == 0 or not self.archive:
            return self.top, SIGMA0
        want = list(self.S.script.order or _fate_sequence(self.S.script))
        cells = sorted(self.archive.values(), key=lambda t: (out_mod._edit(list(t.outcome.sequence), want), t.cost))
        return cells[(k // 2) % len(cells)], SIGMA0 / 3

    def cma(self, k: int) -> None:
        import cma

        start, sigma = self.restart_point(k)
        polishing, before = self.contacts_right(self.top), self.top.cost
        es = cma.CMAEvolutionStrategy(start.u.tolist(), sigma,
                                      {"bounds": [0.0, 1.0], "popsize": BATCH, "verbose": -9,
                                       "seed": int(self.rng.integers(1, 2**31 - 1))})
        best_here, stalled = math.inf, 0
        while not self.solved and self.left > 0 and stalled < STALL:
            xs = es.ask()
            trials = self.evaluate(np.array(xs))
            for t in trials:
                self.insert(t, [start])
            if len(trials) < len(xs):
                break
            costs = [t.cost for t in trials]
            es.tell(xs, costs)
            if min(costs) < best_here - 1e-9:
                best_here, stalled = min(costs), 0
            else:
                stalled += 1
        if polishing:
            self.spent = 0 if self.top.cost < before - 1e-9 else self.spent + 1


def _fate_sequence(script) -> list:
    """A contact sequence the fates imply when the script gives no global order: each vehicle's
    hits, in script order (a guide for the restarts, not a requirement)."""
    seq = []
    for i, v in enumerate(script.vehicles):
        for j in v.fate.hits or ():
            p = (min(i, j), max(i, j))
            if p not in seq:
                seq.append(p)
    return seq


def directed(space: CrashSpace, rng: np.random.Generator, u: np.ndarray | None = None) -> np.ndarray:
    """The paper's *directed randomize* for vehicles: a unit point whose drivers aim where their
    first victim will be at their arrival time (drawn in its range), the victim driving straight
    at its speed towards its own aim point; a vehicle that hits nobody aims at its rest region.
    Coordinates it does not set are kept from ``u`` (uniform when None)."""
    S = space
    u = rng.random(S.dim) if u is None else u.copy()
    intents = S.intents(u[None])[0]
    IX = drv.IX
    sc = S.script
    for i, v in enumerate(sc.vehicles):
        d, f = v.driver, v.fate
        if d.aim_x is None or d.aim_x.fixed and d.aim_y.fixed:
            continue
        t = intents[i, IX["arrive"]] if np.isfinite(intents[i, IX["arrive"]]) else 3.0
        if f.hits:
            j = f.hits[0]
            w = sc.vehicles[j]
            aim = intents[j, [IX["aim_x"], IX["aim_y"]]]
            direc = np.array([math.cos(w.heading), math.sin(w.heading)])
            if np.isfinite(aim).all() and np.hypot(*(aim - [w.x, w.y])) > 1.0:
                direc = (aim - [w.x, w.y]) / np.hypot(*(aim - [w.x, w.y]))
            speed = intents[j, IX["speed"]]
            if np.isfinite(intents[j, IX["arrive"]]) and intents[j, IX["arrive"]] > 0 and np.isfinite(aim).all():
                speed = np.hypot(*(aim - [w.x, w.y])) / intents[j, IX["arrive"]]
            target = np.array([w.x, w.y]) + direc * speed * t
        elif f.rest is not None:
            target = np.array(f.rest[:2])
        else:
            continue
        intents[i, IX["aim_x"]] = np.clip(target[0], d.aim_x.lo, d.aim_x.hi)
        intents[i, IX["aim_y"]] = np.clip(target[1], d.aim_y.lo, d.aim_y.hi)
    out = S.unit_of(intents)
    for k, (i, f, r) in enumerate(S.coords):  # keep what directed randomize does not set
        if f not in (IX["aim_x"], IX["aim_y"]):
            out[k] = u[k]
    return out


def ladder_check(script: Script, xml: str, space: CrashSpace,
                 timesteps: tuple[float, ...] = LADDER_CHECK_TIMESTEPS) -> Callable[[Trial], bool]:
    """``check(trial) -> bool``: the trial's intents meet the script with the same contact
    sequence at every one of ``timesteps`` too (one rollout each)."""
    runners = [CrashRunner(script, xml=xml, timestep=h, batch=1) for h in timesteps]

    def check(t: Trial) -> bool:
        intents = space.intents(t.u[None])
        for R in runners:
            o = R.run(intents).outcomes[0]
            if not (o.solved and o.sequence == t.outcome.sequence):
                return False
        return True
    return check


def solve(script: Script, *, seed: int, max_rollouts: int = DEFAULT_MAX_ROLLOUTS, runner: CrashRunner | None = None,
          jobs: int = 1, callback: Callable[[CrashProgress], object] | None = None, explore: int = CRASH_EXPLORE,
          keep: Callable[[Trial], object] | None = None, ladder: bool = True) -> CrashResult:
    """Search driver intents that meet ``script``; see the module docstring.

    Args:
        script: the crash script (``nbst.models.crash.script.script_from_dict``, or a built-in
            of ``SCRIPTS`` through ``nbst.models.crash.script.load_script``).
        seed: an integer in [0, 2^63-1]; the same seed gives the same result whatever ``jobs``.
        max_rollouts: the budget, in rollouts (ladder checks included).
        runner: a ``nbst.models.crash.run.CrashRunner`` for this script to reuse (its threads then
            apply), or None: one is made with ``jobs`` threads and closed at the end.
        jobs: threads of the runner made here.
        callback: None, or called with a :class:`CrashProgress` after each batch.
        explore: rollouts of the initial population (half uniform, half directed).
        keep: None, or ``keep(trial)`` called for every rollout (reconstruction collects its fits so).
        ladder: a trial that meets the script counts only when it also does at
            :data:`LADDER_CHECK_TIMESTEPS` (two more rollouts, counted in the budget); one that
            does not costs :data:`FRAGILE` more and the search goes on.

    Returns:
        A :class:`CrashResult`: the best trial (``best.u``: (dim,) float64 unit-cube point, its
        intents ``space_of(script).intents(best.u[None])[0]``: (n, len(INTENT)); ``best.controls``:
        (periods, nu) realised controls; ``best.qpos0``, ``best.final_qpos``: (nq,); ``best.qvel0``:
        (nv,); ``best.outcome``), the rollouts and restarts used, ``stopped`` ("found", "budget"
        or "interrupted": Ctrl-C returns the best so far), the seed, the wall time, the archive
        and the history.

    Raises:
        InputError: ``seed`` is not an integer in [0, 2^63-1], or ``max_rollouts`` is under 1.
        MujocoError: a rollout diverged (a non-finite state).
        KeyboardInterrupt: Ctrl-C before the first batch ended (after it, the best so far is
            returned).
    """
    seed = check_seed(seed, what="seed")
    if isinstance(max_rollouts, bool) or not isinstance(max_rollouts, numbers.Integral) or max_rollouts < 1:
        raise InputError(f"max_rollouts must be a whole number of at least 1, got {max_rollouts!r}")
    own = runner is None
    R = runner if runner is not None else CrashRunner(script, jobs=jobs)
    S = space_of(script)
    rng = np.random.default_rng(seed)
    s = _Search(S, R, rng, max_rollouts, callback, keep, ladder_check(script, R.xml, S) if ladder else None)
    t0 = time.perf_counter()
    restarts = 0
    stopped = "budget"
    try:
        if S.dim == 0:  # nothing to search: one rollout of the fixed intents
            s.evaluate(np.zeros((1, 0)))
        else:
            n0 = max(BATCH, min(int(explore), max_rollouts // 4))
            half = n0 // 2
            U = np.concatenate([rng.random((half, S.dim)), np.array([directed(S, rng) for _ in range(n0 - half)])])
            for t in s.evaluate(U):
                s.insert(t, [])
            while not s.solved and s.left > 0:
                # the paper's operations while contacts are wrong; one batch when only fine-tuning is left
                for _ in range(1 if s.contacts_right(s.top) else GA_BATCHES):
                    if s.solved or s.left <= 0:
                        break
                    s.generation()
                if not s.solved and s.left > 0:
                    s.cma(restarts)
                    restarts += 1
        if s.solved:
            stopped = "found"
    except KeyboardInterrupt:
        stopped = "interrupted"
        if s.best is None:
            raise
    if own:
        R.close()
    return CrashResult(best=s.top, rollouts=s.rollouts, restarts=restarts, stopped=stopped, seed=int(seed),
                       wall_time=time.perf_counter() - t0,
                       archive={k: float(t.cost) for k, t in s.archive.items()}, history=s.history,
                       first_met=s.first_met)
