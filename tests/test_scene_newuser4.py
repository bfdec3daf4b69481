"""What a fourth new user with only the docs met (issue 46; docs/results/scene.md, "Tried by a
fourth new user"): each case a test that failed before its fix."""
import json
import os

import pytest

from nbst.cli.main import main

from test_scene_newuser import BALL, _solved, _solved_then_edited


def _one_line(capsys, *words):
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
    for w in words:
        assert w in err, (w, err)
    return err


def test_export_never_writes_over_the_fates_file_it_replays_from(tmp_path, capsys):
    """`scene export sol.json -o fates.json` replaced the fates file with MJCF; the solution, which
    reads it again, was then unusable. Refused now, as the scene and the solution were."""
    out, doc = _solved(tmp_path, 8)
    before = (tmp_path / "f.json").read_bytes()
    capsys.readouterr()
    assert main(["scene", "export", str(out), "-o", str(tmp_path / "f.json")]) == 2
    _one_line(capsys, "is the same file as", "f.json")
    assert (tmp_path / "f.json").read_bytes() == before
    assert main(["scene", "replay", str(out)]) == 0


def test_gltf_export_notes_a_scene_changed_since_the_solve(tmp_path, capsys):
    """render noted the edited scene; `nbst export --gltf` wrote the file silently."""
    out = _solved_then_edited(tmp_path)
    capsys.readouterr()
    assert main(["export", str(out), "--gltf", str(tmp_path / "m.glb")]) == 0
    err = capsys.readouterr().err
    assert "far.xml changed since sol.json was solved" in err and (tmp_path / "m.glb").is_file(), err


def test_a_hits_body_whose_every_geom_is_never_hit_is_refused(tmp_path, capsys):
    """`hits: [b]` beside `never_hits: [b_geom]`, b's only geom, passed check: no motion meets both.
    A body with another geom left to touch stays allowed."""
    xml = BALL.replace("</worldbody>", '<body name="b" pos="1 0 0.05"><freejoint/><geom name="b_geom" '
                       'type="box" size="0.05 0.05 0.05"/></body></worldbody>')
    (tmp_path / "s.xml").write_text(xml)
    doc = {"format": "nbst-fates", "version": 1, "scene": "s.xml", "duration": 0.5,
           "controls": {"ball": {"linvel": [[0, 1], [0, 0.1], [0, 0.1]]}},
           "fates": {"ball": {"hits": ["b"], "never_hits": ["b_geom"]}}}
    (tmp_path / "f.json").write_text(json.dumps(doc))
    assert main(["scene", "check", str(tmp_path / "f.json")]) == 2
    _one_line(capsys, "fates.ball.never_hits", "every geom of 'b'")
    (tmp_path / "s.xml").write_text(xml.replace('<geom name="b_geom"', '<geom name="b_top" type="sphere" '
                                                'size="0.02" pos="0 0 0.06"/><geom name="b_geom"'))
    assert main(["scene", "check", str(tmp_path / "f.json")]) == 0


@pytest.mark.skipif(not hasattr(os, "symlink"), reason="no symbolic links")
def test_a_mesh_linked_from_outside_is_refused_naming_where_the_link_points(tmp_path, capsys):
    """The refusal named the link (inside the folder) as 'outside the scene's folder'."""
    (tmp_path / "elsewhere").mkdir()
    real = tmp_path / "elsewhere" / "m.obj"
    real.write_text("v 0 0 0\nv 0.1 0 0\nv 0 0.1 0\nv 0 0 0.1\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n")
    home = tmp_path / "scene"
    home.mkdir()
    os.symlink(real, home / "m.obj")
    (home / "s.xml").write_text(BALL.replace("<worldbody>", '<asset><mesh name="m" file="m.obj"/></asset><worldbody>'))
    doc = {"format": "nbst-fates", "version": 1, "scene": "s.xml", "duration": 0.1,
           "controls": {"ball": {"linvel": [[0, 1], [0, 0.1], [0, 0.1]]}}, "fates": {"ball": {"at_rest": True}}}
    (home / "f.json").write_text(json.dumps(doc))
    assert main(["scene", "check", str(home / "f.json")]) == 2
    _one_line(capsys, f"(a link to {real.resolve()})", "outside the scene's folder")


def test_render_of_a_fates_file_or_a_scene_says_to_solve_it(tmp_path, capsys):
    """`nbst render fates.json` answered 'is a problem: give its SOLUTION too' (the 2D disks' usage)."""
    _, _ = _solved(tmp_path, 4)
    for name, word in (("f.json", "is a fates file: solve it first"), ("far.xml", "is a MuJoCo scene")):
        assert main(["render", str(tmp_path / name), "-o", str(tmp_path / "v.mp4")]) == 2
        _one_line(capsys, word, "nbst scene solve")
    assert not (tmp_path / "v.mp4").exists()


def test_exported_option_has_its_own_line_and_the_examples_say_where_they_are(tmp_path, capsys):
    """The `<option>` export adds ran into the next tag; `scene examples` did not say where its files are."""
    xml = BALL.replace('  <option timestep="0.01"/>\n', "")
    (tmp_path / "far.xml").write_text(xml)
    doc = {"format": "nbst-fates", "version": 1, "scene": "far.xml", "duration": 0.2, "timestep": 0.005,
           "controls": {"ball": {"linvel": [[0, 0.1], [0, 0.1], [0, 0.1]]}},
           "fates": {"ball": {"rest_in": {"center": [0, 0, 0.05], "radius": 0.5}}}}
    (tmp_path / "f.json").write_text(json.dumps(doc))
    assert main(["scene", "solve", str(tmp_path / "f.json"), "-o", str(tmp_path / "s.json"), "--seed", "1",
                 "--jobs", "1", "--max-rollouts", "4", "--no-ladder", "-q"]) == 0
    assert main(["scene", "export", str(tmp_path / "s.json"), "-o", str(tmp_path / "e.xml")]) == 0
    lines = (tmp_path / "e.xml").read_text().splitlines()
    assert lines[1].strip() == '<option timestep="0.005" />' and lines[2].strip() == "<worldbody>", lines[:3]
    capsys.readouterr()
    assert main(["scene", "examples"]) == 0
    folder = capsys.readouterr().out.strip().splitlines()[-1].split(": ")[-1]
    assert os.path.isfile(os.path.join(folder, "snake-eyes.json")), folder
