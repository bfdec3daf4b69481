"""How near a crash came to its script, and the climb on it: the robust pick's soft stage.

:func:`slack`: the worst fate's margin in half-widths of its tolerance (1 in the middle of every
band, 0 at an edge, down to -1 for a yes-or-no fate missed); :func:`soft`: its logistic, whose
mean over noisy copies is a smoothed P(fates) that moves before any more copies meet the script;
:func:`soft_climb`: CMA-ES (the engine's, :func:`nbst.models.mjsearch.engine.evolution_strategy`) on
that mean over common copies, from the race's winner (``nbst crash solve --robust``,
:func:`.robust.robust_pick`).

Compute only.
"""
from __future__ import annotations

import math

import numpy as np

from nbst.models.crash.outcome import _wrap
from nbst.models.crash.script import Range
from nbst.models.mjsearch.engine import evolution_strategy
from nbst.seeds import derived_seed

__all__ = ["SOFT_COPIES", "SOFT_POP", "SOFT_SIGMA0", "SOFT_TEMP", "SOFT_CONFIRM", "slack", "soft", "soft_climb"]

#: The soft climb (:func:`soft_climb`, the robust pick's stage after the race): CMA-ES (Hansen 2016, "The CMA
#: Evolution Strategy: A Tutorial", arXiv:1604.00772) on the mean soft success of SOFT_COPIES common
#: copies per candidate (fresh copies each generation, common to its SOFT_POP candidates), from the
#: race's winner at a step of SOFT_SIGMA0 noise sigmas; SOFT_TEMP the logistic's width on the worst
#: fate's slack (:func:`slack`: 0 at a tolerance's edge, 1 at its middle); then the start, the final
#: mean and the generation's best are screened on SOFT_CONFIRM common copies (the best of them goes
#: on).
SOFT_COPIES, SOFT_POP, SOFT_SIGMA0, SOFT_TEMP, SOFT_CONFIRM = 16, 8, 1.5, 0.25, 48


def slack(o, script) -> float:
    """How far inside its tolerance the worst fate of an outcome lies, in half-widths of that
    tolerance: 1 at the middle of every band, rest region, heading and spin; 0 at the edge of the
    worst; negative outside (at most -1 for a yes-or-no fate missed: a contact, the order, an
    attitude, a curb or barrier strike; a vehicle still moving has no rest, -0.25 at best). The
    smooth measure of how near a noisy copy came to meeting the script (:func:`soft`), where
    ``solved`` is yes or no.

    Args:
        o: a judged outcome (:func:`.outcome.judge`).
        script: its script.

    Returns:
        The slack (``solved`` copies have slack >= 0 up to the bands' closed ends).
    """
    worst = 1.0 if o.order_ok else -1.0
    for vs, vo in zip(script.vehicles, o.vehicles):
        f = vs.fate
        m = []
        if f.hits is not None:
            m.append(1.0 if [j for j, _ in vo.hits] == list(f.hits) else -1.0)
        for key, val in (("impact_speed", vo.impact_speed), ("delta_v", vo.delta_v)):
            band = getattr(f, key)
            if band is not None:
                half = (band.hi - band.lo) / 2
                if not math.isfinite(val):
                    m.append(-1.0)
                elif half > 0:
                    m.append(1.0 - abs(val - (band.lo + band.hi) / 2) / half)
                else:
                    m.append(1.0 if val == band.lo else -1.0)
        for key, centre, tol in (("rest", vo.rest[:2], f.rest), ("impact_at", vo.impact_pos, f.impact_at)):
            if tol is not None:
                d = math.hypot(centre[0] - tol[0], centre[1] - tol[1])
                x = 1.0 - d / tol[2] if math.isfinite(d) else -1.0
                m.append(min(x, -0.25) if key == "rest" and vo.moving else x)
        if f.heading is not None:
            x = 1.0 - abs(float(_wrap(vo.rest[2] - f.heading[0]))) / f.heading[1]
            m.append(min(x, -0.25) if vo.moving else x)
        if f.quarter_turns is not None:
            lo, hi = f.quarter_turns
            half = (hi - lo) / 2 + 0.5
            m.append(1.0 - abs(abs(vo.roll) / (math.pi / 2) - (lo + hi) / 2) / half)
        if f.spin is not None:
            m.append(1.0 - abs(abs(vo.spin) - f.spin[0]) / f.spin[1])
        for key, val in (("attitude", vo.attitude == f.attitude), ("curb", (not math.isnan(vo.curb)) == f.curb),
                         ("barrier", (not math.isnan(vo.barrier)) == f.barrier)):
            if getattr(f, key) is not None:
                m.append(1.0 if val else -1.0)
        worst = min([worst] + [max(x, -1.0) for x in m])
    return float(worst)


