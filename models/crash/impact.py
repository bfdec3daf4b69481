"""Each impact's velocity change (Delta-v) and principal direction of force (PDOF), from a crash's motion.

A reconstructionist's quantities, per vehicle per impact:

* **impact speed**: the speed of the vehicle's centre of mass just before the contact;
* **Delta-v**: the change of its centre of mass's velocity over the contact episode, as a vector
  (world frame and vehicle frame: x forward, y left) and its magnitude;
* **PDOF**: where the force on the vehicle comes from, in its own frame at the first touch, as an
  angle (0 deg: from straight ahead, clockwise positive seen from above: 90 deg from the right)
  and as a clock direction (12 o'clock: straight ahead, 3 o'clock: the right side, 6: behind,
  9: the left side), SAE J224's convention (*Collision Deformation Classification*). The force
  on the vehicle points along its Delta-v, so it comes from the opposite direction.

**The contact episode.** The scene's pair sensor (``contact subtree1 subtree2``) says at every
step whether two vehicles touch; an episode is a run of touching steps with no gap longer than
:data:`CONTACT_GAP` s (the bodies chatter for a few ms while they crush; a later touch after a
longer gap is a second impact). Its velocity change is read from the velocity at the step before
the first touch to the velocity after the last one. The sensors' net force summed over the
episode's steps is the contact impulse J, so J / m is the Delta-v of the contact force alone;
the motion's Delta-v also holds the tyres' and the road's forces over the episode (a locked
wheel's 0.8 g over a 0.1 s pulse is ~0.8 m/s), so two vehicles' m Delta-v balance only within
what the road can give over the episode, mu g tau (m_a + m_b): 15-17 % of the mean m |Delta-v|
in tests/test_crash_report.py's cases, 10 % in the built-in t-bone solved at seed 1
(:attr:`PairImpact.momentum_error`).

:func:`crash_impacts` replays a crash file (``crashfile.replay``: the file's own replay, bit for
bit) and records what it needs; :func:`pair_impact` and :func:`pdof_of` are the arithmetic on
recorded arrays.

Compute only.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from nbst.models.crash import crashfile
from nbst.models.crash import scene as scene_mod

__all__ = ["CONTACT_GAP", "KMH", "VehicleImpact", "PairImpact", "CrashImpacts", "pdof_of", "episodes", "pair_impact",
           "crash_impacts", "impact_recorder"]

#: A pair's contact episode ends at a gap in its touching longer than this (s).
CONTACT_GAP = 0.02
KMH = 3.6


@dataclass(frozen=True)
class VehicleImpact:
    """One vehicle in one impact (SI: m/s, rad, s)."""

    vehicle: int
    other: int
    v_before: tuple      # (vx, vy) world frame, just before the first touch
    v_after: tuple       # (vx, vy) world frame, just after the last touch
    dv_world: tuple      # v_after - v_before, world frame
    dv_body: tuple       # the same in the vehicle's frame at the first touch (x forward, y left)
    heading: float       # the vehicle's yaw at the first touch (rad, counter-clockwise from +x)
    dv_impulse: float    # |J| / m: the contact force's alone (m/s)
    pdof_deg: float      # [0, 360): where the force comes from, clockwise from straight ahead
    pdof_clock: int      # 1..12

    @property
    def speed_before(self) -> float:
        return math.hypot(*self.v_before)

    @property
    def speed_after(self) -> float:
        return math.hypot(*self.v_after)

    @property
    def dv(self) -> float:
        """|Delta-v| (m/s)."""
        return math.hypot(*self.dv_world)


@dataclass(frozen=True)
class PairImpact:
    """One contact episode of vehicles ``a`` < ``b`` from ``t`` to ``t_end`` (s; the outcome's
    times: the end of the step that read the touch), ``impulse`` J on ``a`` (N s, world frame;
    ``b`` takes -J), ``pos`` the force-weighted contact point at the first touch (m)."""

    a: int
    b: int
    t: float
    t_end: float
    pos: tuple
    impulse: tuple
    vehicles: tuple      # (VehicleImpact of a, VehicleImpact of b)
    momentum_error: float  # |m_a dv_a + m_b dv_b| / the mean of m_a |dv_a| and m_b |dv_b|

    @property
    def closing_speed(self) -> float:
        """|v_a - v_b| just before the first touch (m/s)."""
        va, vb = self.vehicles[0].v_before, self.vehicles[1].v_before
        return math.hypot(va[0] - vb[0], va[1] - vb[1])

    def of(self, i: int) -> VehicleImpact:
        """The :class:`VehicleImpact` of vehicle ``i`` (one of the pair)."""
        return self.vehicles[0] if i == self.a else self.vehicles[1]


@dataclass(frozen=True)
class CrashImpacts:
    """A crash file's impacts and the motion they were read from (SI units).

    times (S,) s (0 and every step); vel (S, n, 2) each vehicle's CoM velocity (world frame),
    speed (S, n) its magnitude; yaw (S, n) unwrapped; pos (S, n, 2) CoM; mass (n,) kg; impacts:
    every :class:`PairImpact` in time order; identical: the replay ended in the file's final state
    bit for bit."""

    times: np.ndarray
    vel: np.ndarray
    speed: np.ndarray
    yaw: np.ndarray
    pos: np.ndarray
    mass: np.ndarray
    impacts: list
    identical: bool

    def of(self, i: int) -> list:
        """Vehicle ``i``'s impacts: [(PairImpact, its VehicleImpact)] in time order."""
        return [(p, p.of(i)) for p in self.impacts if i in (p.a, p.b)]


