"""Progress that tells the truth, command by command: the last line of each progress bar says the
count and the seconds that the command's summary says (issue 35: validate's headline said 20,024
steps in 12.30 s while its stepping line said 0.60 s; render printed "ETA 1 s, ETA 1 s").

Each command runs in-process with stderr captured (not a terminal: whole lines). To cover a new
command that shows progress, add a function that runs it and returns (bar lines, summary).
"""
from __future__ import annotations

import json
import re

import pytest

from nbst.cli import main

#: The final line of a bar: "DESC: N/TOTAL UNITs (100%) in T s[, note]" or "DESC: N UNITs in T s".
FINAL = re.compile(r"^(?P<desc>.+?): (?P<n>[\d,]+)(?:/| of at most )?(?P<total>[\d,]*) (?P<unit>\w+)"
                   r"(?: \(\d+%\))? in (?P<t>[\d.]+ s)(?:, (?P<note>.*))?$")


def _finals(err: str) -> dict:
    """{bar description: its last line's match} over the progress lines of ``err``."""
    out = {}
    for line in err.splitlines():
        m = FINAL.match(line)
        if m:
            out[m["desc"]] = m
    return out


@pytest.fixture
def over5_sol(tmp_path):
    p = tmp_path / "s.json"
    assert main(["solve", "over5", "-o", str(p), "--seed", "1", "--max-trials", "3000", "--jobs", "1", "-q"]) == 0
    return str(p)


def test_validate_headline_is_its_bar(over5_sol, capsys):
    """--stepping aligned --convergence: the headline's steps of h and seconds are the MuJoCo bar's,
    not the whole validation's; the stepping line repeats no other time; every bar ends at 100%."""
    assert main(["validate", "over5", over5_sol, "--stepping", "aligned", "--convergence", "--timestep", "0.005"]) == 0
    cap = capsys.readouterr()
    bars = _finals(cap.err)
    run = bars["nbst validate: MuJoCo, aligned steps"]
    head = cap.out.splitlines()[0]
    assert f"aligned: {run['n']} steps of h (" in head and head.endswith(f" in {run['t']}"), (head, run.group(0))
    assert all(m["n"] == m["total"] for m in bars.values())  # every stage ended where its bar said it would
    assert len([d for d in bars if "convergence" in d]) >= 5
    stepping = [ln for ln in cap.out.splitlines() if ln.startswith("stepping   aligned:") and "micro-steps" in ln]
    assert stepping and not re.search(r"\d s\b", stepping[0])  # no second clock
    assert "ETA" not in cap.err


def test_validate_report_says_the_same_seconds(over5_sol, tmp_path, capsys):
    assert main(["validate", "over5", over5_sol, "--convergence", "--timestep", "0.005", "--json"]) == 0
    cap = capsys.readouterr()
    d = json.loads(cap.out)
    run = _finals(cap.err)["nbst validate: MuJoCo, fixed steps"]
    from nbst.progress import seconds_text

    assert seconds_text(d["mujoco"]["wall_time_s"]) == run["t"]
    assert d["mujoco"]["validate_wall_time_s"] >= d["mujoco"]["wall_time_s"]


def test_render_bar_ends_where_the_summary_does(over5_sol, tmp_path, capsys):
    pytest.importorskip("moderngl")
    out = tmp_path / "v.mp4"
    assert main(["render", "over5", over5_sol, "-o", str(out), "--size", "128x72", "--fps", "6"]) == 0
    err = capsys.readouterr().err
    bar = _finals(err)[f"nbst render: {out.name}"]
    summary = [ln for ln in err.splitlines() if ln.startswith(f"nbst render: wrote {out}")][0]
    assert bar["n"] == bar["total"] and f": {bar['n']} frames," in summary and f" in {bar['t']}" in summary
    assert all(ln.count("ETA") <= 1 for ln in err.splitlines())  # "ETA 1 s, ETA 1 s" was two


def test_mjcf_bar_counts_every_disk(tmp_path, capsys, monkeypatch):
    pytest.importorskip("mujoco")
    import nbst.cli.mujoco as M

    monkeypatch.setattr(M, "MJCF_PROGRESS_MIN_N", 1)
    out = tmp_path / "s.xml"
    assert main(["mjcf", "diamond-s14", "-o", str(out)]) == 0
    err = capsys.readouterr().err
    bar = _finals(err)["nbst mjcf: building the scene"]
    assert bar["n"] == bar["total"] == "14" and "(14 disks;" in err


def test_generate_stage_bars_end_at_their_totals(tmp_path, capsys, monkeypatch):
    import nbst.cli.generate as G

    monkeypatch.setattr(G, "LONG_STAGE_S", 0.0)  # every stage shows its bar
    assert main(["generate", "--targets-from", "hi", "--disks", "60", "--seed", "1", "-o", str(tmp_path / "f.json")]) == 0
    cap = capsys.readouterr()
    bars = _finals(cap.err)
    assert bars and all(m["total"] == "" or m["n"] == m["total"] for m in bars.values()), cap.err
    m = re.search(r"(\d+) swap passes", cap.out)
    sweeps = [b for d, b in bars.items() if b["unit"] == "sweeps"]
    if m and sweeps:
        assert sweeps[-1]["n"] == m.group(1)  # the bar's passes are the summary's


# solve and bowl solve: their commands are H1's and H2's (issue 35, items 4-5); both use nbst.progress.

