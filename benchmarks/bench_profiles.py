"""The bowler profiles' first balls on a fresh house shot (issue 34), and their games (issue 48).

    python benchmarks/bench_profiles.py [--n 100] [--seed 1] [--jobs 2] [--only pro]
    python benchmarks/bench_profiles.py --series 10 [--seed 101] [--jobs 1] [--only pro] [--moves none,auto]

``--series B``: each profile bowls B blocks of 3 games (a league series), each block on a fresh
house shot that every ball of the block wears (``bowl series``: transition, spares with the
profile's spare noise), block b's releases drawn from seed ``--seed + b``, once standing still
and once with the automatic "2 and 1" mover (the same releases: a paired comparison). Prints
per profile and mover the average of the 3 B games with a 95 % interval over the blocks
(mean +- t s / sqrt(B), s the sd of the B block averages: the games of a block share a lane),
the strike and spare rates (Wilson), the moves, and the mover's gain per 3-game block (paired,
its mean and 95 % interval); seconds. Targets (issue 48): league150 140-160, league200 190-210,
pro 215-240; the mover gains, or at least does not lose.

Without ``--series``:
For each profile of ``models/bowling/lane/profiles.py``: ``--n`` noisy throws of its strike ball
(its correlated release noise, seed ``--seed``; the same seed for every profile) into a full rack
on a fresh house shot (the lane is not worn between throws: no transition), each a settled USBC
frame at h = 1 ms. Prints the strike %, with its 95 % Wilson interval; the pocket-hit rate (the
ball on boards 16.5-18.5 at the head pin's line, entering at 4-6 deg: issue 34's pocket); carry (strikes of the
pocket hits) with its interval; the spread of the ball at the pins (sd of board and entry angle);
the most frequent leaves; seconds. Published figures to read them against (docs/bowling.md):
PBA 61 % strikes, 74 % carry of pocket hits.
"""
from __future__ import annotations

import argparse
import time

import numpy as np

from nbst.models.bowling import lane
from nbst.models.bowling.lane import frame, noise, profiles

POCKET = (16.5, 18.5)
ENTRY = (4.0, 6.0)
#: Two-sided 95 % t quantiles by degrees of freedom (1..30); beyond, 1.96.
T95 = (12.71, 4.30, 3.18, 2.78, 2.57, 2.45, 2.36, 2.31, 2.26, 2.23, 2.20, 2.18, 2.16, 2.14, 2.13, 2.12, 2.11, 2.10,
       2.09, 2.09, 2.08, 2.07, 2.07, 2.06, 2.06, 2.06, 2.05, 2.05, 2.05, 2.04)


def t95(df: int) -> float:
    return T95[df - 1] if 1 <= df <= len(T95) else 1.96


def block(args) -> dict:
    """One 3-game block of ``profile`` on a fresh house shot, releases from ``seed``, moving as ``move``."""
    from nbst.models.bowling.lane import transition as T

    name, seed, move = args
    t0 = time.time()
    r = T.Run(T.lineup(name), 3, seed, move, "house")
    r.play()
    d = r.to_dict()
    first = [b for b in d["balls"] if len(b["standing"]) == 10]
    spare = [b for b in d["balls"] if len(b["standing"]) < 10]
    return {"profile": name, "seed": seed, "move": move, "games": [g[-1] for g in d["scores"]["0"]],
            "moves": len(d["moves"]), "strikes": sum(b["strike"] for b in first), "first": len(first),
            "spares": sum(not b["leave"] for b in spare), "spare_balls": len(spare), "s": time.time() - t0}


