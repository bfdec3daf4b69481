"""Partially autonomous drivers: what each vehicle's driver does, every :data:`PERIOD` seconds.

The search does not set velocities; it sets each driver's **intent** (a row of
:data:`INTENT`, SI units), within the ranges the script gives:

* ``speed``: the start speed and the cruise speed (m/s);
* ``aim_x``, ``aim_y``: the aim point; the script's waypoints, when given, come first;
* ``arrive``: the time (s) to reach the aim point; the speed is paced as distance / time left
  (NaN: cruise at ``speed``);
* ``brake_at``: the time (s) of a reaction stop: every wheel braked, the wheel held (NaN: none);
* ``slide_at``, ``slide_steer``, ``slide_power``: a slide: from that time the wheel goes to
  ``slide_steer`` (rad, + left) and stays there, and the rear wheels either lock (a handbrake
  turn; ``slide_power`` 0 or NaN) or spin under ``slide_power`` x the full drive torque (a
  power slide: the rear breaks away and the car keeps turning; NaN: no slide);
* ``headway``, ``reaction``: the car-following driver (IDM) behind the script's ``follow``
  leader: time gap (s) and reaction delay (s): it sees the leader as it was that long ago;
* ``after``: what the driver does once the vehicle has touched anything (another vehicle, a
  curb, a barrier), as real drivers effectively leave the loop: 0 brake (every wheel locked),
  1 coast (no drive, no brake), 2 hold (the last drive and brake kept);
* ``after_steer``: the wheel after the first contact (rad; NaN: held where it was).

**Steering** is pure pursuit (Coulter 1992): delta = atan(2 L sin(alpha) / l_d), alpha the
angle between the heading and the line from the rear axle to the target, l_d that line's
length (at least :data:`LOOKAHEAD_MIN`); a target within :data:`REACHED` or behind the
vehicle is done, and after the last one the wheel is straight. The wheels turn at most
:data:`STEER_RATE`; left and right get Ackermann angles. **Speed**: the commanded acceleration
``KV (v_target - v)`` (clipped to :data:`ACCEL` and :data:`DECEL`) is a torque on the rear
wheels when positive (at most the engine's power over the wheels' speed) and a proportional
brake on all four when negative. **IDM** (Treiber,
Hennecke and Helbing 2000): a = a_max [1 - (v / v0)^4 - (s* / s)^2], s* = s0 + v T + v dv /
(2 sqrt(a_max b)); beyond the brakes' reach the driver stands on them.

Compute only, vectorised over (simulations, vehicles): :func:`controls` takes the state and
returns the actuators' values; :class:`DriverState` carries what a driver remembers.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from nbst.models.crash import vehicle as veh

__all__ = ["PERIOD", "INTENT", "IX", "NOISE_KIND_NAMES", "AFTER_BRAKE", "AFTER_COAST", "AFTER_HOLD", "LOOKAHEAD_MIN", "REACHED",
           "STEER_RATE", "KV", "ACCEL", "DECEL", "VMAX", "IDM_A", "IDM_B", "IDM_S0", "IDM_DELTA", "IDM_PANIC",
           "DriverState", "Fleet", "yaw_of", "ackermann", "controls"]

#: The drivers act every PERIOD seconds (the controls hold in between).
PERIOD = 0.02
INTENT = ("speed", "aim_x", "aim_y", "arrive", "brake_at", "slide_at", "slide_steer", "slide_power", "headway",
          "reaction", "after", "after_steer")
IX = {k: i for i, k in enumerate(INTENT)}
#: The kinds of driver noise (their spreads: :data:`.robust.NOISE_KINDS`), the default first.
NOISE_KIND_NAMES = ("retake", "population")
AFTER_BRAKE, AFTER_COAST, AFTER_HOLD = 0, 1, 2
#: Pure pursuit: shortest look-ahead (m), a target counts as reached within REACHED m.
LOOKAHEAD_MIN, REACHED = 6.0, 3.0
#: Road-wheel steering rate (rad/s): ~35 deg/s, an emergency swerve's.
STEER_RATE = 0.6
#: Speed loop: gain (1/s), largest acceleration and deceleration asked (m/s^2), speed cap (m/s).
KV, ACCEL, DECEL, VMAX = 1.5, 3.0, 7.0, 60.0
#: IDM: largest acceleration, comfortable deceleration (m/s^2), jam gap (m), exponent.
IDM_A, IDM_B, IDM_S0, IDM_DELTA = 1.5, 2.0, 2.0, 4
#: A driver stands on the brakes when IDM asks for more than this deceleration (m/s^2).
IDM_PANIC = 4.0


@dataclass
class DriverState:
    """What the drivers of ``nsim`` simulations of ``n`` vehicles remember between periods."""

    in_loop: np.ndarray      # (s, n) bool: not yet touched anything
    steer: np.ndarray        # (s, n) the bicycle steering angle last commanded (rad)
    drive: np.ndarray        # (s, n) rear torque per wheel last commanded (N m)
    brake: np.ndarray        # (s, n, 4) brake controls last commanded
    target: np.ndarray       # (s, n) int: index of the current target (waypoints, then the aim point)
    hist: np.ndarray         # (periods, 4, s, n): t, x, y, forward speed of past periods (the IDM's delay)
    count: int = 0

    @classmethod
    def start(cls, nsim: int, n: int, periods: int) -> DriverState:
        return cls(in_loop=np.ones((nsim, n), bool), steer=np.zeros((nsim, n)), drive=np.zeros((nsim, n)),
                   brake=np.zeros((nsim, n, 4)), target=np.zeros((nsim, n), int),
                   hist=np.zeros((max(1, periods), 4, nsim, n)))

    def remember(self, t: float, x, y, v) -> None:
        k = min(self.count, len(self.hist) - 1)
        self.hist[k, 0], self.hist[k, 1], self.hist[k, 2], self.hist[k, 3] = t, x, y, v
        self.count = k + 1


@dataclass(frozen=True)
class Fleet:
    """The fixed part of the drivers (from the script): per vehicle wheelbase, track, wheel
    radius, mass, half length, steering lock, drive torque, waypoints (a list of (k, 2) arrays)
    and the leader it follows (-1: none)."""

    wheelbase: np.ndarray
    track: np.ndarray
    radius: np.ndarray
    mass: np.ndarray
    front: np.ndarray        # CoM to front bumper (m)
    rear: np.ndarray         # CoM to rear bumper (m)
    b: np.ndarray            # CoM to rear axle (m)
    lock: np.ndarray
    torque: np.ndarray
    power: np.ndarray        # engine power (W)
    waypoints: tuple
    leader: np.ndarray

    @classmethod
    def of(cls, vtypes, waypoints, leaders) -> Fleet:
        a = lambda f: np.array([f(v) for v in vtypes], dtype=float)  # noqa: E731
        return cls(wheelbase=a(lambda v: v.wheelbase), track=a(lambda v: v.track), radius=a(lambda v: v.wheel_radius),
                   mass=a(lambda v: v.mass), front=a(lambda v: v.a + v.front_overhang),
                   rear=a(lambda v: v.length - v.a - v.front_overhang), b=a(lambda v: v.b),
                   lock=a(lambda v: math.radians(v.steer_max_deg)), torque=a(lambda v: v.drive_torque),
                   power=a(lambda v: v.power),
                   waypoints=tuple(np.asarray(w, dtype=float).reshape(-1, 2) for w in waypoints),
                   leader=np.array(leaders, dtype=int))


def yaw_of(q: np.ndarray) -> np.ndarray:
    """Heading (rad) of quaternions (..., 4) (w, x, y, z): the yaw of a ZYX decomposition."""
    w, x, y, z = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    return np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))


def ackermann(delta: np.ndarray, wheelbase: np.ndarray, track: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(left, right) road-wheel angles (rad) for the bicycle angle ``delta``: both wheels turn
    about one point on the rear axle's line."""
    t = np.tan(delta)
    return (np.arctan(wheelbase * t / (wheelbase - track / 2 * t)),
            np.arctan(wheelbase * t / (wheelbase + track / 2 * t)))


