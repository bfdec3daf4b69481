"""Bowling calibrated on seeds it was not fitted on (issue 48): carry, spares, the leave mix, entry angles.

    python benchmarks/bench_bowling_calibration.py [--part carry|spares|leaves|angles|games|all]
                                                   [--seeds heldout|fit|S1,S2,..] [--n 260] [--spares 100]
                                                   [--blocks 10] [--moves auto,none] [--profiles P1,P2,..]
                                                   [--setting KEY=V,..] [--jobs 1] [--cache DIR]

Every figure is printed with its 95 % Wilson interval and the seeds it was measured on, and says
whether those seeds were used to fit anything (**fit**) or never (**held out**):

- :data:`FIT_SEEDS` (strike balls) and :data:`FIT_SPARE_SEEDS` (spares) are the seeds the pins'
  parameters and the profiles were chosen on (issue 48's fit; issue 34's fit used seeds 1 and 2);
- :data:`HELDOUT_SEEDS` and :data:`HELDOUT_SPARE_SEEDS` were never looked at while fitting: the
  figures docs/bowling.md gives are theirs, pooled.

**Parts.**

- ``carry``: ``--n`` first balls of the ``pro`` profile per seed (its strike ball and fitted noise) on a
  fresh house shot, each a settled USBC frame at h = 1 ms. A **pocket hit** is the ball on boards
  16.5-18.5 at the head pin's line at any entry angle (issue 48: PBA's "pocket hit" is the board the
  ball hits, not its angle; the 4-6 deg subset of issue 34 is printed beside it); **carry** is strikes
  of pocket hits. Against PBA: 74 % (40 of 54 pocket hits, one televised show; Jason Thomas, PBA.com
  column, reprinted at sjsubowling.pbworks.com), issue 48's band 74 +- 8.
- ``spares``: ``--spares`` throws per seed at the 3-10, the 10 and the 7 with the straight spare ball
  (17 mph, 200 rpm) cross-lane through the leave's aim point (``spares.straight_at``), under the pro's
  spare noise. Against PBA television 2005-10 (ESPN The Magazine, 7 Feb 2011, as reported by North
  American Bowling News, "ESPN Magazine Analyzes PBA Spare Shooting on TV"): the 3-10 48.6 % (17 of
  35), the 10 pin 95.9 % (of 710), the 7 pin 95.5 % (of 333).
- ``leaves``: the non-strikes of the ``carry`` part's first balls, by leave, in order, with their share
  of non-strikes (the leave mix), against the published ranking (the same ESPN study's attempt counts:
  10 pin 710, 7 pin 333, 9 pin 88, 7-10 53, 3-10 35, big four 30 of 2,781 spare attempts).
- ``angles``: the ball alone on a fresh house shot (no pins, no noise): each profile's strike ball
  (entry angle, breakpoint), and the league-200 release with balls of RG 2.46-2.80 and differential
  0-0.060 in, thrown on the same line (the same stance and launch angle), re-aimed to board 17.5 from
  the same board, and re-aimed to board 17.5 through the 0.040 in ball's breakpoint board (the feet
  moved: "the same breakpoint and pocket").
- ``games``: the profiles' games (issue 48's averages: league150 140-160, league200 190-210, pro
  215-240): ``--blocks`` blocks of 3 games per profile, each on a fresh house shot that every ball of
  the block wears (``transition.Run``: strike and spare balls, the profile's noises), block b's
  releases from seed ``GAME_HELDOUT_SEEDS[b]`` (``--seeds fit``: :data:`GAME_FIT_SEEDS`), with the
  automatic "2 and 1" mover and standing still on the same releases (``--moves``). Prints each
  profile's average with a 95 % interval over the block averages (t), its strikes, pocket hits and
  spares (Wilson), the mover's paired gain per block, each profile's figures by game of the block
  (the strike balls' board at the head pin's line and its spread, pocket hits, strikes, spares,
  open frames) and its spares by leave against PBA television, and the leave mix of all the
  profiles' first balls together (a population of bowlers, not one) against ESPN's ranking.

The pin deck is replayed from each throw's deck start (``frame.deck_start``; the lane phase once per
throw, as ``bench_carry_fit.py``), so ``--setting`` (the keys of ``bench_carry_fit.DEFAULTS``: ``pp_mu``,
``bp_mu``, ``pp_zeta``, ``bp_zeta``, ``deck_mu``, ``pin_mass``, ``pin_com_in``, ...) moves the pins from
the scene's on the same throws. Results are kept in ``--cache`` (default ``~/.cache/nbst/calibration``)
as they come, keyed by the lane scene (``lane.SCENE``: its pins), the profile and the setting: a rerun
prints them without running anything (delete the folder to measure again).
"""
from __future__ import annotations

