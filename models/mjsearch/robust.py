"""The robust maximiser: the parameter vector whose outcome holds most often under noise.

:func:`maximise` climbs the probability that a rollout gives the wanted outcome under the
caller's noise, from one or more starts. It knows nothing of the model: the caller passes a
:class:`RobustProblem` (how to turn a point into a candidate and back, how to draw its noisy copies
with common random numbers, how to run and judge them, the timestep ladder, the fresh
estimate).

**Method** (a (1+lambda) evolution strategy with a cross-entropy step, on paired trials):

* **Scaled coordinates.** The RobustProblem's points measure each parameter in its noise sigma, so a
  step of 1 is as far as one sigma of the noise; ``RobustProblem.moved`` masks the coordinates the
  search may move.
* **Common random numbers.** Every candidate is scored on the *same* ``m`` noisy copies (one
  screen seed, derived from ``seed``): two candidates differ only on the copies whose outcome
  differs, so a comparison is paired. A score is (copies with the outcome, partial credit
  summed over them), compared in that order.
* **The incumbent** is the best start on the ``m`` copies (``m`` = ``budget`` // 6, within
  [12, 60]). Each generation proposes candidates about it: steps of 1/2, 1 and 2 (times the
  step size) along the cross-entropy direction -- the mean scaled offset of the incumbent's
  own noisy copies that gave the outcome minus the mean of all of them (the score-function
  estimate of the gradient of the probability, free from copies already run) -- and
  Gaussian steps of the step size in every moved coordinate.
* **Successive halving.** Candidates are first run on the informative copies only: those the
  incumbent failed and as many it passed (at least 4). The best two that beat the incumbent
  there are run on the rest of the ``m``; the best of them replaces the incumbent only when
  its score on all ``m`` is higher. A success widens the step size (x 1.4), a failure narrows
  it (x 0.7), within [0.25, 3]. The search ends when the budget is spent or the incumbent
  gives the outcome on every one of the ``m`` copies.
* **The pick** is the latest incumbent whose noise-free rollout keeps the outcome at every
  timestep of the ladder (``RobustProblem.ladder``), going back along the accepted incumbents (at
  most 3 tried; the best on the screen if none holds: ``ladder_holds`` False). Its
  probability is then measured **afresh** (``RobustProblem.fresh``, ``n`` copies of the seed
  ``seed`` itself, which the search never used): the screen score is biased upwards.

**Budget** is in noisy rollouts: the search stops before running more than ``budget``; the
ladder's and the fresh estimate's rollouts come on top (``frames`` counts the search's and
the ladder's). The result depends on ``seed`` only, when ``RobustProblem.run`` returns results in
order. **Ctrl-C**: a KeyboardInterrupt is raised again as :class:`Interrupted` with the
incumbent so far.

Compute only: no files, no printing, no MuJoCo.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

from nbst.errors import SolveError
from nbst.seeds import derived_seed

__all__ = ["ALONG", "GAUSS", "STEP0", "STEP_MIN", "STEP_MAX", "WIDEN", "NARROW", "SCREEN_DIV", "SCREEN_MIN",
           "SCREEN_MAX", "SECOND_RUNG", "LADDER_TRIES", "SALT", "RobustProblem", "Interrupted", "Screen", "Maximum",
           "maximise"]

#: Candidates per generation: along the cross-entropy direction, and Gaussian.
ALONG = (0.5, 1.0, 2.0)
GAUSS = 5
#: Step size (in sigmas): start, bounds, and its change after a success / a failure.
STEP0, STEP_MIN, STEP_MAX, WIDEN, NARROW = 1.0, 0.25, 3.0, 1.4, 0.7
#: The screen's copies: budget // SCREEN_DIV, within [SCREEN_MIN, SCREEN_MAX].
SCREEN_DIV, SCREEN_MIN, SCREEN_MAX = 6, 12, 60
#: Candidates run on the whole screen per generation (the best of the first rung), at most.
SECOND_RUNG = 2
#: Accepted incumbents tried on the ladder, latest first.
LADDER_TRIES = 3
#: Salt of the seed sequence that derives the screen's seed and the search's generator from
#: ``seed`` (kept as first chosen, issue 22, so that results stay the same bits).
SALT = 22


class RobustProblem(Protocol):
    """What :func:`maximise` needs to know of a model; candidates are the caller's objects."""

    moved: np.ndarray  # (D,) 1.0 where the search may move the coordinate, else 0.0

    def project(self, x: np.ndarray) -> np.ndarray:
        """A scaled point clipped into the limits (a round trip through a candidate)."""

    def make(self, x: np.ndarray) -> Any:
        """The candidate at a projected point; ValueError when it is not a valid one."""

    def point(self, cand: Any) -> np.ndarray:
        """The scaled point of a candidate (or of one of its noisy copies)."""

    def noisy(self, cand: Any, m: int, seed: int) -> list:
        """``m`` noisy copies of ``cand``: copy i is the same draw for every candidate."""

    def run(self, copies: list) -> list:
        """Run the copies, results in order."""

    def judge(self, result: Any) -> tuple[bool, int, str]:
        """(outcome held, partial credit, label of what happened) of a result."""

    def ladder(self, cand: Any) -> tuple[list, bool, int]:
        """(rows, whether the noise-free outcome holds at every timestep, rollouts run)."""

    def fresh(self, cand: Any, n: int, seed: int) -> Any:
        """The fresh estimate of ``cand``'s probability (``n`` copies of ``seed``)."""


