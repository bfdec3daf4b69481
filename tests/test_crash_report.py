"""The reconstructionist's report (`nbst crash report`) and the impacts it reads
(models/crash/impact.py): physical facts with stated tolerances, the page's numbers against the
library's, the page opened in headless Chromium, and bad input refused in one line.

Crash files are made as `nbst crash solve` writes them, from one rollout of a fixed script
(every intent fixed: no search)."""
from __future__ import annotations

import json
import math
import re
import shutil
import subprocess

import numpy as np
import pytest

from nbst.cli.main import main
from nbst.models.crash import crashfile, impact, run, script, space

G = 9.81
#: A 90-degree t-bone: A (sedan, 50 km/h east) into the left side of B (SUV, 5 km/h north), A braking after.
TBONE = {
    "kind": "nbst-crash-script", "name": "t-bone-90", "road": {"layout": "intersection", "width": 7, "length": 80},
    "duration": 3.0,
    "vehicles": [
        {"name": "A", "type": "sedan", "start": {"x": -22, "y": -1.75, "heading": 0}, "speed": 50,
         "driver": {"arrive": 1.6, "aim": {"x": 1.75, "y": -1.75}, "after_impact": "brake"},
         "fate": {"hits": ["B"], "impact_speed": [45, 60], "rest": {"x": 5, "y": 5, "radius": 3}}},
        {"name": "B", "type": "suv", "start": {"x": 1.75, "y": -4, "heading": 90}, "speed": 5,
         "driver": {"aim": {"x": 1.75, "y": 10}}, "fate": {"hits": ["A"], "heading": {"deg": 60, "tol": 30}}},
    ],
}
#: A full-overlap head-on on a straight road: a sedan and an SUV at 40 km/h each, the sedan braking from 1.2 s.
HEADON = {
    "kind": "nbst-crash-script", "name": "head-on", "road": {"layout": "straight", "width": 7, "length": 80},
    "duration": 2.5,
    "vehicles": [
        {"name": "A", "type": "sedan", "start": {"x": -20, "y": 0, "heading": 0}, "speed": 40,
         "driver": {"brake_at": 1.2}, "fate": {"hits": ["B"]}},
        {"name": "B", "type": "suv", "start": {"x": 20, "y": 0, "heading": 180}, "speed": 40,
         "fate": {"hits": ["A"]}},
    ],
}


def _crash_file(raw: dict, path) -> str:
    s = script.script_from_dict(json.loads(json.dumps(raw)), source=raw["name"])
    sp = space.space_of(s)
    U = np.random.default_rng(3).random((1, sp.dim))
    R = run.CrashRunner(s, jobs=1, batch=1)
    res = R.run(sp.intents(U))
    d = crashfile.crash_dict(s, R.xml, R.model, sp.intents(U)[0], res.qpos0[0], res.qvel0[0], res.controls[0],
                             res.final_qpos[0], res.outcomes[0], seed=3, period_steps=R.period)
    path.write_text(json.dumps(d, indent=1, allow_nan=False))
    return str(path)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("crash-report")
    crush = json.loads(json.dumps(TBONE))
    crush["name"] = "t-bone-crush"
    for v in crush["vehicles"]:
        v["type"] += "-crush"
    return {"t-bone": _crash_file(TBONE, tmp / "tbone.json"), "head-on": _crash_file(HEADON, tmp / "headon.json"),
            "t-bone-crush": _crash_file(crush, tmp / "tbone-crush.json")}


@pytest.fixture(scope="module")
def impacts(files):
    out = {}
    for k, f in files.items():
        d, s, m = crashfile.load(f)
        out[k] = (d, s, m, impact.crash_impacts(d, s, m))
    return out


def _off(deg: float, target: float) -> float:
    """Angular distance (deg) between two directions."""
    return abs((deg - target + 180.0) % 360.0 - 180.0)


