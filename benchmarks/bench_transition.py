"""Lane transition: the drift of a bowler over games on one lane, without and with moves (issue 34).

    nice -n 10 python benchmarks/bench_transition.py [--bowler pro] [--games 3] [--seeds 1-6] [--lineup 1]
                                                     [--lefty-share 0] [--jobs 1]
    nice -n 10 python benchmarks/bench_transition.py --part sensitivity [--throws 20]
    nice -n 10 python benchmarks/bench_transition.py --part depletion [--seeds 1-4] [--lineup 4]
    nice -n 10 python benchmarks/bench_transition.py --part wear [--seeds 1-4] [--games 3] [--oil house]

For each seed: the series of ``nbst bowl series --move both`` (models/bowling/lane/transition.py):
``--games`` games by ``--lineup`` bowlers of the profile on one fresh house shot that every ball wears,
bowled twice with the same releases, once keeping the line (move none) and once with the coach's
"2 and 1" moves (move auto). Prints, per game and run, pooled over the seeds: pocket hits of the strike
balls (boards 16.5-18.5 at the head pin) with the 95 % Wilson interval, strikes, the mean board at the
pins, breakpoint (ft, board) and entry angle, the moves made, the mean score; then the change from
game 1 to the last game and the paired difference in pocket hits (auto minus none, over the same
releases); the oil taken from the lane, left on it and carried past the pattern's end; seconds.
Seeds run in ``--jobs`` processes (each series on one core).

``--part sensitivity``: the assumed oil-exchange constants (the share of the film difference that
lane and cover even out, ``OilLaw.exchange``, 0.3; the cover's absorption time, ``Ball.absorb_s``,
1 s: no published figure) halved and doubled, on ``--throws`` identical throws of issue 34's typical
release (the ball alone, no noise): the oil a throw takes, the film under the track at 20 ft, the
board at the pins after 10 and after all throws, and the oil carried past the pattern's end.

``--part depletion``: the exchange share against the one published figure we found for how fast play
takes oil off a lane. Kegel's tape tests at the 2013 WTBA World Championships (Ted Thompson, "Who do
you follow?", Kegel's *The Inside Line*, 25 November 2013): when players play a similar line on a fresh
pattern, "over 40 percent of the lane conditioner can be removed from that area throughout the
ENTIRE length of the applied oil pattern" by the time about 4-5 games have been bowled on the lane.
Here ``--lineup`` bowlers of ``--bowler`` (default 4 pros) bowl one game each on a fresh house shot (so 4 games on the lane,
every ball, strike and spare), no moves, at exchange 0.15, 0.3 (as shipped) and 0.6, seeds
``--seeds``. Read like a tape: at every 0.25 ft from 5 ft to 2 ft short of the pattern's end, the
board that lost the largest share of its oil, and the share lost by the 3, 5 and 7 boards centred on
it (the area of play: its width is our choice, and the table gives all three); the mean over those
distances, per seed, and the share of the whole pattern taken.

``--part wear`` (issue 48: the track and the carry-down): for each profile, ``--games`` x 12 strike balls
under the profile's noise, the ball alone (:func:`.wear.strike_wear`), on one lane of ``--oil``, per
seed: after each game, the track's width at 10, 20 and 30 ft (the run of boards around the driest that lost
at least 10 % of their film), the driest board's loss there, the oil past the pattern's end, and the
oil's account (initial minus removed, carried and remaining).
"""
from __future__ import annotations

import argparse
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np

from dataclasses import replace

from nbst.models.bowling import lane
from nbst.models.bowling.lane import noise, transition as T, wear as W
from nbst.models.bowling.lane.oil import CELL_AREA


def _seeds(text: str) -> list[int]:
    a, _, b = text.partition("-")
    return list(range(int(a), int(b or a) + 1))


def one(seed: int, args) -> dict:
    t0 = time.time()
    bowlers = T.lineup(args.bowler, args.lineup, args.lefty_share)
    runs = [T.Run(bowlers, args.games, seed, m, "house") for m in args.moves.split(",")]
    for r in runs:
        r.play()
    doc = T.series_dict(runs, profile=args.bowler, lineup_n=args.lineup, lefty_share=args.lefty_share)
    doc["seconds"] = time.time() - t0
    for r in doc["runs"]:  # the maps are large: keep the oil's totals only
        before, after = np.asarray(r["oil"].pop("before")), np.asarray(r["oil"].pop("after"))
        r["oil"].pop("games", None)
        j = int(np.ceil(r["oil"]["length_ft"] / r["oil"]["dx_ft"]))
        r["oil"].update(before_ml=before.sum() * CELL_AREA, after_ml=after.sum() * CELL_AREA,
                        past_before_ml=before[:, j:].sum() * CELL_AREA, past_after_ml=after[:, j:].sum() * CELL_AREA)
    return doc


