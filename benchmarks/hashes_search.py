"""Solution hashes of fixed runs: what a refactoring of the search must leave unchanged, bit for bit.

    .venv/bin/python benchmarks/hashes_search.py            # prints one line per case
    .venv/bin/python benchmarks/hashes_search.py --json F   # and writes them to F

Each case runs ``nbst solve`` as a user would (a subprocess of the command line) with a fixed
seed, jobs and budget, and prints two sha256 digests (12 hex digits):

* ``v``: the bytes of the written velocities as float64 (N, 2), C order;
* ``file``: the written solution file, its keys in the order written, minus the wall-clock
  fields (``wall_time`` and ``trials_per_s``, at any depth), dumped as compact JSON.

The cases: diamond-s14 (seed 1, the default search and budget, one process and two islands),
over5 with variants A and nbst (200,000 trials, seed 1; nbst's portfolio on one core and on two),
the baseline cma (20,000 trials), and a planted 250-disk problem (``nbst generate --planted 250
--seed 1``; the many-body search, 3,000 trials, seed 1). Takes a few minutes of one core.
"""
from __future__ import annotations

import argparse
import hashlib
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

NBST = [sys.executable, "-m", "nbst.cli"]
#: Fields that hold wall-clock readings: they differ from run to run by design.
CLOCK_FIELDS = ("wall_time", "trials_per_s")

CASES = [
    ("diamond-s14 default, jobs 1", "diamond-s14", ["--seed", "1", "--jobs", "1"]),
    ("diamond-s14 default, jobs 2", "diamond-s14", ["--seed", "1", "--jobs", "2"]),
    ("over5 A 200k, jobs 1", "over5", ["--variant", "A", "--seed", "1", "--max-trials", "200000", "--jobs", "1"]),
    ("over5 nbst 200k, jobs 1", "over5", ["--variant", "nbst", "--seed", "1", "--max-trials", "200000",
                                          "--jobs", "1"]),
    ("over5 nbst 200k, jobs 2", "over5", ["--variant", "nbst", "--seed", "1", "--max-trials", "200000",
                                          "--jobs", "2"]),
    ("over5 nbst-noplan 200k, jobs 1", "over5", ["--variant", "nbst-noplan", "--seed", "2", "--max-trials",
                                                 "200000", "--jobs", "1"]),
    ("diamond-s14 cma 20k, jobs 1", "diamond-s14", ["--algorithm", "cma", "--seed", "1", "--max-trials", "20000",
                                                    "--jobs", "1"]),
    ("planted 250 many-body 3000, jobs 1", "@planted250", ["--seed", "1", "--max-trials", "3000", "--jobs", "1"]),
]


def strip_clock(x):
    """``x`` without the wall-clock fields, at any depth (key order kept)."""
    if isinstance(x, dict):
        return {k: strip_clock(v) for k, v in x.items() if k not in CLOCK_FIELDS}
    if isinstance(x, list):
        return [strip_clock(v) for v in x]
    return x


def digests(path: Path) -> tuple[str, str]:
    import numpy as np

    d = json.loads(path.read_text())
    v = np.asarray(d["velocities"], dtype=np.float64)
    hv = hashlib.sha256(np.ascontiguousarray(v).tobytes()).hexdigest()[:12]
    hf = hashlib.sha256(json.dumps(strip_clock(d), separators=(",", ":")).encode()).hexdigest()[:12]
    return hv, hf


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(allow_abbrev=False, description=__doc__.split("\n\n")[0])
    ap.add_argument("--json", default=None, help="also write the digests to this JSON file")
    ap.add_argument("--only", default=None, help="run only the cases whose label contains this text")
    args = ap.parse_args(argv)
    out = {}
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        planted = tmp / "planted250.json"
        subprocess.run([*NBST, "generate", "--planted", "250", "--seed", "1", "-o", str(planted), "-q"], check=True)
        for label, problem, flags in CASES:
            if args.only and args.only not in label:
                continue
            sol = tmp / "sol.json"
            t0 = time.perf_counter()
            p = str(planted) if problem == "@planted250" else problem
            r = subprocess.run([*NBST, "solve", p, "-o", str(sol), "-q", *flags], capture_output=True, text=True)
            if r.returncode != 0:
                print(f"{label}: exit {r.returncode}: {r.stderr.strip()[-300:]}", file=sys.stderr)
                return 1
            hv, hf = digests(sol)
            cost = json.loads(sol.read_text())["cost"]
            out[label] = {"velocities": hv, "file": hf}
            print(f"{label:36s} v {hv}  file {hf}  cost {cost:.6g}  ({time.perf_counter() - t0:.0f} s)", flush=True)
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
