"""Hardening of the command line: bounded work, output paths, full disks, signals.

Each class of failure a tester found has one test here: special files and symlinks as
``-o``, a full disk (ENOSPC simulated by monkeypatching the write), an output that is
the command's own input, a huge t_final for ``validate`` / ``render``, and cleanup after
SIGTERM / SIGKILL (render's partial video, experiment's worker processes).
"""
from __future__ import annotations

import errno
import json
import os
import signal
import stat
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from procs import children, running

from nbst.cli import main
from nbst.outputs import (OutputError, partial_path, refuse_same_file, remove_stale_partials, signals_deferred,
                          write_text_atomic)

NBST = [sys.executable, "-m", "nbst.cli"]
#: Problem with slow disks: a huge t_final stays within the simulator's event cap.
SLOW = {"name": "slow", "box": [400.0, 400.0], "t_final": 2.0, "target_radius": 30.0, "disks": [
    {"start": [100.0, 200.0], "target": [300.0, 200.0], "radius": 10.0},
    {"start": [300.0, 100.0], "target": [100.0, 200.0], "radius": 10.0}]}


def _files(tmp_path, t_final=2.0, speed=1.0):
    d = dict(SLOW, t_final=t_final)
    p = tmp_path / "p.json"
    p.write_text(json.dumps(d))
    s = tmp_path / "s.json"
    s.write_text(json.dumps({"problem": "slow", "velocities": [[speed, 0.0], [0.0, speed]]}))
    return str(p), str(s)


def _one_line_error(capsys) -> str:
    err = capsys.readouterr().err.strip()
    assert err and "\n" not in err and "Traceback" not in err, err
    return err


def _dead_pid() -> int:
    p = subprocess.Popen([sys.executable, "-c", "pass"])
    p.wait()
    return p.pid


# --------------------------------------------------------------------------- special files, symlinks

def test_fifo_and_device_outputs_are_refused_never_replaced(tmp_path, capsys):
    fifo = tmp_path / "pipe.json"
    os.mkfifo(fifo)
    assert main(["generate", "--planted", "2", "--seed", "1", "-o", str(fifo)]) == 2
    assert "FIFO" in _one_line_error(capsys)
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)
    with pytest.raises(OutputError, match="character device"):
        write_text_atomic(os.devnull, "x")
    assert main(["generate", "--planted", "2", "--seed", "1", "-o", os.devnull]) == 2
    assert "character device" in _one_line_error(capsys)
    assert stat.S_ISCHR(os.lstat(os.devnull).st_mode)


# symbolic links, FIFOs and folders for every command: tests/test_hardening_links.py


# --------------------------------------------------------------------------- full disk

@pytest.fixture
def full_disk(monkeypatch):
    """Every os.write to a regular file fails with ENOSPC, as on a full disk (pipes still work)."""
    real = os.write

    def write(fd, data):
        if stat.S_ISREG(os.fstat(fd).st_mode):
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return real(fd, data)

    monkeypatch.setattr(os, "write", write)


def test_full_disk_is_one_line_exit_2_and_keeps_the_previous_file(tmp_path, capsys, full_disk, monkeypatch):
    out = tmp_path / "prob.json"
    out.write_bytes(b"previous\n")
    assert main(["generate", "--planted", "2", "--seed", "1", "-o", str(out)]) == 2
    assert "No space left on device" in _one_line_error(capsys)
    assert out.read_bytes() == b"previous\n"
    assert sorted(f.name for f in tmp_path.iterdir()) == ["prob.json"]  # no partial file left

    # a writer that wants a file name (matplotlib): a half-written figure must not replace the old one
    import nbst.render.figures as figures

    def savefig_then_fail(fig, path, dpi=None):
        Path(path).write_bytes(b"\x89PNG half")
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(figures, "save_figure", savefig_then_fail)
    png = tmp_path / "fig.png"
    png.write_bytes(b"old png")
    assert main(["plot", "problem", "over5", "-o", str(png)]) == 2
    assert "No space left on device" in _one_line_error(capsys)
    assert png.read_bytes() == b"old png"


def test_full_disk_mjcf_keeps_the_previous_scene(tmp_path, capsys, full_disk):
    pytest.importorskip("mujoco")
    out = tmp_path / "scene.xml"
    out.write_bytes(b"<mujoco/>\n")
    assert main(["mjcf", "over5", "-o", str(out)]) == 2
    assert "No space left on device" in _one_line_error(capsys)
    assert out.read_bytes() == b"<mujoco/>\n"


