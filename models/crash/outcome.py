"""What happened to each vehicle, read inside the rollout, and whether its fate holds.

:class:`Recorder` reads the scene's contact sensors after every step and the vehicles' poses
every driver period, for a batch of simulations at once (numpy over the batch):

* per vehicle pair: the first and last contact times, the force-weighted point of the first
  contact, and the impulse J = sum of the net contact force x dt over every step in contact,
  so the pair's delta-V for vehicle i is |J| / m_i;
* per vehicle: the time of its first contact of any kind (the driver leaves the loop), its
  speed just before its first vehicle contact (the impact speed), its curb and barrier
  strikes, its roll and yaw unwrapped from the quaternion (quarter turns = |roll| / 90 deg
  rounded; spin = yaw turned), its closest approach to each other vehicle, its rest pose.

:func:`outcomes` turns a finished record into :class:`Outcome` values; :func:`judge` checks
them against a script's fates: one **signature** bit per vehicle, set when every fate of that
vehicle holds (the paper's i-acceptable), the global order, and a cost that grows with how far
each fate is from holding (the search's guide; a met script costs at most a few hundredths:
the centring term, :data:`W_CENTRE`).

Compute only.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from nbst.models.crash import driver as drv
from nbst.models.crash import scene as scene_mod
from nbst.models.crash import vehicle as veh
from nbst.models.crash.script import Script

__all__ = ["KMH", "COS45", "REST_SPEED", "W_CONTACT", "W_NEAR", "W_METRE", "W_HEADING", "W_TURN",
           "W_ATTITUDE", "W_STRIKE", "W_KMH", "W_SPIN", "W_CENTRE", "W_MOVING", "Recorder", "VehicleOutcome", "Outcome",
           "outcomes", "judge"]

KMH = 3.6
#: cos(45 deg): the up axis's vertical part that splits upright / side / roof.
COS45 = math.sqrt(0.5)
#: A vehicle is at rest under this speed (m/s).
REST_SPEED = 0.5
#: Cost weights (docs/results/crash.md): a wrong or missing contact, a metre outside a rest region,
#: 30 degrees outside a heading tolerance, a quarter turn, a wrong attitude or strike, 10 km/h
#: outside a speed band, 45 degrees of spin.
W_CONTACT, W_NEAR, W_METRE, W_HEADING, W_TURN, W_ATTITUDE, W_STRIKE, W_KMH, W_SPIN = \
    10.0, 5.0, 0.5, 1.0 / math.radians(30), 2.0, 3.0, 2.0, 0.1, 1.0 / math.radians(45)
#: Centring: a fate met near the edge of its tolerance is one the timestep or the driver's noise
#: can lose, so every measured fate also costs W_CENTRE x (how far from the middle of its band,
#: in band halves): the search prefers the middle of the rest region, heading, spin and bands.
W_CENTRE = 0.02
#: A vehicle asked to come to rest (a rest region, a heading at rest) that still moves at the end
#: costs this much, plus the slide it has left (:func:`_still_moving`): its rest and heading fates
#: do not hold (the pose at the script's end is not a rest position).
W_MOVING = 0.5


class Recorder:
    """Collects a batch's outcome while it runs (see the module docstring)."""

    def __init__(self, layout: scene_mod.Layout, nsim: int, dt: float):
        L = self.L = layout
        n, P = L.n, len(L.pairs)
        self.dt = dt
        self.t_first = np.full((nsim, P), np.nan)
        self.t_last = np.full((nsim, P), np.nan)
        self.pos_first = np.full((nsim, P, 3), np.nan)
        self.J = np.zeros((nsim, P, 3))
        self.touch = np.full((nsim, n), np.nan)       # first contact of any kind
        self.hit_first = np.full((nsim, n), np.nan)   # first vehicle contact
        self.impact_speed = np.full((nsim, n), np.nan)
        self.impact_heading = np.full((nsim, n), np.nan)
        self.impact_pos = np.full((nsim, n, 2), np.nan)  # CoM (x, y) just before its first vehicle contact
        self.curb = np.full((nsim, n), np.nan)
        self.barrier = np.full((nsim, n), np.nan)
        self.roll = np.zeros((nsim, n))
        self.yaw = np.zeros((nsim, n))
        self.roll_prev = np.zeros((nsim, n))
        self.yaw_prev = np.zeros((nsim, n))
        self.min_dist = np.full((nsim, P), np.inf)
        self.final: dict[str, np.ndarray] = {}  # set by finish: pos, yaw, up, speed
        self.pair_of = [[k for k, (a, b) in enumerate(L.pairs) if i in (a, b)] for i in range(n)]
        self._f = L.pair_adr.copy()
        self._F = L.pair_adr[:, None] + np.arange(1, 4)
        self._p = L.pair_adr[:, None] + np.arange(4, 7)
        # every "found" number (pairs, curbs, barriers) at once: a step with none costs one test
        self._any = np.concatenate([L.pair_adr, L.curb_adr[L.curb_adr >= 0], L.barrier_adr[L.barrier_adr >= 0]])

    def begin(self, qpos: np.ndarray) -> None:
        """The state at t = 0 (nsim, nq): the starting roll and yaw."""
        q = qpos[:, self.L.qpos[:, None] + np.arange(3, 7)]
        self.roll_prev, self.yaw_prev = _roll(q), drv.yaw_of(q)

    def step(self, t: float, sensordata: np.ndarray, vel_before: np.ndarray, pos_before: np.ndarray) -> np.ndarray:
        """After a step ending at time ``t``: ``sensordata`` (nsim, nsensordata), the vehicles'
        planar velocities and CoM positions before the step (nsim, n, 2). Returns (nsim, n) bool:
        touched anything this step."""
        L = self.L
        touched = np.zeros(self.touch.shape, bool)
        if not sensordata[:, self._any].any():
            return touched
        found = sensordata[:, self._f] > 0
        if found.any():
            F = sensordata[:, self._F]
            self.J += np.where(found[..., None], F * self.dt, 0.0)
            new = found & np.isnan(self.t_first)
            if new.any():
                self.t_first[new] = t
                self.pos_first[new] = sensordata[:, self._p][new]
            self.t_last[found] = t
            for i in range(L.n):
                got = found[:, self.pair_of[i]].any(axis=1)
                first = got & np.isnan(self.hit_first[:, i])
                self.hit_first[first, i] = t
                self.impact_speed[first, i] = np.hypot(*vel_before[first, i].T)
                self.impact_heading[first, i] = np.arctan2(vel_before[first, i, 1], vel_before[first, i, 0])
                self.impact_pos[first, i] = pos_before[first, i]
                touched[:, i] |= got
        for arr, adr in ((self.curb, L.curb_adr), (self.barrier, L.barrier_adr)):
            if adr[0] < 0:
                continue
            hit = sensordata[:, adr] > 0
            arr[hit & np.isnan(arr)] = t
            touched |= hit
        self.touch[touched & np.isnan(self.touch)] = t
        return touched

    def period(self, qpos: np.ndarray) -> None:
        """Every driver period: unwrap roll and yaw, track the pairs' closest approach."""
        L = self.L
        q = qpos[:, L.qpos[:, None] + np.arange(3, 7)]
        r, y = _roll(q), drv.yaw_of(q)
        self.roll += _wrap(r - self.roll_prev)
        self.yaw += _wrap(y - self.yaw_prev)
        self.roll_prev, self.yaw_prev = r, y
        p = qpos[:, L.qpos[:, None] + np.arange(2)]
        for k, (a, b) in enumerate(L.pairs):
            self.min_dist[:, k] = np.minimum(self.min_dist[:, k], np.hypot(*(p[:, a] - p[:, b]).T))

    def finish(self, qpos: np.ndarray, qvel: np.ndarray) -> None:
        self.period(qpos)
        L = self.L
        q = qpos[:, L.qpos[:, None] + np.arange(3, 7)]
        v = qvel[:, L.qvel[:, None] + np.arange(3)]
        self.final = {"pos": qpos[:, L.qpos[:, None] + np.arange(3)].copy(), "yaw": drv.yaw_of(q),
                      "up": _up_z(q), "speed": np.linalg.norm(v, axis=-1)}


