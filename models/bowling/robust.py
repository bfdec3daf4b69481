"""A throw that holds up: maximise the probability of an outcome under the release noise.

:func:`maximise` searches the delivery of :mod:`.lane` (board at the foul line, launch angle,
mph, rpm, axis rotation; the axis tilt only when the noise moves it; the hand is kept) for the
highest probability that a frame gives the outcome (every pin in play down, or with ``want``
exactly those pins down) under the release noise of :mod:`.noise`.

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

import numpy as np

from nbst.models.bowling import frame, lane, noise as noise_mod

#: Parameters searched (the tilt is carried, and moved only when the noise moves it).
KEYS = ("board", "angle", "mph", "rpm", "rotation", "tilt")
#: Candidates per generation: along the cross-entropy direction, and Gaussian.
ALONG = (0.5, 1.0, 2.0)
GAUSS = 5
#: Step size (in sigmas): start, bounds, and its change after a success / a failure.
STEP0, STEP_MIN, STEP_MAX, WIDEN, NARROW = 1.0, 0.25, 3.0, 1.4, 0.7
#: The screen's throws: budget // SCREEN_DIV, within [SCREEN_MIN, SCREEN_MAX].
SCREEN_DIV, SCREEN_MIN, SCREEN_MAX = 6, 12, 60
#: Candidates run on the whole screen per generation (the best of the first rung), at most.
SECOND_RUNG = 2
#: Accepted incumbents tried on the ladder, latest first.
LADDER_TRIES = 3


class Interrupted(KeyboardInterrupt):
    """Ctrl-C during :func:`maximise`: ``best`` (Delivery) is the incumbent so far, ``screen``
    its (k, m) on the screen's throws, ``frames`` the frames run, ``history`` the generations."""

    def __init__(self, best, screen, frames, history):
        super().__init__("robust search interrupted")
        self.best, self.screen, self.frames, self.history = best, screen, frames, history


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


class _Search:
    """The bookkeeping of one search: candidates, their results on the common throws, frames."""

    def __init__(self, base, keys, scale, standing, want, runner, nz, seed, on_done):
        self.base, self.keys, self.scale = base, keys, scale
        self.standing, self.want, self.runner, self.nz, self.on_done = standing, want, runner, nz, on_done
        self.seed = seed
        self.frames = 0
        self.points: list[np.ndarray] = []  # scaled coordinates
        self.res: list[dict] = []  # per candidate: throw index -> (outcome, pins right, leave)
        self.exact: dict = {}  # candidate -> the start's own Delivery (no round trip through the scaling)

    def delivery(self, x) -> lane.Delivery:
        kw = {}
        for k, v in zip(self.keys, x):
            lo, hi = noise_mod.CLIP[k]
            kw[k] = float(np.clip(v * self.scale[k], lo, hi))
        return replace(self.base, **kw)

    def coords(self, d: lane.Delivery) -> np.ndarray:
        return np.array([getattr(d, k) / self.scale[k] for k in self.keys])

    def add(self, x) -> int | None:
        x = self.coords(self.delivery(x))  # clipped to the limits
        try:
            self.delivery(x).check()
        except lane.LaneError:
            return None
        for i, p in enumerate(self.points):
            if np.allclose(p, x, atol=1e-9):
                return i
        self.points.append(x)
        self.res.append({})
        return len(self.points) - 1

    def throws(self, c: int, idx) -> list:
        m = max(idx) + 1
        return noise_mod.sample(self.of(c), m, self.seed, self.nz)

    def of(self, c: int) -> lane.Delivery:
        return self.exact.get(c) or self.delivery(self.points[c])

    def run(self, jobs: list, budget: int) -> bool:
        """Run (candidate, throw indices) pairs not yet run, in one batch; False (nothing run)
        if they do not fit in ``budget``."""
        todo = []
        for c, idx in jobs:
            need = [i for i in idx if i not in self.res[c]]
            if need:
                th = self.throws(c, need)
                todo += [(c, i, th[i]) for i in need]
        if not todo or self.frames + len(todo) > budget:
            return not todo
        out = self.runner.map([t for _, _, t in todo], standing=self.standing, on_done=self.on_done)
        self.frames += len(todo)
        for (c, i, _), r in zip(todo, out):
            down = set(r.down)
            target = set(r.in_play) if self.want is None else set(self.want)
            right = sum(1 for p in r.in_play if (p in down) == (p in target))
            self.res[c][i] = (noise_mod.success(r, self.want), right, "-".join(str(p) for p in r.leave))
        return True

    def score(self, c: int, idx) -> tuple[int, int]:
        got = [self.res[c][i] for i in idx]
        return sum(1 for g in got if g[0]), sum(g[1] for g in got)

    def offsets(self, c: int, idx) -> np.ndarray:
        """The scaled offsets of candidate ``c``'s noisy throws ``idx`` from its release (clipped)."""
        th = self.throws(c, idx)
        x = self.points[c]
        return np.array([[getattr(th[i], k) / self.scale[k] for k in self.keys] for i in idx]) - x


