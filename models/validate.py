"""Cross-validation: a solution run in MuJoCo against nbst's exact simulator.

``validate(problem, velocities) -> Validation`` (compute only); ``Validation.to_dict()``
is ``report.json``; :mod:`nbst.render.report` draws ``report.html``.

What is compared:
* per-disk final position error (units), cost / signature / order under each;
* the collision sequences (disk-disk and wall), aligned in order by their (kind, i, j)
  keys; each matched pair gets a time offset (MuJoCo time - exact time). MuJoCo sees a
  contact in the first step state with overlap (offset 0 .. h for a first impact) and
  resolves it one step late (measured: an exact reflection delayed by h), so the lags of
  earlier impacts add up: offsets of a few h are normal;
* energy drift: kinetic energy relative to the start, over the steps with no contact
  (while a contact spring is compressed the kinetic energy dips, which is not drift);
* divergence: the first time any disk's two trajectories part by more than ``tol``
  units, the disk, and the event that caused it (the last event involving that disk at
  or before that time, in either motion). Chaos makes late divergence normal: a 0.1 deg
  error at one collision grows at every later one.

The MuJoCo run steps ``fixed`` (h every step) or ``aligned`` (:mod:`nbst.models.stepping`:
every impact resolved at its touch; its cost is reported). Also reported:

* ``sensitivity``: :func:`nbst.sim.sensitivity.analyze` at the run's h, and ``prediction_check``:
  its fixed-step prediction (keeps the signature? max error) against a fixed-step run at h;
* with ``convergence=True``: fixed steps at h, h/2, ... h/32 (the scene rebuilt per step,
  k = 2/h^2) and aligned stepping, each entry's max final error, signature and cost, and the
  fitted order (least-squares slope of log error on log h over the entries in the first-order
  regime, :data:`nbst.models.convergence.FIT_RULE`; the study lives in :mod:`nbst.models.convergence`).

Many disks (docs/mujoco.md, "Many disks"): ``stepping="auto"`` picks the stepping by N and cost
(:func:`choose_stepping`), the sensitivity is skipped above :data:`SENSITIVITY_MAX_N`, and
:func:`nbst.models.gas.gas_motion` makes test motions of any size.

Length: one comparison and the one schema of report.json (``Validation.to_dict``), with the
stepping choice that feeds it; split, the schema's keys would be written in several files.
"""
from __future__ import annotations

import difflib
from dataclasses import dataclass
from typing import Any

import numpy as np

from nbst.errors import InputError
from nbst.problem import Problem

from nbst.models.convergence import convergence_study, entry, fit_order, staged as run_stage
from nbst.models.mjrun import MAX_STEPS, STEPPINGS, check_steps, run_final, run_mujoco, steps_needed
from nbst.models.scene import DEFAULT_TIMESTEP, DEFAULT_UNIT
from nbst.progress import count_text, seconds_text

__all__ = ["SCHEMA_VERSION", "AUTO_FIXED_MAX_N", "AUTO_MAX_COST_RATIO", "AUTO_TRIALS_PER_IMPACT", "SENSITIVITY_MAX_N",
           "WORST_DISKS", "SUMMARY_STRING_MAX_N", "DIVERGE_TOL", "CURVE_SAMPLES", "COMPARE_CHUNK", "describe",
           "Validation", "choose_stepping", "validate", "prediction_check"]

