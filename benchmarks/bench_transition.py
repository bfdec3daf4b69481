"""Lane transition: the drift of a bowler over games on one lane, without and with moves (issue 34).

    nice -n 10 python benchmarks/bench_transition.py [--bowler pro] [--games 3] [--seeds 1-6] [--lineup 1]
                                                     [--lefty-share 0] [--jobs 1]

For each seed: the series of ``nbst bowl series --move both`` (models/bowling/lane/transition.py):
``--games`` games by ``--lineup`` bowlers of the profile on one fresh house shot that every ball wears,
bowled twice with the same releases, once keeping the line (move none) and once with the coach's
"2 and 1" moves (move auto). Prints, per game and run, pooled over the seeds: pocket hits of the strike
balls (boards 16.5-18.5 at the head pin) with the 95 % Wilson interval, strikes, the mean board at the
pins, breakpoint (ft, board) and entry angle, the moves made, the mean score; then the change from
game 1 to the last game and the paired difference in pocket hits (auto minus none, over the same
releases); the oil taken from the lane, left on it and carried past the pattern's end; seconds.
Seeds run in ``--jobs`` processes (each series on one core).
"""
from __future__ import annotations

import argparse
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np

from nbst.models.bowling.lane import noise, transition as T
from nbst.models.bowling.lane.oil import CELL_AREA


def _seeds(text: str) -> list[int]:
    a, _, b = text.partition("-")
    return list(range(int(a), int(b or a) + 1))


def one(seed: int, args) -> dict:
    t0 = time.time()
    bowlers = T.lineup(args.bowler, args.lineup, args.lefty_share)
    runs = [T.Run(bowlers, args.games, seed, m, "house") for m in ("none", "auto")]
    for r in runs:
        r.play()
    doc = T.series_dict(runs, profile=args.bowler, lineup_n=args.lineup, lefty_share=args.lefty_share)
    doc["seconds"] = time.time() - t0
    for r in doc["runs"]:  # the maps are large: keep the oil's totals only
        before, after = np.asarray(r["oil"].pop("before")), np.asarray(r["oil"].pop("after"))
        j = int(np.ceil(r["oil"]["length_ft"] / r["oil"]["dx_ft"]))
        r["oil"].update(before_ml=before.sum() * CELL_AREA, after_ml=after.sum() * CELL_AREA,
                        past_before_ml=before[:, j:].sum() * CELL_AREA, past_after_ml=after[:, j:].sum() * CELL_AREA)
    return doc


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0], allow_abbrev=False)
    ap.add_argument("--bowler", default="pro")
    ap.add_argument("--games", type=int, default=3)
    ap.add_argument("--seeds", default="1-6", help="seeds A-B (default 1-6)")
    ap.add_argument("--lineup", type=int, default=1)
    ap.add_argument("--lefty-share", type=float, default=0.0)
    ap.add_argument("--jobs", type=int, default=1)
    args = ap.parse_args()
    seeds = _seeds(args.seeds)
    t0 = time.time()
    if args.jobs > 1:
        with ProcessPoolExecutor(args.jobs) as ex:
            docs = list(ex.map(one, seeds, [args] * len(seeds)))
    else:
        docs = [one(s, args) for s in seeds]
    print(f"## lane transition: {args.bowler}, {args.lineup} bowler(s) ({args.lefty_share:g} left-handed), "
          f"{args.games} games on a fresh house shot, seeds {seeds[0]}-{seeds[-1]}, pooled\n")
    print("| move | game | hand | pocket hits (95 % CI) | strikes | board at pins | breakpoint | entry | moves | "
          "score |\n|---|---|---|---|---|---|---|---|---|---|")
    pooled = {}
    for m in (0, 1):
        for g in range(1, args.games + 1):
            for hand in ("right", "left"):
                rows = [s for d in docs for s in d["runs"][m]["summary"] if s["game"] == g and s["hand"] == hand]
                if not rows:
                    continue
                k, n = sum(s["pocket_hits"] for s in rows), sum(s["strike_balls"] for s in rows)
                lo, hi = noise.wilson(k, n)
                w = np.array([s["strike_balls"] for s in rows], dtype=float)

                def avg(key):
                    v = [(s[key], x) for s, x in zip(rows, w) if s[key] is not None]
                    return sum(a * b for a, b in v) / sum(b for _, b in v) if v else float("nan")

                moves = sum(1 for d in docs for mv in d["runs"][m]["moves"]
                            if _game_of(d["runs"][m], mv["after_ball"]) == g
                            and d["runs"][m]["bowlers"][mv["bowler"]]["hand"] == hand)
                scores = [v[g - 1][-1] for d in docs for b, v in d["runs"][m]["scores"].items()
                          if d["runs"][m]["bowlers"][int(b)]["hand"] == hand and v[g - 1]]
                pooled[(m, g, hand)] = (k, n)
                move = docs[0]["runs"][m]["move"]
                print(f"| {move} | {g} | {hand} | {k}/{n} = {100 * k / n:.0f} % ({100 * lo:.0f}-{100 * hi:.0f} %) | "
                      f"{sum(s['strikes'] for s in rows)}/{n} | {avg('board_at_pins'):.2f} | "
                      f"{avg('breakpoint_ft'):.1f} ft, board {avg('breakpoint_board'):.1f} | "
                      f"{avg('entry_angle_deg'):.2f} deg | {moves} | {np.mean(scores):.0f} |")
    last = args.games
    print()
    for m, name in ((0, "none"), (1, "auto")):
        for hand in ("right", "left"):
            if (m, 1, hand) in pooled:
                (k1, n1), (k3, n3) = pooled[(m, 1, hand)], pooled[(m, last, hand)]
                print(f"move {name}, {hand}: pocket hits game 1 {100 * k1 / n1:.0f} % -> game {last} "
                      f"{100 * k3 / n3:.0f} % ({100 * (k3 / n3 - k1 / n1):+.0f} points)")
    for g in range(1, last + 1):
        a = sum(pooled.get((1, g, h), (0, 0))[0] for h in ("right", "left"))
        b = sum(pooled.get((0, g, h), (0, 0))[0] for h in ("right", "left"))
        print(f"game {g}: pocket hits with moves minus without, same releases: {a - b:+d}")
    for m in (0, 1):
        o = [d["runs"][m]["oil"] for d in docs]
        taken = [sum(b["oil"]["taken"] for b in d["runs"][m]["balls"]) for d in docs]
        nb = [len(d["runs"][m]["balls"]) for d in docs]
        print(f"oil, move {docs[0]['runs'][m]['move']}: {np.mean(nb):.1f} balls a series; taken {np.mean(taken):.3f} ml "
              f"(lane {np.mean([x['before_ml'] for x in o]):.2f} -> {np.mean([x['after_ml'] for x in o]):.3f} ml); "
              f"past the pattern's end {np.mean([x['past_before_ml'] for x in o]) * 1000:.1f} -> "
              f"{np.mean([x['past_after_ml'] for x in o]) * 1000:.1f} ul")
    print(f"\n{len(seeds)} series x 2 runs in {time.time() - t0:.0f} s on {args.jobs} process(es) "
          f"({np.mean([d['seconds'] for d in docs]):.0f} s a series)")


def _game_of(run: dict, n: int) -> int:
    return next(b["game"] for b in run["balls"] if b["n"] == n)


if __name__ == "__main__":
    main()