class Interrupted(KeyboardInterrupt):
    """Ctrl-C during :func:`maximise`: ``best`` is the incumbent so far, ``screen`` its (k, m) on
    the screen's copies (None before there was one), ``frames`` the rollouts run, ``history``
    the generations."""

    def __init__(self, best, screen, frames, history):
        super().__init__("robust search interrupted")
        self.best, self.screen, self.frames, self.history = best, screen, frames, history


@dataclass
class Screen:
    """A candidate on the screen's copies: k of n held; ``labels``: {label: count} in copy order."""

    k: int
    n: int
    labels: dict


@dataclass
class Maximum:
    """What :func:`maximise` found: the pick and the best start (candidates), their screens,
    the pick's ladder, the fresh estimate, the rollouts run and the generations."""

    best: Any
    start: Any
    screen: Screen
    start_screen: Screen
    screen_seed: int
    ladder: list
    ladder_holds: bool | None
    fresh: Any
    frames: int
    history: list = field(default_factory=list)


class _Search:
    """The bookkeeping of one search: candidates, their results on the common copies, rollouts."""

    def __init__(self, problem: RobustProblem, seed: int):
        self.P, self.seed = problem, seed
        self.frames = 0
        self.points: list[np.ndarray] = []
        self.res: list[dict] = []  # per candidate: copy index -> (held, credit, label)
        self.exact: dict = {}  # candidate -> a start's own object (no round trip through the scaling)

    def add(self, x) -> int | None:
        x = self.P.project(x)
        try:
            self.P.make(x)
        except ValueError:
            return None
        for i, p in enumerate(self.points):
            if np.allclose(p, x, atol=1e-9):
                return i
        self.points.append(x)
        self.res.append({})
        return len(self.points) - 1

    def of(self, c: int):
        e = self.exact.get(c)  # a candidate may be an array: no truth value
        return e if e is not None else self.P.make(self.points[c])

    def copies(self, c: int, idx) -> list:
        return self.P.noisy(self.of(c), max(idx) + 1, self.seed)

    def run(self, jobs: list, budget: int) -> bool:
        """Run (candidate, copy indices) pairs not yet run, in one batch; False (nothing run)
        if they do not fit in ``budget``."""
        todo = []
        for c, idx in jobs:
            need = [i for i in idx if i not in self.res[c]]
            if need:
                th = self.copies(c, need)
                todo += [(c, i, th[i]) for i in need]
        if not todo or self.frames + len(todo) > budget:
            return not todo
        out = self.P.run([t for _, _, t in todo])
        self.frames += len(todo)
        for (c, i, _), r in zip(todo, out):
            self.res[c][i] = self.P.judge(r)
        return True

    def score(self, c: int, idx) -> tuple[int, int]:
        got = [self.res[c][i] for i in idx]
        return sum(1 for g in got if g[0]), sum(g[1] for g in got)

    def offsets(self, c: int, idx) -> np.ndarray:
        """The scaled offsets of candidate ``c``'s noisy copies ``idx`` from its point (clipped)."""
        th = self.copies(c, idx)
        return np.array([self.P.point(th[i]) for i in idx]) - self.points[c]

    def screen(self, c: int, idx) -> Screen:
        labels: dict = {}
        for i in idx:
            labels[self.res[c][i][2]] = labels.get(self.res[c][i][2], 0) + 1
        return Screen(k=self.score(c, idx)[0], n=len(idx), labels=labels)


