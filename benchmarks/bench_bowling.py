"""Rollout throughput of the bowling scene (nbst.models.bowling), and the choice it rests on.

    python benchmarks/bench_bowling.py [--n 48] [--seed 0]

Prints launches/s (2.5 s shots, 1 ms steps) for the same N uniform throws:

* nbst's runner (``deck.DeliveryRunner``): sleeping on, MjData reset before every launch,
  one ``mujoco.rollout`` call per launch on each of K threads, final state only;
* one ``mujoco.rollout`` call per batch over K reused MjData (no reset), sleeping on:
  speed, and how many launches end bitwise different from the reset-per-launch runner;
* sleeping off, one ``mujoco.rollout`` call per batch (no hidden state to carry).

Launches are independent, so the figures are for 1 and 2 threads (``--threads``).

    python benchmarks/bench_bowling.py --outcomes 1000 [--jobs 2]

instead runs N uniform throws and prints how often each kind of outcome comes up: the
number of distinct subsets, by size, and the share of the named targets of docs/bowling.md
(what a plain random search would need: ~1/share launches).

    python benchmarks/bench_bowling.py --atlas-ablation 3000 [--seed 1] [--jobs 1] [--methods uniform,elites,targeted]

instead grows an empty atlas archive with each method (``models/bowling/atlas.py``: uniform
throws, the MAP-Elites emitter, the earlier uniform-then-targeted-solves atlas) for the same N
launches and seed, and prints the distinct subsets found (at each quarter of the budget, and
by size at the end).
"""
from __future__ import annotations

import argparse
import math
import os
import sys
import time
from pathlib import Path

import numpy as np
from nbst.models.bowling import deck, pinfall

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(allow_abbrev=False, description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=48, help="launches per measurement (default 48)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--threads", default="1,2", help="thread counts (default 1,2)")
    ap.add_argument("--outcomes", type=int, default=0, metavar="N",
                    help="instead: the outcome frequencies of N uniform throws")
    ap.add_argument("--jobs", type=int, default=None, help="threads for --outcomes (default: all cores)")
    ap.add_argument("--atlas-ablation", type=int, default=0, metavar="N",
                    help="instead: distinct subsets that N launches find with each atlas method")
    ap.add_argument("--methods", default="uniform,elites,targeted",
                    help="atlas methods to ablate (uniform, elites, elites-plain, targeted)")
    args = ap.parse_args(argv)
    if args.atlas_ablation:
        return atlas_ablation(args.atlas_ablation, seed=args.seed, jobs=args.jobs or 1,
                              methods=args.methods.split(","))
    if args.outcomes:
        return outcomes(args.outcomes, seed=args.seed, jobs=args.jobs)

    import mujoco
    from mujoco import rollout

    from nbst.models.bowling import scene
    from nbst.models.bowling.deck import search

    model = scene.build_model()
    X = search.from_unit(np.random.default_rng(args.seed).random((args.n, 4)))
    threads = [int(t) for t in args.threads.split(",")]
    print(f"bowling rollouts: {args.n} uniform throws (seed {args.seed}), {deck.DURATION} s each at "
          f"h = {model.opt.timestep} s; mujoco {mujoco.__version__}; {os.cpu_count()} cores")

    ref = None
    for k in threads:
        with deck.DeliveryRunner(model, jobs=k) as L:
            st = np.array([L.initial_state(*deck.initial_qpos_qvel(model, x)) for x in X])
            t = time.perf_counter()
            f = L.run_states(st)
            dt = time.perf_counter() - t
        ref = f if ref is None else ref
        same = np.array_equal(f, ref)
        masks = pinfall.mask_of(pinfall.pins_down(model, f[:, 1:1 + model.nq]))
        print(f"  Launcher (sleep, reset per launch), {k} thread(s): {args.n / dt:6.2f} launches/s "
              f"({dt / args.n * 1e3:.0f} ms each); equal to the first run: {same}; "
              f"strikes {int((masks == 1023).sum())}, no pin {int((masks == 0).sum())}")

    def batch(m, k):
        datas = [mujoco.MjData(m) for _ in range(max(1, k))]
        nstep = deck.n_steps(m)
        out = np.empty((len(st), m.nq))
        t = time.perf_counter()
        chunk = 4 * max(1, k)  # chunked: the state of every step is kept, ~2.9 MB per launch
        with rollout.Rollout(nthread=k if k > 1 else 0) as r:
            for i in range(0, len(st), chunk):
                s, _ = r.rollout(m, datas if k > 1 else datas[0], st[i:i + chunk], nstep=nstep)
                out[i:i + chunk] = s[:, -1, 1:1 + m.nq]
        return out, time.perf_counter() - t

    for k in threads:
        q, dt = batch(model, k)
        differ = int((~np.all(q == ref[:, 1:1 + model.nq], axis=1)).sum())
        print(f"  rollout over reused MjData (sleep, no reset), {k} thread(s): {args.n / dt:6.2f} launches/s; "
              f"bitwise different from reset-per-launch: {differ}/{args.n}")
    awake = scene.build_model()
    awake.opt.enableflags &= ~int(mujoco.mjtEnableBit.mjENBL_SLEEP)
    for k in threads:
        q, dt = batch(awake, k)
        print(f"  rollout, sleeping off, {k} thread(s): {args.n / dt:6.2f} launches/s")
    return 0


