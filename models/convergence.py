"""The convergence study of a validation: fixed steps at h, h/2, ... h/32 and aligned stepping.

``convergence_study`` runs the ladder (:data:`CONVERGENCE_LADDER`; the scene rebuilt per step, k = 2/h^2),
one entry per run with its max final error against the exact motion, its signature and cost;
``fit_order`` fits the order of the fixed-step error on the entries :data:`FIT_RULE` picks.
``staged`` runs one stage under a progress bar and returns its seconds (the bar's), shared with
:func:`nbst.models.validate.validate`, which calls the study when asked (``convergence=True``).
"""
from __future__ import annotations

from typing import Any

import numpy as np

from nbst.models.mjrun import run_final, run_mujoco, steps_needed
from nbst.problem import Problem

__all__ = ["CONVERGENCE_LADDER", "FIT_RULE", "FIT_MIN_ERROR", "staged", "entry", "convergence_study", "fit_order"]

#: Convergence ladder: h divided by these.
CONVERGENCE_LADDER = (1, 2, 4, 8, 16, 32)
#: Which ladder entries the order is fitted on, and why (also written into the report).
FIT_RULE = ("fixed-step entries that keep the exact signature with a max error below the smallest disk radius "
            "(first order: the collision sequence is unchanged) and above 1e-9 units (round-off)")
FIT_MIN_ERROR = 1e-9


def staged(progress, desc: str, total: int, fn, unit: str = "step"):
    """Run ``fn(callback)`` as one stage: (its result, its seconds). With a ``progress`` factory the
    stage has a bar, and the seconds are the bar's (its clock from its start to its close), so a
    summary that quotes them says what the bar's last line says."""
    import time

    if progress is None:
        t0 = time.monotonic()
        out = fn(None)
        return out, time.monotonic() - t0
    bar = progress(desc, total, unit)
    try:
        out = fn(bar.update)
    except BaseException:
        bar.close()
        raise
    bar.close()
    return out, float(getattr(bar, "seconds", 0.0))


def entry(problem: Problem, ex, final, steps, wall, *, h, divisor, stepping="fixed", stats=None,
           skipped=None) -> dict:
    """One convergence entry (final positions against the exact ones)."""
    if final is None:
        return {"stepping": stepping, "h": h, "divisor": divisor, "max_error": None, "mean_error": None,
                "signature": None, "same_signature": None, "cost": None, "steps": steps, "wall_time": None,
                "stats": stats, "skipped": skipped}
    err = np.hypot(*(np.asarray(final) - ex.final_positions).T)
    target = np.asarray(problem.target, dtype=float)
    R2 = float(problem.target_radius) ** 2
    d2 = ((np.asarray(final) - target) ** 2).sum(axis=1)
    sig = "".join("1" if x else "0" for x in d2 <= R2)
    sig_ex = "".join("1" if x else "0" for x in ((ex.final_positions - target) ** 2).sum(axis=1) <= R2)
    return {"stepping": stepping, "h": h, "divisor": divisor, "max_error": float(err.max()),
            "mean_error": float(err.mean()), "signature": sig, "same_signature": sig == sig_ex,
            "cost": float(d2.sum()), "steps": int(steps), "wall_time": float(wall), "stats": stats,
            "skipped": skipped}


def convergence_study(problem: Problem, v, ex, *, timestep: float, unit: float, max_steps: int,
                      aligned=None, fixed=None, progress=None) -> list:
    """Fixed steps at timestep / CONVERGENCE_LADDER and aligned stepping at timestep: one entry each.

    aligned / fixed : a MujocoRun already made (aligned at h / fixed at h) to reuse
    An entry whose steps exceed max_steps is kept with ``skipped`` saying so.
    """
    out = []
    for div in CONVERGENCE_LADDER:
        h = timestep / div
        n = steps_needed(problem.t_final, h)
        if n > max_steps:
            out.append(entry(problem, ex, None, n, None, h=h, divisor=div,
                              skipped=f"{n:,} steps, over the limit of {max_steps:,} (--max-steps)"))
        elif div == 1 and fixed is not None:
            out.append(entry(problem, ex, fixed.final_positions, fixed.steps, fixed.wall_time, h=h, divisor=1))
        else:
            res, _ = staged(progress, f"convergence, fixed h/{div}", n,
                             lambda cb: run_final(problem, v, timestep=h, unit=unit, max_steps=max_steps, progress=cb))
            out.append(entry(problem, ex, *res, h=h, divisor=div))
    if aligned is not None:
        run = aligned
    else:
        n = steps_needed(problem.t_final, timestep)
        run, _ = staged(progress, "convergence, aligned", n,
                         lambda cb: run_mujoco(problem, v, timestep=timestep, unit=unit, max_steps=max_steps,
                                               stepping="aligned", progress=cb))
    out.append(entry(problem, ex, run.final_positions, run.stats["steps"] + run.stats["impacts"], run.wall_time,
                      h=None, divisor=None, stepping="aligned", stats=run.stats))
    return out


def fit_order(entries: list, problem: Problem) -> dict:
    """Least-squares slope of log(max error) on log(h) over the entries :data:`FIT_RULE` picks."""
    rmin = float(np.min(problem.radius))
    pts = [e for e in entries if e["stepping"] == "fixed" and e["max_error"] is not None and e["same_signature"]
           and FIT_MIN_ERROR < e["max_error"] < rmin]
    out: dict[str, Any] = {"order": None, "points_h": [e["h"] for e in pts], "rule": FIT_RULE}
    if len(pts) >= 2:
        x = np.log([e["h"] for e in pts])
        y = np.log([e["max_error"] for e in pts])
        slope, icpt = np.polyfit(x, y, 1)
        out["order"] = float(slope)
        out["intercept_log"] = float(icpt)
    return out
