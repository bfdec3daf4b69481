"""Reconstruction: from the rest positions of the vehicles back to their speeds before the crash.

A reconstruction case is a crash script (:mod:`.script`) whose fates are the **evidence**: each
vehicle's rest position (``rest``, its radius the tolerance) and heading at rest (``heading``,
its tolerance), whom it hit (``hits``), optionally where it was at the first contact
(``impact_at``: its centre of mass, as a reconstructionist places the vehicles at impact from
the crush and the marks on the road); a vehicle's ``impact_speed`` is left out: that is what
is sought. Its drivers' ranges bound the unknowns: the speeds, the approach (aim point,
arrival time), what each driver did after the impact.

:func:`reconstruct` runs in two stages on one rollout budget:

1. **fit**. Two vehicles that hit each other, with rest and impact positions as evidence
   (:func:`applies`), get the **momentum fit** (:func:`momentum_fit`), the reconstructionist's
   own method carried to rollouts: the momentum seed (each vehicle leaves its impact position
   sliding to rest on locked wheels, v = sqrt(2 mu g d); linear momentum through the impact
   gives the speeds before it), rounds that fit the intents to the impact positions and the
   target speeds and correct the speeds by the momentum balance of the evidence's slides
   against the simulated ones, then CMA-ES on the evidence's least squares. Any other case
   gets the crash search (:func:`.search.solve`: the signature search, the archive keyed by
   contact sequence, CMA-ES restarts) until a set of intents meets the evidence;
2. **spread**: every fit found so far is a parent; children are its intents moved by Gaussian
   steps in the unit cube at three scales (1 %, 3 %, 10 % of each range), drawn per child, and
   every child that meets the evidence is kept as another fit (an evidence-constrained random
   walk, not a posterior: each fit counts once).

The answer is every fit within the tolerances, summarised per vehicle as ranges (lowest,
median, highest) of the impact speed (its speed just before its first vehicle contact), its
direction of travel then, and its delta-V; the **estimate** is the fit of least squares
against the evidence (:func:`residuals`, in units of the tolerances: the middle of the
evidence, where the hidden crash lies). docs/results/crash.md compares the method, point by point,
with PC-Crash's optimiser (Moser and Steffan, SAE 980373).

Compute only.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from nbst.models.crash import search as search_mod
from nbst.models.crash.outcome import _wrap as out_wrap
from nbst.models.crash.run import BATCH, CrashRunner
from nbst.models.crash.script import Script
from nbst.models.crash.space import space_of
from nbst.models.crash.vehicle import G
from nbst.seeds import check_seed

__all__ = ["FIT_SHARE", "FIT_SHARE_MOMENTUM", "SCALES", "MAX_FITS", "Reconstruction", "METHOD_SEARCH",
           "METHOD_MOMENTUM", "ranges_of", "reconstruct", "ROUNDS", "SPEED_TOL", "LM_ROUND", "FD_STEP",
           "MAX_STEP", "SIGMA_FINAL", "GAIN", "START", "MISS", "applies", "slide_speed", "momentum_speeds",
           "residuals", "momentum_fit"]

#: Share of the budget the fit stage may use before the spread starts (it starts earlier when a fit is found).
FIT_SHARE = 0.7
#: The same for the momentum fit (:func:`momentum_fit`: its least-squares fit is the estimate; the
#: spread only measures the range).
FIT_SHARE_MOMENTUM = 0.85
#: Spread: step scales in the unit cube, and the fits kept at most as parents (the first found first).
SCALES = (0.01, 0.03, 0.1)
MAX_FITS = 2000


@dataclass
class Reconstruction:
    """The fits of a case and what they say."""

    fits: list                  # Trials that meet the evidence, in the order found
    best: search_mod.Trial      # the trial of lowest cost (a fit when there is one)
    rollouts: int
    fit_rollouts: int           # rollouts of the fit stage
    seed: int
    ranges: list = field(default_factory=list)  # per vehicle: {quantity: (lo, median, hi)}
    interrupted: bool = False   # Ctrl-C: what ran is here
    estimate: list = field(default_factory=list)  # per vehicle: {quantity: the least-squares fit's value}
    method: str = ""

    @property
    def found(self) -> bool:
        return bool(self.fits)

    def to_dict(self, names) -> dict:
        kmh = 3.6

        def rng(t, est, scale=1.0, k=2):
            return None if t is None else {"min": round(t[0] * scale, k), "estimate": round(est * scale, k),
                                           "median": round(t[1] * scale, k), "max": round(t[2] * scale, k)}

        return {"fits": len(self.fits), "rollouts": self.rollouts, "fit_rollouts": self.fit_rollouts, "seed": self.seed,
                "vehicles": [{"name": nm, "impact_speed_kmh": rng(r.get("impact_speed"), e.get("impact_speed"), kmh),
                              "impact_speed_m_s": rng(r.get("impact_speed"), e.get("impact_speed")),
                              "impact_heading_deg": rng(r.get("impact_heading"), e.get("impact_heading"),
                                                        180 / math.pi, 1),
                              "delta_v_kmh": rng(r.get("delta_v"), e.get("delta_v"), kmh)}
                             for nm, r, e in zip(names, self.ranges, self.estimate or [{}] * len(names))],
                "method": self.method}


METHOD_SEARCH = ("fit: the crash search; spread: Gaussian children of the fits at 1, 3 and 10 % of each range, every "
                 "child within the evidence kept; ranges over every fit; the estimate the fit of least squares")
METHOD_MOMENTUM = ("fit: the momentum seed from the impact and rest positions (slides on locked wheels), rounds of "
                   "momentum corrections of the speeds, then CMA-ES on the evidence's least squares; spread: Gaussian "
                   "children of the fits; ranges over every fit; the estimate the fit of least squares")


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


def reconstruct(case: Script, *, seed: int, max_rollouts: int = search_mod.DEFAULT_MAX_ROLLOUTS,
                runner: CrashRunner | None = None, jobs: int = 1,
                callback: Callable[[search_mod.CrashProgress], object] | None = None) -> Reconstruction:
    """Every fit of ``case`` (a Script whose fates are the evidence) within ``max_rollouts``.

    Args:
        case: the crash script whose fates are the evidence (rest positions, headings, ...).
        seed: an integer in [0, 2^63-1]; the same seed gives the same fits whatever ``jobs``.
        max_rollouts: the budget, in rollouts: the crash search for fits first, then Gaussian
            children of the fits that spread them.
        runner: a ``nbst.models.crash.run.CrashRunner`` for this case to reuse, or None: one is made
            with ``jobs`` threads and closed at the end.
        jobs: threads of the runner made here.
        callback: None, or called with a :class:`~nbst.models.crash.search.CrashProgress` after
            each batch.

    Returns:
        A :class:`Reconstruction`: the fits in the order found (search trials: ``u`` (dim,)
        unit-cube point, ``outcome``, ``controls`` (periods, nu), ...), the best trial, the
        rollouts, and per vehicle the range (min, median, max) of impact speed (m/s), heading
        (rad) and delta-V (m/s) over the fits (``to_dict`` gives them in km/h and degrees);
        ``interrupted`` after Ctrl-C.

    Raises:
        InputError: ``seed`` is not an integer in [0, 2^63-1].
        MujocoError: a rollout diverged (a non-finite state).
    """
    own = runner is None
    R = runner if runner is not None else CrashRunner(case, jobs=jobs)
    S = space_of(case)
    fits: list = []

    def keep(t):
        if t.outcome.solved and len(fits) < MAX_FITS:
            fits.append(t)

    momentum = applies(case)
    share = FIT_SHARE_MOMENTUM if momentum else FIT_SHARE
    fit_budget = min(int(max_rollouts), max(BATCH, int(share * max_rollouts)))
    seed = check_seed(seed, what="seed")
    rng = np.random.default_rng([seed, 32])
    interrupted = False
    if momentum:
        seen: list = []

        def keep_all(t):
            seen.append(t)
            keep(t)
        def told(p):  # the fits found so far, as the search reports its archive
            callback(search_mod.CrashProgress(p.rollouts, p.best_cost, p.best_signature, bool(fits), len(fits)))
        try:
            used = momentum_fit(case, R, S, fit_budget, rng, keep_all, told if callback else None)
        except KeyboardInterrupt:
            interrupted, used = True, len(seen)
        if not seen:
            raise KeyboardInterrupt
        best = min(seen, key=lambda t: t.cost)
        fit_used = used
    else:
        res = search_mod.solve(case, seed=seed, max_rollouts=fit_budget, runner=R, callback=callback, keep=keep,
                               ladder=False)  # a fit is a fit at the case's step; the spread measures the rest
        used = fit_used = res.rollouts
        best = res.best
        interrupted = res.stopped == "interrupted"
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
                callback(search_mod.CrashProgress(used, best.cost, best.outcome.signature_text(case.n), True,
                                                  len(fits)))
    except KeyboardInterrupt:
        interrupted = True
    finally:
        if own:
            R.close()
    if fits:  # the estimate: the fit of least squares against the evidence, in units of its tolerances
        best = min(fits, key=lambda f: float(np.sum(residuals(f.outcome, case) ** 2)))
    return Reconstruction(fits=fits, best=best, rollouts=used, fit_rollouts=fit_used, seed=int(seed),
                          ranges=ranges_of(fits, case.n) if fits else [{} for _ in range(case.n)],
                          estimate=[{"impact_speed": v.impact_speed, "impact_heading": v.impact_heading,
                                     "delta_v": v.delta_v} for v in best.outcome.vehicles] if fits else [],
                          method=METHOD_MOMENTUM if momentum else METHOD_SEARCH,
                          interrupted=interrupted)


# --------------------------------------------------------------------------- the reconstructionist's fit

#: Momentum rounds (simulate, compare the slides, correct the speeds), the residuals' tolerance
#: on a speed (m/s) in those rounds, Levenberg-Marquardt iterations per round, its
#: finite-difference step (unit cube) and the largest step it takes at once; the final CMA-ES's
#: initial step (unit cube).
ROUNDS, SPEED_TOL, LM_ROUND, FD_STEP, MAX_STEP, SIGMA_FINAL = 6, 0.5, 3, 0.02, 0.3, 0.03
#: The share of the momentum correction taken per round (the whole correction overshot in the
#: planted crashes: the speeds swung about the answer from round to round).
GAIN = 0.5
#: Random rollouts the fit starts from (the one nearest the momentum seed's impact is the start).
START = 32
#: A residual entry for a contact that did not happen (a flat, large miss).
MISS = 10.0


def applies(case) -> bool:
    """Whether the momentum fit applies: two vehicles that hit each other and brake after it
    (the slides on locked wheels), each with a rest position and an impact position as evidence."""
    if case.n != 2:
        return False
    return all(v.fate.hits == (1 - i,) and v.fate.rest is not None and v.fate.impact_at is not None
               and v.driver.after_impact == ("brake",) for i, v in enumerate(case.vehicles))


def slide_speed(distance: float, mu: float) -> float:
    """The speed (m/s) that a slide on locked wheels over ``distance`` (m) at friction ``mu``
    takes off: sqrt(2 mu g d)."""
    return math.sqrt(2.0 * mu * G * max(distance, 0.0))


def momentum_speeds(mass, impact, approach, rest, mu: float) -> np.ndarray:
    """Pre-impact speeds (m/s) of two vehicles from the conservation of linear momentum through
    the impact: each leaves its impact position ``impact[i]`` (x, y) towards its rest position
    ``rest[i]`` at :func:`slide_speed` of that distance, and came in along the unit ``approach[i]``;
    m_A v_A e_A + m_B v_B e_B = m_A u_A + m_B u_B, solved for (v_A, v_B) (least squares when the
    approaches are parallel)."""
    mass = np.asarray(mass, float)
    post = np.zeros(2)
    for i in range(2):
        d = np.asarray(rest[i][:2], float) - np.asarray(impact[i][:2], float)
        n = float(np.hypot(*d))
        if n > 1e-9:
            post = post + mass[i] * slide_speed(n, mu) * d / n
    A = np.column_stack([mass[0] * np.asarray(approach[0], float), mass[1] * np.asarray(approach[1], float)])
    return np.linalg.lstsq(A, post, rcond=None)[0]


def _unit(a: float) -> np.ndarray:
    return np.array([math.cos(a), math.sin(a)])


def residuals(o, case, target=None) -> np.ndarray:
    """The evidence's misses in units of its tolerances: per vehicle the impact position (x, y),
    then (``target`` None) the rest position (x, y) and heading, or (``target``: speeds m/s) the
    impact speed against the target in :data:`SPEED_TOL`. A vehicle whose hits are wrong gets
    :data:`MISS` in each entry."""
    r = []
    for i, (vs, vo) in enumerate(zip(case.vehicles, o.vehicles)):
        f = vs.fate
        ok = [j for j, _ in vo.hits] == list(f.hits or ()) and (not f.hits or math.isfinite(vo.impact_speed))
        k = 2 * (f.impact_at is not None) + (1 if target is not None else
                                             2 * (f.rest is not None) + (f.heading is not None))
        if not ok:
            r += [MISS] * k
            continue
        if f.impact_at is not None:
            r += [(vo.impact_pos[0] - f.impact_at[0]) / f.impact_at[2], (vo.impact_pos[1] - f.impact_at[1]) / f.impact_at[2]]
        if target is not None:
            r.append((vo.impact_speed - target[i]) / SPEED_TOL)
            continue
        if f.rest is not None:
            r += [(vo.rest[0] - f.rest[0]) / f.rest[2], (vo.rest[1] - f.rest[1]) / f.rest[2]]
        if f.heading is not None:
            r.append(float(out_wrap(vo.rest[2] - f.heading[0])) / f.heading[1])
    return np.array(r)


class _Fitter:
    """Runs the fit's rollouts on the budget, every one handed to ``keep``."""

    def __init__(self, case, R, S, budget: int, keep, callback):
        self.case, self.R, self.S, self.budget, self.keep, self.callback = case, R, S, int(budget), keep, callback
        self.used = 0
        self.best: search_mod.Trial | None = None

    def run(self, U: np.ndarray) -> list:
        U = np.clip(np.atleast_2d(U), 0.0, 1.0)[: max(0, self.budget - self.used)]
        if not len(U):
            return []
        r = self.R.run(self.S.intents(U))
        out = []
        for i, u in enumerate(U):
            t = search_mod.Trial(u=u.copy(), outcome=r.outcomes[i], controls=r.controls[i], qpos0=r.qpos0[i],
                                 qvel0=r.qvel0[i], final_qpos=r.final_qpos[i])
            self.keep(t)
            if self.best is None or t.cost < self.best.cost:
                self.best = t
            out.append(t)
        self.used += len(U)
        best = self.best
        if self.callback and best is not None:  # not None: U had a row
            self.callback(search_mod.CrashProgress(self.used, best.cost, best.outcome.signature_text(self.case.n),
                                                   best.outcome.solved, 0))
        return out

    def cma(self, t, fn, rng, sigma: float = SIGMA_FINAL):
        """CMA-ES from trial ``t`` on the sum of squares of ``fn(outcome)`` until the budget
        (restarted at a third of the step from the best when it stalls); the trial of least squares."""
        import cma

        best, rb = t, fn(t.outcome)
        k = 0
        while self.used + BATCH <= self.budget:
            es = cma.CMAEvolutionStrategy(best.u.tolist(), sigma / 3 ** (k % 3),
                                          {"bounds": [0.0, 1.0], "popsize": BATCH, "verbose": -9,
                                           "seed": int(rng.integers(1, 2**31 - 1))})
            stalled, here = 0, float(rb @ rb)
            while self.used + BATCH <= self.budget and stalled < 6:
                xs = es.ask()
                ts = self.run(np.array(xs))
                rs = [fn(x.outcome) for x in ts]
                cs = [float(x @ x) for x in rs]
                es.tell(xs, cs)
                j = int(np.argmin(cs))
                if cs[j] < float(rb @ rb):
                    best, rb = ts[j], rs[j]
                if cs[j] < here - 1e-9:
                    here, stalled = cs[j], 0
                else:
                    stalled += 1
            k += 1
        return best, rb

    def lm(self, t, fn, iters: int):
        """Levenberg-Marquardt from trial ``t`` on the residuals ``fn(outcome)``: each iteration a
        forward-difference Jacobian (one rollout per coordinate) and a batch of damped steps;
        returns the trial of least squares."""
        d = self.S.dim
        r0 = fn(t.outcome)
        for _ in range(iters):
            if self.used + d + 1 > self.budget:
                break
            h = np.where(t.u + FD_STEP <= 1.0, FD_STEP, -FD_STEP)
            fd = self.run(t.u[None] + np.diag(h))
            if len(fd) < d:
                break
            J = np.column_stack([(fn(f.outcome) - r0) / h[k] for k, f in enumerate(fd)])
            JTJ, g = J.T @ J, J.T @ r0
            scale = max(float(np.trace(JTJ)) / d, 1e-9)
            steps = []
            for lam in (1e-4, 1e-3, 1e-2, 0.03, 0.1, 0.3, 1.0, 3.0):
                s = -np.linalg.solve(JTJ + lam * scale * np.eye(d), g)
                n = float(np.linalg.norm(s))
                steps.append(s * min(1.0, MAX_STEP / n) if n > 0 else s)
            cand = self.run(t.u[None] + np.array(steps))
            if not cand:
                break
            rs = [fn(c.outcome) for c in cand]
            k = int(np.argmin([float(x @ x) for x in rs]))
            if float(rs[k] @ rs[k]) < float(r0 @ r0):
                t, r0 = cand[k], rs[k]
            if float(r0 @ r0) < 1e-3:
                break
        return t, r0


