"""The NHTSA NCAP frontal test on the crash vehicles: 56 km/h, full width, into a rigid wall.

    python benchmarks/bench_barrier.py [--types sedan-crush,suv-crush,van-crush,sedan] [--speeds 56,16]

For each type and each step of the crash's timestep ladder (h = 2 ms, h/2, h/4) it prints what a
crash test reads off the occupant compartment (the sprung body): time from first contact to
zero velocity, dynamic crush (the body's travel over that time), residual crush (the front
zone's plastic joints once the wall let go; rigid types have none), mean deceleration (speed /
time to zero), peak deceleration (SAE J211 CFC 60), the deceleration of the first contact step,
restitution, and the kinetic energy the impact took beside CRASH3's energy of the residual
crush; then the published ranges (docs/crash.md "Crush") and whether each figure sits in them
at every step. A rigid type (``sedan``) is the baseline the crush replaces, measured in the
same run.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

#: The published ranges the pulse is held to (docs/crash.md "Crush" has the sources).
RANGES = {"t_zero": (0.060, 0.090), "dynamic_crush": (0.5, 0.8), "mean_g": (18.0, 30.0), "restitution": (0.1, 0.2)}
LADDER = (0.002, 0.001, 0.0005)


def main(argv=None) -> int:
    from nbst.models.crash import checks, crush, vehicle

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0], allow_abbrev=False)
    ap.add_argument("--types", default="sedan-crush,suv-crush,van-crush,sedan")
    ap.add_argument("--speeds", default="56,16")
    a = ap.parse_args(argv)
    print(f"{'type':12} {'km/h':>5} {'h ms':>5} {'t0 ms':>6} {'dyn m':>6} {'res m':>6} {'mean g':>6} {'CFC60 g':>7} "
          f"{'1st g':>6} {'e':>6} {'E lost kJ':>9} {'E crush kJ':>10} {'ees km/h':>8} {'cpu s':>6}")
    ok_all = True
    for t in a.types.split(","):
        vt = vehicle.VEHICLE_TYPES[t]
        for v in (float(x) for x in a.speeds.split(",")):
            rows = []
            for h in LADDER:
                c0 = time.process_time()
                r = checks.barrier_pulse(t, v, timestep=h)
                cpu = time.process_time() - c0
                ees = crush.crush_ees(vt, {"front": r.residual}) * 3.6 if vt.crush else float("nan")
                rows.append(r)
                print(f"{t:12} {v:5.0f} {h * 1e3:5.2f} {r.t_zero * 1e3:6.1f} {r.dynamic_crush:6.3f} {r.residual:6.3f} "
                      f"{r.mean_g:6.1f} {r.peak_g:7.1f} {r.first_step_g:6.1f} {r.restitution:6.3f} "
                      f"{r.energy_lost / 1e3:9.1f} {r.crush_energy / 1e3:10.1f} {ees:8.1f} {cpu:6.2f}")
            if v == 56.0:
                verdicts = []
                for k, (lo, hi) in RANGES.items():
                    inside = all(lo <= getattr(r, k) <= hi for r in rows)
                    verdicts.append(f"{k} {lo:g}-{hi:g}: {'in' if inside else 'OUT'}")
                    ok_all &= inside or not vt.crush
                print(f"{'':12} ranges at every step: " + "; ".join(verdicts))
    print("target (the crushing types' 56 km/h pulse in the published ranges at h, h/2, h/4):",
          "met" if ok_all else "not met")
    _cost()
    return 0


def _cost(steps: int = 3000) -> None:
    """CPU of a plain mj_step loop (6 s at 2 ms) of a 2-vehicle head-on scene, crushing against
    rigid twins, measured in the same run (the crush zones' cost)."""
    import mujoco

    from nbst.models.crash import road, scene, vehicle

    out = {}
    for a, b in (("sedan", "suv"), ("sedan-crush", "suv-crush")):
        vs = [scene.SceneVehicle("v0", vehicle.VEHICLE_TYPES[a], -20.0, 0.0, 0.0),
              scene.SceneVehicle("v1", vehicle.VEHICLE_TYPES[b], 20.0, 0.0, 3.141592653589793)]
        m = scene.build_spec(road.Road(layout="straight", width=12.0, length=200.0), vs, timestep=0.002).compile()
        d = mujoco.MjData(m)
        d.qpos[:], d.qvel[:] = scene.initial_state(m, vs, [10.0, 10.0])
        c0 = time.process_time()
        mujoco.mj_step(m, d, nstep=steps)
        out[a] = (time.process_time() - c0, m.nv)
    (r, nr), (c, nc) = out["sedan"], out["sedan-crush"]
    print(f"cost: a 6 s head-on at 20 m/s closing, plain mj_step: rigid {r * 1e3:.0f} ms CPU (nv {nr}), "
          f"crushing {c * 1e3:.0f} ms (nv {nc}): {c / r:.2f}x")


if __name__ == "__main__":
    raise SystemExit(main())
