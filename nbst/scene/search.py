"""The paper's per-body signature search, carried to the free bodies of any scene.

A trial is a controls vector, kept in the unit cube (coordinate k maps to ``lo[k] + u[k] (hi[k] -
lo[k])``), cut into **blocks**, one per controlled body. Its **signature** holds one bit per body
with fates: set when all of that body's fates are met (``nbst.scene.judge``). As in the paper
(docs/scene.md, "The search"):

* **initialize**: random trials (each block by *directed* or *uniform randomize*, even odds) until
  every bit is set in at least :data:`INIT_PER_BIT` members, or after :data:`INIT_MAX` rollouts (a
  tenth of the budget at most);
* **generate**: one of four operators, even odds: *creep* (one block perturbed), *directed
  randomize* (one block aimed), *uniform randomize* (one block drawn anew), *crossover* (two
  parents; the second among those whose signature OR'ed with the first's sets the most bits; each
  block from the parent whose body meets its fates when exactly one does, else from either). A
  parent is chosen "Senate-like": each order (bits set) present is as likely, each signature of
  that order as likely, then the better of two members of that signature drawn at random;
* **insert**: a child with the signature of one parent replaces it, unless that parent is the
  best of its signature and the child is not better (elitism); otherwise it joins, the worst of its
  signature leaving past :data:`PER_SIGNATURE`; past :data:`POPULATION` members the lowest-order
  signatures subsumed by higher-order ones are culled (not the best's);
* with a ladder (finer timesteps, h/2 and h/4), a trial that meets every fate is rolled out there
  too and counts only if it meets them there as well (each miss adds :data:`LADDER_PENALTY` to
  its cost, so a trial that holds is better);
* the search stops when every bit is set (all fates met), or at the rollout budget. Asked for
  several answers, it goes on until that many rollouts meet every fate, each with a contact
  sequence of its own (Chenney & Forsyth 2000: the animator chooses).

*Directed randomize* aims a body that has a place to be (``rest_in`` or ``at``): the velocity that
would carry its origin ballistically (the model's gravity, no contacts) to a point of the region in a
random flight time (``at``: its time); half the time it instead takes the block of the member whose
body is nearest its fates and creeps it. *Creep* adds a normal step of sigma 0.01, 0.04 or 0.15 (of
the range, one at random) to the block.

Children are made :data:`BATCH` at a time from one generator stream (``nbst.seeds``) and rolled out
on ``jobs`` threads: the result depends on the seed alone, never on ``jobs``. Ctrl-C stops the
search: the best trial so far is returned (``stopped="interrupted"``).
"""
from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Callable

import numpy as np

from nbst.models.mjsearch.probability import Probability, normal_draws, perturb
from nbst.scene.rollout import SceneRollout, SceneSim

__all__ = ["DEFAULT_MAX_ROLLOUTS", "BATCH", "POPULATION", "PER_SIGNATURE", "INIT_PER_BIT", "INIT_MAX", "LADDER_PENALTY", "SceneProgress",
           "SceneSearchResult", "signature_search", "noisy_probability"]

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
#: The initialisation ends when every bit is set in this many members (the paper: 5) ...
INIT_PER_BIT = 3
#: ... or after this many rollouts (and at most a tenth of the budget).
INIT_MAX = 160
_CREEP = (0.01, 0.04, 0.15)


@dataclass(frozen=True)
class SceneProgress:
    """Where a search stands: rollouts so far, the best cost and signature, the population."""

    rollouts: int
    best_cost: float
    best_signature: str
    population: int
    signatures: int


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


class _Member:
    __slots__ = ("u", "r", "sig", "cost", "held")

    def __init__(self, u: np.ndarray, r: SceneRollout):
        self.u, self.r, self.sig, self.cost = u, r, r.signature, r.cost
        #: with a ladder: every fate also met at each finer step (None: not looked at)
        self.held: bool | None = None


def _better(a: _Member, b: _Member) -> bool:
    """a is better than b: more bits set, then lower cost."""
    return (sum(a.sig), -a.cost) > (sum(b.sig), -b.cost)