def momentum_fit(case, R, S, budget: int, rng, keep, callback=None) -> int:
    """The reconstructionist's fit of a case that :func:`applies`: (1) the momentum seed: the
    speeds that conserve momentum from the evidence's impact positions (approaching from the
    start) to its rest positions along slides on locked wheels; (2) rounds of: least squares of
    the intents to the impact positions and the target speeds (the approach is smooth in the
    intents), then a simulation, and the target speeds corrected by the momentum balance of the
    evidence's slides against the simulated ones (from the simulated impact: the model's errors
    cancel); (3) least squares of the intents to the whole evidence (impact and rest positions,
    headings). Every rollout goes to ``keep``. Returns the rollouts used."""
    F = _Fitter(case, R, S, budget, keep, callback)
    mass = [v.vtype.mass for v in case.vehicles]
    mu = case.road.friction
    ev_imp = [v.fate.impact_at for v in case.vehicles]
    ev_rest = [v.fate.rest for v in case.vehicles]
    approach = []
    for v, p in zip(case.vehicles, ev_imp):
        d = np.array(p[:2]) - [v.x, v.y]
        approach.append(d / max(float(np.hypot(*d)), 1e-9))
    target = momentum_speeds(mass, ev_imp, approach, ev_rest, mu)
    hi = max(v.speed.hi for v in case.vehicles)
    target = np.clip(target, 0.5, hi * 1.5)
    starts = F.run(rng.random((START, S.dim)))
    if not starts:
        return F.used
    t = min(starts, key=lambda x: float(np.sum(residuals(x.outcome, case, target) ** 2)))
    for _ in range(ROUNDS):
        t, _ = F.lm(t, lambda o: residuals(o, case, target), LM_ROUND)
        vo = t.outcome.vehicles
        if not all(math.isfinite(v.impact_speed) for v in vo):
            break
        full = residuals(t.outcome, case)
        if float(np.max(np.abs(full))) <= 0.5:
            break
        imp = [v.impact_pos for v in vo]
        app = [_unit(v.impact_heading) for v in vo]
        sim = np.array([v.impact_speed for v in vo])
        corr = momentum_speeds(mass, imp, app, ev_rest, mu) - momentum_speeds(mass, imp, app,
                                                                               [v.rest for v in vo], mu)
        target = np.clip(sim + GAIN * corr, 0.5, hi * 1.5)
    F.cma(t, lambda o: residuals(o, case), rng)
    return F.used
