"""The crash model's figures and the issue's targets (docs/crash.md).

    python benchmarks/bench_crash.py --part physics

prints the vehicle checks: braking distances against v^2/2 mu g, the tilt table against
atan(SSF), the restitution curve (closing speed -> restitution, sedan into sedan) against the
published band, and the NCAP frontal pulse (56 km/h into a rigid wall) against its bracket.
"""
from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

PARTS = ("physics",)


def physics() -> None:
    from nbst.models.crash import checks, vehicle

    print("braking on locked wheels (m): type, v0 m/s, mu, measured, v^2/2 mu g, error")
    for t in vehicle.TYPES:
        for v in (20.0, 30.0):
            for mu in (0.8, 0.5):
                d = checks.braking_distance(t, v, mu)
                th = v * v / (2 * mu * vehicle.G)
                print(f"  {t:6s} {v:4.0f} {mu:4.2f} {d:7.2f} {th:7.2f} {100 * (d / th - 1):+6.2f} %")
    print("tilt table (deg): type, uphill wheels lift, tips over, atan(SSF)")
    for t, vt in vehicle.TYPES.items():
        r = checks.tilt_angle(t)
        print(f"  {t:6s} {r.lift_deg:6.2f} {r.tip_deg:6.2f} {math.degrees(math.atan(vt.ssf)):6.2f}")
    print("restitution, sedan into a standing sedan: closing km/h, e, band, contact ms, momentum after/before")
    for v in checks.RESTITUTION_SPEEDS:
        r = checks.impact("sedan", v)
        lo, hi = checks.restitution_band(v)
        print(f"  {v:4.0f} {r.restitution:6.3f} [{lo:.2f}, {hi:.2f}] {1e3 * r.duration:5.0f} "
              f"{r.momentum_after / r.momentum_before:.5f}")
    print("NCAP frontal, 56 km/h into a rigid wall: type, pulse ms, mean g, restitution, penetration m "
          f"(bracket {checks.NCAP_DURATION_S[0] * 1e3:.0f}-{checks.NCAP_DURATION_S[1] * 1e3:.0f} ms, "
          f"{checks.NCAP_MEAN_G[0]:.0f}-{checks.NCAP_MEAN_G[1]:.0f} g)")
    for t in vehicle.TYPES:
        r = checks.barrier(t, 56.0)
        print(f"  {t:6s} {1e3 * r.duration:5.0f} {r.mean_g:6.1f} {r.restitution:6.3f} {r.penetration:6.3f}")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(allow_abbrev=False, description=__doc__.splitlines()[0])
    ap.add_argument("--part", choices=PARTS, action="append", help="which figures (default: all)")
    args = ap.parse_args(argv)
    for part in args.part or PARTS:
        t0 = time.perf_counter()
        globals()[part]()
        print(f"[{part}: {time.perf_counter() - t0:.1f} s wall]")
    return 0


if __name__ == "__main__":
    sys.exit(main())
