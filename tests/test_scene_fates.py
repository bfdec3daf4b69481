"""The fates file (nbst.scene.fates, nbst.scene.scenefile): a good file loads into frozen
dataclasses; every bad input is refused in one line naming the file and the field (FatesError, an
InputError), and `nbst scene solve` then exits 2 with nothing written."""
import copy
import dataclasses
import json
import os
from pathlib import Path

import pytest

from nbst.cli.main import main
from nbst.errors import InputError
from nbst.scene.fates import (AT_REST_SPEED, MAX_MESH_BYTES, MAX_STEPS, STILL_DISTANCE, Fates, FatesError,
                              parse_fates)
from nbst.scene.scenefile import check_scene_files, load_fates

XML = """<mujoco model="t">
  <option timestep="0.01"/>
  <worldbody>
    <geom name="floor" type="plane" size="2 2 0.1"/>
    <body name="ball" pos="0 0 0.5"><freejoint/><geom name="ball_g" type="sphere" size="0.05"/></body>
    <body name="post" pos="1 0 0.2"><geom name="post_g" type="box" size="0.05 0.05 0.2"/></body>
    <body name="arm" pos="-1 0 0.2"><joint name="hinge" type="hinge"/><geom type="capsule" size="0.02 0.1"/></body>
  </worldbody>
  <keyframe><key name="high" qpos="0 0 1 1 0 0 0 0"/></keyframe>
</mujoco>
"""

DOC = {"format": "nbst-fates", "version": 1, "scene": "t.xml", "duration": 0.5,
       "controls": {"ball": {"linvel": [[0, 1], [-1, 1], [0, 0]], "angvel": [[0, 0], [0, 0], [-1, 1]]}},
       "fates": {"ball": {"rest_in": {"center": [1, 0, 0], "radius": 0.2}, "never_hits": ["post"], "at_rest": True},
                 "post": {"still": True}}}


def _write(tmp_path: Path, doc, xml: str = XML) -> Path:
    (tmp_path / "t.xml").write_text(xml)
    p = tmp_path / "f.json"
    p.write_text(json.dumps(doc) if not isinstance(doc, str) else doc)
    return p


def test_a_good_file_loads_into_frozen_dataclasses(tmp_path):
    f, model = load_fates(_write(tmp_path, DOC))
    assert isinstance(f, Fates) and model.nbody == 4  # world, ball, post, arm
    assert [c.body for c in f.controls] == ["ball"] and [x.body for x in f.fates] == ["ball", "post"]
    assert f.dim == 6 and f.controls[0].noise == (0.02,) * 3 + (0.2,) * 3
    lo, hi = f.bounds()
    assert list(lo) == [0, -1, 0, 0, 0, -1] and list(hi) == [1, 1, 0, 0, 0, 1]
    assert f.fates[0].asks() == ["rest_in", "never_hits", "at_rest"]
    with pytest.raises(dataclasses.FrozenInstanceError):
        f.duration = 2.0  # type: ignore[misc]
    assert 0 < AT_REST_SPEED < 1 and STILL_DISTANCE == 0.01 and MAX_STEPS >= 10_000


def _bad(**change):
    doc = copy.deepcopy(DOC)
    for path, value in change.items():
        keys = path.split("__")
        d = doc
        for k in keys[:-1]:
            d = d[int(k)] if isinstance(d, list) else d[k]
        if value is KeyError:
            del d[keys[-1]]
        else:
            d[keys[-1]] = value
    return doc