def maximise(problem: RobustProblem, starts: list, *, budget: int, seed: int, n: int, ladder: bool = True) -> Maximum:
    """The candidate near ``starts`` (candidates of ``problem``) with the highest probability of
    the outcome; ``budget``: noisy rollouts for the search; ``n``: copies of the fresh
    estimate (seed ``seed``). See the module docstring for the method."""
    if not (isinstance(budget, int) and budget >= 1):
        raise SolveError(f"budget: must be a whole number of frames >= 1, got {budget!r}")
    if not (isinstance(n, int) and n >= 1):
        raise SolveError(f"n: must be a whole number >= 1, got {n!r}")
    if not starts:
        raise SolveError("starts: give at least one")
    moved = np.asarray(problem.moved, dtype=float)
    screen_seed = derived_seed(seed, SALT)
    rng = np.random.default_rng(np.random.SeedSequence([int(seed), SALT]).spawn(1)[0])
    S = _Search(problem, screen_seed)
    m = int(np.clip(budget // SCREEN_DIV, SCREEN_MIN, SCREEN_MAX))
    history: list = []
    chain: list[int] = []  # accepted incumbents, oldest first
    start_ids = []
    for d in starts:
        c = S.add(problem.point(d))
        if c is not None and c not in start_ids:
            start_ids.append(c)
            S.exact[c] = d
    inc = None
    try:
        idx = list(range(m))
        fitted = [c for c in start_ids if S.run([(c, idx)], budget)]
        if not fitted:  # not even one start fits: screen the first on what the budget allows
            m = max(1, min(m, budget))
            idx = list(range(m))
            S.run([(start_ids[0], idx)], budget)
            fitted = [start_ids[0]]
        inc = max(fitted, key=lambda c: (S.score(c, idx), -c))
        best_start = inc
        chain.append(inc)
        step = STEP0
        history.append({"generation": 0, "m": m, "starts": len(fitted), "incumbent": list(S.score(inc, idx)),
                        "step": step, "frames": S.frames, "accepted": True})
        gen = 0
        while True:
            gen += 1
            frames0 = S.frames
            k_inc, _ = S.score(inc, idx)
            if k_inc == m:  # every common copy gives the outcome: the screen cannot tell better
                break
            fail = [i for i in idx if not S.res[inc][i][0]]
            passed = [i for i in idx if S.res[inc][i][0]]
            probe = sorted(fail + passed[:max(len(fail), 4)])
            rest = [i for i in idx if i not in set(probe)]
            # the cross-entropy direction from the incumbent's own copies
            z = S.offsets(inc, idx)
            y = np.array([1.0 if S.res[inc][i][0] else 0.0 for i in idx])
            g = ((y - y.mean())[:, None] * z).mean(axis=0)
            props = []
            g = g * moved
            if np.linalg.norm(g) > 1e-12 and 0 < k_inc < m:
                u = g / np.linalg.norm(g)
                props += [S.points[inc] + a * step * u for a in ALONG]
            props += [S.points[inc] + step * moved * rng.standard_normal(len(moved)) for _ in range(GAUSS)]
            cands = []
            for x in props:
                c = S.add(x)
                if c is not None and c != inc and c not in cands:
                    cands.append(c)
            # rung 1: the informative copies; fit as many candidates as the budget allows
            fit, need = [], 0
            for c in cands:
                more = sum(1 for i in probe if i not in S.res[c])
                if S.frames + need + more <= budget:
                    fit.append(c)
                    need += more
            if not fit:
                break  # the budget is spent
            S.run([(c, probe) for c in fit], budget)
            base_p = S.score(inc, probe)
            up = sorted((c for c in fit if S.score(c, probe) > base_p), key=lambda c: (S.score(c, probe), -c),
                        reverse=True)
            up = up[:SECOND_RUNG]
            # rung 2: the rest of the screen, as many as fit
            full = [c for c in up if S.run([(c, rest)], budget)]
            acc = False
            if full:
                top = max(full, key=lambda c: (S.score(c, idx), -c))
                if S.score(top, idx) > S.score(inc, idx):
                    inc, acc = top, True
                    chain.append(inc)
            step = float(np.clip(step * (WIDEN if acc else NARROW), STEP_MIN, STEP_MAX))
            history.append({"generation": gen, "m": m, "candidates": len(fit), "second_rung": len(full),
                            "incumbent": list(S.score(inc, idx)), "step": step, "frames": S.frames,
                            "accepted": acc})
            if len(full) < len(up):
                break  # the budget is spent
            if S.frames == frames0 and not acc:
                # Nothing ran: every candidate that fitted was run before (the cross-entropy
                # steps repeat once the step is at STEP_MIN) and no new one fits what is left
                # of the budget; nothing can change, so the search is over (it looped for ever).
                break
    except KeyboardInterrupt:
        best = S.of(inc) if inc is not None else starts[0]
        raise Interrupted(best, None if inc is None else (S.score(inc, idx)[0], m), S.frames, history) from None
    # the pick: the latest incumbent (the best on the screen) that keeps its outcome on the ladder
    order = list(reversed(chain))[:LADDER_TRIES]
    lad, holds, pick, frames = [], None, order[0], S.frames
    try:
        if ladder:
            holds = False
            for c in order:
                rows, ok, ran = problem.ladder(S.of(c))
                frames += ran
                if c == order[0]:
                    lad = rows
                if ok:
                    lad, holds, pick = rows, True, c
                    break
        est = problem.fresh(S.of(pick), n, seed)
    except KeyboardInterrupt:
        raise Interrupted(S.of(pick), (S.score(pick, idx)[0], m), frames, history) from None
    return Maximum(best=S.of(pick), start=S.of(best_start), screen=S.screen(pick, idx),
                   start_screen=S.screen(best_start, idx), screen_seed=screen_seed, ladder=lad, ladder_holds=holds,
                   fresh=est, frames=frames, history=history)
