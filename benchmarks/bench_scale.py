"""How nbst's cost grows with the number of disks (issue: many bodies).

    python benchmarks/bench_scale.py            # everything (~15 min on 2 cores)
    python benchmarks/bench_scale.py --quick    # smaller sizes, 1 seed (~2 min)
    python benchmarks/bench_scale.py --part sim --sizes 100 10000

Parts:
* ``sim``: the exact simulator at fixed density (the planted generator's: 60 disks of radius 15
  in 800 x 800, speeds of that box) from 10 to 10,000 disks: physical events per second of the
  cell-grid kernel (``nbst.sim.cells``) and of the O(N^2) table (``nbst.sim.kernel``, measured
  in the same run up to 3,000 disks), their agreement (event lists compared bit for bit), and
  the peak memory of a whole ``nbst.sim.simulate`` in a fresh process;
* ``solve``: time to exact (every disk within 1e-6 of its target) for planted all-cueable
  problems against N, 3 seeds each, with ``nbst.search.solve`` defaults and a target cost of
  1e-12 (so every disk ends within 1e-6), each run stopped after ``--budget`` seconds;
* ``noncue``: planted N = 100 with 10 noncueable disks: the disks within R per seed (the bar:
  all of them on half the seeds), against the search with exactness counted first.

Rates are best-of-3 wall times on a shared machine; ratios are against N = 100 of the same run.
``--figure`` writes the log-log figure docs/figures/scale.png; ``--markdown`` prints the tables
for docs/results/disks.md.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from nbst.planted import DEFAULT_SIDE, DENSITY_DISKS  # noqa: E402
from nbst.sim.cells import alloc_cells, run_cells  # noqa: E402
from nbst.sim.kernel import alloc_work, run  # noqa: E402

RADIUS = 15.0
T_FINAL = 5.0
TABLE_UP_TO = 3000


def gas(n: int, seed: int = 1):
    """n disks of radius 15 at the planted generator's density, on a jittered grid, with speeds
    of the planted generator's scale (0.05-0.35 of the 800 x 800 diagonal per t_final)."""
    rng = np.random.default_rng(seed)
    side = DEFAULT_SIDE * math.sqrt(n / DENSITY_DISKS)
    m = int(math.ceil(math.sqrt(n)))
    g = side / m
    idx = rng.permutation(m * m)[:n]
    x0 = np.stack([(idx % m + 0.5) * g, (idx // m + 0.5) * g], 1)
    x0 += rng.uniform(-1, 1, (n, 2)) * max(g / 2 - RADIUS - 1.0, 0.0)
    ang = rng.uniform(0, 2 * np.pi, n)
    speed = rng.uniform(0.05, 0.35, n) * DEFAULT_SIDE * math.sqrt(2) / T_FINAL
    v = np.stack([np.cos(ang), np.sin(ang)], 1) * speed[:, None]
    return np.ascontiguousarray(x0), np.ascontiguousarray(v), np.full(n, RADIUS), np.ones(n), side


def _timed(kernel, work, x0, v, rad, mass, side, rec: bool, reps: int = 3):
    n = x0.shape[0]
    cap = 4_000_000 if rec else 0
    fin, vel = np.empty((n, 2)), np.empty((n, 2))
    et, ei, ej, es = np.empty(cap), np.empty(cap, np.int64), np.empty(cap, np.int64), np.empty((cap, 8))
    best = math.inf
    for _ in range(reps):
        t = time.perf_counter()
        st = kernel(x0, v, rad, mass, side, side, T_FINAL, work, fin, vel, 10 ** 8, et, ei, ej, es)
        best = min(best, time.perf_counter() - t)
    ne = st[1]
    return best, st, (fin.copy(), et[:ne].copy(), ei[:ne].copy(), ej[:ne].copy())


def peak_memory_mb(n: int) -> tuple[float, float]:
    """(peak RSS in MB of a fresh process that builds the n-disk problem and runs ``simulate``,
    the same process's peak when it stops just before ``simulate``)."""
    code = f"""
import resource, sys, numpy as np
sys.path.insert(0, {str(ROOT)!r})
sys.path.insert(0, {str(ROOT / 'benchmarks')!r})
from bench_scale import gas
from nbst.problem import problem_from_dict
from nbst.sim import simulate
x0, v, rad, mass, side = gas({n})
d = {{"name": "gas", "box": [side, side], "t_final": {T_FINAL}, "target_radius": 75.0,
     "disks": [{{"start": x0[i].tolist(), "target": x0[i].tolist(), "radius": {RADIUS}}} for i in range({n})]}}
p = problem_from_dict(d)
before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
if sys.argv[1] == "run":
    tr = simulate(p, v)
    tr.at([0.0, 2.5, {T_FINAL}])
print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, before / 1024)
"""
    out = {}
    for mode in ("run", "base"):
        r = subprocess.run([sys.executable, "-c", code, mode], capture_output=True, text=True, check=True)
        out[mode] = float(r.stdout.split()[0])
    return out["run"], out["base"]


def part_sim(sizes):
    rows = []
    for n in sizes:
        x0, v, rad, mass, side = gas(n)
        tc, st, rec_c = _timed(run_cells, alloc_cells(n), x0, v, rad, mass, side, False)
        _, _, rec_c = _timed(run_cells, alloc_cells(n), x0, v, rad, mass, side, True, reps=1)
        row = {"n": n, "events": int(st[1]), "collisions": int(st[2]), "cells_s": tc,
               "cells_rate": st[1] / tc}
        if n <= TABLE_UP_TO:
            tt, st2, _ = _timed(run, alloc_work(n), x0, v, rad, mass, side, False)
            _, _, rec_t = _timed(run, alloc_work(n), x0, v, rad, mass, side, True, reps=1)
            row.update(table_s=tt, table_rate=st2[1] / tt,
                       identical=all(np.array_equal(a, b) for a, b in zip(rec_c, rec_t)))
        row["peak_mb"], row["base_mb"] = peak_memory_mb(n)
        rows.append(row)
        print(f"  sim N={n:>6}: {row['events']:>7} events ({row['collisions']} disk-disk); cells "
              f"{row['cells_rate']:>11,.0f} ev/s" + (f", table {row['table_rate']:>11,.0f} ev/s, same events: "
                                                     f"{row['identical']}" if "table_rate" in row else "")
              + f"; simulate peak {row['peak_mb']:.0f} MB (process without it {row['base_mb']:.0f} MB)", flush=True)
    return rows


def part_solve(sizes, seeds, budget_s):
    from nbst.planted import planted
    from nbst.search import solve
    from nbst.sim import simulate

    rows = []
    for n in sizes:
        for seed in seeds:
            p, _ = planted(n, seed=seed)
            deadline = time.perf_counter() + budget_s

            def stop(_prog, deadline=deadline):
                return time.perf_counter() > deadline

            t = time.perf_counter()
            sol = solve(p, seed=seed, target_cost=1e-12, callback=stop)
            wall = time.perf_counter() - t
            err = np.hypot(*(simulate(p, sol.velocities).final_positions - p.target).T)
            rows.append({"n": n, "seed": seed, "wall_s": wall, "exact": bool(err.max() <= 1e-6),
                         "order": int(sol.meta["order"]), "max_err": float(err.max())})
            r = rows[-1]
            print(f"  solve N={n:>5} seed {seed}: {'exact' if r['exact'] else 'not exact'} in {wall:.1f} s, "
                  f"order {r['order']}/{n}, worst miss {r['max_err']:.3g}", flush=True)
    return rows


def part_noncue(seeds, budget_s):
    """Planted N = 100 with 10 noncueable disks: disks within R with nbst's default search (the
    order counted first, since resting disks must be struck) and with exactness counted first
    (the ablation, ``ManyParams(order_first=False)``), per seed."""
    from nbst.planted import planted
    from nbst.search import run_search
    from nbst.search.many import ManyParams

    rows = []
    for seed in seeds:
        p, _ = planted(100, noncue=10, seed=seed)
        row = {"seed": seed}
        for key, prm in (("order", None), ("order_exact_first", ManyParams(order_first=False))):
            deadline = time.perf_counter() + budget_s
            t = time.perf_counter()
            sol = run_search(p, seed=seed, many=prm, callback=lambda _p, d=deadline: time.perf_counter() > d).result
            row[key], row[key + "_wall_s"] = int(sol.meta["order"]), time.perf_counter() - t
        rows.append(row)
        print(f"  noncue N=100 (10 noncueable) seed {seed}: order {row['order']}/100 in {row['order_wall_s']:.0f} s; "
              f"exactness first: {row['order_exact_first']}/100 in {row['order_exact_first_wall_s']:.0f} s", flush=True)
    return rows


def work_memory_mb(n: int) -> tuple[float, float]:
    """(the cell-grid kernel's scratch, the table kernel's scratch) for n disks, MB: the arrays
    a simulation of n disks allocates besides its event record (exact, from their sizes)."""
    cells = sum(a.nbytes for a in alloc_cells(n)) / 1e6
    table = (8.0 * n * n + 8 * 4 * n) / 1e6  # the N x N table of pair times dominates (alloc_work)
    return cells, table


def figure(sim, solve_rows, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    panels = 3 if solve_rows else 2
    fig, axs = plt.subplots(1, panels, figsize=(5.2 * panels, 4.4))
    a, b = axs[0], axs[1]
    n = [r["n"] for r in sim]
    nt = [r["n"] for r in sim if "table_rate" in r]
    a.loglog(n, [r["cells_rate"] for r in sim], "o-", color="#1b7837", label="cell grid + calendar (sim.cells)")
    a.loglog(nt, [r["table_rate"] for r in sim if "table_rate" in r], "s--", color="#762a83",
             label="N x N table, O(N) rescan (sim.kernel)")
    a.set_xlabel("disks N (fixed density and speeds)")
    a.set_ylabel("physical events per second")
    a.set_title("Simulator throughput")
    a.grid(True, which="both", alpha=0.3)
    a.legend(fontsize=8, loc="lower left")
    mem = [work_memory_mb(k) for k in n]
    b.loglog(n, [m[0] for m in mem], "o-", color="#1b7837", label="cell kernel's scratch")
    b.loglog(n, [m[1] for m in mem], "s--", color="#762a83", label="table kernel's scratch (N x N)")
    b.loglog(n, [r["peak_mb"] for r in sim], "^:", color="#555555", label="whole process running simulate (peak RSS)")
    b.axhline(1024, color="#b2182b", lw=0.8)
    b.text(n[-1], 1300, "1 GiB", color="#b2182b", fontsize=8, ha="right")
    b.set_xlabel("disks N")
    b.set_ylabel("MB")
    b.set_title("Memory")
    b.grid(True, which="both", alpha=0.3)
    b.legend(fontsize=8, loc="lower right")
    if solve_rows:
        c = axs[2]
        sizes = sorted({r["n"] for r in solve_rows})
        for k in sizes:
            rows = [r for r in solve_rows if r["n"] == k]
            for r in rows:
                c.semilogx(k, 100.0 * r["order"] / k, "o" if r["exact"] else "x",
                           color="#1b7837" if r["exact"] else "#b2182b", ms=8)
        c.plot([], [], "o", color="#1b7837", label="exact (every disk within 1e-6)")
        c.plot([], [], "x", color="#b2182b", label="not exact (the search stopped, or its time budget)")
        c.set_ylim(80, 101)
        c.set_xlabel("disks N (planted, all cueable; 3 seeds)")
        c.set_ylabel("% of disks within R at the end")
        c.set_title("The search: what it reaches")
        c.grid(True, which="both", alpha=0.3)
        c.legend(fontsize=8, loc="lower left")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print(f"wrote {path}")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(allow_abbrev=False, description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="smaller sizes and one seed")
    ap.add_argument("--part", choices=("sim", "solve", "noncue", "all"), default="all")
    ap.add_argument("--sizes", type=int, nargs="*", default=None)
    ap.add_argument("--seeds", type=int, nargs="*", default=None)
    ap.add_argument("--budget", type=float, default=600.0, help="seconds per solve (default 600)")
    ap.add_argument("--figure", default=None, help="write the log-log figure here")
    ap.add_argument("--json", default=None, help="write the rows here")
    ap.add_argument("--from-json", nargs="*", default=None, help="draw the figure from rows written before")
    a = ap.parse_args(argv)
    out = {}
    if a.from_json:
        for f in a.from_json:
            for k, v in json.loads(Path(f).read_text()).items():
                out.setdefault(k, []).extend(v)
        figure(out["sim"], out.get("solve", []), a.figure)
        return 0
    print(f"bench_scale: {os.cpu_count()} cores, numpy {np.__version__}", flush=True)
    if a.part in ("sim", "all"):
        sizes = a.sizes or ([10, 100, 1000, 3000] if a.quick else [10, 30, 100, 300, 1000, 3000, 10000])
        out["sim"] = part_sim(sizes)
        ref = next((r for r in out["sim"] if r["n"] == 100), None)
        if ref:
            for r in out["sim"]:
                print(f"  N={r['n']:>6}: cells rate / N=100 cells rate {r['cells_rate'] / ref['cells_rate']:.2f}; "
                      f"/ N=100 table rate {r['cells_rate'] / ref['table_rate']:.2f}")
    if a.part in ("solve", "all"):
        sizes = a.sizes if (a.sizes and a.part == "solve") else ([10, 60, 250] if a.quick else [10, 30, 60, 100, 250,
                                                                                                 1000])
        out["solve"] = part_solve(sizes, a.seeds or ([1] if a.quick else [1, 2, 3]), a.budget)
    if a.part in ("noncue", "all"):
        out["noncue"] = part_noncue(a.seeds or ([1] if a.quick else [1, 2, 3]), min(a.budget, 300.0))
    if a.json:
        Path(a.json).write_text(json.dumps(out, indent=1))
    if a.figure and "sim" in out:
        figure(out["sim"], out.get("solve", []), a.figure)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
