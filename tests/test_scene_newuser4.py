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


def test_replay_says_at_which_step_it_judged_and_when_the_file_says_the_ladder_fails(tmp_path, capsys):
    """`scene replay` printed 'met' for a file recorded `met: false` (its ladder failed), with no word
    of the ladder unless --ladder was given."""
    out, _ = _solved(tmp_path, 8)
    doc = json.loads(out.read_text())
    doc["ladder"] = {"timesteps": [doc["timestep"], doc["timestep"] / 2, doc["timestep"] / 4], "holds": False}
    out.write_text(json.dumps(doc))
    capsys.readouterr()
    main(["scene", "replay", str(out)])
    head = capsys.readouterr().out.splitlines()[0]
    assert f"at h = {doc['timestep'] * 1e3:g} ms" in head and "does not hold at h/2 and h/4" in head, head


def test_an_interrupt_while_sampling_keeps_the_searchs_own_stop(tmp_path, monkeypatch, capsys):
    """A fifth new user's search met every fate, then Ctrl-C during --samples: the file said
    `"stopped": "interrupted"`, as if the search had been cut short. The search's stop is kept
    ("met"), `"interrupted"` names the phase cut short, the probability is absent, exit 130."""
    from nbst.scene import api as scene_api

    (tmp_path / "far.xml").write_text(BALL)
    doc = {"format": "nbst-fates", "version": 1, "scene": "far.xml", "duration": 0.3,
           "controls": {"ball": {"linvel": [[0, 0.1], [0, 0.1], [0, 0.1]]}},
           "fates": {"ball": {"rest_in": {"center": [0, 0, 0.05], "radius": 0.5}}}}
    (tmp_path / "f.json").write_text(json.dumps(doc))

    def cut(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(scene_api, "noisy_probability", cut)
    out = tmp_path / "sol.json"
    assert main(["scene", "solve", str(tmp_path / "f.json"), "-o", str(out), "--seed", "1", "--jobs", "1",
                 "--samples", "50", "--no-ladder"]) == 130
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert "interrupted during the samples after the search (no probability): met" in err, err
    d = json.loads(out.read_text())
    assert d["search"]["stopped"] == "met" and d["interrupted"] == "samples" and "probability" not in d


def test_the_python_api_refuses_wrong_types_in_one_line_of_its_own_errors(tmp_path):
    """A fifth new user's `solve(None, None)` raised a TypeError from pathlib, `solution_dict(None)`
    an AttributeError, `max_rollouts=np.int64(30)` was refused while `seed=np.int64(7)` was taken,
    and `jobs=300` passed the CLI's cap of 256."""
    import numpy as np

    from nbst.errors import NbstError, SolveError
    from nbst.scene import solution_dict, solve

    (tmp_path / "far.xml").write_text(BALL)
    doc = {"format": "nbst-fates", "version": 1, "scene": "far.xml", "duration": 0.2,
           "controls": {"ball": {"linvel": [[0, 0.1], [0, 0.1], [0, 0.1]]}},
           "fates": {"ball": {"rest_in": {"center": [0, 0, 0.05], "radius": 0.5}}}}
    (tmp_path / "f.json").write_text(json.dumps(doc))
    for args, kw, words in (((None, None), {}, "fates must be"), ((3, tmp_path / "f.json"), {}, "scene must be"),
                            ((None, tmp_path / "f.json"), {"jobs": 300}, "<= 256")):
        with pytest.raises(SolveError, match=words):
            solve(*args, **kw)
    with pytest.raises(NbstError, match="SceneResult"):
        solution_dict(None)
    res = solve(None, tmp_path / "f.json", seed=np.int64(7), max_rollouts=np.int64(4), ladder=False)
    assert res.max_rollouts == 4 and type(res.max_rollouts) is int and res.rollouts >= 1


def test_check_notes_a_through_passed_at_the_start_and_up_asked_of_a_sphere(tmp_path, capsys):
    """A fifth new user's `through` whose first region held the start was judged passed at 0 s, and
    `up` on a ping-pong ball (a sphere: no face) was searched; `check` said nothing of either."""
    (tmp_path / "far.xml").write_text(BALL)
    doc = {"format": "nbst-fates", "version": 1, "scene": "far.xml", "duration": 0.2,
           "controls": {"ball": {"linvel": [[0, 0.1], [0, 0.1], [0, 0.1]]}},
           "fates": {"ball": {"through": [{"center": [0, 0, 0.3], "radius": 0.2}, {"center": [2, 0, 0.3], "radius": 0.2}],
                              "up": {"axis": [0, 0, 1], "within_deg": 10}}}}
    (tmp_path / "f.json").write_text(json.dumps(doc))
    assert main(["scene", "check", str(tmp_path / "f.json")]) == 0
    notes = [ln for ln in capsys.readouterr().out.splitlines() if "note:" in ln]
    assert any("starts inside through's first region" in ln for ln in notes), notes
    assert any("every geom is a sphere" in ln for ln in notes), notes
    doc["fates"]["ball"]["through"][0]["center"] = [1, 0, 0.3]          # apart from the start: no note
    doc["fates"]["ball"].pop("up")
    (tmp_path / "f.json").write_text(json.dumps(doc))
    assert main(["scene", "check", str(tmp_path / "f.json")]) == 0
    assert "note:" not in capsys.readouterr().out


def test_another_of_nbsts_files_given_as_fates_is_told_by_its_kind(tmp_path, capsys):
    """An audit's crash file and bowling throw got 'format: missing' from `scene check`, and a
    validation report was told to give 'its fates file (a solution keeps it under fates_file)'."""
    for doc, word, hint in (({"kind": "nbst-crash", "schema_version": 1}, "'nbst-crash' file", False),
                            ({"format": "nbst-scene-validation", "version": 1}, "'nbst-scene-validation' file", False),
                            ({"format": "nbst-scene-solution", "version": 1}, "'nbst-scene-solution' file", True)):
        (tmp_path / "x.json").write_text(json.dumps(doc))
        assert main(["scene", "check", str(tmp_path / "x.json")]) == 2
        err = _one_line(capsys, "format: must be 'nbst-fates'", word, "not a fates file")
        assert ("fates_file" in err) == hint, err
