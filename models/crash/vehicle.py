"""The built-in vehicle types and the MuJoCo bodies that stand for them.

Axes of a vehicle: x forward, y to the driver's left, z up; the body frame's origin is the
vehicle's centre of mass (CoM), so a free joint's position is the CoM and its quaternion the
vehicle's attitude. Units: m, kg, s, N, rad inside; the script and the reports speak km/h
and degrees.

**Types** (:data:`VEHICLE_TYPES`, one data file each in ``models/crash/vehicles/``; sources and
the assumed parameters in docs/crash.md):

* ``sedan``: a mid-size sedan (2018 Toyota Camry class: 4.88 x 1.83 x 1.45 m, wheelbase
  2.82 m), 1,450 kg, track 1.58 m, SSF 1.41;
* ``suv``: a mid-size SUV, 2,000 kg, 4.90 x 1.93 x 1.75 m, wheelbase 2.86 m, track 1.65 m, SSF 1.17;
* ``van``: a full-size van (light truck), 2,500 kg, 5.53 x 2.05 x 2.10 m, wheelbase 3.30 m,
  track 1.72 m, SSF 1.12.

The SSFs are NHTSA's sales-weighted averages of model year 2003 for each class (NHTSA report
HS 809 868); the CoM height follows from SSF = track / (2 h). The moments of inertia are the
usual approximations (assumed; docs/results/crash.md names their sensitivity): yaw ``m a b`` (dynamic
index 1), pitch 0.9 x yaw, roll ``m (0.39 track)^2``.

**Model** (per vehicle, names prefixed by the vehicle's ``prefix``):

* body ``{p}`` on a free joint ``{p}_free``: the sprung mass with explicit inertia; two
  collision boxes, ``{p}_lower`` (bumper to belt line, full length and width) and ``{p}_cabin``
  (belt line to roof), which carry the car-to-car contacts (a rigid type does not crush:
  penetration stands in for crush; docs/crash.md);
* a crushing type (``crush`` true: ``sedan-crush``, ``suv-crush``, ``van-crush``) has four crush
  zones (front, rear, left, right: :mod:`nbst.models.crash.crush`): the lower box keeps its core and each
  zone is a slab on a chain of slide joints ``{p}_crush_{zone}_{k}`` with dry friction, CRASH3's
  force per unit width A + B C as a staircase of yield forces (:class:`CrushZone`); the joints
  hold what they crushed (plastic), so their sum is the residual crush (:func:`.crush.crush_residual`)
  and CRASH3's energy of it the EES (:func:`.crush.crush_ees`);
* four corners ``fl fr rl rr``: a knuckle body on a sprung slide joint ``{p}_susp_{c}``
  (stiffness for a 1.5 Hz ride, damping ratio 0.3, travel limited by bump stops), the front
  ones with a steer hinge ``{p}_steer_{c}`` (Ackermann angles set by the driver), and a wheel
  body on a spin hinge ``{p}_spin_{c}`` with an ellipsoid tyre ``{p}_tyre_{c}`` (not a
  cylinder: MJX and MuJoCo Warp do not collide cylinders with boxes and meshes);
* actuators, :data:`CONTROLS` per vehicle in this order: 2 steering servos (position, rad),
  2 rear drive motors (torque, N m), 4 brakes (damper, 0..1: torque = -kv omega ctrl, clamped).

Contacts: tyres touch the road, curbs and barriers only (contype 2); bodies touch the road,
curbs, barriers and other vehicles' bodies (contype 4), with priority over the road so that
their own friction and ``solref`` rule (the road's friction rules the tyres). Parameters in
:data:`BODY_CONTACT`.

Compute only: functions add elements to an ``MjSpec`` or return numbers.
"""
from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass
from importlib import resources
from typing import Any

import numpy as np

from nbst.errors import InputError
from nbst.models.crash import crush as crush_mod
from nbst.registry import Registry

