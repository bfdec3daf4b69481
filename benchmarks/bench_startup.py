"""Start-up cost: `import nbst` and `nbst --help`, against a bare `python -c pass` measured
in the same run (median wall time of REPEATS fresh processes each, and their least CPU time
(user + system), which other load on a shared machine disturbs less; warm OS file cache).

    .venv/bin/python benchmarks/bench_startup.py [CHECKOUT]   # CHECKOUT: another tree, e.g. a git worktree
"""
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

REPEATS = 15
ROOT = Path(sys.argv[1]).resolve() if len(sys.argv) > 1 else Path(__file__).resolve().parents[1]  # or a checkout to compare


def _children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def seconds(argv: list[str]) -> tuple[float, float]:
    """(median wall seconds, least CPU seconds) over REPEATS fresh processes."""
    walls, cpus = [], []
    for _ in range(REPEATS):
        t0, c0 = time.perf_counter(), _children_cpu()
        subprocess.run(argv, cwd=ROOT, stdout=subprocess.DEVNULL, check=True)
        walls.append(time.perf_counter() - t0)
        cpus.append(_children_cpu() - c0)
    return statistics.median(walls), min(cpus)


def main() -> None:
    py = sys.executable
    base = seconds([py, "-c", "pass"])
    rows = [("python -c pass", base),
            ("import nbst", seconds([py, "-c", "import nbst"])),
            ("nbst --help", seconds([py, "-m", "nbst.cli", "--help"]))]
    print(f"checkout {ROOT}")
    print(f"{'what':<16} {'median s':>9} {'x bare python':>14} {'least CPU s':>12} {'x bare python':>14}")
    for name, (wall, cpu) in rows:
        print(f"{name:<16} {wall:9.3f} {wall / base[0]:14.1f} {cpu:12.3f} {cpu / base[1]:14.1f}")


if __name__ == "__main__":
    main()
