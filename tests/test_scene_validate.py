"""`nbst scene validate` (nbst.scene.validate, nbst.render.scene_report): a built-in example's
solution tabled under every setting (integrators, solvers, cones, the timestep ladder) and noise;
the scene's own row is the replay; the noise row is the room's --samples machinery; a bad out-dir
is refused in one line, exit 2; the page opens in headless Chromium when it is installed."""
import json
import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from nbst.cli.main import main
from nbst.render.scene_report import REPORT_FILES
from nbst.scene.validate import CONES, DIVISORS, GROUPS, INTEGRATORS, SOLVERS, validate_solution

SAMPLES = 6


@pytest.fixture(scope="module")
def solved(tmp_path_factory):
    """snake-eyes solved at seed 1 within a small budget (a few seconds), and its validation."""
    from nbst.outputs import write_json_atomic
    from nbst.scene import solve, solution_dict

    folder = tmp_path_factory.mktemp("scene-validate")
    res = solve(None, "snake-eyes", seed=1, max_rollouts=300)
    sol = folder / "dice.json"
    write_json_atomic(sol, solution_dict(res))
    return sol, validate_solution(str(sol), samples=SAMPLES)


def _expected() -> list[tuple[str, str]]:
    return [("scene", "as the scene"), *(("integrator", n) for n in INTEGRATORS), *(("solver", n) for n in SOLVERS),
            *(("cone", n) for n in CONES), *(("timestep", "h" if k == 1 else f"h/{k}") for k in DIVISORS)]


