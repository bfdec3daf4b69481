"""Logs: progress in a file or a pipe is whole lines (no carriage returns), every bar has
a total, and a warm set-up says nothing about compiling."""
import io
import subprocess
import sys
from pathlib import Path

from nbst.progress import LineProgress, progress_bar

ROOT = Path(__file__).resolve().parents[1]
NBST = [sys.executable, "-m", "nbst.cli"]


def test_a_pipe_gets_line_progress_and_a_terminal_tqdm():
    assert isinstance(progress_bar(total=3, file=io.StringIO()), LineProgress)

    class Tty(io.StringIO):
        def isatty(self):
            return True

    bar = progress_bar(total=3, file=Tty(), desc="x")
    assert type(bar).__name__ == "tqdm"
    bar.close()


def test_line_progress_writes_whole_lines_with_the_total():
    out = io.StringIO()
    bar = LineProgress(total=2000, desc="solve p", unit="trial", file=out, interval=0.0)
    bar.update(500)
    bar.set_postfix_str("best cost 3.5")
    bar.update(1500)
    bar.close()
    bar.close()  # idempotent: one final line
    lines = out.getvalue().splitlines()
    assert "\r" not in out.getvalue()
    assert lines[0].startswith("solve p: 500/2,000 trials (25%)")
    assert lines[-1].startswith("solve p: 2,000/2,000 trials (100%)") and lines[-1].endswith("best cost 3.5")
    assert len(lines) == 3


def test_solve_into_a_log_has_no_carriage_returns(tmp_path):
    out = subprocess.run(NBST + ["solve", "diamond-s14-tiny", "-o", str(tmp_path / "s.json"), "--seed", "1",
                                 "--jobs", "1"], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    assert "\r" not in out.stderr
    assert "/1,000,000 trials" in out.stderr  # the progress line carries its total


def test_a_second_warm_up_says_nothing():
    subprocess.run([sys.executable, "-m", "nbst.warmup", "-q"], cwd=ROOT, check=True, timeout=600)
    out = subprocess.run([sys.executable, "-m", "nbst.warmup"], cwd=ROOT, capture_output=True, text=True,
                         timeout=600)
    assert out.returncode == 0
    assert "compiling" not in out.stderr and out.stdout == ""
