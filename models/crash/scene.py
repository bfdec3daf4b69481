"""A crash scene: a road and its vehicles as one MuJoCo model, with the sensors the outcome reads.

:func:`build_spec` puts the road (:mod:`.road`) and each vehicle (:mod:`.vehicle`, body
``v{i}``) into an ``MjSpec``, sets the options and adds the contact sensors:

* ``pair_{i}_{j}`` for every pair of vehicles i < j: ``contact subtree1=v{i} subtree2=v{j}
  data="found force pos" reduce="netforce"`` (7 numbers: how many contacts, the net force
  in the world frame, the force-weighted contact point);
* ``curb_{i}`` and ``barrier_{i}`` per vehicle, when the road has curbs or barriers
  (``data="found force"``, 4 numbers).

Options (docs/crash.md): the ``implicitfast`` integrator, pyramidal friction cones, warm-starting
**disabled** and sleeping off: a rollout run in chunks (drivers between them) then gives the same
numbers, bit for bit, as one ``mj_step`` loop with the same controls, on any number of threads
(the scout measured rest positions moving by up to 14 m from chunk boundaries alone with
warm-starting on).

The **XML** (:func:`scene_xml`) is written from the spec: every number in it was rounded to 6
significant digits when the spec was built (the digits MuJoCo's writer keeps), and the keyframe
is rewritten at full precision, so the model loaded from the text is the one that was simulated.
Every search and replay runs on the model compiled from that text.

Compute only.
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from nbst.models.crash import road as road_mod
from nbst.models.crash import vehicle as veh
from nbst.models.scene import full_precision

__all__ = ["COLOURS", "PAIR_SIZE", "STRIKE_SIZE", "SETTLE_TIME", "SceneVehicle", "vehicle_prefix",
           "build_spec", "scene_xml", "model_from_xml", "settled", "initial_state", "Layout", "layout"]

#: Vehicle colours (RGBA), in script order; the renderer reads them from the geoms.
COLOURS = ((0.80, 0.12, 0.12, 1.0), (0.15, 0.35, 0.80, 1.0), (0.95, 0.75, 0.10, 1.0), (0.15, 0.60, 0.25, 1.0),
           (0.92, 0.92, 0.92, 1.0), (0.55, 0.20, 0.65, 1.0), (0.95, 0.45, 0.10, 1.0), (0.20, 0.20, 0.20, 1.0))
#: Numbers per pair sensor (found, force xyz, pos xyz) and per curb/barrier sensor (found, force xyz).
PAIR_SIZE, STRIKE_SIZE = 7, 4
#: How long a vehicle settles on its springs before its start state is taken (s).
SETTLE_TIME = 1.5


@dataclass(frozen=True)
class SceneVehicle:
    """A vehicle of the scene: its body prefix (``v{i}``), type and start pose (x, y m; heading rad)."""

    prefix: str
    vtype: veh.VehicleType
    x: float
    y: float
    heading: float


def vehicle_prefix(i: int) -> str:
    return f"v{i}"


def build_spec(road: road_mod.Road, vehicles, *, timestep: float, name: str = "crash"):
    """The ``MjSpec`` of ``road`` with ``vehicles`` (SceneVehicle list) at step ``timestep`` s."""
    import mujoco

    spec = mujoco.MjSpec()
    spec.compiler.degree = False  # every angle below is in radians
    spec.modelname = "".join(ch if ch.isalnum() or ch in "_-." else "_" for ch in name)[:64] or "crash"
    spec.option.timestep = float(timestep)
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.option.cone = mujoco.mjtCone.mjCONE_PYRAMIDAL
    spec.option.disableflags |= mujoco.mjtDisableBit.mjDSBL_WARMSTART
    spec.visual.global_.offwidth = 1280
    spec.visual.global_.offheight = 720
    statics = road_mod.add_road(spec, road)
    for i, v in enumerate(vehicles):
        veh.add_vehicle(spec, v.vtype, v.prefix, pos=(v.x, v.y), heading=v.heading, rgba=COLOURS[i % len(COLOURS)])
        if v.vtype.crush and statics["barriers"]:  # a crushing front meets a wall with its crush zone, as it
            for c in veh.CORNERS:                   # meets another vehicle: its wheels pass (they touch no vehicle)
                spec.add_exclude(bodyname1=f"{v.prefix}_wheel_{c}", bodyname2="barriers")
    n = len(vehicles)
    for i in range(n):
        for j in range(i + 1, n):
            _contact_sensor(spec, f"pair_{i}_{j}", vehicles[i].prefix, vehicles[j].prefix, "subtree", pos=True)
    for i in range(n):
        for what in ("curb", "barrier"):
            if statics[what + "s"]:
                _contact_sensor(spec, f"{what}_{i}", vehicles[i].prefix, what + "s", "body", pos=False)
    return spec


def _contact_sensor(spec, name, subtree, other, kind, *, pos: bool) -> None:
    """A contact sensor, net force (and point) of the contacts between ``subtree`` and ``other``
    (a subtree or a body, per ``kind``)."""
    import mujoco

    s = spec.add_sensor(name=name, type=mujoco.mjtSensor.mjSENS_CONTACT)
    s.objtype = mujoco.mjtObj.mjOBJ_XBODY  # subtree1: the vehicle
    s.objname = subtree
    s.reftype = mujoco.mjtObj.mjOBJ_XBODY if kind == "subtree" else mujoco.mjtObj.mjOBJ_BODY
    s.refname = other
    # intprm: (data bits, reduce, num): found=1, force=2, pos=16; reduce netforce = 3
    data = 1 | 2 | (16 if pos else 0)
    s.intprm[0:3] = [data, 3, 1]


def scene_xml(spec) -> str:
    """MJCF text of ``spec`` whose model equals ``spec.compile()``'s bit for bit (see the module
    docstring); the keyframes at full precision."""
    spec.compile()
    return full_precision(spec.to_xml(), spec, exact_attrs={"key": ("time", "qpos", "qvel", "ctrl")})


def model_from_xml(xml: str):
    """The MjModel of scene text ``xml`` (what every rollout and replay runs on)."""
    import mujoco

    return mujoco.MjModel.from_xml_string(xml)


# --------------------------------------------------------------------------- state

@functools.lru_cache(maxsize=32)
def settled(type_name: str, timestep: float) -> tuple:
    """(body z, body pitch quaternion (4,), suspension q (4,)) of a vehicle of ``type_name``
    resting on a flat road after :data:`SETTLE_TIME` s at step ``timestep``: the start of
    every rollout, so that no vehicle bounces on its springs at t = 0."""
    import mujoco

    r = road_mod.Road(layout="straight", width=10.0, length=40.0)
    spec = build_spec(r, [SceneVehicle("v0", veh.VEHICLE_TYPES[type_name], 0.0, 0.0, 0.0)], timestep=timestep)
    m = spec.compile()
    d = mujoco.MjData(m)
    mujoco.mj_step(m, d, nstep=int(round(SETTLE_TIME / timestep)))
    q = d.qpos
    susp = tuple(float(d.joint(f"v0_susp_{c}").qpos[0]) for c in veh.CORNERS)
    return float(q[2]), tuple(float(x) for x in q[3:7]), susp


def _quat_mul(a, b):
    w1, x1, y1, z1 = a
    w2, x2, y2, z2 = b
    return (w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2)


def initial_state(model, vehicles, speeds) -> tuple[np.ndarray, np.ndarray]:
    """(qpos, qvel) of the scene: each vehicle settled on its springs at its start pose, moving
    at ``speeds[i]`` m/s along its heading, its wheels rolling at that speed, steering straight."""
    qpos = np.array(model.qpos0, dtype=float)
    qvel = np.zeros(model.nv)
    dt = float(model.opt.timestep)
    for v, speed in zip(vehicles, speeds):
        z, qpitch, susp = settled(v.vtype.name, dt)
        j = model.joint(f"{v.prefix}_free")
        a, b = int(j.qposadr[0]), int(j.dofadr[0])
        qyaw = veh.heading_quat(v.heading)
        qpos[a:a + 7] = [v.x, v.y, z, *_quat_mul(qyaw, qpitch)]
        c, s = math.cos(v.heading), math.sin(v.heading)
        qvel[b:b + 3] = [speed * c, speed * s, 0.0]
        for corner, q in zip(veh.CORNERS, susp):
            qpos[model.joint(f"{v.prefix}_susp_{corner}").qposadr[0]] = q
            qvel[model.joint(f"{v.prefix}_spin_{corner}").dofadr[0]] = speed / v.vtype.wheel_radius
    return qpos, qvel


@dataclass(frozen=True)
class Layout:
    """Where each vehicle's numbers live in qpos/qvel/ctrl/sensordata (arrays of indices)."""

    n: int
    qpos: np.ndarray      # (n,) free joint's qpos address
    qvel: np.ndarray      # (n,) free joint's dof address
    ctrl: np.ndarray      # (n, 8) actuator ids in vehicle.CONTROLS order
    spin: np.ndarray      # (n, 4) dof addresses of the spin hinges
    steer: np.ndarray     # (n, 2) qpos addresses of the steer hinges
    pairs: list           # [(i, j)] in sensor order
    pair_adr: np.ndarray  # (npairs,) sensordata address of each pair sensor
    curb_adr: np.ndarray  # (n,) address of curb_{i}, -1 when the road has no curbs
    barrier_adr: np.ndarray
    mass: np.ndarray      # (n,) whole-vehicle mass (kg)


