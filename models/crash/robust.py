"""A crash that holds up: driver noise, the probability of the fates, the timestep ladder, and
the robust maximiser, on the rollout room's machinery (:mod:`nbst.models.mjsearch`).

**Driver noise**, two kinds (:data:`NOISE_KINDS`, standard deviations, SI): a driver never
repeats an intent exactly. **Retake** noise (:data:`NOISE`, the default; assumed figures) is what
a stunt crew repeats from take to take: the same drivers, rehearsed. **Population** noise
(:data:`POPULATION`; published spreads, docs/crash.md cites them) is what real drivers vary:
perception-reaction times, chosen speeds, lane position; a crash its fates hold under it is one
ordinary drivers would repeat. Every intent a script sets is drawn from a normal distribution
about its value (independent draws; :data:`RELATIVE` columns scale with the intent: a share of
the speed), clipped to what a car can do (:data:`CLIP`); the after-impact choice is kept.
**Common random numbers**: copy i of any intent set uses row i of the same standard-normal
draws of the seed (:func:`nbst.models.mjsearch.probability.normal_draws`), so two intent sets
are compared on paired copies (and the two kinds on the same draws).

:func:`probability`: the share of ``n`` noisy copies that meet the script, with its 95 %
Wilson interval, and how often each outcome came up. :func:`ladder`: the same intents run at
2, 1 and 0.5 ms (:data:`.run.TIMESTEP_LADDER`; the drivers keep their 20 ms period): a crash
is a result when its outcome (signature, order, met) holds at every rung.
:class:`RobustCrashProblem` is the crash as the room's
:func:`~nbst.models.mjsearch.robust.maximise` sees it (``nbst crash solve --robust``).

Compute only.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from nbst.errors import InputError
from nbst.models.crash import driver as drv
from nbst.models.crash.run import BATCH, TIMESTEP_LADDER, CrashRunner
from nbst.models.crash.script import AFTER_IMPACT, Range
from nbst.models.crash.slack import soft_climb
from nbst.models.crash.space import CrashSpace
from nbst.models.mjsearch.ladder import climb
from nbst.models.mjsearch.probability import Probability, counts, normal_draws, perturb
from nbst.seeds import derived_seed

__all__ = ["DEFAULT_SAMPLES", "SOLVE_SAMPLES", "DEFAULT_ROBUST_BUDGET", "NOISE", "POPULATION", "RELATIVE",
           "NOISE_KINDS", "DEFAULT_NOISE", "CLIP", "check_noise", "sigma_row", "noisy", "label", "CrashEstimate",
           "estimate_of", "probability", "ladder", "ladder_rows", "RobustCrashProblem", "POOL_SHARE", "POOL_SEARCHES", "POOL_ROLLOUTS", "RACE_SHARE",
           "RACE_COPIES", "SOFT_SHARE", "RobustPick", "robust_pick", "LOTTERY_P", "lottery"]

#: Noisy copies a probability is estimated from when none is given (``nbst crash probability
#: --samples``; ``nbst crash solve --robust``'s fresh estimate).
DEFAULT_SAMPLES = 100
#: Noisy copies of the probability every ``nbst crash solve`` writes (its ``--samples`` default;
#: 0 skips it): cheap beside the search (32 rollouts; a few seconds), and enough to tell a crash
#: its drivers repeat most of the time from a lottery (0 of 32: the 95 % Wilson interval 0-11 %).
SOLVE_SAMPLES = 32
#: The robust maximiser's budget of noisy rollouts when none is given (``nbst crash solve --robust``).
DEFAULT_ROBUST_BUDGET = 1200
#: Below this share of its own drivers' noisy re-drives meeting the script, a crash is a **lottery**, not a
#: script (issue 47: fates met 0-6 % of the time; the t-bone under retake noise, whichever crash
#: meets it): the file marks it (``probability.lottery``) and ``nbst crash solve`` says so.
LOTTERY_P = 0.10
#: Retake noise (a stunt crew's take to take; assumed): standard deviation of each intent (SI).
NOISE = {"speed": 0.5, "aim_x": 0.2, "aim_y": 0.2, "arrive": 0.1, "brake_at": 0.1, "slide_at": 0.1,
         "slide_steer": math.radians(1.0), "slide_power": 0.05, "headway": 0.05, "reaction": 0.1,
         "after_steer": math.radians(1.0)}
#: Population noise (what ordinary drivers vary; docs/crash.md cites each): the perception-reaction
#: time of a brake, a slide or a follower, 0.44 s (Johansson and Rumar 1971: median 0.9 s, a
#: quarter above 1.2 s, as a log-normal); the chosen speed and so the arrival time, 13.5 % of the
#: intent (FHWA-SA-10-001 ch. 5: speeds normally distributed, SD 7 mph about a 52 mph mean); the
#: lane position, 0.2 m (the weaving, SDLP, of sober drivers: Verster and Roth 2011); the time gap
#: behind a leader, 0.3 s (1-2 s in rush-hour traffic: Ayres et al. 2001); the stunt manoeuvres
#: (slide steer and power, the wheel after impact), which no survey measures, as in retakes.
POPULATION = {"speed": 0.135, "aim_x": 0.2, "aim_y": 0.2, "arrive": 0.135, "brake_at": 0.44, "slide_at": 0.44,
              "slide_steer": math.radians(1.0), "slide_power": 0.05, "headway": 0.3, "reaction": 0.44,
              "after_steer": math.radians(1.0)}
#: The kinds of driver noise by name, and the columns each gives as a share of the intent's value.
NOISE_KINDS = dict(zip(drv.NOISE_KIND_NAMES, (NOISE, POPULATION)))
RELATIVE = {"retake": (), "population": ("speed", "arrive")}
#: The noise a probability is measured under when none is named.
DEFAULT_NOISE = drv.NOISE_KIND_NAMES[0]
#: What a noisy intent is clipped to (a car's and a driver's limits, not the script's ranges).
CLIP = {"speed": (0.0, 70.0), "arrive": (0.0, 60.0), "brake_at": (0.0, 60.0), "slide_at": (0.0, 60.0),
        "slide_steer": (-math.radians(35), math.radians(35)), "slide_power": (0.0, 1.0), "headway": (0.05, 10.0),
        "reaction": (0.0, 5.0), "after_steer": (-math.radians(35), math.radians(35))}


def check_noise(noise: str) -> str:
    """The noise kind ``noise`` checked.

    Args:
        noise: a name of :data:`NOISE_KINDS`.

    Returns:
        The name.

    Raises:
        InputError: an unknown kind.
    """
    if noise not in NOISE_KINDS:
        raise InputError(f"noise: {noise!r} is not a kind of driver noise; known: {', '.join(NOISE_KINDS)}")
    return noise


def sigma_row(noise: str = DEFAULT_NOISE) -> np.ndarray:
    """(len(INTENT),) the noise of each intent column (0 where none; a share of the intent for
    the kind's :data:`RELATIVE` columns)."""
    kind = NOISE_KINDS[check_noise(noise)]
    return np.array([kind.get(k, 0.0) for k in drv.INTENT])


def _sigmas(intents: np.ndarray, noise: str) -> np.ndarray:
    """(n, len(INTENT)) each intent's standard deviation under ``noise`` (SI)."""
    sig = np.broadcast_to(sigma_row(noise), intents.shape).copy()
    for k in RELATIVE[noise]:
        j = drv.IX[k]
        sig[:, j] = sig[:, j] * np.abs(np.nan_to_num(intents[:, j]))
    return sig


def noisy(intents: np.ndarray, m: int, seed: int, noise: str = DEFAULT_NOISE) -> np.ndarray:
    """(m, n, len(INTENT)) noisy copies of ``intents`` (n, len(INTENT)) under the kind ``noise``
    (:data:`NOISE_KINDS`); copy i is the same draw for every intent set and every kind (common
    random numbers). Off behaviours (NaN) stay off."""
    n, P = intents.shape
    lo = np.full((n, P), -np.inf)
    hi = np.full((n, P), np.inf)
    for k, (a, b) in CLIP.items():
        lo[:, drv.IX[k]], hi[:, drv.IX[k]] = a, b
    draws = normal_draws(seed, m, n * P).reshape(m, n, P)
    return perturb(intents[None], _sigmas(intents, noise)[None], draws, lo[None], hi[None])


def label(o) -> str:
    """An outcome as one short label: the signature, '+' when the script is met, '*' when the
    global order is wrong."""
    return o.signature_text(len(o.vehicles)) + ("+" if o.solved else "") + ("" if o.order_ok else "*")


@dataclass
class CrashEstimate:
    """The room's :class:`~nbst.models.mjsearch.probability.Probability` (k of n noisy copies met
    the script, its Wilson interval) with the seed and the outcomes seen ({label: count})."""

    prob: Probability
    seed: int
    outcomes: dict
    noise: str = DEFAULT_NOISE

    def __getattr__(self, name):  # k, n, p, lo, hi, text() of the probability
        if name == "prob":
            raise AttributeError(name)
        return getattr(self.prob, name)

    def to_dict(self) -> dict:
        pr = self.prob
        kind = NOISE_KINDS[self.noise]
        return {"k": pr.k, "n": pr.n, "p": pr.p, "lo": pr.lo, "hi": pr.hi, "seed": self.seed,
                "noise_kind": self.noise, "noise": {k: kind[k] for k in kind},
                "noise_relative": list(RELATIVE[self.noise]), "outcomes": dict(self.outcomes),
                "lottery": lottery(pr)}


def lottery(prob) -> bool:
    """Whether a probability (k of n re-drives met the script) makes its crash a lottery: its
    share ``p`` under :data:`LOTTERY_P` (fewer than 1 take in 10 repeats it)."""
    return bool(prob.p < LOTTERY_P)


def estimate_of(outcomes, seed: int, noise: str = DEFAULT_NOISE) -> CrashEstimate:
    k = sum(1 for o in outcomes if o.solved)
    return CrashEstimate(prob=Probability.of(k, len(outcomes)), seed=int(seed),
                         outcomes=counts(label(o) for o in outcomes), noise=check_noise(noise))


def probability(runner: CrashRunner, intents: np.ndarray, n: int, seed: int, *, noise: str = DEFAULT_NOISE,
                on_batch=None) -> CrashEstimate:
    """The probability that ``intents`` meet the script under driver noise.

    Args:
        runner: the crash's runner.
        intents: (vehicles, len(INTENT)) the drivers' intents.
        n: noisy copies.
        seed: the noise's seed (common random numbers).
        noise: the kind of driver noise (:data:`NOISE_KINDS`).
        on_batch: called with the copies run so far after each batch.

    Returns:
        A :class:`CrashEstimate`.

    Raises:
        InputError: an unknown noise kind.
    """
    check_noise(noise)
    copies = noisy(np.asarray(intents, dtype=float), n, seed, noise)
    outs = []
    for k in range(0, n, runner.size):
        outs += runner.run(copies[k:k + runner.size]).outcomes
        if on_batch:
            on_batch(len(outs))
    return estimate_of(outs, seed, noise)


def ladder(script, xml: str, intents: np.ndarray, timesteps=TIMESTEP_LADDER):
    """The intents run at each timestep (the same scene text): a ``mjsearch.ladder.Ladder`` of
    (signature, met, contact sequence); ``wanted`` is the first rung's."""
    def run(h):
        R = CrashRunner(script, xml=xml, timestep=h, batch=1)
        try:
            return R.run(np.asarray(intents, dtype=float)[None]).outcomes[0]
        finally:
            R.close()

    return climb(run, timesteps, outcome=lambda o: (o.signature, o.solved, o.sequence))


def ladder_rows(lad) -> list:
    """[[timestep s, signature, met, contact sequence]] of a ladder, for files and readouts."""
    n = len(lad.results[0].vehicles) if lad.results else 0
    return [[h, o.signature_text(n), bool(o.solved), [list(p) for p in o.sequence]]
            for h, o in zip(lad.timesteps, lad.results)]


class RobustCrashProblem:
    """The crash as :func:`nbst.models.mjsearch.robust.maximise` sees it: a candidate is an intent
    set (n, len(INTENT)); a point is the search space's coordinates, each in its noise sigma
    (under ``noise``; a relative column's sigma taken at ``ref``, the start's intents)."""

    def __init__(self, space: CrashSpace, runner: CrashRunner, xml: str, noise: str = DEFAULT_NOISE, ref=None):
        self.S, self.R, self.xml, self.noise = space, runner, xml, check_noise(noise)
        sig = _sigmas(np.asarray(space.base if ref is None else ref, dtype=float), noise)
        self.sig = np.array([sig[i, f] if isinstance(r, Range) else 0.0 for i, f, r in space.coords])
        ok = np.isfinite(self.sig) & (self.sig > 0)
        self.scale = np.where(ok, self.sig, 1.0)
        self.moved = np.array([1.0 if isinstance(r, Range) and good else 0.0 for (_, _, r), good in zip(space.coords, ok)])
        self.lo = np.array([r.lo if isinstance(r, Range) else 0.0 for _, _, r in space.coords])
        self.hi = np.array([r.hi if isinstance(r, Range) else 0.0 for _, _, r in space.coords])

    def _values(self, cand) -> np.ndarray:
        return np.array([cand[i, f] if isinstance(r, Range) else float(r.index(_after_name(cand[i, f])))
                         for i, f, r in self.S.coords])

    def project(self, x):
        v = np.asarray(x, dtype=float) * self.scale
        keep = self.moved > 0
        v[keep] = np.clip(v[keep], self.lo[keep], self.hi[keep])
        return v / self.scale

    def make(self, x):
        v = np.asarray(x, dtype=float) * self.scale
        cand = self.S.base.copy()
        for k, (i, f, r) in enumerate(self.S.coords):
            if isinstance(r, Range):
                cand[i, f] = np.clip(v[k], r.lo, r.hi)
            else:
                cand[i, f] = _after_code(r[int(np.clip(round(v[k]), 0, len(r) - 1))])
        return cand

    def point(self, cand):
        return self._values(cand) / self.scale

    def noisy(self, cand, m: int, seed: int) -> list:
        return list(noisy(cand, m, seed, self.noise))

    def run(self, copies: list) -> list:
        out = []
        for k in range(0, len(copies), self.R.size):
            out += self.R.run(np.array(copies[k:k + self.R.size])).outcomes
        return out

    def judge(self, o):
        # partial credit: the fates held (bits), then how near the rest came (a finer tie-break
        # between candidates that meet the script equally often on the screen)
        return bool(o.solved), bin(o.signature).count("1") - min(o.cost, 100.0) / 1000.0, label(o)

    def ladder(self, cand):
        lad = ladder(self.R.script, self.xml, cand)
        return ladder_rows(lad), bool(lad.results[0].solved and lad.holds), len(lad.timesteps)

    def fresh(self, cand, n: int, seed: int) -> CrashEstimate:
        return probability(self.R, cand, n, seed, noise=self.noise)


#: The robust pick's stages (:func:`robust_pick`), in noisy rollouts of its budget: **gathering**
#: other crashes that meet the script, from short searches of the crash (:func:`.search.solve`)
#: from seeds derived from the pick's (at most POOL_SEARCHES, each at most POOL_ROLLOUTS, all
#: within POOL_SHARE of the budget); **racing** them (successive halving from RACE_COPIES common
#: copies each, within RACE_SHARE); the **soft climb** of the winner (:data:`SOFT_SHARE` of what
#: is left: :func:`.slack.soft_climb`); the room's **maximiser** (the rest).
POOL_SHARE, POOL_SEARCHES, POOL_ROLLOUTS = 0.4, 6, 400
RACE_SHARE, RACE_COPIES = 0.3, 12
SOFT_SHARE = 0.6


def _gather(P: RobustCrashProblem, start: np.ndarray, budget: int, seed: int, ladder: bool):
    """Other crashes that meet the script: short crash searches (:func:`.search.solve`) from seeds
    derived from ``seed``, each stopping at its first crash that meets the script (and keeps
    meeting it at 1 and 0.5 ms when ``ladder``), all within ``budget`` rollouts. Every accepted
    trial a search ran is kept (a search's last batch may hold several). Returns (members: the
    start first, then the new ones in the order found, each (intents, from): 'start' or the
    search's seed; rollouts run; searches run)."""
    from nbst.models.crash import search

    members: list[tuple[np.ndarray, object]] = [(np.asarray(start, dtype=float), "start")]
    used = runs = 0
    for k in range(POOL_SEARCHES):
        cap = min(POOL_ROLLOUTS, budget - used)
        if cap < BATCH * 4:  # too few for a search to find anything
            break
        s = derived_seed(seed, 47, k)
        found: list = []
        res = search.solve(P.R.script, seed=s, max_rollouts=cap, runner=P.R, ladder=ladder,
                           keep=lambda t: found.append(t) if t.accepted else None)
        used += res.rollouts
        runs += 1
        for t in found:
            cand = P.S.intents(t.u[None])[0]
            if not any(np.allclose(np.nan_to_num(cand), np.nan_to_num(c), atol=1e-9) for c, _ in members):
                members.append((cand, s))
    return members, used, runs


def _race(P: RobustCrashProblem, members: list, budget: int, seed: int):
    """Successive halving on common copies: every member is run on the first RACE_COPIES noisy
    copies of one race seed (copy i the same draw for all), the better half (copies that meet the
    script, then partial credit) goes on to twice as many copies, and so on while the budget
    allows. Returns (the members' indices ranked, best first: the survivors of the last rung by
    their score on its copies, then the others by the rung each reached and their score there;
    rows [index, met, copies run] in member order; rollouts run)."""
    if len(members) == 1:
        return [0], [[0, 0, 0]], 0
    cs = derived_seed(seed, 48)
    got: list[list] = [[] for _ in members]
    alive = list(range(len(members)))
    reached = {i: 0 for i in alive}
    m, used = RACE_COPIES, 0
    while alive:
        need = sum(max(0, m - len(got[i])) for i in alive)
        if used + need > budget:
            break
        todo = [(i, c) for i in alive for c in P.noisy(members[i], m, cs)[len(got[i]):]]
        for (i, _), o in zip(todo, P.run([c for _, c in todo])):
            got[i].append(P.judge(o))
        used += need
        for i in alive:
            reached[i] = m
        if len(alive) == 1:
            break
        score = {i: (sum(g[0] for g in got[i][:m]), sum(g[1] for g in got[i][:m])) for i in alive}
        alive = sorted(alive, key=lambda i: (score[i], -i), reverse=True)[:(len(alive) + 1) // 2]
        m *= 2

    def key(i):
        r = reached[i]
        return (r, sum(g[0] for g in got[i][:r]), sum(g[1] for g in got[i][:r]), -i)

    order = sorted(range(len(members)), key=key, reverse=True)
    return order, [[i, int(sum(g[0] for g in got[i])), len(got[i])] for i in range(len(members))], used


def robust_pick(space: CrashSpace, runner: CrashRunner, intents: np.ndarray, *, budget: int, seed: int, n: int,
                noise: str = DEFAULT_NOISE, ladder: bool = True):
    """The crash that meets the script most often under driver noise, among ``intents`` and other
    crashes that meet it, and near the best of them. Four stages on one ``budget`` of noisy
    rollouts (:data:`POOL_SHARE` and the rest): other crashes gathered by short searches
    (:func:`_gather`: not only the neighbourhood of ``intents``), raced on common copies
    (:func:`_race`), the winner climbed by CMA-ES on the mean soft success of common copies
    (:func:`.slack.soft_climb`), then the room's robust maximiser from the climbed winner (when its
    screen is better) and the winner (the rest). The pick keeps its outcome on the ladder (the
    maximiser's, else the best-raced member that does) and its probability is measured afresh on
    ``n`` copies of ``seed`` (copies no stage ran).

    Args:
        space: the script's search space.
        runner: its runner.
        intents: (vehicles, len(INTENT)) a crash that meets the script.
        budget: noisy rollouts (and the gathering searches' rollouts) of the four stages; the
            ladder checks and the fresh estimate come on top.
        seed: the seed (searches, race, screens, steps, the fresh estimate).
        n: noisy copies of the fresh estimate.
        noise: the kind of driver noise (:data:`NOISE_KINDS`).
        ladder: keep only crashes that keep their outcome at 1 and 0.5 ms.

    Returns:
        A :class:`RobustPick`: the room's ``Maximum`` (``best``: the pick; ``fresh``: its
        :class:`CrashEstimate`; ``frames`` counting every stage), ``climb`` and ``race``.

    Raises:
        InputError: an unknown noise kind.
        SolveError: a budget or ``n`` the maximiser refuses.
    """
    from nbst.models.mjsearch import robust as room

    budget = int(budget)
    P = RobustCrashProblem(space, runner, runner.xml, noise=noise, ref=intents)
    intents = np.asarray(intents, dtype=float)
    members, used_pool, runs = _gather(P, intents, int(budget * POOL_SHARE), seed, ladder)
    order, rows, used_race = _race(P, [c for c, _ in members], int(budget * RACE_SHARE), seed)
    win = members[order[0]][0]
    left = budget - used_pool - used_race
    climbed, climb = soft_climb(P, win, int(left * SOFT_SHARE), seed)
    better = (climb["climbed"], climb["soft_climbed"]) > (climb["start"], climb["soft_start"])
    starts = [climbed, win] if better else [win]
    mx = room.maximise(P, starts, budget=max(1, left - climb["rollouts"]), seed=seed, n=n, ladder=ladder)
    mx.frames += used_pool + used_race + climb["rollouts"]
    fell_back = False
    if ladder and mx.ladder_holds is False:
        # the maximiser's steps left the ladder: the best-raced member that keeps it instead
        for i in order:
            rows_l, ok, ran = P.ladder(members[i][0])
            mx.frames += ran
            if ok:
                mx.best, mx.ladder, mx.ladder_holds, fell_back = members[i][0], rows_l, True, True
                mx.fresh = P.fresh(members[i][0], n, seed)
                break
    race = {"members": len(members), "searches": runs, "search_rollouts": used_pool, "rollouts": used_race,
            "table": [[r[0], str(members[r[0]][1]), r[1], r[2]] for r in rows], "winner": int(order[0]),
            "fell_back": fell_back}
    return RobustPick(mx=mx, climb=climb, race=race)


@dataclass
class RobustPick:
    """What :func:`robust_pick` found: the room's ``Maximum`` (its fields read through: best,
    fresh, frames, ladder, ...), the soft climb's ``climb`` ({copies, start, climbed, soft_start,
    soft_climbed, generations, rollouts}: how many of its confirming screen's copies the winner and
    the climbed intents met, and their mean soft success there) and the gathering and race's
    ``race`` ({members, searches, search_rollouts, rollouts, table:
    [[member, from (``start`` or the search's seed), met, copies run]], winner, fell_back: the
    pick is the race's best member that keeps the ladder, the maximiser's having lost it})."""

    mx: object
    climb: dict
    race: dict | None = None

    def __getattr__(self, name):
        if name in ("mx", "climb", "race"):
            raise AttributeError(name)
        return getattr(self.mx, name)


def _after_name(code: float) -> str:
    """The after-impact choice an intent column's code stands for."""
    return AFTER_IMPACT[int(code)]


def _after_code(choice: str) -> float:
    """The intent column's code of an after-impact choice."""
    return float(AFTER_IMPACT.index(choice))
