"""How much the bowling frame's outcome depends on its assumed contact parameters (issue 22).

The ball-pin and pin-pin contacts of models/bowling/scene.py share one geom setting:
sliding friction 0.12 (assumed, not calibrated) and solref (0.008 s, damping ratio 0.2)
(calibrated by a note to a restitution of about 0.5). This script varies, one at a time,
ball-pin friction, pin-pin friction, ball-pin restitution and pin-pin restitution on the
compiled frame model (``frame.frame_model()``, copied; the scene's defaults are untouched) and
prints, for each setting:

* the restitution it gives, measured by a two-body collision in the same model (gravity
  off, the bodies 2 m above the lane, every other body parked): a ball at 7 m/s into a free
  pin at the pin's centre-of-mass height, and a pin at 3 m/s into another at belly height,
  each the mean over 4 yaws of the struck pin (a quarter of the 16-gon collision mesh's
  period). Restitution is Newton's: minus the ratio of the relative normal velocity of the
  two material points at the contact after and before the collision;
* the settled leave of the strike line (spares.STRIKE) and of the pocket-cell delivery
  (board 22 at the foul line, 1.6106 deg, 68.487 deg rotation: the one aimed at board 17.5
  at 6 deg), each thrown once without noise;
* the strike probability of the strike line and of the pocket-cell delivery under the default
  release noise (n throws each, one seed: the same throws for every setting, so it also counts
  the throws whose strike / no-strike flipped against the default), with 95 % Wilson intervals;
* carry: strikes among those noisy frames (both deliveries) whose ball entered on boards 17-18;
* the conversion of three spare picks of docs/bowling.md (10, 7 and 3-6-10), n noisy
  throws each.

Separating ball-pin from pin-pin: MuJoCo mixes two geoms' contact parameters by priority
(the higher priority geom's friction, solref and solimp are used whole) and, at equal
priority, takes the element-wise maximum of friction and the solmix-weighted mean of solref
(MuJoCo docs, Modeling, "Contact parameters"). The copy raises every static surface's
priority from 1 to 2 and gives the ball priority 1 (the pins keep 0): ball-lane and pin-lane
contacts still use the surface's parameters, pin-pin contacts the pins' and ball-pin
contacts the ball's. With the default values that copy gives the same frame bit for bit
(checked and printed). The restitution settings move the damping ratio to reach the
default's measured restitution -0.1 and +0.1 (found by bisection); the time constant stays
8 ms.

    python benchmarks/bench_bowling_contacts.py [--quick] [--jobs 2] [--pocket-n 40] [--spare-n 20] [--seed 1]
"""
from __future__ import annotations

import argparse
import copy
import math
import multiprocessing as mp
import signal
import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed

import numpy as np

from nbst.models.bowling import lane, scene
from nbst.models.bowling.lane import frame, noise, spares
from nbst.models.bowling import pin as pinmod

#: The defaults: ball-pin and pin-pin friction, damping ratio (scene.py).
MU0 = scene.MU_BALL_PIN
TC0, ZETA0 = scene.SOLREF_BODY
#: The pocket cell's delivery (docs/results/bowling.md, "The pocket map and carry").
POCKET = lane.Delivery(board=22.0, at="foul", angle=1.6105595330681906, rotation=68.48689904701298)
#: Spare picks of docs/bowling.md's table (straight spare ball, rounded as printed there).
SPARE_PICKS = {
    "10": (lane.Delivery(board=34.0, at="foul", angle=2.32, **spares.SPARE_BALL), (10,)),
    "7": (lane.Delivery(board=6.0, at="foul", angle=-2.32, **spares.SPARE_BALL), (7,)),
    "3-6-10": (lane.Delivery(board=29.3, at="foul", angle=1.43, **{**spares.SPARE_BALL, "mph": 21.0}), (3, 6, 10)),
}
#: Restitution test: impact speeds (m/s) and the struck pin's yaws (deg; the mesh repeats every 22.5).
BALL_PIN_SPEED = 7.0
PIN_PIN_SPEED = 3.0
YAWS = (0.0, 5.625, 11.25, 16.875)
#: Where in a step the bodies first touch (fractions of one step's travel): the collision lasts
#: ~8 steps, and the restitution of one collision moves by ~0.1 with this phase.
PHASES = tuple(np.arange(8) / 8)
#: Gap between the bodies at the start (m), and their height above the lane (m).
GAP = 0.005
TEST_Z = 2.0


# --------------------------------------------------------------------- the contact model


