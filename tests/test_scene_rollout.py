"""Controls to state and the rollout (nbst.scene.rollout), the search (nbst.scene.search), solve
and the solution file: physical facts with tolerances, the same result for a seed whatever the
threads, replay bit for bit with the plain mj_step loop of docs/scene.md, Ctrl-C keeping the best
so far, the CLI's exits."""
import json
import math
from pathlib import Path

import numpy as np
import pytest

from nbst.cli.main import main
from nbst.scene import api as scene_api
from nbst.scene.api import solve
from nbst.scene.judge import rotate
from nbst.scene.rollout import SceneSim, conjugate, replay
from nbst.scene.scenefile import load_fates
from nbst.scene.search import signature_search
from nbst.scene.solution import read_solution, replay_solution, solution_dict

SPACE = """<mujoco model="space">
  <option timestep="0.005" gravity="0 0 0"/>
  <worldbody>
    <body name="ball" pos="0 0 1"><freejoint/><geom type="sphere" size="0.05"/></body>
  </worldbody>
  <keyframe><key name="turned" qpos="0.1 0.2 1 0.7071067811865476 0 0 0.7071067811865476"/></keyframe>
</mujoco>
"""

TOSS = """<mujoco model="toss">
  <option timestep="0.01"/>
  <worldbody>
    <geom name="floor" type="plane" size="3 3 0.1"/>
    <geom name="wall" type="box" pos="2.0 0 0.5" size="0.05 1 0.5"/>
    <body name="ball" pos="0 0 0.3"><freejoint/><geom name="ball_g" type="sphere" size="0.05"/></body>
    <body name="cube" pos="0 0.5 0.05"><freejoint/><geom type="box" size="0.05 0.05 0.05"/></body>
  </worldbody>
</mujoco>
"""

TOSS_FATES = {"format": "nbst-fates", "version": 1, "scene": "toss.xml", "duration": 0.6,
              "controls": {"ball": {"linvel": [[0, 4], [-1, 1], [0, 3]], "angvel": [[0, 0], [0, 0], [0, 0]]},
                           "cube": {"linvel": [[0, 3], [-1, 1], [0, 2]]}},
              "fates": {"ball": {"at": [{"t": 0.3, "in": {"center": [0.6, 0, 0.4], "radius": 0.1}}],
                                 "never_hits": ["wall"]},
                        "cube": {"rest_in": {"min": [0.5, 0.2, 0], "max": [1.0, 0.8, 0.2]}}}}


@pytest.fixture
def space(tmp_path):
    (tmp_path / "space.xml").write_text(SPACE)
    doc = {"format": "nbst-fates", "version": 1, "scene": "space.xml", "keyframe": "turned", "duration": 1.0,
           "controls": {"ball": {"linvel": [[-1, 1], [-1, 1], [-1, 1]], "angvel": [[-9, 9], [-9, 9], [-9, 9]],
                                 "pos": [[-0.5, 0.5], [-0.5, 0.5], [-0.5, 0.5]]}},
           "fates": {"ball": {"rest_in": {"center": [0, 0, 1], "radius": 0.2}}}}
    (tmp_path / "space.json").write_text(json.dumps(doc))
    return load_fates(tmp_path / "space.json")


@pytest.fixture
def toss(tmp_path):
    (tmp_path / "toss.xml").write_text(TOSS)
    (tmp_path / "toss.json").write_text(json.dumps(TOSS_FATES))
    return tmp_path / "toss.json"


@pytest.fixture
def impossible(tmp_path):
    """The toss, but the cube must rest 1.5 m up in the air."""
    (tmp_path / "toss.xml").write_text(TOSS)
    doc = json.loads(json.dumps(TOSS_FATES))
    doc["fates"]["cube"]["rest_in"] = {"min": [0.5, 0.2, 1.5], "max": [1.0, 0.8, 2.0]}
    (tmp_path / "impossible.json").write_text(json.dumps(doc))
    return tmp_path / "impossible.json"


