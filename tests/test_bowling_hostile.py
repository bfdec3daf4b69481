"""Hostile inputs and honest output for ``nbst bowl`` (issue 35, round 4 and the small things).

One test per class of failure the audit found: integers too large for a float in every bowling
file (a throw file, a throw atlas, the foul-line search's checkpoint, a 5 m throw file), the
frame pool outliving a parent killed by SIGKILL, ``--cluster`` pointed at an HTTP server, and
what the commands say: a flag named once, the ``--robust`` ladder stated in one line and in the
file (``--require-robust``), and progress whose last line is the summary's.
"""
from __future__ import annotations

import json
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from procs import children, running
from test_hardening_cluster import http_server  # noqa: F401 (the fixture: an HTTP server on loopback)

ROOT = Path(__file__).resolve().parents[1]
NBST = [sys.executable, "-m", "nbst.cli"]
BIG = "9" * 400  # a JSON integer the core reader takes (at most 400 digits) and a float cannot hold


def _main(argv, capsys):
    from nbst.cli import main

    rc = main([str(a) for a in argv])
    cap = capsys.readouterr()
    return rc, cap.out, cap.err


def _one_line(rc, err, *words):
    assert rc == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    for w in words:
        assert w in lines[0], (w, lines[0])


def _with_big(text: str, key: str) -> str:
    """``text`` (JSON) with the first number after ``"key":`` replaced by a 400-digit integer."""
    return re.sub(rf'("{key}":\s*)-?[0-9.eE+-]+', lambda m: m.group(1) + BIG, text, count=1)


# --------------------------------------------------------------------------- integers too large for a float

@pytest.fixture(scope="module")
def throw_file(tmp_path_factory):
    """A foul-line throw file, as ``bowl frame -o`` writes it."""
    from nbst.models.bowling.lane import frame, throwfile

    d = tmp_path_factory.mktemp("throw")
    from nbst.models.bowling import lane

    r = frame.run_frame(lane.Delivery(board=10.0, at="arrows"), "house")
    p = d / "t.json"
    p.write_text(throwfile.dumps(throwfile.throw_dict(r, oil="house")))
    return p


@pytest.mark.parametrize("key,field", [("rpm", "delivery.rpm"), ("weight_lb", "ball.weight_lb")])
def test_a_throw_file_with_a_400_digit_integer_is_one_line(throw_file, tmp_path, capsys, key, field):
    bad = tmp_path / "bad.json"
    bad.write_text(_with_big(throw_file.read_text(), key))
    assert BIG in bad.read_text()
    rc, _, err = _main(["bowl", "replay", bad], capsys)
    _one_line(rc, err, field, "too large (400 digits)")


def test_a_5m_throw_file_with_a_320_digit_integer_in_qpos0_is_one_line(tmp_path, capsys):
    import shutil

    from nbst.models.bowling.deck import throwfile as deckfile

    atlas = json.loads(Path(deckfile.SHIPPED_ATLAS).read_text())
    d = atlas["shots"][0]
    d["qpos0"][3] = int("7" * 320)
    shutil.copyfile(deckfile.SHIPPED_SCENE, tmp_path / "scene.xml")
    (tmp_path / "t.json").write_text(json.dumps(d))
    rc, _, err = _main(["bowl", "replay", tmp_path / "t.json"], capsys)
    _one_line(rc, err, "qpos0[3]", "too large (320 digits)")
    rc, _, err = _main(["render", tmp_path / "t.json", "-o", tmp_path / "v.png", "--still", "0.1"], capsys)
    _one_line(rc, err, "qpos0[3]", "too large")


@pytest.mark.parametrize("mutate, field", [
    (lambda d: d.__setitem__("timestep", 10 ** 300), "timestep"),
    (lambda d: d.__setitem__("hamming", 11), "hamming"),
    (lambda d: d.__setitem__("found", 1), "found"),
    (lambda d: d["launch"].__setitem__("speed", 1e300), "launch.speed"),
    (lambda d: d["robustness"].__setitem__("lateral_m", -1.0), "robustness.lateral_m"),
    (lambda d: d["robustness"].__setitem__("speed_m_s_rollouts", 10 ** 300), "robustness.speed_m_s_rollouts"),
])
def test_a_5m_throw_file_s_recorded_outputs_go_to_their_domain(tmp_path, capsys, mutate, field):
    """Every field of a 5 m throw, the recorded outputs beside the replayed state too, is checked
    to its domain (issue 45): one line naming the file and the field, exit 2."""
    import shutil

    from nbst.models.bowling.deck import throwfile as deckfile

    d = json.loads(Path(deckfile.SHIPPED_ATLAS).read_text())["shots"][0]
    mutate(d)
    shutil.copyfile(deckfile.SHIPPED_SCENE, tmp_path / "scene.xml")
    (tmp_path / "t.json").write_text(json.dumps(d))
    rc, _, err = _main(["bowl", "replay", tmp_path / "t.json"], capsys)
    _one_line(rc, err, f"t.json: {field}:")