def pin_geoms(m) -> list[int]:
    """Ids of the pins' collision geoms (the visual meshes do not collide)."""
    return [g for g in range(m.ngeom) if m.geom_contype[g] and int(m.geom_bodyid[g]) in
            {m.body(f"pin{n}").id for n in scene.PIN_NUMBERS}]


def contact_model(base, bp_mu=MU0, pp_mu=MU0, bp_zeta=ZETA0, pp_zeta=ZETA0):
    """A copy of ``base`` whose ball-pin contacts use (bp_mu, bp_zeta) and pin-pin (pp_mu, pp_zeta);
    surfaces keep theirs (see the module docstring)."""
    m = copy.copy(base)
    ball = m.geom("ball").id
    pr = np.array(m.geom_priority)
    pr[pr >= 1] += 1
    pr[ball] = 1
    m.geom_priority[:] = pr
    m.geom_friction[ball, 0] = bp_mu
    m.geom_solref[ball] = (TC0, bp_zeta)
    for g in pin_geoms(m):
        m.geom_friction[g, 0] = pp_mu
        m.geom_solref[g] = (TC0, pp_zeta)
    return m


# --------------------------------------------------------------------- restitution


def _yaw(deg: float) -> list:
    a = math.radians(deg) / 2
    return [math.cos(a), 0.0, 0.0, math.sin(a)]


def restitution(m, kind: str, yaw: float = 0.0, phase: float = 0.0, speed: float | None = None) -> float:
    """Newton's restitution of one head-on collision in model ``m`` (gravity off, sleep off, 2 m up):
    ``kind`` "ball-pin" (the ball into pin 1 at its centre-of-mass height) or "pin-pin" (pin 2 into
    pin 1, both upright, at belly height); pin 1 turned ``yaw`` deg about its axis; the gap at the
    start is :data:`GAP` plus ``phase`` (0..1) of one step's travel, which sets where in a step the
    bodies first touch."""
    import mujoco

    m = copy.copy(m)
    m.opt.gravity[:] = 0.0
    m.opt.enableflags &= ~int(mujoco.mjtEnableBit.mjENBL_SLEEP)
    d = mujoco.MjData(m)
    qpos, qvel = np.array(m.qpos0, dtype=float), np.zeros(m.nv)
    qa = {n: int(m.joint(f"pin{n}_free").qposadr[0]) for n in scene.PIN_NUMBERS}
    va = {n: int(m.joint(f"pin{n}_free").dofadr[0]) for n in scene.PIN_NUMBERS}
    for k, n in enumerate(scene.PIN_NUMBERS):
        qpos[qa[n]:qa[n] + 7] = [frame.PARK_X - frame.PARK_STEP * k, 0.0, scene.FLOOR_Z, 1.0, 0.0, 0.0, 0.0]
    bq, bv = int(m.joint("ball_free").qposadr[0]), int(m.joint("ball_free").dofadr[0])
    qpos[bq:bq + 7] = [frame.PARK_X - 5.0, 0.0, 0.5, 1.0, 0.0, 0.0, 0.0]
    qpos[qa[1]:qa[1] + 7] = [0.0, 0.0, TEST_Z, *_yaw(yaw)]
    geo = pinmod.geometry()
    belly = max(pinmod.profile()[:, 0])
    if kind == "ball-pin":
        v = BALL_PIN_SPEED if speed is None else speed
        gap = GAP + phase * v * m.opt.timestep
        qpos[bq:bq + 7] = [-(scene.BALL_RADIUS + belly + gap), 0.0, TEST_Z + geo.com[2], 1.0, 0.0, 0.0, 0.0]
        qvel[bv] = v
        a, b = m.body("ball").id, m.body("pin1").id
    elif kind == "pin-pin":
        v = PIN_PIN_SPEED if speed is None else speed
        gap = GAP + phase * v * m.opt.timestep
        qpos[qa[2]:qa[2] + 7] = [-(2 * belly + gap), 0.0, TEST_Z, 1.0, 0.0, 0.0, 0.0]
        qvel[va[2]] = v
        a, b = m.body("pin2").id, m.body("pin1").id
    else:
        raise ValueError(f"kind: 'ball-pin' or 'pin-pin', got {kind!r}")
    d.qpos[:], d.qvel[:] = qpos, qvel
    mujoco.mj_forward(m, d)

    def touching():
        return [c for c in d.contact[:d.ncon] if {int(m.geom_bodyid[c.geom1]), int(m.geom_bodyid[c.geom2])} == {a, b}]

    def normal_speed(p_loc, n):  # (v_b - v_a) . n at the material points p_loc[a], p_loc[b]
        v = []
        for body in (a, b):
            R = d.xmat[body].reshape(3, 3)
            jp = np.zeros((3, m.nv))
            mujoco.mj_jac(m, d, jp, None, d.xpos[body] + R @ p_loc[body], body)
            v.append(jp @ d.qvel)
        return float((v[1] - v[0]) @ n)

    for _ in range(1000):
        before = (d.qpos.copy(), d.qvel.copy())
        mujoco.mj_step(m, d)
        cs = touching()
        if cs:
            break
    else:
        raise RuntimeError(f"restitution test ({kind}): the bodies never met")
    p = np.mean([c.pos for c in cs], axis=0)
    n = np.array(cs[0].frame[:3])
    if int(m.geom_bodyid[cs[0].geom1]) != a:
        n = -n  # from a to b
    p_loc = {body: d.xmat[body].reshape(3, 3).T @ (p - d.xpos[body]) for body in (a, b)}
    after = (d.qpos.copy(), d.qvel.copy())
    d.qpos[:], d.qvel[:] = before
    mujoco.mj_forward(m, d)
    pre = normal_speed(p_loc, n)  # free flight until this step: the approach speed
    d.qpos[:], d.qvel[:] = after
    mujoco.mj_forward(m, d)
    clear = 0
    for _ in range(1000):
        mujoco.mj_step(m, d)
        clear = clear + 1 if not touching() else 0
        if clear >= 5:
            break
    return -normal_speed(p_loc, n) / pre


