"""Signals at the edges of the long commands (issue 23).

Each long command (solve with one and two islands, render, experiment, validate) is sent 2-3
signals drawn from SIGINT, SIGTERM and SIGHUP, at random gaps of 0-100 ms, once its work has
started. Whatever the sequence: the command exits 130 without a traceback, no partial file
(``.NAME.partial-PID...``) is left anywhere, no worker process outlives it, and the result file is
whole: the best solution so far for ``solve``, the previous file untouched for ``render``, only
complete run files for ``experiment``. SIGKILL cannot be handled: after it, the island workers of
``solve --jobs 2`` must still die with their parent (the experiment's pool workers: see
tests/test_hardening_outputs.py).

The draws are seeded (one seed per case), so a failure replays with the same signals and gaps;
the timing of the process under test is the machine's.
"""
from __future__ import annotations

import json
import os
import random
import select
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from procs import children, running

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"),
                                reason="reads the process table from /proc; SIGHUP and ptys are POSIX")

NBST = [sys.executable, "-m", "nbst.cli"]
STOP = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)
#: A problem that nbst's search does not solve exactly within a few seconds: it keeps searching.
HARD = "over5"
#: Two slow disks: a long, cheap video (with a small --speed) and a long MuJoCo run.
SLOW = {"name": "slow", "box": [400.0, 400.0], "t_final": 2.0, "target_radius": 30.0, "disks": [
    {"start": [100.0, 200.0], "target": [300.0, 200.0], "radius": 10.0},
    {"start": [300.0, 100.0], "target": [100.0, 200.0], "radius": 10.0}]}


def _slow_files(tmp_path, t_final=2.0, speed=20.0):
    p = tmp_path / "p.json"
    p.write_text(json.dumps(dict(SLOW, t_final=t_final)))
    s = tmp_path / "s.json"
    s.write_text(json.dumps({"problem": "slow", "velocities": [[speed, 0.0], [0.0, speed]]}))
    return str(p), str(s)


def _wait_for(cond, timeout: float) -> bool:
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        if cond():
            return True
        time.sleep(0.02)
    return False


class Run:
    """A command in a subprocess, its stderr on a pseudo-terminal (so progress bars draw at once)."""

    def __init__(self, argv, cwd):
        import fcntl
        import pty
        import struct
        import termios

        self.master, slave = pty.openpty()
        fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 160, 0, 0))
        # a crash prints Python's stack (faulthandler), so a rare one says where it happened
        self.proc = subprocess.Popen([*NBST, *argv], cwd=cwd, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                     stderr=slave, env=dict(os.environ, PYTHONFAULTHANDLER="1"))
        os.close(slave)
        self.err = b""

    def read(self, timeout: float = 0.05) -> None:
        while select.select([self.master], [], [], timeout)[0]:
            try:
                chunk = os.read(self.master, 65536)
            except OSError:  # the other end closed
                return
            if not chunk:
                return
            self.err += chunk
            timeout = 0

    def wait_output(self, text: bytes, timeout: float = 90) -> bool:
        t0 = time.monotonic()
        while time.monotonic() - t0 < timeout:
            self.read(0.1)
            if text in self.err:
                return True
            if self.proc.poll() is not None:
                self.read(0)
                return text in self.err
        return False

    def signals(self, rng: random.Random) -> list:
        """2-3 stop signals at random 0-100 ms gaps, after a random 0-300 ms pause."""
        time.sleep(rng.uniform(0.0, 0.3))
        sent = []
        for _ in range(rng.choice((2, 3))):
            sig = rng.choice(STOP)
            try:
                self.proc.send_signal(sig)
            except ProcessLookupError:
                break
            sent.append(signal.Signals(sig).name)
            time.sleep(rng.uniform(0.0, 0.1))
        return sent

    def finish(self, timeout: float = 60) -> tuple[int, str]:
        t0 = time.monotonic()
        while self.proc.poll() is None and time.monotonic() - t0 < timeout:
            self.read(0.1)
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGABRT)  # faulthandler prints where every thread is
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
            self.read(0.5)
            pytest.fail(f"still running {timeout} s after the signals; stderr: {self.err.decode(errors='replace')[-3000:]}")
        self.read(0)
        os.close(self.master)
        return self.proc.returncode, self.err.decode("utf-8", "replace")


def _no_partials(root: Path) -> None:
    left = [str(p) for p in root.rglob("*") if ".partial-" in p.name or p.name == "MUJOCO_LOG.TXT"]
    assert not left, left