def test_world_velocities_reach_the_free_joint_in_its_frames(space):
    f, model = space
    sim = SceneSim(f, model)
    w, v, off = np.array([1.0, 2.0, -3.0]), np.array([0.3, -0.2, 0.1]), np.array([0.1, 0.0, -0.2])
    qpos, qvel = sim.initial_state(np.concatenate([v, w, off]))
    q = qpos[3:7]
    assert np.allclose(qpos[:3], [0.2, 0.2, 0.8], atol=1e-15)  # the key's position plus the offset
    assert np.array_equal(qvel[:3], v)  # linear: world frame, as given
    assert np.allclose(rotate(q, qvel[3:6]), w, atol=1e-14)  # angular: stored in the body frame
    assert np.allclose(qvel[3:6], [2.0, -1.0, -3.0], atol=1e-14)  # the key turns the body 90 deg about z


def test_a_free_ball_without_gravity_keeps_the_commanded_world_spin_and_velocity(space):
    """The physical fact: a sphere (isotropic inertia) with no gravity and no contact spins about
    the commanded world axis at the commanded rate, and its centre moves at the commanded velocity."""
    import mujoco

    f, model = space
    sim = SceneSim(f, model)
    w, v = np.array([1.0, 2.0, -3.0]), np.array([0.3, -0.2, 0.1])
    qpos0, qvel0 = sim.initial_state(np.concatenate([v, w, np.zeros(3)]))
    d = mujoco.MjData(model)
    d.qpos[:], d.qvel[:] = qpos0, qvel0
    n = 100  # 0.5 s: a turn of 1.87 rad, under pi (a quaternion tells angles up to pi)
    for _ in range(n):
        mujoco.mj_step(model, d)
    t = n * model.opt.timestep
    assert np.allclose(d.qpos[:3], qpos0[:3] + v * t, atol=1e-9)
    assert np.allclose(rotate(d.qpos[3:7], d.qvel[3:6]), w, atol=1e-9)
    # the turn from start to end is |w| t about w
    dq = np.empty(4)
    mujoco.mju_mulQuat(dq, d.qpos[3:7], conjugate(qpos0[3:7]))
    angle = 2 * math.acos(min(1.0, abs(dq[0])))
    axis = np.sign(dq[0]) * dq[1:] / np.linalg.norm(dq[1:])
    assert abs(angle - (np.linalg.norm(w) * t) % (2 * math.pi)) < 1e-6
    assert np.allclose(axis, w / np.linalg.norm(w), atol=1e-6)


def test_the_rollout_is_the_plain_mj_step_loop_bit_for_bit(toss):
    f, model = load_fates(toss)
    with SceneSim(f, model) as sim:
        x = (f.bounds()[0] + f.bounds()[1]) / 2
        r = sim.rollout(x)
        q, v = replay(model, r.qpos0, r.qvel0, sim.nstep)
    assert q.tobytes() == r.qpos.tobytes() and v.tobytes() == r.qvel.tobytes()


def test_the_one_call_rollout_is_the_loop_too(space):
    """A scene whose fates need only the end (rest_in) steps in one mj_step(nstep=n) call: the
    same bits as the loop, the same verdict."""
    f, model = space
    with SceneSim(f, model) as sim:
        assert not sim.per_step and not sim.pairs
        r = sim.rollout(np.array([0.3, -0.2, 0.1, 1.0, 2.0, -3.0, 0.1, 0.0, -0.2]))
        q, v = replay(model, r.qpos0, r.qvel0, sim.nstep, key=sim.key)
    assert q.tobytes() == r.qpos.tobytes() and v.tobytes() == r.qvel.tobytes()
    end = r.qpos[:3]  # (0.2, 0.2, 0.8) + (0.3, -0.2, 0.1) x 1 s, no gravity
    assert np.allclose(end, [0.5, 0.0, 0.9], atol=1e-12)
    assert abs(r.judgement.cost - max(0.0, float(np.linalg.norm(end - [0, 0, 1])) - 0.2)) < 1e-12


def test_touches_are_first_contacts(toss):
    f, model = load_fates(toss)
    with SceneSim(f, model) as sim:
        r = sim.rollout(np.array([4.0, 0, 3.0, 0, 0, 0, 0, 0, 0]))  # the ball thrown hard at the wall
        assert not r.judgement.bodies[0].fates[1].met and r.judgement.bodies[0].fates[1].happened == "touched wall"
        r = sim.rollout(np.array([0.5, 0, 0.5, 0, 0, 0, 0, 0, 0]))
        assert r.judgement.bodies[0].fates[1].met


