#!/usr/bin/env python3
"""Issue 3's result runs for docs/results/disks.md (benchmark runs, not tests). Prints markdown.

    python benchmarks/results_search.py                 # tiny (20 seeds), diamond-s14 and over5 (5 x 400k)
    python benchmarks/results_search.py --variants      # also variants A-H, 5 seeds x 400k, both problems
    python benchmarks/results_search.py --variants-only --tiny-seeds 0   # just that table

One trial = one simulated candidate (initialize's included); "iterations" are
generate-insert iterations only (trials minus initialize's trials), the paper's
footnote-4 unit. Seeds are 1..n; patience is off so every run uses its budget.
"""
from __future__ import annotations

import argparse
import os
import platform
import statistics

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

from nbst import __version__, load_problem  # noqa: E402
from nbst.search import solve  # noqa: E402


def tiny(seeds: int) -> None:
    p = load_problem("diamond-s14-tiny")
    print(f"### diamond-s14-tiny: trials to cost < 1e-6 ({seeds} seeds)\n")
    print("| seed | trials (total) | initialize trials | generate-insert iterations | final cost |")
    print("|---:|---:|---:|---:|---:|")
    tot, its = [], []
    for seed in range(1, seeds + 1):
        m = solve(p, seed=seed, max_trials=1_000_000, patience=0, target_cost=1e-6).meta
        ok = m["cost"] < 1e-6
        tot.append(m["trials"] if ok else float("inf"))
        its.append(m["trials"] - m["init_trials"] if ok else float("inf"))
        print(f"| {seed} | {m['trials']} | {m['init_trials']} | {m['trials'] - m['init_trials']} | {m['cost']:.3g} |")
    print(f"\nMedian: **{statistics.median(tot):g} trials** in all, **{statistics.median(its):g} generate-insert "
          f"iterations** (paper: 54 iterations); range {min(its)}-{max(its)} iterations.\n")


def big(name: str, seeds: int, trials: int) -> None:
    p = load_problem(name)
    print(f"### {name}: {seeds} seeds x {trials:,} trials (variant A)\n")
    print("| seed | best cost | order | signature | first trial with order N | trials/s |")
    print("|---:|---:|---:|---|---:|---:|")
    costs, fallback, culls = [], 0, 0
    for seed in range(1, seeds + 1):
        m = solve(p, seed=seed, max_trials=trials, patience=0).meta
        costs.append(m["cost"])
        fallback += m["fallback_deletions"]
        culls += m["cull_rounds"]
        ff = m["first_full_order_trial"]
        print(f"| {seed} | {m['cost']:.6g} | {m['order']}/{p.n} | `{m['signature']}` | "
              f"{ff if ff is not None else 'never'} | {m['trials_per_s']:,.0f} |")
    print(f"\nBest cost: median {statistics.median(costs):.6g}, best {min(costs):.6g}, worst {max(costs):.6g}. "
          f"Culling rounds: {culls:,} in all; hard-limit fallback deletions: {fallback}.\n")


def variants(seeds: int, trials: int) -> None:
    print(f"### Variants A-H ({seeds} seeds x {trials:,} trials; the paper's Figures 7 and 8)\n")
    for name in ("diamond-s14", "over5"):
        p = load_problem(name)
        print(f"**{name}** (L2 cost of the best solution per run)\n")
        print("| variant | mean | best | worst | runs reaching order N | median trials/s |")
        print("|---|---:|---:|---:|---:|---:|")
        for v in "ABCDEFGH":
            ms = [solve(p, seed=s, max_trials=trials, patience=0, variant=v).meta for s in range(1, seeds + 1)]
            c = [m["cost"] for m in ms]
            full = sum(m["order"] == p.n for m in ms)
            print(f"| {v} | {statistics.mean(c):.6g} | {min(c):.6g} | {max(c):.6g} | {full}/{seeds} | "
                  f"{statistics.median(m['trials_per_s'] for m in ms):,.0f} |")
        print()


def main() -> None:
    ap = argparse.ArgumentParser(allow_abbrev=False, description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--tiny-seeds", type=int, default=20)
    ap.add_argument("--trials", type=int, default=400_000)
    ap.add_argument("--variants", action="store_true")
    ap.add_argument("--variants-only", action="store_true", help="only the variants table (implies --variants)")
    args = ap.parse_args()
    solve(load_problem("over5"), seed=0, max_trials=1000)  # load the compiled loop
    print(f"<!-- nbst {__version__}, python {platform.python_version()}, {platform.machine()} -->\n")
    if args.tiny_seeds > 0:
        tiny(args.tiny_seeds)
    if not args.variants_only:
        for name in ("diamond-s14", "over5"):
            big(name, args.seeds, args.trials)
    if args.variants or args.variants_only:
        variants(args.seeds, args.trials)


if __name__ == "__main__":
    main()
