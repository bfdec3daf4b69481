"""What a new user with only the docs met when trying scenes no one here wrote (issue 46; the list
in docs/results/scene.md, "Tried by a new user"): each case a test that failed before its fix."""
import json

from nbst.cli.main import main
from nbst.scene import api as scene_api

BALL = """<mujoco model="far">
  <option timestep="0.01"/>
  <worldbody>
    <geom name="floor" type="plane" size="3 3 0.1"/>
    <body name="ball" pos="0 0 0.3"><freejoint/><geom type="sphere" size="0.05"/></body>
  </worldbody>
</mujoco>
"""
#: a ball that can not reach its region: every rollout misses at the scene's step
FAR = {"format": "nbst-fates", "version": 1, "scene": "far.xml", "duration": 0.3,
       "controls": {"ball": {"linvel": [[0, 0.1], [0, 0.1], [0, 0.1]]}},
       "fates": {"ball": {"rest_in": {"center": [5, 5, 0], "radius": 0.1}}}}


def _far(tmp_path):
    (tmp_path / "far.xml").write_text(BALL)
    (tmp_path / "far.json").write_text(json.dumps(FAR))
    return tmp_path / "far.json"


def test_an_interrupted_solve_says_so_in_its_summary(tmp_path, monkeypatch, capsys):
    """Ctrl-C mid-solve wrote the best so far and exited 130, but the summary read like a search that
    ran out of budget ("not met ... after 336 rollouts"); the other solve commands say "interrupted;
    best so far written"."""
    original = scene_api.signature_search

    def interrupted(sim, *, rng, max_rollouts, callback=None, **more):
        def stop(p):
            if p.rollouts >= 8:
                raise KeyboardInterrupt
        return original(sim, rng=rng, max_rollouts=max_rollouts, callback=stop, **more)

    monkeypatch.setattr(scene_api, "signature_search", interrupted)
    out = tmp_path / "sol.json"
    assert main(["scene", "solve", str(_far(tmp_path)), "-o", str(out), "--seed", "1", "--jobs", "1"]) == 130
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert "interrupted; best so far written: not met" in err, err
    assert json.loads(out.read_text())["search"]["stopped"] == "interrupted"


def test_a_motion_missed_at_h_is_not_said_to_miss_the_ladder(tmp_path, capsys):
    """A motion that misses at the scene's step is never rolled out at h/2 and h/4; the summary said
    "not kept at h/2 and h/4" of it, as if it had been."""
    out = tmp_path / "sol.json"
    assert main(["scene", "solve", str(_far(tmp_path)), "-o", str(out), "--seed", "1", "--jobs", "1",
                 "--max-rollouts", "16"]) == 1
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert "not met (cost" in err and "h/2" not in err, err
    # a third new user: which fates the best misses, named (there, the one that could not be met)
    assert "the best misses ball's rest_in" in err, err


def test_the_fates_example_in_formats_md_is_a_good_fates_file(tmp_path):
    """docs/formats.md's example is what a user copies first: it must pass the fates file's checks."""
    import re
    from pathlib import Path

    from nbst.scene.fates import parse_fates

    text = (Path(__file__).resolve().parents[1] / "docs" / "formats.md").read_text()
    section = text.split("## Fates file (JSON)", 1)[1].split("\n## ", 1)[0]
    block = re.search(r"```json\n(.*?)```", section, re.S)
    assert block, "no JSON example in the fates section"
    f = parse_fates(json.loads(block.group(1)), "formats.md", folder=tmp_path)
    assert f.fates[0].asks() == ["rest_in", "through", "never_hits", "at_rest"]


def test_a_misspelt_built_in_is_told_its_name(capsys):
    """`nbst scene check snake-eye` said only "snake-eye: no such file"."""
    assert main(["scene", "check", "snake-eye"]) == 2
    err = capsys.readouterr().err
    assert "did you mean 'snake-eyes'" in err and len(err.strip().splitlines()) == 1, err


