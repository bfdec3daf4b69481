"""Flush pocket hits against entry angle (issue 34): do the fitted pins ever leave a solid 4?

    python benchmarks/bench_pocket_angle.py [--releases "pro:4,6,7,8;twohander:8"] [--n 200]
                                            [--seed 1] [--jobs 1] [--setting key=value,...] [--cache DIR]
    python benchmarks/bench_pocket_angle.py --restitution [--setting kick_zeta=0.2]
    python benchmarks/bench_pocket_angle.py --two-pin [--setting spot_mm=6]
    python benchmarks/bench_pocket_angle.py --collision-segments 32 [--two-pin]   # the pins as 32-gons (probe)
    python benchmarks/bench_pocket_angle.py --by-board 16,19.5,0.25 --n 40 [--seed 11] [--setting h=0.0005]
                                            [--profile league150]

Bowlers' lore (a right-hander): a ball that comes in too strong, too high or at too much angle
leaves the 4 (the 2 pin goes round the 4, or drives behind it), the 4-7, the 4-9 or worse: "a
high hit on the 1-3 pocket can tend to leave combinations such as a 4 pin, 9 pin, 4-7, 4-9,
4-6-7-9-10" (bowl.com, "Looking for the Perfect Strike"); "when you leave the 4-pin, this is an
indication that the ball is too high in the pocket" (Denver Bowling, "I Got A Bad Break", 2005).

**The throws.** For each release of ``--releases`` (a profile's strike ball: its speed, revs and
tilt) and each entry angle listed, :func:`.spares.aim_entry` finds the line (foul board, launch
angle, axis rotation) whose ball alone crosses the head pin's line on board 17.5 at that angle
(the axis rotation is the entry angle's knob); ``--n`` noisy copies of it under the pro's fitted
strike-ball noise (``profiles.PRO_NOISE``; the two-hander's is the same), seed ``--seed`` + the
bucket's index. Each throw's lane phase runs once (``frame.deck_start``, cached); the pin deck is
then run from there on the scene's fitted pins, or on a copy with ``--setting``'s pins
(``bench_carry_fit.pin_deck_model``: the bounded probe of one parameter, e.g. ``kick_zeta``, the
kickbacks' contact damping ratio; ``--restitution`` prints a pin's rebound off the kickback), or with
the pins set off their spots (``spot_mm``: ``bench_carry_fit.scatter``, each pin's x and y offset
normal with that sigma, drawn anew for every throw of every bucket, the same draws in every run).

**Figures.** Every throw is binned by where its ball actually entered (board and angle at the
head pin's line, the deck start's): flush hits (boards 17-18) and high pocket hits (18-19) per
whole-degree bin of entry angle; per bin the strikes, the solid 10s as ``names.leave_names`` names
them, the 4 left alone (``names``' solid 4 on a pocket hit), the leaves with the 4 in them
(4-7, 4-9, 4-7-10 ...) and those with the 9, with Wilson 95 % intervals. Results go to ``--cache``
as they come (resumable; keyed by the lane scene, ``lane.SCENE``, and the setting). ``--two-pin``: on
the flush hits, the first body to touch the 4 and the line the 2 pin is sent along
(:func:`two_pin_paths`).

**By board** (``--by-board LO,HI,STEP``, issue 48: where the pocket's high side falls off). ``--n`` of
the ``pro``'s first balls (or ``--profile``'s: its strike ball under its own noise,
``profiles.profile(name).noise``), seed ``--seed`` (by default 11, a seed the calibration bench calls
"fit"), each carried sideways on the deck (:func:`shifted`: the same speed, spin and entry angle, the
ball moved along y where it crosses the deck front; the deck's friction is the same on every board, so
this is the ball arriving on another board) onto every bin of boards LO..HI: throw i enters bin b on
board ``lo_b + STEP * u_i``, u_i uniform from ``derived_seed(seed, 48)`` (the same u_i in every bin and
setting). Per bin: strikes, the 10 alone, splits (``names.is_split``), leaves with the 9 and the
commonest leaves, with Wilson 95 % intervals; ``--setting h=0.0005`` runs the pin deck at half the step.
"""
from __future__ import annotations