def soft(o, script, temp: float = SOFT_TEMP) -> float:
    """The soft success of an outcome: the logistic of its :func:`slack` over ``temp`` (0.5 at a
    tolerance's edge, near 1 in the middle of every fate's, near 0 for a yes-or-no fate missed).
    Its mean over noisy copies is a smoothed P(fates): it moves when a step brings the copies
    nearer, before any more of them meet the script.

    Args:
        o: a judged outcome.
        script: its script.
        temp: the logistic's width, in half-widths of a tolerance.

    Returns:
        The soft success, in (0, 1).
    """
    return float(1.0 / (1.0 + math.exp(-slack(o, script) / temp)))


def soft_climb(P, start: np.ndarray, budget: int, seed: int):
    """CMA-ES from ``start`` on the mean :func:`soft` success of its noisy copies (module
    constants SOFT_*): the moved coordinates in noise sigmas and the after-impact choices as
    numbers rounded to a choice; each generation's candidates share SOFT_COPIES fresh common copies
    (paired: a ranking compares them on the same draws). Then ``start``, the final mean and the
    candidate of the best soft score are screened on SOFT_CONFIRM common copies (met, then soft
    success summed): (the best of them, its record {copies, start, climbed (met of the screen),
    soft_start, soft_climbed, generations, rollouts})."""
    sc = P.R.script
    K, lam, C = SOFT_COPIES, SOFT_POP, SOFT_CONFIRM
    choice = np.array([0.0 if isinstance(r, Range) else float(len(r) - 1) for _, _, r in P.S.coords])
    free = np.flatnonzero((P.moved > 0) | (choice > 0))
    rec = {"copies": C, "start": 0, "climbed": 0, "soft_start": 0.0, "soft_climbed": 0.0, "generations": 0,
           "rollouts": 0}
    if len(free) == 0 or budget < 3 * C + K * lam:  # not one generation and the confirming screens
        return start, rec
    x0 = P.point(start)

    def full(z):
        x = x0.copy()
        x[free] = z
        ch = choice > 0
        x[ch] = np.clip(x[ch], 0.0, choice[ch])
        return P.project(x)

    def scores(cands, m, cs):
        outs = P.run([c for cand in cands for c in P.noisy(cand, m, cs)])
        got = []
        for k in range(len(cands)):
            part = outs[k * m:(k + 1) * m]
            got.append((sum(1 for o in part if o.solved), sum(soft(o, sc) for o in part)))
        return got

    stds = np.where(choice[free] > 0, 0.5, 1.0)
    es = evolution_strategy(x0[free], SOFT_SIGMA0, popsize=lam, seed=derived_seed(seed, 49) % (2 ** 31 - 1) + 1,
                            stds=stds)
    used, gen, best = 0, 0, (-1.0, None)
    while used + K * lam + 3 * C <= budget:
        zs = es.ask()
        cands = [P.make(full(z)) for z in zs]
        got = scores(cands, K, derived_seed(seed, 49, gen))
        used += K * lam
        gen += 1
        es.tell(zs, [-g[1] for g in got])
        i = max(range(lam), key=lambda i: (got[i][1], got[i][0], -i))
        if got[i][1] > best[0]:
            best = (got[i][1], cands[i])
    picks = [start, P.make(full(es.result.xfavorite))] + ([best[1]] if best[1] is not None else [])
    conf = scores(picks, C, derived_seed(seed, 50))
    used += C * len(picks)
    j = max(range(len(picks)), key=lambda j: (conf[j], -j))
    rec.update(start=conf[0][0], climbed=conf[j][0], soft_start=round(conf[0][1] / C, 3),
               soft_climbed=round(conf[j][1] / C, 3), generations=gen, rollouts=used)
    return picks[j], rec