NAN_RANGE = '"linvel": [[0, 1], [NaN, 1], [0, 0]]'
BAD = [
    # (document, the field named, a word of the reason)
    (_bad(format="nbst-fate"), "format", "nbst-fates"),
    (_bad(version=2), "version", "must be 1"),
    (_bad(duraton=1.0), "duraton", "did you mean 'duration'"),
    (_bad(duration=KeyError), "duration", "missing"),
    (_bad(controls__ball__linvel=[[1, 0], [0, 0], [0, 0]]), "controls.ball.linvel[0]", "inverted"),
    (_bad(controls__ball__linvel=[[], [0, 0], [0, 0]]), "controls.ball.linvel[0]", "empty"),
    (_bad(controls__ball__linvel=[[0, 1], [0, 1]]), "controls.ball.linvel", "3 ranges"),
    (_bad(controls__ball__angvle=[[0, 1], [0, 1], [0, 1]]), "controls.ball.angvle", "did you mean 'angvel'"),
    (_bad(controls__ball__linvel=[[0, 1e300], [0, 0], [0, 0]]), "controls.ball.linvel[0][1]", "larger"),
    (_bad(fates__ball__rest_in={"center": [1, 0, 0], "radius": 0}), "fates.ball.rest_in.radius", "positive size"),
    (_bad(fates__ball__rest_in={"center": [1, 0, 0], "radius": -1}), "fates.ball.rest_in.radius", "positive size"),
    (_bad(fates__ball__rest_in={"min": [0, 0, 0], "max": [1, 0, 1]}), "fates.ball.rest_in.max[1]", "positive size"),
    (_bad(fates__ball__rest_in={"center": [1, 0, 0], "min": [0, 0, 0]}), "fates.ball.rest_in", "not both"),
    (_bad(fates__ball__rest_in={"min": [0, 0, 0], "max": [1, 1, 1], "radius": 1}), "fates.ball.rest_in", "not both"),
    (_bad(fates__ball__rest_in={"min": [0, 0, 0], "max": [1, 1, 1], "mid": 1}), "fates.ball.rest_in.mid", "unknown"),
    (_bad(fates__ball__at=[{"t": 9, "in": {"center": [0, 0, 0], "radius": 1}}]), "fates.ball.at[0].t", "after"),
    (_bad(fates__ball__up={"axis": [0, 0, 0], "within_deg": 10}), "fates.ball.up.axis", "zero"),
    (_bad(fates__ball__at_rest="yes"), "fates.ball.at_rest", "true or false"),
    (_bad(fates__ball__rest=True), "fates.ball.rest", "unknown key"),
    (_bad(noise={"ball": {"linvel": -1}}), "noise.ball.linvel", ">= 0"),
    (_bad(noise={"cube": {"linvel": 1}}), "noise.cube", "unknown key"),
    # an empty list asks nothing (as an empty "through" or "at", refused); a name both hit and never hit
    (_bad(fates__ball__hits=[]), "fates.ball.hits", "non-empty list"),
    (_bad(fates__ball__hits=["post"]), "fates.ball.never_hits", "'post' is in hits too"),
    # noise on a part the search does not choose would be silently ignored: refused by name
    (_bad(noise={"ball": {"pos": 0.01}}), "noise.ball.pos", "chooses no pos"),
    # what the file is comes first: another version, or another of nbst's files, is told so
    ({"format": "nbst-fates", "version": 2}, "version", "must be 1"),
    ({"format": "nbst-scene-solution", "version": 1, "fates_file": "f.json", "x": []}, "format", "fates_file"),
]


@pytest.mark.parametrize("doc, field, why", BAD, ids=[b[1] + ":" + b[2] for b in BAD])
def test_a_bad_field_is_refused_in_one_line_naming_file_and_field(tmp_path, doc, field, why):
    p = _write(tmp_path, doc)
    with pytest.raises(FatesError) as e:
        load_fates(p)
    msg = str(e.value)
    assert isinstance(e.value, InputError) and "\n" not in msg
    assert msg.startswith(f"{p}: {field}: ") and why in msg, msg


@pytest.mark.parametrize("text, why", [
    (json.dumps(DOC).replace('"duration": 0.5', '"duration": NaN'), "finite"),
    (json.dumps(DOC).replace('"duration": 0.5', '"duration": Infinity'), "finite"),
    (json.dumps(DOC).replace('"duration": 0.5', '"duration": 1' + "0" * 40), "15 digits"),
    ('{"format": "nbst-fates", ', "not JSON"),
    ("[" * 100_000 + "]" * 100_000, "nested too deeply"),
    (json.dumps(DOC).replace('"duration": 0.5', '"duration": 0.5, "duration": 0.7'), "'duration' appears twice"),
])
def test_non_finite_and_huge_numbers_are_refused(tmp_path, text, why):
    p = _write(tmp_path, text)
    with pytest.raises(FatesError, match=why):
        load_fates(p)


def _scene_bad(tmp_path, xml, doc=DOC):
    p = _write(tmp_path, doc, xml)
    with pytest.raises(FatesError) as e:
        load_fates(p)
    assert "\n" not in str(e.value) and str(e.value).startswith(str(p))
    return str(e.value)


def test_mjcf_that_does_not_compile_gives_mujocos_message_with_the_line(tmp_path):
    msg = _scene_bad(tmp_path, XML.replace('type="sphere" size="0.05"', 'type="sphere" size="oops"'))
    assert "scene:" in msg and "MuJoCo will not compile it" in msg and "line" in msg