def restitutions(m, kind: str) -> np.ndarray:
    """Restitution over every yaw of :data:`YAWS` and phase of :data:`PHASES`."""
    return np.array([restitution(m, kind, y, ph) for y in YAWS for ph in PHASES])


def mean_restitution(m, kind: str) -> float:
    return float(np.mean(restitutions(m, kind)))


def zeta_for(base, kind: str, target: float, lo: float = 0.02, hi: float = 0.9, iters: int = 14) -> float:
    """The damping ratio (ball-pin or pin-pin, the other at its default) whose mean restitution is ``target``."""
    key = "bp_zeta" if kind == "ball-pin" else "pp_zeta"
    e = lambda z: mean_restitution(contact_model(base, **{key: z}), kind)  # noqa: E731
    e_lo, e_hi = e(lo), e(hi)
    if not e_hi < target < e_lo:
        raise ValueError(f"restitution {target:.3f} ({kind}) is outside [{e_hi:.3f}, {e_lo:.3f}] over damping ratio {lo}-{hi}")
    for _ in range(iters):
        mid = (lo + hi) / 2
        if e(mid) > target:
            lo = mid
        else:
            hi = mid
    return (lo + hi) / 2


# --------------------------------------------------------------------- workers

_W: dict = {}


def _init() -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the parent's
    _W["base"] = frame.frame_model()
    _W["models"] = {}


def _run(params: tuple, delivery, standing):
    models = _W["models"]
    if params not in models:
        models[params] = contact_model(_W["base"], *params)
    r = frame.run_frame(delivery, standing=standing, model=models[params])
    return r.leave, r.converted, r.board_at_pins, r.cap_hit


# --------------------------------------------------------------------- main


def pct(k: int, n: int) -> str:
    lo, hi = noise.wilson(k, n)
    return f"{100 * k / n:.0f} % ({k}/{n}; {100 * lo:.0f}-{100 * hi:.0f})"


def leave_text(leave) -> str:
    return "-".join(map(str, leave)) or "strike"


def positive_int(s: str) -> int:
    try:
        v = int(s)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a whole number >= 1, got {s!r}") from None
    if v < 1:
        raise argparse.ArgumentTypeError(f"must be a whole number >= 1, got {s!r}")
    return v


