"""Start-up cost: `import nbst` and `nbst --help`, against a bare `python -c pass` measured
in the same run (median of REPEATS fresh processes each; warm OS file cache).

    .venv/bin/python benchmarks/bench_startup.py [CHECKOUT]   # CHECKOUT: another tree, e.g. a git worktree
"""
import statistics
import subprocess
import sys
import time
from pathlib import Path

REPEATS = 15
ROOT = Path(sys.argv[1]).resolve() if len(sys.argv) > 1 else Path(__file__).resolve().parents[1]  # or a checkout to compare


def median_seconds(argv: list[str]) -> float:
    times = []
    for _ in range(REPEATS):
        t0 = time.perf_counter()
        subprocess.run(argv, cwd=ROOT, stdout=subprocess.DEVNULL, check=True)
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def main() -> None:
    py = sys.executable
    base = median_seconds([py, "-c", "pass"])
    rows = [("python -c pass", base),
            ("import nbst", median_seconds([py, "-c", "import nbst"])),
            ("nbst --help", median_seconds([py, "-m", "nbst.cli", "--help"]))]
    print(f"{'what':<16} {'median s':>9} {'x bare python':>14}")
    for name, t in rows:
        print(f"{name:<16} {t:9.3f} {t / base:14.1f}")


if __name__ == "__main__":
    main()
