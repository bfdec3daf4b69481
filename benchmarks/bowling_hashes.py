"""Bit-for-bit check of bowling's results: hashes of what the bowl commands write, small budgets.

Runs each ``nbst bowl`` command below in a fresh folder with a fixed seed and prints a SHA-256
(first 16 hex digits) of what it wrote: the 5 m shot files (``bowl solve``, three methods of
``bowl atlas``), the foul-line throw files (``bowl solve --foul-line``, ``--robust``), the
``bowl frame --probability`` outputs, a foul-line atlas, ``bowl spares`` and ``bowl pocket``. A
refactor that keeps every result keeps every hash. The first case hashes MuJoCo's binary models
of the 5 m deck and the full lane (the one scene path must build the same models). Fields that measure the machine, not the
result (``wall_time_s``, the ``jobs`` or ``cluster`` that ran it, the run's seconds in a summary),
are dropped before hashing; summary.md (its seconds) and PNGs are not hashed.

    python benchmarks/bowling_hashes.py --save before.json      # record
    python benchmarks/bowling_hashes.py --compare before.json   # after a change: exit 1 on a difference

About 8 minutes of CPU on 2 cores (most of it foul-line frames at ~0.5 s each).
"""
from __future__ import annotations

import argparse
import hashlib
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

NBST = [sys.executable, "-m", "nbst.cli"]
#: Keys that measure the machine or the run's wiring, not the result.
VOLATILE = {"wall_time_s", "jobs", "cluster"}


def _clean(o):
    if isinstance(o, dict):
        return {k: _clean(v) for k, v in o.items() if k not in VOLATILE}
    if isinstance(o, list):
        return [_clean(v) for v in o]
    return o


def digest(paths) -> str:
    """SHA-256 over the files (JSON files cleaned of VOLATILE keys, then dumped sorted)."""
    h = hashlib.sha256()
    for p in paths:
        p = Path(p)
        h.update(p.name.encode())
        data = p.read_bytes()
        if p.suffix == ".json":
            data = json.dumps(_clean(json.loads(data)), sort_keys=True).encode()
        h.update(data)
    return h.hexdigest()[:16]


#: The compiled scenes (the 5 m deck, the full lane with and without pins, another oil, ball and
#: delivery): MuJoCo's binary model of each, hashed (the one scene path must build the same models).
MODELS = """
import hashlib, mujoco, numpy as np
from nbst.models.bowling import lane, scene
build = getattr(lane, "lane_spec", None) or lane.build_spec
specs = [scene.build_spec(), build(), build(pins=False),
         build(lane.Ball(weight_lb=14, rg=2.6, diff=0.05, friction=0.25),
               lane.Delivery(hand="left", board=30, angle=-1, rpm=400, rotation=70, tilt=30))]
for spec in specs:
    m = spec.compile()
    buf = np.zeros(mujoco.mj_sizeModel(m), dtype=np.uint8)
    mujoco.mj_saveModel(m, None, buf)
    print(hashlib.sha256(buf.tobytes()).hexdigest())
"""


def run(argv, cwd, ok=(0, 1)) -> str:
    cmd = [sys.executable, "-c", MODELS] if argv == ["models"] else [*NBST, *argv]
    p = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True)
    if p.returncode not in ok:
        sys.exit(f"{' '.join(argv)}: exit {p.returncode}\n{p.stderr[-2000:]}")
    return p.stdout