def _targets(fleet: Fleet, intent: np.ndarray, state: DriverState, x, y, yaw):
    """(target x, target y, has target) per (sim, vehicle); advances past reached targets.
    Vehicles without waypoints (the aim point alone) are done in numpy over the batch."""
    s, n = x.shape
    tx, ty, has = np.zeros((s, n)), np.zeros((s, n)), np.zeros((s, n), bool)
    for j in range(n):
        pts = fleet.waypoints[j]
        aim = intent[:, j, [IX["aim_x"], IX["aim_y"]]]  # (s, 2)
        if not len(pts):
            live = (state.target[:, j] == 0) & np.isfinite(aim).all(axis=1)
            dx, dy = aim[:, 0] - x[:, j], aim[:, 1] - y[:, j]
            ahead = dx * np.cos(yaw[:, j]) + dy * np.sin(yaw[:, j])
            done = live & ((np.hypot(dx, dy) < REACHED) | (ahead < 0.0))
            state.target[done, j] = 1
            live &= ~done
            tx[:, j], ty[:, j], has[:, j] = np.where(live, aim[:, 0], 0.0), np.where(live, aim[:, 1], 0.0), live
            continue
        for i in range(s):
            k = state.target[i, j]
            while True:
                if k < len(pts):
                    p = pts[k]
                elif k == len(pts) and np.isfinite(aim[i]).all():
                    p = aim[i]
                else:
                    break
                dx, dy = p[0] - x[i, j], p[1] - y[i, j]
                ahead = dx * math.cos(yaw[i, j]) + dy * math.sin(yaw[i, j])
                if math.hypot(dx, dy) < REACHED or ahead < 0.0:
                    k += 1
                    continue
                tx[i, j], ty[i, j], has[i, j] = p[0], p[1], True
                break
            state.target[i, j] = k
    return tx, ty, has