def test_the_search_meets_the_toss_and_a_seed_gives_the_same_result_for_any_jobs(toss):
    a = solve(None, toss, seed=7, max_rollouts=600, jobs=1)
    b = solve(None, toss, seed=7, max_rollouts=600, jobs=2)
    assert a.met and a.stopped == "met" and a.rollouts < 600
    assert a.rollouts == b.rollouts and a.best.x.tobytes() == b.best.x.tobytes()
    assert a.best.qpos.tobytes() == b.best.qpos.tobytes()
    c = solve(None, toss, seed=8, max_rollouts=600, jobs=1)
    assert c.best.x.tobytes() != a.best.x.tobytes()


def test_ctrl_c_returns_the_best_so_far(impossible):
    f, model = load_fates(impossible)
    seen = []

    def stop(p):
        seen.append(p.rollouts)
        if p.rollouts >= 16:
            raise KeyboardInterrupt

    with SceneSim(f, model) as sim:
        r = signature_search(sim, rng=np.random.default_rng(1), max_rollouts=10_000, callback=stop)
    assert r.stopped == "interrupted" and r.rollouts == 16 and math.isfinite(r.best.cost)


def test_solution_file_replays_bit_for_bit_with_the_docs_loop(toss, tmp_path):
    import mujoco

    res = solve(None, toss, seed=3, max_rollouts=64)
    d = solution_dict(res)
    p = tmp_path / "sol.json"
    p.write_text(json.dumps(d))
    sol = read_solution(p)
    # the loop of docs/scene.md, "Replay by hand"
    model = mujoco.MjModel.from_xml_path(sol["scene"])
    model.opt.timestep = sol["timestep"]
    data = mujoco.MjData(model)
    if sol["keyframe"] is not None:
        mujoco.mj_resetDataKeyframe(model, data, model.key(sol["keyframe"]).id)
    data.qpos[:] = sol["qpos0"]
    data.qvel[:] = sol["qvel0"]
    for _ in range(sol["nstep"]):
        mujoco.mj_step(model, data)
    assert np.array(sol["final"]["qpos"]).tobytes() == data.qpos.tobytes()
    assert np.array(sol["final"]["qvel"]).tobytes() == data.qvel.tobytes()
    r = replay_solution(p)
    assert r.same and not r.scene_changed and r.judgement.signature == res.best.signature


def test_cli_solve_replay_and_their_exits(toss, impossible, tmp_path, capsys, monkeypatch):
    out = tmp_path / "sol.json"
    assert main(["scene", "solve", str(toss), "-o", str(out), "--seed", "7", "--max-rollouts", "600",
                 "--jobs", "2", "--samples", "6", "-q"]) == 0
    d = json.loads(out.read_text())
    assert d["format"] == "nbst-scene-solution" and d["met"] and d["seed"] == 7
    p = d["probability"]
    assert p["n"] == 6 and 0 <= p["k"] <= 6 and p["lo"] <= p["p"] <= p["hi"] and len(p["noise"]) == 9
    assert set(d["versions"]) == {"nbst", "mujoco"} and d["verdicts"]["cube"]["met"]
    assert main(["scene", "replay", str(out)]) == 0
    assert "reproduced bit for bit" in capsys.readouterr().out
    # a changed final state no longer replays
    d["final"]["qpos"][0] += 1e-12
    out.write_text(json.dumps(d))
    assert main(["scene", "replay", str(out)]) == 1
    # not met within the budget: exit 1, the nearest written
    assert main(["scene", "solve", str(impossible), "-o", str(out), "--seed", "7", "--max-rollouts", "40", "-q"]) == 1
    assert json.loads(out.read_text())["met"] is False
    # interrupted: the best so far written, exit 130
    original = scene_api.signature_search

    def interrupted(sim, *, rng, max_rollouts, callback=None, **more):
        def stop(p):
            if p.rollouts >= 16:
                raise KeyboardInterrupt
        return original(sim, rng=rng, max_rollouts=max_rollouts, callback=stop, **more)

    monkeypatch.setattr(scene_api, "signature_search", interrupted)
    out.unlink()
    assert main(["scene", "solve", str(impossible), "-o", str(out), "--seed", "7", "-q"]) == 130
    d = json.loads(out.read_text())
    assert d["search"]["stopped"] == "interrupted" and d["search"]["rollouts"] == 16


