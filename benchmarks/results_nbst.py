"""Results of nbst's own search (variant "nbst", issue 4): benchmark runs, not tests.

Prints Markdown tables (paste into docs/results/disks.md):

    python benchmarks/results_nbst.py targets      # diamond-s14, tiny, over5 against the issue's targets
    python benchmarks/results_nbst.py ablation     # each addition off, one at a time
    python benchmarks/results_nbst.py planted      # planted instances: nbst vs the paper's A (and CMA-ES if available)
    python benchmarks/results_nbst.py speed        # trials/s of the nbst loop on diamond-s14 (polish counted)

One trial = one simulation (polish's simulations included). Costs and trial counts are
exact functions of the seeds; times depend on the machine's load.
"""
from __future__ import annotations

import argparse
import dataclasses
import statistics
import sys
import time

import numpy as np

from nbst import load_problem
from nbst.planted import planted
from nbst.search import solve, variant_params

OFF = {  # ablation: each addition off alone (and the two that are off by default, on)
    "nbst (all on)": {},
    "no polish": {"polish": False},
    "no bank shots": {"bank_weight": 0.0},
    "no strikes": {"strike_weight": 0.0},
    "no straight start": {"straight_start": False},
    "+ adaptive schedule (off by default)": {"adapt": True},
    "+ restarts every 20k (off by default)": {"restart": 20_000},
}


def med(xs):
    xs = [x for x in xs if x is not None]
    return statistics.median(xs) if xs else None


def fmt(x, digits=4):
    if x is None:
        return "—"
    if isinstance(x, (int, np.integer)):
        return f"{int(x):,}"
    return f"{x:.{digits}g}"


def run(problem, seed, max_trials, target_cost=None, **params):
    p = dataclasses.replace(variant_params("nbst"), **params) if params else None
    sol = solve(problem, seed=seed, max_trials=max_trials, patience=0, target_cost=target_cost, params=p)
    return sol.meta


def targets(a):
    print("### nbst against the issue's targets\n")
    s14 = load_problem("diamond-s14")
    rows = [run(s14, seed, 1_000_000, 1e-6) for seed in range(1, 6)]
    ok = [m for m in rows if m["cost"] < 1e-6]
    print(f"- diamond-s14, 5 seeds, budget 1,000,000: cost < 1e-6 in {len(ok)}/5; trials "
          f"{', '.join(fmt(m['trials']) for m in rows)} (median {fmt(med([m['trials'] for m in ok]))}); "
          f"wall {', '.join(format(m['wall_time'], '.2f') for m in rows)} s")
    tiny = load_problem("diamond-s14-tiny")
    rows = [run(tiny, seed, 100_000, 1e-6) for seed in range(1, 21)]
    ok = [m for m in rows if m["cost"] < 1e-6]
    print(f"- diamond-s14-tiny, 20 seeds: cost < 1e-6 in {len(ok)}/20; median trials "
          f"{fmt(med([m['trials'] for m in ok]))} (max {fmt(max(m['trials'] for m in rows))})")
    o5 = load_problem("over5")
    rows = [run(o5, seed, 1_000_000) for seed in range(1, 6)]
    print(f"- over5, 5 seeds x 1,000,000 trials: best order {', '.join(str(m['order']) for m in rows)}; "
          f"order 5 in {sum(m['order'] == 5 for m in rows)}/5; best cost "
          f"{', '.join(fmt(m['cost']) for m in rows)} (median {fmt(med([m['cost'] for m in rows]))}); "
          f"first order-5 trial {', '.join(fmt(m['first_full_order_trial']) for m in rows)}")


