"""The reconstruction's coverage and time (issue 47's "Coverage" and "One reconstruction" targets).

    nice -n 10 python benchmarks/bench_crash_coverage.py [--cases 20] [--from 0] [--budget N] [--draws N]
        [--jobs 1] [--templates crossing,oblique,head-on,rear-end] [--no-wall]

* **coverage**: ``--cases`` planted 2-car cases (``planted.planted_reconstruction``: the
  templates in turn, seeds 1, 2, ...: case k is template k mod 4 at seed k // 4 + 1), each with
  its road friction drawn in 0.7-0.9 (the case states the range, not the value), its loads and
  contact factors drawn in their default ranges, its evidence the rest positions (1.5 m),
  headings (15 deg) and impact positions (1 m); each reconstructed with ``--budget`` rollouts
  and ``--draws`` draws (defaults: the library's), seed 1. Prints per case the true impact
  speeds against the 90 % intervals, and at the end the share of true impact speeds inside
  (target >= 85 %, with its Wilson 95 % interval), the median half-width (km/h), and the share
  inside of the intervals called identifiable (the pinned ones: honest when near their 90 %);
* **wall**: one reconstruction of the built-in crossing-case at the library's defaults on
  ``--jobs`` threads (target <= 5 min on 2 cores), wall and CPU time.

The machine is shared: the figures printed say the load average when each case ended.
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

TEMPLATES = ("crossing", "oblique", "head-on", "rear-end")


def main() -> int:
    from nbst.models.crash import evidence as ev
    from nbst.models.crash import planted
    from nbst.models.crash import reconstruct as rc
    from nbst.models.mjsearch.probability import wilson

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0], allow_abbrev=False)
    ap.add_argument("--cases", type=int, default=20)
    ap.add_argument("--from", dest="start", type=int, default=0, help="first case index")
    ap.add_argument("--budget", type=int, default=rc.MAX_ROLLOUTS)
    ap.add_argument("--draws", type=int, default=rc.DRAWS)
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--templates", default=",".join(TEMPLATES))
    ap.add_argument("--no-wall", action="store_true", help="skip the one-reconstruction wall time")
    a = ap.parse_args()
    temps = a.templates.split(",")
    inside = total = pinned = pinned_in = 0
    halves, pinned_halves = [], []
    print(f"coverage: {a.cases} planted cases from {a.start}, budget {a.budget} rollouts and {a.draws} draws each, "
          f"seed 1, {a.jobs} thread(s)", flush=True)
    for k in range(a.start, a.start + a.cases):
        tpl, seed = temps[k % len(temps)], k // len(temps) + 1
        d, truth = planted.planted_reconstruction(tpl, seed)
        case = ev.case_from_dict(d, source=f"<planted {tpl} {seed}>")
        t0, c0 = time.perf_counter(), time.process_time()
        rec = rc.reconstruct(case, seed=1, max_rollouts=a.budget, draws=a.draws, jobs=a.jobs)
        parts = []
        for nm, iv, t in zip(case.script.names(), rec.intervals, truth["vehicles"]):
            s = iv.get("impact_speed")
            v = t["impact_speed"] * 3.6
            total += 1
            if not s:
                parts.append(f"{nm} {v:.1f} km/h: no interval")
                continue
            lo, hi = s["lo"] * 3.6, s["hi"] * 3.6
            ok = lo <= v <= hi
            inside += ok
            halves.append((hi - lo) / 2)
            if s.get("identifiable", True):
                pinned += 1
                pinned_in += ok
                pinned_halves.append((hi - lo) / 2)
            parts.append(f"{nm} {v:.1f} in [{lo:.1f}, {hi:.1f}]{'' if s.get('identifiable', True) else ' (n.i.)'}"
                         f"{'' if ok else ' MISSED'}")
        print(f"  {tpl} {seed} (mu {truth['friction']:.2f}): {'; '.join(parts)}; {len(rec.accepted)}/{len(rec.draws)} "
              f"draws, {rec.rollouts} rollouts, {time.perf_counter() - t0:.0f} s wall, {time.process_time() - c0:.0f} s "
              f"CPU, load {os.getloadavg()[0]:.1f}", flush=True)
    if total:
        lo, hi = wilson(inside, total)
        halves.sort()
        med = halves[len(halves) // 2] if halves else float("nan")
        print(f"coverage: {inside} of {total} true impact speeds inside their 90 % intervals ({100 * inside / total:.0f} "
              f"%, Wilson 95 % {100 * lo:.0f}-{100 * hi:.0f} %; target >= 85 %): "
              f"{'met' if inside / total >= 0.85 else 'NOT met'}; median half-width {med:.1f} km/h", flush=True)
        if pinned:
            plo, phi = wilson(pinned_in, pinned)
            print(f"identifiable (pinned) intervals: {pinned_in} of {pinned} hold the truth ({100 * pinned_in / pinned:.0f} "
                  f"%, Wilson 95 % {100 * plo:.0f}-{100 * phi:.0f} %; their level 90 %), median half-width "
                  f"{sorted(pinned_halves)[len(pinned_halves) // 2]:.1f} km/h", flush=True)
    if not a.no_wall:
        case = ev.load_case("crossing-case")
        t0, c0 = time.perf_counter(), time.process_time()
        rec = rc.reconstruct(case, seed=1, jobs=a.jobs)
        w = time.perf_counter() - t0
        print(f"one reconstruction: crossing-case, {rec.rollouts} rollouts, {len(rec.accepted)}/{len(rec.draws)} draws "
              f"accepted, {w:.0f} s wall, {time.process_time() - c0:.0f} s CPU on {a.jobs} thread(s), load "
              f"{os.getloadavg()[0]:.1f} (target <= 300 s on 2 cores): {'met' if w <= 300 else 'NOT met'}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
