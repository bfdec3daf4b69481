"""Coverage of the reconstruction's 90 % intervals on planted 2-car crashes (docs/crash.md).

    python benchmarks/bench_reconstruct.py [--templates crossing,oblique,head-on,rear-end] [--seeds 1-5]
        [--budget 2400] [--particles 128] [--jobs 2] [--friction 0.7,0.9]

Each case (:func:`nbst.models.crash.evidence.planted`): hidden intents, a road friction drawn
uniformly in ``--friction`` (the case states the range, never the value), loads and contact
factors drawn in their default ranges, simulated; handed over as evidence: whom each hit, its
rest position (1.5 m) and heading (15 deg), and, except in the rear-end, its centre of mass at
the impact (1 m). The rear-end gets its rest positions alone: the case the issue names as not
identifiable. Each case is reconstructed (``reconstruct``, seed 1) and the bench prints, per
case, the 90 % intervals of each vehicle's impact speed against the hidden one, whether each is
flagged identifiable, the tolerance reached, the rollouts and the time; then the share of
intervals that hold the truth (target >= 85 %) with its Wilson 95 % interval, the median
half-width (km/h) and the median time of one reconstruction (target <= 5 min on 2 cores).
"""
from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from nbst.models.crash import evidence as ev_mod
from nbst.models.crash import reconstruct as rc
from nbst.models.mjsearch.probability import wilson


def _seeds(text: str) -> list[int]:
    if "-" in text:
        a, b = text.split("-")
        return list(range(int(a), int(b) + 1))
    return [int(x) for x in text.split(",")]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--templates", default="crossing,oblique,head-on,rear-end")
    ap.add_argument("--seeds", default="1-5")
    ap.add_argument("--budget", type=int, default=rc.MAX_ROLLOUTS)
    ap.add_argument("--particles", type=int, default=rc.PARTICLES)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--friction", default="0.7,0.9")
    a = ap.parse_args()
    fr = tuple(float(x) for x in a.friction.split(","))
    held = total = 0
    halves, walls, cpus, rolls = [], [], [], []
    by_tpl: dict = {}
    for seed in _seeds(a.seeds):  # every template at a seed, then the next seed: a run cut short covers them all
        for tpl in a.templates.split(","):
            d, truth = ev_mod.planted(tpl, seed, impact_at=tpl != "rear-end", friction=fr)
            case = ev_mod.case_from_dict(d, source=f"<planted {tpl} {seed}>")
            t0, c0 = time.perf_counter(), time.process_time()
            rec = rc.reconstruct(case, seed=1, max_rollouts=a.budget, particles=a.particles, jobs=a.jobs)
            wall, cpu = time.perf_counter() - t0, time.process_time() - c0
            walls.append(wall)
            cpus.append(cpu)
            rolls.append(rec.rollouts)
            parts = []
            for nm, iv, tr in zip(case.script.names(), rec.intervals, truth["vehicles"]):
                x = iv.get("impact_speed", {}) if iv else {}
                ok = bool(x) and x["lo"] <= tr["impact_speed"] <= x["hi"]
                held += ok
                total += 1
                k = by_tpl.setdefault(tpl, [0, 0])
                k[0] += ok
                k[1] += 1
                if x:
                    halves.append((x["hi"] - x["lo"]) / 2 * 3.6)
                    parts.append(f"{nm} {tr['impact_speed'] * 3.6:.1f} in [{x['lo'] * 3.6:.1f}, {x['hi'] * 3.6:.1f}]"
                                 f" km/h {'yes' if ok else 'NO'}"
                                 f"{'' if x.get('identifiable', True) else ' (not identifiable)'}")
                else:
                    parts.append(f"{nm} {tr['impact_speed'] * 3.6:.1f} km/h: no interval NO")
            mu = rec.phys["friction"][rec.accepted] if rec.found else rec.phys["friction"]
            print(f"{tpl} {seed}: mu {truth['friction']:.3f} (drawn {np.quantile(mu, 0.05):.2f}-"
                  f"{np.quantile(mu, 0.95):.2f}); " + "; ".join(parts)
                  + f"; eps {rec.epsilon:.2f}, {int(rec.accepted.sum())}/{rec.particles} accepted, {rec.rollouts} "
                    f"rollouts, {rec.generations} generations, {wall:.0f} s wall, {cpu:.0f} s CPU", flush=True)
    lo, hi = wilson(held, total)
    print(f"coverage: {held} of {total} intervals hold the true impact speed, {100 * held / max(total, 1):.0f} % "
          f"(Wilson 95 % {100 * lo:.0f}-{100 * hi:.0f} %; target >= 85 %); by template: "
          + ", ".join(f"{t} {k}/{n}" for t, (k, n) in by_tpl.items()))
    if halves:
        print(f"median half-width {statistics.median(halves):.1f} km/h; one reconstruction: median "
              f"{statistics.median(walls):.0f} s wall ({statistics.median(cpus):.0f} s CPU, "
              f"{statistics.median(rolls):.0f} rollouts, --jobs {a.jobs}; target <= 300 s on 2 cores)")


if __name__ == "__main__":
    main()
