"""A throw that holds up: maximise the probability of an outcome under the release noise.

:func:`maximise` searches the delivery of :mod:`.lane` (board at the foul line, launch angle,
mph, rpm, axis rotation; the axis tilt only when the noise moves it; the hand is kept) for the
highest probability that a frame gives the outcome (every pin in play down, or with ``want``
exactly those pins down) under the release noise of :mod:`.noise`. The search is the rollout
room's (:func:`nbst.models.mjsearch.robust.maximise`); this module is its bowling side
(:class:`Release`: deliveries as points in noise sigmas, noisy throws, frames, pins right).

**Method** (a (1+lambda) evolution strategy with a cross-entropy step, on paired throws):

* **Scaled coordinates.** Each parameter is measured in its noise sigma (1/2 board, 0.15 deg,
  0.3 mph, 15 rpm, 5 deg by default; a parameter the noise does not move uses
  :data:`.noise.DEFAULT`'s sigma, and the tilt stays fixed unless the noise moves it), so a
  step of 1 is as far as one sigma of the bowler's own scatter.
* **Common random numbers.** Every candidate is scored on the *same* ``m`` noisy throws: the
  same standard-normal draws of :func:`.noise.sample` (one screen seed, derived from
  ``seed``) added to its own release. Two candidates then differ only on the throws whose
  outcome differs, and a comparison is paired, not two independent estimates. A score is
  (throws with the outcome, pins right summed over the throws), compared in that order.
* **The incumbent** is the best start on the ``m`` throws (``m`` = ``budget`` // 6, between
  12 and 60). Each generation proposes ``lambda`` candidates about it: steps of 1/2, 1 and 2
  (times the step size) along the cross-entropy direction -- the mean scaled offset of the
  incumbent's own noisy throws that gave the outcome minus the mean of all of them (the
  score-function estimate of the gradient of the probability, free from throws already run)
  -- and Gaussian steps of the step size in every coordinate.
* **Successive halving.** Candidates are first run on the informative throws only: those
  the incumbent failed and as many it passed (at least 4). The best two that beat the
  incumbent there are run on the rest of the ``m``; the best of them replaces the incumbent only when its
  score on all ``m`` is higher. A success widens the step size (x 1.4), a failure narrows it
  (x 0.7), within [0.25, 3]. The search ends when the budget is spent or the incumbent gives
  the outcome on every one of the ``m`` throws (the screen can then tell no better).
* **The pick** is the latest incumbent whose noise-free throw gives the outcome at every
  timestep of :data:`.frame.LADDER` (1, 0.5, 0.25 ms), going back along the accepted
  incumbents (at most 3 tried; the best on the screen if none holds: ``ladder_holds`` False).
  Every accepted incumbent scores higher on the screen than the one before it, so the pick
  is never worse on the screen than the best start.
  Its probability is measured **afresh** on ``n`` throws with the seed ``seed`` itself,
  which the search never used: the screen score is biased upwards (the pick was selected
  on those throws); the fresh one is not.

**Assumptions.** The probability is smooth enough on the scale of a sigma for a local search
to climb it (it is a step function of the release for a single throw, smoothed by the noise);
a local optimum near the starts is what is found (give several starts to cover more); the
throws of the screen stand for the noise (``m`` of them; the fresh estimate checks it).

**Budget** is in frames: the search (starts and candidates) stops before running more than
``budget`` noisy frames; the fresh estimate's ``n`` and the ladder's frames (3 per pick
tried, run in this process) come on top, and ``frames`` counts them all. ``on_done()`` is
called after each noisy frame: at most ``budget + n`` calls. The result depends on ``seed``
only, not on the runner's number of processes (its frames come back in order).

**Ctrl-C**: a KeyboardInterrupt during the search, the ladder or the fresh estimate is
raised again as :class:`Interrupted` (a KeyboardInterrupt) whose ``best`` is the incumbent
so far (a Delivery), with its screen score, the frames run and the history.

Compute only: no files, no printing.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, field, replace
from typing import Any

import numpy as np

from nbst.models.bowling import lane
from nbst.models.bowling.lane import frame, noise as noise_mod
from nbst.models.mjsearch import robust as _robust
from nbst.models.mjsearch.robust import (ALONG, GAUSS, LADDER_TRIES, NARROW, SCREEN_DIV, SCREEN_MAX,  # noqa: F401
                                         SCREEN_MIN, SECOND_RUNG, STEP0, STEP_MAX, STEP_MIN, WIDEN, Interrupted)

__all__ = ["KEYS", "RobustResult", "Release", "maximise", "Interrupted", "LADDER_TRIES"]

#: Parameters searched (the tilt is carried, and moved only when the noise moves it).
KEYS = ("board", "angle", "mph", "rpm", "rotation", "tilt")


@dataclass
class RobustResult:
    """The pick of :func:`maximise` (a Delivery with the board at the foul line)."""

    delivery: lane.Delivery
    start: lane.Delivery  # the best start (the pick's screen is never below its)
    want: list | None
    standing: list
    estimate: noise_mod.Estimate  # fresh: seed ``seed``, n throws
    screen: noise_mod.Estimate  # the pick on the search's common throws (biased upwards)
    start_screen: noise_mod.Estimate  # the best start on the same throws
    ladder: list  # [timestep, leave, down] of the pick without noise (empty if ladder=False)
    ladder_holds: bool | None
    frames: int
    budget: int
    history: list = field(default_factory=list)

    def to_dict(self) -> dict:
        d = asdict(self)
        d["delivery"], d["start"] = self.delivery.to_dict(), self.start.to_dict()
        return d


class Release:
    """The rollout room's :class:`~nbst.models.mjsearch.robust.RobustProblem` for a bowler's release:
    candidates are Deliveries (the board at the foul line), points their :data:`KEYS` in noise
    sigmas, noisy copies :func:`.noise.sample`'s, run as frames on the pins ``standing``."""

    def __init__(self, base: lane.Delivery, *, standing, want, runner: frame.FrameRunner, nz: noise_mod.Noise,
                 on_done=None):
        self.base, self.standing, self.want, self.runner, self.nz, self.on_done = \
            base, standing, want, runner, nz, on_done
        self.scale = {k: (getattr(nz, k) or getattr(noise_mod.DEFAULT, k) or 1.0) for k in KEYS}
        self.moved = np.array([1.0 if k != "tilt" or nz.tilt > 0 else 0.0 for k in KEYS])  # the tilt: only if noisy

    def delivery(self, x) -> lane.Delivery:
        kw: dict[str, Any] = {}
        for k, v in zip(KEYS, x):
            lo, hi = noise_mod.CLIP[k]
            kw[k] = float(np.clip(v * self.scale[k], lo, hi))
        return replace(self.base, **kw)

    def point(self, d: lane.Delivery) -> np.ndarray:
        return np.array([getattr(d, k) / self.scale[k] for k in KEYS])

    def project(self, x) -> np.ndarray:
        return self.point(self.delivery(x))  # clipped to the limits

    def make(self, x) -> lane.Delivery:
        return self.delivery(x).check()  # LaneError (a ValueError) when off the lane

    def noisy(self, d: lane.Delivery, m: int, seed: int) -> list:
        return noise_mod.sample(d, m, seed, self.nz)

    def run(self, throws: list) -> list:
        return self.runner.map(throws, standing=self.standing, on_done=self.on_done)

    def judge(self, r) -> tuple[bool, int, str]:
        down = set(r.down)
        target = set(r.in_play) if self.want is None else set(self.want)
        right = sum(1 for p in r.in_play if (p in down) == (p in target))
        return noise_mod.success(r, self.want), right, "-".join(str(p) for p in r.leave)

    def ladder(self, d: lane.Delivery) -> tuple[list, bool, int]:
        rs = frame.ladder(d, self.runner.oil, self.runner.ball, standing=self.standing)
        return [[r.timestep, r.leave, r.down] for r in rs], all(noise_mod.success(r, self.want) for r in rs), len(rs)

    def fresh(self, d: lane.Delivery, n: int, seed: int) -> noise_mod.Estimate:
        est, _ = noise_mod.probability(d, n, seed, runner=self.runner, standing=self.standing, noise=self.nz,
                                       on_done=self.on_done, want=self.want)
        return est

    def estimate(self, screen: _robust.Screen, seed: int) -> noise_mod.Estimate:
        lo, hi = noise_mod.wilson(screen.k, screen.n)
        return noise_mod.Estimate(k=screen.k, n=screen.n, p=screen.k / screen.n, lo=lo, hi=hi, seed=int(seed),
                                  noise=self.nz.to_dict(),
                                  leaves=dict(sorted(screen.labels.items(), key=lambda kv: -kv[1])))


