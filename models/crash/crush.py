"""Crush zones: CRASH3's force per unit width A + B C on MuJoCo, residual crush and EES.

A crushing vehicle type (``crush`` true in its data file: ``sedan-crush``, ``suv-crush``,
``van-crush``; docs/crash.md "Crush") has four zones, front, rear, left and right
(:func:`crush_zones`). The lower box keeps a core and each zone is a slab on a chain of slide
joints ``{prefix}_crush_{zone}_{k}`` (:func:`add_crush`):

* **plastic**: each joint's dry friction (``frictionloss``) is one step of CRASH3's line
  F / w = A + B C (Campbell's linear model as NHTSA's CRASH3 uses it), its travel one step's
  depth; a joint keeps what it crushed, so the sum of a zone's joints is its residual crush
  (:func:`crush_residual`);
* **elastic**: the unloading law, two springs in series between the body and the steps: a
  stiff one (:data:`CRUSH_ELASTIC_DEFLECTION` at the first yield force: its energy grows with
  the square of the force reached) and a soft one with a stop, full at the first yield force,
  that holds ½ m v_b² (:data:`CRUSH_BUMPER_SPEED`: a bumper's elastic range). What they hold is
  all that comes back (the slab contact and the steps' travel limits are dampers), so
  restitution falls with speed: the soft element's energy is fixed while the crush energy grows;
* **energy**: CRASH3's crush energy of a residual crush, w (A C + B C^2 / 2 + A^2 / (2 B)) per
  zone (:meth:`CrushZone.energy`), and the energy-equivalent speed EES = sqrt(2 E / m)
  (:func:`crush_ees`); the crash file's ``crush`` entry (:func:`crush_record`).

A vehicle type here is read by its attributes (``crush``, ``crush_front_a`` ...: the fields of
:class:`nbst.models.crash.vehicle.VehicleType`); the vehicle module builds the bodies and calls
:func:`add_crush` with its contact bits. Plain MJCF: no controller, so a crash with crush replays
and exports bit for bit.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["CRUSH_ZONES", "CRUSH_STEPS", "CRUSH_LINK_MASS", "CRUSH_SLAB_MASS", "CRUSH_SOLREF", "CRUSH_SOLIMP",
           "CRUSH_ELASTIC_DEFLECTION", "CRUSH_ELASTIC_ZETA", "CRUSH_ELASTIC_SHARE", "CRUSH_BUMPER_SPEED",
           "CRUSH_BUMPER_ZETA", "CRUSH_BUMPER_SHARE", "CRUSH_MIN_RESIDUAL", "CRUSH_JOINT_SOLREF", "CRUSH_LIMIT_SOLREF",
           "CRUSH_JOINT_SOLIMP", "CrushZone", "crush_zones", "crush_masses", "crush_joint_names",
           "add_crush", "crush_residual", "crush_energy", "crush_ees", "crush_record"]


def _six(x: float) -> float:
    """x to 6 significant digits: numbers MuJoCo's XML writer keeps exactly."""
    return float(f"{float(x):.6g}")