import argparse
import importlib.util
import json
import os
import pickle
import time
from pathlib import Path

import numpy as np

from nbst.models.bowling import lane, pin
from nbst.models.bowling.lane import frame, names, noise, phases, profiles, spares
from nbst.models.bowling.lane.ball import Ball

#: Seeds of the pro's first balls used to fit (issue 48), and those held out (never used to fit).
FIT_SEEDS = (11, 12, 13)
HELDOUT_SEEDS = (31, 32, 33, 34, 35)
#: Seeds of the spare throws: fit, held out.
FIT_SPARE_SEEDS = (21, 22, 23)
HELDOUT_SPARE_SEEDS = (41, 42, 43, 44, 45)
#: Seeds of the profiles' 3-game blocks: those the profiles' lines and noises were fitted on (issue 48:
#: 101-105 chose the mover, 101-103 the league lines and noises), and those held out (never used to fit).
GAME_FIT_SEEDS = (101, 102, 103)
GAME_HELDOUT_SEEDS = tuple(range(301, 311))
#: The profiles whose averages issue 48 asks for, and their bands.
GAME_TARGETS = {"league150": (140, 160), "league200": (190, 210), "pro": (215, 240)}
#: Two-sided 95 % t quantiles by degrees of freedom (1..12).
T95 = (12.71, 4.30, 3.18, 2.78, 2.57, 2.45, 2.36, 2.31, 2.26, 2.23, 2.20, 2.18)
POCKET = (16.5, 18.5)
ENTRY_34 = (4.0, 6.0)
SPARE_LEAVES = {"3-10": (3, 10), "10": (10,), "7": (7,)}
#: Published figures (see the module docstring for their sources).
PBA_CARRY = 0.74
PBA_SPARES = {"3-10": 0.486, "10": 0.959, "7": 0.955}
#: ESPN The Magazine's PBA television spare attempts, 2005-06 to 2009-10 (right- and left-handers
#: together), of 2,781 spare attempts.
ESPN_ATTEMPTS = {"10": 710, "7": 333, "9": 88, "7-10": 53, "3-10": 35, "4-6-7-10": 30}
ESPN_SPARE_ATTEMPTS = 2781