# --------------------------------------------------------------------------- output == input

def test_output_equal_to_input_is_refused(tmp_path, capsys):
    x = tmp_path / "x.json"
    assert main(["generate", "--planted", "2", "--seed", "1", "-o", str(x), "--solution", str(x)]) == 2
    assert "same file" in _one_line_error(capsys)
    assert not x.exists()
    p, s = _files(tmp_path)
    before = Path(s).read_bytes()
    alias = tmp_path / "alias.json"
    alias.symlink_to(s)
    pytest.importorskip("mujoco")
    for target in (s, str(alias)):
        assert main(["mjcf", p, s, "-o", target]) == 2
        assert "same file" in _one_line_error(capsys)
    assert Path(s).read_bytes() == before
    refuse_same_file(tmp_path / "over5", ["over5"])  # a built-in problem name is not a file: no clash
    before_p = Path(p).read_bytes()
    assert main(["solve", p, "-o", p, "--max-trials", "10", "-q"]) == 2  # solve P.json -o P.json
    assert "same file" in _one_line_error(capsys)
    assert Path(p).read_bytes() == before_p


def test_solve_full_disk_is_one_line_and_keeps_the_previous_file(tmp_path, capsys, full_disk):
    out = tmp_path / "sol.json"
    out.write_bytes(b"previous\n")
    assert main(["solve", "diamond-s14-tiny", "-o", str(out), "--seed", "1", "-q"]) == 2
    assert "No space left on device" in _one_line_error(capsys)
    assert out.read_bytes() == b"previous\n"


# --------------------------------------------------------------------------- bounded work

def test_huge_t_final_is_refused_up_front(tmp_path, capsys):
    p, s = _files(tmp_path, t_final=1e6, speed=1e-3)
    t0 = time.perf_counter()
    assert main(["render", p, s, "-o", str(tmp_path / "v.mp4")]) == 2
    err = _one_line_error(capsys)
    assert "--max-frames" in err and "60,000,061 frames" in err
    assert not list(tmp_path.glob("*.mp4")) and not list(tmp_path.glob(".v.*"))
    pytest.importorskip("mujoco")
    assert main(["validate", p, s]) == 2
    assert "--max-steps" in _one_line_error(capsys)
    assert time.perf_counter() - t0 < 30.0  # refused before any simulation (was: 298 GiB, 60M frames)


# --------------------------------------------------------------------------- signals and leftovers

def test_stale_partial_files_of_dead_writers_are_removed(tmp_path):
    target = tmp_path / "out.json"
    dead = _dead_pid()
    stale = [tmp_path / f".out.partial-{dead}.json", tmp_path / f".out.partial-{dead}-a1b2c3.json"]
    live = partial_path(target)  # this process's: alive, kept
    other = tmp_path / f".other.partial-{dead}.json"  # another target's: not ours to judge here
    for f in (*stale, live, other):
        f.write_text("x")
    write_text_atomic(target, "new")
    assert target.read_text() == "new"
    assert not any(f.exists() for f in stale) and live.exists() and other.exists()
    assert remove_stale_partials(tmp_path / "other.json") == [other]


def test_video_writer_removes_stale_partial_videos(tmp_path):
    from nbst.render.core.video import VideoWriter

    stale = tmp_path / f".v.partial-{_dead_pid()}.mp4"
    stale.write_bytes(b"half a video")
    with VideoWriter(tmp_path / "v.mp4", (16, 16), 10) as w:
        w.submit(np.zeros((16, 16, 3), np.uint8))
    assert not stale.exists() and (tmp_path / "v.mp4").stat().st_size > 0


def test_signals_deferred_holds_ctrl_c_until_the_write_is_done(tmp_path):
    out = tmp_path / "best.json"
    before = signal.getsignal(signal.SIGINT)  # Python's handler, or SIG_IGN when run in the background
    with pytest.raises(KeyboardInterrupt):
        with signals_deferred() as got:
            os.kill(os.getpid(), signal.SIGINT)
            write_text_atomic(out, "written")
            assert got == [signal.SIGINT]
    assert out.read_text() == "written"
    assert signal.getsignal(signal.SIGINT) is before  # restored


def _wait_for(cond, timeout):
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        if cond():
            return True
        time.sleep(0.05)
    return False