def test_check_notes_a_touch_already_there_at_the_start(tmp_path, capsys):
    """A bead resting on the table it must never hit can not meet never_hits whatever the search
    chooses: 3,000 rollouts ran before the verdict said so; `nbst scene check` now notes it up front
    (and a hits name touched from the start, whose first touch is then at 0 s)."""
    xml = BALL.replace('pos="0 0 0.3"', 'pos="0 0 0.05"').replace(
        "</worldbody>", '<body name="post" pos="1 0 0.2"><geom type="box" size="0.05 0.05 0.2"/></body></worldbody>')
    (tmp_path / "far.xml").write_text(xml)
    doc = {**FAR, "fates": {"ball": {"never_hits": ["floor"], "hits": ["post"]}}}
    (tmp_path / "f.json").write_text(json.dumps(doc))
    assert main(["scene", "check", str(tmp_path / "f.json")]) == 0
    out = capsys.readouterr().out
    assert "note: ball already touches floor at the start" in out and "can not be met" in out, out
    assert "post" not in out.split("note:", 1)[1]          # the post is 1 m away: no note of it
    doc["fates"] = {"ball": {"hits": ["floor"]}}
    (tmp_path / "f.json").write_text(json.dumps(doc))
    assert main(["scene", "check", str(tmp_path / "f.json")]) == 0
    assert "its first touch of floor is at 0 s" in capsys.readouterr().out
    (tmp_path / "far.xml").write_text(BALL)                # 25 cm up: nothing noted
    assert main(["scene", "check", str(tmp_path / "f.json")]) == 0
    assert "note:" not in capsys.readouterr().out


def _solved(tmp_path, budget: int):
    """The ball with a region it can reach (f.json), solved at seed 1 without the ladder: (sol.json, the fates)."""
    (tmp_path / "far.xml").write_text(BALL)
    doc = {**FAR, "fates": {"ball": {"rest_in": {"center": [0, 0, 0.05], "radius": 0.5}}}}
    (tmp_path / "f.json").write_text(json.dumps(doc))
    out = tmp_path / "sol.json"
    assert main(["scene", "solve", str(tmp_path / "f.json"), "-o", str(out), "--seed", "1", "--jobs", "1",
                 "--max-rollouts", str(budget), "--no-ladder", "-q"]) == 0
    return out, doc


def test_replay_says_when_the_fates_file_changed_since_the_solve(tmp_path, capsys):
    """A solution names its fates file, which replay, render and validate read again: a user who moved
    a region after solving saw 'not met' for a motion solve had called met, with no word of why."""
    out, doc = _solved(tmp_path, 40)
    assert main(["scene", "replay", str(out)]) == 0
    assert "changed" not in capsys.readouterr().out
    doc["fates"]["ball"]["rest_in"]["center"] = [3, 0, 0.05]        # moved after the solve
    (tmp_path / "f.json").write_text(json.dumps(doc))
    assert main(["scene", "replay", str(out)]) == 0                   # the motion is the same, bit for bit
    said = capsys.readouterr().out
    assert "the fates file changed since it was solved" in said and "not met" in said, said


def test_a_solve_says_when_its_search_is_over_and_the_samples_begin(tmp_path):
    """--samples' noisy rollouts ran after the search's last batch with nothing said: the bar sat
    still for seconds. The callback now hears the phase after the search, before the samples."""
    from nbst.scene.scenefile import load_fates
    fates, _ = load_fates(str(_far(tmp_path)))
    seen = []
    res = scene_api.solve(None, fates, seed=1, max_rollouts=16, jobs=1, samples=4, callback=seen.append)
    assert res.probability is not None and res.probability.n == 4
    assert [p.phase for p in seen if p.phase != "search"] == ["P from 4 noisy rollouts"]
    assert seen[-1].phase != "search" and seen[-1].rollouts == res.rollouts


def _solved_then_edited(tmp_path):
    """A solution of the far ball, then its scene edited (the ball twice as heavy)."""
    out, _ = _solved(tmp_path, 8)
    (tmp_path / "far.xml").write_text(BALL.replace('size="0.05"/>', 'size="0.05" mass="9"/>'))
    return out


def test_export_after_the_scene_changed_says_so(tmp_path, capsys):
    """A third new user (issue 46) edited the scene after solving: export said 'the written file is
    damaged', where the cause is the scene's change (replay said so). Now export says it, exit 2."""
    out = _solved_then_edited(tmp_path)
    capsys.readouterr()
    assert main(["scene", "export", str(out), "-o", str(tmp_path / "e.xml")]) == 2
    err = capsys.readouterr().err
    assert "the scene file changed since it was solved" in err and "damaged" not in err, err
    assert not (tmp_path / "e.xml").exists()


