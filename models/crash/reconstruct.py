"""Reconstruction with honest uncertainty: approximate Bayesian computation over batched rollouts.

A case (:mod:`.evidence`: a crash script whose fates are the evidence, the unknowns besides the
drivers, more evidence kinds with their tolerances) is reconstructed by **ABC-SMC**, sequential
Monte Carlo approximate Bayesian computation with an adaptive tolerance schedule and MCMC moves
(Beaumont, Cornuet, Marin and Robert, *Adaptive approximate Bayesian computation*, Biometrika
96, 2009; Toni, Welch, Strelkowa, Ipsen and Stumpf, J. R. Soc. Interface 6, 2009; the
replenishment form of Drovandi and Pettitt, Biometrics 67, 2011, and Del Moral, Doucet and
Jasra, Stat. Comput. 22, 2012):

* the **unknowns** θ are the drivers' intents within the script's ranges, the road's friction,
  each vehicle's load, and factors on the body contact's stiffness and damping ratio (the
  restitution), each uniform over its stated range (the prior);
* a draw's **distance** is the largest of its evidence's misses, each in units of its
  tolerance (:func:`.evidence.distances`); the target population is every draw within 1: each
  piece of evidence within its tolerance. That is the posterior under the model that every
  piece of evidence is known to within its tolerance (a uniform error; Wilkinson, *ABC gives
  exact results under the assumption of model error*, SAGMB 12, 2013), so the tolerances are
  part of the model, not a knob;
* :data:`PARTICLES` draws from the prior; then each generation the tolerance drops to the
  median distance (never below 1), the draws beyond it are replaced by copies of those within,
  and each copy takes up to :data:`MAX_MOVES` Metropolis steps (a Gaussian of 2.38^2/d times
  the population's covariance, accepted when within the tolerance and the prior's box); at
  tolerance 1 every draw takes :data:`FINAL_MOVES` more steps so that the copies spread.

Each vehicle's impact speed (just before its first vehicle contact), delta-V (the impulse of
that contact over the drawn mass) and PDOF (the principal direction of force, as a clock: 12 is
a force from straight ahead, 3 from the right) are summarised over the accepted draws as a 90 %
interval (5th to 95th percentile, :data:`LEVEL`) and the median. A quantity whose interval is
at least :data:`WEAK` of its prior interval (the same quantity over the first generation's
draws that hit as the evidence says) is **not identifiable** from the evidence: the interval
is reported wide, and flagged. Brach and Brach (*Vehicle Accident Analysis and Reconstruction
Methods*, SAE, 2nd ed. 2011, the chapters on uncertainty) and the Monte Carlo reconstructions of
SAE 2001-01-3347 and SAE 2003-01-0489 treat the inputs the same way: ranges in, distributions out.

The rollouts run on :class:`AbcRunner`: the case's :class:`~.run.CrashRunner` whose batch
gives each simulation its own friction, masses and contact parameters
(``mujoco.batch.Batch.expand``) and records every vehicle's track per driver period (the EDR
speed, the skid's start and length). The crash written for a reconstruction is its draw of
least squared distance, run again on a scene whose XML holds that draw's parameters, so that it
replays bit for bit.

Compute only.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from nbst.errors import InputError
from nbst.models.crash import driver as drv
from nbst.models.crash import evidence as ev_mod
from nbst.models.crash import scene as scene_mod
from nbst.models.crash import search as search_mod
from nbst.models.crash.run import BATCH, CrashRollouts, CrashRunner, scene_vehicles
from nbst.models.crash.space import space_of
from nbst.models.crash.vehicle import BIT_BODY, G
from nbst.seeds import check_seed

__all__ = ["PARTICLES", "MAX_ROLLOUTS", "LEVEL", "WEAK", "MAX_MOVES", "FINAL_MOVES", "ALPHA", "MIN_ACCEPTED",
           "METHOD", "Progress", "AbcRunner", "Reconstruction", "reconstruct", "ranges_of", "slide_speed",
           "momentum_speeds", "pdof_clock", "phys_coords", "scene_xml_of"]

#: The population: draws kept per generation (a multiple of the batch). The default sample size.
PARTICLES = 64
#: The default rollout budget of one reconstruction (the CLI's --max-rollouts).
MAX_ROLLOUTS = 2400
#: The interval reported: the central 90 % of the accepted draws.
LEVEL = 0.90
#: A quantity whose interval is at least this share of its prior interval is not identifiable.
WEAK = 0.5
#: Metropolis steps per replenished draw and generation at most, and per draw at the end.
MAX_MOVES, FINAL_MOVES = 2, 2
#: The share of the population replaced each generation (the tolerance falls to its quantile).
ALPHA = 0.5
#: Fewer accepted draws than this: the intervals are rough (said in the report).
MIN_ACCEPTED = 32

METHOD = ("ABC-SMC (Beaumont et al. 2009; Toni et al. 2009; Drovandi and Pettitt 2011): the drivers' intents, the "
          "road friction, each vehicle's load and the body contact's stiffness and damping drawn uniformly within "
          "their ranges; each piece of evidence met within its tolerance; adaptive tolerances, Metropolis moves; "
          "90 % intervals over the accepted draws")


@dataclass
class Progress:
    """After each batch: rollouts so far, the tolerance now, how many draws are within 1."""

    rollouts: int
    epsilon: float
    accepted: int


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


class AbcRunner(CrashRunner):
    """A :class:`CrashRunner` of a case whose simulations each take their own physical unknowns
    (``run(intents, phys)``) and whose rollouts keep each vehicle's track (see the module docstring)."""

    def __init__(self, case: ev_mod.Case, *, jobs: int = 1, batch: int = BATCH):
        super().__init__(case.script, jobs=jobs, batch=batch)
        self.case = case
        self.stepper = _Track(self.stepper, self.L)
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
            tracks.append({"pos": self.stepper.pos, "speed": self.stepper.speed,
                           "locked": (brakes >= 0.999).all(axis=-1)})
        rolls = CrashRollouts(outcomes=[o for p in parts for o in p.outcomes],
                              min_dist=np.concatenate([p.min_dist for p in parts]),
                              qpos0=np.concatenate([p.qpos0 for p in parts]),
                              qvel0=np.concatenate([p.qvel0 for p in parts]),
                              controls=np.concatenate([p.controls for p in parts]),
                              final_qpos=np.concatenate([p.final_qpos for p in parts]))
        return rolls, {key: np.concatenate([t[key] for t in tracks]) for key in tracks[0]}

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


