"""Speed-up of ``nbst solve --jobs K`` against ``--jobs 1``, measured in one run.

Problems: planted all-cueable instances (``nbst generate --planted N``; N = 10, 20, 30,
problem seeds 1-3) and diamond-s14. Each is solved to round-off cost with search seeds
1..S, once with K = 1 and once with K = 2 (interleaved, so load drifts hit both alike).
Reported: median time to target per K and its ratio, the geometric mean of the per-case
ratios, and trials/s (all islands together). Also ``nbst.evaluate`` on a large batch
with 1 and 2 threads.

    python benchmarks/bench_jobs.py [--seeds 3] [--max-trials 2000000]
"""
from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from nbst import evaluate, load_problem
from nbst.solvers.islands import solve_islands
from nbst.planted import planted
from nbst.search import roundoff_cost


def main() -> None:
    ap = argparse.ArgumentParser(allow_abbrev=False, description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--max-trials", type=int, default=2_000_000)
    ap.add_argument("--jobs", type=int, default=2)
    a = ap.parse_args()

    cases = [("diamond-s14", load_problem("diamond-s14"))]
    for n in (10, 20, 30):
        for ps in (1, 2, 3):
            cases.append((f"planted-{n}-s{ps}", planted(n, seed=ps)[0]))
    # compile (and load) the kernels outside the timings
    solve_islands(cases[1][1], jobs=1, seed=0, max_trials=3000, patience=0)
    solve_islands(cases[1][1], jobs=a.jobs, seed=0, max_trials=3000, patience=0)

    print(f"{'problem':16s} {'K':>2s} {'solved':>6s} {'median s':>9s} {'trials/s':>10s}")
    ratios = []
    for name, p in cases:
        t = {1: [], a.jobs: []}
        rate = {1: [], a.jobs: []}
        solved = {1: 0, a.jobs: 0}
        for s in range(1, a.seeds + 1):
            for k in (1, a.jobs):
                t0 = time.perf_counter()
                sol = solve_islands(p, jobs=k, seed=s, max_trials=a.max_trials, patience=0,
                                    target_cost=roundoff_cost(p))
                dt = time.perf_counter() - t0
                t[k].append(dt)
                rate[k].append(sol.meta["trials"] / dt)
                solved[k] += sol.meta["cost"] <= roundoff_cost(p)
        for k in (1, a.jobs):
            print(f"{name:16s} {k:2d} {solved[k]:>3d}/{a.seeds:<2d} {statistics.median(t[k]):9.3f} "
                  f"{statistics.median(rate[k]):10.0f}")
        ratios.append(statistics.median(t[1]) / statistics.median(t[a.jobs]))
        print(f"{'':16s} time-to-target speed-up K={a.jobs}: {ratios[-1]:.2f}x")
    gm = float(np.exp(np.mean(np.log(ratios))))
    print(f"geometric mean speed-up of time to target, K={a.jobs} vs 1: {gm:.2f}x over {len(ratios)} problems")

    p = load_problem("diamond-s14")
    V = p.straight_velocities() + np.random.default_rng(0).normal(0, 50, (100_000, 14, 2))
    evaluate(p, V[:10], jobs=1)
    te = {}
    for k in (1, a.jobs, 1, a.jobs):
        t0 = time.perf_counter()
        evaluate(p, V, jobs=k)
        te.setdefault(k, []).append(time.perf_counter() - t0)
    b1, bk = min(te[1]), min(te[a.jobs])
    print(f"evaluate 100k candidates: {len(V) / b1:,.0f}/s on 1 thread, {len(V) / bk:,.0f}/s on {a.jobs} "
          f"({b1 / bk:.2f}x)")


if __name__ == "__main__":
    main()