def test_export_names_the_one_other_file_without_dots(tmp_path, capsys):
    """A scene reading one mesh, exported into another folder: the refusal named 'gem.stl, ...'."""
    import struct

    stl = b"\0" * 80 + struct.pack("<I", 4) + b"".join(
        struct.pack("<12fH", 0, 0, 0, *a, *b, *c, 0) for a, b, c in
        [((0, 0, 0), (0.1, 0, 0), (0, 0.1, 0)), ((0, 0, 0), (0, 0.1, 0), (0, 0, 0.1)),
         ((0, 0, 0), (0, 0, 0.1), (0.1, 0, 0)), ((0.1, 0, 0), (0, 0.1, 0), (0, 0, 0.1))])
    (tmp_path / "gem.stl").write_bytes(stl)
    xml = BALL.replace("<worldbody>", '<asset><mesh name="gem" file="gem.stl"/></asset>\n  <worldbody>').replace(
        '<geom type="sphere" size="0.05"/>', '<geom type="mesh" mesh="gem"/>')
    (tmp_path / "far.xml").write_text(xml)
    doc = {**FAR, "fates": {"ball": {"rest_in": {"center": [0, 0, 0.05], "radius": 0.5}}}}
    (tmp_path / "f.json").write_text(json.dumps(doc))
    out = tmp_path / "sol.json"
    main(["scene", "solve", str(tmp_path / "f.json"), "-o", str(out), "--seed", "1", "--jobs", "1",
          "--max-rollouts", "4", "--no-ladder", "-q"])
    other = tmp_path / "elsewhere"
    other.mkdir()
    capsys.readouterr()
    assert main(["scene", "export", str(out), "-o", str(other / "e.xml")]) == 2
    err = capsys.readouterr().err
    assert "reads other files (gem.stl) found relative to its folder" in err, err


def test_check_notes_rolling_friction_that_condim_3_ignores(tmp_path, capsys):
    """A third new user gave the floor rolling friction, left the ball at condim 3 (MuJoCo ignores
    it there) and searched 1,000 rollouts for a ball that could never come to rest. `check` notes
    it; not at condim 6, nor for MuJoCo's default friction, which every geom carries."""
    def check(xml: str) -> str:
        (tmp_path / "far.xml").write_text(xml)
        (tmp_path / "f.json").write_text(json.dumps(FAR))
        assert main(["scene", "check", str(tmp_path / "f.json")]) == 0
        return capsys.readouterr().out

    rough = BALL.replace('size="3 3 0.1"/>', 'size="3 3 0.1" friction="1 0.05 0.03"/>')
    out = check(rough)
    assert "note: ball's contact with floor has rolling friction 0.03 but condim 3: MuJoCo ignores it" in out, out
    assert "torsional friction 0.05 but condim 3" in out, out
    assert "condim 3" not in check(rough.replace('<geom type="sphere" size="0.05"/>',
                                                 '<geom type="sphere" size="0.05" condim="6"/>'))
    assert "note:" not in check(BALL)


def test_a_touch_already_there_at_the_start_is_not_in_the_contact_sequence():
    """A third new user's two answers both began 'bystander-floor', 'top-b2': blocks resting where the
    scene put them, not choices. A first touch in the first step is left out; a later one stays."""
    from nbst.scene.rollout import contact_sequence

    assert contact_sequence([(0, "top", "b2"), (0, "bystander", "floor"), (7, "ball", "top"), (3, "ball", "floor"),
                             (9, "top", "floor")]) == ["ball-floor", "ball-top", "top-floor"]


def test_check_advises_a_step_that_resolves_a_contact_mujoco_held_at_two_steps(tmp_path, capsys):
    """A third new user's stiff coin (solref 0.004 0.1 at a 4 ms step): MuJoCo holds the time constant
    at 2 steps (8 ms), and the note said 'a step of at most 0.59 ms', where at 0.59 ms the contact
    lasts its own 1.2 ms, 2 steps. The step advised is the unheld contact's over 4: 0.296 ms."""
    xml = BALL.replace('timestep="0.01"', 'timestep="0.004"').replace(
        '<geom type="sphere" size="0.05"/>', '<geom type="sphere" size="0.05" solref="0.004 0.1"/>').replace(
        'size="3 3 0.1"/>', 'size="3 3 0.1" solref="0.004 0.1"/>')
    (tmp_path / "far.xml").write_text(xml)
    (tmp_path / "f.json").write_text(json.dumps(FAR))
    assert main(["scene", "check", str(tmp_path / "f.json")]) == 0
    out = capsys.readouterr().out
    assert "MuJoCo holds its time constant at 2 steps, 8 ms" in out, out
    assert "a step of at most 0.296 ms gives it 4" in out, out
