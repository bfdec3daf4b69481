"""Ball motion on the lane (issue 34): the friction, flare, RG and differential, the oil law's fit, speed.

    python benchmarks/bench_ball_motion.py                 # every section (~2-4 min of CPU)
    python benchmarks/bench_ball_motion.py --part sbs      # one: friction, flare, sbs, fit, sens, speed

Sections (the ball alone, ``lane.throw``; the figures docs/bowling.md quotes):

* **friction**: a ball sliding on a dry lane (no oil, coverstock 0.2 / 0.1, differential 0): the
  slip's fall rate against Coulomb's ``mu g (1 + R^2/k^2)`` and the centre's height, at
  h = 1, 0.5, 0.25 ms; beside it MuJoCo's own soft friction on the same lane (condim 3): the
  share of Coulomb it delivers and the steps the ball spends off the lane.
* **flare**: track flare (the spread of the ball's spin axes over the first 40 ft, in of arc)
  against the differential (0 .. 0.06) and the pin-to-PAP distance (0.5 .. 6.5 in), on the
  uniform pattern (a thick film: mu 0.04 all the way).
* **sbs**: the side-by-side of docs/bowling.md: one release fixed (the league-200 release, 17 mph,
  350 rpm, 45 deg rotation, 12 deg tilt, aimed at the pocket from board 20 with the default
  ball), then the differential 0.00 / 0.06 and the RG 2.46 / 2.80 (at the same rpm, and at the
  same effort: rpm x (2.50 / RG)^2); flare, breakpoint, roll, hook (boards from the breakpoint
  to the pins), entry angle, board at the pins.
* **fit**: the house shot: the league-200 release and a stroker (16 mph, 300 rpm) aimed at the
  pocket from foul-line boards 16-24 (breakpoint distance and board of each line), for the law's
  h0 = 0.1, 0.2 (the fit) and 0.3 um; then the line from board 20 on every shipped pattern.
* **sens**: the same line aimed again with each assumed constant moved (the exchange share, the
  band, the cover's absorption, the full film's and the coverstock's friction).
* **speed**: ms per throw (``lane.throw``: friction kernel, oil, recording, phases) against a bare
  ``mj_step`` loop over the same number of steps, in the same run; the kernel alone per step.
"""
from __future__ import annotations

import argparse
import math
import time
from dataclasses import replace

import numpy as np

from nbst.models.bowling import lane, scene
from nbst.models.bowling.lane import friction, phases

L200 = lane.Delivery(mph=17.0, rpm=350.0, rotation=45.0, tilt=12.0)
STROKER = lane.Delivery(mph=16.0, rpm=300.0, rotation=45.0, tilt=15.0)
R = scene.BALL_RADIUS


def _f(v, fmt="5.1f"):
    return "  -  " if v is None else format(v, fmt)


def row(r) -> str:
    hook = r.board_at_pins - (r.breakpoint_board if r.breakpoint_board is not None else r.board_at_foul_line)
    return (f"bp {_f(r.breakpoint_ft)} ft b{_f(r.breakpoint_board, '4.1f')}  roll {_f(r.roll_ft)}  "
            f"pins {r.board_at_pins:5.1f}  entry {r.entry_angle_deg:4.2f}  hook {hook:5.1f}  flare {r.flare_in:4.2f} in  "
            f"lost {r.speed_lost_mph:4.2f} mph")


