"""What a sixth new user with only the docs met on scenes of unusual MJCF (height fields, flexes,
sites, a body and a geom of one name; issue 46, docs/results/scene.md, "Tried by a sixth new
user"): each case a test that failed before its fix."""
import json
import shutil

import pytest

from nbst.cli.main import main

#: a ball, a wall geom and a free crate, the crate and the wall both called `target` unless renamed
AMBIGUOUS = """<mujoco model="amb">
  <option timestep="0.01"/>
  <worldbody>
    <geom name="floor" type="plane" size="3 3 0.1"/>
    <geom name="target" type="box" pos="1 0 0.2" size="0.05 0.5 0.2"/>
    <site name="mark" pos="0 1 0"/>
    <body name="ball" pos="0 0 0.05"><freejoint/><geom type="sphere" size="0.05"/>
      <site name="ballsite"/></body>
    <body name="BODYNAME" pos="-1 0 0.1"><freejoint/><geom name="crate_g" type="box" size="0.1 0.1 0.1"/></body>
    <body name="decal" pos="0 -1 0.001"><geom type="box" size="0.1 0.1 0.001" contype="0" conaffinity="0"/></body>
  </worldbody>
</mujoco>
"""
#: a ball and a small cloth (a flex: its vertex bodies have no geoms)
CLOTH = """<mujoco model="cloth">
  <option timestep="0.005"/>
  <worldbody>
    <geom name="floor" type="plane" size="3 3 0.1"/>
    <body name="ball" pos="0 0 0.05"><freejoint/><geom type="sphere" size="0.05"/></body>
    <flexcomp name="cloth" type="grid" count="3 3 1" spacing="0.1 0.1 0.1" pos="1 0 0.3" dim="2" radius="0.005">
      <edge equality="true"/>
    </flexcomp>
  </worldbody>
</mujoco>
"""


def _fates(tmp_path, xml, fates, name="amb"):
    (tmp_path / f"{name}.xml").write_text(xml)
    doc = {"format": "nbst-fates", "version": 1, "scene": f"{name}.xml", "duration": 0.5,
           "controls": {"ball": {"linvel": [[0, 2], [0, 0], [0, 0]]}}, **fates}
    (tmp_path / f"{name}.json").write_text(json.dumps(doc))
    return tmp_path / f"{name}.json"


def _err(capsys, argv):
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "Traceback" not in err, err
    return err


def test_a_name_of_both_a_body_and_a_geom_is_refused(tmp_path, capsys):
    """A wall geom and a free body were both `target`: `hits target` meant the body, silently, and the
    ball that struck the wall every time read 'first touches: none' after 300 rollouts."""
    xml = AMBIGUOUS.replace('name="BODYNAME"', 'name="target"')
    f = _fates(tmp_path, xml, {"fates": {"ball": {"hits": ["target"]}}})
    err = _err(capsys, ["scene", "check", str(f)])
    assert "fates.ball.hits" in err and "names both a body and a geom" in err, err
    # a body and its own geom of one name mean the same geoms: taken as before
    xml = AMBIGUOUS.replace('name="crate_g"', 'name="crate"').replace('name="BODYNAME"', 'name="crate"')
    assert main(["scene", "check", str(_fates(tmp_path, xml, {"fates": {"ball": {"hits": ["crate"]}}}))]) == 0


def test_a_site_named_in_fates_is_told_as_a_site(tmp_path, capsys):
    """`hits: ["ballsite"]` read 'no body or geom' with a suggestion of another body."""
    f = _fates(tmp_path, AMBIGUOUS, {"fates": {"target": {"hits": ["ballsite"]}}})
    err = _err(capsys, ["scene", "check", str(f)])
    assert "no body 'target'" in err   # the fated body first: the wall geom is not a body
    f = _fates(tmp_path, AMBIGUOUS, {"fates": {"ball": {"hits": ["ballsite"]}}})
    assert "'ballsite' is a site of body 'ball'" in _err(capsys, ["scene", "check", str(f)])
    f = _fates(tmp_path, AMBIGUOUS, {"fates": {"mark": {"still": True}}})
    assert "'mark' is a site of body 'world'" in _err(capsys, ["scene", "check", str(f)])


def test_fates_no_motion_can_meet_are_refused(tmp_path, capsys):
    """A fate on the world body, and a still body that must also rest 5 m away, were accepted."""
    f = _fates(tmp_path, AMBIGUOUS, {"fates": {"world": {"still": True}}})
    assert "world body, which never moves" in _err(capsys, ["scene", "check", str(f)])
    f = _fates(tmp_path, AMBIGUOUS, {"fates": {"ball": {"still": True,
                                                        "rest_in": {"center": [5, 0, 0.05], "radius": 0.1}}}})
    err = _err(capsys, ["scene", "check", str(f)])
    assert "fates.ball.rest_in" in err and "4.9 m from where 'ball' starts" in err, err
    # a still body whose region holds its start is fine
    f = _fates(tmp_path, AMBIGUOUS, {"fates": {"ball": {"still": True,
                                                        "rest_in": {"center": [0, 0, 0.05], "radius": 0.1}}}})
    assert main(["scene", "check", str(f)]) == 0


