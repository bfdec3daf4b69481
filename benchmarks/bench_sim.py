"""Simulator throughput (prints figures; not a test).

For each built-in problem: trials/s of ``nbst.evaluate`` on velocities drawn as the
paper's *uniform randomize* and *directed randomize*, events/s and events per
trial, and, in the same run, the same workload on a plain O(N^2)-rescan kernel
(benchmarks/rescan.py), with the ratio. One core (numba kernels are serial).

uniform randomize, as drawn here: the end point is uniform over the positions the
disk's centre can occupy ([r, W-r] x [r, H-r]); it is reached through a mirror
image (kx, ky) drawn uniformly from the 61 images with |kx| + |ky| <= 5 (so up to
five wall bounces); velocity = (image - start) / t_final.

    python benchmarks/bench_sim.py [--trials 20000] [--repeat 3]
"""
import argparse
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import nbst  # noqa: E402
from nbst.sim import evaluate_kernel  # noqa: E402
from rescan import evaluate_rescan  # noqa: E402
from nbst.constants import MAX_EVENTS  # noqa: E402

IMAGES = np.array([(kx, ky) for kx in range(-5, 6) for ky in range(-5, 6) if abs(kx) + abs(ky) <= 5])


def mirror(u, k, lo, hi):
    """Coordinate of image k of point u (in [lo, hi]) when the segment is unfolded."""
    L = hi - lo
    return lo + k * L + np.where(k % 2 == 0, u - lo, hi - u)


def uniform_randomize(p, rng, B):
    n = p.n
    r = p.radius
    W, H = p.box
    ex = rng.uniform(r, W - r, (B, n))
    ey = rng.uniform(r, H - r, (B, n))
    k = IMAGES[rng.integers(0, len(IMAGES), (B, n))]
    ix = mirror(ex, k[..., 0], r, W - r)
    iy = mirror(ey, k[..., 1], r, H - r)
    V = np.stack([ix - p.start[:, 0], iy - p.start[:, 1]], axis=-1) / p.t_final
    V[:, ~p.cueable] = 0.0
    return np.ascontiguousarray(V)


def directed_randomize(p, B):
    return np.ascontiguousarray(np.broadcast_to(p.straight_velocities(), (B, p.n, 2)))


def timed(kernel, p, V, repeat, *, ours):
    x0 = np.ascontiguousarray(p.start)
    args_tail = (np.ascontiguousarray(p.radius), np.ascontiguousarray(p.mass), np.ascontiguousarray(p.target),
                 float(p.box[0]), float(p.box[1]), float(p.t_final), float(p.target_radius))
    B = V.shape[0]
    final = np.empty((B, p.n, 2))
    cost = np.empty(B)
    sig = np.empty(B, np.int64)
    ne = np.empty(B, np.int64)
    def call(VV, f, c, s, e):
        if ours:
            kernel(x0, VV, *args_tail, MAX_EVENTS, f, c, s, e)
        else:
            kernel(x0, VV, *args_tail, f, c, s, e)
    call(V[:4], final[:4], cost[:4], sig[:4], ne[:4])  # compile / load cache
    best = np.inf
    for _ in range(repeat):
        t = time.perf_counter()
        call(V, final, cost, sig, ne)
        best = min(best, time.perf_counter() - t)
    return B / best, ne.sum() / best, ne.mean(), final


def startup_time():
    """Wall time of a second `nbst simulate` run (warm numba cache)."""
    import tempfile
    from nbst.solution import make_solution, save_solution
    p = nbst.load_problem("diamond-s14")
    with tempfile.TemporaryDirectory() as d:
        f = Path(d) / "s.json"
        save_solution(f, make_solution(p, p.straight_velocities()))
        cmd = [sys.executable, "-m", "nbst.cli", "simulate", "diamond-s14", str(f)]
        subprocess.run(cmd, capture_output=True, check=True)
        times = []
        for _ in range(3):
            t = time.perf_counter()
            subprocess.run(cmd, capture_output=True, check=True)
            times.append(time.perf_counter() - t)
    return min(times), float(np.median(times))


def main():
    ap = argparse.ArgumentParser(allow_abbrev=False, description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--trials", type=int, default=20000)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--seed", type=int, default=0)
    a = ap.parse_args()
    rng = np.random.default_rng(a.seed)
    print(f"{'problem':18s} {'workload':9s} {'nbst trials/s':>14s} {'Mevents/s':>10s} {'events/trial':>13s}"
          f" {'rescan trials/s':>16s} {'ratio':>6s}")
    for name in nbst.builtin_names():
        p = nbst.load_problem(name)
        for label, V in (("uniform", uniform_randomize(p, rng, a.trials)), ("directed", directed_randomize(p, a.trials))):
            ours = timed(evaluate_kernel, p, V, a.repeat, ours=True)
            base = timed(evaluate_rescan, p, V, a.repeat, ours=False)
            same = np.allclose(ours[3], base[3], atol=1e-6)
            agree = np.mean(np.all(np.abs(ours[3] - base[3]) < 1e-6, axis=(1, 2)))
            print(f"{name:18s} {label:9s} {ours[0]:14,.0f} {ours[1] / 1e6:10.2f} {ours[2]:13.1f}"
                  f" {base[0]:16,.0f} {ours[0] / base[0]:6.1f}x"
                  + ("" if same else f"   (final positions agree within 1e-6 in {agree:.1%} of trials: chaos)"))
    best, med = startup_time()
    print(f"\n`nbst simulate diamond-s14` with a warm numba cache: {best:.2f} s best, {med:.2f} s median of 3")


if __name__ == "__main__":
    main()
