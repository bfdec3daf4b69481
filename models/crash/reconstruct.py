"""Reconstruction: from the rest positions of the vehicles back to their speeds before the crash.

A reconstruction case is a crash script (:mod:`.script`) whose fates are the **evidence**: each
vehicle's rest position (``rest``, its radius the tolerance) and heading at rest (``heading``,
its tolerance), whom it hit (``hits``), optionally where the first contact was (a vehicle's
``impact_speed`` is left out: that is what is sought). Its drivers' ranges bound the unknowns:
the speeds, the approach (aim point, arrival time), what each driver did after the impact.

:func:`reconstruct` runs in two stages on one rollout budget:

1. **fit**: the crash search (:func:`.search.solve`: the signature search, the archive keyed by
   contact sequence, CMA-ES restarts) until a set of intents meets the evidence;
2. **spread**: every fit found so far is a parent; children are its intents moved by Gaussian
   steps in the unit cube at three scales (1 %, 3 %, 10 % of each range), drawn per child, and
   every child that meets the evidence is kept as another fit (an evidence-constrained random
   walk, not a posterior: each fit counts once).

The answer is every fit within the tolerances, summarised per vehicle as ranges (lowest,
median, highest) of the impact speed (its speed just before its first vehicle contact), its
direction of travel then, and its delta-V; the **estimate** is the median. docs/crash.md
compares the method, point by point, with PC-Crash's optimiser (Moser and Steffan, SAE 980373).

Compute only.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from nbst.models.crash import search as search_mod
from nbst.models.crash.run import BATCH
from nbst.models.crash.space import space_of

#: Share of the budget the fit stage may use before the spread starts (it starts earlier when a fit is found).
FIT_SHARE = 0.7
#: Spread: step scales in the unit cube, and the fits kept at most as parents (the first found first).
SCALES = (0.01, 0.03, 0.1)
MAX_FITS = 2000


@dataclass
class Reconstruction:
    """The fits of a case and what they say."""

    fits: list                  # Trials that meet the evidence, in the order found
    best: object                # the trial of lowest cost (a fit when there is one)
    rollouts: int
    fit_rollouts: int           # rollouts of the fit stage
    seed: int
    ranges: list = field(default_factory=list)  # per vehicle: {quantity: (lo, median, hi)}
    interrupted: bool = False   # Ctrl-C: what ran is here

    @property
    def found(self) -> bool:
        return bool(self.fits)

    def to_dict(self, names) -> dict:
        kmh = 3.6

        def rng(t, scale=1.0, k=2):
            return None if t is None else {"min": round(t[0] * scale, k), "median": round(t[1] * scale, k),
                                           "max": round(t[2] * scale, k)}

        return {"fits": len(self.fits), "rollouts": self.rollouts, "fit_rollouts": self.fit_rollouts, "seed": self.seed,
                "vehicles": [{"name": nm, "impact_speed_kmh": rng(r.get("impact_speed"), kmh),
                              "impact_speed_m_s": rng(r.get("impact_speed")),
                              "impact_heading_deg": rng(r.get("impact_heading"), 180 / math.pi, 1),
                              "delta_v_kmh": rng(r.get("delta_v"), kmh)}
                             for nm, r in zip(names, self.ranges)],
                "method": "fit: the crash search; spread: Gaussian children of the fits at 1, 3 and 10 % of each "
                          "range, every child within the evidence kept; ranges over every fit, estimate the median"}


def _summary(values: list) -> tuple | None:
    v = np.array([x for x in values if np.isfinite(x)])
    return None if not len(v) else (float(v.min()), float(np.median(v)), float(v.max()))


def ranges_of(fits: list, n: int) -> list:
    """Per vehicle, (lowest, median, highest) of impact speed, heading (unwrapped about the
    first fit's) and delta-V over ``fits``."""
    out = []
    for i in range(n):
        vs = [t.outcome.vehicles[i] for t in fits]
        h0 = vs[0].impact_heading if vs else 0.0
        heads = [h0 + (v.impact_heading - h0 + math.pi) % (2 * math.pi) - math.pi for v in vs]
        out.append({"impact_speed": _summary([v.impact_speed for v in vs]), "impact_heading": _summary(heads),
                    "delta_v": _summary([v.delta_v for v in vs])})
    return out


def reconstruct(case, *, seed: int, max_rollouts: int = 2000, runner=None, jobs: int = 1,
                callback=None) -> Reconstruction:
    """Every fit of ``case`` (a Script whose fates are the evidence) within ``max_rollouts``.

    Args:
        case: the crash script whose fates are the evidence (rest positions, headings, ...).
        seed: the seed; the same seed gives the same fits whatever ``jobs``.
        max_rollouts: the budget, in rollouts: the crash search for fits first, then Gaussian
            children of the fits that spread them.
        runner: a ``nbst.models.crash.run.Runner`` for this case to reuse, or None: one is made
            with ``jobs`` threads and closed at the end.
        jobs: threads of the runner made here.
        callback: None, or called with a ``Progress`` after each batch.

    Returns:
        A :class:`Reconstruction`: the fits in the order found, the best trial, the rollouts,
        and per vehicle the range (min, median, max) of impact speed, heading and delta-V over
        the fits (``to_dict`` gives them in km/h and degrees); ``interrupted`` after Ctrl-C.
    """
    from nbst.models.crash.run import Runner

    own = runner is None
    R = Runner(case, jobs=jobs) if own else runner
    S = space_of(case)
    fits: list = []

    def keep(t):
        if t.outcome.solved and len(fits) < MAX_FITS:
            fits.append(t)

    fit_budget = max(BATCH, int(FIT_SHARE * max_rollouts))
    res = search_mod.solve(case, seed=seed, max_rollouts=fit_budget, runner=R, callback=callback, keep=keep,
                           ladder=False)  # a fit is a fit at the case's step; the spread measures the rest
    used = res.rollouts
    best = res.best
    interrupted = res.stopped == "interrupted"
    rng = np.random.default_rng([int(seed), 32])
    try:
        while fits and used < max_rollouts and S.dim and not interrupted:
            k = min(BATCH, max_rollouts - used)
            parents = rng.integers(0, len(fits), size=k)
            scale = np.asarray(SCALES)[rng.integers(0, len(SCALES), size=k)]
            U = np.clip(np.array([fits[p].u for p in parents]) + scale[:, None] * rng.standard_normal((k, S.dim)),
                        0.0, 1.0)
            r = R.run(S.intents(U))
            for u, i in zip(U, range(k)):
                t = search_mod.Trial(u=u, outcome=r.outcomes[i], controls=r.controls[i], qpos0=r.qpos0[i],
                                     qvel0=r.qvel0[i], final_qpos=r.final_qpos[i])
                keep(t)
                if t.cost < best.cost:
                    best = t
            used += k
            if callback:
                callback(search_mod.Progress(used, best.cost, best.outcome.signature_text(case.n), True, len(fits)))
    except KeyboardInterrupt:
        interrupted = True
    finally:
        if own:
            R.close()
    if fits:
        med = np.median([f.outcome.vehicles[0].impact_speed for f in fits])
        best = min(fits, key=lambda f: abs(f.outcome.vehicles[0].impact_speed - med))  # the fit nearest the estimate
    return Reconstruction(fits=fits, best=best, rollouts=used, fit_rollouts=res.rollouts, seed=int(seed),
                          ranges=ranges_of(fits, case.n) if fits else [{} for _ in range(case.n)],
                          interrupted=interrupted)