def test_never_hits_of_a_name_it_can_never_touch_is_noted(tmp_path, capsys):
    """`never_hits decal` (contype 0) is always met; the same name in `hits` is refused, but this one
    passed without a word."""
    f = _fates(tmp_path, AMBIGUOUS, {"fates": {"ball": {"never_hits": ["decal", "target"]}}})
    assert main(["scene", "check", str(f)]) == 0
    notes = [ln for ln in capsys.readouterr().out.splitlines() if "note:" in ln]
    assert len(notes) == 1 and "never_hits 'decal'" in notes[0] and "always met" in notes[0], notes


def test_a_flex_is_noted_and_its_names_told(tmp_path, capsys):
    """A cloth (flexcomp) was stepped right but drawn nowhere, with no note; `hits cloth` suggested
    'cloth_9', and `hits cloth_4` was refused with reasons that left out the real one."""
    f = _fates(tmp_path, CLOTH, {"fates": {"ball": {"never_hits": ["floor"]}}}, "cloth")
    assert main(["scene", "check", str(f)]) == 0
    out = capsys.readouterr().out
    assert "1 flex" in out and "draw geoms only" in out, out
    f = _fates(tmp_path, CLOTH, {"fates": {"ball": {"hits": ["cloth"]}}}, "cloth")
    assert "'cloth' is a flex" in _err(capsys, ["scene", "check", str(f)])
    f = _fates(tmp_path, CLOTH, {"fates": {"ball": {"hits": ["cloth_4"]}}}, "cloth")
    assert "'cloth_4' has no geoms" in _err(capsys, ["scene", "check", str(f)])


@pytest.fixture
def solved(tmp_path):
    (tmp_path / "old").mkdir()
    f = _fates(tmp_path / "old", AMBIGUOUS, {"fates": {"ball": {"rest_in": {"center": [0.3, 0, 0.05], "radius": 0.5}}}})
    assert main(["scene", "solve", str(f), "-o", str(f.parent / "sol.json"), "--seed", "1", "--jobs", "1",
                 "--max-rollouts", "8", "-q", "--no-ladder"]) == 0
    return f.parent / "sol.json"


def test_a_moved_folder_with_its_scene_edited_is_told_as_changed(solved, tmp_path, capsys):
    """Moved with its folder and the scene then edited (a comment), replay, render, export and
    validate read 'scene: /old/place/amb.xml: no such file', though the scene was beside it. In place
    the same edit reads 'the scene file changed since it was solved'; moved, it now reads the same."""
    new = tmp_path / "new"
    shutil.copytree(solved.parent, new)
    shutil.rmtree(solved.parent)
    with open(new / "amb.xml", "a") as fh:
        fh.write("<!-- a comment -->\n")
    capsys.readouterr()
    assert main(["scene", "replay", str(new / "sol.json")]) == 0
    assert "the scene file changed since it was solved" in capsys.readouterr().out


def test_the_solution_commands_tell_a_fates_file_and_pick_0(solved, capsys):
    """replay, validate and export of a fates file read 'not a scene solution', where render and
    `nbst export` said 'a fates file: solve it first'; `pick SOL 0` of a solution solved without
    --answers read 'answers: none' though the help says 0 is the solution's own."""
    fates = solved.parent / "amb.json"
    for argv in (["scene", "replay", str(fates)], ["scene", "export", str(fates), "-o", str(solved.parent / "o.xml")],
                 ["scene", "validate", str(fates), "--out-dir", str(solved.parent / "rep")]):
        assert "a fates file, not a solution: solve it first" in _err(capsys, argv)
    err = _err(capsys, ["scene", "pick", str(solved), "0", "-o", str(solved.parent / "p.json")])
    assert "solved without --answers" in err and "the file itself" in err, err


def test_replay_of_a_motion_never_met_says_nothing_of_the_ladder(solved, capsys):
    """An unmet solution read 'not met ...; the file says it does not hold at h/2 and h/4': it was
    never met at h, so there was nothing to hold."""
    doc = json.loads(solved.read_text())
    doc["ladder"] = {"timesteps": [0.01, 0.005, 0.0025], "holds": False}
    fates = json.loads((solved.parent / "amb.json").read_text())
    fates["fates"]["ball"]["rest_in"]["center"] = [2.5, 2.5, 0.05]   # the fates, edited: not met now
    (solved.parent / "amb.json").write_text(json.dumps(fates))
    solved.write_text(json.dumps(doc))
    capsys.readouterr()
    assert main(["scene", "replay", str(solved)]) == 0   # reproduced bit for bit
    out = capsys.readouterr().out
    assert "not met at h" in out and "h/2 and h/4" not in out, out