#: Targets named in docs/bowling.md: pins down.
TARGETS = {"strike": range(1, 11), "7 alone": [7], "10 alone": [10],
           "7-10 split (1-6, 8, 9 down)": [1, 2, 3, 4, 5, 6, 8, 9], "big four 4-6-7-10 standing": [1, 2, 3, 5, 8, 9],
           "1-2-4-7": [1, 2, 4, 7],
           "2-4-7": [2, 4, 7], "3-6-10": [3, 6, 10], "1-3-6-10": [1, 3, 6, 10], "1-2-3": [1, 2, 3]}


def outcomes(n: int, *, seed: int, jobs) -> int:
    from collections import Counter

    from nbst.models.bowling.deck import search

    X = search.from_unit(np.random.default_rng(seed).random((n, 4)))
    t = time.perf_counter()
    with deck.DeliveryRunner(jobs=jobs) as L:
        masks = np.concatenate([L.throw(X[i:i + 64])[0] for i in range(0, n, 64)])
    dt = time.perf_counter() - t
    c = Counter(int(m) for m in masks)
    print(f"{n} uniform throws (seed {seed}) in {dt:.0f} s ({n / dt:.1f}/s, {L.jobs} threads): "
          f"{len([m for m in c if m])} distinct non-empty subsets; no pin {c[0] / n:.1%}, strike {c[1023] / n:.1%}")
    sizes = Counter(bin(m).count("1") for m in c if m)
    print("  found / possible by subset size: " + ", ".join(
        f"{k}: {sizes[k]}/{math.comb(10, k)}" for k in range(1, 11)))
    for name, pins in TARGETS.items():
        m = pinfall.mask_from_pins(pins)
        print(f"  {name}: {c[m]} of {n} ({c[m] / n:.2%})")
    return 0


def atlas_ablation(n: int, *, seed: int, jobs: int, methods) -> int:
    from nbst.models.bowling.deck import atlas

    print(f"atlas ablation: {n} launches per method from an empty archive, seed {seed}, {jobs} thread(s)")
    quarters = [n // 4, n // 2, 3 * n // 4, n]
    with deck.DeliveryRunner(jobs=jobs) as L:
        for method in methods:
            t = time.perf_counter()
            a = atlas.run(L, atlas.SubsetArchive(), method=method, budget=n, seed=seed)
            dt = time.perf_counter() - t
            at = [max((s for r, s in a.curve if r <= q), default=0) for q in quarters]
            sizes = ", ".join(f"{k}: {g}" for k, g, _ in atlas.size_table(a.elite))
            print(f"  {method:9s}: {len(a):4d} subsets in {a.rollouts} launches ({dt:.0f} s, {a.rollouts / dt:.1f}/s); "
                  f"after {'/'.join(map(str, quarters))}: {'/'.join(map(str, at))}; by size {sizes}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