SCHEMA_VERSION = 4  # 2: stepping, sensitivity, prediction_check, convergence, convergence_order;
#                    3: stepping requested/reason/record_stride, final_error mean/median/worst;
#                    4: mujoco.wall_time_s is the MuJoCo run's (its bar's), validate_wall_time_s the whole
#: ``stepping="auto"`` (the default): fixed steps up to this many disks (every problem nbst took before
#: it lifted its 63-disk cap validates as it always did), aligned stepping above. Measured on gas
#: motions at fixed density (``nbst.models.gas.gas_motion``, 2 s, ~3 impacts per disk; docs/mujoco.md "Many disks"):
#: fixed steps of 0.25 ms end 194-549 units off at every N from 10 to 1,000 (each impact lags one step
#: and the collisions amplify it), aligned stepping 3e-8 to 1e-3 units, at 3-8x the wall time of fixed
#: steps (4.1x at 10 disks, 7.8x at 1,000: its mj_step calls grow with the impacts, 2.8x those of fixed
#: steps at 1,000 disks, and each call adds a collision check).
AUTO_FIXED_MAX_N = 63
#: ... unless aligned stepping would take more than this many times the mj_step calls of fixed steps
#: (~10-20x their wall time): its calls are about steps + AUTO_TRIALS_PER_IMPACT x impacts (measured
#: 4.7-5.2 per impact on the gas motions of 100-1,000 disks: search trials, a micro-step, the shortened
#: step), the fixed run's t_final / h. The gas motions reach it near 2,000 disks (their impacts grow
#: as N: an extrapolation, not a measurement); there auto falls back to fixed steps.
AUTO_MAX_COST_RATIO = 5.0
AUTO_TRIALS_PER_IMPACT = 5.2
#: The sensitivity analysis (``nbst.sim.sensitivity``) is skipped by default above this many disks:
#: it carries a dense (2N x 2C) Jacobian through every event (measured 0.27 s at 300 disks, 21 s at
#: 1,000 on the gas motions); ``sensitivity=True`` forces it.
SENSITIVITY_MAX_N = 300
#: Disks listed by name in the report's worst-disk table and in report.json's ``final_error.worst``.
WORST_DISKS = 10
#: Above this many disks the summary gives counts instead of the signature strings (report.json keeps them).
SUMMARY_STRING_MAX_N = 64
#: Default divergence tolerance (units): a tenth of the benchmark disks' radius of 10-20,
#: far above MuJoCo's one-step impact lag (|dv| h ~ 0.05-0.2 units) for a few impacts.
DIVERGE_TOL = 1.0
#: Samples of the per-disk error curve kept in the report (the divergence is found on every
#: recorded step: every step unless the run recorded with a stride, ``MujocoRun.stride``).
CURVE_SAMPLES = 600
#: Positions compared at once when the per-step error is computed (bounds its memory: 2e6 x 16 B).
COMPARE_CHUNK = 2_000_000
_WALL_NAMES = ("left", "right", "bottom", "top")


def describe(kind: int, i: int, j: int, t: float | None = None) -> str:
    at = "" if t is None else f"t={t:.4f}s "
    if kind == 1:
        return f"{at}disk {i} hits the {_WALL_NAMES[j]} wall"
    return f"{at}disks {i} and {j} collide"


def _keys(events) -> list:
    out = []
    for e in events:
        i, j = int(e["i"]), int(e["j"])
        if e["kind"] == 0 and i > j:
            i, j = j, i
        out.append((int(e["kind"]), i, j))
    return out