# --------------------------------------------------------------------------- what a draw says

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


# --------------------------------------------------------------------------- ABC-SMC

@dataclass
class Reconstruction:
    """What a reconstruction found (see the module docstring)."""

    names: list
    labels: list                 # the evidence's pieces, in the order of ``distances``' columns
    Z: np.ndarray                # (N, dim) the final population, unit cube (intents, then physics)
    distance: np.ndarray         # (N,) each draw's distance (met at <= 1)
    distances: np.ndarray        # (N, pieces)
    quantities: np.ndarray       # (N, 3 n + 1): per vehicle impact speed, delta-V (m/s), PDOF (h); closing speed
    phys: dict                   # the final population's physical unknowns
    prior_quantities: np.ndarray  # the first generation's quantities of the draws that hit as the evidence says
    epsilon: float               # the tolerance reached (1: every piece within its tolerance)
    rollouts: int
    generations: int
    seed: int
    particles: int
    best: search_mod.Trial | None = None  # the draw of least squares, rolled out on its own scene
    best_xml: str = ""
    best_index: int = -1
    interrupted: bool = False
    method: str = METHOD
    intervals: list = field(default_factory=list)  # per vehicle {quantity: {...}}; see intervals_of

    @property
    def accepted(self) -> np.ndarray:
        return self.distance <= 1.0

    @property
    def found(self) -> bool:
        return bool(self.accepted.any())

    @property
    def fits(self) -> list:
        """The accepted draws' indices (a fit: every piece of evidence within its tolerance)."""
        return list(np.flatnonzero(self.accepted))

    @property
    def estimate(self) -> list:
        """Per vehicle the accepted draws' median impact speed (m/s) and delta-V."""
        return [{"impact_speed": v["impact_speed"]["median"], "delta_v": v["delta_v"]["median"]}
                if v else {} for v in self.intervals]

    @property
    def ranges(self) -> list:
        """Per vehicle (5th percentile, median, 95th percentile) of the impact speed (m/s)."""
        return [{"impact_speed": (v["impact_speed"]["lo"], v["impact_speed"]["median"], v["impact_speed"]["hi"])}
                if v else {} for v in self.intervals]

    def to_dict(self) -> dict:
        """The reconstruction as the crash file's ``reconstruction`` (km/h, o'clock, metres)."""
        kmh = 3.6
        vs = []
        for nm, iv in zip(self.names, self.intervals):
            if not iv:
                vs.append({"name": nm, "impact_speed_kmh": None, "delta_v_kmh": None, "pdof_clock": None})
                continue
            row = {"name": nm}
            for key, scale, unit in (("impact_speed", kmh, "impact_speed_kmh"), ("delta_v", kmh, "delta_v_kmh"),
                                     ("pdof", 1.0, "pdof_clock")):
                x = iv[key]
                row[unit] = {k: (round(x[k] * scale, 2) if isinstance(x[k], float) else x[k])
                             for k in ("lo", "median", "hi", "min", "max", "prior_lo", "prior_hi", "identifiable")
                             if k in x}
            b = self.quantities[self.best_index] if self.best_index >= 0 else None
            x = iv["impact_speed"]
            row["impact_speed_m_s"] = {"min": round(x["min"], 3), "lo": round(x["lo"], 3), "median": round(x["median"], 3),
                                       "hi": round(x["hi"], 3), "max": round(x["max"], 3),
                                       "estimate": None if b is None else round(float(b[3 * len(vs)]), 3)}
            vs.append(row)
        acc = self.accepted
        phys = {}
        for key in ("friction", "stiffness", "damping"):
            v = self.phys[key][acc] if acc.any() else self.phys[key]
            phys[key] = {"lo": round(float(np.quantile(v, (1 - LEVEL) / 2)), 3), "median": round(float(np.median(v)), 3),
                         "hi": round(float(np.quantile(v, 1 - (1 - LEVEL) / 2)), 3)}
        cs = self.quantities[acc, -1] if acc.any() else self.quantities[:, -1]
        cs = cs[np.isfinite(cs)]
        closing = None if not len(cs) else {
            "lo": round(float(np.quantile(cs, (1 - LEVEL) / 2)) * kmh, 2),
            "median": round(float(np.median(cs)) * kmh, 2),
            "hi": round(float(np.quantile(cs, 1 - (1 - LEVEL) / 2)) * kmh, 2)}
        return {"method": self.method, "level": LEVEL, "particles": self.particles, "accepted": int(acc.sum()),
                "fits": int(acc.sum()), "epsilon": round(float(self.epsilon), 4), "rollouts": self.rollouts,
                "generations": self.generations, "seed": self.seed, "evidence": self.labels,
                "vehicles": vs, "closing_speed_kmh": closing, "unknowns": phys,
                "weak_threshold": WEAK, "interrupted": self.interrupted}