def test_render_sigterm_removes_its_partial_video(tmp_path):
    p, s = _files(tmp_path, t_final=2.0, speed=20.0)
    proc = subprocess.Popen([*NBST, "render", p, s, "-o", "v.mp4", "--speed", "0.002", "--size", "32x32", "-q"],
                            cwd=tmp_path, stderr=subprocess.PIPE, text=True,
                            env=dict(os.environ, PYTHONFAULTHANDLER="1"))  # a crash says where
    started = _wait_for(lambda: list(tmp_path.glob(".v.partial-*.mp4")) or proc.poll() is not None, 60)
    if proc.poll() is not None:
        pytest.skip(f"render did not start here (no OpenGL?): {proc.stderr.read()[-300:]}")
    assert started
    proc.send_signal(signal.SIGTERM)
    rc = proc.wait(30)
    err = proc.stderr.read()
    assert rc == 130, err[-3000:]
    assert "interrupted" in err
    assert not list(tmp_path.glob(".v.*")) and not (tmp_path / "v.mp4").exists()


@pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")
def test_a_stop_signal_dropped_in_a_finalizer_still_ends_the_video(tmp_path):
    """Python drops a KeyboardInterrupt raised while a ``__del__`` runs ("Exception ignored"): a
    signal that lands there must still end the render, with no video and no partial file."""
    import gc

    from nbst.outputs import interrupt_once, stop_requested
    from nbst.render.core.video import VideoWriter, encode

    class Finalized:
        def __del__(self):
            os.kill(os.getpid(), signal.SIGINT)  # the handler runs here; its exception is dropped

    out = tmp_path / "v.mp4"
    frames = []
    with interrupt_once():
        with pytest.raises(KeyboardInterrupt):
            with VideoWriter(out, (16, 16), 10) as w:
                def draw(k, buf):
                    if k == 3:
                        Finalized()
                        gc.collect()
                    buf[:] = k
                    frames.append(k)
                    return None if k > 200 else buf
                encode(draw, w)
        assert stop_requested()
    assert frames == [0, 1, 2, 3]  # the next frame is not drawn
    assert not stop_requested() and list(tmp_path.iterdir()) == []


def test_ffmpeg_runs_in_its_own_process_group(tmp_path):
    """A Ctrl-C at the terminal goes to the foreground process group: it reaches nbst, which stops
    ffmpeg itself (and keeps a finished video's last write), not ffmpeg behind its back."""
    from nbst.render.core.video import VideoWriter

    with VideoWriter(tmp_path / "v.mp4", (16, 16), 10) as w:
        w.submit(np.zeros((16, 16, 3), np.uint8))
        pid = w._proc.pid
        assert os.getpgid(pid) == pid != os.getpgid(0)
    assert w._proc.returncode == 0 and (tmp_path / "v.mp4").stat().st_size > 0


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads the process table from /proc")
@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGKILL])
def test_experiment_workers_die_with_their_parent(tmp_path, sig):
    p, _ = _files(tmp_path, speed=20.0)
    proc = subprocess.Popen([*NBST, "experiment", "curves", p, "--runs", "3", "--max-trials", "1000000000",
                             "--jobs", "2", "--out-dir", str(tmp_path / "exp"), "--quiet"],
                            stderr=subprocess.PIPE, text=True)
    assert _wait_for(lambda: len(children(proc.pid)) >= 2, 60), "the worker pool did not start"
    kids = children(proc.pid)
    time.sleep(0.5)  # let the workers get into their initializer and the search
    proc.send_signal(sig)
    rc = proc.wait(30)
    assert rc == (130 if sig == signal.SIGTERM else -signal.SIGKILL)
    # PR_SET_PDEATHSIG kills them at once; the getppid watchdog within a second
    assert _wait_for(lambda: not any(running(k) for k in kids), 10), [k for k in kids if running(k)]
    if sig == signal.SIGTERM:
        err = proc.stderr.read()
        assert err.strip() == "nbst: interrupted", err


# --------------------------------------------------------------------------- videos on a full disk

def _video(tmp_path, ext, **kw):
    """A short video of over5 written by ``nbst render`` (in-process): its bytes."""
    p, s = _files(tmp_path)
    out = tmp_path / f"ok{ext}"
    assert main(["render", p, s, "-o", str(out), "--size", "96x64", "--fps", "8", "-q"]) == 0
    return out.read_bytes()


