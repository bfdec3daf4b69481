"""Reconstruction with honest uncertainty: Optimisation Monte Carlo over batched rollouts.

A case (:mod:`.evidence`: a crash script whose fates are the evidence, the unknowns besides the
drivers, more evidence kinds with their tolerances) is reconstructed by **Optimisation Monte
Carlo** (OMC: Meeds and Welling, *Optimization Monte Carlo: efficient and embarrassingly
parallel likelihood-free inference*, NeurIPS 2015). A likelihood-free posterior is sampled by
drawing the simulator's nuisance randomness and *optimising* the parameters of interest to the
observation for each draw, instead of waiting for a random draw to land on the evidence (the
rejection and ABC-SMC samplers a crash with 8 driver coordinates starves: 0 draws met the
built-in crossing-case in 2,400 rollouts, docs/results/crash.md). Here:

* the **parameters** are the drivers' intents within the script's ranges (speeds, aim,
  arrival, ...), the unit cube of :func:`.space.space_of`;
* each **draw** k takes the nuisance unknowns from their stated ranges, uniformly: the road's
  friction, each vehicle's load (kg over its type's mass), factors on the body contact's
  stiffness and damping ratio (the restitution); and an **error of the evidence** within its
  tolerances (:func:`.evidence.jitter`, :data:`JITTER` of each tolerance: the model that each
  piece of evidence is known to within its tolerance);
* the draw's intents are **fitted** to its moved evidence on the one rollout engine
  (:class:`nbst.models.mjsearch.engine.Engine`: a short exploring batch from a warm start, then
  CMA-ES, :data:`DRAW_ROLLOUTS` rollouts at most, every rollout with the draw's friction,
  masses and contact);
* the draw is **accepted** when its fit meets the *stated* evidence, every piece within its
  tolerance;
* each accepted draw's **local set** (:func:`_local`): the draw is linearised by forward
  differences in every coordinate of the intents and of the unknowns (one rollout each), and the
  set where every piece of the stated evidence stays within its tolerance, in that linear model,
  is sampled by hit-and-run (R. L. Smith, Operations Research 32, 1984); the intervals are over
  these samples. A set held in by its trust region (the intents within :data:`LOCAL_TRUST` of
  the draw) has its ends (each vehicle's lowest and highest impact speed) rolled out: while they
  meet the evidence its reach doubles (:data:`LOCAL_GROW` times at most), as a trust-region
  method grows its region where the model predicts well; where they do not, it keeps the reach
  last confirmed. With a uniform kernel and uniform priors the posterior near a draw is uniform
  on that set; a fit stops where it first meets the evidence, so the accepted draws bunch at one
  end of it, and a dozen draws sample the unknowns' ranges thinly (the planted cases' pinned
  intervals held the truth in 7 of 11 without the sets: docs/results/crash.md). Meeds and
  Welling weight each optimum by its prior over the Jacobian's volume; the weights here are
  equal (each set's volume is not estimated): an approximation, said so.

The fits start near a **pilot** fit (the intents and the unknowns together): for two vehicles
with impact and rest positions, the classic reconstructionist's **momentum Monte Carlo**
(linear momentum through the impact, each vehicle sliding to rest at sqrt(2 mu g d), the
inputs drawn over their ranges: Brach and Brach, *Vehicle Accident Analysis and Reconstruction
Methods*, SAE International, the chapter on uncertainty and sensitivity (its Monte Carlo
method); W. Bartlett and A. Fonda, *Evaluating Uncertainty in Accident Reconstruction with
Finite Differences*, SAE 2003-01-0489; the Monte Carlo reconstruction of SAE 2001-01-3347)
screens the speeds and gives the pilot its target speeds; then an engine fit of the whole
evidence, the unknowns coordinates too; each draw's warm start is a fit found so far with the
speeds scaled by the momentum balance at the draw's friction and masses. Then the **profile
probes** (:func:`_profile`: a speed held away from the accepted draws, the rest fitted; the
profile likelihood's test, Raue et al., Bioinformatics 25, 2009) look for a ridge of equal fits
the draws did not spread along.

Each vehicle's impact speed (just before its first vehicle contact), delta-V (that contact's
impulse over the drawn mass) and PDOF (principal direction of force, a clock: 12 from straight
ahead, 3 from the right) are summarised over the local sets' samples as a 90 % interval
(:data:`LEVEL`: 5th to 95th percentile). A quantity whose interval spans at least :data:`WEAK`
of its prior interval (the same quantity over the pilot's exploring rollouts that hit as the
evidence says, or the driver's speed range), a speed a profile probe moves, or one that fewer
than :data:`MIN_ACCEPTED` draws pin, is **not identifiable** from this evidence: its interval is reported at least as wide as
the prior's, never narrow. A pinned speed whose interval ends within :data:`EDGE` of its driver's
range's width of that range's end is taken to the end (a posterior piled against the range's
end, the truth at the edge).

The rollouts run on :class:`PhysRunner`: the case's :class:`~.run.CrashRunner` whose batch
gives each simulation its own friction, masses and contact (``mujoco.batch.Batch.expand``) and
records every vehicle's track per driver period (the EDR speed, the skid's start and length).
The crash written for a reconstruction is its accepted draw of least squared distance, run
again on a scene whose XML holds that draw's unknowns, so that it replays bit for bit.

Compute only.

Length: one method in one place: the runner with per-simulation physics, the momentum screen,
the pilot and the draws on the engine, the intervals and their identifiability verdicts (the
local sets' geometry, which needs no rollout, is :mod:`.localsets`).
"""
from __future__ import annotations

import math
import os
import sys
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from nbst.errors import InputError
from nbst.models.crash import driver as drv
from nbst.models.crash import evidence as ev_mod
from nbst.models.crash import scene as scene_mod
from nbst.models.crash import search as search_mod
from nbst.models.crash import crush as crush_mod
from nbst.models.crash.localsets import LOCAL_BURN, LOCAL_SAMPLES, LOCAL_TRUST, cut, residual, sample_set
from nbst.models.crash.run import BATCH, CrashRollouts, CrashRunner, scene_vehicles
from nbst.models.crash.script import Range
from nbst.models.crash.space import space_of
from nbst.models.crash.vehicle import BIT_BODY, G
from nbst.seeds import check_seed

__all__ = ["MAX_ROLLOUTS", "DRAWS", "DRAW_ROLLOUTS", "DRAW_PARALLEL", "DRAW_UNIFORM", "PILOT_SHARE", "PILOT_APPROACH", "EXPLORE",
           "POPSIZE", "STALL", "SIGMA_PILOT", "SIGMA_FIT", "SIGMA_DRAW", "PILOT_DONE", "DRAW_DONE", "JITTER", "LEVEL",
           "WEAK", "MIN_ACCEPTED", "SCREEN_SAMPLES", "SCREEN_SPEED_TOL", "PARALLEL_DEG", "ROUNDS", "GAIN", "PROFILE_ROLLOUTS", "PROFILE_SHARE",
           "LOCAL_SHARE", "LOCAL_DRAWS", "LOCAL_STEP", "LOCAL_TRUST", "LOCAL_SAMPLES", "LOCAL_BURN", "LOCAL_GROW",
           "LOCAL_CHECK_SHARE", "EDGE", "METHOD", "Progress",
           "PhysRunner", "Reconstruction", "reconstruct", "best_trial", "slide_speed", "momentum_speeds",
           "momentum_applies", "momentum_screen", "pdof_clock", "phys_coords", "scene_xml_of"]