@pytest.mark.parametrize("change, field, why", [
    ({"controls": {"bal": {"linvel": [[0, 1], [0, 1], [0, 1]]}}}, "controls.bal", "did you mean 'ball'"),
    ({"controls": {"post": {"linvel": [[0, 1], [0, 1], [0, 1]]}}}, "controls.post", "no free joint"),
    ({"controls": {"arm": {"linvel": [[0, 1], [0, 1], [0, 1]]}}}, "controls.arm", "no free joint"),
    ({"fates": {"ball": {"hits": ["pots"]}}}, "fates.ball.hits", "no body or geom 'pots'"),
    ({"fates": {"ball": {"never_hits": ["ball"]}}}, "fates.ball.never_hits", "the body itself"),
    # a new user's slips: a typo of a body or geom name gets the nearest name; a geom of the body
    # itself can never be touched by it (MuJoCo does not collide a body with itself)
    ({"fates": {"ball": {"hits": ["pst"]}}}, "fates.ball.hits", "did you mean 'post'"),
    ({"fates": {"ball": {"hits": ["post_gg"]}}}, "fates.ball.hits", "did you mean 'post_g'"),
    ({"fates": {"ball": {"hits": ["post", "ball_g"]}}}, "fates.ball.hits", "a geom of 'ball' itself"),
    ({"fates": {"nobody": {"still": True}}}, "fates.nobody", "no body"),
    ({"keyframe": "low"}, "keyframe", "no key 'low' in t.xml (its keys: high)"),
    ({"keyframe": "hihg"}, "keyframe", "did you mean 'high'"),   # a demanding user's typo
    ({"duration": 5000.0}, "duration", "steps"),
])
def test_names_the_model_lacks_and_bodies_without_free_joint_are_refused(tmp_path, change, field, why):
    doc = {**DOC, **change}
    p = _write(tmp_path, doc)
    with pytest.raises(FatesError) as e:
        load_fates(p)
    assert str(e.value).startswith(f"{p}: {field}: ") and why in str(e.value), str(e.value)


def test_files_outside_the_scenes_folder_are_refused(tmp_path):
    scene = tmp_path / "scene"
    scene.mkdir()
    (tmp_path / "secret.xml").write_text("<mujoco/>")
    (tmp_path / "far.stl").write_bytes(b"solid x\nendsolid x\n")
    cases = [
        ('<include file="../secret.xml"/>', "include"),
        ('<asset><mesh name="m" file="../far.stl"/></asset>', "mesh"),
        ('<compiler meshdir=".."/><asset><mesh name="m" file="far.stl"/></asset>', "mesh"),
        ('<compiler assetdir="/"/><asset><texture name="t" type="2d" file="etc/x.png"/></asset>', "texture"),
        ('<asset><hfield name="h" file="/etc/hostname"/></asset>', "hfield"),
        ('<asset><texture name="c" type="cube" fileup="../far.png"/></asset>', "texture"),
        ('<worldbody><flexcomp name="f" type="mesh" file="../far.stl" dim="2"/></worldbody>', "flexcomp"),
    ]
    for extra, tag in cases:
        (scene / "s.xml").write_text(XML.replace('<option timestep="0.01"/>', extra))
        doc = {**DOC, "scene": "scene/s.xml"}
        p = _write(tmp_path, doc)
        with pytest.raises(FatesError) as e:
            load_fates(p)
        msg = str(e.value)
        assert f"<{tag} " in msg and "outside the scene's folder" in msg and "\n" not in msg, (extra, msg)


def test_a_link_out_of_the_folder_is_refused_and_a_big_mesh_too(tmp_path):
    scene = tmp_path / "scene"
    scene.mkdir()
    (tmp_path / "far.stl").write_bytes(b"solid x\nendsolid x\n")
    os.symlink(tmp_path / "far.stl", scene / "near.stl")
    (scene / "s.xml").write_text(XML.replace('<option timestep="0.01"/>',
                                             '<asset><mesh name="m" file="near.stl"/></asset>'))
    with pytest.raises(FatesError, match="outside the scene's folder"):
        check_scene_files(scene / "s.xml")
    with open(scene / "big.stl", "wb") as f:
        f.truncate(MAX_MESH_BYTES + 1)
    (scene / "s.xml").write_text(XML.replace('<option timestep="0.01"/>',
                                             '<asset><mesh name="m" file="big.stl"/></asset>'))
    with pytest.raises(FatesError, match="larger than"):
        check_scene_files(scene / "s.xml")


def test_an_include_inside_the_folder_is_read(tmp_path):
    (tmp_path / "part.xml").write_text('<mujoco><worldbody><body name="extra" pos="0 1 1"><freejoint/>'
                                       '<geom type="sphere" size="0.05"/></body></worldbody></mujoco>')
    xml = XML.replace("</worldbody>", "</worldbody>\n  <include file=\"part.xml\"/>")
    doc = {**DOC, "controls": {**DOC["controls"], "extra": {"linvel": [[0, 1], [0, 0], [0, 0]]}}}
    f, model = load_fates(_write(tmp_path, doc, xml))
    assert [c.body for c in f.controls] == ["ball", "extra"]


def test_parse_fates_alone_needs_no_mujoco(tmp_path):
    f = parse_fates(DOC, "mem", folder=tmp_path)
    assert f.scene == tmp_path / "t.xml" and f.duration == 0.5