def _wrap(a):
    return (a + np.pi) % (2 * np.pi) - np.pi


def _roll(q: np.ndarray) -> np.ndarray:
    w, x, y, z = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    return np.arctan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))


def _up_z(q: np.ndarray) -> np.ndarray:
    """The vertical part of each vehicle's up axis (R[2, 2])."""
    x, y = q[..., 1], q[..., 2]
    return 1 - 2 * (x * x + y * y)


# --------------------------------------------------------------------------- outcomes

@dataclass
class VehicleOutcome:
    """What happened to one vehicle (SI inside; :meth:`to_dict` speaks km/h and degrees)."""

    name: str
    hits: list            # [(other index, first contact time s)] in time order
    impact_speed: float   # m/s just before its first vehicle contact (NaN: none)
    impact_heading: float  # rad: its direction of travel then
    impact_pos: tuple     # (x, y) m: its CoM then (NaN: none)
    delta_v: float        # m/s in its first vehicle impact (NaN: none)
    rest: tuple           # (x, y, heading rad)
    quarter_turns: int
    roll: float           # rad, unwrapped, signed
    attitude: str
    spin: float           # rad of yaw turned, signed
    curb: float           # first curb strike time (NaN: none)
    barrier: float
    moving: bool          # still above REST_SPEED at the end
    fates: dict = field(default_factory=dict)  # fate -> held (bool)
    end_speed: float = math.nan  # m/s of its centre of mass at the end (not written: ``moving`` is)

    def to_dict(self, names) -> dict:
        r = lambda x, k=3: None if x is None or (isinstance(x, float) and math.isnan(x)) else round(float(x), k)  # noqa: E731
        return {"name": self.name, "hits": [{"vehicle": names[j], "t": r(t)} for j, t in self.hits],
                "impact_speed_kmh": r(self.impact_speed * KMH, 2),
                "impact_heading_deg": r(math.degrees(self.impact_heading), 2),
                "impact_pos": {"x": r(self.impact_pos[0]), "y": r(self.impact_pos[1])},
                "delta_v_kmh": r(self.delta_v * KMH, 2),
                "rest": {"x": r(self.rest[0]), "y": r(self.rest[1]), "heading_deg": r(math.degrees(self.rest[2]), 2)},
                "quarter_turns": self.quarter_turns, "roll_deg": r(math.degrees(self.roll), 1),
                "attitude": self.attitude, "spin_deg": r(math.degrees(self.spin), 1),
                "curb_strike_t": r(self.curb), "barrier_strike_t": r(self.barrier), "moving_at_end": self.moving,
                "fates": dict(self.fates)}


