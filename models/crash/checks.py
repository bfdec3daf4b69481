"""The physics checks of the vehicle model, as experiments that return numbers.

Each function builds a small scene, runs it with a plain ``mj_step`` loop and returns what a
crash engineer would measure; tests/test_crash_physics.py asserts them against published
figures and ``benchmarks/bench_crash.py --physics`` prints them (docs/crash.md has the curves
and their sources):

* :func:`braking_distance`: a car on locked wheels from ``v`` m/s, against v^2 / (2 mu g);
* :func:`tilt_angle`: the tilt-table angle at which the uphill wheels lift, against atan(SSF);
* :func:`impact`: a car into the back (collinear, full overlap) or the side of a standing car:
  restitution, contact time, momentum before and after the contact window;
  :func:`restitution_curve` the restitution over closing speed;
* :func:`barrier`: a car into a rigid wall (the NHTSA NCAP frontal test is 56 km/h): contact
  time, mean deceleration, restitution, largest penetration (what stands in for crush).

Compute only: no files, no printing.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from nbst.errors import InputError, SolveError
from nbst.models.crash import crush as crush_mod
from nbst.models.crash import road as road_mod
from nbst.models.crash import scene as scene_mod
from nbst.models.crash import vehicle as veh

__all__ = ["TIMESTEP", "RESTITUTION_SPEEDS", "RESTITUTION_MAX", "RESTITUTION_MIN", "RESTITUTION_HIGH_SPEED",
           "NCAP_DURATION_S", "NCAP_MEAN_G", "restitution_band", "braking_distance", "Tilt",
           "TILT_RESOLUTION", "TILT_RATE", "TILT_HOLD", "tilt_angle", "Impact", "impact", "Barrier",
           "barrier", "restitution_curve", "CFC_PULSE", "cfc_filter", "BarrierPulse", "barrier_pulse"]

G = veh.G
#: Step of the checks (s): the crash search's own step.
TIMESTEP = 0.002

# --- published figures the checks are held to (docs/crash.md: the sources) -----------------
#: Closing speeds of the restitution curve (km/h): the issue's 15-60 km/h.
RESTITUTION_SPEEDS = (15.0, 20.0, 30.0, 40.0, 50.0, 60.0)
#: Restitution of car-to-car impacts: 0.2-0.4 in staged low-speed impacts (SAE 931842:
#: velocity changes of 2-5 mph, i.e. closing speeds up to ~16 km/h between equal cars) and
#: about 0.1 at medium and high speed (SAE 931842), falling as the speed rises (Monson and
#: Germane, SAE 1999-01-0097, NHTSA crash tests). The band: at most 0.4 everywhere, at least
#: 0.05, and at most 0.2 from 40 km/h up.
RESTITUTION_MAX, RESTITUTION_MIN, RESTITUTION_HIGH_SPEED = 0.4, 0.05, (40.0, 0.2)
#: The NHTSA NCAP frontal test: full width into a rigid barrier at 56 km/h (35 mph). Its pulse
#: lasts about a tenth of a second (docs/crash.md); the bracket held here: 60-130 ms, and a mean
#: deceleration (velocity change, rebound included, over the pulse) of 12-25 g.
NCAP_DURATION_S = (0.060, 0.130)
NCAP_MEAN_G = (12.0, 25.0)


def restitution_band(speed_kmh: float) -> tuple[float, float]:
    """(lowest, highest) published restitution of a car-to-car impact at ``speed_kmh`` closing speed."""
    hi = RESTITUTION_HIGH_SPEED[1] if speed_kmh >= RESTITUTION_HIGH_SPEED[0] else RESTITUTION_MAX
    return RESTITUTION_MIN, hi


def _model(road, vehicles, timestep):
    spec = scene_mod.build_spec(road, vehicles, timestep=timestep)
    return spec, spec.compile()


def braking_distance(type_name: str, speed: float, mu: float, *, timestep: float = TIMESTEP) -> float:
    """Distance (m) a vehicle of ``type_name`` travels on a flat road of friction ``mu`` from
    ``speed`` m/s with every wheel braked from t = 0 until it stops."""
    import mujoco

    road = road_mod.Road(layout="straight", width=12.0, length=max(200.0, 2 * speed ** 2 / (mu * G) + 40),
                         friction=mu)
    x0 = -road.length / 2 + 10
    v = scene_mod.SceneVehicle("v0", veh.VEHICLE_TYPES[type_name], x0, 0.0, 0.0)
    _, m = _model(road, [v], timestep)
    d = mujoco.MjData(m)
    d.qpos[:], d.qvel[:] = scene_mod.initial_state(m, [v], [speed])
    L = scene_mod.layout(m, 1)
    d.ctrl[L.ctrl[0, 4:8]] = 1.0  # the four brakes
    b = L.qvel[0]
    limit = int(4 * speed / (mu * G) / timestep) + 1000
    for _ in range(limit):
        mujoco.mj_step(m, d)
        if d.qvel[b] <= 0.0:
            break
    return float(d.qpos[L.qpos[0]] - x0)


@dataclass(frozen=True)
class Tilt:
    """A tilt-table run: the table angle (degrees) at which the uphill wheels lift for good (their
    load under 50 N from then on) and the static tip-over angle (the smallest table angle, to
    :data:`TILT_RESOLUTION`, held at which the vehicle rolls over)."""

    lift_deg: float
    tip_deg: float


#: Resolution of the tip-over angle (degrees), the table's tilting rate (deg/s) and the hold
#: at the final angle that decides whether the vehicle tips (s).
TILT_RESOLUTION, TILT_RATE, TILT_HOLD = 0.125, 5.0, 3.0


def _roll_deg(q) -> float:
    w, x, y, z = q
    return math.degrees(math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y)))


def tilt_angle(type_name: str, *, timestep: float = TIMESTEP, table_friction: float = 2.0,
               lo_deg: float = 25.0, hi_deg: float = 75.0) -> Tilt:
    """The tilt table for ``type_name``: the table is the road, tilted about the vehicle's long
    axis by turning gravity (the same thing, seen from the table); its friction is high enough
    that the tyres do not slide, and the brakes are on.

    One trial tilts a level, settled vehicle to an angle at :data:`TILT_RATE` and holds it
    there for :data:`TILT_HOLD` s: the vehicle tips over if it rolls past 20 degrees. A bisection
    between ``lo_deg`` and ``hi_deg`` finds the smallest such angle to :data:`TILT_RESOLUTION`;
    the lift angle is where the uphill wheels' load first stays under 50 N on the way there.
    A rigid vehicle tips at tan(angle) = SSF; the suspension lets the body roll towards the low
    side first, so the uphill wheels lift a few degrees earlier."""
    import mujoco

    road = road_mod.Road(layout="straight", width=12.0, length=40.0, friction=table_friction)
    v = scene_mod.SceneVehicle("v0", veh.VEHICLE_TYPES[type_name], 0.0, 0.0, 0.0)
    _, m = _model(road, [v], timestep)
    d = mujoco.MjData(m)
    L = scene_mod.layout(m, 1)
    uphill = (m.geom("v0_tyre_fl").id, m.geom("v0_tyre_rl").id)
    a = L.qpos[0] + 3
    f = np.zeros(6)
    chunk = 10

    def load():
        total = 0.0
        for i in range(d.ncon):
            c = d.contact[i]
            if c.geom1 in uphill or c.geom2 in uphill:
                mujoco.mj_contactForce(m, d, i, f)
                total += f[0]
        return total

    def trial(target):
        """(tips over, the angle at which the uphill wheels lifted for good or None)."""
        mujoco.mj_resetData(m, d)
        d.qpos[:], d.qvel[:] = scene_mod.initial_state(m, [v], [0.0])
        d.ctrl[L.ctrl[0, 4:8]] = 1.0
        lift = None
        steps = int(round((target / TILT_RATE + TILT_HOLD) / (chunk * timestep)))
        for k in range(steps):
            theta = min(target, TILT_RATE * k * chunk * timestep)
            t = math.radians(theta)
            m.opt.gravity[:] = [0.0, -G * math.sin(t), -G * math.cos(t)]
            mujoco.mj_step(m, d, nstep=chunk)
            lift = (theta if lift is None else lift) if load() < 50.0 else None
            if _roll_deg(d.qpos[a:a + 4]) > 20.0:
                return True, lift
        return False, lift

    grid = np.arange(lo_deg, hi_deg + TILT_RESOLUTION / 2, TILT_RESOLUTION)
    lo, hi = 0, len(grid) - 1
    tips_lo, _ = trial(grid[lo])
    tips_hi, lift = trial(grid[hi])
    if tips_lo or not tips_hi:
        return Tilt(lift_deg=math.nan, tip_deg=math.nan)
    while hi - lo > 1:
        mid = (lo + hi) // 2
        tips, lf = trial(grid[mid])
        if tips:
            hi, lift = mid, lf
        else:
            lo = mid
    return Tilt(lift_deg=float(lift) if lift is not None else math.nan, tip_deg=float(grid[hi]))


@dataclass(frozen=True)
class Impact:
    """A collinear impact: closing speed (km/h), restitution, contact time (s), momentum before and
    after the contact window (kg m/s), the struck vehicle's delta-V from the sensor's impulse
    (km/h) beside its measured velocity change (km/h), and each vehicle's residual crush at
    separation ({zone: m}; {} for a rigid type)."""

    speed_kmh: float
    restitution: float
    duration: float
    momentum_before: float
    momentum_after: float
    delta_v_impulse_kmh: float
    delta_v_kmh: float
    residual: tuple = ({}, {})


def impact(type_name: str, speed_kmh: float, *, timestep: float = TIMESTEP, other: str | None = None,
           struck: str = "rear") -> Impact:
    """A vehicle of ``type_name`` at ``speed_kmh`` into a standing ``other`` (default the same
    type), wheels free, on a dry road: into its back (``struck`` "rear": collinear, full overlap)
    or square into its left side at its centre of mass (``struck`` "side": the struck car's tyres
    take a sideways impulse, so the pair's momentum along x is not kept there). The contact window
    is read from the pair's contact sensor; restitution = separation speed / closing speed along x.

    Args:
        type_name: the striking vehicle's registered type.
        speed_kmh: its speed (km/h); the other stands.
        timestep: the step (s).
        other: the struck vehicle's type (default ``type_name``).
        struck: "rear" or "side".

    Returns:
        the :class:`Impact`.

    Raises:
        InputError: ``struck`` is neither "rear" nor "side".
        SolveError: the vehicles never touched and parted within 3 s.
    """
    import mujoco

    road = road_mod.Road(layout="straight", width=12.0, length=200.0)
    a, b = veh.VEHICLE_TYPES[type_name], veh.VEHICLE_TYPES[other or type_name]
    if struck == "rear":  # CoM to CoM: 0.5 m between the bumpers
        gap, heading = (a.a + a.front_overhang) + (b.length - b.a - b.front_overhang) + 0.5, 0.0
    elif struck == "side":  # the other turned 90 degrees, its left side 0.5 m ahead of the front
        gap, heading = (a.a + a.front_overhang) + b.width / 2 + 0.5, math.pi / 2
    else:
        raise InputError(f"impact: struck: {struck!r} is neither 'rear' nor 'side'")
    vs = [scene_mod.SceneVehicle("v0", a, -gap, 0.0, 0.0), scene_mod.SceneVehicle("v1", b, 0.0, 0.0, heading)]
    _, m = _model(road, vs, timestep)
    d = mujoco.MjData(m)
    v0 = speed_kmh / 3.6
    d.qpos[:], d.qvel[:] = scene_mod.initial_state(m, vs, [v0, 0.0])
    L = scene_mod.layout(m, 2)
    ia, ib = L.qvel
    s = L.pair_adr[0]
    before = None
    J = 0.0
    for _ in range(int(3.0 / timestep)):
        va, vb = d.qvel[ia], d.qvel[ib]
        mujoco.mj_step(m, d)
        found = d.sensordata[s] > 0
        if found:
            J += d.sensordata[s + 1] * timestep
            if before is None:
                before, t0 = (va, vb), d.time - timestep
        elif before is not None:
            after = (d.qvel[ia], d.qvel[ib])
            e = (after[1] - after[0]) / (before[0] - before[1])
            mass = L.mass
            return Impact(speed_kmh=speed_kmh, restitution=float(e), duration=float(d.time - timestep - t0),
                          momentum_before=float(mass[0] * before[0] + mass[1] * before[1]),
                          momentum_after=float(mass[0] * after[0] + mass[1] * after[1]),
                          delta_v_impulse_kmh=float(J / mass[1] * 3.6), delta_v_kmh=float((after[1] - before[1]) * 3.6),
                          residual=(crush_mod.crush_residual(m, "v0", a, d.qpos), crush_mod.crush_residual(m, "v1", b, d.qpos)))
    raise SolveError(f"restitution check at {speed_kmh:g} km/h: the vehicles never touched")


@dataclass(frozen=True)
class Barrier:
    """A full-width rigid-barrier impact: speed (km/h), contact time (s), mean deceleration (g) =
    velocity change / contact time, restitution, largest penetration (m)."""

    speed_kmh: float
    duration: float
    mean_g: float
    restitution: float
    penetration: float


def _at_the_wall(vt, speed: float, gap: float, timestep: float):
    """(model, data, layout) of one vehicle of type ``vt`` driving square at ``speed`` m/s into a
    rigid wall (a barrier 2 m tall, full width) that its front is ``gap`` m from."""
    import mujoco

    wall_x = 5.0
    road = road_mod.Road(layout="straight", width=12.0, length=200.0,
                         barriers=(road_mod.Barrier((wall_x + road_mod.BARRIER_THICKNESS / 2, -4.0),
                                                    (wall_x + road_mod.BARRIER_THICKNESS / 2, 4.0), 2.0),))
    v = scene_mod.SceneVehicle("v0", vt, wall_x - (vt.a + vt.front_overhang) - gap, 0.0, 0.0)
    _, m = _model(road, [v], timestep)
    d = mujoco.MjData(m)
    d.qpos[:], d.qvel[:] = scene_mod.initial_state(m, [v], [speed])
    return m, d, scene_mod.layout(m, 1)


def barrier(type_name: str, speed_kmh: float = 56.0, *, timestep: float = TIMESTEP) -> Barrier:
    """A vehicle of ``type_name`` at ``speed_kmh`` square into a rigid wall (a barrier 2 m tall)."""
    import mujoco

    m, d, L = _at_the_wall(veh.VEHICLE_TYPES[type_name], speed_kmh / 3.6, 0.3, timestep)
    s = int(L.barrier_adr[0])
    bar = m.geom("barrier0").id
    before, pen = None, 0.0
    for _ in range(int(2.0 / timestep)):
        vx = d.qvel[L.qvel[0]]
        mujoco.mj_step(m, d)
        if d.sensordata[s] > 0:
            if before is None:
                before, t0 = vx, d.time - timestep
            pen = max([pen] + [-c.dist for c in d.contact[:d.ncon] if bar in (c.geom1, c.geom2)])
        elif before is not None:
            after = d.qvel[L.qvel[0]]
            dur = d.time - timestep - t0
            return Barrier(speed_kmh=speed_kmh, duration=float(dur), mean_g=float((before - after) / dur / G),
                           restitution=float(-after / before), penetration=float(pen))
    raise SolveError(f"barrier check at {speed_kmh:g} km/h: the vehicle never reached the barrier")


def restitution_curve(type_name: str = "sedan", speeds_kmh=(15, 20, 30, 40, 50, 60), *,
                      timestep: float = TIMESTEP, other: str | None = None, struck: str = "rear") -> np.ndarray:
    """(k, 2): closing speed (km/h) and restitution of :func:`impact` at each speed (``other``
    and ``struck`` as there)."""
    return np.array([[v, impact(type_name, v, timestep=timestep, other=other, struck=struck).restitution]
                     for v in speeds_kmh])


#: SAE J211's channel frequency class for vehicle-structure accelerations (integration to
#: velocity and displacement, and the crash pulse): CFC 60.
CFC_PULSE = 60.0


def cfc_filter(x: np.ndarray, dt: float, cfc: float = CFC_PULSE) -> np.ndarray:
    """``x`` (samples ``dt`` s apart) through SAE J211-1's phaseless digital filter of class
    ``cfc``: a 2-pole Butterworth run forward, then backward (4 poles, no phase shift)."""
    wd = 2.0 * math.pi * cfc * 2.0775
    wa = math.sin(wd * dt / 2) / math.cos(wd * dt / 2)
    den = 1.0 + math.sqrt(2.0) * wa + wa * wa
    a0 = wa * wa / den
    a1, a2 = 2 * a0, a0
    b1 = -2.0 * (wa * wa - 1.0) / den
    b2 = (-1.0 + math.sqrt(2.0) * wa - wa * wa) / den

    def once(u):
        y = np.empty_like(u)
        y[:2] = u[:2]
        for n in range(2, len(u)):
            y[n] = a0 * u[n] + a1 * u[n - 1] + a2 * u[n - 2] + b1 * y[n - 1] + b2 * y[n - 2]
        return y
    x = np.asarray(x, dtype=float)
    return once(once(x)[::-1])[::-1]


@dataclass(frozen=True)
class BarrierPulse:
    """A vehicle square into a rigid wall, read as a crash test reads it (the sprung body's own
    motion: the occupant compartment): ``speed_kmh``; ``t_zero`` (s), from first contact to zero
    velocity; ``dynamic_crush`` (m), the body's travel over that time; ``mean_g`` = speed /
    t_zero / g; ``peak_g`` the peak of the CFC 60 filtered deceleration; ``restitution`` =
    rebound speed / speed at separation; ``duration`` (s) the contact time; ``residual`` (m)
    the front zone's crush once the contact let go (0 for a rigid type); ``energy_lost`` (J)
    the kinetic energy the impact took (before - after); ``crush_energy`` (J) CRASH3's energy
    of the residual crush (0 for a rigid type); ``first_step_g`` the deceleration over the
    first contact step."""

    speed_kmh: float
    t_zero: float
    dynamic_crush: float
    mean_g: float
    peak_g: float
    restitution: float
    duration: float
    residual: float
    energy_lost: float
    crush_energy: float
    first_step_g: float


def barrier_pulse(type_name: str, speed_kmh: float = 56.0, *, timestep: float = 0.002) -> BarrierPulse:
    """The NHTSA NCAP frontal test (full width into a rigid barrier; 56 km/h) for a vehicle of
    ``type_name`` at step ``timestep`` s: a plain ``mj_step`` loop, wheels free.

    Args:
        type_name: a registered vehicle type (``sedan-crush`` etc. crush; the others are rigid).
        speed_kmh: the impact speed.
        timestep: the step (s).

    Returns:
        the :class:`BarrierPulse`.

    Raises:
        SolveError: the vehicle never reached the wall or never left it within 2 s.
    """
    import mujoco

    vt = veh.VEHICLE_TYPES[type_name]
    v0 = speed_kmh / 3.6
    m, d, L = _at_the_wall(vt, v0, 0.05, timestep)
    s, ix, iq = int(L.barrier_adr[0]), int(L.qvel[0]), int(L.qpos[0])
    vl: list[float] = []
    xl: list[float] = []
    tl: list[bool] = []
    window, k0 = int(round(0.25 / timestep)), None  # 0.25 s after the first contact: parted by then
    for k in range(int(round(2.0 / timestep))):
        mujoco.mj_step(m, d)
        vl.append(float(d.qvel[ix]))
        xl.append(float(d.qpos[iq]))
        tl.append(bool(d.sensordata[s] > 0))
        if k0 is None and tl[-1]:
            k0 = k
        if k0 is not None and k - k0 >= window:
            break
    if k0 is None or tl[-1]:
        raise SolveError(f"barrier pulse at {speed_kmh:g} km/h: the vehicle did not touch and leave the wall "
                         "within 2 s")
    vel, xs, touching = np.array(vl), np.array(xl), np.array(tl)
    k1 = int(np.flatnonzero(touching)[-1]) + 1  # the first step after the last contact
    before = v0 if k0 == 0 else vel[k0 - 1]
    x0 = xs[k0 - 1] if k0 > 0 else xs[0] - before * timestep
    kz = k0 + int(np.argmax(vel[k0:] <= 0.0))
    # zero crossing, interpolated inside the step
    t_zero = (kz - k0 + 1 - vel[kz] / (vel[kz] - vel[kz - 1])) * timestep if kz > k0 else timestep
    acc = -np.diff(np.concatenate([[before], vel[k0:]])) / timestep
    pad = int(round(0.02 / timestep))  # a quiet lead-in and tail: the filter's edges
    acc = np.concatenate([np.zeros(pad), acc, np.zeros(pad)])
    peak = float(cfc_filter(acc, timestep).max() / veh.G)
    after = vel[k1]
    residual = crush_mod.crush_residual(m, "v0", vt, d.qpos).get("front", 0.0)
    mass = float(L.mass[0])
    return BarrierPulse(speed_kmh=speed_kmh, t_zero=float(t_zero), dynamic_crush=float(xs[kz] - x0),
                        mean_g=float(before / t_zero / veh.G), peak_g=peak, restitution=float(-after / before),
                        duration=float((k1 - k0) * timestep), residual=float(residual),
                        energy_lost=0.5 * mass * (before ** 2 - after ** 2),
                        crush_energy=float(sum(crush_mod.crush_energy(vt, {"front": residual}).values())),
                        first_step_g=float(acc[pad] / veh.G))