#: The default rollout budget of one reconstruction (the CLI's --max-rollouts).
MAX_ROLLOUTS = 2000
#: OMC draws (the CLI's --draws), the most rollouts one draw's fit takes, and the draws fitted
#: together (their rollouts share batches).
DRAWS, DRAW_ROLLOUTS, DRAW_PARALLEL = 16, 64, 2
#: Of a draw's first batch (the warm start and steps about it), this many points are uniform in
#: the cube: where the evidence leaves a ridge of equal fits, a draw may start anywhere along it.
DRAW_UNIFORM = 3
#: The pilot's share of the budget, and the share of the pilot that fits the approach (impact
#: positions at the momentum screen's speeds) before the whole evidence.
PILOT_SHARE, PILOT_APPROACH = 0.45, 0.45
#: The pilot's exploring rollouts (uniform in the cube) and the CMA-ES population and stall.
EXPLORE, POPSIZE, STALL = 32, 8, 4
#: CMA-ES steps (unit cube): the pilot from a random best, the pilot from the approach fit, a draw.
SIGMA_PILOT, SIGMA_FIT, SIGMA_DRAW = 0.12, 0.04, 0.03
#: A fit stops once every target is within this many tolerances: the pilot, a draw.
PILOT_DONE, DRAW_DONE = 0.3, 0.35
#: A draw moves each piece of evidence by an error uniform within this share of its tolerance.
JITTER = 0.7
#: The profile probes (identifiability): per vehicle, its speed held halfway between the
#: accepted draws' and the prior's ends, each a fit of at most PROFILE_ROLLOUTS rollouts; a probe
#: that meets the evidence makes the speed not identifiable (the profile likelihood's test:
#: Raue et al., Bioinformatics 25, 2009). PROFILE_SHARE of the budget is kept for them.
PROFILE_ROLLOUTS, PROFILE_SHARE = 40, 0.1
#: The local sets (:func:`_local`): each of up to LOCAL_DRAWS accepted draws linearised by
#: forward differences of LOCAL_STEP (unit cube) in every coordinate, at its own unknowns; the
#: set where every piece of the stated evidence stays within its tolerance, in that linear model
#: and within LOCAL_TRUST of the draw, sampled by LOCAL_SAMPLES steps of hit-and-run after
#: LOCAL_BURN; LOCAL_SHARE of the budget is kept for the differences.
LOCAL_SHARE, LOCAL_DRAWS, LOCAL_STEP = 0.08, 16, 0.03  # (LOCAL_TRUST, LOCAL_SAMPLES, LOCAL_BURN: .localsets)
#: The local sets' reach, checked on the engine (:func:`_local`): a set that its trust region
#: bounds has its extreme samples (each vehicle's lowest and highest impact speed) rolled out;
#: when every one meets the stated evidence the trust doubles (up to 1: the ranges) and the set
#: is sampled again, at most LOCAL_GROW times; LOCAL_CHECK_SHARE of the budget is kept for it.
LOCAL_GROW, LOCAL_CHECK_SHARE = 2, 0.04
#: An interval's end within EDGE of its prior's width of the prior's end is taken to that end:
#: a posterior piled against a range's end (the truth at the edge) is cut there by a central
#: interval only by convention.
EDGE = 0.05
#: The intervals' level; an interval spanning WEAK of its prior's is not identifiable; fewer
#: accepted draws than MIN_ACCEPTED pin nothing (every interval widened to the prior's).
LEVEL, WEAK, MIN_ACCEPTED = 0.90, 0.3, 8
#: The momentum screen's draws, its speeds' tolerance (m/s) as a pilot target, and the angle
#: (deg) between approaches under which the momentum balance cannot split the speeds.
SCREEN_SAMPLES, SCREEN_SPEED_TOL, PARALLEL_DEG = 2000, 1.5, 15.0
#: The pilot's approach rounds (each: fit the approach, then correct the target speeds by the
#: momentum balance of the evidence's slides against the simulated ones, by GAIN of it: the
#: simulated slide is not the locked-wheel ideal, and the difference cancels).
ROUNDS, GAIN = 3, 0.7

METHOD = ("Optimisation Monte Carlo (Meeds and Welling, NeurIPS 2015): each draw takes the road friction, the loads "
          "and the contact's stiffness and damping from their ranges and an error of the evidence within its "
          "tolerances, fits the drivers' intents to it on the rollout engine, and is accepted when the fit meets "
          "every piece of the stated evidence within its tolerance; each accepted draw linearised in the intents and "
          "unknowns by finite differences and the set meeting the evidence about it sampled by hit-and-run (Smith "
          "1984), its reach doubled while its ends, rolled out, meet the evidence; equal weights; 90 % intervals over those samples; the pilot fit starts from the momentum Monte "
          "Carlo screen (Brach and Brach)")


# --------------------------------------------------------------------------- the runner

def phys_coords(case: ev_mod.Case) -> list:
    """The physical unknowns that vary, as [(name, vehicle index or None, lo, hi)]."""
    u = case.unknowns
    out = []
    if u.friction[1] > u.friction[0]:
        out.append(("friction", None, *u.friction))
    if u.load[1] > u.load[0]:
        out += [("load", i, *u.load) for i in range(case.n)]
    for nm in ("stiffness", "damping"):
        r = getattr(u, nm)
        if r[1] > r[0]:
            out.append((nm, None, *r))
    return out


def _phys_values(case: ev_mod.Case, P: np.ndarray) -> dict:
    """Unit physical coordinates (s, p) -> {friction (s,), load (s, n), stiffness (s,), damping (s,)}."""
    u, s = case.unknowns, len(P)
    out = {"friction": np.full(s, u.friction[0]), "load": np.full((s, case.n), u.load[0]),
           "stiffness": np.full(s, u.stiffness[0]), "damping": np.full(s, u.damping[0])}
    for k, (nm, i, lo, hi) in enumerate(phys_coords(case)):
        x = lo + (hi - lo) * P[:, k]
        if i is None:
            out[nm] = x
        else:
            out[nm][:, i] = x
    return out


def _targets(model, n: int) -> dict:
    """Where the physical unknowns live in the model: the road's friction geoms, each vehicle's
    sprung body, the vehicles' body-contact geoms."""
    names = [model.geom(g).name for g in range(model.ngeom)]
    road = [g for g, nm in enumerate(names) if nm == "ground" or nm.startswith(("curb", "barrier"))]
    bodies = [model.body(scene_mod.vehicle_prefix(i)).id for i in range(n)]
    contact = [g for g in range(model.ngeom) if model.geom_contype[g] & BIT_BODY and model.geom_bodyid[g] in bodies
               and model.geom_solref[g, 0] > 0]
    return {"road": np.array(road, int), "bodies": np.array(bodies, int), "contact": np.array(contact, int)}