@dataclass(frozen=True, eq=False)
class Validation:
    """Everything ``nbst validate`` reports. Positions in problem units, times in s."""

    problem: Problem
    velocities: np.ndarray
    timestep: float
    unit: float
    tol: float
    exact: Any  # nbst.sim.Trajectory
    mujoco: Any  # nbst.models.mjrun.MujocoRun
    final_error: np.ndarray  # (N,) units
    mj_cost: float
    mj_signature: int
    matches: list  # [(exact index, mujoco index)]
    error_curve_t: np.ndarray  # (S,)
    error_curve: np.ndarray  # (S, N)
    diverge: dict | None
    energy_drift_free: float  # max |E/E0 - 1| over contact-free steps
    energy_drift_final: float
    wall_time: float
    stepping: str = "fixed"
    sensitivity: dict | None = None
    prediction_check: dict | None = None
    convergence: list | None = None
    convergence_order: dict | None = None
    stepping_requested: str | None = None  # "auto", "fixed" or "aligned" (None: as ``stepping``)
    stepping_reason: str = ""  # why this stepping (``choose_stepping``)
    exact_on: np.ndarray | None = None  # (N,) bool: exact final position within R of the target
    mj_on: np.ndarray | None = None  # (N,) bool: the same under MuJoCo
    #: seconds of the MuJoCo run compared (its scene built and stepped: the span of its progress bar);
    #: ``wall_time`` is the whole validation (exact motion, comparison, sensitivity, convergence study)
    mujoco_seconds: float | None = None

    def _on(self, which: str) -> np.ndarray:
        on = self.exact_on if which == "exact" else self.mj_on
        if on is not None:
            return np.asarray(on, bool)
        sig = self.exact.signature if which == "exact" else self.mj_signature
        return np.array([(int(sig) >> i) & 1 == 1 for i in range(self.problem.n)], dtype=bool)

    @property
    def exact_signature_string(self) -> str:
        return "".join("1" if x else "0" for x in self._on("exact"))

    @property
    def exact_order(self) -> int:
        return int(self._on("exact").sum())

    @property
    def mj_signature_string(self) -> str:
        return "".join("1" if x else "0" for x in self._on("mujoco"))

    @property
    def mj_order(self) -> int:
        return int(self._on("mujoco").sum())

    @property
    def signatures_agree(self) -> bool:
        return bool(np.array_equal(self._on("exact"), self._on("mujoco")))

    @property
    def signature_differs_at(self) -> np.ndarray:
        """Indices of the disks on target in one motion and not in the other."""
        return np.flatnonzero(self._on("exact") != self._on("mujoco"))

    @property
    def matched_offsets(self) -> np.ndarray:
        ex, mj = self.exact.events, self.mujoco.events
        return np.array([mj["time"][b] - ex["time"][a] for a, b in self.matches])

    def worst_disks(self, k: int = WORST_DISKS) -> list:
        """The k disks with the largest final error, worst first: [{disk, error, exact, mujoco}]."""
        idx = np.argsort(-self.final_error, kind="stable")[:k]
        return [{"disk": int(i), "error": float(self.final_error[i]),
                 "exact": self.exact.final_positions[i].tolist(), "mujoco": self.mujoco.final_positions[i].tolist()}
                for i in idx]

    def to_dict(self) -> dict:
        p, ex, mj = self.problem, self.exact, self.mujoco
        off = self.matched_offsets
        matched_ex = {a for a, _ in self.matches}
        matched_mj = {b for _, b in self.matches}

        def ev_list(evs, matched):
            return [{"time": float(e["time"]), "kind": "disk" if e["kind"] == 0 else "wall", "i": int(e["i"]),
                     "j": int(e["j"]), "matched": k in matched,
                     "text": describe(int(e["kind"]), int(e["i"]), int(e["j"]), float(e["time"]))}
                    for k, e in enumerate(evs)]

        return {
            "schema_version": SCHEMA_VERSION,
            "problem": p.name,
            "n": p.n,
            "t_final": p.t_final,
            "velocities": self.velocities.tolist(),
            "mujoco": {"version": _mujoco_version(), "timestep": self.timestep, "unit_m": self.unit,
                       "steps": mj.steps, "wall_time_s": self._mujoco_seconds,
                       "validate_wall_time_s": self.wall_time},
            "stepping": {"mode": self.stepping, "requested": self.stepping_requested or self.stepping,
                         "reason": self.stepping_reason, "timestep": self.timestep, "steps": mj.steps,
                         "stepping_wall_time_s": mj.wall_time, "cost": mj.stats,
                         "record_stride": int(getattr(mj, "stride", 1))},
            "tolerance": self.tol,
            "final_error": {"per_disk": self.final_error.tolist(), "max": float(self.final_error.max()),
                            "mean": float(self.final_error.mean()), "median": float(np.median(self.final_error)),
                            "worst": self.worst_disks(),
                            "exact_final": ex.final_positions.tolist(), "mujoco_final": mj.final_positions.tolist()},
            "exact": {"cost": ex.cost, "signature": self.exact_signature_string, "order": self.exact_order,
                      "disk_disk": ex.n_disk_disk, "wall": ex.n_wall, "truncated": bool(ex.truncated)},
            "mujoco_result": {"cost": self.mj_cost, "signature": self.mj_signature_string,
                              "order": self.mj_order,
                              "disk_disk": int(np.count_nonzero(mj.events["kind"] == 0)),
                              "wall": int(np.count_nonzero(mj.events["kind"] == 1))},
            "signatures_agree": self.signatures_agree,
            "events": {
                "matched": len(self.matches),
                "exact_only": len(ex.events) - len(self.matches),
                "mujoco_only": len(mj.events) - len(self.matches),
                "offset_s": {"min": float(off.min()) if off.size else None,
                             "max": float(off.max()) if off.size else None,
                             "mean_abs": float(np.abs(off).mean()) if off.size else None},
                "offset_s_before_divergence": self._offsets_before_divergence(),
                "first_mismatch": self._first_mismatch(),
                "exact": ev_list(ex.events, matched_ex),
                "mujoco": ev_list(mj.events, matched_mj),
            },
            "energy": {"drift_max_contact_free": self.energy_drift_free, "drift_final": self.energy_drift_final},
            "divergence": self.diverge,
            "sensitivity": self.sensitivity,
            "prediction_check": self.prediction_check,
            "convergence": self.convergence,
            "convergence_order": self.convergence_order,
        }

    def _offsets_before_divergence(self):
        """min/max of the matched offsets of exact events before the divergence (all if none)."""
        off = self.matched_offsets
        if not off.size:
            return None
        t_ex = np.array([self.exact.events["time"][a] for a, _ in self.matches])
        keep = off if self.diverge is None else off[t_ex <= self.diverge["time"]]
        if not keep.size:
            return None
        return {"min": float(keep.min()), "max": float(keep.max()), "count": int(keep.size)}

    def _first_mismatch(self):
        """The earliest event (by time) that has no partner in the other motion, or None."""
        ex, mj = self.exact.events, self.mujoco.events
        me = {a for a, _ in self.matches}
        mm = {b for _, b in self.matches}
        cands = [(float(ex["time"][k]), "exact only", k, ex) for k in range(len(ex)) if k not in me]
        cands += [(float(mj["time"][k]), "mujoco only", k, mj) for k in range(len(mj)) if k not in mm]
        if not cands:
            return None
        t, side, k, evs = min(cands, key=lambda c: c[0])
        e = evs[k]
        return {"time": t, "side": side, "text": describe(int(e["kind"]), int(e["i"]), int(e["j"]), t)}

    def summary(self) -> str:
        d = self.to_dict()
        ev = d["events"]
        lines = [
            f"problem    {self.problem.name}  ({self.problem.n} disks, t_final = {self.problem.t_final:g} s); "
            f"MuJoCo {d['mujoco']['version']}, h = {self.timestep * 1e3:g} ms, {self._run_text()}",
            f"final      max error {self.final_error.max():.4g} units (disk {int(self.final_error.argmax())}); "
            f"mean {self.final_error.mean():.4g}" + (f"; median {np.median(self.final_error):.4g}; "
                                                     f"{int((self.final_error <= self.tol).sum())} of "
                                                     f"{self.problem.n} disks within {self.tol:g}"
                                                     if self.problem.n > SUMMARY_STRING_MAX_N else ""),
            *self._signature_lines(d),
            f"events     {ev['matched']} matched in order, {ev['exact_only']} exact only, {ev['mujoco_only']} "
            f"MuJoCo only" + (f"; offsets {ev['offset_s']['min'] * 1e3:.3g} .. {ev['offset_s']['max'] * 1e3:.3g} ms"
                              if ev["matched"] else "")
            + (f" ({pre['min'] * 1e3:.3g} .. {pre['max'] * 1e3:.3g} ms before the divergence)"
               if self.diverge and (pre := ev["offset_s_before_divergence"]) else ""),
            f"energy     drift {self.energy_drift_free:.3g} (max, contact-free steps), "
            f"{self.energy_drift_final:+.3g} at t_final",
        ]
        lines += self._summary_extra()
        if ev["first_mismatch"]:
            lines.append(f"mismatch   first: {ev['first_mismatch']['text']} ({ev['first_mismatch']['side']})")
        if self.diverge:
            dv = self.diverge
            unit = "unit" if self.tol == 1 else "units"
            lines.append(f"diverge    disk {dv['disk']} parts by > {self.tol:g} {unit} at t={dv['time']:.4f}s; "
                         f"cause: {dv['cause']}")
        else:
            lines.append(f"diverge    never: every disk stays within {self.tol:g} unit{'' if self.tol == 1 else 's'} of its exact path")
        return "\n".join(lines)


    @property
    def _mujoco_seconds(self) -> float:
        return float(self.mujoco.wall_time if self.mujoco_seconds is None else self.mujoco_seconds)

    def _run_text(self) -> str:
        """The MuJoCo run in the summary's first line: its steps of h (what its progress bar counts)
        and its seconds (the bar's clock: compiling and the rest of the validation are not in it)."""
        t = seconds_text(self._mujoco_seconds)
        st = self.mujoco.stats
        if self.stepping == "aligned" and st:
            return (f"aligned: {count_text(steps_needed(self.problem.t_final, self.timestep))} steps of h "
                    f"({count_text(st['steps'])} accepted + {count_text(st['impacts'])} impact micro-steps) in {t}")
        return f"{count_text(self.mujoco.steps)} steps in {t}"

    def _signature_lines(self, d) -> list:
        """The exact and MuJoCo lines of the summary: the signature strings up to
        :data:`SUMMARY_STRING_MAX_N` disks, counts above (report.json keeps the strings)."""
        ex, mj = d["exact"], d["mujoco_result"]
        n = self.problem.n
        agree = "same" if self.signatures_agree else "DIFFERENT"
        if n <= SUMMARY_STRING_MAX_N:
            return [f"exact      cost {ex['cost']:.6g}  signature {ex['signature']}  order {ex['order']}",
                    f"mujoco     cost {mj['cost']:.6g}  signature {mj['signature']}  order {mj['order']}  "
                    f"({agree} signature)"]
        diff = self.signature_differs_at
        where = "" if not diff.size else (f"; differs at {diff.size} disks: "
                                          + ", ".join(map(str, diff[:10])) + (" ..." if diff.size > 10 else ""))
        return [f"exact      cost {ex['cost']:.6g}  order {ex['order']} of {n} disks on target",
                f"mujoco     cost {mj['cost']:.6g}  order {mj['order']} of {n} disks on target  "
                f"({agree} signature{where})"]

    def _summary_extra(self) -> list:
        """Summary lines of the stepping choice and cost, the prediction check and the convergence study."""
        out = []
        if self.stepping_reason:
            out.append(f"stepping   {self.stepping}: {self.stepping_reason}")
        st = self.mujoco.stats
        if st:
            out.append(f"stepping   aligned: {st['steps']:,} steps + {st['impacts']:,} impact micro-steps "
                       f"({st['simultaneous']} simultaneous), {st['bisections']:,} search + {st['graze_checks']:,} "
                       f"graze trial steps")
        pc = self.prediction_check
        if pc:
            def yn(x):
                return "?" if x is None else ("yes" if x else "no")
            out.append(f"predicted  fixed h = {pc['timestep'] * 1e3:g} ms: max error "
                       f"{_g(pc['predicted_error_linear_max'])} (linear), <= {_g(pc['predicted_error_max'])} "
                       f"(worst case); measured {_g(pc['measured_error_max'])}; keeps signature: predicted "
                       f"{yn(pc['keeps_signature_predicted'])}, measured {yn(pc['keeps_signature_measured'])} "
                       f"({pc['verdict']})")
        elif self.sensitivity and self.sensitivity.get("error"):
            out.append(f"predicted  no prediction: {self.sensitivity['error']}")
        if self.convergence:
            fixed = [e for e in self.convergence if e["stepping"] == "fixed" and e["max_error"] is not None]
            al = [e for e in self.convergence if e["stepping"] == "aligned"]
            co = self.convergence_order or {}
            txt = ", ".join(f"h/{e['divisor']} {_g(e['max_error'])}" for e in fixed)
            order = f"order {co['order']:.2f} on {len(co['points_h'])} points" if co.get("order") is not None \
                else "order not fitted (fewer than 2 points in the first-order regime)"
            out.append(f"converge   max error {txt}; aligned {_g(al[0]['max_error']) if al else '-'}; {order}")
        return out


