"""MuJoCo at many disks: MJCF, fixed-step and event-aligned stepping against the exact simulator.

    python benchmarks/bench_mujoco_scale.py            # N = 10, 30, 100, 300, 1,000 (~2-3 min)
    python benchmarks/bench_mujoco_scale.py --quick    # N = 10, 30, 100, 300 (< 1 min)
    python benchmarks/bench_mujoco_scale.py --mjcf 1000 3000 10000   # the scene only (~1 min)

The motions are ``nbst.models.gas.gas_motion(N, seed=1)``: N disks of radius 10 on a square
grid at area fraction 0.08 (fixed density: the box grows as sqrt(N)), random directions, speeds
100-250 units/s, t_final = 2 s, targets where the exact simulator takes them (about 3 impacts
per disk). For each N it prints one row:

* the exact motion: its events (disk-disk + wall) and ``nbst.sim.simulate``'s time;
* ``scene_xml`` (what ``nbst mjcf`` writes) and ``mujoco.MjModel.from_xml_string`` on it: seconds,
  and the loaded model's body count (N disks + the world);
* fixed steps of h = 0.25 ms (``run_final``: MuJoCo's own loop): steps, wall time, worst final
  position error against ``simulate`` (units);
* aligned stepping at probe step h (``run_mujoco(..., stepping="aligned")``): mj_step calls (trials
  and micro-steps), impacts, stepping wall time, worst final error;
* aligned / fixed wall time, and each stepping's wall time over its own at N = 10, measured in the
  same run.

``--mjcf N ...`` times only the scene at those N (the same grid and density, disks at rest, no
simulation): ``build_spec``, ``scene_xml`` and ``MjModel.from_xml_string``, with ratios to the first N.
"""
from __future__ import annotations

import argparse
import time

import numpy as np

H = 0.00025
NS = (10, 30, 100, 300, 1000)


def row(n: int, repeat: int) -> dict:
    import mujoco

    from nbst.models.mjrun import run_final, run_mujoco
    from nbst.models.scene import scene_xml
    from nbst.models.gas import gas_motion
    from nbst.sim import simulate

    p, v = gas_motion(n, seed=1)
    t0 = time.perf_counter()
    ex = simulate(p, v)
    t_sim = time.perf_counter() - t0
    t0 = time.perf_counter()
    xml = scene_xml(p, v, timestep=H)
    t_xml = time.perf_counter() - t0
    t0 = time.perf_counter()
    model = mujoco.MjModel.from_xml_string(xml)
    t_load = time.perf_counter() - t0
    fixed = []
    for _ in range(repeat):
        final, steps, wall = run_final(p, v, timestep=H)
        fixed.append(wall)
    err_f = float(np.hypot(*(final - ex.final_positions).T).max())
    aligned = []
    for _ in range(repeat):
        run = run_mujoco(p, v, timestep=H, stepping="aligned")
        aligned.append(run.stats["wall_time"])
    st = run.stats
    err_a = float(np.hypot(*(run.final_positions - ex.final_positions).T).max())
    return {"n": n, "box": p.width, "dd": ex.n_disk_disk, "wall": ex.n_wall, "t_sim": t_sim, "t_xml": t_xml,
            "t_load": t_load, "bodies": model.nbody, "xml_mb": len(xml) / 1e6, "steps": steps,
            "t_fixed": min(fixed), "err_fixed": err_f, "calls": st["trials"] + st["impacts"],
            "impacts": st["impacts"], "t_aligned": min(aligned), "err_aligned": err_a}


def mjcf_only(ns) -> None:
    import mujoco

    from nbst.models.scene import build_spec, scene_xml
    from nbst.models.validate import GAS_AREA_FRACTION, GAS_RADIUS
    from nbst.problem import problem_from_dict

    print(f"MuJoCo {mujoco.__version__}: the scene of N disks at rest on the gas_motion grid; times in s")
    print("| N | build_spec | scene_xml | from_xml_string | XML (MB) | bodies | scene_xml vs first N |")
    print("|---|---|---|---|---|---|---|")
    first = None
    for n in ns:
        side = float(np.sqrt(n * np.pi * GAS_RADIUS ** 2 / GAS_AREA_FRACTION))
        k = int(np.ceil(np.sqrt(n)))
        st = [[(a + 0.5) * side / k, (b + 0.5) * side / k] for a in range(k) for b in range(k)][:n]
        p = problem_from_dict({"name": f"grid-{n}", "box": [side, side], "t_final": 2.0, "target_radius": 20.0,
                               "disks": [{"start": s, "target": s, "radius": GAS_RADIUS} for s in st]})
        t0 = time.perf_counter()
        build_spec(p, None)
        t_spec = time.perf_counter() - t0
        t0 = time.perf_counter()
        xml = scene_xml(p, None)
        t_xml = time.perf_counter() - t0
        t0 = time.perf_counter()
        m = mujoco.MjModel.from_xml_string(xml)
        t_load = time.perf_counter() - t0
        first = first or t_xml
        print(f"| {n:,} | {t_spec:.2f} | {t_xml:.2f} | {t_load:.2f} | {len(xml) / 1e6:.1f} | {m.nbody:,} | "
              f"{t_xml / first:.1f}x |", flush=True)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(allow_abbrev=False, description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="N up to 300, one run each")
    ap.add_argument("--mjcf", type=int, nargs="+", metavar="N", help="time only the scene at these N")
    args = ap.parse_args(argv)
    if args.mjcf:
        mjcf_only(args.mjcf)
        return
    import mujoco

    from nbst.models.gas import gas_motion
    from nbst.sim import simulate

    p, v = gas_motion(10)
    simulate(p, v)  # compile / warm the numba kernels outside the timings
    ns = NS[:-1] if args.quick else NS
    print(f"MuJoCo {mujoco.__version__}, h = {H * 1e3:g} ms (fixed step and aligned probe step), gas_motion(N, "
          f"seed=1): area fraction 0.08, radius 10, t_final 2 s; times in s, best of "
          f"{1 if args.quick else '3 (N <= 100) or 1'}")
    print("| N | box | exact events dd+wall | simulate | mjcf: scene_xml / load / bodies | fixed: steps | "
          "fixed: wall | fixed: max error | aligned: mj_step calls | aligned: wall | aligned: max error | "
          "aligned / fixed | fixed vs N=10 | aligned vs N=10 |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    base = None
    for n in ns:
        r = row(n, 1 if (args.quick or n > 100) else 3)
        base = base or r
        print(f"| {n:,} | {r['box']:.0f} | {r['dd']:,}+{r['wall']:,} | {r['t_sim']:.3f} | {r['t_xml']:.2f} / "
              f"{r['t_load']:.2f} / {r['bodies']:,} | {r['steps']:,} | {r['t_fixed']:.2f} | {r['err_fixed']:.3g} | "
              f"{r['calls']:,} | {r['t_aligned']:.2f} | {r['err_aligned']:.2g} | "
              f"{r['t_aligned'] / r['t_fixed']:.1f}x | {r['t_fixed'] / base['t_fixed']:.1f}x | "
              f"{r['t_aligned'] / base['t_aligned']:.1f}x |", flush=True)


if __name__ == "__main__":
    main()