def test_pdof_reads_the_clock_from_the_velocity_change():
    """The force points along the velocity change, so it comes from the opposite side: a change
    backwards is a frontal blow (12), to the left a blow from the right (3), forwards from behind
    (6), to the right from the left (9)."""
    assert impact.pdof_of((-1.0, 0.0)) == (0.0, 12)
    assert impact.pdof_of((0.0, 1.0)) == (90.0, 3)
    assert impact.pdof_of((1.0, 0.0)) == (180.0, 6)
    assert impact.pdof_of((0.0, -1.0)) == (270.0, 9)
    deg, clock = impact.pdof_of((-1.0, -math.tan(math.radians(40))))   # 40 deg left of ahead
    assert deg == pytest.approx(320.0) and clock == 11
    assert impact.episodes(np.array([0, 1, 1, 0, 0, 1, 0, 0, 0, 0, 1], bool), 2) == [(1, 5), (10, 10)]


def test_a_90_degree_t_bone_strikes_the_struck_vehicle_from_its_side(impacts):
    """A's front into B's left side: B's PDOF within 30 deg of 9 o'clock (270 deg), A's within
    30 deg of 12; one impact, the replay the file's own bit for bit."""
    d, s, m, ci = impacts["t-bone"]
    assert ci.identical
    (p,) = [p for p in ci.impacts if max(v.dv for v in p.vehicles) * impact.KMH >= 1.0]
    a, b = p.of(0), p.of(1)
    assert _off(b.pdof_deg, 270.0) <= 30 and b.pdof_clock in (8, 9, 10), b
    assert _off(a.pdof_deg, 0.0) <= 30 and a.pdof_clock in (11, 12, 1), a
    assert a.speed_before * impact.KMH == pytest.approx(d["outcome"]["vehicles"][0]["impact_speed_kmh"], abs=0.05)


def test_a_head_on_strikes_both_from_straight_ahead(impacts):
    d, s, m, ci = impacts["head-on"]
    (p,) = [p for p in ci.impacts if max(v.dv for v in p.vehicles) * impact.KMH >= 1.0]
    for v in p.vehicles:
        assert _off(v.pdof_deg, 0.0) <= 15 and v.pdof_clock == 12, v


@pytest.mark.parametrize("case", ["t-bone", "head-on", "t-bone-crush"])
def test_the_two_vehicles_momentum_changes_balance_within_the_roads_reach(impacts, case):
    """m_a dv_a + m_b dv_b: the contact forces cancel between the two, so what is left is the
    road's over the episode, at most mu g tau (m_a + m_b) (the friction cone; tau the window from
    the state before the first touch to after the last). Measured 0.88 (t-bone), 0.91 (head-on)
    and 0.91 (t-bone with crush) of that bound, 15-17 % of the mean m |dv|. And the contact
    impulse's share, |J| / m, is the outcome's delta-V."""
    d, s, m, ci = impacts[case]
    p = max(ci.impacts, key=lambda q: max(v.dv for v in q.vehicles))
    tau = p.t_end - p.t + float(m.opt.timestep)
    ma, mb = ci.mass[p.a], ci.mass[p.b]
    imbalance = np.linalg.norm(ma * np.array(p.of(p.a).dv_world) + mb * np.array(p.of(p.b).dv_world))
    assert imbalance <= s.road.friction * G * tau * (ma + mb)
    assert p.momentum_error < 0.25
    for i in (p.a, p.b):
        assert p.of(i).dv_impulse * impact.KMH == pytest.approx(d["outcome"]["vehicles"][i]["delta_v_kmh"], abs=0.1)


