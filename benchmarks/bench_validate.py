"""Benchmark and measurements of the MuJoCo cross-check (nbst.models).

    python benchmarks/bench_validate.py            # timing + accuracy figures (~1 min)
    python benchmarks/bench_validate.py --quick    # timing only

Prints:
* validation wall time of a 5 s, 14-disk scene (diamond-s14, straight-line velocities,
  17 disk-disk collisions), best of 3, and MuJoCo steps/s in it (target: < 5 s);
* accuracy at h = 1 ms and 0.25 ms: wall bounce and head-on collision (speed error and
  position lag), oblique collision direction error;
* kinetic energy drift of a dense 14-disk scene over 60 s at both timesteps.
"""
from __future__ import annotations

import argparse
import time

import numpy as np


def _problem(starts, radius, *, t_final, box=(800.0, 800.0), masses=None, name="bench"):
    from nbst.problem import problem_from_dict
    disks = [{"start": list(map(float, s)), "target": list(map(float, s)), "radius": float(radius),
              **({"mass": float(masses[i])} if masses is not None else {})} for i, s in enumerate(starts)]
    return problem_from_dict({"name": name, "box": list(box), "t_final": t_final, "target_radius": 75.0,
                              "disks": disks})


def bench_validate() -> None:
    from nbst import load_problem
    from nbst.models.validate import validate

    p = load_problem("diamond-s14")
    v = p.straight_velocities()
    validate(p, v)  # warm up (numba, mujoco import)
    times, runs = [], []
    for _ in range(3):
        t0 = time.perf_counter()
        val = validate(p, v)
        times.append(time.perf_counter() - t0)
        runs.append(val.mujoco.wall_time)
    steps = val.mujoco.steps
    print(f"validate diamond-s14 (14 disks, 5 s, h = 0.25 ms, {steps} steps, {val.exact.n_disk_disk} disk-disk "
          f"collisions): best {min(times):.2f} s (median {np.median(times):.2f} s); MuJoCo stepping "
          f"{min(runs):.2f} s = {steps / min(runs):,.0f} steps/s; target < 5 s")


def accuracy() -> None:
    from nbst import simulate
    from nbst.models.mjrun import run_mujoco

    for h in (1e-3, 2.5e-4):
        # wall bounce
        p = _problem([[700.0, 400.0]], 10.0, t_final=0.5)
        v = np.array([[333.3, 0.0]])
        tr, r = simulate(p, v), run_mujoco(p, v, timestep=h)
        vm = (r.positions[-1] - r.positions[-2]) / h
        lag = (r.final_positions - tr.final_positions)[0, 0] / (333.3 * h)
        print(f"h = {h * 1e3:g} ms  wall bounce: speed rel. error {abs(np.hypot(*vm[0]) / 333.3 - 1):.1e}, "
              f"position lag {lag:.6f} x v h (1 bounce)")
        # head-on, masses 1 and 2
        p = _problem([[300, 400], [500, 400]], 10.0, t_final=2.0, masses=[1.0, 2.0])
        v = np.array([[100.0, 0], [-50.0, 0]])
        tr, r = simulate(p, v), run_mujoco(p, v, timestep=h)
        vm = (r.positions[-1] - r.positions[-2]) / h
        print(f"h = {h * 1e3:g} ms  head-on: velocity error {np.abs(vm - tr.final_velocities).max():.1e} units/s, "
              f"position error {np.abs(r.final_positions - tr.final_positions).max():.3g} units")
        # oblique, several impact parameters
        worst = 0.0
        for b in (2.0, 5.0, 10.0, 14.142, 18.0):
            p = _problem([[300, 400], [500, 400 + b]], 10.0, t_final=2.0)
            v = np.array([[100.0, 0], [0, 0]])
            tr, r = simulate(p, v), run_mujoco(p, v, timestep=h)
            vm = (r.positions[-1] - r.positions[-2]) / h
            va = tr.final_velocities
            ang = np.degrees(np.arctan2(vm[:, 1], vm[:, 0]) - np.arctan2(va[:, 1], va[:, 0]))
            worst = max(worst, float(np.abs(ang).max()))
        print(f"h = {h * 1e3:g} ms  oblique (impact parameter 0.1-0.9 x 2r): direction error up to {worst:.3f} deg")


def energy_drift() -> None:
    from nbst import load_problem
    from nbst.models.mjrun import run_mujoco

    base = load_problem("diamond-s14")
    p = _problem(base.start, 20.0, t_final=60.0, name="dense14")
    rng = np.random.default_rng(0)
    ang = rng.uniform(0, 2 * np.pi, p.n)
    for speed, h in ((150.0, 1e-3), (150.0, 2.5e-4), (500.0, 1e-3), (500.0, 2.5e-4)):
        v = speed * np.stack([np.cos(ang), np.sin(ang)], axis=1)
        r = run_mujoco(p, v, timestep=h)
        E = r.energy
        free = ~r.in_contact
        n_dd = int(np.count_nonzero(r.events["kind"] == 0))
        print(f"h = {h * 1e3:g} ms  dense 14 disks (r = 20, {speed:g} units/s) over 60 s: {n_dd} disk-disk contacts; "
              f"kinetic energy drift max {np.abs(E[free] / E[0] - 1).max() * 100:.2f}% "
              f"(contact-free steps), {100 * (E[-1] / E[0] - 1):+.2f}% at 60 s; {r.wall_time:.1f} s")


def main() -> None:
    ap = argparse.ArgumentParser(allow_abbrev=False, description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="timing only")
    args = ap.parse_args()
    import mujoco
    print(f"MuJoCo {mujoco.__version__}")
    bench_validate()
    if not args.quick:
        accuracy()
        energy_drift()


if __name__ == "__main__":
    main()