def ablation(a):
    print("### Ablation: each addition of the nbst search off alone\n")
    s14, o5 = load_problem("diamond-s14"), load_problem("over5")
    print("| configuration | diamond-s14: solved (< 1e-6) / 5 within 200k | median trials to 1e-6 | "
          "over5: median best cost (5 x 400k) | over5: order-5 runs |")
    print("|---|---|---|---|---|")
    for name, off in OFF.items():
        d = [run(s14, seed, 200_000, 1e-6, **off) for seed in range(1, 6)]
        solved = [m for m in d if m["cost"] < 1e-6]
        o = [run(o5, seed, 400_000, **off) for seed in range(1, 6)]
        print(f"| {name} | {len(solved)}/5 | {fmt(med([m['trials'] for m in solved]))} | "
              f"{fmt(med([m['cost'] for m in o]))} | {sum(m['order'] == 5 for m in o)}/5 |", flush=True)


def planted_set(a):
    print("### Planted instances (3 per size; one run each; budget 1,000,000 trials)\n")
    algos = {"nbst": lambda p, s: solve(p, seed=s, max_trials=a.trials, patience=0, target_cost=1e-6).meta,
             "A (paper)": lambda p, s: solve(p, seed=s, max_trials=a.trials, patience=0, target_cost=1e-6,
                                             variant="A").meta}
    try:
        from nbst.solvers.baselines import solve_cma
        algos["CMA-ES (IPOP)"] = lambda p, s: solve_cma(p, seed=s, max_trials=a.trials, target_cost=1e-6).meta
    except ImportError:
        print("(nbst.solvers.baselines.solve_cma not available: CMA-ES column omitted)\n")
    sets = ((0.0, "all cueable: cost < 1e-6"), (0.3, "30% noncueable"))
    for noncue_frac, title in (s for s, name in zip(sets, ("cueable", "noncue")) if a.set in (name, "both")):
        print(f"#### {title}\n")
        print("| N | " + " | ".join(f"{k}: solved / order N / median cost / median trials" for k in algos) + " |")
        print("|---|" + "---|" * len(algos))
        for n in a.sizes:
            k = int(round(noncue_frac * n))
            cells = []
            for name, f in algos.items():
                ms = [f(planted(n, noncue=k, seed=1000 + 10 * n + i)[0], i + 1) for i in range(3)]
                solved = [m for m in ms if m["cost"] < 1e-6]
                cells.append(f"{len(solved)}/3 / {sum(m['order'] == n for m in ms)}/3 / "
                             f"{fmt(med([m['cost'] for m in ms]), 3)} / {fmt(med([m['trials'] for m in ms]))}")
            print(f"| {n} | " + " | ".join(cells) + " |", flush=True)
        print()


def speed(a):
    s14 = load_problem("diamond-s14")
    print("### Speed of the nbst loop (diamond-s14, polish counted as the simulations it runs)\n")
    print("| seed | trials | wall s | trials/s | of which polish | restarts |")
    print("|---|---|---|---|---|---|")
    for seed in (1, 2, 3):
        t = time.perf_counter()
        m = solve(s14, seed=seed, max_trials=400_000, patience=0).meta  # no target: keeps refining past 1e-6
        dt = time.perf_counter() - t
        print(f"| {seed} | {m['trials']:,} | {dt:.2f} | {m['trials'] / dt:,.0f} | "
              f"{m['polish']['simulations']:,} | {m['restarts']} |")
    m = solve(s14, seed=1, max_trials=400_000, patience=0, variant="A").meta
    print(f"\nsame machine, same run: the paper's A at {m['trials_per_s']:,.0f} trials/s")


def main():
    ap = argparse.ArgumentParser(allow_abbrev=False, description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("what", choices=["targets", "ablation", "planted", "speed"])
    ap.add_argument("--trials", type=int, default=1_000_000)
    ap.add_argument("--sizes", type=int, nargs="+", default=[6, 10, 14, 20, 30])
    ap.add_argument("--set", choices=["cueable", "noncue", "both"], default="both",
                    help="planted: which set (all cueable, or 30%% noncueable)")
    a = ap.parse_args()
    {"targets": targets, "ablation": ablation, "planted": planted_set, "speed": speed}[a.what](a)
    sys.stdout.flush()


if __name__ == "__main__":
    main()
