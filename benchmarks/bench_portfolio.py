"""nbst's default search (the portfolio) against its own ablations, same trial budget.

Configurations, each through ``nbst.solvers.islands.solve_islands`` as ``nbst solve`` runs it
(the CLI's target: round-off cost; ``--patience`` as given, default 0 = the whole budget):

* ``portfolio``: the default (variant "nbst"): on a problem with noncueable disks island k runs
  "nbst" (with the backward planner) or "nbst-noplan" in turn, and an island stopped by
  patience restarts with the other one (so with ``--patience 0`` nothing restarts); with
  ``--jobs 1`` the two islands take turns in one process;
* ``planner``: the old default, every island "nbst" (``portfolio=False``);
* ``noplan``: every island ``--variant nbst-noplan``.

For each problem, K in ``--jobs`` and search seed, it prints the final cost, order (disks
on target), whether it is exact (cost at round-off level), the trials spent and the wall
time; for the portfolio also which configuration produced the written solution. Then a
summary: the median cost per configuration and how many seeds each configuration is the
best (ties shared) or at least as good as the best ablation. Problems: the built-ins by
name, ``planted:N:NONCUE:SEED`` for ``nbst generate --planted N --noncue NONCUE --seed
SEED``, and ``planted-set[:TRIALS]`` for the 20 instances of docs/results/disks.md's planner section
(N = 6, 10, 14, 20, NONCUE = round(N/4), problem seeds 1-5). Runs are interleaved per seed,
so load drifts hit every configuration alike.

    python benchmarks/bench_portfolio.py [--problems over5:1000000,diamond-s14,diamond-s14-tiny]
        [--max-trials 300000] [--seeds 1,2,3] [--jobs 1,2] [--patience 0] [--target-cost C]
"""
from __future__ import annotations

import argparse
import statistics
import time

from nbst import load_problem
from nbst.search import roundoff_cost
from nbst.solvers.islands import solve_islands

CONFIGS = {"portfolio": {"variant": "nbst"},
           "planner": {"variant": "nbst", "portfolio": False},
           "noplan": {"variant": "nbst-noplan"}}


def load(spec: str):
    if spec.startswith("planted:"):
        from nbst.planted import planted

        _, n, non, seed = spec.split(":")
        return planted(int(n), noncue=int(non), seed=int(seed), name=spec)[0]
    return load_problem(spec)


def main() -> None:
    ap = argparse.ArgumentParser(allow_abbrev=False, description=__doc__.splitlines()[0])
    ap.add_argument("--problems", default="over5:1000000,diamond-s14,diamond-s14-tiny",
                    help="comma-separated NAME[:TRIALS] (planted:N:NONCUE:SEED[:TRIALS] and planted-set[:TRIALS] too); "
                         "TRIALS overrides --max-trials")
    ap.add_argument("--max-trials", type=int, default=300_000)
    ap.add_argument("--seeds", default="1,2,3")
    ap.add_argument("--jobs", default="1,2")
    ap.add_argument("--patience", type=int, default=0)
    ap.add_argument("--configs", default=",".join(CONFIGS))
    ap.add_argument("--target-cost", type=float, default=None,
                    help="stop at this cost (default: round-off level, as nbst solve); exact = cost <= it")
    a = ap.parse_args()
    seeds = [int(s) for s in a.seeds.split(",")]
    jobs_list = [int(j) for j in a.jobs.split(",")]
    configs = a.configs.split(",")

    specs = []
    for spec in a.problems.split(","):
        if spec.split(":")[0] == "planted-set":
            tail = spec[len("planted-set"):]
            specs += [f"planted:{n}:{round(n / 4)}:{s}{tail}" for n in (6, 10, 14, 20) for s in range(1, 6)]
        else:
            specs.append(spec)
    cases = []
    for spec in specs:
        parts = spec.split(":")
        want = 5 if parts[0] == "planted" else 2
        budget = int(parts[-1]) if len(parts) == want else a.max_trials
        cases.append((load(":".join(parts[:want - 1])), budget))
    solve_islands(load_problem("over5"), jobs=1, seed=0, max_trials=5000, patience=0)  # compile outside timings

    print(f"patience {a.patience}; seeds {seeds}; cost / order / exact (x) / trials / wall s")
    summary = []
    for p, budget in cases:
        target = roundoff_cost(p) if a.target_cost is None else a.target_cost
        for jobs in jobs_list:
            rows = {c: [] for c in configs}
            for seed in seeds:
                for c in configs:
                    t = time.perf_counter()
                    m = solve_islands(p, jobs=jobs, seed=seed, max_trials=budget, patience=a.patience,
                                      target_cost=target, **CONFIGS[c]).meta
                    rows[c].append((m["cost"], m["order"], m["cost"] <= target, m["trials"],
                                    time.perf_counter() - t, m.get("configuration", "")))
            print(f"\n{p.name}, {budget:,} trials, --jobs {jobs}")
            print("| config | " + " | ".join(f"seed {s}" for s in seeds) + " | median cost | median wall s |")
            print("|---|" + "---|" * (len(seeds) + 2))
            for c in configs:
                cells = [f"{cost:.6g} / {o}/{p.n}{' x' if ex else ''} / {tr // 1000}k / {w:.1f}"
                         + (f" ({cf})" if cf else "") for cost, o, ex, tr, w, cf in rows[c]]
                print(f"| {c} | " + " | ".join(cells)
                      + f" | {statistics.median(r[0] for r in rows[c]):.6g}"
                      + f" | {statistics.median(r[4] for r in rows[c]):.1f} |")
            abl = [c for c in configs if c != "portfolio"]
            ok = (sum(rows["portfolio"][i][0] <= min(rows[c][i][0] for c in abl) for i in range(len(seeds)))
                  if abl else len(seeds)) if "portfolio" in rows else None
            best = {c: sum(rows[c][i][0] == min(rows[d][i][0] for d in configs) for i in range(len(seeds)))
                    for c in configs}
            summary.append((p.name, budget, jobs, ok, best,
                            {c: (statistics.median(r[0] for r in rows[c]), statistics.mean(r[0] for r in rows[c]),
                                 sum(r[2] for r in rows[c]), statistics.median(r[3] for r in rows[c]))
                             for c in configs}))
    print("\nsummary: per problem and K, seeds where the portfolio is <= every ablation and seeds each "
          "configuration is best (the seeds are not paired: each configuration's islands draw their own), "
          "then per configuration: median cost / mean cost / exact runs / median trials")
    for name, budget, jobs, ok, best, st in summary:
        print(f"  {name} {budget:,} --jobs {jobs}: "
              + (f"portfolio <= ablations on {ok}/{len(seeds)} seeds; " if ok is not None else "") + "best: "
              + ", ".join(f"{c} {n}" for c, n in best.items()) + "; "
              + "; ".join(f"{c} {md:.6g} / {mn:.6g} / {ex}/{len(seeds)} / {tr:,.0f}" for c, (md, mn, ex, tr) in st.items()))


if __name__ == "__main__":
    main()