def _carry_fit():
    path = Path(__file__).resolve().parent / "bench_carry_fit.py"
    spec = importlib.util.spec_from_file_location("bench_carry_fit", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def ci(k: int, n: int) -> str:
    """``k/n = p % (lo-hi %)``, the 95 % Wilson interval."""
    if n == 0:
        return "none"
    lo, hi = noise.wilson(k, n)
    return f"{k}/{n} = {100 * k / n:.0f} % ({100 * lo:.0f}-{100 * hi:.0f} %)"


def _store(cache: Path, name: str) -> tuple[Path, dict]:
    path = cache / name
    return path, (json.loads(path.read_text()) if path.exists() else {})


def _save(path: Path, doc: dict) -> None:
    _save_bytes(path, json.dumps(doc).encode())


def _save_bytes(path: Path, data: bytes) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp")
    tmp.write_bytes(data)
    os.replace(tmp, path)


def _profile_tag() -> str:
    """The lane scene, the pro's strike ball and noises and the pins' collision polygon, so that a changed
    scene (its pins: ``scene.LANE_PINS``), profile or pin is measured afresh."""
    p = profiles.profile("pro")
    s = p.strike
    return (f"{lane.SCENE}-b{s.board:g}a{s.angle:g}m{s.mph:g}r{s.rpm:g}o{s.rotation:g}t{s.tilt:g}"
            f"x{p.noise_scale:g}s{p.spare_noise_scale:g}g{pin.COLLISION_SEGMENTS}")


def first_balls(seed: int, n: int, prm: dict, cache: Path) -> list:
    """``n`` pro first balls of ``seed`` on the pins of ``prm``: [board, angle, leave, cap] each (cached)."""
    bcf = _carry_fit()
    path, done = _store(cache, f"first_{_profile_tag()}.json")
    k = f"{bcf.key(prm)}|seed{seed}|n{n}"
    if k not in done:
        t0 = time.time()
        bcf._init(prm)
        recs = []
        for i, (dv, st) in enumerate(_deck_starts(seed, n, cache)):
            lv, cap = bcf._replay(dv, st, i)
            recs.append([st.board, st.angle, list(lv), cap])
        done = _store(cache, f"first_{_profile_tag()}.json")[1]  # another run may have written
        done[k] = recs
        _save(path, done)
        print(f"  ({k}: {time.time() - t0:.0f} s)", flush=True)
    return done[k]


def _deck_starts(seed: int, n: int, cache: Path) -> list:
    """The pro's ``n`` first balls of ``seed`` and their deck starts (kept in ``cache``: every setting meets them)."""
    path = cache / f"starts_{_profile_tag()}_seed{seed}_n{n}.pkl"
    if not path.exists():
        pro, m = profiles.profile("pro"), frame.frame_model()
        _save_bytes(path, pickle.dumps([(dv, frame.deck_start(dv, model=m))
                                        for dv in noise.sample(pro.strike, n, seed, pro.noise)]))
    return pickle.loads(path.read_bytes())


def spare_throws(name: str, seed: int, n: int, prm: dict, cache: Path) -> list:
    """``n`` throws at spare ``name`` under the pro's spare noise (seed ``seed``): leaves (cached)."""
    bcf = _carry_fit()
    path, done = _store(cache, f"spares_{_profile_tag()}.json")
    k = f"{name}|{bcf.key(prm)}|seed{seed}|n{n}"
    if k not in done:
        t0 = time.time()
        pins = SPARE_LEAVES[name]
        line = spares.straight_at(*spares.aim_point(pins))
        m = frame.frame_model()
        bcf._init(prm)
        out = []
        for i, dv in enumerate(noise.sample(line, n, seed, profiles.profile("pro").spare())):
            st = frame.deck_start(dv, model=m, standing=pins)
            out.append(list(bcf._replay(dv, st, 100_000 + i)[0]))
        done = _store(cache, f"spares_{_profile_tag()}.json")[1]
        done[k] = out
        _save(path, done)
        print(f"  ({k}: {time.time() - t0:.0f} s)", flush=True)
    return done[k]


def _pocket(recs: list, entry=None) -> list:
    out = []
    for b, a, lv, _ in recs:
        if b is None or a is None or not POCKET[0] <= b <= POCKET[1]:
            continue
        if entry is not None and not entry[0] <= a <= entry[1]:
            continue
        out.append(lv)
    return out


def _which(seeds, fit) -> str:
    return f"seeds {','.join(map(str, seeds))} ({'fit' if set(seeds) <= set(fit) else 'held out' if not set(seeds) & set(fit) else 'mixed'})"


def part_carry(seeds, n, prm, cache) -> dict:
    print(f"\n## carry: the pro's first balls, {n} per seed, {_which(seeds, FIT_SEEDS)}, pins: {_carry_fit().key(prm)}\n")
    print("| seed | strikes | pocket hits (16.5-18.5) | carry of pocket hits | carry at 4-6 deg | flush 17-18: solid 10 / solid 4 |")
    print("|---|---|---|---|---|---|")
    tot = {"n": 0, "s": 0, "p": 0, "c": 0, "p46": 0, "c46": 0}
    every = []
    for seed in seeds:
        recs = first_balls(seed, n, prm, cache)
        every += recs
        pk, pk46 = _pocket(recs), _pocket(recs, ENTRY_34)
        fl = [lv for b, a, lv, _ in recs if b is not None and 17 <= b <= 18]
        s = sum(1 for r in recs if not r[2])
        c, c46 = sum(1 for lv in pk if not lv), sum(1 for lv in pk46 if not lv)
        print(f"| {seed} | {ci(s, len(recs))} | {len(pk)} | {ci(c, len(pk))} | {ci(c46, len(pk46))} | "
              f"{sum(1 for lv in fl if lv == [10])} / {sum(1 for lv in fl if lv == [4])} of {len(fl)} |")
        for key_, v in (("n", len(recs)), ("s", s), ("p", len(pk)), ("c", c), ("p46", len(pk46)), ("c46", c46)):
            tot[key_] += v
    print(f"| **pooled** | {ci(tot['s'], tot['n'])} | {tot['p']} | **{ci(tot['c'], tot['p'])}** | "
          f"{ci(tot['c46'], tot['p46'])} | |")
    lo, hi = noise.wilson(tot["c"], tot["p"])
    print(f"\nPBA 74 % (band 66-82 %): the pooled interval {100 * lo:.0f}-{100 * hi:.0f} % "
          f"{'contains' if lo <= PBA_CARRY <= hi else 'excludes'} 74 % and "
          f"{'overlaps' if hi >= 0.66 and lo <= 0.82 else 'misses'} the band.")
    entry = np.array([r[1] for r in every if r[1] is not None])
    board = np.array([r[0] for r in every if r[0] is not None])
    print(f"The ball at the head pin's line: board {board.mean():.2f} (sd {board.std():.2f}), "
          f"entry {entry.mean():.2f} deg (sd {entry.std():.2f}).")
    return {"records": every, **tot}


def part_spares(seeds, n, prm, cache) -> None:
    print(f"\n## spares: {n} throws per seed and leave, the pro's spare noise, {_which(seeds, FIT_SPARE_SEEDS)}, "
          f"pins: {_carry_fit().key(prm)}\n")
    print("| leave | " + " | ".join(f"seed {s}" for s in seeds) + " | pooled (95 % CI) | PBA television |")
    print("|---|" + "---|" * (len(seeds) + 2))
    for name in SPARE_LEAVES:
        ks, ns = [], []
        for seed in seeds:
            lv = spare_throws(name, seed, n, prm, cache)
            ks.append(sum(1 for x in lv if not x))
            ns.append(len(lv))
        lo, hi = noise.wilson(sum(ks), sum(ns))
        pba = PBA_SPARES[name]
        print(f"| {name} | " + " | ".join(f"{k}/{m}" for k, m in zip(ks, ns)) +
              f" | **{ci(sum(ks), sum(ns))}** | {100 * pba:.1f} % ({'inside' if lo <= pba <= hi else 'outside'}) |")


def part_leaves(rec: dict) -> None:
    leaves: dict = {}
    for _, _, lv, _ in rec["records"]:
        if lv:
            k = "-".join(map(str, lv))
            leaves[k] = leaves.get(k, 0) + 1
    ns = sum(leaves.values())
    print(f"\n## leaves: the {ns} non-strikes of the {rec['n']} first balls above, by leave\n")
    print("| rank | leave | count | share of non-strikes (95 % CI) | ESPN: share of PBA TV spare attempts |")
    print("|---|---|---|---|---|")
    for r, (k, v) in enumerate(sorted(leaves.items(), key=lambda kv: -kv[1])[:12], 1):
        lo, hi = noise.wilson(v, ns)
        e = ESPN_ATTEMPTS.get(k)
        print(f"| {r} | {k} | {v} | {100 * v / ns:.1f} % ({100 * lo:.0f}-{100 * hi:.0f} %) | "
              f"{'' if e is None else f'{100 * e / ESPN_SPARE_ATTEMPTS:.1f} %'} |")
    single = sum(v for k, v in leaves.items() if "-" not in k)
    splits = sum(v for k, v in leaves.items() if names.is_split([int(p) for p in k.split("-")]))
    wide = leaves.get("7-10", 0) + leaves.get("4-6-7-10", 0)
    print(f"\nSingle pins {single} of {ns} ({100 * single / max(ns, 1):.0f} %); splits (USBC) {ci(splits, ns)}; the 7-10 "
          f"and the big four {ci(wide, ns)}, ESPN {100 * (53 + 30) / ESPN_SPARE_ATTEMPTS:.1f} % of spare attempts; the "
          f"10 and the 7 {100 * (710 + 333) / ESPN_SPARE_ATTEMPTS:.1f} % (right- and left-handers together).")


def part_angles() -> None:
    print("\n## entry angles: the ball alone on a fresh house shot, aimed at board 17.5\n")
    print("| release | from | breakpoint | entry angle |")
    print("|---|---|---|---|")
    files = sorted(profiles.PROFILES_DIR.glob("*.json"))
    extra = [f for f in files if f.stem not in profiles.NAMES]  # a profile's file not yet registered
    for name, prof in [(n, profiles.profile(n)) for n in profiles.NAMES] + [(f.stem, profiles.load_profile(f))
                                                                         for f in extra]:
        d = prof.strike
        t = lane.throw(d, "house")
        print(f"| `{name}` {d.mph:g} mph, {d.rpm:g} rpm, rotation {d.rotation:g}, tilt {d.tilt:g} | board {d.board:g}, "
              f"{d.angle:.2f} deg | {t.breakpoint_ft:.1f} ft, board {t.breakpoint_board:.1f} | **{t.entry_angle_deg:.2f} deg** |")
    for name in ("league200", "cranker"):
        base = profiles.profile(name).strike
        bp0 = lane.throw(base, "house", Ball(diff=0.04)).breakpoint_board
        print(f"\nThe {name} release ({base.mph:g} mph, {base.rpm:g} rpm, rotation {base.rotation:g}, tilt "
              f"{base.tilt:g}) with other balls: on its own line (board {base.board:g} at the foul line, "
              f"{base.angle:.2f} deg), re-aimed to board 17.5 from the same board, and re-aimed to board 17.5 "
              f"through the 0.040 in ball's breakpoint board ({bp0:.1f}; the feet moved)\n")
        print("| ball | same line: board at the pins, entry | re-aimed: launch angle, breakpoint, entry | same "
              "breakpoint board: from, breakpoint, entry |")
        print("|---|---|---|---|")
        for kw in ({"rg": 2.46}, {"rg": 2.50}, {"rg": 2.60}, {"rg": 2.80}, {"diff": 0.0}, {"diff": 0.02},
                   {"diff": 0.04}, {"diff": 0.05}, {"diff": 0.06}):
            b = Ball(**kw)
            t = lane.throw(base, "house", b)
            try:
                dd, ta = phases.aim_angle(base, 17.5, "house", b)
                re = (f"{dd.angle:.2f} deg, {ta.breakpoint_ft or float('nan'):.1f} ft board "
                      f"{ta.breakpoint_board or float('nan'):.1f}, {ta.entry_angle_deg:.2f} deg")
            except lane.LaneError:
                re = "no launch angle reaches 17.5"
            print(f"| RG {b.rg:.2f}, diff {b.diff:.3f} | board {t.board_at_pins:.2f}, {t.entry_angle_deg:.2f} deg | "
                  f"{re} | {_same_breakpoint(base, b, bp0) if 'diff' in kw else '-'} |", flush=True)


def _same_breakpoint(base: lane.Delivery, ball: Ball, bp_board: float) -> str:
    """``base`` re-aimed at board 17.5 from the foul-line board whose breakpoint is on ``bp_board`` (secant
    on the board, each step ``phases.aim_angle``): 'from board, breakpoint, entry'."""
    from dataclasses import replace

    def at(fb):
        d, t = phases.aim_angle(replace(base, board=float(fb)), 17.5, "house", ball)
        return d, t, t.breakpoint_board - bp_board

    try:
        a, b = base.board - 2.0, base.board + 2.0
        _, _, fa = at(a)
        d, t, fb_ = at(b)
        for _ in range(8):
            if abs(fb_) < 0.05 or fb_ == fa:
                break
            a, fa, b = b, fb_, b - fb_ * (b - a) / (fb_ - fa)
            d, t, fb_ = at(b)
    except lane.LaneError:
        return "not reached"
    if abs(fb_) >= 0.1:
        return "not reached"
    return f"board {d.board:.1f}, {d.angle:.2f} deg; {t.breakpoint_ft:.1f} ft board {t.breakpoint_board:.1f}, **{t.entry_angle_deg:.2f} deg**"


def _game_tag(name: str) -> str:
    """The lane scene and a profile's strike ball and noises, so that a changed scene's or profile's games
    are bowled afresh."""
    p = profiles.profile(name)
    s = p.strike
    return (f"{lane.SCENE}-{name}-b{s.board:g}a{s.angle:g}m{s.mph:g}r{s.rpm:g}o{s.rotation:g}t{s.tilt:g}"
            f"x{p.noise_scale:g}s{p.spare_noise_scale}" + ("-reads" if p.reads_lane else ""))


def game_block(name: str, seed: int, move: str, cache: Path) -> dict:
    """One 3-game block of profile ``name`` on a fresh house shot (transition), releases from ``seed``,
    moving as ``move``: the games, and per first ball [game, board at the head pin's line, entry
    angle, leave], per spare ball [standing, leave] (cached)."""
    from nbst.models.bowling.lane import transition as T

    path, done = _store(cache, "games.json")
    k = f"{_game_tag(name)}|{move}|seed{seed}"
    if k not in done:
        t0 = time.time()
        r = T.Run(T.lineup(name), 3, seed, move, "house")
        r.play()
        d = r.to_dict()
        rec = {"games": [g[-1] for g in d["scores"]["0"]], "moves": len(d["moves"]),
               "first": [[b["game"], b["board_at_pins"], b["entry_angle_deg"], list(b["leave"])]
                         for b in d["balls"] if len(b["standing"]) == 10],
               "spare": [[list(b["standing"]), list(b["leave"]), b["game"]] for b in d["balls"]
                         if len(b["standing"]) < 10],
               # an open frame: a second ball at a leave that leaves pins (the tenth's fill balls are not)
               "opens": [sum(1 for b in d["balls"] if b["game"] == g + 1 and b["roll"] == 2
                             and len(b["standing"]) < 10 and b["leave"]) for g in range(3)]}
        done = _store(cache, "games.json")[1]
        done[k] = rec
        _save(path, done)
        print(f"    ({k}: games {rec['games']}, {time.time() - t0:.0f} s)", flush=True)
    return done[k]


def _t_half(x: np.ndarray) -> float:
    """The half-width of the 95 % t interval of the mean of ``x`` (nan for fewer than 2)."""
    if len(x) < 2:
        return float("nan")
    return float(T95[min(len(x) - 1, len(T95)) - 1] * x.std(ddof=1) / np.sqrt(len(x)))


def part_games(seeds, names, moves, cache) -> None:
    print(f"\n## games: {len(seeds)} blocks of 3 games per profile on a fresh house shot (transition, moves "
          f"{', '.join(moves)}), {_which(seeds, GAME_FIT_SEEDS)}\n")
    for s in seeds:  # seed by seed: an interrupted run has every profile's first blocks (cached)
        for n in names:
            for m in moves:
                game_block(n, s, m, cache)
    out = {(n, m): [game_block(n, s, m, cache) for s in seeds] for n in names for m in moves}
    print("| profile | mover | games | average (95 % CI) | target | strikes | pocket hits (16.5-18.5) | carry of "
          "pocket hits | spares | moves |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for n in names:
        for m in moves:
            rs = out[(n, m)]
            g = np.array([x for r in rs for x in r["games"]], float)
            b = np.array([np.mean(r["games"]) for r in rs])
            half = _t_half(b)
            first = [x for r in rs for x in r["first"]]
            pk = [x for x in first if x[1] is not None and POCKET[0] <= x[1] <= POCKET[1]]
            spare = [x for r in rs for x in r["spare"]]
            if n in GAME_TARGETS:
                lo_t, hi_t = GAME_TARGETS[n]
                target = f"{lo_t:g}-{hi_t:g} ({'met' if lo_t <= g.mean() <= hi_t else 'not met'})"
            else:
                target = "- (none named)"
            print(f"| {n} | {m} | {len(g)} | **{g.mean():.1f}** ({g.mean() - half:.1f}-{g.mean() + half:.1f}) | "
                  f"{target} | {ci(sum(1 for x in first if not x[3]), len(first))} | "
                  f"{ci(len(pk), len(first))} | {ci(sum(1 for x in pk if not x[3]), len(pk))} | "
                  f"{ci(sum(1 for x in spare if not x[1]), len(spare))} | {sum(r['moves'] for r in rs)} |")
    if {"auto", "none"} <= set(moves):
        print("\n| profile | the mover's gain per 3-game block, paired (95 % CI) | blocks gaining / even / losing |")
        print("|---|---|---|")
        for n in names:
            dd = np.array([sum(a["games"]) - sum(z["games"]) for a, z in zip(out[(n, "auto")], out[(n, "none")])], float)
            half = _t_half(dd)
            print(f"| {n} | {dd.mean():+.1f} pins ({dd.mean() - half:+.1f} to {dd.mean() + half:+.1f}) | "
                  f"{int((dd > 0).sum())} / {int((dd == 0).sum())} / {int((dd < 0).sum())} |")
    m0 = "auto" if "auto" in moves else moves[0]
    for n in names:
        _by_game(n, m0, out[(n, m0)])
    recs = [[x[1], x[2], x[3], False] for n in names for r in out[(n, m0)] for x in r["first"]]
    print(f"\nThe leave mix of all {len(recs)} first balls of {', '.join(names)} (mover {m0}): a population "
          f"of bowlers.")
    part_leaves({"records": recs, "n": len(recs)})


def _by_game(name: str, move: str, rs: list) -> None:
    """Where a profile's pins go, by game of its blocks (1: the fresh lane): its strike balls at the head
    pin's line (mean board and spread, pocket hits, light and high), strikes, spares and open frames,
    then its spares by leave, against PBA television (ESPN's study)."""
    print(f"\n**`{name}`, mover {move}, by game of its {len(rs)} blocks** (light: below board 16.5 at the head "
          f"pin's line; high: above 18.5)\n")
    print("| game | strike balls: board at the pins, mean (sd) | pocket hits | light / high | strikes | spares | "
          "open frames a game |")
    print("|---|---|---|---|---|---|---|")
    for g in (1, 2, 3):
        first = [x for r in rs for x in r["first"] if x[0] == g]
        b = np.array([x[1] for x in first if x[1] is not None])
        pk = sum(1 for x in first if x[1] is not None and POCKET[0] <= x[1] <= POCKET[1])
        lo = sum(1 for x in first if x[1] is not None and x[1] < POCKET[0])
        hi = sum(1 for x in first if x[1] is not None and x[1] > POCKET[1])
        sp = [x for r in rs for x in r["spare"] if len(x) > 2 and x[2] == g]
        op = [r["opens"][g - 1] for r in rs if "opens" in r]
        print(f"| {g} | {b.mean():.2f} ({b.std():.2f}) | {ci(pk, len(first))} | {lo} / {hi} | "
              f"{ci(sum(1 for x in first if not x[3]), len(first))} | {ci(sum(1 for x in sp if not x[1]), len(sp))} | "
              f"{np.mean(op) if op else float('nan'):.1f} |")
    by: dict = {}
    for r in rs:
        for x in r["spare"]:
            k = "-".join(map(str, x[0]))
            by.setdefault(k, [0, 0])
            by[k][0] += not x[1]
            by[k][1] += 1
    pba = {"10": "95.9 %", "7": "95.5 %", "9": "98.9 %", "3-10": "48.6 %", "7-10": "0 %", "4-6-7-10": "3.3 %"}
    print(f"\n| `{name}`'s spare leave | converted (95 % CI) | PBA television |")
    print("|---|---|---|")
    for k, (c, m) in sorted(by.items(), key=lambda kv: -kv[1][1])[:10]:
        print(f"| {k} | {ci(c, m)} | {pba.get(k, '')} |")


def _seeds(text: str, fit, held) -> tuple:
    return {"fit": tuple(fit), "heldout": tuple(held)}.get(text) or tuple(int(s) for s in text.split(","))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0], allow_abbrev=False)
    ap.add_argument("--part", choices=("carry", "spares", "leaves", "angles", "games", "all"), default="all")
    ap.add_argument("--seeds", default="heldout", help="'heldout' (default), 'fit' or a list of seeds")
    ap.add_argument("--n", type=int, default=260, help="pro first balls per seed (default 260)")
    ap.add_argument("--spares", type=int, default=100, help="throws per spare and seed (default 100)")
    ap.add_argument("--blocks", type=int, default=None, help="games: the first B seeds' 3-game blocks (default all)")
    ap.add_argument("--moves", default="auto,none", help="games: the movers, comma-separated (default auto,none)")
    ap.add_argument("--profiles", default=",".join(GAME_TARGETS), help="games: the profiles (default: "
                    "league150, league200, pro)")
    ap.add_argument("--setting", default="", help="the pins moved from the scene's, 'key=value,...'")
    ap.add_argument("--collision-segments", type=int, default=None, metavar="N",
                    help="probe: the pins' collision rings as N-gons (8..128; the scene's by default)")
    ap.add_argument("--cache", type=Path, default=Path.home() / ".cache" / "nbst" / "calibration")
    args = ap.parse_args()
    prm = _carry_fit().parse_setting(args.setting)
    if args.collision_segments is not None:
        if not 8 <= args.collision_segments <= 128:
            ap.error("--collision-segments: 8..128")
        pin.COLLISION_SEGMENTS = args.collision_segments  # before any model is compiled (one process)
    print(f"# bowling calibration (issue 48): lane scene {lane.SCENE}, h = {frame.TIMESTEP * 1000:g} ms, "
          f"the pro and pins {_profile_tag()}")
    if args.part in ("carry", "leaves", "all"):
        rec = part_carry(_seeds(args.seeds, FIT_SEEDS, HELDOUT_SEEDS), args.n, prm, args.cache)
        if args.part != "carry":
            part_leaves(rec)
    if args.part in ("spares", "all"):
        part_spares(_seeds(args.seeds, FIT_SPARE_SEEDS, HELDOUT_SPARE_SEEDS), args.spares, prm, args.cache)
    if args.part in ("angles", "all"):
        part_angles()
    if args.part in ("games", "all"):
        gs = _seeds(args.seeds, GAME_FIT_SEEDS, GAME_HELDOUT_SEEDS)[:args.blocks]
        part_games(gs, args.profiles.split(","), args.moves.split(","), args.cache)


if __name__ == "__main__":
    main()