TYPICAL = lane.Delivery(board=23.0, at="foul", angle=3.627, mph=17.0, rpm=400.0, rotation=45.0, tilt=10.0)


def sensitivity(n: int) -> None:
    print(f"## transition's assumed constants: {n} identical throws of the typical release (17 mph, 400 rpm, "
          f"45/10, board 23 at 3.627 deg), the ball alone, fresh house shot\n")
    print("| setting | oil taken, throw 1 / throw n (ul) | film at 20 ft, throw 1 -> n (um) | board at pins: 1, 10, n | "
          "past 40 ft after n (ul) | s |\n|---|---|---|---|---|---|")
    b0 = lane.Ball()
    for label, law, ball in (("as shipped: exchange 0.3, absorb 1 s", lane.LAW, b0),
                             ("exchange 0.15", replace(lane.LAW, exchange=0.15), b0),
                             ("exchange 0.6", replace(lane.LAW, exchange=0.6), b0),
                             ("absorb 0.5 s", lane.LAW, replace(b0, absorb_s=0.5)),
                             ("absorb 2 s", lane.LAW, replace(b0, absorb_s=2.0))):
        t0 = time.time()
        out = W.identical_throws(TYPICAL, n, "house", ball, law=law)
        b = [o["board_at_pins"] for o in out]
        print(f"| {label} | {1e3 * out[0]['oil']['taken']:.1f} / {1e3 * out[-1]['oil']['taken']:.1f} | "
              f"{out[0]['film_um']:.2f} -> {out[-1]['film_um']:.2f} | {b[0]:.2f}, {b[min(9, n - 1)]:.2f}, {b[-1]:.2f} | "
              f"{1e3 * out[-1]['past_ml']:.1f} | {time.time() - t0:.0f} |", flush=True)


def _area_of_play(before: np.ndarray, after: np.ndarray, dx_ft: float, length_ft: float, width: int) -> float:
    """Mean over distances (5 ft .. length - 2 ft) of the share of oil lost by the ``width`` boards
    centred on the board that lost the largest share there (boards with a film above 0.05 um)."""
    half = width // 2
    shares = []
    for j in range(int(5 / dx_ft), int((length_ft - 2) / dx_ft)):
        b, a = before[:, j], after[:, j]
        lost = np.where(b > 0.05, 1 - a / np.maximum(b, 1e-12), -1.0)
        k = int(np.argmax(lost))
        w = slice(max(k - half, 0), k + half + 1)
        shares.append(1 - a[w].sum() / b[w].sum())
    return float(np.mean(shares))


def depletion(seeds: list[int], n: int, bowler: str = "pro") -> None:
    print(f"## oil taken from the area of play: {n} bowlers of profile {bowler}, one game each on a fresh house shot ({n} games on the "
          f"lane), no moves; Kegel (WTBA 2013): over 40 % after about 4-5 games on the lane\n")
    print("| exchange | seed | balls on the lane | area of play lost: 3 / 5 / 7 boards | whole pattern lost | s |\n"
          "|---|---|---|---|---|---|")
    for ex in (0.15, 0.3, 0.6):
        law = replace(lane.LAW, exchange=ex)
        for seed in seeds:
            t0 = time.time()
            r = T.Run(T.lineup(bowler, n), 1, seed, "none", "house", law=law)
            r.play()
            d = r.to_dict()
            before, after = np.asarray(d["oil"]["before"]), np.asarray(d["oil"]["after"])
            dx, length = d["oil"]["dx_ft"], d["oil"]["length_ft"]
            shares = [_area_of_play(before, after, dx, length, w) for w in (3, 5, 7)]
            j = int(np.ceil(length / dx))
            whole = 1 - after[:, :j].sum() / before[:, :j].sum()
            print(f"| {ex:g} | {seed} | {len(d['balls'])} | {' / '.join(f'{100 * x:.0f} %' for x in shares)} | "
                  f"{100 * whole:.1f} % | {time.time() - t0:.0f} |", flush=True)