def _check_exit(rc: int, err: str, sent) -> None:
    assert "Traceback" not in err, (sent, err[-2000:])
    assert rc == 130, (sent, rc, err[-1000:])


# --------------------------------------------------------------------------- solve

@pytest.mark.parametrize("jobs, case", [(1, 0), (1, 1), (1, 2), (2, 3)])
def test_solve_writes_the_best_so_far_whatever_the_signals(tmp_path, jobs, case):
    rng = random.Random(1000 + case)
    out = tmp_path / "sol.json"
    out.write_text("old")
    run = Run(["solve", HARD, "-o", str(out), "--jobs", str(jobs), "--max-trials", "1000000000", "--patience", "0",
               "--target-cost", "0", "--seed", str(case)], tmp_path)
    assert run.wait_output(b"trial"), run.err.decode(errors="replace")[-500:]  # the search reports progress
    if jobs > 1:
        assert _wait_for(lambda: children(run.proc.pid), 60), "no island worker started"
    kids = children(run.proc.pid)
    sent = run.signals(rng)
    rc, err = run.finish()
    _check_exit(rc, err, sent)
    from nbst import load_problem, load_solution

    sol = load_solution(out, load_problem(HARD))  # the whole new file, not the old one
    assert sol.meta["stopped"] == "interrupted", (sent, sol.meta["stopped"])
    assert "best so far written" in err, (sent, err[-500:])
    _no_partials(tmp_path)
    assert _wait_for(lambda: not any(running(k) for k in kids), 10), (sent, kids)


@pytest.mark.slow
@pytest.mark.parametrize("delay", [0.5, 2.0, 8.0])
def test_solve_writes_the_best_motion_so_far_at_any_moment(tmp_path, monkeypatch, delay):
    """Issue 35, item 5: a signal at any moment after the problem is read writes the best motion so
    far, the straight start included (before any search result: at 0.5 s the numba load or the
    backward planner may still run). ``--jobs 1`` on over5: nbst's portfolio, planner first. The
    first line comes at once (issue 35, item 4: within 2 s), and the bar's last state is the
    summary's."""
    import re

    from nbst import load_problem, load_solution, simulate

    out = tmp_path / "sol.json"
    monkeypatch.setenv("COLUMNS", "250")  # a terminal wide enough for the whole bar
    t0 = time.monotonic()
    run = Run(["solve", HARD, "-o", str(out), "--jobs", "1", "--max-trials", "1000000000", "--patience", "0",
               "--target-cost", "0", "--seed", "3"], tmp_path)
    while not run.err and run.proc.poll() is None and time.monotonic() - t0 < 30:
        run.read(0.01)
    first = time.monotonic() - t0
    assert first < 2.0, f"the first line came after {first:.2f} s"  # the problem is read by now
    while time.monotonic() - t0 < delay:
        run.read(0.01)
    run.proc.send_signal(signal.SIGINT)
    rc, err = run.finish()
    _check_exit(rc, err, ["SIGINT"])
    p = load_problem(HARD)
    sol = load_solution(out, p)
    m = sol.meta
    assert m["stopped"] == "interrupted" and m["seed"] == 3 and "best so far written" in err
    # the recorded cost is the motion's own (as nbst simulate sees it; the two kernels agree to round-off)
    assert m["cost"] == pytest.approx(simulate(p, sol.velocities).cost, rel=1e-9, abs=1e-9)
    bar = re.findall(r"best cost ([0-9.e+-]+), (\d)/5 disks on target", err.split("nbst solve:")[0])
    summary = re.search(r"nbst solve: interrupted; best so far written: cost ([0-9.e+-]+), (\d)/5", err)
    assert bar and summary and bar[-1] == summary.groups(), (bar[-3:], err[-600:])
    _no_partials(tmp_path)