def cases():
    """(name, argv, files to hash (relative to the run's folder), hash stdout too)."""
    yield ("scene models (MJB bytes)", ["models"], [], "text")
    yield ("deck solve --down 1,2,4", ["bowl", "solve", "--down", "1,2,4", "--seed", "3", "--max-rollouts", "200",
                                       "--no-atlas", "--jobs", "2", "-o", "s.json", "-q"], ["s.json", "s.scene.xml"], False)
    yield ("deck solve --distance geometry --jobs 1", ["bowl", "solve", "--down", "1,2,4", "--seed", "3",
                                                        "--max-rollouts", "200", "--no-atlas", "--jobs", "1",
                                                        "--distance", "geometry", "-o", "s.json", "-q"],
           ["s.json"], False)
    yield ("deck solve --leave 7,10 (shipped atlas)", ["bowl", "solve", "--leave", "7,10", "--seed", "1",
                                                       "--jobs", "2", "-o", "s.json", "-q"], ["s.json"], False)
    yield ("deck solve --leave 2,10 (atlas restarts)", ["bowl", "solve", "--leave", "2,10", "--seed", "2",
                                                         "--max-rollouts", "120", "--no-robustness", "--jobs", "2",
                                                         "-o", "s.json", "-q"], ["s.json"], False)
    yield ("deck atlas elites", ["bowl", "atlas", "--out-dir", "A", "--max-rollouts", "400", "--seed", "2", "--jobs", "2",
                                 "-q"], ["A/atlas.json", "A/summary.csv"], False)
    yield ("deck atlas targeted", ["bowl", "atlas", "--out-dir", "A", "--method", "targeted", "--max-rollouts", "300",
                                   "--per-subset", "40", "--seed", "5", "--no-robustness", "--jobs", "2", "-q"],
           ["A/atlas.json"], False)
    yield ("deck atlas uniform", ["bowl", "atlas", "--out-dir", "A", "--method", "uniform", "--max-rollouts", "96",
                                  "--seed", "7", "--no-robustness", "--jobs", "2", "-q"], ["A/atlas.json"], False)
    yield ("throw --json", ["bowl", "throw", "--board", "10", "--json"], [], True)
    yield ("frame --probability 8 --timesteps", ["bowl", "frame", "--probability", "8", "--timesteps", "--seed", "3",
                                                 "--jobs", "2", "-o", "t.json", "--json", "-q"], ["t.json"], True)
    yield ("frame --leave 10 --probability 6", ["bowl", "frame", "--leave", "10", "--board", "30", "--at", "foul",
                                                "--angle", "-1", "--rpm", "200", "--rotation", "0",
                                                "--probability", "6", "--seed", "2", "--jobs", "1", "--json", "-q"],
           [], True)
    yield ("foul solve --down 1,2,4,5 (search)", ["bowl", "solve", "--foul-line", "--down", "1,2,4,5", "--no-atlas",
                                                  "--max-rollouts", "32", "--samples", "4", "--seed", "5",
                                                  "--jobs", "2", "-o", "t.json", "-q"], ["t.json"], False)
    yield ("foul solve --leave 7,10 (shipped)", ["bowl", "solve", "--foul-line", "--leave", "7,10", "--samples", "4",
                                                 "--seed", "1", "--jobs", "2", "-o", "t.json", "-q"], ["t.json"], False)
    yield ("foul solve --robust 60 --leave 10", ["bowl", "solve", "--robust", "60", "--leave", "10", "--samples", "4",
                                                 "--seed", "1", "--jobs", "2", "-o", "t.json", "-q"], ["t.json"], False)
    yield ("foul atlas", ["bowl", "atlas", "--foul-line", "--out-dir", "F", "--max-rollouts", "32", "--samples", "2",
                          "--seed", "4", "--jobs", "2", "-q"],
           ["F/foul_atlas.json", "F/archive.json", "F/checks.json"], False)
    yield ("spares 10", ["bowl", "spares", "--leaves", "10", "--screen", "2", "--samples", "4", "--polish", "24",
                         "--seed", "1", "--jobs", "2", "--json", "-q"], [], True)
    yield ("pocket 17.5 x 5", ["bowl", "pocket", "--boards", "17.5:17.5:1", "--angles", "5:5:1", "--samples", "4",
                               "--seed", "1", "--jobs", "2", "-o", "p.png", "--json", "-q"], [], True)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0], allow_abbrev=False)
    ap.add_argument("--save", metavar="FILE", help="write the hashes as JSON")
    ap.add_argument("--compare", metavar="FILE", help="compare with saved hashes; exit 1 on any difference")
    ap.add_argument("-k", default="", help="only the cases whose name contains this text")
    ap.add_argument("--resume", action="store_true", help="with --save: keep the cases already in FILE, run the rest")
    ap.add_argument("--ignore", action="append", default=[], metavar="KEY",
                    help="also drop this JSON key before hashing (e.g. a field a change added on purpose)")
    args = ap.parse_args()
    VOLATILE.update(args.ignore)
    old = json.loads(Path(args.compare).read_text()) if args.compare else {}
    got, differ = {}, []
    if args.resume and args.save and Path(args.save).exists():
        got = json.loads(Path(args.save).read_text())
    t_all = time.perf_counter()
    for name, argv, files, stdout in cases():
        if args.k not in name or name in got:
            continue
        with tempfile.TemporaryDirectory() as tmp:
            t0 = time.perf_counter()
            out = run(argv, tmp)
            paths = [Path(tmp) / f for f in files]
            h = digest(paths)
            if stdout == "text":
                h = hashlib.sha256(out.encode()).hexdigest()[:16]
            elif stdout:
                doc = _clean(json.loads(out))
                doc.pop("output", None)
                h = hashlib.sha256((h + json.dumps(doc, sort_keys=True)).encode()).hexdigest()[:16]
            got[name] = h
        mark = ""
        if name in old:
            mark = "same" if old[name] == h else f"DIFFERENT (was {old[name]})"
            if old[name] != h:
                differ.append(name)
        print(f"{name:<44} {h}  {time.perf_counter() - t0:6.1f} s  {mark}", flush=True)
        if args.save:
            Path(args.save).write_text(json.dumps(got, indent=1) + "\n")
    print(f"{len(got)} cases in {time.perf_counter() - t_all:.0f} s" + (f"; {len(differ)} differ" if old else ""))
    return 1 if differ else 0


if __name__ == "__main__":
    os.environ.setdefault("PYTHONHASHSEED", "0")
    sys.exit(main())