def test_cli_examples_and_check(capsys):
    assert main(["scene", "examples"]) == 0
    out = capsys.readouterr().out
    assert "snake-eyes" in out and "egg-in-cup" in out and "bank-shot" in out
    assert main(["scene", "check", "snake-eyes"]) == 0
    assert "within 20 deg of up" in capsys.readouterr().out


@pytest.mark.slow
@pytest.mark.parametrize("name", ["snake-eyes", "egg-in-cup", "bank-shot"])
def test_the_built_in_examples_are_solved_and_replay(name, tmp_path):
    res = solve(None, name, seed=1, max_rollouts=2000)
    assert res.met, (name, res.rollouts, res.best.judgement.to_dict())
    p = tmp_path / "sol.json"
    p.write_text(json.dumps(solution_dict(res)))
    assert replay_solution(p).same


def test_the_dice_have_real_pips():
    """Face 1 is the body's +z face: one pip there, six on -z, and opposite faces sum to 7."""
    import mujoco

    from nbst.scene.builtin import example_path

    p = example_path("snake-eyes")
    assert p is not None
    m = mujoco.MjModel.from_xml_path(str(Path(p).with_suffix(".xml")))
    die = m.body("die1").id
    pips = [g for g in range(m.ngeom) if m.geom_bodyid[g] == die and m.geom_contype[g] == 0]
    faces = {}
    for g in pips:
        pos = m.geom_pos[g]
        k = int(np.argmax(np.abs(pos)))
        faces[(k, int(np.sign(pos[k])))] = faces.get((k, int(np.sign(pos[k]))), 0) + 1
    assert faces[(2, 1)] == 1 and faces[(2, -1)] == 6
    assert all(faces[(k, 1)] + faces[(k, -1)] == 7 for k in range(3))


def test_export_plays_the_same_motion_from_its_keyframe(toss, tmp_path, capsys):
    """`nbst scene export`: the scene with a key holding the initial state; reset to the key and
    stepped with mj_step, it ends where replay does, bit for bit (a timestep set by the fates is
    written on <option>)."""
    import mujoco

    doc = json.loads(toss.read_text())
    doc["timestep"] = 0.005  # the fates override the model's 0.01
    toss.write_text(json.dumps(doc))
    sol, out = tmp_path / "sol.json", tmp_path / "elsewhere" / "scene.xml"
    assert main(["scene", "solve", str(toss), "-o", str(sol), "--seed", "2", "--max-rollouts", "40", "-q"]) in (0, 1)
    assert main(["scene", "export", str(sol), "-o", str(out)]) == 0
    capsys.readouterr()
    d = json.loads(sol.read_text())
    m = mujoco.MjModel.from_xml_path(str(out))
    assert m.opt.timestep == 0.005 and m.nkey == 1
    data = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, data, m.key("nbst").id)
    assert data.qpos.tobytes() == np.array(d["qpos0"]).tobytes()
    for _ in range(d["nstep"]):
        mujoco.mj_step(m, data)
    q, v = replay_solution(sol).qpos, replay_solution(sol).qvel
    assert data.qpos.tobytes() == q.tobytes() and data.qvel.tobytes() == v.tobytes()