def _interval(x: np.ndarray, prior: np.ndarray, circular: float | None = None) -> dict:
    """{lo, median, hi (the central LEVEL), min, max, prior_lo, prior_hi, identifiable} of samples ``x``;
    ``circular`` the period of a circular quantity (the clock's 12 h)."""
    x = x[np.isfinite(x)]
    prior = prior[np.isfinite(prior)]
    if not len(x):
        return {}
    if circular is not None:  # unwrap about the circular mean
        ang = x / circular * 2 * math.pi
        c = math.atan2(float(np.mean(np.sin(ang))), float(np.mean(np.cos(ang)))) / (2 * math.pi) * circular
        x = c + (x - c + circular / 2) % circular - circular / 2
        prior = c + (prior - c + circular / 2) % circular - circular / 2
    a = (1 - LEVEL) / 2
    out = {"lo": float(np.quantile(x, a)), "median": float(np.median(x)), "hi": float(np.quantile(x, 1 - a)),
           "min": float(x.min()), "max": float(x.max())}
    if len(prior) >= 8:
        plo, phi = float(np.quantile(prior, a)), float(np.quantile(prior, 1 - a))
        out["prior_lo"], out["prior_hi"] = plo, phi
        out["identifiable"] = bool(out["hi"] - out["lo"] < WEAK * max(phi - plo, 1e-9))
    if circular is not None:
        for k in ("lo", "median", "hi", "min", "max", "prior_lo", "prior_hi"):
            if k in out:
                h = out[k] % circular
                out[k] = circular if h < 1e-6 or h > circular - 1e-6 else h
    return out