@dataclass
class Outcome:
    """One simulation's outcome: its vehicles, the contact sequence, and how it meets the script."""

    vehicles: list
    contacts: list        # [(i, j, t first, t last, pos (3,), impulse (3,))] in time order
    signature: int = 0    # bit i: every fate of vehicle i holds
    order_ok: bool = True
    cost: float = 0.0
    solved: bool = False

    @property
    def sequence(self) -> tuple:
        """The contact sequence: vehicle pairs in the order of their first contact (the archive's key)."""
        return tuple((i, j) for i, j, *_ in self.contacts)

    def signature_text(self, n: int) -> str:
        return "".join("1" if self.signature >> i & 1 else "0" for i in range(n))


def outcomes(rec: Recorder, names: list[str], mass: np.ndarray) -> list[Outcome]:
    """The :class:`Outcome` of every simulation of a finished record."""
    L = rec.L
    out = []
    for s in range(rec.t_first.shape[0]):
        contacts = []
        for k in np.argsort(np.where(np.isnan(rec.t_first[s]), np.inf, rec.t_first[s]), kind="stable"):
            if np.isnan(rec.t_first[s, k]):
                break
            i, j = L.pairs[k]
            contacts.append((i, j, float(rec.t_first[s, k]), float(rec.t_last[s, k]), rec.pos_first[s, k].copy(),
                             rec.J[s, k].copy()))
        vs = []
        for i, nm in enumerate(names):
            hits = [(j if a == i else a, t) for a, j, t, *_ in contacts if i in (a, j)]
            dv = math.nan
            if hits:
                first = next(c for c in contacts if i in c[:2])
                dv = float(np.linalg.norm(first[5]) / mass[i])
            roll = float(rec.roll[s, i])
            turns = int(round(abs(roll) / (math.pi / 2)))
            up = rec.final["up"][s, i]
            att = "upright" if up > COS45 else ("roof" if up < -COS45 else "side")
            vs.append(VehicleOutcome(
                name=nm, hits=[(j, t) for j, t in hits], impact_speed=float(rec.impact_speed[s, i]),
                impact_heading=float(rec.impact_heading[s, i]),
                impact_pos=(float(rec.impact_pos[s, i, 0]), float(rec.impact_pos[s, i, 1])), delta_v=dv,
                rest=(float(rec.final["pos"][s, i, 0]), float(rec.final["pos"][s, i, 1]), float(rec.final["yaw"][s, i])),
                quarter_turns=turns, roll=roll, attitude=att, spin=float(rec.yaw[s, i]), curb=float(rec.curb[s, i]),
                barrier=float(rec.barrier[s, i]), moving=bool(rec.final["speed"][s, i] > REST_SPEED),
                end_speed=float(rec.final["speed"][s, i])))
        out.append(Outcome(vehicles=vs, contacts=contacts))
    return out


# --------------------------------------------------------------------------- the script's fates

def _edit(a, b) -> int:
    """Levenshtein distance between two short sequences."""
    prev = list(range(len(b) + 1))
    for i, x in enumerate(a, 1):
        cur = [i]
        for j, y in enumerate(b, 1):
            cur.append(min(prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (x != y)))
        prev = cur
    return prev[-1]


def _band(x: float, lo: float, hi: float) -> float:
    """How far x lies outside [lo, hi] (0 inside; inf for NaN)."""
    if math.isnan(x):
        return math.inf
    return max(0.0, lo - x, x - hi)