def _g(x) -> str:
    return "-" if x is None else f"{x:.3g}"


def _mujoco_version() -> str:
    import mujoco
    return str(mujoco.__version__)


def choose_stepping(problem: Problem, exact, timestep: float, requested: str = "auto") -> tuple[str, str]:
    """(stepping, why): ``requested`` if it is "fixed" or "aligned"; for "auto", fixed up to
    :data:`AUTO_FIXED_MAX_N` disks, aligned above unless its estimated cost passes
    :data:`AUTO_MAX_COST_RATIO` x the fixed steps (``exact``: the exact motion, for its impacts)."""
    if requested in STEPPINGS:
        return requested, f"--stepping {requested} requested"
    if requested != "auto":
        raise InputError(f"stepping must be auto, fixed or aligned, got {requested!r}")
    n = problem.n
    if n <= AUTO_FIXED_MAX_N:
        return "fixed", (f"auto: fixed steps for at most {AUTO_FIXED_MAX_N} disks ({n} here); "
                         f"--stepping aligned resolves each impact at its touch")
    steps = steps_needed(problem.t_final, timestep)
    impacts = len(exact.events)
    ratio = (steps + AUTO_TRIALS_PER_IMPACT * impacts) / max(steps, 1)
    if ratio > AUTO_MAX_COST_RATIO:
        return "fixed", (f"auto: {n} disks, but aligned stepping would take ~{ratio:.0f}x the mj_step calls of "
                         f"fixed steps ({impacts:,} exact impacts in {steps:,} steps; limit "
                         f"{AUTO_MAX_COST_RATIO:g}x); --stepping aligned forces it")
    return "aligned", (f"auto: aligned stepping above {AUTO_FIXED_MAX_N} disks ({n} here, {impacts:,} exact "
                       f"impacts: ~{ratio:.1f}x the mj_step calls of fixed steps, each with a collision check): "
                       f"fixed steps lag every impact by one step and many collisions amplify it; "
                       f"--stepping fixed for MuJoCo's own steps")