def part_friction() -> None:
    import mujoco

    print("## friction: a sliding ball on a dry lane (coverstock mu, differential 0, 17 mph, 300 rpm end over end "
          "+ side): slip fall rate over 0.2 s")
    ball0 = lane.Ball(diff=0.0)
    d = lane.Delivery(board=20, at="foul", angle=0.0, mph=17, rpm=300, rotation=60, tilt=10)
    k = ball0.rg * scene.INCH
    for mu in (0.2, 0.1):
        ball = replace(ball0, friction=mu)
        want = mu * 9.81 * (1 + R * R / (k * k))
        for h in (0.001, 0.0005, 0.00025):
            dry = lane.OilField(np.zeros((lane.N_BOARDS, lane.NX)))
            t, p, v, w, _ = phases.run(d, "house", ball, field=dry, timestep=h)
            slip = np.hypot(*(v + np.cross(w, [0.0, 0.0, -R]))[:, :2].T)
            i = int(round(0.2 / h))
            rate = (slip[0] - slip[i]) / t[i]
            # MuJoCo's soft friction on the same lane: the lane contact with condim 3 and this mu
            spec = lane.lane_spec(ball, lane.Delivery(), pins=False)
            g = spec.geom(lane.LANE_GEOM)
            g.condim, g.friction = 3, [mu, 0.0, 0.0]
            m = spec.compile()
            m.opt.timestep = h
            dd = mujoco.MjData(m)
            dd.qpos[:7], dd.qvel[:6] = phases.release_state(m, d, ball)
            s0, off = None, 0
            gid = m.geom(lane.LANE_GEOM).id
            for n in range(i):
                wv = phases.quat_to_mat(np.array(dd.qpos[3:7])[None])[0] @ dd.qvel[3:6]
                u = np.hypot(*(dd.qvel[:3] + np.cross(wv, [0.0, 0.0, -R]))[:2])
                s0 = u if s0 is None else s0
                off += all(int(c.geom1) != gid and int(c.geom2) != gid for c in dd.contact[:dd.ncon])
                mujoco.mj_step(m, dd)
            wv = phases.quat_to_mat(np.array(dd.qpos[3:7])[None])[0] @ dd.qvel[3:6]
            u = np.hypot(*(dd.qvel[:3] + np.cross(wv, [0.0, 0.0, -R]))[:2])
            soft = (s0 - u) / (i * h)
            print(f"mu {mu:.1f} h {h * 1e3:5.2f} ms: Coulomb by hand {rate:.4f} m/s^2 (analytic {want:.4f}, "
                  f"{rate / want:.6f}); centre height -{(R - p[:, 2].min()) * 1e3:.3f}..+{(p[:, 2].max() - R) * 1e3:.3f} mm; "
                  f"MuJoCo soft friction {soft:.3f} m/s^2 = {soft / want:.3f} of Coulomb, off the lane "
                  f"{100 * off / i:.0f} % of steps")


def _flare(d, ball) -> float:
    t, p, v, w, extra = phases.run(d, "uniform", ball)  # the ball alone, to the pins or the gutter
    return phases.flare_in(extra["omega_body"], lane.x_to_ft(p[:, 0]))


def part_flare() -> None:
    print("## flare: the uniform pattern (mu 0.04 everywhere), 17 mph, 400 rpm, rotation 45, tilt 10, board 20 "
          "straight; track flare over the first 40 ft (in of arc)")
    d = lane.Delivery(board=20, at="foul", angle=0.0, mph=17, rpm=400, rotation=45, tilt=10)
    for rg in (2.46, 2.80):
        fl = [_flare(d, lane.Ball(rg=rg, diff=df)) for df in (0, .01, .02, .03, .045, .06)]
        print(f"RG {rg:.2f}, differential 0 / .010 / .020 / .030 / .045 / .060: " + " / ".join(f"{x:.2f}" for x in fl))
    fl = [_flare(d, lane.Ball(diff=0.05, pin_pap_in=pp)) for pp in (0.5, 1.5, 2.5, 3.375, 4.5, 5.5, 6.5)]
    print("differential .050, pin to PAP 0.5 / 1.5 / 2.5 / 3.375 / 4.5 / 5.5 / 6.5 in: " + " / ".join(f"{x:.2f}" for x in fl))
    fl = [_flare(replace(d, rpm=r), lane.Ball(diff=0.05)) for r in (250, 300, 400, 500)]
    print("differential .050, 250 / 300 / 400 / 500 rpm: " + " / ".join(f"{x:.2f}" for x in fl))
    a = _flare(d, lane.Ball(diff=0.05, intdiff=0.0))
    b = _flare(d, lane.Ball(diff=0.05, intdiff=0.02))
    print(f"differential .050, intermediate differential 0 / .020 (mass bias 6 in from the PAP): {a:.2f} / {b:.2f}")


def part_sbs() -> None:
    d, r0 = phases.aim_angle(replace(L200, board=20.0, at="foul"), 17.5, "house")
    print(f"## side by side: the league-200 release aimed at the pocket from board 20 with the default ball "
          f"(RG 2.50, diff .040): angle {d.angle:+.3f} deg; then the release fixed, house shot")
    print(f"{'default (RG 2.50, diff .040)':36s} {row(r0)}")
    for label, kw in (("diff 0.00", {"diff": 0.0}), ("diff 0.06", {"diff": 0.06}), ("RG 2.46", {"rg": 2.46}),
                      ("RG 2.80", {"rg": 2.80})):
        print(f"{label + ' (same rpm)':36s} {row(lane.throw(d, 'house', lane.Ball(**kw)))}")
    for rg in (2.46, 2.80):
        rpm = d.rpm * (2.50 / rg) ** 2
        print(f"{f'RG {rg:.2f} same effort ({rpm:.0f} rpm)':36s} {row(lane.throw(replace(d, rpm=rpm), 'house', lane.Ball(rg=rg)))}")