def intervals_of(rec: Reconstruction) -> list:
    """Per vehicle {impact_speed, delta_v (m/s), pdof (h)} intervals over the accepted draws
    (over the whole population when none is accepted)."""
    acc = rec.accepted if rec.accepted.any() else np.ones(len(rec.distance), bool)
    out = []
    for i in range(len(rec.names)):
        Q, P = rec.quantities[acc], rec.prior_quantities
        iv = {"impact_speed": _interval(Q[:, 3 * i], P[:, 3 * i]), "delta_v": _interval(Q[:, 3 * i + 1], P[:, 3 * i + 1]),
              "pdof": _interval(Q[:, 3 * i + 2], P[:, 3 * i + 2], circular=12.0)}
        out.append(iv if iv["impact_speed"] else {})
    return out


def reconstruct(case, *, seed: int, max_rollouts: int = MAX_ROLLOUTS, particles: int = PARTICLES,
                runner: AbcRunner | None = None, jobs: int = 1,
                callback: Callable[[Progress], object] | None = None) -> Reconstruction:
    """Reconstruct ``case`` by ABC-SMC (see the module docstring).

    Args:
        case: an :class:`.evidence.Case`, or a crash script whose fates are the evidence (its
            unknowns take the defaults of :mod:`.evidence`).
        seed: an integer in [0, 2^63-1]; the same seed gives the same draws whatever ``jobs``.
        max_rollouts: the rollout budget (at least one batch).
        particles: the population (rounded up to whole batches; at most the budget).
        runner: an :class:`AbcRunner` of this case to reuse, or None: one is made with ``jobs``
            threads and closed at the end.
        jobs: threads of the runner made here.
        callback: None, or called with a :class:`Progress` after each batch of moves.

    Returns:
        A :class:`Reconstruction`: the final population (unit-cube draws, distances, per-vehicle
        impact speed, delta-V, PDOF), the tolerance reached (1: every piece of evidence within its
        tolerance; more when the budget ran out first), the per-vehicle 90 % intervals with their
        identifiability, and the draw of least squares rolled out on its own scene (``best``,
        ``best_xml``); ``interrupted`` after Ctrl-C.

    Raises:
        InputError: ``seed`` is not an integer in [0, 2^63-1], or ``max_rollouts`` is under one batch.
        MujocoError: a rollout diverged (a non-finite state).
    """
    if not isinstance(case, ev_mod.Case):
        case = ev_mod.case_from_dict(case.raw, source=case.source)
    seed = check_seed(seed, what="seed")
    if int(max_rollouts) < BATCH:
        raise InputError(f"max_rollouts {max_rollouts}: a reconstruction needs at least one batch ({BATCH})")
    own = runner is None
    R = runner if runner is not None else AbcRunner(case, jobs=jobs)
    S = space_of(case.script)
    pc = phys_coords(case)
    dim = S.dim + len(pc)
    N = min(-(-int(particles) // BATCH) * BATCH, int(max_rollouts) // BATCH * BATCH)
    rng = np.random.default_rng([seed, 47])
    used = 0
    labels = ev_mod.labels(case)
    whole = R.L.mass  # each vehicle's whole mass; the load adds to it

    def simulate(Z: np.ndarray):
        nonlocal used
        phys = _phys_values(case, Z[:, S.dim:])
        rolls, track = R.run_phys(S.intents(Z[:, :S.dim]), phys)
        used += len(Z)
        Dm = np.array([ev_mod.distances(case, o, track, k, md) for k, (o, md) in
                       enumerate(zip(rolls.outcomes, rolls.min_dist))]).reshape(len(Z), len(labels))
        mass = whole[None] + phys["load"]
        Q = np.array([_quantities(case, o, track, k, mass[k]) for k, o in enumerate(rolls.outcomes)])
        return (Dm.max(axis=1) if Dm.shape[1] else np.zeros(len(Z))), Dm, Q, phys

    interrupted = False
    Z = rng.random((N, dim))
    eps = math.inf
    gens = 0
    D = None
    try:
        D, Dm, Q, phys = simulate(Z)
        hk = [k for k, lb in enumerate(labels) if lb.endswith(".hits")]
        hit = np.all(Dm[:, hk] == 0.0, axis=1) if hk else np.ones(N, bool)
        prior_Q = Q[hit] if hit.sum() >= 8 else Q.copy()
        if callback:
            callback(Progress(used, eps, int((D <= 1).sum())))
        moves = MAX_MOVES
        idle = 0
        while used + BATCH <= max_rollouts and idle < 3:
            gens += 1
            before = used
            final = bool((D <= 1.0).all())
            if final:  # every draw within the evidence: FINAL_MOVES steps for all, so that the copies spread
                eps, alive, move, steps = 1.0, np.ones(N, bool), np.arange(N), FINAL_MOVES
            else:
                eps = min(eps, max(1.0, float(np.quantile(D, 1 - ALPHA))))
                alive = D <= eps
                if alive.sum() < 2:  # a population of misses: keep the better half
                    alive = D <= np.sort(D)[N // 2 - 1]
                    eps = float(D[alive].max())
                move = np.flatnonzero(~alive)
                src = rng.choice(np.flatnonzero(alive), size=len(move))
                for arr in (Z, D, Dm, Q):
                    arr[move] = arr[src]
                for key in phys:
                    phys[key][move] = phys[key][src]
                steps = moves
                if not len(move):  # ties at the tolerance: nothing to replace, so every draw moves
                    move = np.arange(N)
            cov = np.atleast_2d(np.cov(Z[alive].T)) * (2.38 ** 2 / dim) + np.eye(dim) * 1e-8
            Lc = np.linalg.cholesky(cov)
            tried = taken = 0
            for _ in range(steps):
                room = (max_rollouts - used) // BATCH * BATCH
                if not room or not len(move):
                    break
                prop = Z[move] + rng.standard_normal((len(move), dim)) @ Lc.T
                inside = np.all((prop >= 0.0) & (prop <= 1.0), axis=1)  # the prior's box
                tried += len(move)
                idx, prop_in = move[inside][:room], prop[inside][:room]
                if not len(idx):
                    continue
                d, dm, q, ph = simulate(prop_in)
                ok = d <= eps
                taken += int(ok.sum())
                k = idx[ok]
                Z[k], D[k], Dm[k], Q[k] = prop_in[ok], d[ok], dm[ok], q[ok]
                for key in phys:
                    phys[key][k] = ph[key][ok]
                if callback:
                    callback(Progress(used, eps, int((D <= 1).sum())))
            p = taken / max(tried, 1)
            # enough steps that a draw moves at least once with probability 0.9 (at most MAX_MOVES)
            moves = MAX_MOVES if p <= 0.0 else (1 if p >= 0.9 else
                                                int(min(MAX_MOVES, math.ceil(math.log(0.1) / math.log(1.0 - p)))))
            if final:
                break
            idle = idle + 1 if used == before else 0  # three generations of proposals all outside the box: stop
    except KeyboardInterrupt:
        interrupted = True
        if D is None:
            raise
    finally:
        if own:
            R.close()
    done = bool((D <= 1.0).all())
    rec = Reconstruction(names=case.script.names(), labels=labels, Z=Z, distance=D, distances=Dm, quantities=Q,
                         phys=phys, prior_quantities=prior_Q,
                         epsilon=float(D.max()) if done else float(eps if math.isfinite(eps) else D.max()),
                         rollouts=used, generations=gens, seed=int(seed), particles=N, interrupted=interrupted)
    rec.intervals = intervals_of(rec)
    pool = np.flatnonzero(rec.accepted) if rec.found else np.arange(N)
    rec.best_index = int(pool[np.argmin((Dm[pool] ** 2).sum(axis=1))]) if Dm.shape[1] else int(pool[0])
    return rec


def best_trial(case: ev_mod.Case, rec: Reconstruction) -> tuple[search_mod.Trial, str]:
    """The draw of least squares rolled out again on a scene that holds its physical unknowns:
    (its trial, the scene's MJCF text)."""
    S = space_of(case.script)
    k = rec.best_index
    xml = scene_xml_of(case, rec.phys, k)
    R = CrashRunner(case.script, xml=xml, batch=1)
    try:
        r = R.run(S.intents(rec.Z[k:k + 1, :S.dim]))
    finally:
        R.close()
    t = search_mod.Trial(u=rec.Z[k, :S.dim].copy(), outcome=r.outcomes[0], controls=r.controls[0], qpos0=r.qpos0[0],
                         qvel0=r.qvel0[0], final_qpos=r.final_qpos[0])
    return t, xml


# --------------------------------------------------------------------------- kept helpers

def ranges_of(fits: list, n: int) -> list:
    """Per vehicle, (lowest, median, highest) of impact speed, heading (unwrapped about the
    first fit's) and delta-V over ``fits`` (search trials)."""
    out = []
    for i in range(n):
        vs = [t.outcome.vehicles[i] for t in fits]
        h0 = vs[0].impact_heading if vs else 0.0
        heads = [h0 + (v.impact_heading - h0 + math.pi) % (2 * math.pi) - math.pi for v in vs]
        out.append({"impact_speed": _summary([v.impact_speed for v in vs]), "impact_heading": _summary(heads),
                    "delta_v": _summary([v.delta_v for v in vs])})
    return out


def _summary(values: list) -> tuple | None:
    v = np.array([x for x in values if np.isfinite(x)])
    return None if not len(v) else (float(v.min()), float(np.median(v)), float(v.max()))


def slide_speed(distance: float, mu: float) -> float:
    """The speed (m/s) that a slide on locked wheels over ``distance`` (m) at friction ``mu``
    takes off: sqrt(2 mu g d)."""
    return math.sqrt(2.0 * mu * G * max(distance, 0.0))


def momentum_speeds(mass, impact, approach, rest, mu: float) -> np.ndarray:
    """Pre-impact speeds (m/s) of two vehicles from the conservation of linear momentum through
    the impact: each leaves its impact position ``impact[i]`` (x, y) towards its rest position
    ``rest[i]`` at :func:`slide_speed` of that distance, and came in along the unit ``approach[i]``;
    m_A v_A e_A + m_B v_B e_B = m_A u_A + m_B u_B, solved for (v_A, v_B) (least squares when the
    approaches are parallel: then only the total momentum is known, the split is not)."""
    mass = np.asarray(mass, float)
    post = np.zeros(2)
    for i in range(2):
        d = np.asarray(rest[i][:2], float) - np.asarray(impact[i][:2], float)
        n = float(np.hypot(*d))
        if n > 1e-9:
            post = post + mass[i] * slide_speed(n, mu) * d / n
    A = np.column_stack([mass[0] * np.asarray(approach[0], float), mass[1] * np.asarray(approach[1], float)])
    return np.linalg.lstsq(A, post, rcond=None)[0]
