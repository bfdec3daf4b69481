"""Progress that tells the truth (nbst.progress), and logs: whole lines in a file or a pipe (no
carriage returns), a redrawn line on a terminal, an ETA only from measured rates, a final line
that is the summary's state, and a warm set-up that says nothing about compiling."""
import io
import subprocess
import sys
from pathlib import Path

import pytest

from nbst import progress
from nbst.progress import Bar, count_text, progress_bar, seconds_text

ROOT = Path(__file__).resolve().parents[1]
NBST = [sys.executable, "-m", "nbst.cli"]


class Tty(io.StringIO):
    def isatty(self):
        return True


@pytest.fixture
def clock(monkeypatch):
    """A clock the test moves by hand: ``clock.t += 5``."""
    class C:
        t = 1000.0

        def __call__(self):
            return self.t
    c = C()
    monkeypatch.setattr(progress, "_now", c)
    return c


def test_a_pipe_gets_whole_lines_from_the_first_moment_to_the_last(clock):
    out = io.StringIO()
    bar = Bar("solve p", 2000, unit="trial", file=out, interval=0.0, ticker=False)
    clock.t += 0.5
    bar.update(500)
    bar.note("best cost 3.5")
    clock.t += 0.5
    bar.update(1500)
    bar.close()
    bar.close()  # idempotent: one final line
    lines = out.getvalue().splitlines()
    assert "\r" not in out.getvalue()
    assert lines[0] == "solve p: 0/2,000 trials (0%) in 0.00 s"  # at once, before any work is done
    assert lines[1] == "solve p: 500/2,000 trials (25%) in 0.50 s"
    assert lines[-1] == "solve p: 2,000/2,000 trials (100%) in 1.00 s, best cost 3.5"
    assert len(lines) == 4


def test_a_terminal_gets_one_redrawn_line_that_ends_with_the_final_state(clock):
    out = Tty()
    bar = progress_bar(total=3, file=out, desc="x", unit="frame", ticker=False)
    assert isinstance(bar, Bar) and bar.tty
    clock.t += 1
    bar.update(3)
    bar.close()
    text = out.getvalue()
    assert text.startswith("\rx: 0/3 frames (0%) in 0.00 s") and text.endswith("x: 3/3 frames (100%) in 1.00 s\n")
    assert text.count("\n") == 1  # one line, redrawn


def test_no_eta_before_the_rate_is_measured_after_the_warm_up(clock):
    """Compiling before the first update (10 s here) is not in the rate: the ETA comes from the
    work measured after it, and only once ETA_MIN_S seconds of it are measured."""
    bar = Bar("render", 100, unit="frame", file=io.StringIO(), ticker=False)
    clock.t += 10.0  # the warm-up: nothing done
    bar.update(1)  # the first frame ends the warm-up
    assert bar.eta() is None
    clock.t += progress.ETA_MIN_S / 2
    bar.update(9)
    assert bar.eta() is None and "ETA" not in bar.line()  # not measured long enough
    clock.t += progress.ETA_MIN_S  # 40 frames over 1.5 ETA_MIN_S s after the first
    bar.update(30)
    rate = 39 / (1.5 * progress.ETA_MIN_S)
    assert bar.eta() == pytest.approx(60 / rate)  # the warm-up's 10 s would have made it ~4x longer
    assert f"ETA {seconds_text(60 / rate)}" in bar.line()
    assert bar.line().count("ETA") == 1


def test_the_eta_follows_the_recent_rate_and_a_bound_has_none(clock):
    bar = Bar("s", 10_000, unit="trial", file=io.StringIO(), ticker=False)
    bar.update(1)
    for _ in range(40):  # 40 s at 10 trials/s
        clock.t += 1
        bar.update(10)
    for _ in range(40):  # then 40 s at 100 trials/s
        clock.t += 1
        bar.update(100)
    left = 10_000 - bar.n
    assert bar.eta() == pytest.approx(left / 100, rel=0.05)  # the last ETA_WINDOW_S seconds' rate
    budget = Bar("s", 10_000, unit="trial", file=io.StringIO(), ticker=False, bound=True)
    budget.update(1)
    clock.t += 60
    budget.update(5000)
    assert budget.eta() is None and "of at most 10,000 trials" in budget.line() and "%" not in budget.line()


def test_the_final_line_is_the_state_the_summary_quotes(clock):
    out = io.StringIO()
    bar = Bar("nbst validate: MuJoCo, fixed steps", 20_000, unit="step", file=out, ticker=False,
              start=clock.t - 0.3)  # the command's clock started 0.3 s before the bar was made
    clock.t += 1.0
    bar.update(19_500)
    bar.close(n=20_000, end=clock.t + 0.03)
    clock.t += 5  # later reads do not move it
    summary = f"{count_text(bar.n)} steps in {seconds_text(bar.seconds)}"
    assert summary == "20,000 steps in 1.33 s"
    assert out.getvalue().splitlines()[-1] == "nbst validate: MuJoCo, fixed steps: 20,000/20,000 steps (100%) in 1.33 s"


def test_quiet_prints_nothing_but_still_counts(clock):
    out = io.StringIO()
    bar = Bar("x", 10, file=out, quiet=True)
    clock.t += 2
    bar.update(4)
    bar.close()
    assert out.getvalue() == "" and bar.n == 4 and bar.seconds == 2.0


def test_the_ticker_keeps_a_silent_stage_alive(monkeypatch):
    monkeypatch.setattr(progress, "TICK_S", 0.05)
    out = Tty()
    bar = Bar("compiling", None, unit=None, file=out)
    import time

    time.sleep(0.4)
    bar.close()
    assert out.getvalue().count("\r") >= 3  # redrawn while nothing was updated
    assert out.getvalue().endswith("\n")


def test_a_log_gets_the_first_line_soon_and_a_short_stage_only_its_last(monkeypatch):
    import time

    monkeypatch.setattr(progress, "FIRST_LINE_S", 0.2)
    out = io.StringIO()
    Bar("short", 5, unit="step", file=out).close(n=5)
    assert out.getvalue().splitlines() == [out.getvalue().splitlines()[-1]] and "5/5 steps (100%)" in out.getvalue()
    out = io.StringIO()
    bar = Bar("long", 5, unit="step", file=out)
    time.sleep(0.6)  # a stage that runs: its first line comes after FIRST_LINE_S, before any update
    assert out.getvalue().startswith("long: 0/5 steps (0%) in ")
    bar.close()
    out = io.StringIO()  # a bar on the command's clock, made after FIRST_LINE_S (loading took long): at once
    bar = Bar("render", 5, unit="frame", file=out, start=progress.command_start() - 1.0)
    time.sleep(0.1)
    assert out.getvalue().startswith("render: 0/5 frames (0%) in ")
    bar.close()


def test_solve_into_a_log_has_no_carriage_returns(tmp_path):
    out = subprocess.run(NBST + ["solve", "diamond-s14-tiny", "-o", str(tmp_path / "s.json"), "--seed", "1",
                                 "--jobs", "1"], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    assert "\r" not in out.stderr
    assert "1,000,000 trials" in out.stderr  # the progress line carries its total


def test_a_second_warm_up_says_nothing():
    subprocess.run([sys.executable, "-m", "nbst.warmup", "-q"], cwd=ROOT, check=True, timeout=600)
    out = subprocess.run([sys.executable, "-m", "nbst.warmup"], cwd=ROOT, capture_output=True, text=True,
                         timeout=600)
    assert out.returncode == 0
    assert "compiling" not in out.stderr and out.stdout == ""
