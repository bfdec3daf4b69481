"""``solve(..., robust=BUDGET)``: the scene's answer moved to where it holds most often under the
fates' noise, by the rollout room's robust maximiser (``nbst.models.mjsearch.robust.maximise``).

:class:`SceneRobustProblem` is the scene as the maximiser sees it: a candidate is a controls
vector (D,) in the fates' units; a point measures each coordinate in its noise sigma (the fates'
``"noise"``, or the defaults of docs/scene.md), so a step of 1 is one sigma; a coordinate whose
range is one value, or whose sigma is 0, is not moved. Its noisy copies are the draws of
``solve --samples`` (``normal_draws``/``perturb``: common random numbers, clipped into the
ranges); a copy holds when every fate is met and MuJoCo did not warn; its partial credit is the
signature's bits set, less a thousandth of its graded cost (at most 100), so that of two
candidates that hold equally often the nearer wins. The ladder is the same initial state at h,
h/2 and h/4 (every fate met at each); the fresh estimate is :func:`nbst.scene.search.noisy_probability`
of the seed itself.

mujoco is imported by the sims it is given.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from nbst.models.mjsearch.probability import Probability, normal_draws, perturb
from nbst.scene.judge import signature_text
from nbst.scene.rollout import SceneRollout, SceneSim
from nbst.scene.search import noisy_probability

__all__ = ["DEFAULT_ROBUST_BUDGET", "DEFAULT_ROBUST_SAMPLES", "SceneRobustProblem"]

#: Noisy rollouts of the robust maximiser when ``--robust`` names no budget.
DEFAULT_ROBUST_BUDGET = 600
#: Copies of the fresh estimate after it when ``--samples`` is not given.
DEFAULT_ROBUST_SAMPLES = 200


class SceneRobustProblem:
    """The scene as ``nbst.models.mjsearch.robust.maximise`` sees it (module docstring).

    Args:
        sim: the scene's rollouts (its threads run the noisy copies).
        ladder: sims of the same scene at h/2 and h/4 (empty: the ladder is h alone).

    Returns:
        The problem.
    """

    def __init__(self, sim: SceneSim, ladder: tuple[SceneSim, ...] = ()):
        f = sim.fates
        self.sim, self.rungs = sim, ladder
        self.lo, self.hi = f.bounds()
        self.sigma = f.noise()
        ok = (self.sigma > 0) & (self.hi > self.lo)
        self.scale = np.where(ok, self.sigma, 1.0)
        self.moved = ok.astype(float)

    def project(self, x: np.ndarray) -> np.ndarray:
        return np.clip(np.asarray(x, dtype=float) * self.scale, self.lo, self.hi) / self.scale

    def make(self, x: np.ndarray) -> np.ndarray:
        return np.clip(np.asarray(x, dtype=float) * self.scale, self.lo, self.hi)

    def point(self, cand: np.ndarray) -> np.ndarray:
        return np.asarray(cand, dtype=float) / self.scale

    def noisy(self, cand: np.ndarray, m: int, seed: int) -> list:
        return list(perturb(cand, self.sigma, normal_draws(seed, m, len(self.lo)), self.lo, self.hi))

    def run(self, copies: list) -> list:
        return self.sim.run(np.array(copies, dtype=float).reshape(-1, len(self.lo)))

    def judge(self, r: SceneRollout) -> tuple[bool, float, str]:
        held = bool(r.judgement.met and not r.warnings)
        return held, sum(r.signature) - min(r.cost, 100.0) / 1000.0, signature_text(r.signature)

    def ladder(self, cand: np.ndarray) -> tuple[list, bool, int]:
        rows, ok = [], True
        for s in (self.sim, *self.rungs):
            r = s.rollout(cand)
            met = bool(r.judgement.met and not r.warnings)
            ok = ok and met
            rows.append({"timestep": float(s.model.opt.timestep), "met": met,
                         "signature": signature_text(r.signature)})
        return rows, ok, len(rows)

    def fresh(self, cand: np.ndarray, n: int, seed: int) -> Probability:
        return noisy_probability(self.sim, np.asarray(cand, dtype=float), n=n, seed=seed)

    def value(self, cand: Any) -> np.ndarray:
        """The controls vector of a candidate (it is one)."""
        return np.asarray(cand, dtype=float)