def _remaining(fleet: Fleet, intent, state, x, y, tx, ty, has) -> np.ndarray:
    """Path length (m) left to the aim point: to the current target, then along the rest."""
    s, n = x.shape
    out = np.hypot(tx - x, ty - y)
    for j in range(n):
        pts = fleet.waypoints[j]
        if not len(pts):
            continue  # the aim point is the target
        for i in range(s):
            if not has[i, j]:
                continue
            k = state.target[i, j]
            rest = list(pts[k:]) + ([intent[i, j, [IX["aim_x"], IX["aim_y"]]]]
                                   if np.isfinite(intent[i, j, IX["aim_x"]]) else [])
            out[i, j] += sum(math.hypot(*(b - a)) for a, b in zip(rest, rest[1:]))
    return out


def controls(t: float, fleet: Fleet, intent: np.ndarray, state: DriverState, pos: np.ndarray, quat: np.ndarray,
             vel: np.ndarray, wheel: np.ndarray, touched: np.ndarray) -> np.ndarray:
    """Actuator values (s, n, 8) in :data:`vehicle.CONTROLS` order at time ``t`` (s).

    intent  : (s, n, len(INTENT)) the drivers' intents (SI; NaN = off)
    pos     : (s, n, 3) CoM positions; quat (s, n, 4); vel (s, n, 3) CoM velocities (world)
    touched : (s, n) bool, the vehicle has touched anything since the last period
    """
    s, n, _ = intent.shape
    x, y = pos[..., 0], pos[..., 1]
    yaw = yaw_of(quat)
    c, sn = np.cos(yaw), np.sin(yaw)
    v = vel[..., 0] * c + vel[..., 1] * sn  # forward speed
    state.remember(t, x, y, v)
    leaving = state.in_loop & touched
    state.in_loop &= ~touched

    # steering: pure pursuit from the rear axle
    tx, ty, has = _targets(fleet, intent, state, x, y, yaw)
    rx, ry = x - fleet.b * c, y - fleet.b * sn
    dx, dy = tx - rx, ty - ry
    alpha = np.arctan2(-sn * dx + c * dy, c * dx + sn * dy)
    ld = np.maximum(np.hypot(dx, dy), LOOKAHEAD_MIN)
    delta = np.where(has, np.arctan(2 * fleet.wheelbase * np.sin(alpha) / ld), 0.0)

    # speed: paced to the arrival time, else the cruise speed
    arrive = intent[..., IX["arrive"]]
    left = arrive - t
    dist = _remaining(fleet, intent, state, x, y, tx, ty, has)
    paced = np.isfinite(arrive) & has & (left > PERIOD)
    vt = np.where(paced, dist / np.where(paced, left, 1.0), intent[..., IX["speed"]])
    vt = np.clip(vt, 0.0, VMAX)
    acc = np.clip(KV * (vt - v), -DECEL, ACCEL)

    # car following (IDM) behind a leader, seen ``reaction`` s late
    lead = fleet.leader
    panic = np.zeros((s, n), bool)
    for j in range(n):
        if lead[j] < 0:
            continue
        k = lead[j]
        lx, ly, lv = _delayed(state, t - intent[:, j, IX["reaction"]], k)
        gap = np.hypot(lx - x[:, j], ly - y[:, j]) - fleet.front[j] - fleet.rear[k]
        gap = np.maximum(gap, 0.1)
        vj = np.maximum(v[:, j], 0.0)
        v0 = np.maximum(intent[:, j, IX["speed"]], 0.1)
        sstar = IDM_S0 + vj * intent[:, j, IX["headway"]] + vj * (vj - lv) / (2 * math.sqrt(IDM_A * IDM_B))
        a_idm = IDM_A * (1 - (vj / v0) ** IDM_DELTA - (np.maximum(sstar, 0.0) / gap) ** 2)
        acc[:, j] = np.clip(a_idm, -DECEL, ACCEL)
        panic[:, j] = a_idm < -IDM_PANIC

    # rate-limited steering, then the manoeuvres that override it
    step = STEER_RATE * PERIOD
    want = np.clip(delta, -fleet.lock, fleet.lock)
    brake = np.zeros((s, n, 4))
    drive = np.where(acc > 0, fleet.mass * acc * fleet.radius / 2, 0.0)
    drive = np.minimum(drive, fleet.torque)
    speed = np.maximum(np.abs(v), 0.5)
    soft = np.clip(fleet.mass * np.maximum(-acc, 0.0) * fleet.radius ** 2 / (4 * veh.BRAKE_KV * speed), 0.0, 1.0)
    brake[:] = soft[..., None]
    slide = t >= intent[..., IX["slide_at"]]  # NaN compares False
    stop = t >= intent[..., IX["brake_at"]]
    stop &= ~(slide & (intent[..., IX["slide_at"]] > intent[..., IX["brake_at"]]))  # a later slide takes over
    stop |= panic
    brake[stop] = 1.0
    drive[stop] = 0.0
    want = np.where(stop, state.steer, want)
    slide &= ~stop
    want = np.where(slide, np.clip(intent[..., IX["slide_steer"]], -fleet.lock, fleet.lock), want)
    power = np.nan_to_num(intent[..., IX["slide_power"]])
    hand = slide & (power <= 0)
    brake[hand] = [0.0, 0.0, 1.0, 1.0]
    drive[hand] = 0.0
    gun = slide & (power > 0)
    brake[gun] = 0.0
    drive[gun] = (power * fleet.torque)[gun]
    # the engine's power caps the torque at the rear wheels' speed (no wheel spins up without end)
    drive = np.minimum(drive, fleet.power / 2 / np.maximum(np.abs(wheel).max(axis=-1), 1.0))
    steer = state.steer + np.clip(want - state.steer, -step, step)

    # out of the loop: after the first contact the driver does what ``after`` says
    after = intent[..., IX["after"]]
    out = ~state.in_loop
    held = np.isnan(intent[..., IX["after_steer"]])
    post_steer = np.where(held, state.steer, intent[..., IX["after_steer"]])
    post_steer = np.where(leaving | ~held, post_steer, state.steer)
    steer = np.where(out, np.where(held, state.steer, state.steer + np.clip(post_steer - state.steer, -step, step)),
                     steer)
    for code, b, dr in ((AFTER_BRAKE, 1.0, 0.0), (AFTER_COAST, 0.0, 0.0)):
        m = out & (after == code)
        brake[m] = b
        drive[m] = dr
    m = out & (after == AFTER_HOLD)
    brake[m] = state.brake[m]
    drive[m] = state.drive[m]

    state.steer, state.drive, state.brake = steer, drive, brake
    left_w, right_w = ackermann(steer, fleet.wheelbase, fleet.track)
    u = np.empty((s, n, len(veh.CONTROLS)))
    u[..., 0], u[..., 1] = left_w, right_w
    u[..., 2] = u[..., 3] = drive
    u[..., 4:8] = brake
    return u


def _delayed(state: DriverState, when: np.ndarray, k: int):
    """Leader ``k``'s (x, y, forward speed) per simulation as of time ``when`` (s,): the latest
    period at or before it (the first period if none)."""
    h = state.hist[:state.count]
    idx = np.clip(np.searchsorted(h[:, 0, 0, 0], when + 1e-9, side="right") - 1, 0, state.count - 1)
    sims = np.arange(len(when))
    return h[idx, 1, sims, k], h[idx, 2, sims, k], h[idx, 3, sims, k]