def pdof_of(dv_body) -> tuple[float, int]:
    """(angle in degrees [0, 360), clock direction 1..12) a force comes from, given the velocity
    change ``dv_body`` (x forward, y left) it made in the vehicle's frame: 0 deg / 12 o'clock from
    straight ahead (the change points back), 90 / 3 from the right, 180 / 6 from behind, 270 / 9
    from the left.

    Args:
        dv_body: (dx, dy) m/s in the vehicle's frame.

    Returns:
        (degrees clockwise from straight ahead, clock hour); (nan, 0) for a zero change.
    """
    fx, fy = -float(dv_body[0]), -float(dv_body[1])
    if fx == 0.0 and fy == 0.0:
        return math.nan, 0
    deg = (-math.degrees(math.atan2(fy, fx))) % 360.0
    if deg >= 360.0 - 1e-9:   # -0.0 and a hair below 0 read as straight ahead
        deg = 0.0
    h = round(deg / 30.0) % 12
    return deg, 12 if h == 0 else int(h)


def episodes(touch: np.ndarray, gap_steps: int) -> list[tuple[int, int]]:
    """Runs of touching steps: ``touch`` (S,) bool; a run ends at more than ``gap_steps`` steps
    without a touch. Returns [(first index, last index)] of each run."""
    idx = np.nonzero(touch)[0]
    if not idx.size:
        return []
    cut = np.nonzero(np.diff(idx) > gap_steps + 1)[0]
    starts = np.concatenate([[idx[0]], idx[cut + 1]])
    ends = np.concatenate([idx[cut], [idx[-1]]])
    return [(int(s), int(e)) for s, e in zip(starts, ends)]


def _vehicle(i: int, other: int, v0, v1, yaw: float, J, mass: float) -> VehicleImpact:
    d = np.asarray(v1, float) - np.asarray(v0, float)
    c, s = math.cos(yaw), math.sin(yaw)
    body = (c * d[0] + s * d[1], -s * d[0] + c * d[1])
    deg, clock = pdof_of(body)
    return VehicleImpact(vehicle=i, other=other, v_before=(float(v0[0]), float(v0[1])),
                         v_after=(float(v1[0]), float(v1[1])), dv_world=(float(d[0]), float(d[1])),
                         dv_body=(float(body[0]), float(body[1])), heading=float(yaw),
                         dv_impulse=float(np.linalg.norm(J)) / mass, pdof_deg=deg, pdof_clock=clock)