__all__ = ["G", "CORNERS", "CONTROLS", "BIT_STATIC", "BIT_TYRE", "BIT_BODY", "VEHICLE_KIND", "BodyContact",
           "BODY_CONTACT", "TYRE_FRICTION", "BRAKE_KV", "TYRE_SOLREF", "VehicleType",
           "vehicle_type_from_dict", "VEHICLE_TYPES", "control_names", "corner_positions", "heading_quat",
           "add_vehicle"]

G = 9.81
#: Corner names, in the order of every per-corner array.
CORNERS = ("fl", "fr", "rl", "rr")
#: Actuator suffixes of a vehicle, in control order (:func:`control_names`).
CONTROLS = ("steer_fl", "steer_fr", "drive_rl", "drive_rr", "brake_fl", "brake_fr", "brake_rl", "brake_rr")
#: Collision bits: static world (road, curbs, barriers), tyres, bodies.
BIT_STATIC, BIT_TYRE, BIT_BODY = 1, 2, 4
#: The ``kind`` of a vehicle type's data file.
VEHICLE_KIND = "nbst-crash-vehicle"


@dataclass(frozen=True)
class BodyContact:
    """Car-to-car and body-to-ground contact (the body geoms' ``solref``/``solimp``/friction).

    ``solref`` (time constant s, damping ratio) and ``solimp`` set how a rigid box stands for a
    crushing car: restitution falls with impact speed because the impedance rises with the
    penetration (docs/crash.md has the measured curve, the band it sits in and its sources).
    """

    timeconst: float = 0.08
    dampratio: float = 0.6
    solimp: tuple = (0.95, 0.3, 0.1, 0.5, 2.0)
    friction: float = 0.4


BODY_CONTACT = BodyContact()
#: Tyre friction ratios: the road's own friction rules tyre contacts (priority), so these only
#: matter against nothing; kept low so that a tyre never raises a contact's friction.
TYRE_FRICTION = 0.1
#: Brake damping (N m s/rad): torque = -kv omega ctrl, clamped to the type's brake torque. The
#: damper is integrated explicitly, so kv dt / I_wheel must stay below ~1 (0.9 kg m^2 wheels,
#: 2 ms steps: kv < 450); at 400 a braked wheel turns at most ~2.5 rad/s (0.8 m/s at the tread)
#: while the tyre slides: a locked wheel for the friction, which does not depend on slip speed.
BRAKE_KV = 400.0
#: Tyre contact time constant (s) and damping ratio: a stiff, critically damped tyre.
TYRE_SOLREF = (0.01, 1.0)


@dataclass(frozen=True)
class VehicleType:
    """A vehicle type (SI units). ``front_weight`` is the static share on the front axle."""

    name: str
    label: str
    mass: float
    length: float
    width: float
    height: float
    wheelbase: float
    track: float
    ssf: float
    front_weight: float
    wheel_radius: float
    wheel_width: float
    clearance: float
    belt: float          # height of the lower box's top (the belt line), m
    cabin_length: float  # length of the cabin box, m
    cabin_offset: float  # cabin centre behind the lower box's centre, m
    front_overhang: float
    corner_mass: float = 40.0   # unsprung: knuckle 20 kg + wheel 20 kg
    ride_hz: float = 2.0
    ride_zeta: float = 0.3
    roll_bar: float = 3.0         # anti-roll bars' roll stiffness / the springs' (per axle)
    steer_max_deg: float = 35.0
    drive_torque: float = 1500.0  # N m per rear wheel
    power: float = 150e3          # W at the rear wheels (a spinning wheel's torque is at most power / omega)
    brake_torque: float = 6000.0  # N m per wheel (beyond what a tyre can pass on at mu 1.2: the wheel locks)
    source: str = ""
    # crush (opt-in; off: the rigid boxes of before, nothing else in the model changes): CRASH3's
    # force per unit width F/w = A + B C per zone (A N/m, B N/m^2) and each zone's depth (m)
    crush: bool = False
    crush_front_a: float = 0.0
    crush_front_b: float = 0.0
    crush_front_depth: float = 0.0
    crush_rear_a: float = 0.0
    crush_rear_b: float = 0.0
    crush_rear_depth: float = 0.0
    crush_side_a: float = 0.0
    crush_side_b: float = 0.0
    crush_side_depth: float = 0.0

    @property
    def cg_height(self) -> float:
        """Height of the CoM above the road (m): SSF = track / (2 h)."""
        return self.track / (2.0 * self.ssf)

    @property
    def a(self) -> float:
        """CoM to front axle (m)."""
        return self.wheelbase * (1.0 - self.front_weight)

    @property
    def b(self) -> float:
        """CoM to rear axle (m)."""
        return self.wheelbase * self.front_weight

    @property
    def inertia(self) -> tuple[float, float, float]:
        """(roll, pitch, yaw) moments of inertia of the whole vehicle about its CoM, kg m^2."""
        yaw = self.mass * self.a * self.b
        return self.mass * (0.39 * self.track) ** 2, 0.9 * yaw, yaw

    def to_dict(self) -> dict:
        ix, iy, iz = self.inertia
        d = {"type": self.name, "label": self.label, "mass_kg": self.mass, "length_m": self.length,
             "width_m": self.width, "height_m": self.height, "wheelbase_m": self.wheelbase,
             "track_m": self.track, "ssf": self.ssf, "cg_height_m": _six(self.cg_height),
             "inertia_kg_m2": [_six(ix), _six(iy), _six(iz)], "wheel_radius_m": self.wheel_radius}
        if self.crush:
            d["crushes"] = True
        return d


