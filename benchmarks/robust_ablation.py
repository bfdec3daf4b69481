"""Ablation of robust mode (issue 13, part 5): plain vs robust vs each robust ingredient on its own.

    python benchmarks/robust_ablation.py [--problem over5] [--seeds 1,2,3] [--trials 400000]
                                         [--patience 100000] [--configs plain,robust,...] [--json OUT]

For each configuration and seed: one ``nbst.search.solve`` run, then the solution's exact cost
and order, its amplification (largest singular value of d final / d v, ``nbst.sim.jacobian``; in
seconds: units of final position per units/s of cue velocity), its robust score (64 fresh start
shifts, ``nbst.search.robust.robust_score``: order kept in all, 90 % quantile of the largest
distance among the disks on target) and the MuJoCo fixed-step outcome at h = 0.25 ms (``nbst.models.validate.validate``:
max final error, signature kept, MuJoCo's order). Prints one Markdown row per run and a summary
per configuration. A benchmark, not a test: ~5-30 s per run on the 2-core machine.

Configurations (``SearchParams`` fields over variant "nbst"):

* plain            : nbst's search, the cheapest solution
* robust           : --robust (search scored under 8 start shifts, archive, fresh rescoring, polish)
* choice-only      : robust_k = 0 (plain search; archive re-ranked under shifts, polished)
* search-only      : robust_archive = 0, robust_polish = 0 (shift-scored search; its best written)
* no-polish        : robust without the final polish
* worst-cost-only  : robust_signature = "plain": the search's cost is the worst over the shifts,
                     its signature the unshifted one (the AND of the signatures is off)
* h=0.1ms / h=0.5ms: robust, shifts sized for another step
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import time

import numpy as np

CONFIGS = {
    "plain": {},
    "robust": {"robust": True},
    "choice-only": {"robust": True, "robust_k": 0},
    "search-only": {"robust": True, "robust_archive": 0, "robust_polish": 0},
    "no-polish": {"robust": True, "robust_polish": 0},
    "worst-cost-only": {"robust": True, "robust_signature": "plain"},
    "h=0.1ms": {"robust": True, "robust_timestep": 0.0001},
    "h=0.5ms": {"robust": True, "robust_timestep": 0.0005},
}


def shifted_error(problem, velocities, *, seed: int, samples: int = 64) -> np.ndarray:
    """(N,) median over ``samples`` start shifts (robust mode's error model) of each disk's final
    displacement from the unshifted run, units: what the model predicts for MuJoCo's final error."""
    from nbst.constants import MAX_EVENTS
    from nbst.search.robust import SHIFT_STEPS, TIMESTEP, draws
    from nbst.sim import evaluate_kernel

    v = np.ascontiguousarray(velocities, dtype=np.float64)
    zeta, smax = draws(problem, np.random.default_rng(seed), samples)
    sigma = SHIFT_STEPS * TIMESTEP * np.hypot(*v[problem.cueable].T).max()
    arrays = [np.ascontiguousarray(a, dtype=np.float64) for a in (problem.radius, problem.mass, problem.target)]
    out = []
    for k in range(samples + 1):
        x0 = problem.start + (min(sigma, smax[k - 1]) * zeta[k - 1] if k else 0.0)
        fin, c, sg, ne = np.empty((1, problem.n, 2)), np.empty(1), np.empty(1, np.int64), np.empty(1, np.int64)
        evaluate_kernel(np.ascontiguousarray(x0, dtype=np.float64), v[None], *arrays, float(problem.box[0]),
                        float(problem.box[1]), float(problem.t_final), float(problem.target_radius), MAX_EVENTS,
                        fin, c, sg, ne)
        out.append(fin[0])
    out = np.array(out)
    return np.median(np.hypot(*(out[1:] - out[0]).transpose(2, 0, 1)), axis=0)


def measure(problem, velocities, *, score_seed: int) -> dict:
    from nbst.sim.jacobian import final_jacobian
    from nbst.models.validate import validate
    from nbst.search.robust import robust_score
    from nbst.sim import simulate

    tr = simulate(problem, velocities)
    _, J = final_jacobian(problem, velocities)
    val = validate(problem, velocities)
    rs = robust_score(problem, velocities, seed=score_seed)
    return {"cost": float(tr.cost), "order": int(tr.order), "signature": tr.signature_string,
            "collisions": int(tr.n_disk_disk), "amplification": float(np.linalg.svd(J, compute_uv=False)[0]),
            "robust_order": rs["order"], "robust_kept": rs["kept"], "robust_worst": rs["worst_distance"],
            "mj_max_error": float(val.final_error.max()), "mj_same_signature": bool(val.signatures_agree),
            "mj_order": bin(val.mj_signature).count("1"), "mj_error_per_disk": val.final_error.tolist(),
            "shift_error_per_disk": shifted_error(problem, velocities, seed=score_seed).tolist()}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(allow_abbrev=False, description=__doc__.splitlines()[0])
    ap.add_argument("--problem", default="over5")
    ap.add_argument("--seeds", default="1,2,3")
    ap.add_argument("--trials", type=int, default=400_000)
    ap.add_argument("--patience", type=int, default=100_000, help="nbst solve's default; 0: the whole budget")
    ap.add_argument("--configs", default=",".join(CONFIGS))
    ap.add_argument("--json", default=None, help="also write every row to this file")
    a = ap.parse_args(argv)

    from nbst import load_problem
    from nbst.search import solve, variant_params

    p = load_problem(a.problem)
    seeds = [int(s) for s in a.seeds.split(",")]
    rows = []
    print(f"{a.problem}, {a.trials} trials, patience {a.patience}, seeds {a.seeds}; MuJoCo h = 0.25 ms\n")
    print("| config | seed | cost | order | collisions | amplification (s) | robust order / kept / worst | "
          "MuJoCo max error | MuJoCo signature | search s |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for name in a.configs.split(","):
        params = dataclasses.replace(variant_params("nbst"), **CONFIGS[name])
        for seed in seeds:
            t0 = time.perf_counter()
            sol = solve(p, seed=seed, max_trials=a.trials, patience=a.patience, params=params)
            wall = time.perf_counter() - t0
            m = measure(p, sol.velocities, score_seed=1000 + seed)
            row = {"config": name, "seed": seed, "wall": wall, **m}
            rows.append(row)
            print(f"| {name} | {seed} | {m['cost']:.4g} | {m['order']} | {m['collisions']} | "
                  f"{m['amplification']:.3g} | {m['robust_order']} / {m['robust_kept']:.2f} / "
                  f"{m['robust_worst']:.4g} | "
                  f"{m['mj_max_error']:.3g} | {'same' if m['mj_same_signature'] else 'DIFFERENT'} "
                  f"(order {m['mj_order']}) | {wall:.1f} |", flush=True)
    print("\n| config | order N | MuJoCo same signature | order N and same signature | median cost | "
          "median MuJoCo max error |")
    print("|---|---|---|---|---|---|")
    for name in a.configs.split(","):
        r = [x for x in rows if x["config"] == name]
        print(f"| {name} | {sum(x['order'] == p.n for x in r)}/{len(r)} | "
              f"{sum(x['mj_same_signature'] for x in r)}/{len(r)} | "
              f"{sum(x['order'] == p.n and x['mj_same_signature'] for x in r)}/{len(r)} | "
              f"{np.median([x['cost'] for x in r]):.4g} | {np.median([x['mj_max_error'] for x in r]):.3g} |")
    print("\nError model vs MuJoCo, per disk (units): MuJoCo's final error / median final displacement "
          "under 64 start shifts")
    print("\n| config | seed | " + " | ".join(f"disk {i}" for i in range(p.n)) + " |")
    print("|---|---|" + "---|" * p.n)
    for x in rows:
        print(f"| {x['config']} | {x['seed']} | " + " | ".join(
            f"{e:.3g} / {m:.3g}" for e, m in zip(x["mj_error_per_disk"], x["shift_error_per_disk"])) + " |")
    if a.json:
        with open(a.json, "w") as f:
            json.dump(rows, f, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