def main() -> int:
    ap = argparse.ArgumentParser(allow_abbrev=False, description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="8 noisy throws of each delivery and 4 of each spare (a smoke run, 1-2 min)")
    ap.add_argument("--jobs", type=positive_int, default=2, help="worker processes (default 2)")
    ap.add_argument("--pocket-n", type=positive_int, default=None, help="noisy throws of the strike line and of the pocket cell, each, per setting (default 40)")
    ap.add_argument("--spare-n", type=positive_int, default=None, help="noisy throws per spare per setting (default 20)")
    ap.add_argument("--seed", type=int, default=1, help="noise seed (default 1)")
    args = ap.parse_args()
    n_pocket = args.pocket_n or (8 if args.quick else 40)
    n_spare = args.spare_n or (4 if args.quick else 20)
    t_start = time.perf_counter()
    base = frame.frame_model()

    print("1. the contact model: ball-pin and pin-pin separated by geom priority (defaults unchanged)")
    r0 = frame.run_frame(spares.STRIKE, model=base)
    r1 = frame.run_frame(spares.STRIKE, model=contact_model(base))
    same = np.array_equal(r0.final_qpos, r1.final_qpos)
    print(f"   strike line on the scene's model and on the separated copy: final state identical: {'yes' if same else 'NO'}")
    m0 = contact_model(base)
    e0 = {}
    print(f"   restitution of the defaults, {len(YAWS)} yaws x {len(PHASES)} phases a speed (mean, min-max):")
    for kind, speeds in (("ball-pin", (3.0, BALL_PIN_SPEED, 9.0)), ("pin-pin", (1.0, PIN_PIN_SPEED, 6.0))):
        row = []
        for v in speeds:
            es = np.array([restitution(m0, kind, y, ph, v) for y in YAWS for ph in PHASES])
            row.append(f"{v:g} m/s {es.mean():.3f} ({es.min():.2f}-{es.max():.2f})")
            if v == (BALL_PIN_SPEED if kind == "ball-pin" else PIN_PIN_SPEED):
                e0[kind] = float(es.mean())
        print(f"   {kind:<9} " + "; ".join(row))
    e_bp0, e_pp0 = e0["ball-pin"], e0["pin-pin"]
    z = {}
    for kind, e0 in (("ball-pin", e_bp0), ("pin-pin", e_pp0)):
        for de in (-0.1, 0.1):
            z[kind, de] = zeta_for(base, kind, e0 + de)
    settings = [
        ("default", dict()),
        ("ball-pin mu x0.5", dict(bp_mu=0.5 * MU0)),
        ("ball-pin mu x1.5", dict(bp_mu=1.5 * MU0)),
        ("pin-pin mu x0.5", dict(pp_mu=0.5 * MU0)),
        ("pin-pin mu x1.5", dict(pp_mu=1.5 * MU0)),
        ("ball-pin e -0.1", dict(bp_zeta=z["ball-pin", -0.1])),
        ("ball-pin e +0.1", dict(bp_zeta=z["ball-pin", 0.1])),
        ("pin-pin e -0.1", dict(pp_zeta=z["pin-pin", -0.1])),
        ("pin-pin e +0.1", dict(pp_zeta=z["pin-pin", 0.1])),
    ]
    params = {}
    print(f"\n{'setting':<18} {'ball-pin mu':>11} {'zeta':>7} {'e':>6} | {'pin-pin mu':>10} {'zeta':>7} {'e':>6}")
    for name, kw in settings:
        p = dict(bp_mu=MU0, pp_mu=MU0, bp_zeta=ZETA0, pp_zeta=ZETA0)
        p.update(kw)
        params[name] = (p["bp_mu"], p["pp_mu"], p["bp_zeta"], p["pp_zeta"])
        m = contact_model(base, **p)
        print(f"{name:<18} {p['bp_mu']:>11.3f} {p['bp_zeta']:>7.4f} {mean_restitution(m, 'ball-pin'):>6.3f} | "
              f"{p['pp_mu']:>10.3f} {p['pp_zeta']:>7.4f} {mean_restitution(m, 'pin-pin'):>6.3f}", flush=True)
    t_rest = time.perf_counter() - t_start

    noisy = {"strike": noise.sample(spares.STRIKE, n_pocket, args.seed), "pocket": noise.sample(POCKET, n_pocket, args.seed)}
    spare_throws = {k: noise.sample(d, n_spare, args.seed) for k, (d, _) in SPARE_PICKS.items()}
    tasks = []  # (setting, group, index, delivery, standing)
    for name, _ in settings:
        tasks.append((name, "strike line", 0, spares.STRIKE, None))
        tasks.append((name, "pocket", 0, POCKET, None))
        for g, throws in noisy.items():
            tasks += [(name, f"{g} noisy", i, d, None) for i, d in enumerate(throws)]
        for k, (_, standing) in SPARE_PICKS.items():
            tasks += [(name, f"spare {k}", i, d, standing) for i, d in enumerate(spare_throws[k])]
    print(f"\n2. frames: {len(tasks)} ({len(settings)} settings x (2 + 2 x {n_pocket} noisy strike-line and pocket + "
          f"{len(SPARE_PICKS)} x {n_spare} spare)) on {args.jobs} processes", flush=True)
    out: dict = {}
    t0 = time.perf_counter()
    pool = ProcessPoolExecutor(max_workers=args.jobs, mp_context=mp.get_context("spawn"), initializer=_init)
    interrupted = False
    futs: dict = {}
    try:
        for t in tasks:
            futs[pool.submit(_run, params[t[0]], t[3], t[4])] = t
        for i, f in enumerate(as_completed(futs), 1):
            t = futs[f]
            out[t[0], t[1], t[2]] = f.result()
            if i % 100 == 0 or i == len(tasks):
                print(f"   {i}/{len(tasks)} frames, {time.perf_counter() - t0:.0f} s", file=sys.stderr, flush=True)
    except KeyboardInterrupt:
        interrupted = True
        print("interrupted: printing the settings finished so far", file=sys.stderr)
        for f in futs:
            f.cancel()
    finally:
        pool.shutdown(wait=not interrupted, cancel_futures=True)
    t_frames = time.perf_counter() - t0

    def done(name):
        return all((name, t[1], t[2]) in out for t in tasks if t[0] == name)

    def strikes(name, g):
        return [out[name, f"{g} noisy", i][1] for i in range(n_pocket)]

    def flips(name, g):
        if not done("default"):
            return "-"
        now, was = strikes(name, g), strikes("default", g)
        return f"+{sum(a and not b for a, b in zip(now, was))}/-{sum(b and not a for a, b in zip(now, was))}"

    print(f"\n3. strikes (seed {args.seed}; 95 % Wilson intervals in %; flips: of the same noisy throws, "
          f"strikes gained / lost against the default)")
    print(f"{'setting':<18} {'strike line':>11} {'pocket':>8} | {'strike line, noisy':>22} {'flips':>7} | "
          f"{'pocket cell, noisy':>22} {'flips':>7} | {'carry (17-18 entries)':>22}")
    for name, _ in settings:
        if not done(name):
            print(f"{name:<18} (not finished)")
            continue
        sl, pk = out[name, "strike line", 0], out[name, "pocket", 0]
        rs = [out[name, f"{g} noisy", i] for g in noisy for i in range(n_pocket)]
        hits = [r for r in rs if r[2] is not None and spares.POCKET_BOARDS[0] <= r[2] <= spares.POCKET_BOARDS[1]]
        carry = pct(sum(r[1] for r in hits), len(hits)) if hits else "no hits"
        ks, kp = sum(strikes(name, "strike")), sum(strikes(name, "pocket"))
        print(f"{name:<18} {leave_text(sl[0]):>11} {leave_text(pk[0]):>8} | {pct(ks, n_pocket):>22} "
              f"{flips(name, 'strike'):>7} | {pct(kp, n_pocket):>22} {flips(name, 'pocket'):>7} | {carry:>22}")

    print(f"\n4. spares converted ({n_spare} noisy throws each, seed {args.seed})")
    print(f"{'setting':<18} " + " | ".join(f"{'leave ' + k:>22}" for k in SPARE_PICKS))
    for name, _ in settings:
        if not done(name):
            print(f"{name:<18} (not finished)")
            continue
        cells = []
        for key in SPARE_PICKS:
            rr = [out[name, f"spare {key}", i] for i in range(n_spare)]
            cells.append(f"{pct(sum(r[1] for r in rr), n_spare):>22}")
        print(f"{name:<18} " + " | ".join(cells))
    caps: dict = {}
    for kk, v in out.items():
        if v[3]:
            caps[kk[1].replace(" noisy", "")] = caps.get(kk[1].replace(" noisy", ""), 0) + 1
    print(f"\n   frames that hit the {frame.CAP_AFTER_PINS:g} s cap (outcome read there): {sum(caps.values())} of {len(out)}"
          + (f" ({', '.join(f'{k}: {v}' for k, v in caps.items())})" if caps else ""))
    print(f"   restitution tests and bisection {t_rest:.0f} s; frames {t_frames:.0f} s wall on {args.jobs} processes; "
          f"total {time.perf_counter() - t_start:.0f} s")
    return 130 if interrupted else 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except KeyboardInterrupt:  # before the frames: nothing measured yet to print
        print("interrupted before the frames ran", file=sys.stderr)
        sys.exit(130)