def wear(seeds: list[int], games: int, oil: str) -> None:
    print(f"## the track and the carry-down: {games} x 12 strike balls a profile, the ball alone, one lane of {oil}, "
          f"seeds {seeds[0]}-{seeds[-1]}\n")
    print("| profile | seed | track width at 10 / 20 / 30 ft by game (boards) | driest board's loss at 10 / 20 / 30 ft "
          "after the last | past the end by game (ul) | account (ml) | s |\n|---|---|---|---|---|---|---|")
    from nbst.models.bowling.lane import profiles

    for prof in profiles.PROFILES.names():
        for seed in seeds:
            t0 = time.time()
            w = W.strike_wear(prof, games, seed, oil)
            b = w["before"]
            widths = "; ".join("/".join(str(T.track_width(b, g["map"], ft)) for ft in (10, 20, 30)) for g in w["games"])
            dry = " / ".join(f"{100 * T.depleted_share(b, w['games'][-1]['map'], ft):.0f} %" for ft in (10, 20, 30))
            past = ", ".join(f"{1e3 * g['past_end_ml']:.0f}" for g in w["games"])
            acct = w["initial"] - (w["removed"] + w["carried"] + w["remaining"])
            print(f"| {prof} | {seed} | {widths} | {dry} | {past} | {acct:.1e} | {time.time() - t0:.0f} |", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0], allow_abbrev=False)
    ap.add_argument("--part", choices=("drift", "sensitivity", "depletion", "wear"), default="drift")
    ap.add_argument("--oil", default="house", help="--part wear: the pattern (default house)")
    ap.add_argument("--throws", type=int, default=20, help="--part sensitivity: identical throws (default 20)")
    ap.add_argument("--bowler", default="pro")
    ap.add_argument("--games", type=int, default=3)
    ap.add_argument("--seeds", default=None, help="seeds A-B (default 1-6; --part depletion 1-4)")
    ap.add_argument("--lineup", type=int, default=None, help="bowlers on the lane (default 1; --part depletion 4)")
    ap.add_argument("--lefty-share", type=float, default=0.0)
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--moves", default="none,auto", help="the runs of each series (default none,auto)")
    args = ap.parse_args()
    if args.part == "sensitivity":
        sensitivity(args.throws)
        return
    if args.part == "wear":
        wear(_seeds(args.seeds or "1-4"), args.games, args.oil)
        return
    if args.part == "depletion":
        depletion(_seeds(args.seeds or "1-4"), args.lineup or 4, args.bowler)
        return
    args.seeds, args.lineup = args.seeds or "1-6", args.lineup or 1
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
    nm = len(docs[0]["runs"])
    for m in range(nm):
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
    for m, name in enumerate(args.moves.split(",")):
        for hand in ("right", "left"):
            if (m, 1, hand) in pooled:
                (k1, n1), (k3, n3) = pooled[(m, 1, hand)], pooled[(m, last, hand)]
                print(f"move {name}, {hand}: pocket hits game 1 {100 * k1 / n1:.0f} % -> game {last} "
                      f"{100 * k3 / n3:.0f} % ({100 * (k3 / n3 - k1 / n1):+.0f} points)")
    for g in range(1, last + 1 if nm == 2 else 1):
        a = sum(pooled.get((1, g, h), (0, 0))[0] for h in ("right", "left"))
        b = sum(pooled.get((0, g, h), (0, 0))[0] for h in ("right", "left"))
        print(f"game {g}: pocket hits with moves minus without, same releases: {a - b:+d}")
    for m in range(nm):
        o = [d["runs"][m]["oil"] for d in docs]
        taken = [sum(b["oil"]["taken"] for b in d["runs"][m]["balls"]) for d in docs]
        nb = [len(d["runs"][m]["balls"]) for d in docs]
        print(f"oil, move {docs[0]['runs'][m]['move']}: {np.mean(nb):.1f} balls a series; taken {np.mean(taken):.3f} ml "
              f"(lane {np.mean([x['before_ml'] for x in o]):.2f} -> {np.mean([x['after_ml'] for x in o]):.3f} ml); "
              f"past the pattern's end {np.mean([x['past_before_ml'] for x in o]) * 1000:.1f} -> "
              f"{np.mean([x['past_after_ml'] for x in o]) * 1000:.1f} ul")
    print(f"\n{len(seeds)} series x {nm} run(s) in {time.time() - t0:.0f} s on {args.jobs} process(es) "
          f"({np.mean([d['seconds'] for d in docs]):.0f} s a series)")


def _game_of(run: dict, n: int) -> int:
    return next(b["game"] for b in run["balls"] if b["n"] == n)


if __name__ == "__main__":
    main()