def layout(model, n: int) -> Layout:
    """The :class:`Layout` of a scene with ``n`` vehicles ``v0`` .. ``v{n-1}``."""
    pre = [vehicle_prefix(i) for i in range(n)]
    qpos = np.array([model.joint(f"{p}_free").qposadr[0] for p in pre], dtype=int)
    qvel = np.array([model.joint(f"{p}_free").dofadr[0] for p in pre], dtype=int)
    ctrl = np.array([[model.actuator(a).id for a in veh.control_names(p)] for p in pre], dtype=int).reshape(n, -1)
    spin = np.array([[model.joint(f"{p}_spin_{c}").dofadr[0] for c in veh.CORNERS] for p in pre], dtype=int)
    steer = np.array([[model.joint(f"{p}_steer_{c}").qposadr[0] for c in ("fl", "fr")] for p in pre], dtype=int)
    pairs = [(i, j) for i in range(n) for j in range(i + 1, n)]
    pair_adr = np.array([model.sensor(f"pair_{i}_{j}").adr[0] for i, j in pairs], dtype=int)

    def adr(name):
        try:
            return int(model.sensor(name).adr[0])
        except KeyError:
            return -1
    curb = np.array([adr(f"curb_{i}") for i in range(n)], dtype=int)
    barrier = np.array([adr(f"barrier_{i}") for i in range(n)], dtype=int)
    mass = np.array([model.body_subtreemass[model.body(p).id] for p in pre])
    return Layout(n=n, qpos=qpos, qvel=qvel, ctrl=ctrl, spin=spin, steer=steer, pairs=pairs, pair_adr=pair_adr,
                  curb_adr=curb, barrier_adr=barrier, mass=mass)


# --------------------------------------------------------------------------- the barrier pulse