def test_solve_islands_die_with_their_parent_on_sigkill(tmp_path):
    proc = subprocess.Popen([*NBST, "solve", HARD, "-o", str(tmp_path / "sol.json"), "--jobs", "2", "--max-trials",
                             "1000000000", "--patience", "0", "--target-cost", "0", "-q"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        assert _wait_for(lambda: children(proc.pid), 90), "no island worker started"
        kids = children(proc.pid)
        time.sleep(0.3)
    finally:
        proc.kill()
        proc.wait()
    # PR_SET_PDEATHSIG kills them at once; the getppid watchdog within half a second
    assert _wait_for(lambda: not any(running(k) for k in kids), 10), [k for k in kids if running(k)]


# --------------------------------------------------------------------------- render

@pytest.mark.parametrize("case", [0, 1])
def test_render_leaves_the_previous_video_and_no_partial_file(tmp_path, case):
    rng = random.Random(2000 + case)
    p, s = _slow_files(tmp_path)
    out = tmp_path / "v.mp4"
    out.write_bytes(b"the previous video")
    run = Run(["render", p, s, "-o", "v.mp4", "--speed", "0.002", "--size", "32x32", "-q"], tmp_path)
    started = _wait_for(lambda: list(tmp_path.glob(".v.partial-*.mp4")) or run.proc.poll() is not None, 90)
    if run.proc.poll() is not None:
        rc, err = run.finish()
        pytest.skip(f"render did not start here (no OpenGL?): rc {rc}: {err[-300:]}")
    assert started
    sent = run.signals(rng)
    rc, err = run.finish()
    _check_exit(rc, err, sent)
    assert out.read_bytes() == b"the previous video", sent
    _no_partials(tmp_path)


# --------------------------------------------------------------------------- experiment

def test_experiment_keeps_only_whole_run_files(tmp_path):
    rng = random.Random(3000)
    p, _ = _slow_files(tmp_path)
    exp = tmp_path / "exp"
    # short runs finish (and are written) while others run: the signals land among writes
    run = Run(["experiment", "curves", p, "--runs", "40", "--max-trials", "3000", "--algorithms", "A,random",
               "--jobs", "2", "--out-dir", str(exp), "-q"], tmp_path)
    assert _wait_for(lambda: len(list(exp.glob("runs/*/*/*.json"))) >= 2 or run.proc.poll() is not None, 120)
    assert run.proc.poll() is None, run.finish()
    kids = children(run.proc.pid)
    sent = run.signals(rng)
    rc, err = run.finish()
    _check_exit(rc, err, sent)
    files = list(exp.glob("runs/*/*/*.json"))
    assert files
    for f in files:
        d = json.loads(f.read_text())
        assert d["kind"] == "nbst-experiment-run" and "history" in d, f
    _no_partials(tmp_path)
    assert _wait_for(lambda: not any(running(k) for k in kids), 10), (sent, kids)


# --------------------------------------------------------------------------- validate

def test_validate_writes_no_partial_report(tmp_path):
    rng = random.Random(4000)
    p, s = _slow_files(tmp_path, t_final=20.0, speed=5.0)
    rep = tmp_path / "rep"
    run = Run(["validate", p, s, "--convergence", "--timestep", "0.0002", "--max-steps", "100000000",
               "--out-dir", str(rep)], tmp_path)
    assert run.wait_output(b"convergence"), run.err.decode(errors="replace")[-500:]
    sent = run.signals(rng)
    rc, err = run.finish()
    if rc == 0:  # finished before the signals: then the report is whole
        json.loads((rep / "report.json").read_text())
    else:
        _check_exit(rc, err, sent)
        for f in ("report.json", "report.html"):
            assert not (rep / f).exists() or (rep / f).stat().st_size > 0
    _no_partials(tmp_path)


# --------------------------------------------------------------------------- the handler itself

def test_interrupt_once_raises_once_then_lets_the_cleanup_finish(monkeypatch):
    from nbst import outputs

    monkeypatch.setattr(outputs, "INSIST_S", 0.5)
    before = {s: signal.getsignal(s) for s in STOP}
    cleaned = []
    with outputs.interrupt_once():
        with pytest.raises(KeyboardInterrupt):
            os.kill(os.getpid(), signal.SIGHUP)  # handled like Ctrl-C
            time.sleep(1)
        for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):  # a cleanup under more signals
            os.kill(os.getpid(), sig)
            time.sleep(0.01)
        cleaned.append(True)
        with outputs.signals_deferred() as got:  # a write: held, and not raised again afterwards
            os.kill(os.getpid(), signal.SIGINT)
            cleaned.append(True)
        assert got == [signal.SIGINT]
        time.sleep(0.6)  # past INSIST_S: a signal stops the work again (the first may have been swallowed)
        with pytest.raises(KeyboardInterrupt):
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(1)
    assert cleaned == [True, True]
    assert {s: signal.getsignal(s) for s in STOP} == before  # restored


def test_a_signal_during_a_deferred_write_stops_the_work_after_it():
    from nbst import outputs

    with outputs.interrupt_once():
        with pytest.raises(KeyboardInterrupt):
            with outputs.signals_deferred():
                os.kill(os.getpid(), signal.SIGTERM)
                written = True
        assert written
        os.kill(os.getpid(), signal.SIGINT)  # the cleanup that follows is not cut short
        time.sleep(0.01)