def validate(problem: Problem, velocities, *, timestep: float = DEFAULT_TIMESTEP, unit: float = DEFAULT_UNIT,
             tol: float = DIVERGE_TOL, max_steps: int | None = None, stepping: str = "auto",
             convergence: bool = False, sensitivity: bool | None = None, progress=None) -> Validation:
    """Run ``velocities`` (N, 2, units/s) in MuJoCo and in the exact simulator; compare (see module doc).

    max_steps   : InputError before any work if t_final needs more MuJoCo steps
                  (default ``nbst.models.mjrun.MAX_STEPS``); the convergence ladder skips the
                  step sizes that need more
    stepping    : "auto" (``choose_stepping``), "fixed" or "aligned" (``nbst.models.mjrun.STEPPINGS``)
    convergence : also run the convergence study (module doc)
    sensitivity : add ``nbst.sim.sensitivity.analyze`` at h and its check against a fixed-step run;
                  None: only up to :data:`SENSITIVITY_MAX_N` disks
    progress    : None, or a factory progress(desc, total, unit) -> a bar with update(k) and close()
                  (``nbst.progress.progress_bar``'s interface), one bar per long stage
    """
    import time

    from nbst.sim import simulate

    if not (np.isfinite(tol) and tol > 0):
        raise InputError(f"tol must be > 0, got {tol!r}")
    max_steps = MAX_STEPS if max_steps is None else int(max_steps)
    check_steps(problem.t_final, timestep, max_steps)
    t0 = time.perf_counter()
    v = np.asarray(velocities, dtype=float)
    ex = simulate(problem, v)
    requested = stepping
    stepping, reason = choose_stepping(problem, ex, timestep, requested)

    def staged(desc, total, fn, unit="step"):
        return run_stage(progress, desc, total, fn, unit)[0]

    steps = steps_needed(problem.t_final, timestep)
    mj, mj_seconds = run_stage(progress, f"MuJoCo, {stepping} steps", steps,
                             lambda cb: run_mujoco(problem, v, timestep=timestep, unit=unit, max_steps=max_steps,
                                                   stepping=stepping, progress=cb))

    final_err = np.hypot(*(mj.final_positions - ex.final_positions).T)
    R2 = float(problem.target_radius) ** 2
    target = np.asarray(problem.target, dtype=float)
    dx = mj.final_positions - target
    d2 = (dx * dx).sum(axis=1)
    mj_cost = float(d2.sum())
    mj_on = d2 <= R2  # the exact simulator's rule (nbst.sim.kernel.cost_signature)
    de = ex.final_positions - target
    exact_on = (de * de).sum(axis=1) <= R2
    mj_sig = int(sum(1 << int(i) for i in np.flatnonzero(mj_on)))

    # event sequences aligned in order by their keys
    ka, kb = _keys(ex.events), _keys(mj.events)
    sm = difflib.SequenceMatcher(a=ka, b=kb, autojunk=False)
    matches = [(blk.a + k, blk.b + k) for blk in sm.get_matching_blocks() for k in range(blk.size)]

    # per-disk error at every recorded MuJoCo step (t <= t_final), in chunks (memory)
    ts = mj.times[mj.times <= problem.t_final * (1 + 1e-12)]
    stride = max(1, ts.size // CURVE_SAMPLES)
    chunk = max(1, COMPARE_CHUNK // max(problem.n, 1))
    keep = np.arange(0, ts.size, stride)
    curve = np.empty((keep.size, problem.n))
    diverge = None
    for a in range(0, ts.size, chunk):
        b = min(a + chunk, ts.size)
        err = np.hypot(*(mj.positions[a:b] - ex.at(ts[a:b])).transpose(2, 0, 1))  # (b - a, N)
        sel = keep[(keep >= a) & (keep < b)]
        curve[np.searchsorted(keep, sel)] = err[sel - a]
        if diverge is None:
            over = np.flatnonzero((err > tol).any(axis=1))
            if over.size:
                s = a + int(over[0])
                disk = int(np.argmax(err[over[0]]))
                diverge = {"time": float(ts[s]), "disk": disk, "error": float(err[over[0], disk])}
                if getattr(mj, "stride", 1) > 1:
                    diverge["resolution_s"] = float(ts[s] - ts[s - 1]) if s else 0.0
                diverge.update(_cause(ex, mj, disk, float(ts[s]), matches))
    E = mj.energy
    free = ~mj.in_contact
    E0 = E[0] if E[0] > 0 else 1.0
    drift_free = float(np.abs(E[free] / E0 - 1).max()) if E[0] > 0 else 0.0
    drift_final = float(E[-1] / E0 - 1) if E[0] > 0 else 0.0
    conv = order = None
    if convergence:
        conv = convergence_study(problem, v, ex, timestep=timestep, unit=unit, max_steps=max_steps,
                                 aligned=mj if stepping == "aligned" else None,
                                 fixed=mj if stepping == "fixed" else None, progress=progress)
        order = fit_order(conv, problem)
    sens = check = None
    if sensitivity is None:
        sensitivity = problem.n <= SENSITIVITY_MAX_N
        if not sensitivity:
            sens = {"skipped": f"{problem.n} disks, above {SENSITIVITY_MAX_N}: the analysis carries a dense "
                               f"(2N x 2C) Jacobian through every event (21 s at 1,000 disks, measured); "
                               f"nbst.sim.sensitivity.analyze runs it"}
    if sensitivity:
        def run_sens(cb):
            out = _sensitivity(problem, v, timestep)
            if cb:
                cb(1)
            return out
        sens = staged(f"sensitivity analysis ({problem.n} disks)", 1, run_sens, unit="run")
        if stepping == "fixed":
            fixed = (float(final_err.max()), bool(np.array_equal(mj_on, exact_on)), "this run")
        elif conv and conv[0]["max_error"] is not None:
            fixed = (conv[0]["max_error"], conv[0]["same_signature"], "convergence entry h")
        else:
            e = entry(problem, ex, *staged("MuJoCo, fixed steps (for the prediction check)", steps,
                                            lambda cb: run_final(problem, v, timestep=timestep, unit=unit,
                                                                 max_steps=max_steps, progress=cb)),
                       h=timestep, divisor=1)
            fixed = (e["max_error"], e["same_signature"], "extra fixed-step run")
        check = prediction_check(sens, timestep, *fixed)
    return Validation(problem=problem, velocities=v, timestep=float(timestep), unit=float(unit), tol=float(tol),
                      exact=ex, mujoco=mj, final_error=final_err, mj_cost=mj_cost, mj_signature=mj_sig,
                      matches=matches, error_curve_t=ts[keep], error_curve=curve, diverge=diverge,
                      energy_drift_free=drift_free, energy_drift_final=drift_final,
                      wall_time=time.perf_counter() - t0, stepping=stepping, sensitivity=sens,
                      prediction_check=check, convergence=conv, convergence_order=order,
                      stepping_requested=requested, stepping_reason=reason, exact_on=exact_on, mj_on=mj_on,
                      mujoco_seconds=mj_seconds)


def _sensitivity(problem: Problem, v, timestep: float) -> dict:
    """``nbst.sim.sensitivity.analyze`` at h, or {"error": why} when it cannot (e.g. too many events)."""
    from nbst.sim.sensitivity import analyze
    try:
        return analyze(problem, v, timestep=timestep)
    except (RuntimeError, ValueError, np.linalg.LinAlgError) as e:
        return {"error": str(e).splitlines()[0] if str(e) else type(e).__name__}


def prediction_check(sens: dict | None, timestep: float, measured_error: float, measured_keeps: bool,
                     source: str) -> dict | None:
    """The sensitivity's fixed-step prediction against a fixed-step run at the same h.

    verdict: "right" (predicted keeps-signature == measured), "conservative" (worst case said it
    may not keep, it did), "wrong" (predicted to keep, it did not).
    """
    pred = (sens or {}).get("prediction")
    if not pred:
        return None
    lin, worst = pred["predicted_error_linear_max"], pred["predicted_error_max"]
    p_keep = bool(pred["keeps_signature_predicted"])
    m_keep = bool(measured_keeps)
    verdict = "right" if p_keep == m_keep else ("conservative" if m_keep else "wrong")
    return {"timestep": float(timestep), "fixed_run": source,
            "keeps_signature_predicted": p_keep, "keeps_signature_predicted_rss": pred["keeps_signature_predicted_rss"],
            "keeps_signature_measured": m_keep, "verdict": verdict,
            "predicted_error_max": worst, "predicted_error_linear_max": lin,
            "measured_error_max": float(measured_error),
            "measured_over_linear": float(measured_error / lin) if lin else None,
            "within_worst_case": bool(measured_error <= worst) if worst is not None else None,
            "within_first_order": pred["within_first_order"]}


def _cause(ex, mj, disk: int, t: float, matches) -> dict:
    """The last event involving ``disk`` at or before t in either motion, described."""
    best = None
    for side, evs in (("exact", ex.events), ("mujoco", mj.events)):
        for k in range(len(evs) - 1, -1, -1):
            e = evs[k]
            if e["time"] <= t + 1e-12 and (e["i"] == disk or (e["kind"] == 0 and e["j"] == disk)):
                if best is None or e["time"] > best[0]:
                    best = (float(e["time"]), side, k, e)
                break
    if best is None:
        return {"cause": "no event: free flight drifted (unexpected; check the timestep)", "cause_event": None}
    t_e, side, k, e = best
    matched = {a for a, _ in matches} if side == "exact" else {b for _, b in matches}
    text = describe(int(e["kind"]), int(e["i"]), int(e["j"]), t_e)
    if k in matched:
        why = f"{text} (in both motions; its small MuJoCo error grew until here)"
    else:
        other = "MuJoCo" if side == "exact" else "the exact simulator"
        why = f"{text} ({side} motion only: {other} has no such event here)"
    return {"cause": why, "cause_event": {"time": t_e, "side": side, "index": int(k), "matched": k in matched}}