def test_solve_bar_ends_where_the_summary_does(tmp_path, capsys):
    assert main(["solve", "over5", "-o", str(tmp_path / "s.json"), "--max-trials", "3000", "--jobs", "1",
                 "--seed", "1"]) == 0
    err = capsys.readouterr().err
    bar = [m for d, m in _finals(err).items() if d.startswith("solve over5")][-1]
    summary = [ln for ln in err.splitlines() if ln.startswith("nbst solve: cost")][0]
    m = re.search(r"after ([\d,]+) trials in ([\d.]+ s)", summary)
    assert m and m.group(1).replace(",", "") == bar["n"].replace(",", "") and m.group(2) == bar["t"], \
        (bar.group(0), summary)
    assert bar["note"].split(",")[0].replace("best cost", "cost") in summary


@pytest.mark.slow
def test_bowl_solve_bar_ends_where_the_summary_does(tmp_path, capsys):
    """It said "1/3,000 rollouts ... 0.72 s" and then "1 launch ... in 0.1 s" (issue 35)."""
    pytest.importorskip("mujoco")
    assert main(["bowl", "solve", "--leave", "7,10", "-o", str(tmp_path / "shot.json"), "--seed", "1"]) == 0
    err = capsys.readouterr().err
    bar = list(_finals(err).values())[-1]
    summary = [ln for ln in err.splitlines() if ln.startswith("nbst bowl solve:")][-1]
    m = re.search(r"after ([\d,]+) rollouts", summary)
    assert m and m.group(1) == bar["n"] and f" in {bar['t']}," in summary, (bar.group(0), summary)
    assert "ETA" not in err  # a budget it stops short of: no ETA over it


# crash solve, crash reconstruct and render CRASH.json: the crash commands are issue 32's; crash
# solve's summary now quotes its bar's count and clock (it said "(54 s)" under a bar at 54.2 s).

#: A short two-car crossing (A eastbound meets B northbound in about 1.6 s; B's rest is evidence).
CRASH = {
    "kind": "nbst-crash-script", "name": "short",
    "road": {"layout": "intersection", "width": 7, "length": 80},
    "duration": 2.5,
    "vehicles": [
        {"name": "A", "type": "sedan", "start": {"x": -22, "y": -1.75, "heading": 0}, "speed": [45, 55],
         "driver": {"aim": {"x": [0, 4], "y": -1.75}, "arrive": [1.5, 1.8], "after_impact": "brake"},
         "fate": {"hits": ["B"], "rest": {"x": 5, "y": 5, "radius": 40}}},
        {"name": "B", "type": "suv", "start": {"x": 1.75, "y": -22, "heading": 90}, "speed": [45, 55],
         "driver": {"aim": {"x": 1.75, "y": [-2, 2]}, "arrive": [1.5, 1.8]},
         "fate": {"hits": ["A"], "rest": {"x": 5, "y": 5, "radius": 40}}},
    ],
}


@pytest.fixture(scope="module")
def crash_script(tmp_path_factory):
    pytest.importorskip("mujoco")
    p = tmp_path_factory.mktemp("crash") / "short.json"
    p.write_text(json.dumps(CRASH))
    return p


@pytest.fixture(scope="module")
def crash_file(crash_script):
    out = crash_script.parent / "crash.json"
    assert main(["crash", "solve", str(crash_script), "-o", str(out), "--seed", "1", "--max-rollouts", "24",
                 "--jobs", "1", "--no-ladder", "-q"]) in (0, 1)
    return out


@pytest.mark.slow
def test_crash_solve_bar_ends_where_the_summary_does(crash_script, tmp_path, capsys):
    rc = main(["crash", "solve", str(crash_script), "-o", str(tmp_path / "c.json"), "--seed", "1", "--max-rollouts",
               "24", "--jobs", "1", "--no-ladder"])
    assert rc in (0, 1)
    err = capsys.readouterr().err
    bar = _finals(err)["crash short"]
    summary = [ln for ln in err.splitlines() if ln.startswith("crash short: ") and " after " in ln][-1]
    rollouts = json.loads((tmp_path / "c.json").read_text())["search"]["rollouts"]
    assert bar["n"] == f"{rollouts:,}" and f"after {bar['n']} rollouts in {bar['t']}," in summary, (bar.group(0), summary)
    assert "ETA" not in err  # a budget it may stop short of: no ETA over it


@pytest.mark.slow
def test_crash_reconstruct_bar_ends_where_the_summary_does(crash_script, tmp_path, capsys):
    rc = main(["crash", "reconstruct", str(crash_script), "-o", str(tmp_path / "r.json"), "--seed", "1",
               "--max-rollouts", "24", "--jobs", "1"])
    assert rc in (0, 1)
    cap = capsys.readouterr()
    bar = _finals(cap.err)["reconstruct short"]
    m = re.search(r"in ([\d,]+) rollouts", cap.out)
    assert m and m.group(1) == bar["n"], (bar.group(0), cap.out)


@pytest.mark.slow
def test_render_crash_bar_ends_where_the_summary_does(crash_file, tmp_path, capsys):
    pytest.importorskip("moderngl")
    out = tmp_path / "c.mp4"
    assert main(["render", str(crash_file), "-o", str(out), "--size", "64x48", "--fps", "4", "--hold", "0"]) == 0
    err = capsys.readouterr().err
    bar = _finals(err)[f"nbst render: {out.name}"]
    summary = [ln for ln in err.splitlines() if ln.startswith(f"nbst render: wrote {out}")][0]
    assert bar["n"] == bar["total"] and f": {bar['n']} frames," in summary and f" in {bar['t']};" in summary, \
        (bar.group(0), summary)
    assert all(ln.count("ETA") <= 1 for ln in err.splitlines())
