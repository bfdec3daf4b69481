"""A crash file's motion, recorded for the picture: poses, marks on the road, impacts, frame times.

* **Motion** (:func:`record`): the crash file's own replay, :func:`nbst.models.crash.crashfile.replay`
  (plain ``mj_step`` from the file's scene, initial state and realised controls), through its
  ``on_step`` hook, which only reads the state: the motion drawn is the one that replay checks
  bit for bit, and the outcome the readout speaks of is the one it judges. Recorded: ``qpos``
  at least every :data:`POSE_DT` s (every step at the scripts' 2 ms; the last step always), each
  vehicle's speed, and every :data:`MARK_DT` s the tyres' and bodies' contacts with the ground.
* **Marks on the road**: a tyre whose contact point slides over the ground faster than
  :data:`SKID_SLIP` leaves a skid mark (locked wheels, yaw marks in a spin); a body touching the
  ground leaves a scrape (a car on its side or roof). Each is a run of samples, drawn as a
  ribbon that grows with time.
* **Impacts**: the vehicle-to-vehicle contacts of the judged outcome (first contact time and
  point, each vehicle's delta-V) and the first curb or barrier strike of each vehicle (the
  outcome's time; the point where the step's contact with the curb or barrier was). For a
  vehicle pair, the crash room's reading (:func:`nbst.models.crash.impact.crash_impacts`, the
  numbers of ``nbst crash report``; :func:`impact_vectors`): each vehicle's velocity just before
  the first touch, its velocity change over the contact episode (from the step before the first
  touch to the step after the last touch: no gap over :data:`CONTACT_GAP` s; the scene's pair
  sensors, so a crushing vehicle's crush bodies count) and the principal direction of force
  (PDOF) as a clock direction in its own frame (12 o'clock: the force comes from straight
  ahead; 3 o'clock: from its right), the direction the velocity change points from (SAE J224's
  convention).
* **Frame times** (:func:`nbst.render.core.times.frame_times` over :func:`slow_windows`): real
  time, slowed :data:`SLOW` x from :data:`SLOW_WINDOW` [0] s before each impact to [1] s after it (overlapping windows merge),
  then a hold; sim time is a piecewise-linear function of video time, so a window adds
  ``(SLOW - 1) x its length x fps`` frames.

Compute only.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from nbst.models.crash.impact import CONTACT_GAP, CrashImpacts, pdof_of

__all__ = ["CONTACT_GAP", "MARK_DT", "MARK_GAP", "POSE_DT", "SCRAPE_HALF", "SKID_HEIGHT", "SKID_SLIP", "SLOW",
           "SLOW_WINDOW", "CrashMotion", "Impact", "MarkRun", "clock_of", "impact_times", "impact_vectors", "record",
           "slow_windows", "slowed"]

#: Poses are recorded at least this often (s): at 60 fps in 4x slow motion a frame is 4.2 ms
#: of crash, so a frame is never more than a step from the pose it shows at 2 ms steps.
POSE_DT = 0.002
#: Contacts with the ground are read this often (s) for the marks: a 0.15 m piece of a skid
#: mark at 15 m/s.
MARK_DT = 0.01
#: A tyre's contact point sliding faster than this (m/s) marks the road. A rolling tyre's
#: contact point is at rest; a braked wheel here turns at most 0.8 m/s at the tread while
#: its tyre slides (nbst.models.crash.vehicle.BRAKE_KV), so a locked-wheel skid marks down
#: to ~1 m/s, and the slip of a driven or cornering tyre (a few tenths of a m/s) does not.
SKID_SLIP = 1.0
#: A tyre's lowest point within this height (m) of the road counts as on it: a sliding tyre
#: chatters (its contact comes and goes within a few mm), and a mark does not.
SKID_HEIGHT = 0.03
#: Samples of a mark further apart than this many MARK_DT end one run and start another.
MARK_GAP = 3.5
#: Slow motion: this many times slower from SLOW_WINDOW[0] s before each impact to
#: SLOW_WINDOW[1] s after it (the contact lasts ~0.1 s; the spin-out that follows is the show).
SLOW = 4.0
SLOW_WINDOW = (0.25, 0.75)


@dataclass(frozen=True)
class Impact:
    """An impact drawn on the road: a vehicle pair (``b`` None: a strike of ``a`` on a ``what``)."""

    t: float
    pos: tuple          # (x, y, z) m
    a: int
    b: int | None
    what: str           # "vehicle", "curb" or "barrier"
    delta_v_kmh: dict = field(default_factory=dict)   # name -> km/h (vehicle pairs)
    #: vehicle index -> its velocity (vx, vy) m/s, world frame, just before the contact
    v_before: dict = field(default_factory=dict)
    #: vehicle index -> its velocity change (dvx, dvy) m/s, world frame, over the contact episode
    dv: dict = field(default_factory=dict)
    #: vehicle index -> the PDOF, a clock direction 1..12 in its own frame (:func:`clock_of`)
    pdof: dict = field(default_factory=dict)
    t_end: float = math.nan   # the contact episode's last touch (s)


@dataclass(frozen=True)
class MarkRun:
    """A mark on the road: ``kind`` "skid" (tyre of ``vehicle``, half width ``half`` m) or
    "scrape" (its body), sampled at ``times`` (K,) at the points ``xy`` (K, 2)."""

    kind: str
    vehicle: int
    half: float
    times: np.ndarray
    xy: np.ndarray


@dataclass(frozen=True)
class CrashMotion:
    """A replayed crash (SI units; times in s from the start).

    times (S,), qpos (S, nq): recorded states; speed (S, n) m/s of each vehicle's CoM, vel (S, n, 3)
    its velocity (world frame);
    pos (S, n, 3) CoM; quat (S, n, 4) attitude (w, x, y, z); roll, yaw (S, n) unwrapped rad;
    marks, impacts; outcome: the replay's judged :class:`nbst.models.crash.outcome.Outcome`;
    outcome_dict: the same in the file's units; same_state: the replay ended in the file's final
    state bit for bit; same_outcome: and read the file's outcome; reading: the vehicle impacts as
    :func:`nbst.models.crash.impact.crash_impacts` reads them, from the same replay."""

    times: np.ndarray
    qpos: np.ndarray
    speed: np.ndarray
    vel: np.ndarray
    pos: np.ndarray
    quat: np.ndarray
    roll: np.ndarray
    yaw: np.ndarray
    marks: list
    impacts: list
    outcome: object
    outcome_dict: dict
    same_state: bool
    same_outcome: bool
    duration: float
    #: every vehicle impact as the crash room reads it (:func:`nbst.models.crash.impact.crash_impacts`)
    reading: CrashImpacts | None = None

    @property
    def identical(self) -> bool:
        return self.same_state and self.same_outcome

    def differs(self) -> str | None:
        """How the replay differs from the file, in words (None: it reproduces it bit for bit)."""
        if not self.same_state:
            return "the replay ends in another state than the file's (another MuJoCo?); the video shows the replay"
        if not self.same_outcome:
            return "the replay reads another outcome than the file records (another nbst?); the readout shows the replay's"
        return None

    def index(self, t: float) -> int:
        """The recorded sample nearest time ``t`` (clamped to the motion)."""
        k = int(np.searchsorted(self.times, t))
        if k >= len(self.times):
            return len(self.times) - 1
        if k > 0 and t - self.times[k - 1] <= self.times[k] - t:
            return k - 1
        return k


def _geom_ids(model, names) -> np.ndarray:
    return np.array([model.geom(nm).id for nm in names], dtype=int)


def record(d: dict, script, model) -> CrashMotion:
    """Replay the checked crash dict ``d`` (``crashfile.load``) and record it (see the module doc)."""
    import mujoco

    from nbst.models.crash import crashfile
    from nbst.models.crash import impact as impact_mod
    from nbst.models.crash import scene as scene_mod
    from nbst.models.crash import vehicle as veh

    n = script.n
    L = scene_mod.layout(model, n)
    dt = float(model.opt.timestep)
    nstep = int(round(script.duration / dt))
    pose_stride = max(1, int(math.floor(POSE_DT / dt + 1e-9)))
    mark_stride = max(1, int(round(MARK_DT / dt)))
    pre = [scene_mod.vehicle_prefix(i) for i in range(n)]
    tyres = np.array([_geom_ids(model, [f"{p}_tyre_{c}" for c in veh.CORNERS]) for p in pre])  # (n, 4)
    bodies = np.array([_geom_ids(model, [f"{p}_lower", f"{p}_cabin"]) for p in pre])            # (n, 2)
    wheel_body = np.array([[model.body(f"{p}_wheel_{c}").id for c in veh.CORNERS] for p in pre])
    ground = model.geom("ground").id
    owner = np.full(model.ngeom, -1)
    role = np.full(model.ngeom, -1)          # corner 0..3 for a tyre, 4 for a body geom
    for i in range(n):
        owner[tyres[i]], role[tyres[i]] = i, np.arange(4)
        owner[bodies[i]], role[bodies[i]] = i, 4
    strike_of = np.full(model.ngeom, "", dtype=object)   # the static geoms a strike is on
    for what in ("curbs", "barriers"):
        try:
            b = model.body(what).id
        except KeyError:
            continue
        strike_of[np.nonzero(model.geom_bodyid == b)[0]] = what[:-1]
    has_strikes = bool((strike_of != "").any())
    half_width = np.array([[float(model.geom_size[g][1]) for g in row] for row in tyres])
    radius = np.array([[float(model.geom_size[g][0]) for g in row] for row in tyres])

    keep = sorted(set(range(0, nstep + 1, pose_stride)) | {nstep})
    slot = {k: j for j, k in enumerate(keep)}
    Q = np.empty((len(keep), model.nq))
    V = np.empty((len(keep), n))
    W = np.empty((len(keep), n, 3))
    vi = L.qvel[:, None] + np.arange(3)
    Q[0] = d["qpos0"]
    W[0] = np.asarray(d["qvel0"], float)[vi]
    V[0] = np.linalg.norm(W[0], axis=-1)
    samples: dict = {}                       # (kind, vehicle, corner) -> [(t, x, y, sliding)]
    strikes: dict = {}                       # (vehicle, what) -> [(t, pos)]
    vel6 = np.zeros(6)

    impacts_step, impacts_of = impact_mod.impact_recorder(d, script, model)   # the report's reading, same replay

    def on_step(k: int, md) -> None:
        impacts_step(k, md)
        j = slot.get(k)
        if j is not None:
            Q[j] = md.qpos
            W[j] = md.qvel[vi]
            V[j] = np.linalg.norm(W[j], axis=-1)
        # after mj_step, data's contacts, poses and body velocities are those of the state the
        # step started from: time (k - 1) dt
        t = (k - 1) * dt
        nc = md.ncon
        geom = md.contact.geom[:nc]
        if has_strikes and nc:
            hit = strike_of[geom]
            for c in np.nonzero((hit[:, 0] != "") | (hit[:, 1] != ""))[0]:
                g0, g1 = geom[c]
                me, what = (g1, hit[c, 0]) if hit[c, 0] else (g0, hit[c, 1])
                if owner[me] >= 0 and (owner[me], what) not in strikes:
                    strikes[(owner[me], what)] = (t, tuple(float(x) for x in md.contact.pos[c]))
        if k % mark_stride:
            return
        for c in np.nonzero((geom == ground).any(axis=1))[0]:
            g = geom[c, 1] if geom[c, 0] == ground else geom[c, 0]
            if owner[g] >= 0 and role[g] == 4:
                p = md.contact.pos[c]
                samples.setdefault(("scrape", owner[g], int(np.nonzero(bodies[owner[g]] == g)[0][0])), []).append(
                    (t, p[0], p[1], True))
        # a tyre marks the road where its lowest point, within SKID_HEIGHT of the road (a sliding
        # tyre chatters: its contact comes and goes), slides faster than SKID_SLIP
        for i in range(n):
            for corner in range(4):
                wb = wheel_body[i, corner]
                c, axle = md.xpos[wb], md.xmat[wb].reshape(3, 3)[:, 1]
                down = np.array([0.0, 0.0, -1.0]) + axle[2] * axle      # -z within the wheel's plane
                norm = math.sqrt(down @ down)
                if norm < 0.5:                                           # the wheel lies flat
                    continue
                r = radius[i, corner] * down / norm
                p = c + r
                if p[2] > SKID_HEIGHT:
                    continue
                mujoco.mj_objectVelocity(model, md, mujoco.mjtObj.mjOBJ_BODY, wb, vel6, 0)
                w = vel6[:3]                                             # the point's velocity: v + w x r
                slip = math.hypot(vel6[3] + w[1] * r[2] - w[2] * r[1], vel6[4] + w[2] * r[0] - w[0] * r[2])
                samples.setdefault(("skid", i, corner), []).append((t, p[0], p[1], slip > SKID_SLIP))

    q_end, outcome = crashfile.replay(d, script, model, on_step=on_step)
    od = crashfile.outcome_dict(outcome, script, L.mass)
    same_state = bool(np.array_equal(q_end, np.asarray(d["final_qpos"], float)))
    qa = L.qpos[:, None]
    pos = Q[:, qa + np.arange(3)]
    quat = Q[:, qa + np.arange(3, 7)]
    w, x, y, z = np.moveaxis(quat, -1, 0)
    roll = np.unwrap(np.arctan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y)), axis=0)
    yaw = np.unwrap(np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z)), axis=0)
    marks = _runs(samples, half_width, mark_stride * dt)
    times = np.array(keep, float) * dt
    found = impacts_of(q_end)
    impacts = [impact_vectors(im, found) for im in _impacts(outcome, od, script, strikes)]
    return CrashMotion(times=times, qpos=Q, speed=V, vel=W, pos=pos, quat=quat, roll=roll, yaw=yaw,
                       marks=marks, impacts=impacts, outcome=outcome, outcome_dict=od,
                       same_state=same_state, same_outcome=od == d["outcome"], duration=nstep * dt, reading=found)


#: A scrape's half width (m): a body corner or edge dragged over the road.
SCRAPE_HALF = 0.15


def _runs(samples: dict, half_width: np.ndarray, dt: float) -> list[MarkRun]:
    """Runs of sliding samples (no gap over MARK_GAP sample periods), at least two long."""
    out = []
    for (kind, i, part), rows in sorted(samples.items(), key=lambda kv: kv[0]):
        a = np.array(rows, float)
        keep = a[:, 3] > 0
        run: list = []

        def flush():
            if len(run) >= 2:
                r = np.array(run)
                out.append(MarkRun(kind=kind, vehicle=i, half=float(half_width[i, part]) if kind == "skid"
                                   else SCRAPE_HALF, times=r[:, 0], xy=r[:, 1:3]))
            run.clear()

        last = -math.inf
        for row, ok in zip(a, keep):
            if not ok or row[0] - last > MARK_GAP * dt:
                flush()
            if ok:
                run.append(row[:3])
                last = row[0]
        flush()
    return out


def _impacts(outcome, od: dict, script, strikes: dict) -> list[Impact]:
    names = script.names()
    out = [Impact(t=c["t"], pos=tuple(c["pos"]), a=names.index(c["a"]), b=names.index(c["b"]), what="vehicle",
                  delta_v_kmh=dict(c["delta_v_kmh"])) for c in od["contacts"]]
    for i, vo in enumerate(outcome.vehicles):
        for what, t in (("curb", vo.curb), ("barrier", vo.barrier)):
            if not math.isnan(t):
                t0, p = strikes.get((i, what), (t, (math.nan,) * 3))
                out.append(Impact(t=float(t), pos=p, a=i, b=None, what=what))
    return sorted(out, key=lambda m: (m.t, m.a))


def clock_of(dv_body) -> int:
    """The clock direction (1..12) a force comes from, given the velocity change ``dv_body``
    (dx forward, dy left) it made in the vehicle's frame: 12 from straight ahead (a frontal
    hit: the change points back), 3 from the right, 6 from behind, 9 from the left
    (:func:`nbst.models.crash.impact.pdof_of`'s clock; 12 for no change)."""
    return pdof_of(dv_body)[1] or 12


def impact_vectors(im: Impact, found: CrashImpacts) -> Impact:
    """``im`` with, for a vehicle pair, each vehicle's velocity before the contact, its velocity
    change over the contact episode and its PDOF, from the crash room's reading of the same
    replay (``found``: :func:`nbst.models.crash.impact.crash_impacts`): the pair's episode that
    starts nearest ``im.t``; other impacts, and a pair whose sensors read no episode, unchanged."""
    from dataclasses import replace

    if im.what != "vehicle" or im.b is None:
        return im
    a, b = min(im.a, im.b), max(im.a, im.b)
    mine = [p for p in found.impacts if (p.a, p.b) == (a, b)]
    if not mine:
        return im
    p = min(mine, key=lambda p: abs(p.t - im.t))
    v_before = {v.vehicle: v.v_before for v in p.vehicles}
    dv = {v.vehicle: v.dv_world for v in p.vehicles}
    pdof = {v.vehicle: v.pdof_clock or 12 for v in p.vehicles}
    return replace(im, v_before=v_before, dv=dv, pdof=pdof, t_end=float(p.t_end))


def impact_times(outcome: dict) -> list[float]:
    """The times (s) of a crash's impacts from its outcome (a crash file's ``outcome``, or
    :attr:`CrashMotion.outcome_dict`): each vehicle pair's first contact, each curb or barrier
    strike (what :attr:`CrashMotion.impacts` holds, known before the replay)."""
    out = [float(c["t"]) for c in outcome["contacts"]]
    for v in outcome["vehicles"]:
        out += [float(v[k]) for k in ("curb_strike_t", "barrier_strike_t") if v.get(k) is not None]
    return sorted(out)


def slow_windows(times, duration: float, window=SLOW_WINDOW) -> list[tuple[float, float]]:
    """The merged (start, end) sim seconds of slow motion around each impact time, within [0, duration]."""
    spans = sorted((max(0.0, t - window[0]), min(duration, t + window[1])) for t in times)
    out: list = []
    for a, b in spans:
        if b <= a:
            continue
        if out and a <= out[-1][1]:
            out[-1] = (out[-1][0], max(out[-1][1], b))
        else:
            out.append((a, b))
    return out


def slowed(t: float, windows) -> bool:
    return any(a <= t < b for a, b in windows)