def test_a_5m_atlas_s_seed_and_count_go_to_their_domain(tmp_path):
    import shutil

    from nbst.models.bowling.deck import throwfile as deckfile

    shutil.copyfile(deckfile.SHIPPED_SCENE, tmp_path / "scene.xml")
    for key, value in (("seed", -1), ("seed", 2 ** 63), ("subsets", 1024), ("subsets", "all")):
        a = json.loads(Path(deckfile.SHIPPED_ATLAS).read_text())
        a[key] = value
        (tmp_path / "atlas.json").write_text(json.dumps(a))
        with pytest.raises(deckfile.ThrowFileError, match=f"atlas.json: {key}:"):
            deckfile.load_atlas(tmp_path / "atlas.json")


def test_a_foul_line_atlas_or_checkpoint_with_a_400_digit_integer_is_one_line(tmp_path, capsys):
    """``bowl atlas --foul-line`` resumes from DIR/archive.json and DIR/foul_atlas.json: a huge
    integer in either is refused in one line before any frame runs."""
    from nbst.models.bowling.lane import atlas as foul_atlas

    out = tmp_path / "A"
    out.mkdir()
    good = json.loads(Path(foul_atlas.SHIPPED).read_text())
    (out / "foul_atlas.json").write_text(_with_big(json.dumps(good), "rpm"))
    rc, _, err = _main(["bowl", "atlas", "--foul-line", "--out-dir", out, "--max-rollouts", "0", "-q"], capsys)
    _one_line(rc, err, "foul_atlas.json", "too large (400 digits)")
    (out / "foul_atlas.json").unlink()
    doc = {"format": foul_atlas.ARCHIVE_FORMAT, "version": foul_atlas.ARCHIVE_VERSION, "seed": 1,
           "keys": [*foul_atlas.KEYS, "hand"], "rollouts": int(BIG), "elites": {}}
    (out / "archive.json").write_text(json.dumps(doc))
    rc, _, err = _main(["bowl", "atlas", "--foul-line", "--out-dir", out, "--max-rollouts", "0", "-q"], capsys)
    _one_line(rc, err, "archive.json", "rollouts", "too large (400 digits)")


# --------------------------------------------------------------------------- the pool dies with its parent

@pytest.mark.slow
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads the process table from /proc")
@pytest.mark.parametrize("argv", [["bowl", "frame", "--probability", "40"],
                                  ["bowl", "solve", "--foul-line", "--leave", "7,10", "-o", "t.json"],
                                  ["bowl", "atlas", "--foul-line", "--out-dir", "A"]],
                         ids=["frame", "solve", "atlas"])
