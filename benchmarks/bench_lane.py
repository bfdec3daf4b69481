"""The full lane (nbst.models.bowling.lane): the ball's phases for a sweep of releases, the
sensitivity to the uncertain frictions, and the time a throw takes.

    python benchmarks/bench_lane.py [--quick]

Prints, in bowler's units (ft past the foul line, boards, mph, degrees):

1. the typical release of issue 22 (right-handed, 17 mph, 300 rpm, 45 deg rotation, 15 deg
   tilt, 10 board at the arrows, 1.5 deg out) on each shipped pattern;
2. a sweep of speed, rev rate and axis rotation around it (house pattern, same line);
3. sensitivity: breakpoint and entry angle as the full-oil friction (lane.MU_OIL, 0.04) and the
   dry back end's (the ball's coverstock friction, 0.20) each move by -20 % and +20 %; and the
   RG differential from 0 to USBC's 0.06 in;
4. timing: a model's build and compile, and a throw (the ball alone, h = 1 ms, to the head
   pin's line, every step recorded and analysed) against a bare ``mj_step`` loop over the same
   steps in the same run (the overhead of recording and analysis).

``--quick`` runs a smaller sweep (for the docs' tests).
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from nbst.models.bowling import lane  # noqa: E402

TYPICAL = lane.Delivery(hand="right", board=10, at="arrows", angle=1.5, mph=17, rpm=300, rotation=45, tilt=15)
HEAD = ("| release | oil | skid ft | breakpoint ft @ board | roll ft | board at pins | entry deg | mph at pins "
        "| mph lost |\n|---|---|---|---|---|---|---|---|---|")


def row(label: str, r) -> str:
    bp = "none" if r.breakpoint_ft is None else f"{r.breakpoint_ft:.1f} @ {r.breakpoint_board:.1f}"
    f = (lambda v: "none" if v is None else f"{v:.1f}")
    return (f"| {label} | {r.oil} | {f(r.skid_ft)} | {bp} | {f(r.roll_ft)} | {r.board_at_pins:.1f} | "
            f"{r.entry_angle_deg:.2f} | {r.speed_pins_mph:.1f} | {r.speed_lost_mph:.2f} |")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(allow_abbrev=False, description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="a smaller sweep")
    args = ap.parse_args(argv)

    print("## 1. the typical release on each pattern\n")
    print(HEAD)
    for oil in ("house", "sport", "short"):
        print(row("typical", lane.throw(TYPICAL, oil)))

    print("\n## 2. sweep around the typical release (house)\n")
    print(HEAD)
    sweep = {"mph": (15, 17, 19, 21), "rpm": (200, 300, 400, 500), "rotation": (15, 30, 45, 60, 75)}
    if args.quick:
        sweep = {"mph": (15, 21), "rpm": (200, 400)}
    for key, values in sweep.items():
        for val in values:
            d = lane.Delivery(**{**TYPICAL.to_dict(), key: float(val)})
            try:
                print(row(f"{key} {val}", lane.throw(d, "house")))
            except lane.LaneError as e:
                print(f"| {key} {val} | house | {e} |")

    print("\n## 3. sensitivity of the typical release (house)\n")
    print("| change | breakpoint ft | breakpoint board | entry deg | board at pins |\n|---|---|---|---|---|")
    base = lane.throw(TYPICAL, "house")
    cases = [("none (mu_oil 0.04, mu_dry 0.20, diff 0.040)", {}, None)]
    cases += [(f"mu_oil x{k:g} ({lane.MU_OIL * k:.3f})", {"law": lane.OilLaw(mu_oil=lane.MU_OIL * k)}, None)
              for k in (0.8, 1.2)]
    cases += [(f"mu_dry x{k:g} ({lane.MU_DRY * k:.2f})", {}, lane.Ball(friction=lane.MU_DRY * k)) for k in (0.8, 1.2)]
    cases += [(f"diff {dd:.2f} in", {}, lane.Ball(diff=dd)) for dd in (0.0, 0.06)]
    for label, kw, ball in cases:
        r = lane.throw(TYPICAL, "house", ball, **kw)
        bp = "none" if r.breakpoint_ft is None else f"{r.breakpoint_ft:.1f} ({r.breakpoint_ft - base.breakpoint_ft:+.1f})"
        bb = "none" if r.breakpoint_board is None else f"{r.breakpoint_board:.1f}"
        print(f"| {label} | {bp} | {bb} | {r.entry_angle_deg:.2f} ({r.entry_angle_deg - base.entry_angle_deg:+.2f}) "
              f"| {r.board_at_pins:.1f} |")

    print("\n## 4. timing\n")
    import mujoco

    n = 3 if args.quick else 10
    t0 = time.perf_counter()
    for k in range(n):
        lane.lane_spec(lane.Ball(rg=2.50 + 0.001 * k), TYPICAL, pins=True).compile()
    build = (time.perf_counter() - t0) / n
    lane.throw(TYPICAL, "house")  # compiled and cached
    t0 = time.perf_counter()
    for _ in range(n):
        r = lane.throw(TYPICAL, "house")
    per = (time.perf_counter() - t0) / n
    steps = int(round(r.seconds_to_pins / lane.TIMESTEP)) + 1
    model = lane.build_model(None, TYPICAL, pins=False)
    t0 = time.perf_counter()
    for _ in range(n):
        d = mujoco.MjData(model)
        pos, v, w = lane.initial_state(TYPICAL)
        d.qpos[:7] = [*pos, 1, 0, 0, 0]
        d.qvel[:6] = [*v, *w]
        mujoco.mj_step(model, d, nstep=steps)
    bare = (time.perf_counter() - t0) / n
    print(f"full scene (pins, {model.ngeom} geoms without them) build + compile: {build * 1000:.0f} ms")
    print(f"throw (ball alone, {steps} steps of 1 ms, recorded and analysed): {per * 1000:.1f} ms "
          f"({1 / per:.0f} throws/s)")
    print(f"bare mj_step over the same steps (baseline): {bare * 1000:.1f} ms; throw / baseline = {per / bare:.2f}x")
    return 0


if __name__ == "__main__":
    sys.exit(main())
