"""The NHTSA NCAP frontal test on the crash vehicles (56 km/h, full width, into a rigid wall), and
car-to-car restitution against closing speed.

    python benchmarks/bench_barrier.py [--types sedan-crush,suv-crush,van-crush,sedan] [--speeds 56,16]
                                       [--parts wall,cars,energy]

For each type and each step of the crash's timestep ladder (h = 2 ms, h/2, h/4) it prints what a
crash test reads off the occupant compartment (the sprung body): time from first contact to
zero velocity, dynamic crush (the body's travel over that time), residual crush (the front
zone's plastic joints once the wall let go; rigid types have none), mean deceleration (speed /
time to zero), peak deceleration (SAE J211 CFC 60), the deceleration of the first contact step,
restitution, and the kinetic energy the impact took beside CRASH3's energy of the residual
crush; then the published ranges (docs/crash.md "Crush") and whether each figure sits in them
at every step. A rigid type (``sedan``) is the baseline the crush replaces, measured in the
same run.

``cars``: restitution at 15-60 km/h closing speed (``checks.restitution_curve``) at each step
of the ladder: a sedan-crush into the back of a standing one, an suv-crush into a sedan-crush's
back, a sedan-crush square into a sedan-crush's side; each against the published band
(``checks.restitution_band``) and whether it falls; the momentum kept through the rear impacts;
the residual crush of the striking front and the struck zone at the highest speed (at separation).
``energy``: where the rebound comes from, a sedan-crush into a standing one at 15 and 50 km/h:
from the deepest compression to separation, the kinetic energy regained (relative motion)
beside the work of each kind of force (the slab contact, the plastic steps' friction and
travel limits, the elastic elements' springs, their dampers).
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
    ap.add_argument("--parts", default="wall,cars,energy")
    a = ap.parse_args(argv)
    parts = set(a.parts.split(","))
    ok_all = True
    if "wall" in parts:
        ok_all &= _wall(a, checks, crush, vehicle)
    if "cars" in parts:
        ok_all &= _cars(checks)
    if "energy" in parts:
        _energy()
    print("target (the crushing types' 56 km/h pulse and car-to-car restitution in the published ranges at h, h/2, "
          "h/4):", "met" if ok_all else "not met")
    if "wall" in parts:
        _cost()
    return 0


def _wall(a, checks, crush, vehicle) -> bool:
    """The barrier pulse of each type at each speed and step; True where the crushing types sit in RANGES."""
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
    return ok_all


def _cars(checks) -> bool:
    """Car-to-car restitution curves at each step, against the band; True where all sit in it."""
    ok_all = True
    cases = (("sedan-crush", "sedan-crush", "rear", checks.RESTITUTION_SPEEDS),
             ("suv-crush", "sedan-crush", "rear", checks.RESTITUTION_SPEEDS),
             ("sedan-crush", "sedan-crush", "side", (15.0, 30.0, 50.0)))
    print(f"\n{'striking':12} {'struck':12} {'into':5} {'h ms':>5}  restitution at closing speed (km/h)")
    for a, b, how, speeds in cases:
        for h in LADDER:
            c0 = time.process_time()
            rs = [checks.impact(a, v, timestep=h, other=b, struck=how) for v in speeds]
            e = [r.restitution for r in rs]
            inside = all(lo <= x <= hi for x, (lo, hi) in zip(e, (checks.restitution_band(v) for v in speeds)))
            falling = all(y <= x + 0.02 for x, y in zip(e, e[1:])) and e[0] > e[-1]
            mom = max(abs(r.momentum_after / r.momentum_before - 1) for r in rs)
            ok_all &= inside
            print(f"{a:12} {b:12} {how:5} {h * 1e3:5.2f}  " + "  ".join(f"{v:g}: {x:.3f}" for v, x in zip(speeds, e))
                  + f"  | band {'in' if inside else 'OUT'}, {'falling' if falling else 'NOT falling'}"
                  + (f", momentum within {mom:.2%}" if how == "rear" else "")
                  + f"; residual crush at {speeds[-1]:g}: front {rs[-1].residual[0]['front']:.2f} m, "
                  + f"{'left' if how == 'side' else 'rear'} {rs[-1].residual[1]['left' if how == 'side' else 'rear']:.2f} m"
                  + f" ({time.process_time() - c0:.1f} s CPU)")
    lo, hi = checks.restitution_band(15.0)
    print(f"band: {lo:g}-{hi:g}, at most {checks.RESTITUTION_HIGH_SPEED[1]:g} from "
          f"{checks.RESTITUTION_HIGH_SPEED[0]:g} km/h up (SAE 931842, SAE 1999-01-0097)")
    return ok_all


def _energy() -> None:
    """The rebound's energy by source: a sedan-crush into a standing one at 15 and 50 km/h."""
    import mujoco
    import numpy as np

    from nbst.models.crash import crush, road, scene, vehicle

    T = mujoco.mjtConstraint
    contact = {int(T.mjCNSTR_CONTACT_PYRAMIDAL), int(T.mjCNSTR_CONTACT_ELLIPTIC), int(T.mjCNSTR_CONTACT_FRICTIONLESS)}
    print("\nthe rebound's energy (kJ), sedan-crush into a standing sedan-crush: from the deepest compression to "
          "separation, kinetic energy of the relative motion regained; work of each kind of force")
    print(f"{'km/h':>5} {'h ms':>5} {'KE back':>8} {'contact':>8} {'friction':>8} {'limits':>8} {'springs':>8} "
          f"{'dampers':>8} {'e':>6}")
    vt = vehicle.VEHICLE_TYPES["sedan-crush"]
    for v in (15.0, 50.0):
        for h in LADDER:
            gap = (vt.a + vt.front_overhang) + (vt.length - vt.a - vt.front_overhang) + 0.5
            vs = [scene.SceneVehicle("v0", vt, -gap, 0.0, 0.0), scene.SceneVehicle("v1", vt, 0.0, 0.0, 0.0)]
            m = scene.build_spec(road.Road(layout="straight", width=12.0, length=200.0), vs, timestep=h).compile()
            d = mujoco.MjData(m)
            d.qpos[:], d.qvel[:] = scene.initial_state(m, vs, [v / 3.6, 0.0])
            L = scene.layout(m, 2)
            ia, ib = L.qvel
            mass = L.mass
            plastic = {m.joint(n).id for p in ("v0", "v1") for z in crush.crush_zones(vt)
                       for n in crush.crush_joint_names(p, z)}
            springs = [j for j in range(m.njnt) if m.jnt_stiffness[j] > 0 and "_crush_" in m.joint(j).name]
            sq, sd = [m.jnt_qposadr[j] for j in springs], [m.jnt_dofadr[j] for j in springs]
            k, c = m.jnt_stiffness[springs], m.dof_damping[sd]
            W = dict.fromkeys(("contact", "friction", "limits", "dampers"), 0.0)
            rows, seen = [], False
            for _ in range(int(1.0 / h)):
                mujoco.mj_step(m, d)
                jv = np.zeros(d.nefc)
                if d.nefc:
                    mujoco.mj_mulJacVec(m, d, jv, d.qvel)
                for i in range(d.nefc):
                    t, idx = int(d.efc_type[i]), int(d.efc_id[i])
                    if t in contact:
                        g1, g2 = d.contact[idx].geom1, d.contact[idx].geom2
                        roots = {int(m.body_rootid[m.geom_bodyid[g]]) for g in (g1, g2)}
                        key = "contact" if roots == {m.body("v0").id, m.body("v1").id} else None
                    elif t == int(T.mjCNSTR_FRICTION_DOF):
                        key = "friction" if m.dof_jntid[idx] in plastic else None
                    elif t == int(T.mjCNSTR_LIMIT_JOINT):
                        key = "limits" if idx in plastic else None
                    else:
                        key = None
                    if key:
                        W[key] += d.efc_force[i] * jv[i] * h
                W["dampers"] -= float((c * d.qvel[sd] ** 2).sum()) * h
                touching = d.sensordata[L.pair_adr[0]] > 0
                vcm = (mass[0] * d.qvel[ia] + mass[1] * d.qvel[ib]) / mass.sum()
                ke = 0.5 * (mass[0] * (d.qvel[ia] - vcm) ** 2 + mass[1] * (d.qvel[ib] - vcm) ** 2)
                if touching or seen:
                    seen = True
                    rows.append((ke, float((0.5 * k * d.qpos[sq] ** 2).sum()), dict(W), d.qvel[ia], d.qvel[ib]))
                    if not touching:
                        break
            lo = min(range(len(rows)), key=lambda i: rows[i][0])
            (ke0, s0, w0, _, _), (ke1, s1, w1, va, vb) = rows[lo], rows[-1]
            print(f"{v:5.0f} {h * 1e3:5.2f} {(ke1 - ke0) / 1e3:8.2f} {(w1['contact'] - w0['contact']) / 1e3:8.2f} "
                  f"{(w1['friction'] - w0['friction']) / 1e3:8.2f} {(w1['limits'] - w0['limits']) / 1e3:8.2f} "
                  f"{(s0 - s1) / 1e3:8.2f} {(w1['dampers'] - w0['dampers']) / 1e3:8.2f} {(vb - va) / (v / 3.6):6.3f}")


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
