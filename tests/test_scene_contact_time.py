"""``nbst scene check``'s note on a contact that the step does not resolve
(``nbst.scene.contacts.short_contacts``): the rebound time it computes from a solref is MuJoCo's
own, and the built-ins as shipped have no such contact."""
import json
import math

import mujoco
import numpy as np
import pytest

from nbst.cli.main import main
from nbst.scene.builtin import example_names, example_path
from nbst.scene.contacts import MIN_CONTACT_STEPS, contact_time, short_contacts
from nbst.scene.scenefile import load_fates

_DROP = """<mujoco><option timestep="{h}" gravity="0 0 0"/>
<worldbody><geom type="plane" size="1 1 0.1" solref="{tau} {zeta}"/>
<body pos="0 0 0.101"><freejoint/><geom type="sphere" size="0.1" mass="1" solref="{tau} {zeta}"/></body>
</worldbody></mujoco>"""


def _rebound_time(tau: float, zeta: float, h: float) -> float:
    """A ball thrown down at 1 m/s onto a plane (no gravity): how long it pushes on the plane (s)."""
    m = mujoco.MjModel.from_xml_string(_DROP.format(h=h, tau=tau, zeta=zeta))
    d = mujoco.MjData(m)
    d.qvel[2] = -1.0
    on = []
    for k in range(int(0.5 / h)):
        mujoco.mj_step(m, d)
        on.append(bool(d.nefc) and float(d.efc_force[:d.nefc].max()) > 0.0)
    idx = np.flatnonzero(on)
    assert len(idx) and idx[-1] < len(on) - 1, "the ball left the plane"
    return float((idx[-1] - idx[0] + 1) * h)


@pytest.mark.parametrize("tau,zeta", [(0.005, 0.3), (0.01, 0.1), (0.02, 0.5), (0.02, 0.8), (0.01, 1.0), (0.01, 1.5), (0.004, 3.0)])
def test_the_contact_time_is_mujocos_to_five_percent(tau, zeta):
    """The linear spring-dashpot's time to zero force against MuJoCo's own contact at a step of 0.02 ms,
    150 to 1,700 times shorter than it, damping ratios 0.1 to 3: within 5 % (MuJoCo's impedance, 0.9
    to 0.95 over the contact, moves the stiffness a little; the step adds at most one)."""
    h = 2e-5
    assert _rebound_time(tau, zeta, h) == pytest.approx(contact_time(tau, zeta, h), rel=0.05)


def test_refsafe_holds_the_time_constant_at_two_steps():
    assert contact_time(0.001, 0.3, 0.002) == pytest.approx(contact_time(0.004, 0.3, 0.0))
    assert contact_time(0.001, 0.3, 0.002, refsafe=False) == pytest.approx(contact_time(0.001, 0.3, 0.0))
    assert contact_time(0.02, 1.0, 0.002) == 0.04  # critically damped: 2 tau, the limit of both sides
    assert contact_time(0.02, 1.0 - 1e-7, 0.0) == pytest.approx(0.04, rel=1e-4)
    assert contact_time(0.02, 1.0 + 1e-7, 0.0) == pytest.approx(0.04, rel=1e-4)
    # no damping: the spring's half-period, pi / w
    assert contact_time(0.01, 1e-9, 0.0) == pytest.approx(math.pi * 0.01 * 1e-9, rel=1e-6)


@pytest.mark.parametrize("name", example_names())
def test_no_built_in_has_a_contact_its_step_does_not_resolve(name):
    fates, model = load_fates(name)
    assert short_contacts(fates, model) == [], name