class _Search:
    def __init__(self, sim: SceneSim, rng: np.random.Generator, want: int = 1, ladder: tuple[SceneSim, ...] = ()):
        f = sim.fates
        self.sim, self.rng, self.fates = sim, rng, f
        self.lo, self.hi = f.bounds()
        self.span = self.hi - self.lo
        self.blocks = f.blocks()
        fated = [fa.body for fa in f.fates]
        #: per block: the signature bit of its body (None: the body has no fates)
        self.bit = [fated.index(c.body) if c.body in fated else None for c in f.controls]
        self.pop: list[_Member] = []
        self.best: _Member | None = None
        self.seen: set[tuple[bool, ...]] = set()
        self.want = want
        self.ladder = ladder
        self.answers: dict[tuple[str, ...], SceneRollout] = {}
        self.rollouts = 0
        # the origin of each controlled body at the start (for aiming), gravity
        mid = (self.lo + self.hi) / 2
        q0, _ = sim.initial_state(mid)
        self.origin = []
        for qa, _da in sim.adr:  # (the middle of a pos range is added already)
            self.origin.append(q0[qa:qa + 3].copy())
        self.gravity = np.array(sim.model.opt.gravity, dtype=float)

    # -- operators --------------------------------------------------------------------
    def x_of(self, u: np.ndarray) -> np.ndarray:
        return self.lo + np.clip(u, 0.0, 1.0) * self.span

    def u_of(self, x: np.ndarray) -> np.ndarray:
        with np.errstate(divide="ignore", invalid="ignore"):
            u = np.where(self.span > 0, (x - self.lo) / np.where(self.span > 0, self.span, 1.0), 0.5)
        return np.asarray(np.clip(u, 0.0, 1.0))

    def uniform(self, u: np.ndarray, i: int) -> None:
        sl = self.blocks[i]
        u[sl] = self.rng.random(sl.stop - sl.start)

    def creep(self, u: np.ndarray, i: int, sigma: float | None = None) -> None:
        sl = self.blocks[i]
        s = float(self.rng.choice(_CREEP)) if sigma is None else sigma
        u[sl] = np.clip(u[sl] + s * self.rng.standard_normal(sl.stop - sl.start), 0.0, 1.0)

    def directed(self, u: np.ndarray, i: int) -> None:
        c, b = self.fates.controls[i], self.bit[i]
        fate = None if b is None else self.fates.fates[b]
        aimable = fate is not None and c.linvel is not None and (fate.rest_in is not None or fate.at)
        if self.pop and (not aimable or self.rng.random() < 0.5):
            # the block of the member whose body comes nearest its fates, crept
            if b is not None:
                donor = min(self.pop, key=lambda m: m.r.judgement.bodies[b].cost)
            else:
                donor = min(self.pop, key=lambda m: m.cost)
            sl = self.blocks[i]
            u[sl] = donor.u[sl]
            self.creep(u, i, 0.04)
            return
        self.uniform(u, i)
        if not aimable:
            return
        assert fate is not None
        if fate.at and (fate.rest_in is None or self.rng.random() < 0.5):
            t, region = fate.at[int(self.rng.integers(len(fate.at)))]
            t = max(t, 1e-3)
        else:
            assert fate.rest_in is not None
            region = fate.rest_in
            t = float(self.rng.uniform(0.1, max(0.2, min(1.0, 0.5 * self.fates.duration))))
        target = region.mid()
        if region.center is not None:
            target = target + region.radius * 0.5 * self.rng.uniform(-1, 1, 3)
        else:
            target = target + 0.25 * (np.asarray(region.hi) - np.asarray(region.lo)) * self.rng.uniform(-1, 1, 3)
        v = (target - self.origin[i] - 0.5 * self.gravity * t * t) / t
        k = [p for p, _ in c.parts()].index("linvel")
        sl = self.blocks[i]
        a = sl.start + 3 * k
        x = self.x_of(u)
        x[a:a + 3] = v
        u[a:a + 3] = self.u_of(x)[a:a + 3]

    def random_trial(self) -> np.ndarray:
        u = self.rng.random(len(self.lo))
        for i in range(len(self.blocks)):
            if self.rng.random() < 0.5:
                self.directed(u, i)
        return u

    # -- parents ----------------------------------------------------------------------
    def senate(self, among: list[_Member]) -> _Member:
        orders = sorted({sum(m.sig) for m in among})
        o = orders[int(self.rng.integers(len(orders)))]
        sigs = sorted({m.sig for m in among if sum(m.sig) == o})
        s = sigs[int(self.rng.integers(len(sigs)))]
        mem = [m for m in among if m.sig == s]
        a, b = (mem[int(k)] for k in self.rng.integers(len(mem), size=2))
        return a if a.cost <= b.cost else b  # a tournament of two inside the signature

    def block_to_change(self, parent: _Member) -> int:
        unmet = [i for i, b in enumerate(self.bit) if b is None or not parent.sig[b]]
        if unmet and self.rng.random() < 0.5:
            return unmet[int(self.rng.integers(len(unmet)))]
        return int(self.rng.integers(len(self.blocks)))

    def child(self) -> tuple[np.ndarray, tuple[_Member, ...]]:
        op = int(self.rng.integers(4))
        p1 = self.senate(self.pop)
        if op == 3 and len(self.pop) > 1:
            others = [m for m in self.pop if m is not p1]
            best_or = max(sum(a or b for a, b in zip(p1.sig, m.sig)) for m in others)
            p2 = self.senate([m for m in others if sum(a or b for a, b in zip(p1.sig, m.sig)) == best_or])
            u = p1.u.copy()
            for i, sl in enumerate(self.blocks):
                b = self.bit[i]
                ok1, ok2 = (p1.sig[b], p2.sig[b]) if b is not None else (False, False)
                take2 = ok2 if ok1 != ok2 else bool(self.rng.random() < 0.5)
                if take2:
                    u[sl] = p2.u[sl]
            return u, (p1, p2)
        u = p1.u.copy()
        i = self.block_to_change(p1)
        (self.creep, self.directed, self.uniform, self.creep)[op](u, i)
        return u, (p1,)

    # -- population -------------------------------------------------------------------
    def note(self, m: _Member) -> None:
        self.seen.add(m.sig)
        met = m.r.judgement.met and not m.r.warnings
        if met and self.ladder:  # the finer steps: a miss there costs, and keeps the search going
            fails = sum(not (r.judgement.met and not r.warnings) for r in (s.rollout(m.r.x) for s in self.ladder))
            self.rollouts += len(self.ladder)
            m.held, m.cost = fails == 0, m.cost + LADDER_PENALTY * fails
        if met and m.held is not False and m.r.sequence not in self.answers and len(self.answers) < self.want:
            self.answers[m.r.sequence] = m.r
        if self.best is None or _better(m, self.best):
            self.best = m

    def add(self, m: _Member) -> None:
        self.pop.append(m)
        same = [x for x in self.pop if x.sig == m.sig]
        if len(same) > PER_SIGNATURE:
            worst = max((x for x in same if x is not self.best), key=lambda x: x.cost, default=None)
            if worst is not None:
                self.pop.remove(worst)
        if len(self.pop) > POPULATION:
            self.cull()

    def cull(self) -> None:
        assert self.best is not None
        sigs = {x.sig for x in self.pop}
        subsumed = [s for s in sigs if s != self.best.sig and all(
            any(t[k] and sum(t) > sum(s) for t in sigs) for k in range(len(s)) if s[k])]
        if subsumed:
            low = min(sum(s) for s in subsumed)
            gone = {s for s in subsumed if sum(s) == low}
            self.pop = [x for x in self.pop if x.sig not in gone]
        while len(self.pop) > POPULATION:
            worst = max((x for x in self.pop if x is not self.best), key=lambda x: (-sum(x.sig), x.cost))
            self.pop.remove(worst)

    def insert(self, m: _Member, parents: tuple[_Member, ...]) -> None:
        self.note(m)
        same = [p for p in parents if p.sig == m.sig and p in self.pop]
        if same:
            p = same[int(self.rng.integers(len(same)))] if len(same) > 1 else same[0]
            best_of_sig = min((x for x in self.pop if x.sig == p.sig), key=lambda x: x.cost)
            if not (p is best_of_sig and m.cost >= p.cost):
                self.pop[self.pop.index(p)] = m
                return
        self.add(m)

    def done(self) -> bool:
        if self.want > 1:
            return len(self.answers) >= self.want
        return (self.best is not None and self.best.r.judgement.met and not self.best.r.warnings
                and self.best.held is not False)


