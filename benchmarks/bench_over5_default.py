"""over5: nbst's default search against each single configuration it ships, per seed (issue 35, item 6).

    nice -n 5 .venv/bin/python benchmarks/bench_over5_default.py [--seeds 1,2,3,4,5] [--max-trials 1000000]

* **default**: what ``nbst solve over5 --seed S`` runs: ``solve_islands`` with the default jobs
  (every core), --max-trials, the CLI's patience (100,000) and target (round-off level): on over5
  (noncueable disks) nbst's portfolio of islands (``nbst.solvers.islands.PORTFOLIO``).
* **single configurations**: one search of one variant in one process (``nbst.search.solve``),
  the same budget, patience off as in ``nbst experiment ablation`` and with the CLI's 100,000
  (``nbst solve --variant V --jobs 1``).

Prints a markdown table: the final cost per seed, the median and the mean.
"""
from __future__ import annotations

import argparse
import statistics
import sys
import time


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], allow_abbrev=False)
    ap.add_argument("--seeds", default="1,2,3,4,5")
    ap.add_argument("--max-trials", type=int, default=1_000_000)
    ap.add_argument("--variants", default="nbst-noplan,nbst,A")
    a = ap.parse_args(argv)
    from nbst.parallel import default_jobs
    from nbst.problem import load_problem
    from nbst.search import DEFAULT_PATIENCE, roundoff_cost, solve
    from nbst.solvers.islands import solve_islands

    p = load_problem("over5")
    seeds = [int(s) for s in a.seeds.split(",")]
    jobs = default_jobs()
    solve(p, seed=0, max_trials=5000)  # load the compiled loops outside the timings
    rows = []

    def row(name: str, run) -> None:
        costs, t = [], time.perf_counter()
        for s in seeds:
            costs.append(run(s))
        rows.append((name, costs, time.perf_counter() - t))
        print(f"{name}: " + ", ".join(f"{c:,.0f}" for c in costs) + f"  ({time.perf_counter() - t:.0f} s)",
              file=sys.stderr, flush=True)

    tc = roundoff_cost(p)
    row(f"default (`nbst solve`, --jobs {jobs})",
        lambda s: solve_islands(p, jobs=jobs, seed=s, max_trials=a.max_trials, patience=DEFAULT_PATIENCE,
                                target_cost=tc).cost)
    for v in a.variants.split(","):
        for patience in (0, DEFAULT_PATIENCE):
            row(f"`{v}` alone, patience {patience:,}",
                lambda s, v=v, patience=patience: solve(p, seed=s, max_trials=a.max_trials, patience=patience,
                                                        target_cost=tc, variant=v).cost)
    print(f"over5, {a.max_trials:,} trials, seeds {a.seeds}, final cost (L2) per seed\n")
    print("| configuration | " + " | ".join(f"seed {s}" for s in seeds) + " | median | mean |")
    print("|---|" + "---:|" * (len(seeds) + 2))
    for name, costs, _ in rows:
        print(f"| {name} | " + " | ".join(f"{c:,.0f}" for c in costs)
              + f" | {statistics.median(costs):,.0f} | {statistics.fmean(costs):,.0f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