class _Track:
    """The batch runner with every vehicle's planar position and speed recorded per period."""

    def __init__(self, stepper, L):
        self.stepper, self.L = stepper, L
        self.batch = stepper.batch
        self.pos = self.speed = np.zeros(0)

    def run(self, qpos0, qvel0, nstep, *, period, controller, observer=None):
        s, n = len(qpos0), self.L.n
        periods = -(-int(nstep) // int(period))
        self.pos = np.full((s, periods, n, 2), np.nan)
        self.speed = np.full((s, periods, n), np.nan)
        pxy = self.L.qpos[:, None] + np.arange(2)
        vxy = self.L.qvel[:, None] + np.arange(2)

        def ctl(v):
            k = v.step // period
            self.pos[:, k] = v.qpos[:, pxy]
            self.speed[:, k] = np.hypot(v.qvel[:, vxy][..., 0], v.qvel[:, vxy][..., 1])
            return controller(v)

        return self.stepper.run(qpos0, qvel0, nstep, period=period, controller=ctl, observer=observer)

    def close(self) -> None:
        self.stepper.close()


class PhysRunner(CrashRunner):
    """A :class:`CrashRunner` of a case whose simulations each take their own physical unknowns
    (``run(intents, phys)``) and whose rollouts keep each vehicle's track (see the module docstring)."""

    def __init__(self, case: ev_mod.Case, *, jobs: int = 1, batch: int = BATCH):
        super().__init__(case.script, jobs=jobs, batch=batch)
        self.case = case
        self.stepper = _Track(self.stepper, self.L)  # type: ignore[assignment]
        self.at = _targets(self.model, case.n)
        m = self.model
        self.mass0 = m.body_mass[self.at["bodies"]].copy()
        self.inertia0 = m.body_inertia[self.at["bodies"]].copy()
        self.solref0 = m.geom_solref[self.at["contact"]].copy()
        self._phys: dict = {}

    def run_phys(self, intents: np.ndarray, phys: dict) -> tuple[CrashRollouts, dict]:
        """Rollouts of ``intents`` (s, n, len(INTENT)) with the physical unknowns ``phys``
        (:func:`_phys_values`' arrays of length s): (the rollouts, the tracks: ``pos`` (s,
        periods, n, 2), ``speed`` (s, periods, n), ``locked`` (s, periods, n))."""
        intents = np.asarray(intents, float).reshape(-1, self.script.n, len(drv.INTENT))
        parts, tracks = [], []
        for k in range(0, len(intents), self.size):
            self._set({key: v[k:k + self.size] for key, v in phys.items()})
            r = self._batch(intents[k:k + self.size])
            parts.append(r)
            brakes = r.controls[:, :, self.L.ctrl[:, 4:8]]  # (s, periods, n, 4)
            st: Any = self.stepper
            tracks.append({"pos": st.pos, "speed": st.speed,
                           "locked": (brakes >= 0.999).all(axis=-1)})
        rolls = CrashRollouts(outcomes=[o for p in parts for o in p.outcomes],
                              min_dist=np.concatenate([p.min_dist for p in parts]),
                              qpos0=np.concatenate([p.qpos0 for p in parts]),
                              qvel0=np.concatenate([p.qvel0 for p in parts]),
                              controls=np.concatenate([p.controls for p in parts]),
                              final_qpos=np.concatenate([p.final_qpos for p in parts]))
        track: dict[str, Any] = {key: np.concatenate([t[key] for t in tracks]) for key in tracks[0]}
        track["period"] = drv.PERIOD
        return rolls, track

    def _set(self, phys: dict) -> None:
        B, at = self.stepper.batch, self.at
        s = len(phys["friction"])
        fr = B.expand("geom_friction")
        fr[:s, at["road"], 0] = phys["friction"][:, None]
        mass = self.mass0[None] + phys["load"]  # (s, n)
        bm = B.expand("body_mass")
        bm[:s, at["bodies"]] = mass
        bi = B.expand("body_inertia")
        bi[:s, at["bodies"]] = self.inertia0[None] * (mass / self.mass0[None])[..., None]
        if len(at["contact"]):
            sr = B.expand("geom_solref")
            sr[:s, at["contact"], 0] = self.solref0[None, :, 0] / np.sqrt(phys["stiffness"])[:, None]
            sr[:s, at["contact"], 1] = self.solref0[None, :, 1] * phys["damping"][:, None]
        B.set_const()


def scene_xml_of(case: ev_mod.Case, phys: dict, k: int) -> str:
    """The case's scene as MJCF text with draw ``k``'s physical unknowns written in (the crash
    written for a reconstruction runs and replays on it)."""
    s = case.script
    spec = scene_mod.build_spec(s.road, scene_vehicles(s), timestep=s.timestep, name=s.name)
    model = spec.compile()
    at = _targets(model, case.n)
    for g in at["road"]:
        geom = spec.geom(model.geom(int(g)).name)
        geom.friction[0] = float(phys["friction"][k])
    for i, b in enumerate(at["bodies"]):
        body = spec.body(model.body(int(b)).name)
        f = (model.body_mass[b] + float(phys["load"][k, i])) / model.body_mass[b]
        body.mass = float(model.body_mass[b]) * f
        body.inertia = [float(x) * f for x in model.body_inertia[b]]
    for g in at["contact"]:
        geom = spec.geom(model.geom(int(g)).name)
        geom.solref = [float(model.geom_solref[g, 0]) / math.sqrt(float(phys["stiffness"][k])),
                       float(model.geom_solref[g, 1]) * float(phys["damping"][k])]
    return scene_mod.scene_xml(spec)


# --------------------------------------------------------------------------- what a rollout says

def pdof_clock(force_xy, yaw: float) -> float:
    """The principal direction of force on a vehicle as a clock direction in hours (0 < h <= 12):
    where the force comes from, in the vehicle's frame (12: from straight ahead, 3: from the
    right, 6: from behind, 9: from the left), of a world-frame force or impulse ``force_xy`` on
    the vehicle facing ``yaw`` rad."""
    fx, fy = float(force_xy[0]), float(force_xy[1])
    c, s = math.cos(yaw), math.sin(yaw)
    lx, ly = c * fx + s * fy, -s * fx + c * fy  # in the vehicle frame (x ahead, y left)
    ang = math.degrees(math.atan2(-ly, -lx))    # where it comes from, counter-clockwise from ahead
    h = (12.0 - ang / 30.0) % 12.0
    return 12.0 if h < 1e-9 or h > 12.0 - 1e-9 else h


def _quantities(case: ev_mod.Case, o, track: dict, s: int, mass: np.ndarray) -> np.ndarray:
    """Per vehicle (impact speed m/s, delta-V m/s, PDOF h), then the first contact's closing speed (m/s)."""
    n = case.n
    q = np.full(3 * n + 1, np.nan)
    for i, vo in enumerate(o.vehicles):
        if not vo.hits or not math.isfinite(vo.impact_speed):
            continue
        first = next(c for c in o.contacts if i in c[:2])
        a, b, t = first[0], first[1], first[2]
        J = np.asarray(first[5][:2], float) * (1.0 if i == a else -1.0)  # the sensor's force is on subtree a
        q[3 * i] = vo.impact_speed
        q[3 * i + 1] = float(np.linalg.norm(first[5])) / mass[i]
        k = max(0, min(int(t / drv.PERIOD), track["pos"].shape[1] - 1))
        yaw = _yaw_before(track, s, i, k, vo)
        q[3 * i + 2] = pdof_clock(-J, yaw)
    if o.contacts:
        a, b = o.contacts[0][:2]
        va, vb = o.vehicles[a], o.vehicles[b]
        if math.isfinite(va.impact_speed) and math.isfinite(vb.impact_speed):
            ua = va.impact_speed * np.array([math.cos(va.impact_heading), math.sin(va.impact_heading)])
            ub = vb.impact_speed * np.array([math.cos(vb.impact_heading), math.sin(vb.impact_heading)])
            q[3 * n] = float(np.linalg.norm(ua - ub))
    return q


def _yaw_before(track: dict, s: int, i: int, k: int, vo) -> float:
    """The vehicle's heading just before the impact: its direction of travel when moving (> 1 m/s),
    else the direction of its last metre of track."""
    if vo.impact_speed > 1.0:
        return vo.impact_heading
    p = track["pos"][s, : k + 1, i]
    d = p[-1] - p[0]
    return math.atan2(d[1], d[0]) if float(np.hypot(*d)) > 0.05 else vo.impact_heading




# --------------------------------------------------------------------------- the momentum screen

def slide_speed(distance: float, mu: float) -> float:
    """The speed (m/s) that a slide on locked wheels over ``distance`` (m) at friction ``mu``
    takes off: sqrt(2 mu g d)."""
    return math.sqrt(2.0 * mu * G * max(distance, 0.0))


def momentum_speeds(mass, impact, approach, rest, mu: float) -> np.ndarray:
    """Pre-impact speeds (m/s) of two vehicles from the conservation of linear momentum through
    the impact: each leaves its impact position ``impact[i]`` (x, y) towards its rest position
    ``rest[i]`` at :func:`slide_speed` of that distance, and came in along the unit ``approach[i]``;
    m_A v_A e_A + m_B v_B e_B = m_A u_A + m_B u_B, solved for (v_A, v_B) (least squares when the
    approaches are parallel: then only the total momentum is known, not its split)."""
    mass = np.asarray(mass, float)
    post = np.zeros(2)
    for i in range(2):
        d = np.asarray(rest[i][:2], float) - np.asarray(impact[i][:2], float)
        n = float(np.hypot(*d))
        if n > 1e-9:
            post = post + mass[i] * slide_speed(n, mu) * d / n
    A = np.column_stack([mass[0] * np.asarray(approach[0], float), mass[1] * np.asarray(approach[1], float)])
    return np.linalg.lstsq(A, post, rcond=None)[0]


def momentum_applies(case: ev_mod.Case) -> bool:
    """Whether the momentum screen applies: two vehicles that hit each other, each with a rest
    position and an impact position as evidence."""
    s = case.script
    return s.n == 2 and all(v.fate.hits == (1 - i,) and v.fate.rest is not None and v.fate.impact_at is not None
                            for i, v in enumerate(s.vehicles))


def _approaches(case: ev_mod.Case) -> list:
    out = []
    for v in case.script.vehicles:
        d = np.array(v.fate.impact_at[:2]) - [v.x, v.y]
        out.append(d / max(float(np.hypot(*d)), 1e-9))
    return out


def momentum_screen(case: ev_mod.Case, rng: np.random.Generator, n: int = SCREEN_SAMPLES) -> dict | None:
    """The classic reconstructionist's Monte Carlo (Brach and Brach's uncertainty chapter) over
    the case's ranges: ``n`` draws of friction and loads (uniform in their ranges) and of the
    impact and rest positions (uniform within their tolerances), each through
    :func:`momentum_speeds` along the approach from the start to the impact position.

    Args:
        case: an :class:`.evidence.Case` for which :func:`momentum_applies`.
        rng: the random numbers.
        n: draws.

    Returns:
        None when the screen does not apply; else {"speeds": (n, 2) m/s, "degenerate": bool
        (the approaches within :data:`PARALLEL_DEG` of parallel: the momentum balance gives the
        total, not the split), "angle_deg": the angle between the approaches}.
    """
    if not momentum_applies(case):
        return None
    vs = case.script.vehicles
    app = _approaches(case)
    ang = math.degrees(math.acos(max(-1.0, min(1.0, float(np.dot(app[0], app[1]))))))
    base = np.array([v.vtype.mass for v in vs])
    u = case.unknowns
    out = np.zeros((n, 2))

    def disc(p):
        r, a = p[2] * math.sqrt(float(rng.random())), 2 * math.pi * float(rng.random())
        return (p[0] + r * math.cos(a), p[1] + r * math.sin(a))

    for k in range(n):
        mu = float(rng.uniform(*u.friction))
        mass = base + rng.uniform(u.load[0], u.load[1], size=2)
        imp = [disc(v.fate.impact_at) for v in vs]
        rest = [disc(v.fate.rest) for v in vs]
        out[k] = momentum_speeds(mass, imp, app, rest, mu)
    return {"speeds": out, "degenerate": bool(min(ang, 180.0 - ang) < PARALLEL_DEG), "angle_deg": ang}


# --------------------------------------------------------------------------- one batch, judged

@dataclass
class _Told:
    """What the reconstruction keeps of one rollout."""

    u: np.ndarray
    phys: dict          # this rollout's unknowns (scalars; load (n,))
    dist: np.ndarray    # distances to the stated evidence (tolerance units)
    q: np.ndarray       # (3 n + 1,) impact speed, delta-V, PDOF per vehicle; closing speed
    o: object = field(default=None, repr=False)  # its Outcome


class _Problem:
    """The case, its runner and the rollouts told so far."""

    def __init__(self, case: ev_mod.Case, R: PhysRunner, budget: int, callback):
        self.case, self.R, self.budget, self.callback = case, R, int(budget), callback
        self.S = space_of(case.script)
        self.ps = ev_mod.pieces(case)
        self.hit_rows = [k for k, p in enumerate(self.ps) if p.kind == "hits"]
        self.crush = sorted({int(p.vehicle) for p in self.ps if p.kind == "crush" and p.vehicle is not None})
        self.used = 0
        self.accepted = 0
        self.best: float = math.inf

    def run(self, U: np.ndarray, phys: dict, targets: list) -> list:
        """Roll out unit points U (s, dim) with per-row unknowns ``phys`` and per-row evidence
        ``targets`` (lists of pieces); per row (told, distances to its targets)."""
        U = np.clip(np.atleast_2d(U), 0.0, 1.0)
        rolls, track = self.R.run_phys(self.S.intents(U), phys)
        self.used += len(U)
        mass = self.R.L.mass[None] + phys["load"]
        out = []
        if self.crush:
            for k, o in enumerate(rolls.outcomes):
                for i in self.crush:
                    res = crush_mod.crush_residual(self.R.model, scene_mod.vehicle_prefix(i),
                                                     self.case.script.vehicles[i].vtype, rolls.final_qpos[k])
                    o.vehicles[i].residual_crush = max(res.values()) if res else math.nan  # type: ignore[attr-defined]
        for k, o in enumerate(rolls.outcomes):
            md = rolls.min_dist[k]
            d0 = ev_mod.distances(self.case, self.ps, o, track, k, md)
            dt = d0 if targets[k] is self.ps else ev_mod.distances(self.case, targets[k], o, track, k, md)
            q = _quantities(self.case, o, track, k, mass[k])
            out.append((_Told(u=U[k].copy(), phys={key: np.array(v[k]) for key, v in phys.items()}, dist=d0, q=q, o=o), dt))
            self.best = min(self.best, float(np.max(d0)) if len(d0) else 0.0)
        if self.callback:
            self.callback(Progress(self.used, self.best, self.accepted))
        return out

    def score(self, d: np.ndarray, done_at: float) -> tuple[int, int, float]:
        """(signature, distance, cost) for the engine: signature 1 when every contact is as the
        evidence says; distance 0 within ``done_at`` of every target, 1 with the contacts
        right, 2 without; cost the sum of squared distances."""
        hits_ok = bool(all(float(d[k]) == 0.0 for k in self.hit_rows))
        m = float(np.max(d)) if len(d) else 0.0
        return int(hits_ok), (0 if m <= done_at else (1 if hits_ok else 2)), float(np.sum(d ** 2))


def _phys_mid(case: ev_mod.Case, s: int) -> dict:
    return _phys_values(case, np.full((s, len(phys_coords(case))), 0.5))


def _stack(ph: list) -> dict:
    return {key: np.stack([p[key] for p in ph]) for key in ph[0]}


def _fit(P: _Problem, engines: list, max_rollouts: int) -> None:
    """Run ``engines`` (each a dict: ``eng``, ``phys`` (one row's unknowns), ``targets``,
    ``done_at``, ``told`` list) together, their asks in shared batches, until each stops or the
    reconstruction's budget ends."""
    active = list(engines)
    while active and P.used < max_rollouts:
        rows: list[np.ndarray] = []
        owners: list[dict] = []
        for e in active:
            U = e["eng"].ask()
            U = U[:max(0, max_rollouts - P.used - sum(len(r) for r in rows))]
            rows.append(U)
            owners.append(e)
        if not sum(len(r) for r in rows):
            break
        width = max(r.shape[1] for r in rows)
        U_all = np.concatenate([np.pad(r, ((0, 0), (0, width - r.shape[1])), constant_values=0.5)
                                for r in rows if len(r)])
        at = 0
        for e, r in zip(owners, rows):
            for kf, val in e.get("fix", {}).items():  # a profile: this coordinate held
                U_all[at:at + len(r), kf] = val
            at += len(r)
        rows_phys = []
        for e, r in zip(owners, rows):
            if e.get("joint") is not None:  # the pilot's joint fit: the unknowns are coordinates too
                ph = _phys_values(P.case, r[:, P.S.dim:]) if len(r) else {}
                rows_phys += [{key: v[j] for key, v in ph.items()} for j in range(len(r))]
            else:
                rows_phys += [e["phys"]] * len(r)
        phys = _stack(rows_phys)
        targets = [e["targets"] for e, r in zip(owners, rows) for _ in range(len(r))]
        told = P.run(U_all[:, :P.S.dim], phys, targets)
        k = 0
        for e, r in zip(owners, rows):
            if not len(r):
                continue
            part = told[k:k + len(r)]
            k += len(r)
            sc = [P.score(dt, e["done_at"]) for _, dt in part]
            e["eng"].tell(r, [s[0] for s in sc], [s[1] for s in sc], [s[2] for s in sc],
                          payloads=[t for t, _ in part])
            e["told"] += [(t, s[2]) for (t, _), s in zip(part, sc)]
        active = [e for e in active if not e["eng"].stop()]


def _engine(dim: int, rng, budget: int, start, *, sigma: float, explore: int, spread: float,
            uniform: int = 0):
    """An engine for one fit: ``explore`` points first (the start, then Gaussian steps of
    ``spread`` about it, the last ``uniform`` of them uniform in the cube), then CMA-ES from the
    best at ``sigma``."""
    from nbst.models.mjsearch.engine import Engine

    count = [0]

    def init(e):
        j = count[0]
        count[0] += 1
        if start is None or j >= explore - uniform:
            return e.rng.random(dim)
        if j == 0:
            return np.asarray(start, float)
        return np.asarray(start, float) + spread * e.rng.standard_normal(dim)

    return Engine(dim, seed=rng, max_rollouts=max(1, int(budget)), batch=min(BATCH, explore), explore=explore,
                  init=init, ga_batches=0, cma=True, popsize=POPSIZE, sigma0=sigma, stall=STALL,
                  schedule=(("best", 1.0), ("best", 1.0 / 3.0)))


# --------------------------------------------------------------------------- the reconstruction

@dataclass
class Progress:
    """After each batch: rollouts so far, the least largest distance to the stated evidence
    (1: every piece within its tolerance), the draws accepted so far."""

    rollouts: int
    best: float
    accepted: int


@dataclass
class Reconstruction:
    """What a reconstruction found (the module docstring)."""

    names: list
    labels: list                 # the evidence's pieces
    draws: list                  # per OMC draw: its _Told (the fit) or None, in draw order
    accepted: list               # the accepted draws' _Told
    prior_q: np.ndarray          # quantities of the pilot's exploring rollouts that hit as the evidence says
    speed_prior: list            # per vehicle (lo, hi) m/s: the driver's speed range
    screen: dict | None          # the momentum screen (momentum_screen), or None
    rollouts: int
    pilot_rollouts: int
    seed: int
    intervals: list = field(default_factory=list)  # per vehicle {quantity: {...}}
    closing: dict = field(default_factory=dict)
    verdicts: list = field(default_factory=list)
    not_identifiable: list = field(default_factory=list)
    profile: dict = field(default_factory=dict)  # vehicle index -> impact speeds (m/s) of probe fits that met the evidence
    moves: list = field(default_factory=list)    # per draw linearised: (LOCAL_SAMPLES, 3 n + 1) quantities on its local set
    best: _Told | None = None    # the accepted draw of least squares (else the pilot's best)
    interrupted: bool = False
    method: str = METHOD

    @property
    def found(self) -> bool:
        return bool(self.accepted)

    def to_dict(self) -> dict:
        """The reconstruction as the crash file's ``reconstruction`` (km/h, o'clock; the field
        names of docs/formats.md)."""
        kmh = 3.6
        n = len(self.names)
        b = self.best.q if self.best is not None else np.full(3 * n + 1, np.nan)

        def iv(x, scale, est, k=2):
            if not x:
                return None
            out = {key: (round(float(x[key]) * scale, k) if np.isfinite(x[key]) else None)
                   for key in ("lo", "median", "hi", "prior_lo", "prior_hi") if key in x}
            out["estimate"] = None if not np.isfinite(est) else round(float(est) * scale, k)
            if "identifiable" in x:
                out["identifiable"] = bool(x["identifiable"])
            return out

        vs = []
        for i, (nm, x) in enumerate(zip(self.names, self.intervals)):
            vs.append({"name": nm, "impact_speed_kmh": iv(x.get("impact_speed"), kmh, b[3 * i]),
                       "delta_v_kmh": iv(x.get("delta_v"), kmh, b[3 * i + 1]),
                       "pdof_clock": iv(x.get("pdof"), 1.0, b[3 * i + 2], 1),
                       "impact_speed_m_s": iv(x.get("impact_speed"), 1.0, b[3 * i], 3)})
        unk = {}
        acc = self.accepted
        for key, name in (("friction", "friction"), ("load", "load_kg"), ("stiffness", "stiffness"),
                          ("damping", "damping")):
            if not acc:
                continue
            v = np.array([np.mean(t.phys[key]) for t in acc])
            unk[name] = {"lo": round(float(np.quantile(v, (1 - LEVEL) / 2)), 3), "median": round(float(np.median(v)), 3),
                         "hi": round(float(np.quantile(v, 1 - (1 - LEVEL) / 2)), 3)}
        scr = None
        if self.screen is not None:
            sp = self.screen["speeds"] * kmh
            scr = {"degenerate": self.screen["degenerate"], "angle_deg": round(self.screen["angle_deg"], 1),
                   "vehicles": [{"name": nm, "impact_speed_kmh": {
                       "lo": round(float(np.quantile(sp[:, i], (1 - LEVEL) / 2)), 2),
                       "median": round(float(np.median(sp[:, i])), 2),
                       "hi": round(float(np.quantile(sp[:, i], 1 - (1 - LEVEL) / 2)), 2)}}
                       for i, nm in enumerate(self.names)]}
        return {"method": self.method, "level": LEVEL, "draws": len(self.draws), "accepted": len(acc),
                "fits": len(acc), "rollouts": self.rollouts, "pilot_rollouts": self.pilot_rollouts,
                "seed": self.seed, "interrupted": self.interrupted, "evidence": self.labels, "vehicles": vs,
                "closing_speed_kmh": iv(self.closing, kmh, b[3 * n]) if self.closing else None,
                "not_identifiable": list(self.not_identifiable), "verdicts": list(self.verdicts),
                "unknowns": unk, "momentum_screen": scr, "weak_threshold": WEAK, "min_accepted": MIN_ACCEPTED}


def _interval(x: np.ndarray, circular: float | None = None) -> dict:
    """{lo, median, hi}: the central LEVEL of samples ``x`` (a circular quantity of period
    ``circular`` unwrapped about its circular mean)."""
    x = x[np.isfinite(x)]
    if not len(x):
        return {}
    if circular is not None:
        ang = x / circular * 2 * math.pi
        c = math.atan2(float(np.mean(np.sin(ang))), float(np.mean(np.cos(ang)))) / (2 * math.pi) * circular
        x = c + (x - c + circular / 2) % circular - circular / 2
    a = (1 - LEVEL) / 2
    out = {"lo": float(np.quantile(x, a)), "median": float(np.median(x)), "hi": float(np.quantile(x, 1 - a))}
    if circular is not None:
        for k in out:
            h = out[k] % circular
            out[k] = circular if h < 1e-6 or h > circular - 1e-6 else h
    return out


def _judge(rec: Reconstruction) -> None:
    """The intervals over the accepted draws, each set against its prior: not identifiable
    (reported at least as wide as the prior) when it spans :data:`WEAK` of the prior's width
    or fewer than :data:`MIN_ACCEPTED` draws pin it."""
    n = len(rec.names)
    Q = np.array([t.q for t in rec.accepted]) if rec.accepted else np.zeros((0, 3 * n + 1))
    P = rec.prior_q
    few = len(Q) < MIN_ACCEPTED
    if rec.moves:
        Q = np.concatenate(rec.moves)  # the draws spread over their local sets (_local)
    if not rec.accepted:
        rec.verdicts.append("no draw met every piece of evidence within its tolerance in the budget: every interval "
                            "is the prior's (not identifiable here); a larger budget, or looser tolerances")
    elif few:
        rec.verdicts.append(f"only {len(Q)} draws met the evidence (fewer than {MIN_ACCEPTED}): every interval is "
                            "widened to its prior's")
    rec.intervals = []
    for i, nm in enumerate(rec.names):
        row: dict = {}
        for key, col, circ in (("impact_speed", 3 * i, None), ("delta_v", 3 * i + 1, None), ("pdof", 3 * i + 2, 12.0)):
            x = _interval(Q[:, col], circ) if len(Q) else {}
            pr = _interval(P[:, col], circ) if len(P) >= 8 else {}
            if key == "impact_speed":
                lo, hi = rec.speed_prior[i]
                pr = {"lo": min(pr.get("lo", lo), lo), "hi": max(pr.get("hi", hi), hi)}
            if not x and not pr:
                continue
            has = "lo" in x
            if key == "pdof" or not pr:
                if has:
                    x["identifiable"] = not few
                    row[key] = x
                continue
            x["prior_lo"], x["prior_hi"] = pr["lo"], pr["hi"]
            wide = has and (x["hi"] - x["lo"]) >= WEAK * max(pr["hi"] - pr["lo"], 1e-9)
            if key == "impact_speed" and rec.profile.get(i):
                wide = True
                v = rec.profile[i]
                rec.verdicts.append(f"profile: fits with {nm}'s speed held at {3.6 * min(v):.0f}-{3.6 * max(v):.0f} "
                                    "km/h meet the evidence too")
            ok = has and not few and not wide
            if ok and key == "impact_speed":  # the truth at the driver's range's end: the interval reaches it
                lo, hi = rec.speed_prior[i]
                if lo < x["lo"] <= lo + EDGE * (hi - lo):
                    x["lo"] = lo
                if hi - EDGE * (hi - lo) <= x["hi"] < hi:
                    x["hi"] = hi
            if not ok:
                if not has:
                    x["median"] = math.nan
                x["lo"], x["hi"] = min(x.get("lo", pr["lo"]), pr["lo"]), max(x.get("hi", pr["hi"]), pr["hi"])
                rec.not_identifiable.append(f"{nm}.{key}")
            x["identifiable"] = ok
            row[key] = x
        rec.intervals.append(row)
    cs = Q[:, -1] if len(Q) else np.zeros(0)
    rec.closing = _interval(cs) if len(cs) else {}
    if rec.closing:
        pc = P[:, -1][np.isfinite(P[:, -1])] if len(P) else np.zeros(0)
        if len(pc) >= 8:
            plo, phi = float(np.quantile(pc, 0.05)), float(np.quantile(pc, 0.95))
            wide = rec.closing["hi"] - rec.closing["lo"] >= WEAK * max(phi - plo, 1e-9)
            rec.closing["identifiable"] = not (wide or few)
            if wide or few:
                rec.closing["lo"], rec.closing["hi"] = min(rec.closing["lo"], plo), max(rec.closing["hi"], phi)
                rec.not_identifiable.append("closing_speed")
    if n == 2 and not few and any(x.endswith(".impact_speed") for x in rec.not_identifiable):
        _propagate(rec, Q)
    weak = [x for x in rec.not_identifiable if x.endswith("impact_speed") or x == "closing_speed"]
    if weak and rec.accepted and not few:
        why = (f"the accepted fits spread over at least {100 * WEAK:.0f} % of the prior's range, or a profile fit "
               "away from them meets the evidence too: the evidence given does not pin it; reported at least as wide "
               "as the prior")
        if rec.screen is not None and rec.screen["degenerate"]:
            why += (f" (the approaches are {rec.screen['angle_deg']:.0f} deg apart: momentum through the impact gives "
                    "the total, not the split)")
        rec.verdicts.append(f"not identifiable: {', '.join(weak)}: {why}")


def _propagate(rec: Reconstruction, Q: np.ndarray) -> None:
    """Two vehicles, a speed not identifiable: the closing speed and each delta-V are functions of
    the speeds (delta-V_i = r_i times the closing speed, r_i set by the masses and the
    restitution), so they are not identifiable either: the closing speed's interval becomes the
    range of |v_A e_A - v_B e_B| over the speeds' (widened) intervals along the accepted draws'
    median directions of travel, and each delta-V's the range of r_i (over the accepted draws)
    times it, each joined with the accepted draws' own interval."""
    heads = []
    for i in range(2):
        h = np.array([t.o.vehicles[i].impact_heading for t in rec.accepted if t.o is not None])
        h = h[np.isfinite(h)]
        heads.append(math.atan2(float(np.mean(np.sin(h))), float(np.mean(np.cos(h)))) if len(h) else 0.0)
    e = [np.array([math.cos(h), math.sin(h)]) for h in heads]
    sa, sb = rec.intervals[0].get("impact_speed"), rec.intervals[1].get("impact_speed")
    if not sa or not sb:
        return
    grid = [abs(float(np.linalg.norm(va * e[0] - vb * e[1])))
            for va in np.linspace(sa["lo"], sa["hi"], 17) for vb in np.linspace(sb["lo"], sb["hi"], 17)]
    c_lo, c_hi = min(grid), max(grid)
    cl = rec.closing or {}
    rec.closing = {"lo": min(cl.get("lo", c_lo), c_lo), "median": cl.get("median", math.nan),
                   "hi": max(cl.get("hi", c_hi), c_hi), "identifiable": False}
    if "closing_speed" not in rec.not_identifiable:
        rec.not_identifiable.append("closing_speed")
    for i, nm in enumerate(rec.names):
        dv = rec.intervals[i].get("delta_v")
        ok = np.isfinite(Q[:, 3 * i + 1]) & np.isfinite(Q[:, -1]) & (Q[:, -1] > 0.1)
        if not dv or not ok.any():
            continue
        r = Q[ok, 3 * i + 1] / Q[ok, -1]
        dv["lo"] = min(dv["lo"], float(r.min()) * rec.closing["lo"])
        dv["hi"] = max(dv["hi"], float(r.max()) * rec.closing["hi"])
        dv["identifiable"] = False
        if f"{nm}.delta_v" not in rec.not_identifiable:
            rec.not_identifiable.append(f"{nm}.delta_v")


def reconstruct(case, *, seed: int, max_rollouts: int = MAX_ROLLOUTS, draws: int = DRAWS,
                runner: PhysRunner | None = None, jobs: int = 1,
                callback: Callable[[Progress], object] | None = None) -> Reconstruction:
    """Reconstruct ``case`` by Optimisation Monte Carlo (the module docstring).

    Args:
        case: an :class:`.evidence.Case`, or a crash script whose fates are the evidence (its
            unknowns take the defaults of :mod:`.evidence`).
        seed: an integer in [0, 2^63-1]; the same seed gives the same draws whatever ``jobs``.
        max_rollouts: the rollout budget: the pilot takes up to :data:`PILOT_SHARE` of it, the
            draws the rest (each up to :data:`DRAW_ROLLOUTS`).
        draws: OMC draws (each nuisance and evidence-error draw fitted once).
        runner: a :class:`PhysRunner` of this case to reuse, or None: one is made with ``jobs``
            threads and closed at the end.
        jobs: threads of the runner made here.
        callback: None, or called with a :class:`Progress` after each batch.

    Returns:
        A :class:`Reconstruction`: the accepted draws, per vehicle the 90 % intervals of impact
        speed, delta-V (m/s) and PDOF (o'clock) with their identifiability, the verdicts, the
        momentum screen, the draw of least squares (``best``); ``interrupted`` after Ctrl-C.

    Raises:
        InputError: ``seed`` is not an integer in [0, 2^63-1], ``max_rollouts`` or ``draws``
            under 1.
        MujocoError: a rollout diverged (a non-finite state).
    """
    if not isinstance(case, ev_mod.Case):
        case = ev_mod.case_from_dict(case.raw, source=case.source)
    seed = check_seed(seed, what="seed")
    if isinstance(max_rollouts, bool) or int(max_rollouts) < 1:
        raise InputError(f"max_rollouts {max_rollouts}: at least 1")
    if int(draws) < 1:
        raise InputError(f"draws {draws}: at least 1")
    max_rollouts = int(max_rollouts)
    own = runner is None
    R = runner if runner is not None else PhysRunner(case, jobs=jobs)
    P = _Problem(case, R, max_rollouts, callback)
    S = P.S
    rng = np.random.default_rng([seed, 47])
    screen = momentum_screen(case, np.random.default_rng([seed, 48]))
    speed_prior = [(v.speed.lo, v.speed.hi) for v in case.script.vehicles]
    mid = {key: v[0] for key, v in _phys_mid(case, 1).items()}
    pilot_budget = max(min(2 * BATCH, max_rollouts), int(PILOT_SHARE * max_rollouts))
    interrupted = False
    pilot_told: list = []
    explore_q: list = []
    out_draws: list = []
    accepted: list = []
    profile: dict = {}
    moves: list = []
    try:
        start = None
        if screen is not None and not screen["degenerate"] and S.dim:  # stage A: the approach at momentum speeds
            vs = case.script.vehicles
            mass = np.array([v.vtype.mass for v in vs]) + mid["load"]
            mu = float(mid["friction"])
            ev_rest = [v.fate.rest for v in vs]
            hi_speed = max(v.speed.hi for v in vs) * 1.5
            target = np.clip(np.median(screen["speeds"], axis=0), 0.5, hi_speed)
            for rnd in range(ROUNDS):
                speeds = [ev_mod.Piece(f"{nm}.impact_speed", i, "impact_speed", (float(target[i]),), SCREEN_SPEED_TOL,
                                       False) for i, nm in enumerate(case.script.names())]
                tA = [p for p in P.ps if p.kind in ("hits", "impact_at")] + speeds
                share = PILOT_APPROACH * pilot_budget * (0.5 if rnd == 0 else 0.5 / (ROUNDS - 1))
                eA = {"eng": _engine(S.dim, rng, int(share), start, sigma=SIGMA_PILOT if start is None else SIGMA_FIT,
                                     explore=EXPLORE if start is None else BATCH // 2, spread=SIGMA_FIT,
                                     uniform=EXPLORE if start is None else 0),
                      "phys": mid, "targets": tA, "done_at": DRAW_DONE, "told": []}
                _fit(P, [eA], P.used + int(share))
                pilot_told += eA["told"]
                if not eA["told"]:
                    break
                t = eA["eng"].result.payload
                start = t.u
                vo = t.o.vehicles
                if not all(math.isfinite(v.impact_speed) for v in vo):
                    continue
                imp = [v.impact_pos for v in vo]
                app = [np.array([math.cos(v.impact_heading), math.sin(v.impact_heading)]) for v in vo]
                sim = np.array([v.impact_speed for v in vo])
                corr = (momentum_speeds(mass, imp, app, ev_rest, mu)
                        - momentum_speeds(mass, imp, app, [v.rest for v in vo], mu))
                target = np.clip(sim + GAIN * corr, 0.5, hi_speed)
        npc = len(phys_coords(case))  # the whole evidence: intents and unknowns fitted together
        startB = None if start is None else np.concatenate([start, np.full(npc, 0.5)])
        eB = {"eng": _engine(S.dim + npc, rng, pilot_budget - P.used, startB,
                             sigma=SIGMA_PILOT if start is None else SIGMA_FIT,
                             explore=EXPLORE if start is None else BATCH, spread=SIGMA_FIT,
                             uniform=EXPLORE if start is None else 0),
              "phys": mid, "targets": P.ps, "done_at": PILOT_DONE, "told": [], "joint": npc}
        _fit(P, [eB], pilot_budget)
        pilot_told += eB["told"]
        if os.environ.get("NBST_RECON_DEBUG"):
            print("pilot", P.used, min(float(np.max(t.dist)) for t, _ in pilot_told), file=sys.stderr)
        explore_q = [t.q for t, _ in pilot_told[:EXPLORE] if all(t.dist[k] == 0.0 for k in P.hit_rows)]
        met = [t for t, _ in pilot_told if len(t.dist) and float(np.max(t.dist)) <= 1.0]
        pilot_best = min((t for t, _ in pilot_told), key=lambda t: float(np.sum(t.dist ** 2)))
        pilot_used = P.used
        # the OMC draws, DRAW_PARALLEL at a time in shared batches
        # the budget's ends, last stage first: the profile probes, the sets' reach checks, the sets, the draws
        check_end = max_rollouts - int(PROFILE_SHARE * max_rollouts)
        local_end = check_end - int(LOCAL_CHECK_SHARE * max_rollouts)
        draw_end = local_end - int(LOCAL_SHARE * max_rollouts)
        per = max(BATCH // 2, min(DRAW_ROLLOUTS, (draw_end - P.used) // max(1, int(draws))))
        pcs = phys_coords(case)
        specs = []
        for _ in range(int(draws)):
            ph = _phys_values(case, rng.random((1, len(pcs))))
            specs.append(({key: v[0] for key, v in ph.items()}, ev_mod.jitter(P.ps, rng, JITTER)))
        k = 0
        while k < len(specs) and P.used < draw_end:
            group = []
            for ph1, tg in specs[k:k + DRAW_PARALLEL]:
                pool = met + accepted  # warm starts: the fits that met the stated evidence so far
                base = pool[int(rng.integers(len(pool)))] if pool else pilot_best
                group.append({"eng": _engine(S.dim, rng, per, _warm(case, S, base, base.phys, ph1, screen), sigma=SIGMA_DRAW,
                                             explore=BATCH // 2, spread=SIGMA_DRAW, uniform=DRAW_UNIFORM),
                              "phys": ph1, "targets": tg, "done_at": DRAW_DONE, "told": []})
            _fit(P, group, draw_end)
            for e in group:
                ok = [(t, c) for t, c in e["told"] if float(np.max(t.dist)) <= 1.0]
                t = min(ok, key=lambda x: x[1])[0] if ok else None
                out_draws.append(t)
                if t is not None:
                    accepted.append(t)
            P.accepted = len(accepted)
            k += DRAW_PARALLEL
        moves = _local(P, S, accepted, rng, local_end, check_end)
        profile = _profile(P, S, accepted, rng, max_rollouts)
    except KeyboardInterrupt:
        interrupted = True
        if not pilot_told:
            raise
        pilot_used = locals().get("pilot_used", P.used)
        pilot_best = locals().get("pilot_best", min((t for t, _ in pilot_told), key=lambda t: float(np.sum(t.dist ** 2))))
    finally:
        if own:
            R.close()
    rec = Reconstruction(names=case.script.names(), labels=ev_mod.labels(case), draws=out_draws, accepted=accepted,
                         prior_q=np.array(explore_q) if explore_q else np.zeros((0, 3 * case.n + 1)),
                         speed_prior=speed_prior, screen=screen, rollouts=P.used, pilot_rollouts=pilot_used,
                         seed=int(seed), interrupted=interrupted, profile=profile, moves=moves)
    rec.best = min(accepted, key=lambda t: float(np.sum(t.dist ** 2))) if accepted else pilot_best
    _judge(rec)
    return rec


def _phys_unit(case: ev_mod.Case, phys: dict) -> np.ndarray:
    """One rollout's unknowns (``_Told.phys``) as unit coordinates of :func:`phys_coords`."""
    out = []
    for nm, i, lo, hi in phys_coords(case):
        v = np.atleast_1d(phys[nm])
        out.append((float(v[0] if i is None else v[i]) - lo) / (hi - lo))
    return np.array(out)


def _run_points(P: _Problem, X: np.ndarray, dim: int) -> list:
    """Roll out points of the intents' cube and the unknowns' (X (s, dim + unknowns), unit
    coordinates) against the stated evidence, :data:`BATCH` at a time: per row (told, distances)."""
    phys = _phys_values(P.case, X[:, dim:])
    told: list = []
    for j in range(0, len(X), BATCH):
        told += P.run(X[j:j + BATCH, :dim], {key: v[j:j + BATCH] for key, v in phys.items()},
                      [P.ps] * len(X[j:j + BATCH]))
    return told


def _local(P: _Problem, S, accepted: list, rng, end: int, check_end: int | None = None) -> list:
    """The local sets (:data:`LOCAL_SHARE`): up to :data:`LOCAL_DRAWS` accepted draws (evenly
    spread in draw order), each linearised by forward differences of :data:`LOCAL_STEP` in every
    coordinate of the intents and of the unknowns (:func:`phys_coords`, as unit coordinates of
    their ranges), one rollout each, the draws' in shared batches: the evidence's signed
    residuals (:func:`residual`) and the quantities (impact speed, delta-V, PDOF, closing speed)
    as linear functions about the draw. In that model the set of intents and unknowns that meets
    every piece of the stated evidence within its tolerance (within the ranges, the intents within
    :data:`LOCAL_TRUST` of the draw) is convex; :data:`LOCAL_SAMPLES` points of a hit-and-run
    chain on it (R. L. Smith, Operations Research 32, 1984: a random direction, a uniform point on
    the chord; uniform on the set in the limit), after :data:`LOCAL_BURN`, give their quantities.
    A coordinate whose step changes whom the vehicles hit is held.

    With a uniform kernel (met or not) and uniform priors, the posterior near a draw is uniform on
    that set. The fits stop where they first meet the evidence, bunched at one end of it, and a
    few draws sample the unknowns' ranges thinly; the sets spread both (the finite differences of
    W. Bartlett and A. Fonda, SAE 2003-01-0489; Meeds and Welling's Jacobian about each optimum).

    Returns:
        [(LOCAL_SAMPLES, 3 n + 1) quantities] per draw linearised (empty: none)."""
    case = P.case
    check_end = end if check_end is None else check_end
    dim, npc = S.dim, len(phys_coords(case))
    nd = dim + npc
    room = max(0, end - P.used)
    m = min(len(accepted), LOCAL_DRAWS, room // max(nd, 1))
    if m < 1 or nd < 1:
        return []
    pick = sorted({int(round(x)) for x in np.linspace(0, len(accepted) - 1, m)})
    base = [accepted[a] for a in pick]
    x0s = [np.concatenate([t.u, _phys_unit(case, t.phys)]) for t in base]
    steps = [np.where(x0 + LOCAL_STEP <= 1.0, LOCAL_STEP, -LOCAL_STEP) for x0 in x0s]
    X = np.array([x0 + np.eye(nd)[k] * h[k] for x0, h in zip(x0s, steps) for k in range(nd)])
    told = _run_points(P, X, dim)
    models = []
    for a, (t, x0, h) in enumerate(zip(base, x0s, steps)):
        r0, kinds = residual(P.ps, t.o, t.dist)
        J = np.zeros((len(r0), nd))
        Jq = np.zeros((len(t.q), nd))
        free = np.ones(nd, bool)
        for k in range(nd):
            tk = told[a * nd + k][0]
            rk, kk = residual(P.ps, tk.o, tk.dist)
            if (any(float(tk.dist[j]) != 0.0 for j in P.hit_rows) or [x[0] for x in kk] != [x[0] for x in kinds]
                    or not np.all(np.isfinite(rk))):
                free[k] = False
                continue
            J[:, k] = (rk - r0) / h[k]
            dq = tk.q - t.q
            for c in range(2, len(dq) - 1, 3):  # a PDOF: the nearer way round the clock
                dq[c] = (dq[c] + 6.0) % 12.0 - 6.0
            Jq[:, k] = np.where(np.isfinite(dq), dq, 0.0) / h[k]
        models.append({"q": t.q, "x0": x0, "dim": dim, "r0": r0, "kinds": kinds, "J": J, "Jq": Jq, "free": free,
                       "trust": LOCAL_TRUST})
    sets = [sample_set(m, rng) for m in models]
    for _ in range(LOCAL_GROW):  # the reach: a set its trust region bounds grows where its ends meet the evidence
        grow = {}
        for a, (m, (_, _, bound)) in enumerate(zip(models, sets)):
            if bound:
                g = cut(sample_set({**m, "trust": min(1.0, 2.0 * m["trust"])}, rng), m.get("cuts", []))
                if len(g[1]) >= LOCAL_SAMPLES // 4:
                    grow[a] = g
        checks = []  # (draw, quantity column, side, point)
        for a, (X, q, _) in grow.items():
            for c in range(0, q.shape[1] - 1, 3):
                for side, f in ((-1, np.argmin), (1, np.argmax)):
                    checks.append((a, c, side, models[a]["x0"] + X[int(f(q[:, c]))]))
        if not checks or len(checks) > check_end - P.used:
            break
        told = _run_points(P, np.clip(np.array([x for *_, x in checks]), 0.0, 1.0), dim)
        cuts: dict = {a: [] for a in grow}
        confirmed: dict = {a: False for a in grow}
        for (a, c, side, _), (tc, _) in zip(checks, told):
            if bool(len(tc.dist)) and float(np.max(tc.dist)) <= 1.0:
                confirmed[a] = True
            else:  # this end does not meet the evidence: the quantity keeps its former reach on that side
                old = sets[a][1][:, c]
                cuts[a].append((c, side, float(old.min() if side < 0 else old.max())))
        if os.environ.get("NBST_RECON_DEBUG"):
            print("reach", [(a, c, side, models[a]["trust"], round(float(np.max(tc.dist)), 2))
                            for (a, c, side, _), (tc, _) in zip(checks, told)], file=sys.stderr)
        for a, g in grow.items():
            g = cut(g, cuts[a])
            if confirmed[a] and len(g[1]) >= LOCAL_SAMPLES // 4:
                models[a]["trust"] = min(1.0, 2.0 * models[a]["trust"])
                models[a]["cuts"] = models[a].get("cuts", []) + cuts[a]
                sets[a] = g
            else:  # the linear model does not hold that far: the set keeps its reach
                sets[a] = (sets[a][0], sets[a][1], False)
    return [q for _, q, _ in sets]


def _profile(P: _Problem, S, accepted: list, rng, max_rollouts: int) -> dict:
    """The profile probes (:data:`PROFILE_ROLLOUTS`): for each vehicle's speed coordinate, fits
    with the speed held halfway between the accepted draws' lowest (highest) and the range's end,
    from the accepted draw of least squares at its unknowns, the other vehicles' speeds scaled
    in proportion at the start; {vehicle: [impact speeds (m/s) of
    probe rollouts that met the stated evidence]} (empty: the speed held wherever probed)."""
    if len(accepted) < 2:
        return {}
    best = min(accepted, key=lambda t: float(np.sum(t.dist ** 2)))
    probes = []
    for k, (i, f, r) in enumerate(S.coords):
        if f != drv.IX["speed"] or not isinstance(r, Range) or r.hi <= r.lo:
            continue
        us = np.array([t.u[k] for t in accepted])
        for val, room in ((us.min() / 2, us.min() > 0.1), ((us.max() + 1) / 2, us.max() < 0.9)):
            if room:
                probes.append((i, k, float(val)))
    found: dict = {}
    for j in range(0, len(probes), DRAW_PARALLEL):
        group = []
        for i, k, val in probes[j:j + DRAW_PARALLEL]:
            u0 = best.u.copy()
            r = S.coords[k][2]
            scale = (r.lo + (r.hi - r.lo) * val) / max(r.lo + (r.hi - r.lo) * u0[k], 1e-6)
            for k2, (i2, f2, r2) in enumerate(S.coords):  # the other speeds in proportion: the ridge of equal fits
                if k2 != k and f2 == drv.IX["speed"] and isinstance(r2, Range) and r2.hi > r2.lo:
                    u0[k2] = np.clip(((r2.lo + (r2.hi - r2.lo) * u0[k2]) * scale - r2.lo) / (r2.hi - r2.lo), 0.0, 1.0)
            u0[k] = val
            group.append({"eng": _engine(S.dim, rng, PROFILE_ROLLOUTS, u0, sigma=SIGMA_FIT, explore=BATCH // 2,
                                         spread=SIGMA_FIT, uniform=DRAW_UNIFORM),
                          "phys": best.phys, "targets": P.ps, "done_at": 1.0, "told": [], "fix": {k: val},
                          "vehicle": i})
        _fit(P, group, max_rollouts)
        for e in group:
            met = [float(t.q[3 * e["vehicle"]]) for t, _ in e["told"] if float(np.max(t.dist)) <= 1.0]
            if met:
                found.setdefault(e["vehicle"], []).extend(met)
    return found


def _warm(case, S, base: _Told, mid: dict, ph: dict, screen) -> np.ndarray:
    """A draw's warm start: ``base``'s intents with each vehicle's speed scaled by the momentum
    balance at the draw's friction and masses against the pilot's (sqrt of the friction ratio
    without the screen: a slide's speed goes as sqrt(mu))."""
    u = base.u.copy()
    ratio = np.full(case.n, math.sqrt(float(ph["friction"]) / float(mid["friction"])))
    if screen is not None and not screen["degenerate"]:
        vs = case.script.vehicles
        m0 = np.array([v.vtype.mass for v in vs])
        imp, rest, app = [v.fate.impact_at for v in vs], [v.fate.rest for v in vs], _approaches(case)
        a = momentum_speeds(m0 + mid["load"], imp, app, rest, float(mid["friction"]))
        b = momentum_speeds(m0 + ph["load"], imp, app, rest, float(ph["friction"]))
        ratio = np.where(np.abs(a) > 0.5, b / np.where(np.abs(a) > 0.5, a, 1.0), ratio)
    for k, (i, f, r) in enumerate(S.coords):
        if f == drv.IX["speed"] and isinstance(r, Range) and r.hi > r.lo:
            v = (r.lo + (r.hi - r.lo) * u[k]) * float(np.clip(ratio[i], 0.7, 1.4))
            u[k] = (v - r.lo) / (r.hi - r.lo)
    return np.clip(u, 0.0, 1.0)


def best_trial(case: ev_mod.Case, rec: Reconstruction) -> tuple[search_mod.Trial, str]:
    """The draw of least squares rolled out again on a scene that holds its unknowns: (its
    trial, the scene's MJCF text): the crash a reconstruction writes."""
    S = space_of(case.script)
    t = rec.best
    assert t is not None
    xml = scene_xml_of(case, {k: np.atleast_1d(v)[None] if np.ndim(v) else np.array([v]) for k, v in t.phys.items()}, 0)
    R = CrashRunner(case.script, xml=xml, batch=1)
    try:
        r = R.run(S.intents(t.u[None]))
    finally:
        R.close()
    return search_mod.Trial(u=t.u.copy(), outcome=r.outcomes[0], controls=r.controls[0], qpos0=r.qpos0[0],
                            qvel0=r.qvel0[0], final_qpos=r.final_qpos[0]), xml