def pair_impact(a: int, b: int, k0: int, k1: int, times, vel, yaw, mass, impulse, pos) -> PairImpact:
    """The impact of vehicles ``a`` and ``b`` whose touching steps run from index ``k0`` to ``k1``
    of the recorded motion (``times`` (S,), ``vel`` (S, n, 2), ``yaw`` (S, n); index k is the state
    after step k, so the step that read the first touch started from index ``k0 - 1``).

    Args:
        a, b: the vehicles (a < b).
        k0, k1: the first and last touching indices (k0 >= 1).
        times, vel, yaw: the recorded motion.
        mass: (n,) kg.
        impulse: (3,) or (2,) the contact impulse on ``a`` over the episode (N s).
        pos: the first touch's contact point (m).

    Returns:
        The :class:`PairImpact`.
    """
    kb, ka = max(k0 - 1, 0), min(k1, len(times) - 1)
    J = np.asarray(impulse, float)[:2]
    va = _vehicle(a, b, vel[kb, a], vel[ka, a], float(yaw[kb, a]), J, float(mass[a]))
    vb = _vehicle(b, a, vel[kb, b], vel[ka, b], float(yaw[kb, b]), J, float(mass[b]))
    pa, pb = mass[a] * np.asarray(va.dv_world), mass[b] * np.asarray(vb.dv_world)
    scale = 0.5 * (np.linalg.norm(pa) + np.linalg.norm(pb))
    err = float(np.linalg.norm(pa + pb) / scale) if scale > 0 else math.nan
    return PairImpact(a=a, b=b, t=float(times[k0]), t_end=float(times[k1]), pos=tuple(float(x) for x in pos),
                      impulse=tuple(float(x) for x in np.asarray(impulse, float)), vehicles=(va, vb),
                      momentum_error=err)


def crash_impacts(d: dict, script, model) -> CrashImpacts:
    """Replay a checked crash file (``crashfile.load``'s three values) and read every vehicle
    impact: see the module docstring.

    Args:
        d: the crash dict.
        script: its Script.
        model: its MjModel.

    Returns:
        The :class:`CrashImpacts`.

    Raises:
        nothing of its own (the file was checked by ``crashfile.load``).
    """
    on_step, finish = impact_recorder(d, script, model)
    q_end, _ = crashfile.replay(d, script, model, on_step=on_step)
    return finish(q_end)


def impact_recorder(d: dict, script, model):
    """What :func:`crash_impacts` reads, for a caller that replays the crash file itself with
    more to record (the video's motion): ``(on_step, finish)``, ``on_step(k, data)`` for
    ``crashfile.replay``'s hook and ``finish(q_end)`` -> :class:`CrashImpacts` after it.

    Args:
        d: the crash dict.
        script: its Script.
        model: its MjModel.

    Returns:
        (on_step, finish).
    """
    n = script.n
    L = scene_mod.layout(model, n)
    dt = float(model.opt.timestep)
    nstep = int(round(script.duration / dt))
    P = len(L.pairs)
    vel = np.empty((nstep + 1, n, 2))
    pos = np.empty((nstep + 1, n, 2))
    quat = np.empty((nstep + 1, n, 4))
    found = np.zeros((nstep + 1, P), bool)
    force = np.zeros((nstep + 1, P, 3))
    cpos = np.zeros((nstep + 1, P, 3))
    vi = L.qvel[:, None] + np.arange(2)
    pi = L.qpos[:, None] + np.arange(2)
    qi = L.qpos[:, None] + np.arange(3, 7)
    q0, v0 = np.asarray(d["qpos0"], float), np.asarray(d["qvel0"], float)
    vel[0], pos[0], quat[0] = v0[vi], q0[pi], q0[qi]
    fa = L.pair_adr
    Fa = fa[:, None] + np.arange(1, 4)
    Pa = fa[:, None] + np.arange(4, 7)

    def on_step(k: int, md) -> None:
        vel[k], pos[k], quat[k] = md.qvel[vi], md.qpos[pi], md.qpos[qi]
        s = md.sensordata
        f = s[fa] > 0
        if f.any():
            found[k] = f
            force[k] = s[Fa]
            cpos[k] = s[Pa]

    def finish(q_end) -> CrashImpacts:
        times = np.arange(nstep + 1) * dt
        w, x, y, z = np.moveaxis(quat, -1, 0)
        yaw = np.unwrap(np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z)), axis=0)
        gap = max(0, int(round(CONTACT_GAP / dt)))
        out = []
        for p, (a, b) in enumerate(L.pairs):
            for k0, k1 in episodes(found[:, p], gap):
                # the pair sensor's net force acts on its second subtree (b): a takes -J
                J = -(force[k0:k1 + 1, p] * found[k0:k1 + 1, p, None]).sum(axis=0) * dt
                out.append(pair_impact(a, b, k0, k1, times, vel, yaw, L.mass, J, cpos[k0, p]))
        out.sort(key=lambda m: (m.t, m.a, m.b))
        return CrashImpacts(times=times, vel=vel, speed=np.hypot(vel[..., 0], vel[..., 1]), yaw=yaw, pos=pos,
                            mass=np.asarray(L.mass, float), impacts=out,
                            identical=bool(np.array_equal(q_end, np.asarray(d["final_qpos"], float))))

    return on_step, finish