@pytest.mark.parametrize("doc", [_bad(version=3), {**DOC, "fates": {"ball": {"hits": ["pots"]}}}])
def test_the_cli_exits_2_with_one_line_and_writes_nothing(tmp_path, capsys, doc):
    p = _write(tmp_path, doc)
    out = tmp_path / "out" / "sol.json"
    for argv in (["scene", "check", str(p)], ["scene", "solve", str(p), "-o", str(out), "-q", "--seed", "1"]):
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and err.startswith("nbst: error: ") and str(p) in err
    assert not out.exists() and not out.parent.exists()


def test_the_cli_refuses_a_folder_or_fifo_for_o(tmp_path, capsys):
    p = _write(tmp_path, DOC)
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    for target in (tmp_path, fifo):
        assert main(["scene", "solve", str(p), "-o", str(target), "-q", "--seed", "1", "--max-rollouts", "8"]) == 2
        assert capsys.readouterr().err.count("\n") == 1


RICH = {"format": "nbst-fates", "version": 1, "scene": "t.xml", "keyframe": "high", "timestep": 0.01, "duration": 0.5,
        "description": "x",
        "controls": {"ball": {"linvel": [[0, 1], [-1, 1], [0, 0]], "angvel": [[0, 0], [0, 0], [-1, 1]],
                              "pos": [[0, 0.1], [0, 0], [0, 0]]}},
        "fates": {"ball": {"rest_in": {"min": [0, 0, 0], "max": [1, 1, 1]},
                           "at": [{"t": 0.2, "in": {"center": [0, 0, 1], "radius": 0.5}}],
                           "through": [{"center": [0, 0, 1], "radius": 0.5}], "up": {"axis": [0, 0, 1], "within_deg": 30},
                           "hits": ["floor"], "never_hits": ["post_g"], "at_rest": True},
                  "post": {"still": True}},
        "noise": {"ball": {"linvel": 0.1, "angvel": [0.1, 0.2, 0.3], "pos": 0.001}}}


def _leaves(doc, path=()):
    if isinstance(doc, dict):
        for k, v in doc.items():
            yield from _leaves(v, path + (k,))
    elif isinstance(doc, list):
        for k, v in enumerate(doc):
            yield from _leaves(v, path + (k,))
    yield path


def test_any_wrong_value_anywhere_is_a_fates_error_never_a_crash(tmp_path):
    """Every key and element of a file that asks everything, replaced in turn by a value of each
    wrong kind: the loader either accepts it or refuses it in one line (never a traceback)."""
    f, _ = load_fates(_write(tmp_path, RICH))
    assert f.fates[0].asks() == ["rest_in", "at", "through", "up", "hits", "never_hits", "at_rest"]
    tried = 0
    for path in _leaves(RICH):
        if not path:
            continue
        for bad in (None, "x", [], True, -1, [[1, 2]]):
            doc = copy.deepcopy(RICH)
            d = doc
            for k in path[:-1]:
                d = d[k]
            d[path[-1]] = bad
            tried += 1
            try:
                load_fates(_write(tmp_path, doc))
            except FatesError as e:
                assert "\n" not in str(e)
    assert tried > 400


def test_a_mesh_under_meshdir_in_the_folder_is_read_and_solved(tmp_path):
    """A scene no one here wrote: a mesh body (an OBJ tetrahedron under <compiler meshdir>), read,
    compiled, rolled out and judged."""
    from nbst.scene.api import solve

    (tmp_path / "assets").mkdir()
    (tmp_path / "assets" / "tet.obj").write_text("v 0 0 0\nv 0.1 0 0\nv 0 0.1 0\nv 0 0 0.1\n"
                                                 "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n")
    xml = ('<mujoco><compiler meshdir="assets"/><asset><mesh name="tet" file="tet.obj"/></asset>'
           '<worldbody><geom name="floor" type="plane" size="2 2 0.1"/>'
           '<body name="tet" pos="0 0 0.2"><freejoint/><geom type="mesh" mesh="tet"/></body></worldbody></mujoco>')
    doc = {"format": "nbst-fates", "version": 1, "scene": "t.xml", "duration": 0.5,
           "controls": {"tet": {"linvel": [[0, 2], [-0.5, 0.5], [0, 1]]}},
           "fates": {"tet": {"rest_in": {"center": [0.4, 0, 0], "radius": 0.15}}}}
    p = _write(tmp_path, doc, xml)
    assert [f.name for f in check_scene_files(tmp_path / "t.xml")] == ["t.xml", "tet.obj"]
    res = solve(None, p, seed=1, max_rollouts=400)
    assert res.met and res.best.judgement.bodies[0].fates[0].met