@pytest.mark.parametrize("ext", [".mp4", ".gif"])
def test_a_video_cut_short_anywhere_is_seen(tmp_path, ext):
    """check_video reads the container: a file cut at any point (a full disk) is not a whole video,
    and one with fewer frames than were sent is not the video asked for."""
    pytest.importorskip("moderngl")
    from nbst.render.core.video import check_video

    data = _video(tmp_path, ext)
    whole = tmp_path / f"whole{ext}"
    whole.write_bytes(data)
    kind = ext[1:]
    from nbst.render.core.times import frame_times

    frames = len(frame_times(2.0, 8.0, hold=1.0)) if kind == "mp4" else 1  # a GIF may merge repeated frames
    assert check_video(whole, kind, frames) is None
    cut = tmp_path / f"cut{ext}"
    for k in sorted({0, 10, 100, len(data) // 3, len(data) // 2, len(data) - 200, len(data) - 1}):
        cut.write_bytes(data[:k])
        assert check_video(cut, kind, frames), f"cut at {k} of {len(data)} bytes passed"
    if kind == "mp4":
        assert "frames" in check_video(whole, kind, frames + 1)


@pytest.mark.parametrize("ext", [pytest.param(".mp4"), pytest.param(".gif", marks=pytest.mark.slow)])
def test_a_full_disk_while_encoding_keeps_the_previous_video(tmp_path, ext):
    """A file-size limit (RLIMIT_FSIZE, a full disk for ffmpeg and for us) just under the video's
    size: the encoder's file is cut short near its end (the MP4 index), ffmpeg's exit status goes
    unreported; nbst must refuse in one line, keep the previous video and leave no partial file."""
    pytest.importorskip("moderngl")
    import resource

    old = _video(tmp_path, ext)
    p, s = _files(tmp_path)
    out = tmp_path / f"v{ext}"
    out.write_bytes(old)
    limit = len(old) - 300

    def small_disk():
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

    r = subprocess.run(NBST + ["render", p, s, "-o", str(out), "--size", "96x64", "--fps", "8", "--hold", "1.5"],
                       preexec_fn=small_disk, capture_output=True, text=True, timeout=300)
    err = [ln for ln in r.stderr.splitlines() if ln.startswith("nbst render: error")]
    assert r.returncode == 2 and len(err) == 1 and "Traceback" not in r.stderr, r.stderr
    assert "previous file is unchanged" in err[0]
    assert out.read_bytes() == old
    assert not [f.name for f in tmp_path.iterdir() if ".partial-" in f.name]


def test_out_dir_may_be_a_link_to_a_folder_but_not_to_nothing(tmp_path):
    """An --out-dir that is a link to a folder is a folder on the way (written in the folder it
    leads to, as docs/formats.md says); a link to nothing is refused by name, not as 'File exists'."""
    from nbst.errors import OutputError
    from nbst.outputs import prepare_output
    real = tmp_path / "real"
    real.mkdir()
    (tmp_path / "good").symlink_to(real)
    assert prepare_output(tmp_path / "good", directory=True, option="--out-dir").samefile(real)
    (tmp_path / "bad").symlink_to(tmp_path / "gone")
    with pytest.raises(OutputError, match=r"--out-dir .*bad: is a symbolic link to nothing"):
        prepare_output(tmp_path / "bad", directory=True, option="--out-dir")
    assert not (tmp_path / "gone").exists()


def test_an_output_name_ending_in_a_slash_is_refused_and_the_file_beside_it_kept(tmp_path, capsys):
    """``-o sol.json/`` names a folder: Path() would drop the slash and replace sol.json (a tester
    lost a solution so). Refused in one line before any work; the existing file is untouched."""
    keep = tmp_path / "sol.json"
    keep.write_text("the solution\n")
    for name in (f"{keep}/", f"{tmp_path / 'new.json'}/"):
        rc = main(["solve", "diamond-s14", "-o", name, "--seed", "1", "-q"])
        err = capsys.readouterr().err
        assert rc == 2 and "ends in a slash" in err and len(err.strip().splitlines()) == 1, err
    assert keep.read_text() == "the solution\n" and not (tmp_path / "new.json").exists()
    with pytest.raises(OutputError, match="ends in a slash"):
        from nbst.outputs import prepare_output

        prepare_output(f"{tmp_path}/x.mp4/", option="--video")
