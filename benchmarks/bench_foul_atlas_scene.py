"""A foul-line atlas on today's lane scene: how many of its throws still give their subset.

    python benchmarks/bench_foul_atlas_scene.py [--atlas FILE] [--jobs K]

Each throw of the atlas (default the shipped ``models/bowling/lane/foul_atlas.json``; issue 22's
lane-1 atlas is ``git show ea9c7ad:models/bowling/lane/foul_atlas.json``) is thrown again, once, on
this nbst's scene (``lane.SCENE``) at h = 1 ms, and the script prints how many give their recorded
subset, how many of the throws that held on their timestep ladder do, how many distinct subsets
the re-thrown throws give, and how many frames the sweep counted before they settled. ~300
frames: ~2-5 min of CPU. The figures docs/bowling.md quotes for the lane-1 atlas on lane-2 and
lane-3 (an atlas of this scene gives every subset again: a frame is deterministic).
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
    ap.add_argument("--atlas", type=Path, default=ATLAS, help="the throw atlas (default the shipped one)")
    ap.add_argument("--jobs", type=int, default=1, help="processes running frames (default 1)")
    args = ap.parse_args()
    a = throwfile.load_atlas(args.atlas)
    ts = a["throws"]
    t0 = time.time()
    if any(sorted(t["standing"]) != list(range(1, 11)) for t in ts):
        raise SystemExit(f"{args.atlas}: every throw of the foul-line atlas is on a full rack")
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