def test_the_sequence_runs_from_driving_through_the_impact_to_rest(impacts):
    """The braking sedan's phases tile the crash: driving, the assumed perception-reaction time
    before its reaction stop, braking (its realised brake commands) up to the impact, the impact,
    then post-impact (and rest once it stays below the rest speed); the SUV drives into it without
    braking."""
    from nbst.render.crash.report import PERCEPTION_S, crash_report, phases

    d, s, m, ci = impacts["head-on"]
    rep = crash_report(d, s, m)
    (p,) = rep.major()
    a, b = phases(rep, 0), phases(rep, 1)
    assert [x[0] for x in a[:5]] == ["driving", "perception-reaction (assumed)", "braking", "impact", "post-impact"]
    assert a[2][1] == pytest.approx(1.2, abs=0.02) and a[3][1] == p.t     # the brakes on within a driver period
    assert a[1][1] == pytest.approx(a[2][1] - PERCEPTION_S)
    assert [x[0] for x in b[:3]] == ["driving", "impact", "post-impact"]
    for ph in (a, b):
        assert ph[0][1] == 0.0 and ph[-1][2] == pytest.approx(s.duration)
        assert all(x[2] == pytest.approx(y[1]) for x, y in zip(ph, ph[1:]))      # no gap, no overlap


def _cells(page: str) -> dict:
    """The page's tagged cells: data-q -> text."""
    return {k: re.sub(r"<[^>]+>", "", v).strip() for k, v in re.findall(r"data-q=['\"]([^'\"]+)['\"]>(.*?)</td>", page)}


@pytest.mark.slow
def test_the_page_states_the_librarys_numbers_and_says_what_is_not_recorded(files, impacts, tmp_path):
    from nbst.render.crash.report import crash_report, evidence_rows, report_html

    d, s, m, ci = impacts["t-bone"]
    rep = crash_report(d, s, m, source="tbone.json")
    page = report_html(rep)
    cells = _cells(page)
    for i, nm in enumerate(s.names()):
        p, v = next((p, p.of(i)) for p in ci.impacts if i in (p.a, p.b) and p.of(i).dv * impact.KMH >= 1.0)
        assert cells[f"{nm}.impact_speed"] == f"{v.speed_before * impact.KMH:.1f}"
        assert cells[f"{nm}.delta_v"] == f"{v.dv * impact.KMH:.1f}"
        assert cells[f"{nm}.pdof"].startswith(f"{v.pdof_clock} o'clock")
        assert cells[f"{nm}.ees"] == "not recorded"
    assert page.count("no interval (one crash: the point value)") == 2
    assert page.count("<img") == 3
    rows = evidence_rows(rep)
    assert [(r[0], r[1]) for r in rows] == [("A", "hits"), ("A", "impact speed"), ("A", "rest position"),
                                          ("B", "hits"), ("B", "heading at rest")]
    assert [r[5] for r in rows] == [rep.motion.outcome.vehicles[i].fates[k] for i, k in
                                    ((0, "hits"), (0, "impact_speed"), (0, "rest"), (1, "hits"), (1, "heading"))]


@pytest.mark.slow
def test_the_page_shows_a_reconstructions_intervals_and_recorded_crush(impacts):
    """A crushing pair's EES and residual crush, as the crash file records them, and a
    reconstruction's intervals (the fields as their writer documents them: 90 % intervals with an
    identifiability flag) appear on the page."""
    from nbst.render.crash.report import crash_report, report_html

    d, s, m, ci = impacts["t-bone-crush"]
    d = json.loads(json.dumps(d))
    iv = {"lo": 48.0, "median": 50.0, "hi": 53.5, "estimate": 50.1, "identifiable": True}
    d["reconstruction"] = {"level": 0.9, "method": "Optimisation Monte Carlo", "draws": 40, "accepted": 12,
                           "vehicles": [{"name": "A", "impact_speed_kmh": iv, "delta_v_kmh": None, "pdof_clock": None},
                                        {"name": "B", "impact_speed_kmh": dict(iv, identifiable=False),
                                         "delta_v_kmh": None, "pdof_clock": None}]}
    page = report_html(crash_report(d, s, m))
    cells = _cells(page)
    for v in d["vehicles"]:
        crush = v["crush"]
        assert cells[f"{v['name']}.ees"].startswith(f"{crush['ees_kmh']:.1f}")
        for zone, z in crush["zones"].items():
            assert (f"{zone} {100 * z['residual_m']:.0f} cm" in cells[f"{v['name']}.ees"]) == (z["residual_m"] >= 0.005)
    assert any(z["residual_m"] >= 0.05 for v in d["vehicles"] for z in v["crush"]["zones"].values())
    assert page.count("48.0&ndash;53.5 (90 %), median 50.0") == 2 and page.count("not identifiable") == 1
    assert "12 of 40 draws met every piece of evidence" in page


