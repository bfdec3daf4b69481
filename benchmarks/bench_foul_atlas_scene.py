"""The shipped foul-line atlas on today's lane scene: how many of its throws still give their subset.

    python benchmarks/bench_foul_atlas_scene.py [--jobs K]

``models/bowling/lane/foul_atlas.json`` was grown on lane-1 (issue 22's soft friction on relative
oil; the file names no scene). Each of its throws is thrown again, once, on this nbst's scene
(``lane.SCENE``) at h = 1 ms, and the script prints how many give their recorded subset, how many
of the throws that held on lane-1's timestep ladder do, how many distinct subsets the re-thrown
throws give, and how many frames the sweep counted before they settled. ~300 frames: ~2-5 min of
CPU. The figures docs/bowling.md quotes for the atlas on lane-2.
"""
from __future__ import annotations

import argparse
import time
from pathlib import Path

from nbst.models.bowling import lane
from nbst.models.bowling.lane import frame, throwfile

ATLAS = Path(__file__).resolve().parents[1] / "models" / "bowling" / "lane" / "foul_atlas.json"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0], allow_abbrev=False)
    ap.add_argument("--jobs", type=int, default=1, help="processes running frames (default 1)")
    args = ap.parse_args()
    a = throwfile.load_atlas(ATLAS)
    ts = a["throws"]
    t0 = time.time()
    if any(sorted(t["standing"]) != list(range(1, 11)) for t in ts):
        raise SystemExit(f"{ATLAS}: every throw of the foul-line atlas is on a full rack")
    with frame.FrameRunner(a["oil"], lane.Ball(**a["ball"]), jobs=args.jobs) as run:
        res = run.map([lane.Delivery(**t["delivery"]) for t in ts])
    same = held = held_same = 0
    subsets = set()
    for t, r in zip(ts, res):
        ok = r.down == sorted(t["outcome"]["down"])
        same += ok
        subsets.add(tuple(r.down))
        lad = t.get("ladder") or []
        if lad and all(sorted(x["leave"]) == sorted(t["outcome"]["leave"]) for x in lad):
            held += 1
            held_same += ok
    print(f"{len(ts)} atlas throws (scene {a.get('scene', 'lane-1')}) thrown again on {lane.SCENE}: {same} give their "
          f"subset; of the {held} that held on their ladder, {held_same}; {len(subsets)} distinct subsets among the "
          f"outcomes; counted at the sweep before settling: {sum(r.cap_hit for r in res)}; {time.time() - t0:.0f} s")


if __name__ == "__main__":
    main()