def vehicle_type_from_dict(d: object, *, source: str = "<vehicle type>") -> VehicleType:
    """A vehicle type from its decoded data file (``models/crash/vehicles/NAME.json``).

    Args:
        d: the decoded JSON object: ``kind`` "nbst-crash-vehicle", ``schema_version`` 1, and the
            fields of :class:`VehicleType` (SI units; those with a default may be left out).
        source: how a refusal names the file.

    Returns:
        the :class:`VehicleType`.

    Raises:
        InputError: not such an object, a field missing, unknown or not of its type (one line
            naming ``source`` and the field).
    """
    if not isinstance(d, dict) or d.get("kind") != VEHICLE_KIND or d.get("schema_version") != 1:
        raise InputError(f"{source}: must be a JSON object with kind {VEHICLE_KIND!r} and schema_version 1")
    fields = {f.name: f for f in dataclasses.fields(VehicleType)}
    values = {k: v for k, v in d.items() if k not in ("kind", "schema_version")}
    for k, v in values.items():
        f = fields.get(k)
        if f is None:
            raise InputError(f"{source}: {k}: unknown field; the fields are {', '.join(fields)}")
        text = f.type == "str"
        if f.type == "bool":
            if not isinstance(v, bool):
                raise InputError(f"{source}: {k}: must be true or false, got {v!r}")
            continue
        if (not isinstance(v, str)) if text else (isinstance(v, bool) or not isinstance(v, (int, float))
                                                 or not math.isfinite(v)):
            raise InputError(f"{source}: {k}: must be {'a string' if text else 'a finite number'}, got {v!r}")
    missing = [k for k, f in fields.items() if f.default is dataclasses.MISSING and k not in values]
    if missing:
        raise InputError(f"{source}: {missing[0]}: missing")
    kwargs: dict[str, Any] = {k: v if isinstance(v, (str, bool)) else float(v) for k, v in values.items()}
    vt = VehicleType(**kwargs)
    if vt.crush:
        for z in ("front", "rear", "side"):
            for part in ("a", "b", "depth"):
                if not getattr(vt, f"crush_{z}_{part}") > 0:
                    raise InputError(f"{source}: crush_{z}_{part}: must be > 0 when crush is true")
        if vt.crush_front_depth + vt.crush_rear_depth >= 0.8 * vt.length or 2 * vt.crush_side_depth >= 0.8 * vt.width:
            raise InputError(f"{source}: crush_*_depth: the crush zones must leave a core (front + rear < 80 % of "
                             "the length, twice the side < 80 % of the width)")
    return vt