def test_export_of_a_scene_with_files_goes_beside_it(tmp_path, capsys):
    """A scene that reads other files (an include) is exported into its own folder only: one line,
    exit 2, nothing written elsewhere; beside it, the export works."""
    (tmp_path / "scene").mkdir()
    (tmp_path / "scene" / "ball.xml").write_text('<mujoco><worldbody><body name="ball" pos="0 0 0.3"><freejoint/>'
                                                  '<geom type="sphere" size="0.05"/></body></worldbody></mujoco>')
    (tmp_path / "scene" / "s.xml").write_text('<mujoco><worldbody><geom name="floor" type="plane" size="1 1 0.1"/>'
                                              '</worldbody><include file="ball.xml"/></mujoco>')
    fates = {"format": "nbst-fates", "version": 1, "scene": "scene/s.xml", "duration": 0.1,
             "controls": {"ball": {"linvel": [[0, 1], [0, 0], [0, 0]]}},
             "fates": {"ball": {"rest_in": {"center": [0, 0, 0], "radius": 5}}}}
    (tmp_path / "f.json").write_text(json.dumps(fates))
    sol = tmp_path / "sol.json"
    assert main(["scene", "solve", str(tmp_path / "f.json"), "-o", str(sol), "--seed", "1", "-q"]) == 0
    out = tmp_path / "other" / "x.xml"
    assert main(["scene", "export", str(sol), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "write the exported scene in" in err and not out.exists()
    assert main(["scene", "export", str(sol), "-o", str(tmp_path / "scene" / "with-key.xml")]) == 0


@pytest.mark.parametrize("text, why", [
    ("{", "not JSON"), ('{"format": "nbst-crash"}', "format"), ("[" * 100_000 + "]" * 100_000, "nested"),
    ('{"format": "nbst-scene-solution", "version": 1, "scene": "x.xml"}', "nstep"),
])
def test_a_bad_solution_file_is_one_line_exit_2(tmp_path, capsys, text, why):
    p = tmp_path / "sol.json"
    p.write_text(text)
    for argv in (["scene", "replay", str(p)], ["scene", "export", str(p), "-o", str(tmp_path / "x.xml")]):
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and why in err and str(p) in err
    assert not (tmp_path / "x.xml").exists()


def test_answers_have_contact_sequences_of_their_own_and_each_replays(toss, tmp_path):
    """--answers K (after Chenney & Forsyth): up to K solutions that meet every fate, each with a
    different contact sequence; recording the sequences changes no bit of the search (the first
    answer is the one found without them), and each answer replays bit for bit."""
    doc = json.loads(toss.read_text())
    doc["fates"]["ball"] = {"never_hits": ["cube"]}  # the ball may touch the floor, the wall, both or neither
    toss.write_text(json.dumps(doc))
    one = solve(None, toss, seed=7, max_rollouts=600)
    res = solve(None, toss, seed=7, max_rollouts=600, answers=3, samples=4)
    assert res.met and len(res.answers) == 3 and len(res.answer_probabilities) == 3
    assert res.answers[0].x.tobytes() == one.best.x.tobytes() == res.best.x.tobytes()
    sequences = [a.sequence for a in res.answers]
    assert len(set(sequences)) == 3 and all(a.judgement.met for a in res.answers)
    assert all(s and all("-" in t for t in s) for s in sequences)
    for a in res.answers:
        q, v = replay(res.model, a.qpos0, a.qvel0, res.nstep)
        assert q.tobytes() == a.qpos.tobytes() and v.tobytes() == a.qvel.tobytes()
    d = solution_dict(res)
    assert [x["sequence"] for x in d["answers"]] == [list(s) for s in sequences]
    assert d["answers"][0]["probability"]["n"] == 4


BANK = """<mujoco><option timestep="0.002"/><worldbody>
  <geom name="floor" type="plane" size="3 3 0.1"/>
  <geom name="wall_n" type="box" pos="1 0.6 0.15" size="1.2 0.02 0.15"/>
  <geom name="wall_s" type="box" pos="1 -0.6 0.15" size="1.2 0.02 0.15"/>
  <geom name="wall_e" type="box" pos="2.2 0 0.15" size="0.02 0.6 0.15"/>
  <body name="ball" pos="0 0 0.05"><freejoint/><geom type="sphere" size="0.05" solref="0.005 0.3"/></body>
  <body name="target" pos="1.0 0 0.05"><freejoint/><geom type="sphere" size="0.05" solref="0.005 0.3"/></body>
</worldbody></mujoco>"""
BANK_FATES = {"format": "nbst-fates", "version": 1, "scene": "bank.xml", "timestep": 0.001, "duration": 2.0,
              "controls": {"ball": {"linvel": [[0.5, 4], [-3, 3], [0, 0]]}},
              "fates": {"ball": {"hits": ["target"], "rest_in": {"min": [1.6, 0.2, 0], "max": [2.2, 0.6, 0.2]}},
                        "target": {"never_hits": ["wall_e"]}},
              "noise": {"ball": {"linvel": 0.02}}}


@pytest.mark.slow
def test_with_robust_the_first_answer_is_the_robust_pick(tmp_path):
    """A demanding user (issue 46; this scene is theirs): with --robust and --answers, answers[0] kept
    the search's motion (its x, final state and sequence) beside the robust pick's probability. The
    first answer is the file's own: the pick, with its own state and probability; no sequence twice."""
    (tmp_path / "bank.xml").write_text(BANK)
    (tmp_path / "bank.json").write_text(json.dumps(BANK_FATES))
    plain = solve(None, tmp_path / "bank.json", seed=2, max_rollouts=1000, answers=3)
    res = solve(None, tmp_path / "bank.json", seed=2, max_rollouts=1000, answers=3, samples=50, robust=100)
    assert res.robust is not None and res.answers
    assert res.best.x.tobytes() != plain.best.x.tobytes()   # the robust pick moved the motion
    first = res.answers[0]
    assert first is res.best and first.x.tobytes() == res.best.x.tobytes()
    assert first.qpos.tobytes() == res.best.qpos.tobytes()
    assert res.answer_probabilities[0] is res.probability
    assert len({a.sequence for a in res.answers}) == len(res.answers)
    d = solution_dict(res)
    assert d["answers"][0]["x"] == d["x"] and d["answers"][0]["sequence"] == list(first.sequence)


def test_replay_ladder_rolls_the_same_state_out_at_h_2_and_h_4(toss, tmp_path, capsys):
    from nbst.scene.solution import ladder_solution

    sol = tmp_path / "sol.json"
    assert main(["scene", "solve", str(toss), "-o", str(sol), "--seed", "7", "--max-rollouts", "600", "-q"]) == 0
    lad = ladder_solution(sol)
    assert lad.timesteps == [0.01, 0.005, 0.0025] and lad.outcomes[0] is True
    assert [len(r.qpos0) for r in lad.results] == [14, 14, 14]
    assert all(r.qpos0.tobytes() == lad.results[0].qpos0.tobytes() for r in lad.results)  # one initial state
    rc = main(["scene", "replay", str(sol), "--ladder", "--json"])
    out = json.loads(capsys.readouterr().out)
    assert out["identical"] and [r["met"] for r in out["ladder"]["rungs"]] == lad.outcomes
    assert rc == (0 if lad.holds else 1)


def test_solve_with_the_ladder_keeps_only_answers_met_at_h_2_and_h_4(toss, tmp_path):
    """ladder=True: the answer also meets every fate at h/2 and h/4 (replayed there, it does);
    without it the same seed's search is unchanged."""
    from nbst.scene.solution import ladder_solution

    res = solve(None, toss, seed=7, max_rollouts=1500, ladder=True)
    assert res.met and res.ladder_held is True and res.ladder == (0.01, 0.005, 0.0025)
    p = tmp_path / "sol.json"
    p.write_text(json.dumps(solution_dict(res)))
    assert json.loads(p.read_text())["ladder"]["holds"] is True
    assert ladder_solution(p).holds


@pytest.mark.parametrize("sequences", [False, True])
def test_mujoco_rollout_with_sensors_is_the_python_loop(toss, sequences):
    """The rollouts run on mujoco.rollout, the path and the touches read from sensors added to a copy
    of the scene: the same final state bit for bit, the same verdicts, touch times and contact
    sequences as the plain mj_step loop reading MjData.xpos and MjData.contact between the steps."""
    f, model = load_fates(toss)
    lo, hi = f.bounds()
    xs = lo + (hi - lo) * np.random.default_rng(3).random((12, f.dim))
    xs[0] = [4.0, 0, 3.0, 0, 0, 0, 0, 0, 0]  # into the wall: a touch to find
    with SceneSim(f, model, sequences=sequences) as a, SceneSim(f, model, sequences=sequences, loop=True) as b:
        assert a.engine == "mujoco.rollout" and b.engine == "mj_step loop"
        ra, rb = a.run(xs), b.run(xs)
    for x, y in zip(ra, rb):
        assert x.qpos.tobytes() == y.qpos.tobytes() and x.qvel.tobytes() == y.qvel.tobytes()
        assert x.judgement == y.judgement and x.sequence == y.sequence
    assert ra[0].judgement.bodies[0].fates[1].happened == "touched wall"
    if sequences:
        assert "ball-wall" in ra[0].sequence and "ball-floor" in ra[1].sequence + ra[2].sequence


def test_a_key_with_controls_and_mocap_rolls_out_as_the_loop(tmp_path):
    """A key's ctrl and mocap pose, which mujoco.rollout would reset, are given to it as constant
    controls: the arm the key drives turns, bit for bit as in the plain loop."""
    (tmp_path / "arm.xml").write_text("""<mujoco>
  <option timestep="0.005"/>
  <worldbody>
    <geom name="floor" type="plane" size="2 2 0.1"/>
    <body name="mark" mocap="true" pos="0 0 2"><geom type="sphere" size="0.02" contype="0" conaffinity="0"/></body>
    <body name="arm" pos="0 0 0.5"><joint name="hinge" type="hinge" axis="0 0 1"/>
      <geom type="capsule" fromto="0 0 0 0.4 0 0" size="0.02"/></body>
    <body name="ball" pos="0.3 0.3 0.1"><freejoint/><geom type="sphere" size="0.05"/></body>
  </worldbody>
  <actuator><motor joint="hinge" gear="1"/></actuator>
  <keyframe><key name="go" qpos="0 0.3 0.3 0.1 1 0 0 0" ctrl="0.5" mpos="1 0 2" mquat="1 0 0 0"/></keyframe>
</mujoco>""")
    doc = {"format": "nbst-fates", "version": 1, "scene": "arm.xml", "keyframe": "go", "duration": 0.5,
           "controls": {"ball": {"linvel": [[-1, 1], [-1, 1], [0, 1]]}},
           "fates": {"ball": {"never_hits": ["arm"]}, "arm": {"still": True}}}
    (tmp_path / "arm.json").write_text(json.dumps(doc))
    f, model = load_fates(tmp_path / "arm.json")
    with SceneSim(f, model) as a, SceneSim(f, model, loop=True) as b:
        assert a.engine == "mujoco.rollout"
        ra, rb = a.rollout(np.array([0.2, 0.1, 0.5])), b.rollout(np.array([0.2, 0.1, 0.5]))
    assert ra.qpos.tobytes() == rb.qpos.tobytes() and ra.judgement == rb.judgement
    assert abs(ra.qpos[0]) > 0.1  # the key's torque turned the arm


def test_solve_robust_writes_the_pick_with_its_fresh_probability_and_ladder(toss, tmp_path):
    """--robust: after the search, the robust maximiser's pick; its probability measured afresh from
    --samples copies (a Wilson interval around k/n), its ladder rows h, h/2, h/4; it replays."""
    out = tmp_path / "r.json"
    assert main(["scene", "solve", str(toss), "-o", str(out), "--seed", "7", "--max-rollouts", "600", "--jobs", "1",
                 "--robust", "24", "--samples", "12", "-q"]) in (0, 1)
    d = json.loads(out.read_text())
    p, rb = d["probability"], d["robust"]
    assert p["n"] == 12 and p["lo"] <= p["p"] <= p["hi"] and p["p"] == p["k"] / 12
    assert rb["budget"] == 24 and rb["rollouts"] >= rb["screen"][1] and rb["screen"][0] >= rb["start_screen"][0]
    assert [row["timestep"] for row in rb["ladder"]] == [0.01, 0.005, 0.0025]
    assert main(["scene", "replay", str(out)]) == 0


def test_jobs_and_cluster_are_one_or_the_other(toss, tmp_path, capsys):
    with pytest.raises(SystemExit) as e:
        main(["scene", "solve", str(toss), "-o", str(tmp_path / "x.json"), "--jobs", "2", "--cluster",
              "tcp://127.0.0.1:1"])
    assert e.value.code == 2 and not (tmp_path / "x.json").exists()
    assert "not allowed with argument" in capsys.readouterr().err


@pytest.mark.slow
def test_a_dask_cluster_gives_the_same_solution_as_threads(toss):
    from dask.distributed import LocalCluster

    a = solve(None, toss, seed=7, max_rollouts=300, jobs=1)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as lc:
        b = solve(None, toss, seed=7, max_rollouts=300, cluster=lc.scheduler_address)
    assert a.rollouts == b.rollouts and a.best.x.tobytes() == b.best.x.tobytes()
    assert a.best.qpos.tobytes() == b.best.qpos.tobytes() and a.met == b.met


FLYBY = """<mujoco model="flyby">
  <option timestep="0.005" gravity="0 0 0"/>
  <worldbody>
    <geom name="post" type="sphere" pos="0.5 -0.25 0" size="0.05"/>
    <body name="a" pos="0 0 0"><freejoint/><geom type="sphere" size="0.05"/></body>
    <body name="b" pos="1 0.3 0"><freejoint/><geom type="sphere" size="0.05"/></body>
  </worldbody>
</mujoco>
"""


@pytest.mark.parametrize("loop", [False, True])
def test_a_hits_miss_is_graded_by_the_closest_approach_of_the_two_spheres(tmp_path, loop):
    """No gravity: ball a (r 5 cm) flies along +x at 1 m/s past ball b, whose centre is 0.3 m off
    its line at x = 1, and past a world sphere (r 5 cm) 0.25 m off it at x = 0.5: it touches
    neither. The least gaps are 0.3 - 0.1 = 0.2 m and 0.25 - 0.1 = 0.15 m (at x = 1 and 0.5, on
    recorded steps), the gaps at the start sqrt(1.09) - 0.1 and sqrt(0.3125) - 0.1 m (within
    1e-9 m), on either rollout path; the judge's ``hits`` cost is 2 plus their ratios."""
    (tmp_path / "flyby.xml").write_text(FLYBY)
    doc = {"format": "nbst-fates", "version": 1, "scene": "flyby.xml", "duration": 2.0,
           "controls": {"a": {"linvel": [[1, 1], [0, 0], [0, 0]]}},
           "fates": {"a": {"hits": ["b", "post"]}}}
    (tmp_path / "flyby.json").write_text(json.dumps(doc))
    f, model = load_fates(tmp_path / "flyby.json")
    with SceneSim(f, model, loop=loop) as sim:
        r = sim.rollout(np.array([1.0, 0.0, 0.0]))
    near = dict(zip(("b", "post"), ((0.2, math.sqrt(1.09) - 0.1), (0.15, math.sqrt(0.3125) - 0.1))))
    hits = r.judgement.bodies[0].fates[0]
    assert hits.fate == "hits" and not hits.met and hits.happened == "first touches: none"
    from nbst.scene.rollout import closest_approach
    assert sim.engine == ("mj_step loop" if loop else "mujoco.rollout")
    got = closest_approach(sim, np.array([[[t, 0, 0], [1, 0.3, 0]] for t in np.arange(400) * 0.005]))[0]
    for name, (least, start) in near.items():
        assert abs(got[name][0] - least) < 1e-9 and abs(got[name][1] - start) < 1e-9
    assert abs(hits.cost - (2 + sum(a / b for a, b in near.values()))) < 1e-9


def test_pick_writes_an_answer_as_a_solution_every_command_takes(toss, tmp_path, capsys):
    """A fifth new user could not use answer 1 or 2 (replay, render and export read the file's own
    state only). `nbst scene pick SOL N` writes answer N as a solution: its states replay bit for
    bit in the plain loop, its fates are judged anew (met), its ladder holds, its probability is the
    answer's, and export plays it from its key; N past the answers is one line, exit 2."""
    doc = json.loads(toss.read_text())
    doc["fates"]["ball"] = {"never_hits": ["cube"]}
    toss.write_text(json.dumps(doc))
    sol = tmp_path / "sol.json"
    assert main(["scene", "solve", str(toss), "-o", str(sol), "--seed", "7", "--max-rollouts", "600", "--jobs", "1",
                 "--answers", "3", "--samples", "4", "-q"]) == 0
    answers = json.loads(sol.read_text())["answers"]
    for n in (1, 2):
        out = tmp_path / f"a{n}.json"
        assert main(["scene", "pick", str(sol), str(n), "-o", str(out)]) == 0
        d = json.loads(out.read_text())
        assert d["qpos0"] == answers[n]["qpos0"] and d["final"] == answers[n]["final"]
        assert d["met"] and d["ladder"]["holds"] and d["probability"] == answers[n]["probability"]
        assert d["picked"]["answer"] == n and d["picked"]["sequence"] == answers[n]["sequence"]
        assert main(["scene", "replay", str(out), "--ladder"]) == 0
        assert main(["scene", "export", str(out), "-o", str(tmp_path / f"a{n}.xml")]) == 0
    capsys.readouterr()
    assert main(["scene", "pick", str(sol), "3", "-o", str(tmp_path / "a3.json")]) == 2
    err = capsys.readouterr().err
    assert "no answer 3; it has 3 (0 to 2)" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "a3.json").exists()