def test_check_notes_the_bank_shot_at_2_ms(tmp_path, capsys):
    """bank-shot's backboard (solref 0.005 0.3) pushes for 4.0 ms: at a step of 2 ms that is 2 steps, the
    note names the contact, the steps and the step that would give it 4."""
    src = json.loads(example_path("bank-shot").read_text())
    src["scene"] = str(example_path("bank-shot").with_suffix(".xml"))
    src["timestep"] = 0.002
    p = tmp_path / "coarse.json"
    p.write_text(json.dumps(src))
    coarse, cm = load_fates(p)
    rows = short_contacts(coarse, cm)
    assert rows and rows[0][0] == "ball" and rows[0][2] == pytest.approx(contact_time(0.005, 0.3, 0.002))
    assert {r[1] for r in rows} >= {"backboard_g", "floor"}
    assert rows[0][2] < MIN_CONTACT_STEPS * 0.002
    assert main(["scene", "check", str(p)]) == 0
    out = capsys.readouterr().out
    assert "note: ball's contacts with backboard_g" in out and "1.99 steps of 2 ms" in out, out
    assert "a step of at most 0.995 ms gives it 4" in out, out


@pytest.fixture(scope="module")
def bounce():
    """benchmarks/bench_scene_bounce.py: its phases and its three contacts (one set-up for both)."""
    import importlib.util
    from pathlib import Path

    path = Path(__file__).resolve().parents[1] / "benchmarks" / "bench_scene_bounce.py"
    spec = importlib.util.spec_from_file_location("bench_scene_bounce", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_the_bank_shots_board_bounce_holds_at_its_step(bounce):
    """A ball at 4 m/s square on to the backboard (5 rad/s of back spin): at the scene's step it comes off
    within 15 % of the bounce at a step 16 times finer, wherever in a step it strikes (at 2 ms, the
    scene's step before, it came off at 0.4 to 6.4 m/s)."""
    fates, model = load_fates("bank-shot")
    h = model.opt.timestep
    setup, read, span, t = bounce.board_bounce(model)
    fine = np.mean(bounce.phases(model, setup, read, h / 16, span, t))
    out = bounce.phases(model, setup, read, h, span, t)
    assert 1.0 < fine < 4.0  # it bounces, and loses speed
    assert max(abs(v - fine) for v in out) < 0.15 * fine, (out, fine)


def test_the_billiard_balls_restitution_holds_at_the_scenes_step(bounce):
    """Two balls in the air, the cue at 2 m/s head on into the 3: the restitution at the scene's step is
    within 10 % of that at a step 16 times finer, wherever in a step they meet."""
    fates, model = load_fates("billiards")
    h = model.opt.timestep
    setup, read, span, t = bounce.ball_on_ball(model)
    fine = np.mean(bounce.phases(model, setup, read, h / 16, span, t))
    out = bounce.phases(model, setup, read, h, span, t)
    assert 0.5 < fine < 1.0
    assert max(abs(e - fine) for e in out) < 0.10 * fine, (out, fine)


def test_solve_says_so_before_the_search(tmp_path, capsys):
    """``scene solve`` on a scene with such a contact says so on stderr before it searches (not with -q)."""
    src = json.loads(example_path("bank-shot").read_text())
    src["scene"] = str(example_path("bank-shot").with_suffix(".xml"))
    src["timestep"] = 0.002
    p = tmp_path / "coarse.json"
    p.write_text(json.dumps(src))
    main(["scene", "solve", str(p), "-o", str(tmp_path / "a.json"), "--seed", "1", "--max-rollouts", "2"])
    err = capsys.readouterr().err
    assert "pair(s) of geoms touch for fewer than 4 steps (the shortest, ball with backboard_g, 1.99 steps of 2 ms)" in err, err
    main(["scene", "solve", str(p), "-o", str(tmp_path / "b.json"), "--seed", "1", "--max-rollouts", "2", "-q"])
    assert "fewer than 4 steps" not in capsys.readouterr().err


def test_a_pair_of_two_fated_bodies_is_noted_once(tmp_path):
    """A demanding user's two fated balls (solref 0.005 0.3 at 1 ms: 3.98 steps) got the note twice,
    once from each ball, and read '4 steps ... under 4' (two digits); said once, to three digits."""
    xml = """<mujoco><option timestep="0.001"/><worldbody><geom name="floor" type="plane" size="3 3 0.1"/>
      <body name="a" pos="0 0 0.05"><freejoint/><geom name="a_g" size="0.05" solref="0.005 0.3" contype="2" conaffinity="2"/></body>
      <body name="b" pos="1 0 0.05"><freejoint/><geom name="b_g" size="0.05" solref="0.005 0.3" contype="2" conaffinity="2"/></body>
    </worldbody></mujoco>"""
    (tmp_path / "two.xml").write_text(xml)
    fates = {"format": "nbst-fates", "version": 1, "scene": "two.xml", "duration": 0.5,
             "controls": {"a": {"linvel": [[0.5, 4], [-1, 1], [0, 0]]}},
             "fates": {"a": {"hits": ["b"]}, "b": {"rest_in": {"center": [2, 0, 0.05], "radius": 0.3}}}}
    (tmp_path / "two.json").write_text(json.dumps(fates))
    f, m = load_fates(tmp_path / "two.json")
    rows = short_contacts(f, m)
    assert [(r[0], r[1]) for r in rows] == [("a", "b_g")], rows
    assert rows[0][2] / 0.001 == pytest.approx(3.98, abs=0.01)


@pytest.mark.parametrize("solref,solimp", [("0.02 1", "0.9 0.95 0.001"), ("0.005 1", "0.9 0.95 0.001"),
                                           ("0.02 1", "0.99 0.99 0.001"), ("0.01 0.5", "0.8 0.95 0.002 0.3 3")])
def test_the_resting_depth_is_mujocos(solref, solimp):
    """A ball settled on a plane (both with this solref and solimp): its depth in the plane is
    ``resting_depth``'s to 2 % (MuJoCo's soft contact at rest, 2 s at 0.5 ms)."""
    from nbst.scene.contacts import resting_depth

    xml = f"""<mujoco><option timestep="0.0005"/><worldbody>
      <geom type="plane" size="1 1 .1" solref="{solref}" solimp="{solimp}"/>
      <body pos="0 0 0.05"><freejoint/><geom type="sphere" size="0.05" solref="{solref}" solimp="{solimp}"/></body>
    </worldbody></mujoco>"""
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    for _ in range(4000):
        mujoco.mj_step(m, d)
    depth = 0.05 - float(d.qpos[2])
    want = resting_depth(tuple(map(float, solref.split())), list(map(float, solimp.split())), 9.81, 0.0005)
    assert depth == pytest.approx(want, rel=0.02)


def test_check_notes_a_millimetre_bead_that_sinks(tmp_path, capsys):
    """A demanding user's 1 mm bead sank 37 % of its radius into the floor in MuJoCo's default contact
    with no word; `check` notes a body that would rest deeper than a tenth of its smallest half-size."""
    from nbst.scene.contacts import deep_rests

    xml = """<mujoco><option timestep="0.0002"/><worldbody><geom name="floor" type="plane" size="0.1 0.1 0.01"/>
      <body name="bead" pos="0 0 0.001"><freejoint/><geom type="sphere" size="0.001"/></body>
    </worldbody></mujoco>"""
    (tmp_path / "bead.xml").write_text(xml)
    doc = {"format": "nbst-fates", "version": 1, "scene": "bead.xml", "duration": 0.2,
           "controls": {"bead": {"linvel": [[0, 0.1], [0, 0.1], [0, 0]]}},
           "fates": {"bead": {"rest_in": {"center": [0.01, 0, 0], "radius": 0.005}}}}
    (tmp_path / "bead.json").write_text(json.dumps(doc))
    f, m = load_fates(tmp_path / "bead.json")
    rows = deep_rests(f, m)
    assert len(rows) == 1 and rows[0][:2] == ("bead", "floor") and 0.3e-3 < rows[0][2] < 0.45e-3, rows
    assert main(["scene", "check", str(tmp_path / "bead.json")]) == 0
    assert "note: bead would rest 0.3" in capsys.readouterr().out
    xml_big = xml.replace('size="0.001"', 'size="0.05"').replace('pos="0 0 0.001"', 'pos="0 0 0.05"')
    (tmp_path / "bead.xml").write_text(xml_big)
    f, m = load_fates(tmp_path / "bead.json")
    assert deep_rests(f, m) == []