def _estimate(search: _Search, c: int, idx, seed: int, nz) -> noise_mod.Estimate:
    k, _ = search.score(c, idx)
    lo, hi = noise_mod.wilson(k, len(idx))
    leaves: dict = {}
    for i in idx:
        leaves[search.res[c][i][2]] = leaves.get(search.res[c][i][2], 0) + 1
    return noise_mod.Estimate(k=k, n=len(idx), p=k / len(idx), lo=lo, hi=hi, seed=int(seed), noise=nz.to_dict(),
                              leaves=dict(sorted(leaves.items(), key=lambda kv: -kv[1])))


def maximise(starts, *, standing=None, want=None, runner: frame.FrameRunner, budget: int, seed: int,
             noise: noise_mod.Noise = noise_mod.DEFAULT, on_done=None, ladder: bool = True,
             n: int = 60) -> RobustResult:
    """The release near ``starts`` (a Delivery or several, the same hand) with the highest
    probability of the outcome on the pins in ``standing`` (default all ten): every pin in play
    down, or exactly the pins of ``want`` down. ``budget``: noisy frames for the search; ``n``:
    throws of the fresh estimate (seed ``seed``). See the module docstring for the method."""
    nz = noise.check()
    want = noise_mod.wanted(want)
    in_play = sorted(set(range(1, 11) if standing is None else standing))
    if want is not None and not set(want) <= set(in_play):
        raise ValueError(f"want: pins {want} are not all in play ({in_play})")
    if not (isinstance(budget, int) and budget >= 1):
        raise ValueError(f"budget: must be a whole number of frames >= 1, got {budget!r}")
    if not (isinstance(n, int) and n >= 1):
        raise ValueError(f"n: must be a whole number >= 1, got {n!r}")
    starts = [starts] if isinstance(starts, lane.Delivery) else list(starts)
    if not starts:
        raise ValueError("starts: give at least one delivery")
    starts = [replace(d.check(), board=d.foul_board(), at="foul") for d in starts]
    if len({d.hand for d in starts}) > 1:
        raise ValueError("starts: every start must be thrown with the same hand")
    keys = KEYS
    scale = {k: (getattr(nz, k) or getattr(noise_mod.DEFAULT, k) or 1.0) for k in keys}
    moved = np.array([1.0 if k != "tilt" or nz.tilt > 0 else 0.0 for k in keys])  # the tilt: only if noisy
    ss = np.random.SeedSequence([int(seed), 22])
    screen_seed = int(ss.generate_state(1, np.uint64)[0] >> 1)
    rng = np.random.default_rng(ss.spawn(1)[0])
    S = _Search(starts[0], keys, scale, in_play, want, runner, nz, screen_seed, on_done)
    m = int(np.clip(budget // SCREEN_DIV, SCREEN_MIN, SCREEN_MAX))
    history: list = []
    chain: list[int] = []  # accepted incumbents, oldest first
    start_ids = []
    for d in starts:
        c = S.add(S.coords(d))
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
            k_inc, _ = S.score(inc, idx)
            if k_inc == m:  # every common throw gives the outcome: the screen cannot tell better
                break
            fail = [i for i in idx if not S.res[inc][i][0]]
            passed = [i for i in idx if S.res[inc][i][0]]
            probe = sorted(fail + passed[:max(len(fail), 4)])
            rest = [i for i in idx if i not in set(probe)]
            # the cross-entropy direction from the incumbent's own throws
            z = S.offsets(inc, idx)
            y = np.array([1.0 if S.res[inc][i][0] else 0.0 for i in idx])
            g = ((y - y.mean())[:, None] * z).mean(axis=0)
            props = []
            g = g * moved
            if np.linalg.norm(g) > 1e-12 and 0 < k_inc < m:
                u = g / np.linalg.norm(g)
                props += [S.points[inc] + a * step * u for a in ALONG]
            props += [S.points[inc] + step * moved * rng.standard_normal(len(keys)) for _ in range(GAUSS)]
            cands = []
            for x in props:
                c = S.add(x)
                if c is not None and c != inc and c not in cands:
                    cands.append(c)
            # rung 1: the informative throws; fit as many candidates as the budget allows
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
                rs = frame.ladder(S.of(c), runner.oil, runner.ball, standing=in_play)
                frames += len(rs)
                rows = [[r.timestep, r.leave, r.down] for r in rs]
                if c == order[0]:
                    lad = rows
                if all(noise_mod.success(r, want) for r in rs):
                    lad, holds, pick = rows, True, c
                    break
        d = S.of(pick)
        est, _ = noise_mod.probability(d, n, seed, runner=runner, standing=in_play, noise=nz, on_done=on_done,
                                       want=want)
    except KeyboardInterrupt:
        raise Interrupted(S.of(pick), (S.score(pick, idx)[0], m), frames, history) from None
    frames += n
    return RobustResult(delivery=d, start=S.of(best_start), want=want, standing=in_play,
                        estimate=est, screen=_estimate(S, pick, idx, screen_seed, nz),
                        start_screen=_estimate(S, best_start, idx, screen_seed, nz), ladder=lad, ladder_holds=holds,
                        frames=frames, budget=budget, history=history)