#: Crush zones, in the order of every per-zone list.
CRUSH_ZONES = ("front", "rear", "left", "right")
#: Plastic elements per zone: the force-crush line A + B C is a staircase of this many steps
#: (each step's force at its mid-depth, so each step's energy is the line's exactly).
CRUSH_STEPS = {"front": 6, "rear": 6, "left": 4, "right": 4}
#: Mass (kg) of each inner link of a zone's chain and of the zone's outer slab (taken out of the
#: sprung mass: the vehicle's mass, CoM and inertia stay those of its type).
CRUSH_LINK_MASS = 5.0
CRUSH_SLAB_MASS = {"front": 30.0, "rear": 25.0, "left": 15.0, "right": 15.0}
#: The slabs' contact: MuJoCo's direct reference (negative solref: stiffness 400 s^-2, damping
#: 250 s^-1, so the reference acceleration is -250 v - 400 r), heavily overdamped (ratio 6): it
#: stops a slab in ~4 ms and would recover its penetration over ~0.6 s, so through an impact it
#: gives back next to nothing and the rebound is the elastic elements'. Its rates are the same at
#: every step (a time constant of 20 ms critically damped gave back its penetration under load:
#: 1-2 kJ in a car-to-car rebound, twice as much at 2 ms as at 0.5 ms). Impedance 0.99.
CRUSH_SOLREF = (-400.0, -250.0)
CRUSH_SOLIMP = (0.99, 0.99, 0.001, 0.5, 2.0)
#: The stiff elastic element: a joint spring deflecting ``CRUSH_ELASTIC_DEFLECTION`` m at the
#: zone's first yield force (the unloading line's slope: it holds F^2 / 2k at the force F
#: reached), damped at ``CRUSH_ELASTIC_ZETA`` of critical for the vehicle's mass, on a link of
#: ``CRUSH_ELASTIC_SHARE`` of the vehicle's mass. 0 deflection: no elastic elements.
CRUSH_ELASTIC_DEFLECTION = 0.007
CRUSH_ELASTIC_ZETA = 0.2
CRUSH_ELASTIC_SHARE = {"front": 0.052, "rear": 0.052, "left": 0.026, "right": 0.026}
#: The soft elastic element: a joint spring with a stop, reaching the stop at the zone's first
#: yield force and holding then ½ m v_b² with v_b = ``CRUSH_BUMPER_SPEED`` m/s (3 km/h: the
#: elastic range of a bumper system; 49 CFR 581 tests bumpers at 2.5 mph, 4 km/h), damped at
#: ``CRUSH_BUMPER_ZETA`` of critical for the vehicle's mass, on a link of ``CRUSH_BUMPER_SHARE`` of
#: the vehicle's mass. Heavy links (the sedan's: 75 kg each on a full-width zone; in proportion to
#: the mass, as the springs' stiffness is to the yield force) keep the restitution close at 2, 1
#: and 0.5 ms steps: with a 40 kg link and 5 kg steps the 2 ms step gave back twice the 0.5 ms
#: step's energy through the steps' soft friction and limits.
CRUSH_BUMPER_SPEED = 3.0 / 3.6
CRUSH_BUMPER_ZETA = 0.3
CRUSH_BUMPER_SHARE = {"front": 0.052, "rear": 0.052, "left": 0.026, "right": 0.026}
#: Residual crush below this (m) is no damage: a loaded zone's joints creep by a millimetre or
#: two (braking, a blow on another zone), which CRASH3's energy must not read as crush (its
#: A^2 / 2B term alone is 4 kJ for the sedan's rear).
CRUSH_MIN_RESIDUAL = 0.005
#: The plastic joints' dry friction (and the elastic elements' travel limits): as hard as
#: MuJoCo's constraints go (impedance 0.9999), so that a joint loaded below its yield force creeps
#: by at most ~1 cm through a crash (a softer one slides like a damper: every step yields at once).
CRUSH_JOINT_SOLREF = (0.004, 1.0)
#: The plastic steps' travel limits: a damper (reference -500 v - r), so that a step that
#: reaches its end stops in ~2 ms and no spring pushes it back (with the friction's 4 ms time
#: constant, critically damped, a full step pushed back under load and returned up to 2 kJ).
CRUSH_LIMIT_SOLREF = (-1.0, -500.0)
CRUSH_JOINT_SOLIMP = (0.9999, 0.9999, 0.001, 0.5, 2.0)


@dataclass(frozen=True)
class CrushZone:
    """One crush zone of a vehicle (body frame): its slab's centre and half sizes, the inward
    unit ``axis`` along which it crushes, the crush width ``width`` (m), CRASH3's ``a`` (N/m)
    and ``b`` (N/m^2), the ``depth`` (m) it can crush and its ``steps``."""

    name: str
    axis: tuple
    centre: tuple
    half: tuple
    width: float
    a: float
    b: float
    depth: float
    steps: int

    def step_forces(self) -> np.ndarray:
        """Each plastic element's yield force (N): w (A + B c) at the mid-depth c of its step."""
        d = self.depth / self.steps
        return self.width * (self.a + self.b * (np.arange(self.steps) + 0.5) * d)

    def energy(self, c: float) -> float:
        """CRASH3's crush energy (J) of a residual crush ``c`` (m) across the zone's width:
        w (A c + B c^2 / 2 + A^2 / (2 B)) for c >= :data:`CRUSH_MIN_RESIDUAL` (the last term:
        the energy taken without residual crush, below the no-damage speed), 0 below it."""
        if c < CRUSH_MIN_RESIDUAL:
            return 0.0
        return self.width * (self.a * c + self.b * c * c / 2 + self.a ** 2 / (2 * self.b))