def test_the_frame_pool_dies_with_its_command_killed_by_sigkill(tmp_path, argv):
    """``bowl frame --probability``, ``bowl solve --foul-line`` and ``bowl atlas --foul-line`` run
    their frames in worker processes (--jobs 2); after SIGKILL of the command (which cannot be
    handled) the workers must go too."""
    proc = subprocess.Popen([*NBST, *argv, "--jobs", "2", "-q"], cwd=tmp_path,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    t0 = time.monotonic()
    kids: list = []
    try:
        while time.monotonic() - t0 < 120 and proc.poll() is None:
            kids = [k for k in children(proc.pid) if running(k)]
            if len(kids) >= 2:
                break
            time.sleep(0.1)
        assert len(kids) >= 2, "the frame pool did not start"
        time.sleep(0.5)
        kids = [k for k in children(proc.pid) if running(k)]
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait()
    t1 = time.monotonic()
    while time.monotonic() - t1 < 10 and any(running(k) for k in kids):
        time.sleep(0.1)
    assert not [k for k in kids if running(k)], "frame workers outlived their parent"


# --------------------------------------------------------------------------- --cluster at the wrong place

@pytest.mark.slow
def test_bowl_cluster_at_an_http_server_is_one_line_in_seconds(http_server, tmp_path, capsys, monkeypatch):
    """``bowl atlas`` and ``bowl solve`` go through nbst.cluster.connect: its timeout and its line."""
    from nbst import cluster

    http_server = f"tcp://{http_server}"
    monkeypatch.setattr(cluster, "CONNECT_TIMEOUT_S", 1.0)
    monkeypatch.setattr(cluster, "SPEAKS_FIRST_S", 0.5)
    for argv in (["bowl", "atlas", "--out-dir", tmp_path / "A", "--cluster", http_server, "-q"],
                 ["bowl", "solve", "--down", "1", "-o", tmp_path / "s.json", "--cluster", http_server, "-q"]):
        t0 = time.monotonic()
        rc, _, err = _main(argv, capsys)
        assert time.monotonic() - t0 < 10
        _one_line(rc, err, http_server, "HTTP server")
        assert err.count(f"cluster {http_server}") == 1, err  # said once


# --------------------------------------------------------------------------- what the commands say

def test_a_bad_leave_names_its_flag_once(capsys):
    with pytest.raises(SystemExit) as e:
        _main(["bowl", "solve", "--leave", "11", "-o", "x.json"], capsys)
    err = capsys.readouterr().err
    assert e.value.code == 2 and err.count("--leave") == 1, err
    assert "pins must be numbers 1..10" in err


@pytest.mark.parametrize("argv", [["bowl", "frame", "--leave", "10,10", "-o", "x.json"],
                                  ["bowl", "frame", "--leave", "10,7,10", "-o", "x.json"]])
def test_a_pin_named_twice_is_refused_as_advise_refuses_it(argv, capsys):
    """A coach's `bowl frame --leave 10,10` ran as the 10 alone and 10,7,10 as the 7-10, where
    `bowl advise` refused them; every pin list now refuses a pin named twice, in one line."""
    rc, _, err = _main(argv, capsys)
    _one_line(rc, err, "pin 10 named twice")
    rc, _, err = _main(["bowl", "advise", "--leave", "10,10"], capsys)
    _one_line(rc, err, "pin 10 named twice")
    rc, _, err = _main(["bowl", "advise", "--leave", "11"], capsys)
    _one_line(rc, err, "pins must be numbers 1..10, each once")


def test_bowl_help_describes_both_halves_in_their_units(capsys):
    with pytest.raises(SystemExit):
        _main(["bowl", "--help"], capsys)
    text = " ".join(capsys.readouterr().out.split())
    for words in ("delivery is what the bowler does", "foul line", "board", "mph", "rpm", "axis rotation",
                  "5 m", "spin"):
        assert words in text, words


def test_bowl_throw_crosses_the_arrows_on_the_board_asked(capsys):
    """--at arrows is aimed along the ball's real path: the readout's arrows board is the one asked
    (to 0.01 board), for the typical release and a 450 rpm hook that bends 2 boards before them."""
    for extra in ([], ["--rpm", "450", "--rotation", "60", "--oil", "sport"]):
        rc, out, err = _main(["bowl", "throw", "--board", "10", "--at", "arrows", "--json", *extra], capsys)
        assert rc == 0, err
        doc = json.loads(out)
        assert abs(doc["board_at_arrows"] - 10.0) <= 0.01 and doc["delivery"]["at"] == "foul"
        assert doc["board_at_foul_line"] == pytest.approx(doc["delivery"]["board"], abs=0.02)


def test_a_ladder_row_whose_kept_flag_contradicts_its_leave_is_one_line(throw_file, tmp_path, capsys):
    d = json.loads(throw_file.read_text())
    d["ladder"] = [{"timestep": 0.001, "leave": d["outcome"]["leave"], "kept": False}]
    bad = tmp_path / "k.json"
    bad.write_text(json.dumps(d))
    rc, _, err = _main(["bowl", "replay", bad], capsys)
    _one_line(rc, err, "ladder[0].kept", "says false")


def _final_bar_line(err: str, desc: str) -> str:
    return [line for line in err.splitlines() if line.startswith(desc + ":")][-1]


@pytest.mark.slow
def test_5m_solve_progress_ends_on_the_summary_s_count_and_clock(tmp_path, capsys):
    """The bar's last line and the summary quote the same rollouts and the same seconds (one clock,
    the command's); a budget is a bound, so no ETA is shown."""
    rc, _, err = _main(["bowl", "solve", "--down", "1,2,3", "--no-atlas", "--max-rollouts", "48", "--seed", "2",
                        "--jobs", "1", "--no-robustness", "-o", tmp_path / "s.json"], capsys)
    assert rc in (0, 1), err
    last = _final_bar_line(err, "bowl solve down 1,2,3")
    summary = err.strip().splitlines()[-1]
    n, secs = re.search(r"^bowl solve down 1,2,3: ([\d,]+) of at most [\d,]+ rollouts in ([\d.]+ s)", last).groups()
    assert f"after {n} rollout" in summary and f"in {secs}," in summary, (last, summary)
    assert "ETA" not in err


@pytest.mark.slow
def test_foul_line_solve_states_its_ladder_and_require_robust_exits_by_it(tmp_path, capsys):
    """The written throw's ladder says which timesteps keep its outcome (``kept``, per row), the
    summary line says it in words, and --require-robust exits 1 exactly when not every timestep
    keeps it. The progress bar's last line quotes the summary's frames and seconds."""
    from nbst.models.bowling.lane import throwfile
    from nbst.models.mjsearch.ladder import kept_text

    out = tmp_path / "t.json"
    rc, _, err = _main(["bowl", "solve", "--foul-line", "--leave", "7,10", "--samples", "2", "--seed", "1",
                        "--jobs", "1", "--require-robust", "-o", out], capsys)
    d = throwfile.load(out)
    steps, kept = throwfile.ladder_kept(d)
    assert steps == [0.001, 0.0005, 0.00025] and all("kept" in x for x in d["ladder"])
    assert kept_text(steps, kept) in err
    assert rc == (0 if kept == steps else 1), err
    if rc == 1:
        assert "--require-robust" in err
    last = _final_bar_line(err, "bowl solve leave 7,10")
    n, secs = re.search(r": ([\d,]+) of at most [\d,]+ frames in ([\d.]+ s)", last).groups()
    assert f"; {n} frames in {secs};" in err, (last, err)


@pytest.mark.slow
def test_a_5m_atlas_folder_says_which_throw_files_it_skips(tmp_path, capsys):
    """A damaged subset file in an atlas folder is skipped and said, one line naming the file and
    its field, never silently dropped; the command still runs (the search may find it again)."""
    from nbst.models.bowling.deck import throwfile as deckfile

    out = tmp_path / "A"
    argv = ["bowl", "atlas", "--out-dir", out, "--max-rollouts", "0", "--no-robustness", "-q", "--jobs", "1"]
    rc, _, err = _main(argv, capsys)
    assert rc == 0 and "skipped" not in err, err
    d = json.loads(Path(deckfile.SHIPPED_ATLAS).read_text())["shots"][0]
    d["scene"] = "scene.xml"
    d["qpos0"][3] = int("7" * 320)
    name = "subset-" + "_".join(map(str, d["down"])) + ".json"
    (out / name).write_text(json.dumps(d))
    (out / "subset-0_11.json").write_text("{}")
    rc, _, err = _main(argv, capsys)
    said = [ln for ln in err.splitlines() if "skipped" in ln]
    assert rc == 0 and len(said) == 2, err
    assert any(name in ln and "qpos0[3]" in ln and "too large" in ln for ln in said), said
    assert any("subset-0_11.json" in ln and "pins 1-10" in ln for ln in said), said


@pytest.mark.slow
def test_5m_solve_progress_names_the_leave_that_was_asked(tmp_path, capsys):
    """--leave 7,10 asks for the pins left standing: the bar names the leave, not the eight pins
    knocked down (issue 45); the shipped atlas holds the 7-10, so one rollout confirms it."""
    rc, _, err = _main(["bowl", "solve", "--leave", "7,10", "--max-rollouts", "4", "--seed", "1", "--jobs", "1",
                        "--no-robustness", "-o", tmp_path / "s.json"], capsys)
    assert rc == 0, err
    bars = [line for line in err.splitlines() if line.startswith("bowl solve ")]
    assert bars and all(line.startswith("bowl solve leave 7,10:") for line in bars), err
    assert "1,2,3,4,5,6,8,9" not in "".join(bars)
