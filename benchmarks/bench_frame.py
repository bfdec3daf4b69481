"""Frames from the foul line (issue 22): settle, the timestep ladder, and speed.

Prints, for the typical strike release and each common leave's straight spare ball
(models/bowling/spares.py), the settled leave at h = 1, 0.5 and 0.25 ms and 2 s longer, the
settle time and whether the cap was hit; then the cost of a frame against a bare ``mj_step``
loop over the same simulated time, and 1 process against 2 on a batch of noisy throws.

    python benchmarks/bench_frame.py [--quick]
"""
from __future__ import annotations

import argparse
import time

import mujoco
import numpy as np

from nbst.models.bowling.lane import frame, noise, spares


def leave_text(r) -> str:
    return "-".join(map(str, r.leave)) or "none"


def main() -> None:
    ap = argparse.ArgumentParser(allow_abbrev=False, description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="the strike and two spares only; a batch of 8")
    args = ap.parse_args()
    shots = [("strike (typical release)", spares.STRIKE, None)]
    names = ["10", "7"] if args.quick else list(spares.LEAVES)
    for nm in names:
        key, _ = spares.LEAVES[nm]
        shots.append((f"spare {nm} (straight)", spares.straight_at(*spares.aim_point(key)), spares.leave_pins(nm)))
    print("1. the ladder: leave at h = 1 / 0.5 / 0.25 ms, and at 1 ms run 2 s longer")
    print(f"{'shot':<28} {'1 ms':>8} {'0.5 ms':>8} {'0.25 ms':>8} {'+2 s':>8}  settle (s) at 1/0.5/0.25 ms   same")
    kept = 0
    for label, d, standing in shots:
        rs = frame.ladder(d, standing=standing)
        longer = frame.run_frame(d, standing=standing, extra_s=2.0)
        same = all(r.leave == rs[0].leave for r in rs) and longer.leave == rs[0].leave
        kept += same
        st = "/".join("cap" if r.cap_hit else f"{r.settle_s:.2f}" for r in rs)
        print(f"{label:<28} {leave_text(rs[0]):>8} {leave_text(rs[1]):>8} {leave_text(rs[2]):>8} "
              f"{leave_text(longer):>8}  {st:<28} {'yes' if same else 'NO'}")
    print(f"   {kept} of {len(shots)} keep their outcome over the ladder and 2 s longer")

    print("2. speed: one frame against a bare mj_step loop over the same simulated time")
    r = frame.run_frame(spares.STRIKE)
    t0 = time.perf_counter()
    r = frame.run_frame(spares.STRIKE)
    t_frame = time.perf_counter() - t0
    m = frame.frame_model()
    dd = mujoco.MjData(m)
    q, v = frame.initial_qpos_qvel(m, spares.STRIKE)
    dd.qpos[:], dd.qvel[:] = q, v
    n = int(round(r.seconds / m.opt.timestep))
    t0 = time.perf_counter()
    mujoco.mj_step(m, dd, nstep=n)
    t_bare = time.perf_counter() - t0
    print(f"   frame {1000 * t_frame:.0f} ms for {r.seconds:.2f} s simulated ({n:,} steps); bare mj_step "
          f"{1000 * t_bare:.0f} ms; ratio {t_frame / t_bare:.2f}")

    print("3. a batch of noisy throws: 1 process against 2")
    nb = 8 if args.quick else 24
    times = {}
    for jobs in (1, 2):
        with frame.FrameRunner(jobs=jobs) as R:
            t0 = time.perf_counter()
            est, res = noise.probability(spares.STRIKE, nb, 1, runner=R)
            times[jobs] = time.perf_counter() - t0
        print(f"   {jobs} process(es): {nb} frames in {times[jobs]:.1f} s ({times[jobs] / nb:.2f} s a frame); "
              f"strike {est.text()}")
    b = np.array([r.board_at_pins for r in res if r.board_at_pins is not None])
    a = np.array([r.entry_angle_deg for r in res if r.entry_angle_deg is not None])
    print(f"   the default noise at the pins (strike line, these {nb} throws): board {b.mean():.1f} +- {b.std(ddof=1):.1f} "
          f"(sd), entry angle {a.mean():.1f} +- {a.std(ddof=1):.1f} deg")
    print(f"   speed-up of 2 processes: {times[1] / times[2]:.2f}x")


if __name__ == "__main__":
    main()
