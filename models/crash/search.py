"""The crash search: the paper's signature idea carried to vehicles, on the rollout room's engine.

The search itself is :class:`nbst.models.mjsearch.engine.Engine` (the one engine of every rollout
search: exploration, the paper's GA on whole blocks, the archive, the CMA-ES restarts). This
module holds what knows vehicles, and how the engine is set for them:

* the **space** (:mod:`.space`): one driver intent per vehicle, one **block** of unit-cube
  coordinates per vehicle (the engine's blocks: crossover swaps whole vehicles);
* the **trial** (:class:`Trial`): a rollout's outcome read by :func:`.outcome.judge`. Its
  **signature** has one bit per vehicle, set when every fate of that vehicle holds (the paper's
  i-acceptable); its **cell** in the engine's archive is its **contact sequence** (the vehicle
  pairs in the order they first touch); its **distance** is 0 when it meets the script (every
  bit and the global order) and keeps meeting it at 1 and 0.5 ms (the **ladder**: a crash that
  only the 2 ms step makes is no result; such a trial costs :data:`FRAGILE` more, its distance
  is 1 and the search goes on), else 2; its cost is the outcome's (a few hundredths when met);
  it is **fine** (:func:`contacts_right`) when every vehicle's hits and the global order are right;
* the **moves**: the initial population is :data:`CRASH_EXPLORE` trials, each uniform or
  :func:`directed` (each vehicle aims where its first victim will be at its arrival time, or at
  its rest region), even odds; :func:`directed` is also the engine's *directed randomize* of one
  vehicle's block; creep steps :data:`CREEP`;
* the **restarts**: :data:`GA_BATCHES` batches of the paper's operations (one when the best is
  fine), then one CMA-ES restart (population :data:`.run.BATCH`, ending after :data:`STALL`
  generations without a lower cost): while the contacts are wrong, alternately from the best
  trial (:data:`SIGMA0`) and from the archive's contact sequence nearest the script's (edit
  distance, then cost; :data:`SIGMA0` / 3); once they are right, polishing from the best at
  :data:`SIGMA0`, a third and a ninth of it, and after :data:`SPENT` such restarts that left its
  cost as it was, from the cheapest other fine trial away from every start so far (another
  funnel: near a planted script's hidden answer the met region is a narrow funnel), unless the
  best is met at its own step (fragile: polished where it is).

The search stops at the first accepted trial, at the budget (ladder checks count), or on Ctrl-C
(the best so far is returned, ``stopped`` "interrupted").

Reproducible: batches have a fixed size (:data:`.run.BATCH`), every random number comes from the
seeded Generator in a fixed order, pycma gets seeds drawn from it; the rollouts do not depend on
the number of threads, so ``--jobs`` changes nothing.

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
from nbst.models.mjsearch.engine import Engine
from nbst.seeds import check_seed

__all__ = ["DEFAULT_MAX_ROLLOUTS", "CRASH_EXPLORE", "PER_SIGNATURE", "POPULATION", "CREEP", "GA_BATCHES",
           "LADDER_CHECK_TIMESTEPS", "FRAGILE", "SIGMA0", "STALL", "SPENT", "RIGHT_KEPT", "Trial",
           "CrashProgress", "CrashResult", "contacts_right", "directed", "ladder_check", "solve"]

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


def _distance(t: Trial) -> int:
    """The engine's distance of a trial: 0 accepted (met, and held on the ladder when asked), 1 met
    at its own step only (fragile: polished where it is), 2 otherwise (the cost orders those)."""
    return 0 if t.accepted else 1 if t.outcome.solved else 2


def contacts_right(script: Script, t: Trial) -> bool:
    """Whether a trial has every vehicle's hits and the global order right (what is left is
    fine-tuning: rest poses, speeds, attitudes): the engine's *fine*.

    Args:
        script: the crash script.
        t: the trial.

    Returns:
        bool.
    """
    o = t.outcome
    if script.order is not None and not o.order_ok:
        return False
    return all(v.fate.hits is None or vo.fates.get("hits", True) for v, vo in zip(script.vehicles, o.vehicles))


def _directed_move(space: CrashSpace) -> Callable:
    """The engine's ``"directed"`` move: one vehicle's block of ``u`` set by :func:`directed`."""
    def move(engine: Engine, u: np.ndarray, block: int) -> None:
        blk = list(space.blocks[block])
        u[blk] = directed(space, engine.rng, u)[blk]
    return move


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
    try:
        S = space_of(script)
        check = ladder_check(script, R.xml, S) if ladder else None
        want = list(script.order or _fate_sequence(script))
        eng = Engine(S.dim, seed=np.random.default_rng(seed), max_rollouts=max_rollouts, blocks=S.blocks,
                     batch=BATCH, explore=explore, init=lambda e: directed(S, e.rng) if e.rng.random() < 0.5
                     else e.rng.random(S.dim), ga_batches=GA_BATCHES, ga_fine=1, moves={"directed": _directed_move(S)},
                     creep=(CREEP,), population=POPULATION, per_signature=PER_SIGNATURE, popsize=BATCH,
                     sigma0=SIGMA0, stall=STALL, schedule=(("best", 1.0), ("cell", 1.0 / 3.0)),
                     polish=(1.0, 1.0 / 3.0, 1.0 / 9.0), spent=SPENT, right_kept=RIGHT_KEPT, hold_distance=1,
                     rank=lambda seq: out_mod._edit(list(seq), want))
        first_met: list[int] = []

        def evaluate(U: np.ndarray) -> dict:
            res = R.run(S.intents(U))
            trials, extra = [], 0
            for i, (u, o) in enumerate(zip(U, res.outcomes)):
                t = Trial(u=u.copy(), outcome=o, controls=res.controls[i], qpos0=res.qpos0[i], qvel0=res.qvel0[i],
                          final_qpos=res.final_qpos[i])
                if o.solved and not first_met:
                    first_met.append(eng.rollouts + extra + i + 1)
                if o.solved and check is not None:
                    t.holds = bool(check(t))
                    extra += len(LADDER_CHECK_TIMESTEPS)  # counted: the ladder's rollouts are rollouts too
                if keep is not None:
                    keep(t)
                trials.append(t)
            return {"signatures": [t.signature for t in trials], "distances": [_distance(t) for t in trials],
                    "costs": [t.cost for t in trials], "cells": [t.outcome.sequence for t in trials],
                    "fine": [contacts_right(script, t) for t in trials], "payloads": trials,
                    "rollouts": len(U) + extra}

        def progress(e: Engine) -> None:
            if callback is not None:
                top = e.best.payload
                callback(CrashProgress(e.rollouts, top.cost, top.outcome.signature_text(S.n), top.accepted,
                                       len(e.archive)))

        t0 = time.perf_counter()
        r = eng.run(evaluate, progress)
    finally:
        if own:
            R.close()
    stopped = "interrupted" if "interrupted" in r.stopped else "found" if "solved" in r.stopped else "budget"
    return CrashResult(best=r.payload, rollouts=r.rollouts, restarts=r.restarts, stopped=stopped, seed=int(seed),
                       wall_time=time.perf_counter() - t0,
                       archive={k: float(m.cost) for k, m in r.archive.items()},
                       history=[(n, float(c)) for n, _, c in r.history], first_met=first_met[0] if first_met else None)