def _builtin(file: str) -> VehicleType:
    text = resources.files("nbst.models.crash").joinpath("vehicles", file).read_text(encoding="utf-8")
    return vehicle_type_from_dict(json.loads(text), source=f"<built-in vehicle {file}>")


#: The built-in vehicle types, registered once (a script's ``type`` names one; listed in this
#: order): a new one is a JSON file in ``models/crash/vehicles/`` and one line here.
VEHICLE_TYPES: Registry[VehicleType] = Registry("vehicle type")
VEHICLE_TYPES.register("sedan", _builtin("sedan.json"), help="a mid-size sedan (2018 Toyota Camry class), 1,450 kg")
VEHICLE_TYPES.register("suv", _builtin("suv.json"), help="a mid-size SUV, 2,000 kg")
VEHICLE_TYPES.register("van", _builtin("van.json"), help="a full-size van (light truck), 2,500 kg")
# the crushing twins (opt-in: a script names them; docs/crash.md "Crush")
VEHICLE_TYPES.register("sedan-crush", _builtin("sedan-crush.json"), help="the sedan with crush zones (CRASH3 A, B)")
VEHICLE_TYPES.register("suv-crush", _builtin("suv-crush.json"), help="the SUV with crush zones (CRASH3 A, B)")
VEHICLE_TYPES.register("van-crush", _builtin("van-crush.json"), help="the van with crush zones (CRASH3 A, B)")


def _six(x: float) -> float:
    """x to 6 significant digits: numbers MuJoCo's XML writer keeps exactly."""
    return float(f"{float(x):.6g}")


def control_names(prefix: str) -> list[str]:
    """Actuator names of vehicle ``prefix``, in control order."""
    return [f"{prefix}_{c}" for c in CONTROLS]


def corner_positions(vt: VehicleType) -> np.ndarray:
    """(4, 3) wheel centres in the body frame (CoM origin) at static ride height, corners in
    :data:`CORNERS` order."""
    z = vt.wheel_radius - vt.cg_height
    return np.array([[vt.a, vt.track / 2, z], [vt.a, -vt.track / 2, z],
                     [-vt.b, vt.track / 2, z], [-vt.b, -vt.track / 2, z]])


def _sprung(vt: VehicleType) -> tuple[float, np.ndarray, np.ndarray]:
    """(mass, CoM offset (3,), diagonal inertia (3,)) of the sprung body such that the whole
    vehicle (body plus four corners of ``corner_mass`` at the wheel centres) has ``vt``'s mass,
    CoM at the body origin and inertia."""
    mc = vt.corner_mass
    wheels = corner_positions(vt)
    points = [(mc, p) for p in wheels] + crush_mod.crush_masses(vt)  # corners, and the crush bodies of a crushing type
    ms = vt.mass - sum(m for m, _ in points)
    com = -sum(m * p for m, p in points) / ms  # so that the total CoM is the origin
    ix, iy, iz = vt.inertia
    corner = np.zeros(3)
    for m, p in points:  # point masses (their own inertia is small)
        corner += m * np.array([p[1] ** 2 + p[2] ** 2, p[0] ** 2 + p[2] ** 2, p[0] ** 2 + p[1] ** 2])
    body = ms * np.array([com[1] ** 2 + com[2] ** 2, com[0] ** 2 + com[2] ** 2, com[0] ** 2 + com[1] ** 2])
    inertia = np.array([ix, iy, iz]) - corner - body
    return ms, com, inertia


def heading_quat(heading: float) -> list[float]:
    """Quaternion (w, x, y, z) of a yaw of ``heading`` rad about z."""
    return [math.cos(heading / 2), 0.0, 0.0, math.sin(heading / 2)]


