"""Regenerate the "Experiments (issue 5)" numbers and figures of docs/results/disks.md.

    python benchmarks/results_experiments.py [--out nbst-experiments] [--workers 2] [--cluster ADDRESS]

Runs exactly the commands quoted in docs/results/disks.md (finished runs under OUT/runs are
reused, so a second call only redraws), generates the planted sets with ``nbst generate``
and copies the figures to docs/figures/. The tables are printed and left in OUT/*.md.
About 15 minutes on 2 busy cores.
"""
from __future__ import annotations

import argparse
import shutil
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PLANTED = {"planted6": ("--planted", "6", "--radius", "20"),
           "planted5k2": ("--planted", "5", "--noncue", "2", "--radius", "15"),
           "planted12": ("--planted", "12", "--noncue", "2", "--radius", "25")}


def main(argv=None) -> int:
    from nbst.cli import main as nbst

    ap = argparse.ArgumentParser(allow_abbrev=False, description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="nbst-experiments")
    ap.add_argument("--workers", default="2")
    ap.add_argument("--cluster", default=None)
    a = ap.parse_args(argv)
    out = Path(a.out)
    common = ["--out", str(out), "--workers", a.workers] + (["--cluster", a.cluster] if a.cluster else [])
    for name, flags in PLANTED.items():
        (out / name).mkdir(parents=True, exist_ok=True)
        for s in range(1, 9):
            f = out / name / f"{name.replace('planted', 'p')}-s{s}.json"
            if not f.exists():
                assert nbst(["generate", *flags, "--seed", str(s), "-o", str(f)]) == 0
    commands = [
        ["ablation", "diamond-s14", "--runs", "5", "--trials", "400000"],
        ["ablation", "over5", "--runs", "5", "--trials", "400000"],
        ["curves", "diamond-s14", "--runs", "6", "--trials", "400000", "--algorithms", "A,nbst,cma"],
        ["curves", "over5", "--runs", "6", "--trials", "400000", "--algorithms", "A,nbst,cma"],
        ["compare", str(out / "planted6"), "--trials", "100000", "--name", "planted6"],
        ["compare", str(out / "planted5k2"), "--trials", "100000", "--name", "planted5k2"],
        ["compare", str(out / "planted12"), "--trials", "100000", "--target-cost", "1", "--name", "planted12"],
    ]
    for c in commands:
        print(f"\n$ nbst experiment {' '.join(c)}", flush=True)
        if nbst(["experiment", *c, *common]) != 0:
            return 1
    figs = ROOT / "docs" / "figures"
    figs.mkdir(parents=True, exist_ok=True)
    for kind in ("ablation", "curves"):
        for prob in ("diamond-s14", "over5"):
            for ext in ("png", "svg"):
                shutil.copy(out / f"{kind}-{prob}.{ext}", figs / f"{kind}-{prob}.{ext}")
    print(f"\nfigures copied to {figs}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