def maximise(starts, *, standing=None, want=None, runner: frame.FrameRunner, budget: int, seed: int,
             noise: noise_mod.Noise = noise_mod.DEFAULT, on_done=None, ladder: bool = True,
             n: int = 60) -> RobustResult:
    """The release near ``starts`` (a Delivery or several, the same hand) with the highest
    probability of the outcome on the pins in ``standing`` (default all ten): every pin in play
    down, or exactly the pins of ``want`` down. ``budget``: noisy frames for the search; ``n``:
    throws of the fresh estimate (seed ``seed``). See the module docstring for the method.

    Args:
        starts: a :class:`.lane.Delivery` or several (the same hand).
        standing: the pins standing (None: all ten).
        want: the pins to knock down exactly (None: convert every pin in play).
        runner: the :class:`.frame.FrameRunner` that runs the frames.
        budget: noisy frames of the search (a whole number >= 1).
        seed: the seed of the search and of the fresh estimate.
        noise: the release noise.
        on_done: called after each frame.
        ladder: whether to prefer a pick that keeps its outcome at every timestep of the ladder.
        n: throws of the fresh estimate (a whole number >= 1).

    Returns:
        a :class:`RobustResult` (the pick, its fresh estimate, the screens, the ladder, the frames run).

    Raises:
        LaneError: a start, ``want``, ``budget``, ``n`` or the noise refused.
        Interrupted: on Ctrl-C (a KeyboardInterrupt carrying the best delivery so far).
    """
    nz = noise.check()
    want = noise_mod.wanted(want)
    in_play = sorted(set(range(1, 11) if standing is None else standing))
    if want is not None and not set(want) <= set(in_play):
        raise lane.LaneError(f"want: pins {want} are not all in play ({in_play})")
    if not (isinstance(budget, int) and budget >= 1):
        raise lane.LaneError(f"budget: must be a whole number of frames >= 1, got {budget!r}")
    if not (isinstance(n, int) and n >= 1):
        raise lane.LaneError(f"n: must be a whole number >= 1, got {n!r}")
    starts = [starts] if isinstance(starts, lane.Delivery) else list(starts)
    if not starts:
        raise lane.LaneError("starts: give at least one delivery")
    starts = [replace(d.check(), board=d.foul_board(), at="foul") for d in starts]
    if len({d.hand for d in starts}) > 1:
        raise lane.LaneError("starts: every start must be thrown with the same hand")
    P = Release(starts[0], standing=in_play, want=want, runner=runner, nz=nz, on_done=on_done)
    got = _robust.maximise(P, starts, budget=budget, seed=seed, n=n, ladder=ladder)
    return RobustResult(delivery=got.best, start=got.start, want=want, standing=in_play, estimate=got.fresh,
                        screen=P.estimate(got.screen, got.screen_seed),
                        start_screen=P.estimate(got.start_screen, got.screen_seed), ladder=got.ladder,
                        ladder_holds=got.ladder_holds, frames=got.frames + n, budget=budget, history=got.history)