def crush_zones(vt) -> list[CrushZone]:
    """The four :class:`CrushZone` of a crushing type (front and rear full width, the sides
    between them), [] for a rigid one."""
    if not vt.crush:
        return []
    front = vt.a + vt.front_overhang
    rear = front - vt.length
    zc = (vt.clearance + vt.belt) / 2 - vt.cg_height
    hz = (vt.belt - vt.clearance) / 2
    fd, rd, sd = vt.crush_front_depth, vt.crush_rear_depth, vt.crush_side_depth
    w = vt.width
    ls = vt.length - fd - rd
    xs = (rear + rd + front - fd) / 2
    return [
        CrushZone("front", (-1.0, 0.0, 0.0), (front - fd / 2, 0.0, zc), (fd / 2, w / 2, hz), w,
                  vt.crush_front_a, vt.crush_front_b, fd, CRUSH_STEPS["front"]),
        CrushZone("rear", (1.0, 0.0, 0.0), (rear + rd / 2, 0.0, zc), (rd / 2, w / 2, hz), w,
                  vt.crush_rear_a, vt.crush_rear_b, rd, CRUSH_STEPS["rear"]),
        CrushZone("left", (0.0, -1.0, 0.0), (xs, w / 2 - sd / 2, zc), (ls / 2, sd / 2, hz), ls,
                  vt.crush_side_a, vt.crush_side_b, sd, CRUSH_STEPS["left"]),
        CrushZone("right", (0.0, 1.0, 0.0), (xs, -(w / 2 - sd / 2), zc), (ls / 2, sd / 2, hz), ls,
                  vt.crush_side_a, vt.crush_side_b, sd, CRUSH_STEPS["right"]),
    ]


def crush_masses(vt) -> list[tuple[float, np.ndarray]]:
    """(mass, position) of every crush body (links and slab) of ``vt``, body frame."""
    out = []
    for z in crush_zones(vt):
        el = _six(CRUSH_ELASTIC_SHARE[z.name] * vt.mass) if CRUSH_ELASTIC_DEFLECTION > 0 else 0.0
        el += _six(CRUSH_BUMPER_SHARE[z.name] * vt.mass) if CRUSH_BUMPER_SPEED > 0 else 0.0
        out.append(((z.steps - 1) * CRUSH_LINK_MASS + CRUSH_SLAB_MASS[z.name] + el, np.array(z.centre)))
    return out


def crush_joint_names(prefix: str, zone: CrushZone) -> list[str]:
    """The plastic joints of ``zone`` of vehicle ``prefix``, outermost last."""
    return [f"{prefix}_crush_{zone.name}_{k}" for k in range(zone.steps)]


