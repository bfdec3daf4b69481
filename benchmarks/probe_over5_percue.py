"""Probe: can one cue alone put its share of over5's disks on target? (issue 15)

    python benchmarks/probe_over5_percue.py [--samples 4000000] [--seed 0] [--combine]   # ~15 s; --combine ~45 s

If over5's planted zero split into two independent groups (each cue with the noncueable
disks it sets moving, no contact between the groups), then in the 2-D velocity space of one
cue, simulated with the three noncueable disks alone, some velocities would leave the cue
and every disk it moves near their targets. For each cue this draws ``--samples``
velocities (uniform direction, log-uniform speed 8-400 units/s), counts by the set of
noncueable disks moved how often the cue and all of them end within R, then polishes
(Levenberg-Marquardt, 100 simulations) the 20 best of each group with the cost restricted
to that group. It prints, per cue and group, the counts and the best polished group cost
(sum of squared misses). A group cost that cannot reach ~0 means that cue's share cannot be
exact on its own: the zero needs the two cues' motions to meet.

``--combine`` then pairs the groups of the two cues whose moved sets split the three
noncueable disks (40 samples per group with the smallest largest miss, raw and polished),
simulates every pair in full, and reports the order-5 motions: how many, the cheapest, and
the most robust of them (``nbst.search.robust.choose``, seed 1) with its score and its signature in
MuJoCo (fixed steps, h = 0.25 ms). This asks whether order 5 can be robust on over5
(issue 13's ``--robust`` target).
"""
from __future__ import annotations

import argparse
import time

import numpy as np

from nbst import load_problem
from nbst.search.polish import polish
from nbst.problem import problem_from_dict
from nbst.sim import evaluate


def subproblem(p, idx):
    """The disks ``idx`` of p alone (same box, time and R)."""
    return problem_from_dict({
        "name": "sub", "box": [float(b) for b in p.box], "t_final": float(p.t_final),
        "target_radius": float(p.target_radius),
        "disks": [{"start": p.start[i].tolist(), "target": p.target[i].tolist(), "radius": float(p.radius[i]),
                   "mass": float(p.mass[i]), "cueable": bool(p.cueable[i])} for i in idx]})


def group(mask: int, n_non: int) -> list[int]:
    """Rows of a subproblem (cue first, then the noncueable disks) in the group of ``mask``."""
    return [0] + [1 + j for j in range(n_non) if mask >> j & 1]


def batches(q, rng, samples):
    """Cue 0 of q at ``samples`` random velocities (uniform direction, log-uniform speed
    8-400 units/s), in batches: yields (V (B, n, 2), miss (B, n), keys (B,): the mask of
    the noncueable disks each sample moved)."""
    done = 0
    while done < samples:
        B = min(400_000, samples - done)
        done += B
        th = rng.uniform(0, 2 * np.pi, B)
        sp = np.exp(rng.uniform(np.log(8), np.log(400), B))
        V = np.zeros((B, q.n, 2))
        V[:, 0, 0] = sp * np.cos(th)
        V[:, 0, 1] = sp * np.sin(th)
        fin, _, _ = evaluate(q, V, jobs=1)
        miss = np.hypot(*(fin - q.target[None]).transpose(2, 0, 1))
        moved = np.hypot(*(fin - q.start[None]).transpose(2, 0, 1)) > 1e-9
        yield V, miss, (moved[:, 1:] * (1 << np.arange(q.n - 1))).sum(1)


def group_samples(p, q, c, want, rng, samples, keep=40):
    """The ``keep`` samples of cue c (in q = c + noncueable disks) that move exactly the
    noncueable set ``want`` with the smallest largest miss, raw and polished: (2 keep, 2)."""
    non = np.flatnonzero(~p.cueable)
    sel = group(want, non.size)
    best = []
    for V, miss, keys in batches(q, rng, samples):
        ii = np.flatnonzero(keys == want)
        g = miss[np.ix_(ii, sel)].max(1)
        best = sorted(best + [(float(a), V[b, 0].copy()) for a, b in zip(g, ii)], key=lambda x: x[0])[:keep]
    out = []
    for _, w in best:
        v = np.zeros((q.n, 2))
        v[0] = w
        out += [w, polish(q, v, max_sims=100)[0][0]]
    return np.array(out)


