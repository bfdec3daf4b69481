#!/usr/bin/env python3
"""Speed of the whole generate-insert loop (simulation included) on one core.

    python benchmarks/bench_search.py [--problem diamond-s14] [--trials 400000] [--seeds 3]

Prints trials/s of ``solve`` per seed and, as the baseline for a ratio, the
throughput of plain ``nbst.evaluate`` (the simulator alone, batched, no search)
on four velocity sets: the candidates the same runs simulated (every 20th
trial, recorded by the loop: its exact mix without its bookkeeping, the fair
baseline), those runs' final populations, straight-to-target velocities, and initialize-style
random velocities (each disk directed or uniform randomize with probability 1/2).
Target (issue 3): >= 100,000 trials/s on diamond-s14.
"""
from __future__ import annotations

import argparse
import os
import statistics
import time

import numpy as np

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

from nbst import evaluate, load_problem  # noqa: E402
from nbst.search import mirror_images, run_search  # noqa: E402


def evaluate_rate(problem, V, *, min_time=1.0):
    """Trials/s of nbst.evaluate over the batch V (repeated until min_time seconds)."""
    evaluate(problem, V[:2])  # compile / load
    n, t0 = 0, time.perf_counter()
    while time.perf_counter() - t0 < min_time:
        evaluate(problem, V)
        n += len(V)
    return n / (time.perf_counter() - t0)


def init_style_velocities(problem, B, rng):
    """B velocity sets as initialize draws them: per cueable disk, directed or uniform randomize."""
    n, (W, H), T = problem.n, problem.box, problem.t_final
    images = mirror_images(5)
    V = np.zeros((B, n, 2))
    straight = problem.straight_velocities()
    for b in range(B):
        for i in np.flatnonzero(problem.cueable):
            if rng.random() < 0.5:
                V[b, i] = straight[i]
            else:
                r = problem.radius[i]
                kx, ky = images[rng.integers(len(images))]
                end = r + (np.array([kx, ky]) + rng.random(2)) * (np.array([W, H]) - 2 * r)
                V[b, i] = (end - problem.start[i]) / T
    return V


def main() -> None:
    ap = argparse.ArgumentParser(allow_abbrev=False, description=__doc__.splitlines()[0])
    ap.add_argument("--problem", default="diamond-s14")
    ap.add_argument("--trials", type=int, default=400_000)
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--variant", default="A")
    args = ap.parse_args()
    p = load_problem(args.problem)
    run_search(p, seed=0, max_trials=2000)  # load the compiled loop
    rates, runs = [], []
    print(f"problem {p.name}, variant {args.variant}, {args.trials} trials per run, patience off")
    print("seed  trials/s   best cost     order  first order-N trial")
    for seed in range(1, args.seeds + 1):
        r = run_search(p, seed=seed, max_trials=args.trials, patience=0, variant=args.variant, record_every=20)
        m = r.result.meta
        rates.append(m["trials_per_s"])
        runs.append(r)
        print(f"{seed:4d}  {m['trials_per_s']:9.0f}  {m['cost']:12.6g}  {m['order']:2d}/{p.n}  "
              f"{m['first_full_order_trial']}")
    med = statistics.median(rates)
    pop_v = np.concatenate([r.velocities for r in runs])
    rng = np.random.default_rng(0)
    base_pop = evaluate_rate(p, pop_v)
    kids = np.concatenate([r.recorded for r in runs])
    base_kids = evaluate_rate(p, kids)
    base_straight = evaluate_rate(p, np.repeat(p.straight_velocities()[None], 2000, axis=0))
    base_init = evaluate_rate(p, init_style_velocities(p, 2000, rng))
    print(f"\nsearch loop (median of {len(rates)}): {med:,.0f} trials/s")
    print(f"evaluate baseline, the same runs' candidates (every 20th trial, {len(kids)} sets): "
          f"{base_kids:,.0f} sims/s   loop/baseline = {med / base_kids:.2f}")
    print(f"evaluate baseline, final populations ({len(pop_v)} sets): {base_pop:,.0f} sims/s   "
          f"loop/baseline = {med / base_pop:.2f}")
    print(f"evaluate baseline, straight velocities: {base_straight:,.0f} sims/s   "
          f"loop/baseline = {med / base_straight:.2f}")
    print(f"evaluate baseline, initialize-style random velocities: {base_init:,.0f} sims/s   "
          f"loop/baseline = {med / base_init:.2f}")
    ok = med >= 100_000
    print(f"target >= 100,000 trials/s: {'met' if ok else 'NOT met'}")


if __name__ == "__main__":
    main()