def test_the_report_has_every_setting_row(solved, tmp_path, capsys):
    sol, val = solved
    assert [(r.group, r.setting) for r in val.rows] == _expected()
    assert {r.integrator for r in val.group("integrator")} == set(INTEGRATORS)
    assert {r.solver for r in val.group("solver")} == set(SOLVERS)
    assert {r.cone for r in val.group("cone")} == set(CONES)
    h = val.scene_row.timestep
    assert [(r.timestep, r.nstep) for r in val.group("timestep")] == [
        (h / k, val.scene_row.nstep * k) for k in DIVISORS]
    for r in val.rows:  # every fate of every body judged under every setting
        assert [b.body for b in r.rollout.judgement.bodies] == [f.body for f in val.fates.fates]
        assert r.met == (r.rollout.judgement.met and not r.rollout.warnings)
        assert set(r.paths) == {f.body for f in val.fates.fates}
    out = tmp_path / "report"
    code = main(["scene", "validate", str(sol), "--out-dir", str(out), "--samples", str(SAMPLES)])
    assert code == 0
    said = capsys.readouterr().out
    assert "report" in said
    # a row with the scene's own setting says so, as the HTML does (a demanding user missed it)
    same = [r for r in val.rows if r.same_as_scene and r.group != "scene"]
    assert same and said.count("(the scene's)") == len(same), said
    assert sorted(os.listdir(out)) == sorted(REPORT_FILES)
    doc = json.loads((out / "report.json").read_text())
    assert doc["format"] == "nbst-scene-validation"
    assert [(r["group"], r["setting"]) for r in doc["rows"]] == _expected()
    assert [r["met"] for r in doc["rows"]] == [r.met for r in val.rows]
    assert doc["all_met"] == val.all_met and doc["noise"]["n"] == SAMPLES
    page = (out / "index.html").read_text()
    for g in GROUPS:
        assert f"paths-{g}.png" in page
    assert all((out / n).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" for n in REPORT_FILES if n.endswith(".png"))


def test_strict_exits_1_exactly_when_a_setting_misses_a_fate(solved, capsys):
    sol, val = solved
    assert main(["scene", "validate", str(sol), "--samples", "2", "-q"]) == 0
    assert main(["scene", "validate", str(sol), "--samples", "2", "--strict", "-q"]) == (0 if val.all_met else 1)
    err = capsys.readouterr().err
    assert ("--strict" in err) == (not val.all_met)


def test_the_scenes_row_agrees_with_replay(solved):
    from nbst.scene.solution import replay_solution

    sol, val = solved
    rep = replay_solution(sol)
    row = val.scene_row
    assert rep.same and row.same_as_scene
    assert row.rollout.judgement.to_dict() == rep.judgement.to_dict()
    assert row.rollout.qpos.tobytes() == rep.qpos.tobytes() and row.rollout.qvel.tobytes() == rep.qvel.tobytes()
    doc = json.loads(Path(sol).read_text())
    assert row.met == doc["met"]
    for g in GROUPS:  # the row of each group that is the scene's own setting is the same rollout
        same = [r for r in val.group(g) if r.same_as_scene]
        assert len(same) == 1 and same[0].rollout is row.rollout


def test_the_noise_row_is_the_rooms_samples(solved):
    from nbst.scene.rollout import SceneSim
    from nbst.scene.scenefile import load_fates
    from nbst.scene.search import noisy_probability

    sol, val = solved
    doc = json.loads(Path(sol).read_text())
    fates, model = load_fates(doc["fates_file"] or doc["fates"], scene=doc["scene"])
    model.opt.timestep = doc["timestep"]
    with SceneSim(fates, model) as sim:
        p = noisy_probability(sim, np.array(doc["x"]), n=SAMPLES, seed=doc["seed"])
    assert p == val.probability and val.noise_seed == doc["seed"]
    assert val.noisy_ends.shape == (SAMPLES, len(fates.fates), 3) and int(val.noisy_met.sum()) == p.k


@pytest.mark.parametrize("kind", ["file", "fifo"])
def test_a_bad_out_dir_is_refused_in_one_line(solved, tmp_path, capsys, kind):
    sol, _ = solved
    bad = tmp_path / "out"
    if kind == "file":
        bad.write_text("keep")
    else:
        os.mkfifo(bad)
    assert main(["scene", "validate", str(sol), "--out-dir", str(bad)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--out-dir" in err[0] and "expected a folder" in err[0]
    assert sorted(os.listdir(tmp_path)) == ["out"]
    if kind == "file":
        assert bad.read_text() == "keep"


def test_a_bad_solution_is_refused_in_one_line(tmp_path, capsys):
    bad = tmp_path / "sol.json"
    bad.write_text('{"format": "nbst-fates"}')
    assert main(["scene", "validate", str(bad), "--out-dir", str(tmp_path / "r")]) == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1
    assert not (tmp_path / "r").exists()


@pytest.mark.slow
@pytest.mark.skipif(shutil.which("chromium") is None, reason="chromium is not installed")
def test_the_page_opens_in_headless_chromium(solved, tmp_path):
    sol, val = solved
    out = tmp_path / "report"
    assert main(["scene", "validate", str(sol), "--out-dir", str(out), "--samples", "2", "-q"]) == 0
    shot = tmp_path / "shot.png"
    cmd = ["chromium", "--headless", "--no-sandbox", "--disable-gpu", f"--user-data-dir={tmp_path / 'profile'}",
           "--window-size=1200,2400"]
    dom = subprocess.run([*cmd, "--dump-dom", (out / "index.html").as_uri()], capture_output=True, text=True,
                         timeout=120)
    assert dom.returncode == 0, dom.stderr[-2000:]
    assert "Physics cross-validation" in dom.stdout and dom.stdout.count("<img") == len(GROUPS) + 1
    assert dom.stdout.count("<tr>") >= len(val.rows) + len(GROUPS) + 1
    run = subprocess.run([*cmd, f"--screenshot={shot}", (out / "index.html").as_uri()], capture_output=True,
                         timeout=120)
    assert run.returncode == 0 and shot.stat().st_size > 10_000


def test_the_report_draws_the_fixed_geoms_from_above():
    """A demanding user's ball bounced off a wall the report's path plots did not draw: each geom
    fixed to the world that collides is a footprint from above (a box's turned with it, a sphere's a
    circle); planes, free bodies and geoms that collide with nothing are not."""
    import mujoco

    from nbst.scene.validate import static_footprints

    xml = """<mujoco><worldbody><geom type="plane" size="3 3 0.1"/>
      <geom name="wall" type="box" pos="1 0.6 0.15" size="1.2 0.02 0.15"/>
      <geom name="turned" type="box" pos="-1 0 0.15" size="1.2 0.02 0.15" euler="0 0 90"/>
      <geom name="post" type="sphere" pos="0 -1 0.1" size="0.1"/>
      <geom name="ghost" type="box" pos="0 2 0" size="0.1 0.1 0.1" contype="0" conaffinity="0"/>
      <body name="ball" pos="0 0 0.05"><freejoint/><geom type="sphere" size="0.05"/></body>
    </worldbody></mujoco>"""
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    mujoco.mj_kinematics(m, d)
    polys = static_footprints(m, d)
    assert len(polys) == 3
    boxes = sorted((tuple(np.round(p.min(axis=0), 6)), tuple(np.round(p.max(axis=0), 6))) for p in polys)
    assert ((-1.02, -1.2), (-0.98, 1.2)) in boxes          # turned 90 degrees about z
    assert ((-0.2, 0.58), (2.2, 0.62)) in boxes
    circle = [p for p in polys if len(p) == 24][0]
    assert np.allclose(np.linalg.norm(circle - [0, -1], axis=1), 0.1)


def test_a_fixed_mesh_is_its_hull_and_a_named_fixed_geom_stays_inside_the_axes():
    """A fourth new user's tetrahedral rock was drawn as its bounding rectangle, and the stopper a
    door had to hit fell outside the plots' axes. A fixed mesh is now the hull of its vertices (a
    triangle from above, area within 1e-9 m^2 of the exact 0.5 x 0.3 x 0.4 / 2); a fixed geom a fate
    names is kept inside the axes."""
    import mujoco

    from render.scene_report import _limits
    from nbst.scene.validate import static_footprints

    xml = """<mujoco><asset><mesh name="tet" vertex="0 0 0  0.3 0 0  0 0.4 0  0 0 0.2"/></asset>
      <worldbody><geom type="plane" size="3 3 0.1"/>
      <geom name="rock" type="mesh" mesh="tet" pos="0.5 0.5 0"/>
      <geom name="stopper" type="box" pos="4 0 0.1" size="0.05 0.05 0.1"/>
      <body name="ball" pos="0 0 0.05"><freejoint/><geom type="sphere" size="0.05"/></body>
    </worldbody></mujoco>"""
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    mujoco.mj_kinematics(m, d)
    (rock,) = static_footprints(m, d, names={"rock"})
    x, y = rock[:, 0], rock[:, 1]
    assert len(rock) == 3 and abs(0.5 * abs(np.dot(x, np.roll(y, 1)) - np.dot(y, np.roll(x, 1))) - 0.06) < 1e-9
    (stop,) = static_footprints(m, d, names={"stopper"})

    class Val:   # what _limits reads of a validation: the fates' regions and the named fixed geoms
        class fates:
            fates = ()
        aims = (stop,)

    xlim, _ = _limits(Val, [np.zeros((2, 3))])
    assert xlim[1] >= 4.05