def part_fit() -> None:
    print("## fit: lines aimed at the pocket (board 17.5 at the head pin) on the house shot")
    for h0 in (0.1, 0.2, 0.3):
        law = lane.OilLaw(h0_um=h0)
        for name, base in (("league-200 17/350/45/12", L200), ("stroker 16/300/45/15", STROKER)):
            for foul in (16, 18, 20, 22, 24):
                try:
                    d, r = phases.aim_angle(replace(base, board=float(foul), at="foul"), 17.5, "house", law=law)
                    print(f"h0 {h0:.1f} um  {name}  board {foul} at the foul line, {d.angle:+.2f} deg: {row(r)}")
                except lane.LaneError as e:
                    print(f"h0 {h0:.1f} um  {name}  board {foul}: {e}")
    print("## the league-200 line from board 20 on each shipped pattern (aimed again on each)")
    for name in lane.PATTERNS.names():
        try:
            d, r = phases.aim_angle(replace(L200, board=20.0, at="foul"), 17.5, name)
            print(f"{name:12s} {d.angle:+.2f} deg: {row(r)}")
        except lane.LaneError as e:
            print(f"{name:12s} {e}")


def part_speed(reps: int = 5) -> None:
    import mujoco

    d = replace(L200, board=20.0, at="foul", angle=2.82)
    lane.throw(d, "house")  # compile and cache
    t_throw = []
    for _ in range(reps):
        t0 = time.perf_counter()
        r = lane.throw(d, "house")
        t_throw.append(time.perf_counter() - t0)
    n = len(r.path["t"]) - 1
    m = phases.ball_model()
    data = mujoco.MjData(m)
    qa, va = phases.release_state(m, d, lane.Ball())
    t_bare, t_kern = [], []
    bol = friction.BallOnLane(m, lane.Ball(), lane.OilField.fresh(lane.pattern("house")))
    for _ in range(reps):
        data.qpos[:7], data.qvel[:6] = qa, va
        t0 = time.perf_counter()
        for _ in range(n):
            mujoco.mj_step(m, data)
        t_bare.append(time.perf_counter() - t0)
        data.qpos[:7], data.qvel[:6] = qa, va
        t0 = time.perf_counter()
        for _ in range(n):
            bol.step(data)
        t_kern.append(time.perf_counter() - t0)
    tb, tt, tk = min(t_bare), min(t_throw), min(t_kern)
    print(f"## speed (best of {reps}): a throw {tt * 1e3:.1f} ms ({n} steps); a bare mj_step loop over the same steps "
          f"{tb * 1e3:.1f} ms (x{tt / tb:.2f}); the friction kernel alone {tk / n * 1e6:.1f} us a step")


def part_sens() -> None:
    print("## sensitivity of the assumed constants: the league-200 line from board 20, aimed again on the house shot")
    cases = [("as fitted", lane.LAW, lane.Ball())]
    cases += [(f"exchange {x:g}", lane.OilLaw(exchange=x), lane.Ball()) for x in (0.1, 0.5)]
    cases += [(f"band {x:g} in", lane.OilLaw(band_in=x), lane.Ball()) for x in (0.5, 2.0)]
    cases += [(f"absorb_s {x:g} s", lane.LAW, lane.Ball(absorb_s=x)) for x in (0.3, 3.0, 0.0)]
    cases += [(f"mu_oil {x:g}", lane.OilLaw(mu_oil=x), lane.Ball()) for x in (0.03, 0.05)]
    cases += [(f"coverstock {x:g}", lane.LAW, lane.Ball(friction=x)) for x in (0.16, 0.24)]
    for label, law, ball in cases:
        try:
            d, r = phases.aim_angle(replace(L200, board=20.0, at="foul"), 17.5, "house", ball, law=law)
            print(f"{label:18s} {d.angle:+.2f} deg: {row(r)}")
        except lane.LaneError as e:
            print(f"{label:18s} {e}")


PARTS = {"friction": part_friction, "flare": part_flare, "sbs": part_sbs, "fit": part_fit, "sens": part_sens,
         "speed": part_speed}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0], allow_abbrev=False)
    ap.add_argument("--part", choices=tuple(PARTS), action="append", help="sections to run (default all)")
    args = ap.parse_args()
    for p in args.part or PARTS:
        t0 = time.perf_counter()
        PARTS[p]()
        print(f"({p}: {time.perf_counter() - t0:.0f} s)\n", flush=True)


if __name__ == "__main__":
    main()