def combine(p, samples, rng) -> None:
    from nbst.models.validate import validate
    from nbst.search.robust import choose

    non = np.flatnonzero(~p.cueable)
    c0, c1 = np.flatnonzero(p.cueable)
    full = (1 << non.size) - 1
    order5 = []
    print("\n--combine: pairs of groups that split the noncueable disks")
    for a in range(1, full):
        b = full ^ a
        A = group_samples(p, subproblem(p, [c0, *non]), c0, a, rng, samples)
        B = group_samples(p, subproblem(p, [c1, *non]), c1, b, rng, samples)
        V = np.zeros((len(A) * len(B), p.n, 2))
        V[:, c0] = np.repeat(A, len(B), axis=0)
        V[:, c1] = np.tile(B, (len(A), 1))
        _, cost, sig = evaluate(p, V, jobs=1)
        o = np.array([bin(int(x)).count("1") for x in sig])
        names = lambda m: ",".join(str(non[j]) for j in range(non.size) if m >> j & 1)
        print(f"  cue {c0} moves {names(a):6s} cue {c1} moves {names(b):6s}: {len(V):5d} pairs, "
              f"order 5: {int((o == 5).sum()):3d}, cheapest {cost.min():9.1f}")
        order5.append(V[o == 5])
    V5 = np.concatenate(order5)
    if not len(V5):
        return
    _, cost, _ = evaluate(p, V5, jobs=1)
    v, info = choose(p, V5, seed=1)
    sc = info["score"]
    val = validate(p, v, timestep=0.00025, sensitivity=False)
    print(f"  {len(V5)} order-5 motions, cheapest {cost.min():.1f}; the most robust keeps its signature in "
          f"{sc['kept']:.3f} of the shifts (order {sc['order']} in all); MuJoCo h = 0.25 ms: "
          f"order {bin(val.mj_signature).count('1')}, largest final error {val.final_error.max():.1f} units")


def main() -> None:
    ap = argparse.ArgumentParser(allow_abbrev=False, description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=4_000_000)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--combine", action="store_true", help="also pair the two cues' groups (see above)")
    a = ap.parse_args()
    p = load_problem("over5")
    R = p.target_radius
    non = np.flatnonzero(~p.cueable)
    rng = np.random.default_rng(a.seed)
    t0 = time.perf_counter()
    for c in np.flatnonzero(p.cueable):
        q = subproblem(p, [c, *non])
        best = {}   # group mask -> list of (group cost, velocity)
        all_in = {}
        seen = {}
        for V, miss, keys in batches(q, rng, a.samples):
            for k in np.unique(keys[keys > 0]):
                ii = np.flatnonzero(keys == k)
                sel = group(k, non.size)
                g = (miss[np.ix_(ii, sel)] ** 2).sum(1)
                seen[k] = seen.get(k, 0) + ii.size
                all_in[k] = all_in.get(k, 0) + int(np.all(miss[np.ix_(ii, sel)] < R, axis=1).sum())
                top = ii[np.argsort(g)[:20]]
                best[k] = sorted(best.get(k, []) + [(float(gg), V[b]) for gg, b in zip(np.sort(g)[:20], top)],
                                 key=lambda x: x[0])[:20]
        print(f"cue {c} ({a.samples:,} samples, {time.perf_counter() - t0:.0f} s so far)")
        print(f"  {'disks moved':>12s} {'samples':>9s} {'all in R':>8s} {'best group cost':>16s} {'polished':>10s}")
        for k in sorted(best):
            sel = group(k, non.size)
            pol = []
            for _, v in best[k]:
                v2, _, _, _ = polish(q, v, max_sims=100)
                fin, _, _ = evaluate(q, v2[None], jobs=1)
                mv = np.hypot(*(fin[0] - q.start).T) > 1e-9
                if int((mv[1:] * (1 << np.arange(non.size))).sum()) == k:  # still the same group
                    pol.append(float(((fin[0] - q.target)[sel] ** 2).sum()))
            names = ",".join(str(non[j]) for j in range(non.size) if k >> j & 1)
            print(f"  {names:>12s} {seen[k]:9,d} {all_in[k]:8,d} {best[k][0][0]:16.1f} "
                  f"{(min(pol) if pol else float('nan')):10.1f}")
    if a.combine:
        combine(p, a.samples, rng)


if __name__ == "__main__":
    main()
