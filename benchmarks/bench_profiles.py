"""The bowler profiles' first balls on a fresh house shot: strike %, pocket hits and carry (issue 34).

    python benchmarks/bench_profiles.py [--n 100] [--seed 1] [--jobs 2] [--only pro]

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


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0], allow_abbrev=False)
    ap.add_argument("--n", type=int, default=100, help="noisy throws per profile (default 100)")
    ap.add_argument("--seed", type=int, default=1, help="seed of the release noise (default 1)")
    ap.add_argument("--jobs", type=int, default=2, help="processes running frames (default 2)")
    ap.add_argument("--only", choices=profiles.NAMES, default=None, help="one profile")
    args = ap.parse_args()
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