def signature_search(sim: SceneSim, *, rng: np.random.Generator, max_rollouts: int = DEFAULT_MAX_ROLLOUTS,
                     answers: int = 1, ladder: tuple[SceneSim, ...] = (),
                     callback: Callable[[SceneProgress], None] | None = None) -> SceneSearchResult:
    """Search the controls with the paper's signature search (module docstring).

    Args:
        sim: the scene's rollouts (its ``jobs`` threads roll each batch out).
        rng: the one random stream (``nbst.seeds.check_random_state(seed)``).
        max_rollouts: the rollout budget (>= 1).
        answers: go on after every fate is met until this many rollouts meet them, each with a
            contact sequence of its own (the animator's choice, after Chenney & Forsyth 2000; the
            sim must record sequences, ``SceneSim(sequences=True)``), or the budget is spent.
        ladder: sims of the same scene at finer timesteps (h/2, h/4): a trial that meets every fate
            is rolled out on each too (those rollouts count in the budget), and is an answer only if
            it meets them there as well; a miss adds :data:`LADDER_PENALTY` to its cost per rung.
        callback: called with a :class:`SceneProgress` after each batch.

    Returns:
        the :class:`SceneSearchResult` (the best rollout, also when interrupted).
    """
    S = _Search(sim, rng, want=answers, ladder=ladder)
    t0 = time.perf_counter()
    stopped = "budget"

    def tell() -> None:
        if callback is not None and S.best is not None:
            callback(SceneProgress(S.rollouts, S.best.cost, "".join("1" if b else "0" for b in S.best.sig),
                                   len(S.pop), len(S.seen)))

    try:
        init_budget = max(2 * BATCH, min(max_rollouts // 10, INIT_MAX))
        while S.rollouts < min(init_budget, max_rollouts) and not S.done():
            n = min(BATCH, max_rollouts - S.rollouts)
            us = [S.random_trial() for _ in range(n)]
            outs = sim.run(np.array([S.x_of(u) for u in us]))
            S.rollouts += n
            for u, r in zip(us, outs):
                m = _Member(u, r)
                S.note(m)
                S.add(m)
            tell()
            counts = [sum(1 for m in S.pop if m.sig[b]) for b in range(len(sim.fates.fates))]
            if min(counts) >= INIT_PER_BIT:
                break
        while S.rollouts < max_rollouts and not S.done():
            n = min(BATCH, max_rollouts - S.rollouts)
            kids = [S.child() for _ in range(n)]
            outs = sim.run(np.array([S.x_of(u) for u, _ in kids]))
            S.rollouts += n
            for (u, parents), r in zip(kids, outs):
                S.insert(_Member(u, r), parents)
                if S.done():
                    break
            tell()
    except KeyboardInterrupt:
        stopped = "interrupted"
    if S.done():
        stopped = "met"
    if S.best is None:  # interrupted before the first batch came back: roll out the middle of the ranges
        mid = np.full(len(S.lo), 0.5)
        S.best = _Member(mid, sim.rollout(S.x_of(mid)))
    if stopped != "interrupted":
        tell()
    return SceneSearchResult(best=S.best.r, rollouts=S.rollouts, stopped=stopped,
                             wall_time=time.perf_counter() - t0, signatures=len(S.seen),
                             answers=tuple(S.answers.values()), best_held=S.best.held)


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