def add_crush(spec, body, vt, prefix: str, rgba, *, contype: int, conaffinity: int, friction: float) -> None:
    """The crush zones of ``vt`` on ``body``: per zone a chain of ``steps`` bodies on slide
    joints along the zone's inward axis, each joint with dry friction (``frictionloss``) equal
    to its step's force and a travel of one step, the outermost carrying the zone's slab; the
    vehicle's own crush bodies and its body do not collide with one another."""
    import mujoco

    GT = mujoco.mjtGeom
    slabs = []
    for z in crush_zones(vt):
        forces = z.step_forces()
        step = z.depth / z.steps
        parent = body
        if CRUSH_ELASTIC_DEFLECTION > 0:
            parent = body.add_body(name=f"{prefix}_crush_{z.name}_elastic_link", pos=[_six(c) for c in z.centre])
            k_el = forces[0] / CRUSH_ELASTIC_DEFLECTION
            j = parent.add_joint(name=f"{prefix}_crush_{z.name}_elastic", type=mujoco.mjtJoint.mjJNT_SLIDE,
                                 axis=list(z.axis))
            j.stiffness = [_six(k_el), 0.0, 0.0]
            j.damping = [_six(2 * CRUSH_ELASTIC_ZETA * math.sqrt(k_el * vt.mass)), 0.0, 0.0]
            j.limited = mujoco.mjtLimited.mjLIMITED_TRUE
            j.range = [-0.01, _six(1.5 * forces[-1] / k_el)]
            j.solref_limit = list(CRUSH_JOINT_SOLREF)
            j.solimp_limit = list(CRUSH_JOINT_SOLIMP)
            g = parent.add_geom(name=f"{prefix}_crush_{z.name}_elastic_mass", type=GT.mjGEOM_SPHERE, size=[0.02, 0, 0],
                                mass=_six(CRUSH_ELASTIC_SHARE[z.name] * vt.mass), rgba=[0.3, 0.3, 0.3, 1.0], group=3)
            g.contype = g.conaffinity = 0
        if CRUSH_BUMPER_SPEED > 0:  # the soft element: at its stop at the first yield force, holding 1/2 m v_b^2
            travel = vt.mass * CRUSH_BUMPER_SPEED ** 2 / forces[0]
            k_b = forces[0] / travel
            prev = parent
            parent = prev.add_body(name=f"{prefix}_crush_{z.name}_bumper_link",
                                   pos=[_six(c) for c in z.centre] if prev is body else [0.0, 0.0, 0.0])
            j = parent.add_joint(name=f"{prefix}_crush_{z.name}_bumper", type=mujoco.mjtJoint.mjJNT_SLIDE,
                                 axis=list(z.axis))
            j.stiffness = [_six(k_b), 0.0, 0.0]
            j.damping = [_six(2 * CRUSH_BUMPER_ZETA * math.sqrt(k_b * vt.mass)), 0.0, 0.0]
            j.limited = mujoco.mjtLimited.mjLIMITED_TRUE
            j.range = [-0.01, _six(travel)]
            j.solref_limit = list(CRUSH_JOINT_SOLREF)
            j.solimp_limit = list(CRUSH_JOINT_SOLIMP)
            g = parent.add_geom(name=f"{prefix}_crush_{z.name}_bumper_mass", type=GT.mjGEOM_SPHERE, size=[0.02, 0, 0],
                                mass=_six(CRUSH_BUMPER_SHARE[z.name] * vt.mass), rgba=[0.3, 0.3, 0.3, 1.0], group=3)
            g.contype = g.conaffinity = 0
        for k, name in enumerate(crush_joint_names(prefix, z)):  # the plastic steps, links of CRUSH_LINK_MASS
            last = k == z.steps - 1
            link = parent.add_body(name=f"{prefix}_crush_{z.name}" if last else f"{name}_link",
                                   pos=[_six(c) for c in z.centre] if k == 0 and parent is body else [0.0, 0.0, 0.0])
            j = link.add_joint(name=name, type=mujoco.mjtJoint.mjJNT_SLIDE, axis=list(z.axis))
            j.frictionloss = _six(forces[k])
            j.limited = mujoco.mjtLimited.mjLIMITED_TRUE
            j.range = [0.0, _six(step)]
            j.solref_friction = list(CRUSH_JOINT_SOLREF)
            j.solimp_friction = list(CRUSH_JOINT_SOLIMP)
            j.solref_limit = list(CRUSH_LIMIT_SOLREF)
            j.solimp_limit = list(CRUSH_JOINT_SOLIMP)
            if not last:  # a link's mass on a small sphere that touches nothing (see the hubs)
                g = link.add_geom(name=f"{name}_mass", type=GT.mjGEOM_SPHERE, size=[0.02, 0, 0],
                                  mass=_six(CRUSH_LINK_MASS), rgba=[0.3, 0.3, 0.3, 1.0], group=3)
                g.contype = g.conaffinity = 0
            parent = link
        slab = parent  # the last link carries the slab
        g = slab.add_geom(name=f"{prefix}_crush_{z.name}", type=GT.mjGEOM_BOX, size=[_six(h) for h in z.half],
                          mass=_six(CRUSH_SLAB_MASS[z.name]), rgba=list(rgba))
        g.contype = contype
        g.conaffinity = conaffinity
        g.condim = 3
        g.priority = 3
        g.friction = [friction, 0.0, 0.0]
        g.solref = list(CRUSH_SOLREF)
        g.solimp = list(CRUSH_SOLIMP)
        slabs.append(slab.name)
    for i, a in enumerate(slabs):
        spec.add_exclude(bodyname1=prefix, bodyname2=a)
        for b in slabs[i + 1:]:
            spec.add_exclude(bodyname1=a, bodyname2=b)


def crush_residual(model, prefix: str, vt, qpos) -> dict:
    """{zone: crush (m)} of vehicle ``prefix`` (type ``vt``) in state ``qpos``: the sum of the
    zone's plastic joints (what stays once the contact lets go: the residual crush); {} for a
    rigid type."""
    out = {}
    for z in crush_zones(vt):
        out[z.name] = float(sum(qpos[model.joint(n).qposadr[0]] for n in crush_joint_names(prefix, z)))
    return out


def crush_energy(vt, residual: dict) -> dict:
    """{zone: CRASH3 crush energy (J)} of ``residual`` ({zone: m})."""
    return {z.name: z.energy(max(0.0, residual.get(z.name, 0.0))) for z in crush_zones(vt)}


def crush_ees(vt, residual: dict) -> float:
    """Energy-equivalent speed (m/s): sqrt(2 E / m), E the crush energy of all zones."""
    return math.sqrt(2.0 * sum(crush_energy(vt, residual).values()) / vt.mass)


def crush_record(model, prefix: str, vt, qpos) -> dict | None:
    """The crash file's ``crush`` entry of a vehicle (docs/formats: per zone the residual crush,
    width, A, B and energy; the total energy and the EES), None for a rigid type."""
    if not vt.crush:
        return None
    res = crush_residual(model, prefix, vt, qpos)
    en = crush_energy(vt, res)
    zones = {z.name: {"residual_m": round(res[z.name], 4), "width_m": _six(z.width), "A_N_per_m": z.a,
                      "B_N_per_m2": z.b, "energy_J": round(en[z.name], 1)} for z in crush_zones(vt)}
    return {"zones": zones, "energy_J": round(sum(en.values()), 1),
            "ees_kmh": round(crush_ees(vt, res) * 3.6, 2)}
