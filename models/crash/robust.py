"""A crash that holds up: driver noise, the probability of the fates, the timestep ladder, and
the robust maximiser, on the rollout room's machinery (:mod:`nbst.models.mjsearch`).

**Driver noise** (:data:`NOISE`, standard deviations, SI; assumed figures, docs/crash.md names
their sensitivity): a driver never repeats an intent exactly. Every intent a script sets is
drawn from a normal distribution about its value (independent draws), clipped to what a car
can do (:data:`CLIP`); the after-impact choice is kept. **Common random numbers**: copy i of
any intent set uses row i of the same standard-normal draws of the seed
(:func:`nbst.models.mjsearch.probability.normal_draws`), so two intent sets are compared on
paired copies.

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

from nbst.models.crash import driver as drv
from nbst.models.crash.run import TIMESTEP_LADDER, CrashRunner
from nbst.models.crash.script import AFTER_IMPACT, Range
from nbst.models.crash.space import CrashSpace
from nbst.models.mjsearch.ladder import climb
from nbst.models.mjsearch.probability import Probability, counts, normal_draws, perturb

__all__ = ["DEFAULT_SAMPLES", "DEFAULT_ROBUST_BUDGET", "NOISE", "CLIP", "sigma_row", "noisy", "label",
           "CrashEstimate", "estimate_of", "probability", "ladder", "ladder_rows", "RobustCrashProblem"]

#: Noisy copies a probability is estimated from when none is given (``nbst crash probability
#: --samples``; ``nbst crash solve --robust``'s fresh estimate).
DEFAULT_SAMPLES = 100
#: The robust maximiser's budget of noisy rollouts when none is given (``nbst crash solve --robust``).
DEFAULT_ROBUST_BUDGET = 600
#: Driver noise: standard deviation of each intent (SI).
NOISE = {"speed": 0.5, "aim_x": 0.2, "aim_y": 0.2, "arrive": 0.1, "brake_at": 0.1, "slide_at": 0.1,
         "slide_steer": math.radians(1.0), "slide_power": 0.05, "headway": 0.05, "reaction": 0.1,
         "after_steer": math.radians(1.0)}
#: What a noisy intent is clipped to (a car's and a driver's limits, not the script's ranges).
CLIP = {"speed": (0.0, 70.0), "arrive": (0.0, 60.0), "brake_at": (0.0, 60.0), "slide_at": (0.0, 60.0),
        "slide_steer": (-math.radians(35), math.radians(35)), "slide_power": (0.0, 1.0), "headway": (0.05, 10.0),
        "reaction": (0.0, 5.0), "after_steer": (-math.radians(35), math.radians(35))}


def sigma_row() -> np.ndarray:
    """(len(INTENT),) the noise of each intent column (0 where none)."""
    return np.array([NOISE.get(k, 0.0) for k in drv.INTENT])


def noisy(intents: np.ndarray, m: int, seed: int) -> np.ndarray:
    """(m, n, len(INTENT)) noisy copies of ``intents`` (n, len(INTENT)); copy i is the same draw
    for every intent set (common random numbers). Off behaviours (NaN) stay off."""
    n, P = intents.shape
    lo = np.full((n, P), -np.inf)
    hi = np.full((n, P), np.inf)
    for k, (a, b) in CLIP.items():
        lo[:, drv.IX[k]], hi[:, drv.IX[k]] = a, b
    draws = normal_draws(seed, m, n * P).reshape(m, n, P)
    return perturb(intents[None], np.broadcast_to(sigma_row(), (n, P))[None], draws, lo[None], hi[None])


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

    def __getattr__(self, name):  # k, n, p, lo, hi, text() of the probability
        if name == "prob":
            raise AttributeError(name)
        return getattr(self.prob, name)

    def to_dict(self) -> dict:
        pr = self.prob
        return {"k": pr.k, "n": pr.n, "p": pr.p, "lo": pr.lo, "hi": pr.hi, "seed": self.seed,
                "noise": {k: NOISE[k] for k in NOISE}, "outcomes": dict(self.outcomes)}


def estimate_of(outcomes, seed: int) -> CrashEstimate:
    k = sum(1 for o in outcomes if o.solved)
    return CrashEstimate(prob=Probability.of(k, len(outcomes)), seed=int(seed),
                         outcomes=counts(label(o) for o in outcomes))


def probability(runner: CrashRunner, intents: np.ndarray, n: int, seed: int, *, on_batch=None) -> CrashEstimate:
    """The probability that ``intents`` meet the script under driver noise (``n`` copies of ``seed``)."""
    copies = noisy(np.asarray(intents, dtype=float), n, seed)
    outs = []
    for k in range(0, n, runner.size):
        outs += runner.run(copies[k:k + runner.size]).outcomes
        if on_batch:
            on_batch(len(outs))
    return estimate_of(outs, seed)


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
    set (n, len(INTENT)); a point is the search space's coordinates, each in its noise sigma."""

    def __init__(self, space: CrashSpace, runner: CrashRunner, xml: str):
        self.S, self.R, self.xml = space, runner, xml
        sig = sigma_row()
        self.scale = np.array([sig[f] if isinstance(r, Range) and sig[f] > 0 else 1.0 for _, f, r in space.coords])
        self.moved = np.array([1.0 if isinstance(r, Range) and sig[f] > 0 else 0.0 for _, f, r in space.coords])
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
        return list(noisy(cand, m, seed))

    def run(self, copies: list) -> list:
        out = []
        for k in range(0, len(copies), self.R.size):
            out += self.R.run(np.array(copies[k:k + self.R.size])).outcomes
        return out

    def judge(self, o):
        return bool(o.solved), bin(o.signature).count("1"), label(o)

    def ladder(self, cand):
        lad = ladder(self.R.script, self.xml, cand)
        return ladder_rows(lad), bool(lad.results[0].solved and lad.holds), len(lad.timesteps)

    def fresh(self, cand, n: int, seed: int) -> CrashEstimate:
        return probability(self.R, cand, n, seed)


def _after_name(code: float) -> str:
    """The after-impact choice an intent column's code stands for."""
    return AFTER_IMPACT[int(code)]


def _after_code(choice: str) -> float:
    """The intent column's code of an after-impact choice."""
    return float(AFTER_IMPACT.index(choice))