def add_vehicle(spec, vt: VehicleType, prefix: str, *, pos=(0.0, 0.0), heading: float = 0.0,
                rgba=(0.8, 0.2, 0.2, 1.0)) -> None:
    """Add vehicle ``prefix`` of type ``vt`` to ``spec``, its CoM at ``pos`` (x, y; the wheels on
    the road z = 0), facing ``heading`` (rad, counter-clockwise from +x)."""
    import mujoco

    GT = mujoco.mjtGeom
    ms, com, inertia = _sprung(vt)
    body = spec.worldbody.add_body(name=prefix, pos=[_six(pos[0]), _six(pos[1]), _six(vt.cg_height)],
                                   quat=[_six(q) for q in heading_quat(heading)])
    body.add_freejoint(name=f"{prefix}_free")
    body.explicitinertial = True
    body.mass = _six(ms)
    body.ipos = [_six(c) for c in com]
    body.inertia = [_six(c) for c in inertia]
    h = vt.cg_height
    front = vt.a + vt.front_overhang
    rear = front - vt.length
    lower_h = vt.belt - vt.clearance
    mid = (front + rear) / 2  # the lower box's centre before any crush zone takes its ends
    if vt.crush:  # the core between the crush zones (they take the rest of the lower box)
        front, rear = front - vt.crush_front_depth, rear + vt.crush_rear_depth
    half_w = vt.width / 2 - (vt.crush_side_depth if vt.crush else 0.0)
    lower = body.add_geom(name=f"{prefix}_lower", type=GT.mjGEOM_BOX,
                          size=[_six((front - rear) / 2), _six(half_w), _six(lower_h / 2)],
                          pos=[_six((front + rear) / 2), 0.0, _six(vt.clearance + lower_h / 2 - h)], rgba=list(rgba))
    cab_h = vt.height - vt.belt
    cabin = body.add_geom(name=f"{prefix}_cabin", type=GT.mjGEOM_BOX,
                          size=[_six(vt.cabin_length / 2), _six(0.44 * vt.width), _six(cab_h / 2)],
                          pos=[_six(mid - vt.cabin_offset), 0.0, _six(vt.belt + cab_h / 2 - h)],
                          rgba=[0.75 * c for c in rgba[:3]] + [rgba[3]])
    for g in (lower, cabin):
        _body_contact(g)
        g.mass = 0.0
    if vt.crush:
        crush_mod.add_crush(spec, body, vt, prefix, rgba, contype=BIT_BODY, conaffinity=BIT_STATIC | BIT_BODY,
                            friction=BODY_CONTACT.friction)
    k = _six(_corner_load(vt, 0) / G * (2 * math.pi * vt.ride_hz) ** 2)
    kr = _six(_corner_load(vt, 2) / G * (2 * math.pi * vt.ride_hz) ** 2)
    for i, (c, p) in enumerate(zip(CORNERS, corner_positions(vt))):
        stiff = k if i < 2 else kr
        load = _corner_load(vt, i)
        knuckle = body.add_body(name=f"{prefix}_knuckle_{c}", pos=[_six(v) for v in p])
        # the knuckle's mass (hub, brake, a share of the links) on a small sphere that touches nothing
        # (MuJoCo's XML writer drops an explicit <inertial> of a body without geoms)
        hub = knuckle.add_geom(name=f"{prefix}_hub_{c}", type=GT.mjGEOM_SPHERE, size=[0.12, 0, 0],
                               mass=_six(vt.corner_mass / 2), rgba=[0.3, 0.3, 0.3, 1.0], group=3)
        hub.contype = hub.conaffinity = 0
        m_corner = load / G + vt.corner_mass
        susp = knuckle.add_joint(name=f"{prefix}_susp_{c}", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 0, 1])
        susp.stiffness = [stiff, 0.0, 0.0]
        susp.springref = _six(-load / stiff)  # the spring carries the corner's static load at q = 0
        susp.damping = [_six(2 * vt.ride_zeta * math.sqrt(stiff * m_corner)), 0.0, 0.0]
        susp.limited = mujoco.mjtLimited.mjLIMITED_TRUE
        susp.range = [-0.12, 0.10]
        susp.armature = 0.0
        if i < 2:
            steer = knuckle.add_joint(name=f"{prefix}_steer_{c}", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 0, 1])
            steer.limited = mujoco.mjtLimited.mjLIMITED_TRUE
            lim = _six(math.radians(vt.steer_max_deg + 5))
            steer.range = [-lim, lim]
            steer.damping = [50.0, 0.0, 0.0]
        wheel = knuckle.add_body(name=f"{prefix}_wheel_{c}")
        wheel.add_joint(name=f"{prefix}_spin_{c}", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 1, 0])
        tyre = wheel.add_geom(name=f"{prefix}_tyre_{c}", type=GT.mjGEOM_ELLIPSOID,
                              size=[vt.wheel_radius, _six(vt.wheel_width / 2), vt.wheel_radius],
                              mass=_six(vt.corner_mass / 2), rgba=[0.1, 0.1, 0.1, 1.0])
        tyre.contype, tyre.conaffinity = BIT_TYRE, BIT_STATIC
        tyre.condim = 3
        tyre.friction = [TYRE_FRICTION, 0.0, 0.0]
        tyre.solref = list(TYRE_SOLREF)
    for axle, stiff in (("f", k), ("r", kr)):  # anti-roll bars: a spring on left - right travel
        bar = spec.add_tendon(name=f"{prefix}_bar_{axle}")
        bar.stiffness = [_six(vt.roll_bar * stiff / 2), 0.0, 0.0]
        bar.springlength = [0.0, 0.0]
        bar.wrap_joint(f"{prefix}_susp_{axle}l", 1.0)
        bar.wrap_joint(f"{prefix}_susp_{axle}r", -1.0)
    _add_actuators(spec, vt, prefix)