def series(args) -> None:
    """The profiles' games: ``--series`` blocks of 3 per profile and mover (see the module docstring)."""
    from concurrent.futures import ProcessPoolExecutor

    names = [args.only] if args.only else [n for n in profiles.NAMES if n != "twohander"]
    moves = args.moves.split(",")
    jobs = [(n, args.seed + b, m) for n in names for b in range(args.series) for m in moves]
    print(f"## bowler profiles' games: {args.series} blocks of 3 games each on a fresh house shot (transition), "
          f"seeds {args.seed}..{args.seed + args.series - 1}, h = 1 ms, {args.jobs} process(es)\n")
    if args.jobs > 1:
        with ProcessPoolExecutor(args.jobs) as ex:
            out = list(ex.map(block, jobs))
    else:
        out = []
        for j in jobs:
            out.append(block(j))
            print("    " + " ".join(f"{k}={v}" for k, v in out[-1].items() if k != "s") + f" ({out[-1]['s']:.0f} s)",
                  flush=True)
    print("\n| profile | mover | games | average (95 % CI) | block averages | strikes (95 % CI) | spares (95 % CI) | "
          "moves | s |\n|---|---|---|---|---|---|---|---|---|")
    for n in names:
        for m in moves:
            rs = [r for r in out if r["profile"] == n and r["move"] == m]
            g = np.array([x for r in rs for x in r["games"]], float)
            b = np.array([np.mean(r["games"]) for r in rs])
            half = t95(len(b) - 1) * b.std(ddof=1) / np.sqrt(len(b)) if len(b) > 1 else float("nan")
            k, f = sum(r["strikes"] for r in rs), sum(r["first"] for r in rs)
            ks, fs = sum(r["spares"] for r in rs), sum(r["spare_balls"] for r in rs)
            (lo, hi), (slo, shi) = noise.wilson(k, f), noise.wilson(ks, fs)
            print(f"| {n} | {m} | {len(g)} | **{g.mean():.1f}** ({g.mean() - half:.1f}-{g.mean() + half:.1f}) | "
                  f"{', '.join(f'{v:.0f}' for v in b)} | {k}/{f} {100 * k / f:.0f} % ({100 * lo:.0f}-{100 * hi:.0f}) | "
                  f"{ks}/{fs} {100 * ks / max(fs, 1):.0f} % ({100 * slo:.0f}-{100 * shi:.0f}) | "
                  f"{sum(r['moves'] for r in rs)} | {sum(r['s'] for r in rs):.0f} |", flush=True)
    if {"none", "auto"} <= set(moves):
        print("\n| profile | the mover's gain per 3-game block, paired (95 % CI) | blocks gaining / losing |\n|---|---|---|")
        for n in names:
            a = {r["seed"]: sum(r["games"]) for r in out if r["profile"] == n and r["move"] == "auto"}
            z = {r["seed"]: sum(r["games"]) for r in out if r["profile"] == n and r["move"] == "none"}
            dd = np.array([a[s] - z[s] for s in sorted(a)], float)
            half = t95(len(dd) - 1) * dd.std(ddof=1) / np.sqrt(len(dd)) if len(dd) > 1 else float("nan")
            print(f"| {n} | {dd.mean():+.1f} pins ({dd.mean() - half:+.1f} to {dd.mean() + half:+.1f}) | "
                  f"{int((dd > 0).sum())} / {int((dd < 0).sum())} |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0], allow_abbrev=False)
    ap.add_argument("--n", type=int, default=100, help="noisy throws per profile (default 100)")
    ap.add_argument("--seed", type=int, default=1, help="seed of the release noise (default 1)")
    ap.add_argument("--jobs", type=int, default=2, help="processes running frames (default 2)")
    ap.add_argument("--only", choices=profiles.NAMES, default=None, help="one profile")
    ap.add_argument("--series", type=int, default=0, metavar="B",
                    help="bowl B blocks of 3 games per profile (league150, league200, pro) instead (see above)")
    ap.add_argument("--moves", default="none,auto", help="--series: the movers, comma-separated (default none,auto)")
    args = ap.parse_args()
    if args.series:
        return series(args)
    print(f"## bowler profiles: {args.n} noisy first balls each on a fresh house shot, seed {args.seed}, h = 1 ms\n")
    print("| profile | strike ball | strikes (95 % CI) | pocket hits | carry (95 % CI) | board sd | entry sd | "
          "top leaves | s |\n|---|---|---|---|---|---|---|---|---|")
    with frame.FrameRunner("house", lane.Ball(), jobs=args.jobs) as run:
        for name in ([args.only] if args.only else profiles.NAMES):
            p = profiles.profile(name)
            t0 = time.time()
            est, res = noise.probability(p.strike, args.n, args.seed, runner=run, noise=p.noise)
            boards = np.array([r.board_at_pins if r.board_at_pins is not None else np.nan for r in res])
            angles = np.array([r.entry_angle_deg if r.entry_angle_deg is not None else np.nan for r in res])
            pocket = [(b >= POCKET[0]) & (b <= POCKET[1]) & (a >= ENTRY[0]) & (a <= ENTRY[1])
                      for b, a in zip(boards, angles)]
            hits = int(sum(pocket))
            carried = sum(1 for r, h in zip(res, pocket) if h and r.converted)
            lo, hi = noise.wilson(carried, hits) if hits else (float("nan"), float("nan"))
            top = ", ".join(f"{k or 'none'} {v}" for k, v in list(est.leaves.items())[:4])
            d = p.strike
            print(f"| {name} | board {d.board:g}, {d.angle:.2f} deg, {d.mph:g} mph, {d.rpm:g} rpm, rotation "
                  f"{d.rotation:g}, tilt {d.tilt:g} | {est.text()} | {hits}/{args.n} | "
                  f"{carried}/{hits} ({100 * lo:.0f}-{100 * hi:.0f} %) | {np.nanstd(boards):.2f} | "
                  f"{np.nanstd(angles):.2f} | {top} | {time.time() - t0:.0f} |", flush=True)


if __name__ == "__main__":
    main()