def _still_moving(vo: VehicleOutcome, mu: float) -> float:
    """The cost of a vehicle asked to rest (a rest region or a heading at rest) that still moves at
    the end: :data:`W_MOVING`, plus W_METRE per metre it would still slide on locked wheels,
    v^2 / (2 mu g) (a guide towards stopping in time; the fates are unmet all the same)."""
    v = vo.end_speed if math.isfinite(vo.end_speed) else REST_SPEED
    return W_MOVING + W_METRE * v * v / (2.0 * mu * veh.G)


def judge(o: Outcome, script: Script, min_dist: np.ndarray | None = None) -> Outcome:
    """Fill ``o``'s fates, signature, order check, cost and ``solved`` against ``script``.
    ``min_dist`` (pairs,): the pairs' closest centre distance (m), for the soft part of the cost."""
    pairs = [(i, j) for i in range(script.n) for j in range(i + 1, script.n)]
    cost, sig = 0.0, 0
    for i, (vs, vo) in enumerate(zip(script.vehicles, o.vehicles)):
        f, ok, c = vs.fate, {}, 0.0
        if f.hits is not None:
            got = [j for j, _ in vo.hits]
            ok["hits"] = got == list(f.hits)
            c += W_CONTACT * _edit(got, list(f.hits))
            if min_dist is not None:
                for j in f.hits:
                    if j not in got:
                        c += W_NEAR * min(float(min_dist[pairs.index((min(i, j), max(i, j)))]), 10.0) / 10.0
        for key, val in (("impact_speed", vo.impact_speed), ("delta_v", vo.delta_v)):
            band = getattr(f, key)
            if band is not None:
                miss = _band(val, band.lo, band.hi)
                ok[key] = miss == 0.0
                c += W_KMH * KMH * miss if math.isfinite(miss) else W_CONTACT / 2
                if math.isfinite(val) and band.hi > band.lo:
                    c += W_CENTRE * min(abs(val - (band.lo + band.hi) / 2) / ((band.hi - band.lo) / 2), 2.0)
        if f.rest is not None:
            d = math.hypot(vo.rest[0] - f.rest[0], vo.rest[1] - f.rest[1])
            ok["rest"] = d <= f.rest[2] and not vo.moving  # a vehicle still moving has no rest position
            c += W_METRE * max(0.0, d - f.rest[2]) + W_CENTRE * min(d / f.rest[2], 2.0)
        if f.impact_at is not None:
            d = math.hypot(vo.impact_pos[0] - f.impact_at[0], vo.impact_pos[1] - f.impact_at[1])
            d = d if math.isfinite(d) else math.inf
            ok["impact_at"] = d <= f.impact_at[2]
            c += W_METRE * max(0.0, d - f.impact_at[2]) + W_CENTRE * min(d / f.impact_at[2], 2.0) \
                if math.isfinite(d) else W_CONTACT / 2
        if f.heading is not None:
            err = abs(float(_wrap(vo.rest[2] - f.heading[0])))
            ok["heading"] = err <= f.heading[1] and not vo.moving  # the heading at rest
            c += W_HEADING * max(0.0, err - f.heading[1]) + W_CENTRE * min(err / f.heading[1], 2.0)
        if vo.moving and (f.rest is not None or f.heading is not None):
            c += _still_moving(vo, script.road.friction)
        if f.quarter_turns is not None:
            lo, hi = f.quarter_turns
            ok["quarter_turns"] = lo <= vo.quarter_turns <= hi
            c += W_TURN * _band(abs(vo.roll) / (math.pi / 2), lo - 0.5, hi + 0.5)
        if f.attitude is not None:
            ok["attitude"] = vo.attitude == f.attitude
            c += 0.0 if ok["attitude"] else W_ATTITUDE
        if f.spin is not None:
            err = abs(abs(vo.spin) - f.spin[0])
            ok["spin"] = err <= f.spin[1]
            c += W_SPIN * max(0.0, err - f.spin[1]) + W_CENTRE * min(err / f.spin[1], 2.0)
        for key, t in (("curb", vo.curb), ("barrier", vo.barrier)):
            want = getattr(f, key)
            if want is not None:
                ok[key] = (not math.isnan(t)) == want
                c += 0.0 if ok[key] else W_STRIKE
        vo.fates = ok
        if all(ok.values()):
            sig |= 1 << i
        cost += c
    o.order_ok = True
    if script.order is not None:
        got = list(o.sequence)
        o.order_ok = got == list(script.order)
        cost += W_CONTACT * _edit(got, list(script.order))
    o.signature, o.cost = sig, float(cost)
    o.solved = o.order_ok and sig == (1 << script.n) - 1
    return o