def _corner_load(vt: VehicleType, i: int) -> float:
    """Static load (N) the suspension spring of corner ``i`` carries (sprung weight only)."""
    ms = vt.mass - 4 * vt.corner_mass
    share = vt.front_weight if i < 2 else 1.0 - vt.front_weight
    return ms * G * share / 2


def _body_contact(geom) -> None:
    geom.contype = BIT_BODY
    geom.conaffinity = BIT_STATIC | BIT_BODY
    geom.condim = 3
    geom.priority = 2
    geom.friction = [BODY_CONTACT.friction, 0.0, 0.0]
    geom.solref = [BODY_CONTACT.timeconst, BODY_CONTACT.dampratio]
    geom.solimp = list(BODY_CONTACT.solimp)


def _add_actuators(spec, vt: VehicleType, prefix: str) -> None:
    import mujoco

    T = mujoco.mjtTrn.mjTRN_JOINT
    lim = _six(math.radians(vt.steer_max_deg))
    kp = 20000.0
    for c in ("fl", "fr"):
        a = spec.add_actuator(name=f"{prefix}_steer_{c}", target=f"{prefix}_steer_{c}", trntype=T)
        a.gaintype = mujoco.mjtGain.mjGAIN_FIXED
        a.gainprm[0] = kp
        a.biastype = mujoco.mjtBias.mjBIAS_AFFINE
        a.biasprm[0:3] = [0.0, -kp, -400.0]
        a.ctrllimited = mujoco.mjtLimited.mjLIMITED_TRUE
        a.ctrlrange = [-lim, lim]
    for c in ("rl", "rr"):
        a = spec.add_actuator(name=f"{prefix}_drive_{c}", target=f"{prefix}_spin_{c}", trntype=T)
        a.gaintype = mujoco.mjtGain.mjGAIN_FIXED
        a.gainprm[0] = 1.0
        a.ctrllimited = mujoco.mjtLimited.mjLIMITED_TRUE
        a.ctrlrange = [-vt.drive_torque, vt.drive_torque]
    for c in CORNERS:
        a = spec.add_actuator(name=f"{prefix}_brake_{c}", target=f"{prefix}_spin_{c}", trntype=T)
        a.gaintype = mujoco.mjtGain.mjGAIN_AFFINE
        a.gainprm[0:3] = [0.0, 0.0, -BRAKE_KV]  # torque = -kv * omega * ctrl
        a.ctrllimited = mujoco.mjtLimited.mjLIMITED_TRUE
        a.ctrlrange = [0.0, 1.0]
        a.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
        a.forcerange = [-vt.brake_torque, vt.brake_torque]