import argparse
import copy
import importlib.util
import json
import os
import pickle
import time
from pathlib import Path

import numpy as np

from nbst.models.bowling import lane, pin, scene
from nbst.models.bowling.lane import frame, names, noise, profiles, spares
from nbst.models.bowling.lane.units import BOARD_WIDTH, hand_sign
from nbst.seeds import derived_seed


def _carry_fit():
    path = Path(__file__).resolve().parent / "bench_carry_fit.py"
    spec = importlib.util.spec_from_file_location("bench_carry_fit", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


CF = _carry_fit()
FLUSH = (17.0, 18.0)
HIGH = (18.0, 19.0)
#: The throws whose pin deck is run: the ball on these boards at the head pin's line (the tables' span).
REPLAYED = (16.5, 19.0)
#: The pin scatter's seeds (``--setting spot_mm=``): throw i of bucket b draws its pins' offsets from
#: seed 10,000 + SPOT_SEED (b + 1) + i (``bench_carry_fit._replay``), apart from every other throw's.
SPOT_SEED = 1_000_000
#: How long after it first moves the 2 pin's heading is read (s): past its collision with the head
#: pin or the ball (a contact lasts about 8 ms), before it reaches the 4 (about 50 ms at 4 m/s).
TWO_PIN_S = 0.015


def parse_releases(text: str) -> list:
    """[(profile, angle), ...] of 'pro:4,6;twohander:8'."""
    out = []
    for part in filter(None, text.split(";")):
        name, angles = part.split(":")
        profiles.profile(name)
        out += [(name, float(a)) for a in angles.split(",")]
    return out


def capture(cache: Path, buckets: list, n: int, seed: int) -> dict:
    """Per bucket (profile, angle): the aimed line and ``n`` noisy throws with their deck starts."""
    path = cache / f"angle_starts_n{n}_seed{seed}.pkl"
    out = pickle.loads(path.read_bytes()) if path.exists() else {}
    m = frame.frame_model()
    for b, (name, ang) in enumerate(buckets):
        k = f"{name}@{ang:g}"
        if k in out:
            continue
        t0 = time.time()
        d, r = spares.aim_entry(17.5, ang, base=profiles.profile(name).delivery())
        throws = noise.sample(d, n, seed + b, profiles.PRO_NOISE)
        out[k] = {"line": d.to_dict(), "alone": (r.board_at_pins, r.entry_angle_deg),
                  "throws": [(dv, frame.deck_start(dv, model=m)) for dv in throws]}
        print(f"{k}: line from board {d.foul_board():.1f} at the foul line, {d.angle:+.2f} deg, rotation "
              f"{d.rotation:.1f} deg, {d.mph:g} mph {d.rpm:g} rpm: alone board {r.board_at_pins:.2f} at "
              f"{r.entry_angle_deg:.2f} deg; {n} deck starts in {time.time() - t0:.0f} s", flush=True)
        cache.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(".tmp")
        tmp.write_bytes(pickle.dumps(out))
        os.replace(tmp, path)
    return out


def replay(starts: dict, buckets: list, prm: dict, jobs: int) -> list:
    """(bucket, board, angle, leave, cap) of every throw that reached the pins on :data:`REPLAYED`'s
    boards, its pin deck on the setting ``prm``."""
    calls, tags = [], []
    for b, (name, ang) in enumerate(buckets):
        for i, (dv, st) in enumerate(starts[f"{name}@{ang:g}"]["throws"]):
            if st.board is not None and REPLAYED[0] <= st.board <= REPLAYED[1]:
                calls.append((dv, st, SPOT_SEED * (b + 1) + i))  # each throw its own pin scatter
                tags.append((f"{name}@{ang:g}", st.board, st.angle))
    return [(*t, list(lv), cap) for t, (lv, cap) in zip(tags, _run(calls, prm, jobs))]


def board_starts(cache: Path, n: int, seed: int, name: str = "pro") -> list:
    """``n`` of profile ``name``'s first balls (its strike ball and noise, seed ``seed``): (delivery, deck
    start) each, those that reached the deck (cached)."""
    path = cache / f"board_starts{'' if name == 'pro' else '_' + name}_n{n}_seed{seed}.pkl"
    if path.exists():
        return pickle.loads(path.read_bytes())
    pro, m = profiles.profile(name), frame.frame_model()
    out = [(dv, st) for dv in noise.sample(pro.strike, n, seed, pro.noise)
           for st in [frame.deck_start(dv, model=m)] if st.board is not None]
    cache.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp")
    tmp.write_bytes(pickle.dumps(out))
    os.replace(tmp, path)
    return out


def shifted(start, board: float, qadr: int, hand: str = "right"):
    """A copy of the deck start ``start`` with the ball moved sideways (y) so that it crosses the head
    pin's line on ``board``: its velocity, spin and height kept, the pins where they stand."""
    dy = (board - start.board) * BOARD_WIDTH * hand_sign(hand)
    qpos = start.qpos.copy()
    qpos[qadr + 1] += dy
    pos = start.prev[0].copy()
    pos[1] += dy
    out = copy.copy(start)
    out.qpos, out.prev, out.board = qpos, (pos, start.prev[1]), float(board)
    return out


def _run(calls: list, prm: dict, jobs: int) -> list:
    if jobs <= 1:
        CF._init(prm)
        return [CF._replay(*c) for c in calls]
    from nbst.models.mjsearch.pool import WorkerPool

    with WorkerPool(jobs, CF._init, (prm,)) as pool:
        return pool.map(CF._replay, calls)


def by_board(throws: list, bins: np.ndarray, step: float, seed: int, prm: dict, jobs: int) -> list:
    """(bin's low board, board, entry angle, leave, cap) of every throw of ``throws`` carried onto every bin."""
    qadr = int(frame.frame_model().joint("ball_free").qposadr[0])
    u = np.random.default_rng(derived_seed(seed, 48)).random(len(throws))
    calls, tags = [], []
    for b, lo in enumerate(bins):
        for i, (dv, st) in enumerate(throws):
            board = float(lo + step * u[i])
            calls.append((dv, shifted(st, board, qadr, dv.hand), SPOT_SEED * (b + 1) + i))
            tags.append((float(lo), board, st.angle))
    return [(*t, list(lv), cap) for t, (lv, cap) in zip(tags, _run(calls, prm, jobs))]


def board_table(rows: list, step: float) -> None:
    """Per bin of boards: strikes, the 10 alone, splits, the commonest leaves (Wilson 95 % intervals)."""
    print("| boards at the head pin's line | balls | strikes (95 % CI) | the 10 alone | splits | caps | "
          "leaves with the 9 | commonest leaves |")
    print("|---|---|---|---|---|---|---|---|")
    for lo in sorted({r[0] for r in rows}):
        bin_ = [r for r in rows if r[0] == lo]
        n, c = len(bin_), {}
        for r in bin_:
            if r[3]:
                c["-".join(map(str, r[3]))] = c.get("-".join(map(str, r[3])), 0) + 1
        top = ", ".join(f"{s} {v}" for s, v in sorted(c.items(), key=lambda kv: -kv[1])[:5])
        k = sum(not r[3] for r in bin_)
        lo_, hi_ = noise.wilson(k, n)
        print(f"| {lo:g}-{lo + step:g} | {n} | {k}, {100 * k / n:.0f} % ({100 * lo_:.0f}-{100 * hi_:.0f} %) | "
              f"{sum(r[3] == [10] for r in bin_)} | {_ci(sum(names.is_split(r[3]) for r in bin_ if r[3]), n)} | "
              f"{sum(r[4] for r in bin_)} | {sum(9 in r[3] for r in bin_)} | {top} |")


def kickback_restitution(prm: dict, speed: float = 3.0, phases: int = 8) -> tuple:
    """(mean, min, max) restitution of the 7 pin thrown sideways into the left kickback at ``speed``
    (m/s), upright, 0.3 m above the deck, gravity off, over ``phases`` start offsets within one
    step's travel, on the pin deck model of setting ``prm``: minus its sideways speed after the
    bounce over that before."""
    import mujoco

    m = CF.pin_deck_model(frame.frame_model(), prm)
    m.opt.gravity[:] = 0.0
    m.opt.enableflags &= ~int(mujoco.mjtEnableBit.mjENBL_SLEEP)
    wall = m.geom("wall_left").id
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    face = d.geom_xpos[wall][1] - m.geom_size[wall][1]
    ja, va = m.joint("pin7_free").qposadr[0], m.joint("pin7_free").dofadr[0]
    es = []
    for ph in np.arange(phases) / phases:
        d = mujoco.MjData(m)
        d.qpos[ja + 2] += 0.3
        d.qpos[ja + 1] = face - 0.0605 - 0.02 - ph * speed * m.opt.timestep  # the belly (r 6.05 cm) 2 cm off
        d.qvel[va + 1] = speed
        for _ in range(200):
            mujoco.mj_step(m, d)
        es.append(-float(d.qvel[va + 1]) / speed)
    return float(np.mean(es)), min(es), max(es)


def two_pin_paths(starts: dict, buckets: list, prm: dict) -> list:
    """(first body to touch the 4, the 2 pin's heading in degrees left of down-lane, how far its
    line passes from where the 4 stood, in m) of every flush hit, its pin deck on the setting ``prm``
    (scattered as :func:`replay` scatters it). The heading is the 2 pin's centre of mass's over the
    step :data:`TWO_PIN_S` after it first moved 2 mm from where it stood (or the step it first
    touches the 4, if sooner): the line it was sent along, straight."""
    CF._init(prm)
    m = CF._W["m"]
    pins = {m.body(f"pin{n}").id: f"pin{n}" for n in scene.PIN_NUMBERS}
    ball = int(m.jnt_bodyid[m.joint("ball_free").id])
    deck = {m.geom(g).id for g in (lane.DECK_GEOM, lane.PIN_DECK_GEOM, lane.PIN_LANE_GEOM)}
    b2, b4 = m.body("pin2").id, m.body("pin4").id

    def who(g: int) -> str:
        b = int(m.geom_bodyid[g])
        return pins.get(b) or ("ball" if b == ball else m.geom(g).name or f"geom {g}")

    out = []
    for b, (name, ang) in enumerate(buckets):
        for i, (dv, st) in enumerate(starts[f"{name}@{ang:g}"]["throws"]):
            if st.board is None or not FLUSH[0] <= st.board <= FLUSH[1]:
                continue
            if CF._W["spot"] > 0:
                st = CF.scatter(m, st, CF._W["spot"], 10_000 + SPOT_SEED * (b + 1) + i)
            s: dict = {"first": None, "moved": None, "line": None, "prev": None, "set": None}

            def rec(d, s=s) -> None:
                for c in d.contact[:d.ncon]:
                    g1, g2 = int(c.geom1), int(c.geom2)
                    for a, o in ((g1, g2), (g2, g1)):
                        if s["first"] is None and int(m.geom_bodyid[a]) == b4 and o not in deck:
                            s["first"] = who(o)
                x = d.xipos[b2][:2].copy()
                if s["set"] is None:  # where the 2 and the 4 stand (their spots, or off them: the scatter)
                    s["set"], s["four"] = x, d.xipos[b4][:2].copy()
                if s["line"] is None:
                    if s["moved"] is None and np.linalg.norm(x - s["set"]) > 0.002:
                        s["moved"] = d.time
                    if s["moved"] is not None and (s["first"] is not None or d.time - s["moved"] >= TWO_PIN_S):
                        s["line"] = (x, x - s["prev"])
                s["prev"] = x

            frame.run_frame(dv, model=m, start=st, record=rec)
            if s["line"] is None:  # the 2 pin never moved
                out.append((s["first"], float("nan"), float("nan")))
                continue
            x, v = s["line"]
            u = v / np.linalg.norm(v)
            r = s["four"] - x
            out.append((s["first"], float(np.degrees(np.arctan2(v[1], v[0]))), float(abs(u[0] * r[1] - u[1] * r[0]))))
    return out


def _ci(k: int, n: int) -> str:
    if not n:
        return "-"
    lo, hi = noise.wilson(k, n)
    return f"{k} ({100 * lo:.0f}-{100 * hi:.0f} %)"


def table(rows: list, boards: tuple, label: str) -> None:
    """Per whole-degree bin of actual entry angle: hits on ``boards``, strikes, solid 10s (``names``), the
    4 alone (named a solid 4 on a pocket hit), leaves with the 4, leaves with the 9, the commonest leaves."""
    print(f"\n### {label}: boards {boards[0]:g}-{boards[1]:g} at the head pin's line, binned by actual entry angle\n")
    print("| entry angle | hits | strikes | solid 10 | the 4 alone | leaves with the 4 | leaves with the 9 | "
          "commonest leaves |")
    print("|---|---|---|---|---|---|---|---|")
    sel = [r for r in rows if boards[0] <= r[1] <= boards[1]]
    tot = np.zeros(6, dtype=int)
    for a in range(3, 10):
        bin_ = [r for r in sel if a - 0.5 <= r[2] < a + 0.5]
        if not bin_:
            continue
        nm = [names.leave_names(range(1, 11), r[3], r[1], r[2]) for r in bin_]
        k = np.array([len(bin_), sum(not r[3] for r in bin_), sum("solid 10" in x for x in nm),
                      sum(r[3] == [4] for r in bin_), sum(4 in r[3] for r in bin_), sum(9 in r[3] for r in bin_)])
        tot += k
        c: dict = {}
        for r in bin_:
            if r[3]:
                s = "-".join(map(str, r[3]))
                c[s] = c.get(s, 0) + 1
        top = ", ".join(f"{s} {v}" for s, v in sorted(c.items(), key=lambda kv: -kv[1])[:5])
        print(f"| {a - 0.5:g}-{a + 0.5:g} deg | {k[0]} | {_ci(k[1], k[0])} | {_ci(k[2], k[0])} | {_ci(k[3], k[0])} "
              f"| {_ci(k[4], k[0])} | {_ci(k[5], k[0])} | {top} |")
    print(f"| all | {tot[0]} | {_ci(tot[1], tot[0])} | {_ci(tot[2], tot[0])} | {_ci(tot[3], tot[0])} "
          f"| {_ci(tot[4], tot[0])} | {_ci(tot[5], tot[0])} | |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0], allow_abbrev=False)
    ap.add_argument("--releases", default="pro:4,6,7,8;twohander:8",
                    help="profile:angle,angle;... (the strike balls aimed at board 17.5 at each entry angle)")
    ap.add_argument("--n", type=int, default=200, help="noisy throws per (release, angle) (default 200)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--setting", default="", help="pins moved from the scene's, 'key=value,...' (bench_carry_fit)")
    ap.add_argument("--cache", type=Path, default=Path.home() / ".cache" / "nbst" / "pocket_angle")
    ap.add_argument("--restitution", action="store_true",
                    help="print the pin-kickback restitution of the setting and stop")
    ap.add_argument("--collision-segments", type=int, default=None, metavar="N",
                    help="probe: the pins' collision pieces as N-gons instead of the scene's "
                         f"{pin.COLLISION_SEGMENTS} (one process: --jobs 1)")
    ap.add_argument("--by-board", default=None, metavar="LO,HI,STEP",
                    help="the pro's first balls carried onto every bin of boards LO..HI (issue 48)")
    ap.add_argument("--profile", default="pro", help="--by-board: whose first balls (default pro)")
    ap.add_argument("--two-pin", action="store_true",
                    help="on the flush hits: what touches the 4 first, and the line the 2 pin is sent along")
    args = ap.parse_args()
    segments = ""
    if args.collision_segments is not None and args.collision_segments != pin.COLLISION_SEGMENTS:
        if args.jobs != 1 or not 8 <= args.collision_segments <= 128:
            ap.error("--collision-segments: 8..128, with --jobs 1 (the pins are rebuilt in this process only)")
        pin.COLLISION_SEGMENTS = args.collision_segments  # before any model is compiled
        pin.geometry.cache_clear()
        segments = f"|segments={args.collision_segments}"
    buckets = parse_releases(args.releases)
    prm = CF.parse_setting(args.setting)
    if args.restitution:
        e, lo, hi = kickback_restitution(prm)
        print(f"setting {CF.key(prm)}: a pin into the kickback at 3 m/s rebounds at {e:.2f} ({lo:.2f}-{hi:.2f} "
              "over 8 phases of a step)")
        return
    if args.by_board:
        lo, hi, step = (float(x) for x in args.by_board.split(","))
        bins = np.round(np.arange(lo, hi - 1e-9, step), 6)
        throws = board_starts(args.cache, args.n, args.seed, args.profile)
        path = args.cache / "board_results.json"
        done = json.loads(path.read_text()) if path.exists() else {}
        who = "" if args.profile == "pro" else f"|{args.profile}"
        k = f"{lane.SCENE}|{CF.key(prm)}{segments}{who}|{args.by_board}|n{args.n}|seed{args.seed}"
        if k not in done:
            t0 = time.time()
            done[k] = by_board(throws, bins, step, args.seed, prm, args.jobs)
            print(f"pin decks ({CF.key(prm)}): {len(done[k])} in {time.time() - t0:.0f} s", flush=True)
            done = {**(json.loads(path.read_text()) if path.exists() else {}), k: done[k]}
            tmp = path.with_suffix(".tmp")
            tmp.write_text(json.dumps(done))
            os.replace(tmp, path)
        ang = np.array([st.angle for _, st in throws])
        print(f"\nscene {lane.SCENE}, setting: {CF.key(prm)}{segments}; {args.profile}'s first balls of seed "
              f"{args.seed}: {len(throws)}, "
              f"entry {ang.mean():.2f} deg (sd {ang.std():.2f}), each carried onto every bin\n")
        board_table(done[k], step)
        return
    starts = capture(args.cache, buckets, args.n, args.seed)
    if args.two_pin:
        t0 = time.time()
        rows = two_pin_paths(starts, buckets, prm)
        first: dict = {}
        for r in rows:
            first[r[0]] = first.get(r[0], 0) + 1
        h, miss = (np.array([r[k] for r in rows if r[1] == r[1]]) for k in (1, 2))
        miss = 1000 * miss
        s2, s4 = (np.array(xy) for xy in scene.pin_spots()[1:4:2])
        print(f"setting {CF.key(prm)}{segments}: {len(rows)} flush hits ({time.time() - t0:.0f} s); the first to touch the 4: "
              + ", ".join(f"{k} {v}" for k, v in sorted(first.items(), key=lambda kv: -kv[1])))
        print(f"the 2 pin's heading: {h.min():.1f} to {h.max():.1f} deg left of down-lane (median {np.median(h):.1f}; "
              f"the 2-4 line {np.degrees(np.arctan2(*(s4 - s2)[::-1])):.1f}); its line passes the 4 at "
              f"{miss.min():.0f} to {miss.max():.0f} mm (median {np.median(miss):.0f}; 5-95 %: "
              f"{np.percentile(miss, 5):.0f}-{np.percentile(miss, 95):.0f}); two bellies: 121 mm")
        return
    path = args.cache / f"angle_results_n{args.n}_seed{args.seed}.json"
    done = json.loads(path.read_text()) if path.exists() else {}
    k = f"{lane.SCENE}|{CF.key(prm)}|{args.releases}{segments}"
    if k not in done:
        t0 = time.time()
        done[k] = replay(starts, buckets, prm, args.jobs)
        print(f"pin decks ({CF.key(prm)}): {len(done[k])} in {time.time() - t0:.0f} s", flush=True)
        tmp = path.with_suffix(".tmp")
        tmp.write_text(json.dumps(done))
        os.replace(tmp, path)
    rows = done[k]
    caps = sum(r[4] for r in rows)
    total = sum(len(v["throws"]) for v in starts.values())
    print(f"\nsetting: {CF.key(prm)}{segments}; {len(rows)} throws reached the pins on boards "
          f"{REPLAYED[0]:g}-{REPLAYED[1]:g} of {total}, {caps} read at the sweep")
    table(rows, FLUSH, "flush hits")
    table(rows, HIGH, "high pocket hits")
    pocket = [r for r in rows if 16.5 <= r[1] <= 18.5 and 4.0 <= r[2] <= 6.0]
    carried = sum(not r[3] for r in pocket)
    print(f"\ncarry of these throws' pocket hits (16.5-18.5 at 4-6 deg): {_ci(carried, len(pocket))} of {len(pocket)}")


if __name__ == "__main__":
    main()
