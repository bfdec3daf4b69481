"""Backward planner (issue 15): over5 and planted noncueable sets, nbst against nbst without the
planner and the paper's A at equal trials.

    python benchmarks/planner_results.py [--trials 1000000] [--workers 2] [--sizes 6,10,14,20] [--seeds 1,2,3,4,5]
    python benchmarks/planner_results.py --only over5        # or --only planted

Planted instances are ``nbst generate --planted N --noncue K --seed S`` (K = round(N / 4), radius 15);
each run uses search seed 1 and stops at cost < 1e-6. Every planted motion is also classified:
*plannable* when every struck noncueable disk is set moving once, from rest, by a striker that
comes straight from its start (or down a chain of such strikes) and neither is touched again --
the structures the planner builds; otherwise the first reason it is not. A benchmark, not a test.
"""
from __future__ import annotations

import argparse
import statistics
import sys
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np

EXACT = 1e-6


def _run(job):
    name, n, k, pseed, entry, trials, sseed = job
    from nbst import load_problem
    from nbst.planted import planted
    from nbst.search import solve

    p = load_problem("over5") if name == "over5" else planted(n, noncue=k, seed=pseed)[0]
    t0 = time.perf_counter()
    m = solve(p, seed=sseed, max_trials=trials, patience=0, target_cost=EXACT, variant=entry).meta
    return {"problem": name, "entry": entry, "seed": sseed, "cost": m["cost"], "order": m["order"], "n": p.n,
            "trials": m["trials"], "wall": time.perf_counter() - t0,
            "planner": (m.get("planner") or {}).get("best_cost"),
            "planner_trials": (m.get("planner") or {}).get("trials")}


def classify(n: int, k: int, seed: int) -> str:
    """Why the planted motion of planted(n, noncue=k, seed) is (not) a structure the planner builds."""
    from nbst.planted import planted
    from nbst.constants import EVENT_DISK
    from nbst.sim import simulate

    p, v = planted(n, noncue=k, seed=seed)
    tr = simulate(p, v)
    ev = [(float(e["time"]), int(e["i"]), int(e["j"])) for e in tr.events if e["kind"] == EVENT_DISK]
    cue = set(np.flatnonzero(p.cueable).tolist())
    struck = [j for j in np.flatnonzero(~p.cueable) if np.any(tr.final_positions[j] != p.start[j])]
    if not struck:
        return "no noncueable disk struck (trivial)"
    first = {}
    for t, a_, b_ in ev:
        for d in (a_, b_):
            first.setdefault(d, t)

    def events_of(d):
        return [(t, b_ if a_ == d else a_) for t, a_, b_ in ev if d in (a_, b_)]

    reasons = []
    for j in struck:
        mine = events_of(j)
        t1, s = mine[0]
        s_ev = events_of(s)
        before = [e for e in s_ev if e[0] < t1]
        after_s = [e for e in s_ev if e[0] > t1]
        # a chain link: j's only later event strikes a resting noncueable disk
        link = len(mine) == 2 and mine[1][1] not in cue and first[mine[1][1]] == mine[1][0]
        depth, x = 1, s
        while x not in cue and events_of(x):
            depth += 1
            x = events_of(x)[0][1]
        if s in cue and before or s not in cue and len(before) != 1:
            reasons.append(f"disk {j}'s striker {s} was deflected before the strike")
        elif len(mine) > 1 and not link:
            reasons.append(f"disk {j} is hit again")
        elif s in cue and after_s:
            reasons.append(f"disk {j}'s striker {s} is deflected afterwards")
        elif depth > 3:
            reasons.append(f"disk {j} ends a chain of {depth} strikes (longer than 3)")
    return "plannable" if not reasons else reasons[0] + (f" (+{len(reasons) - 1} more)" if len(reasons) > 1 else "")


def _median(xs):
    return statistics.median(xs) if xs else float("nan")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(allow_abbrev=False, description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=1_000_000)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--sizes", default="6,10,14,20")
    ap.add_argument("--seeds", default="1,2,3,4,5", help="planted instance seeds (nbst generate --seed)")
    ap.add_argument("--entries", default="nbst,nbst-noplan,A")
    ap.add_argument("--only", choices=("over5", "planted"), default=None)
    a = ap.parse_args(argv)
    entries = a.entries.split(",")
    jobs = []
    if a.only != "planted":
        jobs += [("over5", 5, 3, 0, e, a.trials, s) for e in entries for s in (1, 2, 3)]
    inst = []
    if a.only != "over5":
        for n in map(int, a.sizes.split(",")):
            k = max(1, round(n / 4))
            for ps in map(int, a.seeds.split(",")):
                inst.append((f"p{n}k{k}-s{ps}", n, k, ps))
                jobs += [(f"p{n}k{k}-s{ps}", n, k, ps, e, a.trials, 1) for e in entries]
    t0 = time.perf_counter()
    with ProcessPoolExecutor(max_workers=a.workers) as ex:
        res = list(ex.map(_run, jobs))
    print(f"# {len(jobs)} runs, {a.trials:,} trials each (stop at cost < {EXACT:g}), "
          f"{time.perf_counter() - t0:.0f} s wall, {a.workers} workers", file=sys.stderr)
    by = {(r["problem"], r["entry"], r["seed"]): r for r in res}

    if a.only != "planted":
        print("\n### over5 (seeds 1-3)\n")
        print("| entry | seed 1 | seed 2 | seed 3 | exact (< 1e-6) | median | planner's best seed |")
        print("|---|---:|---:|---:|---:|---:|---:|")
        for e in entries:
            rs = [by[("over5", e, s)] for s in (1, 2, 3)]
            pl = rs[0]["planner"]
            print(f"| {e} | " + " | ".join(f"{r['cost']:.6g} (order {r['order']})" for r in rs)
                  + f" | {sum(r['cost'] < EXACT for r in rs)}/3 | {_median([r['cost'] for r in rs]):.6g} | "
                  + (f"{pl:.6g}" if pl is not None else "-") + " |")

    if a.only != "over5":
        print("\n### Planted noncueable sets (K = round(N/4); search seed 1)\n")
        head = " | ".join(f"{e}: cost / trials" for e in entries)
        print(f"| instance | planted motion | {head} | nbst / A | planner's best seed |")
        print("|---|---|" + "---:|" * len(entries) + "---:|---:|")
        exact = {e: 0 for e in entries}
        ratios = []
        for name, n, k, ps in inst:
            rs = {e: by[(name, e, 1)] for e in entries}
            for e in entries:
                exact[e] += rs[e]["cost"] < EXACT
            ratio = None
            if "nbst" in rs and "A" in rs:
                a_c = max(rs["A"]["cost"], 1e-30)
                ratio = rs["nbst"]["cost"] / a_c
                ratios.append(ratio)
            pl = rs[entries[0]]["planner"]
            print(f"| {name} | {classify(n, k, ps)} | "
                  + " | ".join(f"{rs[e]['cost']:.3g} / {rs[e]['trials']:,}" for e in entries)
                  + f" | {ratio:.3g} |" + (f" {pl:.3g} |" if pl is not None else " - |"))
        print()
        for e in entries:
            cs = [by[(name, e, 1)]["cost"] for name, *_ in inst]
            print(f"- {e}: exact {exact[e]}/{len(inst)}, median best cost {_median(cs):.4g}")
        if ratios:
            print(f"- nbst / A cost ratio: median {_median(ratios):.3g}; at most 1/10 in "
                  f"{sum(r <= 0.1 for r in ratios)}/{len(ratios)} instances")
    return 0


if __name__ == "__main__":
    sys.exit(main())
