"""Probe: is over5's planted zero reachable by sampling collision sequences and polishing?

    python benchmarks/probe_over5.py [--seed 1] [--samples 2000000]   # ~1 min

Draws cue velocities aimed at a noncueable disk (impact offset uniform within 2r, speed
uniform in [20, 600]) or in a uniform direction, keeps the candidates that set all three
noncueable disks moving, groups them by their sequence of disk-disk collisions, and polishes
(Levenberg-Marquardt, analytic Jacobian) (a) the 3 lowest-cost members of every sequence
with 60 simulations each, (b) 10 random members of every four-collision sequence (the
planted motion has four) with 300 each. Prints the best polished costs and their sequences.
A benchmark run, not a test.
"""
from __future__ import annotations

import argparse
import collections
import time

import numpy as np

from nbst import load_problem
from nbst.search.polish import polish
from nbst.constants import EVENT_DISK
from nbst.sim import evaluate, simulate


def aimed(p, rng, B):
    V = np.zeros((B, p.n, 2))
    non = np.flatnonzero(~p.cueable)
    for i in np.flatnonzero(p.cueable):
        k = rng.integers(0, 2 * non.size, B)  # half aimed (at one of the noncueable disks), half uniform
        s = non[np.minimum(k, non.size - 1)]
        d = p.start[s] - p.start[i]
        dist = np.hypot(d[:, 0], d[:, 1])
        off = rng.uniform(-1, 1, B) * (p.radius[i] + p.radius[s]) / dist
        ang = np.where(k < non.size, np.arctan2(d[:, 1], d[:, 0]) + np.arcsin(np.clip(off, -1, 1)),
                       rng.uniform(-np.pi, np.pi, B))
        sp = rng.uniform(20, 600, B)
        V[:, i, 0] = sp * np.cos(ang)
        V[:, i, 1] = sp * np.sin(ang)
    return V


def main():
    ap = argparse.ArgumentParser(allow_abbrev=False, description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--samples", type=int, default=2_000_000)
    a = ap.parse_args()
    p = load_problem("over5")
    rng = np.random.default_rng(a.seed)
    non = ~p.cueable
    keep_v, keep_c = [], []
    t0 = time.perf_counter()
    for _ in range(max(1, a.samples // 200_000)):
        V = aimed(p, rng, 200_000)
        fin, cost = evaluate(p, V)[:2]
        moved = np.all(np.hypot(*(fin[:, non] - p.start[non]).transpose(2, 0, 1)) > 1e-9, axis=1)
        keep_v.append(V[moved])
        keep_c.append(cost[moved])
    V, C = np.concatenate(keep_v), np.concatenate(keep_c)
    groups = collections.defaultdict(list)
    for k in range(len(V)):
        e = simulate(p, V[k]).events
        e = e[e["kind"] == EVENT_DISK]
        groups[tuple(zip(e["i"].tolist(), e["j"].tolist()))].append(k)
    print(f"{a.samples:,} samples: {len(V):,} move all noncueable disks, {len(groups):,} distinct "
          f"collision sequences ({time.perf_counter() - t0:.0f} s)")
    print("sequences by number of collisions:", dict(sorted(collections.Counter(map(len, groups)).items())))

    def run(label, picks, sims):
        res, total = [], 0
        for key, ks in picks:
            for k in ks:
                _, c, _, n = polish(p, V[k], max_sims=sims)
                total += n
                res.append((c, key))
        res.sort(key=lambda x: x[0])
        print(f"\n{label}: {total:,} simulations; best polished costs:")
        for c, key in res[:5]:
            print(f"  {c:12.4f}  {key}")

    run("(a) 3 lowest-cost members of every sequence, 60 sims each",
        [(key, sorted(ks, key=lambda k: C[k])[:3]) for key, ks in groups.items()], 60)
    run("(b) 10 random members of every four-collision sequence, 300 sims each",
        [(key, rng.permutation(ks)[:10]) for key, ks in groups.items() if len(key) == 4], 300)


if __name__ == "__main__":
    main()