def test_bad_input_is_one_line_exit_2_and_nothing_written(files, tmp_path, capsys):
    bad = tmp_path / "bad.json"
    bad.write_text('{"kind": "nbst-crash"}')
    folder = tmp_path / "folder.html"
    folder.mkdir()
    link = tmp_path / "link.html"
    link.symlink_to(tmp_path / "elsewhere.html")
    for argv in (["crash", "report", str(bad), "-o", str(tmp_path / "a.html")],
                 ["crash", "report", str(tmp_path / "missing.json"), "-o", str(tmp_path / "a.html")],
                 ["crash", "report", files["t-bone"], "-o", str(tmp_path / "a.txt")],
                 ["crash", "report", files["t-bone"], "-o", str(folder)],
                 ["crash", "report", files["t-bone"], "-o", str(link)]):
        capsys.readouterr()
        assert main(argv) == 2, argv
        assert len(capsys.readouterr().err.strip().splitlines()) == 1, argv
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.json", "folder.html", "link.html"]
    assert not (tmp_path / "elsewhere.html").exists() and not any(folder.iterdir())


@pytest.mark.slow
@pytest.mark.skipif(shutil.which("chromium") is None, reason="chromium is not installed")
def test_the_report_opens_in_headless_chromium(files, impacts, tmp_path):
    """The CLI's page in Debian's Chromium: the DOM holds the library's numbers in its tables and
    three figures; the screenshot is not blank and shows the vehicles' colours (drawn only in the
    figures: the tables are black on white)."""
    from PIL import Image

    out = tmp_path / "report.html"
    assert main(["crash", "report", files["head-on"], "-o", str(out), "-q"]) == 0
    d, s, m, ci = impacts["head-on"]
    cmd = ["chromium", "--headless", "--no-sandbox", "--disable-gpu", f"--user-data-dir={tmp_path / 'profile'}",
           "--window-size=1200,4000", "--hide-scrollbars"]
    dom = subprocess.run([*cmd, "--dump-dom", out.as_uri()], capture_output=True, text=True, timeout=120)
    assert dom.returncode == 0, dom.stderr[-2000:]
    assert "Crash report: head-on" in dom.stdout and dom.stdout.count("<img") == 3
    cells = _cells(dom.stdout)
    p = max(ci.impacts, key=lambda q: max(v.dv for v in q.vehicles))
    for i, nm in enumerate(s.names()):
        assert cells[f"{nm}.delta_v"] == f"{p.of(i).dv * impact.KMH:.1f}"
        assert cells[f"{nm}.impact_speed"] == f"{p.of(i).speed_before * impact.KMH:.1f}"
    shot = tmp_path / "shot.png"
    r = subprocess.run([*cmd, f"--screenshot={shot}", out.as_uri()], capture_output=True, timeout=120)
    assert r.returncode == 0 and shot.exists()
    px = np.asarray(Image.open(shot).convert("RGB")).astype(int)
    assert (px.min(axis=-1) < 200).mean() > 0.01                     # not blank (3.4 % measured)
    for colour in (v["colour"] for v in d["vehicles"]):              # each vehicle's colour, somewhere
        target = np.array(colour[:3]) * 255
        assert (np.abs(px - target).max(axis=-1) < 30).sum() > 200, colour
