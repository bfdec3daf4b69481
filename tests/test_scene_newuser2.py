"""What a second new user with only the docs met on scenes no one here wrote (issue 46; the list in
docs/results/scene.md, "Tried by a second new user"): each case a test that failed before its fix."""
import json

import numpy as np
import pytest

import test_scene_newuser
from nbst.cli.main import main

#: a ball thrown at a mocap paddle that the key moves and turns (mpos, mquat) from the model's pose
MOCAP = """<mujoco model="mocap">
  <option timestep="0.005"/>
  <worldbody>
    <geom name="floor" type="plane" size="3 3 0.1"/>
    <body name="paddle" mocap="true" pos="1.5 0 0.4"><geom type="box" size="0.02 0.4 0.3"/></body>
    <body name="ball" pos="0 0 0.1"><freejoint/><geom type="sphere" size="0.05"/></body>
  </worldbody>
  <keyframe><key name="start" qpos="0 0 0.1 1 0 0 0" mpos="1.2 0.1 0.3" mquat="0.9659258 0 0 0.2588190"/></keyframe>
</mujoco>
"""
MOCAP_FATES = {"format": "nbst-fates", "version": 1, "scene": "mocap.xml", "keyframe": "start", "duration": 0.2,
               "controls": {"ball": {"linvel": [[0, 0.1], [0, 0], [0, 0]]}},
               "fates": {"ball": {"never_hits": ["paddle"]}}}


def _write(tmp_path, name, xml, fates):
    (tmp_path / f"{name}.xml").write_text(xml)
    (tmp_path / f"{name}.json").write_text(json.dumps(fates))
    return tmp_path / f"{name}.json"


@pytest.fixture
def mocap_solution(tmp_path):
    out = tmp_path / "sol.json"
    assert main(["scene", "solve", str(_write(tmp_path, "mocap", MOCAP, MOCAP_FATES)), "-o", str(out),
                 "--seed", "1", "--jobs", "1", "--max-rollouts", "8", "-q", "--no-ladder"]) == 0
    return out


def test_the_gltf_holds_a_mocap_body_where_the_key_puts_it(mocap_solution, tmp_path):
    """The replay holds a mocap body at its key's mpos/mquat; the glTF put it at the model's body pos
    (1.5, 0, 0.4), unturned, 30 cm and 30 degrees from where the ball met it."""
    import pygltflib

    glb = tmp_path / "x.glb"
    assert main(["export", str(mocap_solution), "--gltf", str(glb)]) == 0
    g = pygltflib.GLTF2().load(str(glb))
    node = next(n for n in g.nodes if n.name == "paddle")
    assert np.allclose(node.translation, [1.2, 0.1, 0.3], atol=1e-6), node.translation
    # glTF (x, y, z, w) of MuJoCo's (w, x, y, z) = 30 degrees about z
    assert np.allclose(node.rotation, [0, 0, 0.2588190, 0.9659258], atol=1e-6), node.rotation


def test_the_video_draws_a_mocap_body_where_the_key_puts_it(mocap_solution):
    """The video's frames posed a mocap body from a fresh MjData (the model's pose), not the key's."""
    from nbst.render.scene.motion import record

    motion, _, m = record(mocap_solution, np.array([0.0, 0.2]))
    b = m.body("paddle").id
    assert np.allclose(motion.body_xpos[:, b], [1.2, 0.1, 0.3], atol=1e-9), motion.body_xpos[:, b]
    # the box's x axis turned 30 degrees about z
    assert np.allclose(motion.body_xmat[0, b][:, 0], [np.cos(np.pi / 6), np.sin(np.pi / 6), 0], atol=1e-6)


#: a bystander box placed 4 cm above the floor: it falls by itself, whatever the ball does
AIR = """<mujoco model="air">
  <option timestep="0.005"/>
  <worldbody>
    <geom name="floor" type="plane" size="3 3 0.1"/>
    <body name="ball" pos="0 0 0.05"><freejoint/><geom type="sphere" size="0.05"/></body>
    <body name="crate" pos="1 1 0.12"><freejoint/><geom type="box" size="0.1 0.1 0.08"/></body>
  </worldbody>
</mujoco>
"""
AIR_FATES = {"format": "nbst-fates", "version": 1, "scene": "air.xml", "duration": 1.0,
             "controls": {"ball": {"linvel": [[0, 0.1], [0, 0], [0, 0]]}},
             "fates": {"crate": {"still": True}}}


def test_check_notes_a_still_body_that_moves_by_itself(tmp_path, capsys):
    """A `still` bystander that falls (placed in the air) or rolls away (a ping-pong ball in the
    scene's wind) can not be met by any control: 2,000 rollouts later the search said only 'moved at
    most 0.04265 m'. `nbst scene check` now says so first; a bystander at rest gets no note."""
    fates = _write(tmp_path, "air", AIR, AIR_FATES)
    assert main(["scene", "check", str(fates)]) == 0
    notes = [ln for ln in capsys.readouterr().out.splitlines() if "note:" in ln]
    assert len(notes) == 1 and "crate moves 0.04" in notes[0] and "by itself" in notes[0], notes
    # the box falls the 4 cm gap (12 cm - 8 cm half height), within MuJoCo's contact softness of 2 mm
    (tmp_path / "air.xml").write_text(AIR.replace('pos="1 1 0.12"', 'pos="1 1 0.08"'))
    assert main(["scene", "check", str(fates)]) == 0
    assert "note:" not in capsys.readouterr().out


def test_the_readout_gives_a_kilometre_region_as_written():
    """A crate that must rest past x = 1,000.5 m read `box (1000, -30, 0)-(1100, 30, 20)` in the video
    (four significant digits), beside a verdict '0.5 m from the region'; 12 km read `1.2e+04`."""
    from nbst.render.scene.readout import region_text
    from nbst.scene.fates import Region

    box = Region(lo=(1000.5, -30.0, 0.0), hi=(12000.0, 30.0, 20.0))
    assert region_text(box) == "box (1000.5, -30, 0)-(12000, 30, 20)"
    ball = Region(center=(0.0165, 0.0, 0.002), radius=0.004)   # millimetres, as before
    assert region_text(ball) == "ball r 0.004 at (0.0165, 0, 0.002)"


def test_a_type_checker_sees_solve_and_the_other_lazy_names():
    """docs/scene.md: `from nbst.scene import solve`, "typed, every keyword spelled out". To mypy it
    was `object` (the package's lazy __getattr__ returns object): `solve(None, ...)` read
    '"object" not callable'. Each lazy name is now imported for the type checker alone."""
    import ast
    from pathlib import Path

    import nbst.scene as pkg

    tree = ast.parse(Path(pkg.__file__).read_text())
    seen = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and isinstance(node.test, ast.Name) and node.test.id == "TYPE_CHECKING":
            for imp in node.body:
                if isinstance(imp, ast.ImportFrom):
                    seen |= {a.asname or a.name for a in imp.names}
    assert set(pkg.__all__) <= seen, sorted(set(pkg.__all__) - seen)


#: a ball and what it may be asked to hit: a ghost (contype 0), a post excluded from the ball, its own
#: child (a parent-child pair), a bell (touchable), and a ghost made touchable by an explicit <pair>
FILTERS = """<mujoco model="filters">
  <worldbody>
    <geom name="floor" type="plane" size="3 3 0.1"/>
    <body name="ball" pos="0 0 0.1"><freejoint/><geom name="ball_geom" type="sphere" size="0.05"/>
      <body name="tail" pos="0 0 0.2"><joint type="hinge"/><geom name="tail_geom" type="capsule" size="0.01 0.05"/></body>
    </body>
    <body name="ghost" pos="1 0 0.1"><geom name="ghost_geom" type="sphere" size="0.05" contype="0" conaffinity="0"/></body>
    <body name="ghost2" pos="1 1 0.1"><geom name="ghost2_geom" type="sphere" size="0.05" contype="0" conaffinity="0"/></body>
    <body name="post" pos="2 0 0.1"><freejoint/><geom type="box" size="0.05 0.05 0.1"/></body>
    <body name="bell" pos="3 0 0.1"><geom type="sphere" size="0.05"/></body>
  </worldbody>
  <contact><exclude body1="post" body2="ball"/><pair geom1="ball_geom" geom2="ghost2_geom"/></contact>
</mujoco>
"""


@pytest.mark.parametrize("name, refused", [("ghost", True), ("ghost_geom", True), ("post", True), ("tail", True),
                                           ("bell", False), ("ghost2", False), ("floor", False)])
def test_a_hits_name_the_body_can_never_touch_is_refused(tmp_path, capsys, name, refused):
    """`"hits": ["lamp"]` of a lamp with contype 0 was accepted: 2,000 rollouts for a touch MuJoCo's
    collision filter never makes. It is refused by name; what the filter lets through is kept."""
    fates = {"format": "nbst-fates", "version": 1, "scene": "filters.xml", "duration": 0.1,
             "controls": {"ball": {"linvel": [[0, 1], [0, 0], [0, 0]]}}, "fates": {"ball": {"hits": [name]}}}
    assert main(["scene", "check", str(_write(tmp_path, "filters", FILTERS, fates))]) == (2 if refused else 0)
    err = capsys.readouterr().err
    assert ("can never touch" in err and f"fates.ball.hits: 'ball' can never touch {name!r}" in err) == refused, err


def test_the_collision_filter_agrees_with_mujoco():
    """The refusal's filter is MuJoCo's: the ball dropped on each neighbour in turn touches exactly
    those the filter lets through (a physical check of the exclude signature and parent filter)."""
    import mujoco

    from nbst.scene.scenefile import _can_touch

    m = mujoco.MjModel.from_xml_string(FILTERS)
    ball = m.body("ball").id
    for name in ("ghost", "ghost2", "post", "bell"):
        d = mujoco.MjData(m)
        d.qpos[:3] = m.body(name).pos + [0, 0, 0.09]    # the ball 9 cm over its centre, overlapping it
        mujoco.mj_forward(m, d)
        other = m.body(name).id
        touched = any({int(m.geom_bodyid[c.geom1]), int(m.geom_bodyid[c.geom2])} == {ball, other}
                      for c in d.contact[:d.ncon])
        assert touched == _can_touch(m, ball, name), name


def test_a_fate_of_false_flags_alone_asks_nothing(tmp_path):
    """`{"lamp": {"still": false}}` was accepted and gave the lamp a signature bit always set, though
    `{"lamp": {}}` is refused as asking nothing."""
    from nbst.scene.fates import FatesError, parse_fates

    doc = {"format": "nbst-fates", "version": 1, "scene": "x.xml", "duration": 1,
           "controls": {"ball": {"linvel": [[0, 1], [0, 0], [0, 0]]}},
           "fates": {"ball": {"at_rest": True}, "lamp": {"still": False, "at_rest": False}}}
    with pytest.raises(FatesError, match=r"fates\.lamp: asks nothing \(every flag false\)"):
        parse_fates(doc, "f.json", folder=tmp_path)
    doc["fates"]["lamp"]["still"] = True
    assert [f.body for f in parse_fates(doc, "f.json", folder=tmp_path).fates] == ["ball", "lamp"]


def test_solve_and_export_never_write_over_the_scenes_own_files(tmp_path, capsys):
    """`nbst scene solve FATES -o scene.xml` wrote the solution's JSON over the user's MJCF (exit 0,
    the scene lost); `nbst scene export SOL -o part.xml` would write over a file the scene includes.
    Both now refuse in one line, exit 2, the file untouched."""
    (tmp_path / "part.xml").write_text('<mujoco><worldbody><geom name="floor" type="plane" size="3 3 0.1"/>'
                                       '</worldbody></mujoco>')
    xml = BALL_INCLUDING
    fates = _write(tmp_path, "inc", xml, {"format": "nbst-fates", "version": 1, "scene": "inc.xml", "duration": 0.1,
                                          "controls": {"ball": {"linvel": [[0, 0.1], [0, 0], [0, 0]]}},
                                          "fates": {"ball": {"never_hits": ["floor"]}}})
    before = {p: (tmp_path / p).read_text() for p in ("inc.xml", "part.xml")}
    for target in ("inc.xml", "part.xml"):
        assert main(["scene", "solve", str(fates), "-o", str(tmp_path / target), "--seed", "1", "--jobs", "1",
                     "--max-rollouts", "4", "-q", "--no-ladder"]) == 2
        assert len(capsys.readouterr().err.strip().splitlines()) == 1
    sol = tmp_path / "sol.json"
    assert main(["scene", "solve", str(fates), "-o", str(sol), "--seed", "1", "--jobs", "1", "--max-rollouts", "4",
                 "-q", "--no-ladder"]) == 0
    assert main(["scene", "export", str(sol), "-o", str(tmp_path / "part.xml")]) == 2
    assert "a file the scene reads" in capsys.readouterr().err
    assert {p: (tmp_path / p).read_text() for p in before} == before


BALL_INCLUDING = """<mujoco model="inc">
  <option timestep="0.01"/>
  <include file="part.xml"/>
  <worldbody>
    <body name="ball" pos="0 0 0.3"><freejoint/><geom type="sphere" size="0.05"/></body>
  </worldbody>
</mujoco>
"""


def test_a_solution_moved_with_its_folder_finds_its_fates_and_scene(tmp_path, capsys):
    """A solution sent with its folder (fates, scene, solution) to a colleague read `weld.json:
    scene: /old/place/weld.xml: no such file` in replay, render, export and validate, the files
    beside it. Now each is taken from beside it when its SHA-256 is the one recorded, and only then."""
    import shutil

    old = tmp_path / "old"
    old.mkdir()
    fates = _write(old, "far", BALL, {"format": "nbst-fates", "version": 1, "scene": "far.xml", "duration": 0.5,
                                     "controls": {"ball": {"linvel": [[0, 0.1], [0, 0], [0, 0]]}},
                                     "fates": {"ball": {"rest_in": {"center": [0, 0, 0.05], "radius": 0.2}}}})
    assert main(["scene", "solve", str(fates), "-o", str(old / "sol.json"), "--seed", "1", "--jobs", "1",
                 "--max-rollouts", "8", "-q", "--no-ladder"]) == 0
    new = tmp_path / "new"
    shutil.copytree(old, new)
    shutil.rmtree(old)
    capsys.readouterr()
    assert main(["scene", "replay", str(new / "sol.json")]) == 0
    assert "reproduced bit for bit" in capsys.readouterr().out
    assert main(["export", str(new / "sol.json"), "--gltf", str(tmp_path / "x.glb")]) == 0
    # an edited fates file is not the one solved: refused, saying so (test_scene_newuser6 has the scene edited)
    (new / "far.json").write_text((new / "far.json").read_text().replace('"radius": 0.2', '"radius": 0.3'))
    assert main(["scene", "replay", str(new / "sol.json")]) == 2
    assert "not the fates file it was solved with" in capsys.readouterr().err


#: the first new user's ball (test_scene_newuser), resting on the floor
BALL = test_scene_newuser.BALL.replace('pos="0 0 0.3"', 'pos="0 0 0.05"')


def test_a_height_field_is_drawn_where_mujoco_collides_with_it():
    """A terrain of `type="hfield"` was not drawn at all (the video showed a ball over the sky, the glTF
    had no ground). Its surface is now drawn as MuJoCo's grid: a vertical ray (mj_ray, MuJoCo's own
    geometry) meets it at each grid point at the drawn height, within 1e-6 m."""
    import mujoco

    from nbst.render.core.geoms import geom_rows

    n = 9
    x = np.linspace(-1, 1, n)
    z = (0.5 + 0.5 * np.sin(3 * x)[None, :] * np.cos(2 * x)[:, None]).ravel()   # rows along y
    xml = f"""<mujoco><asset><hfield name="hill" nrow="{n}" ncol="{n}" size="2 1.5 0.4 0.05"
      elevation="{' '.join(f'{v:.4f}' for v in z)}"/></asset>
      <worldbody><geom name="terrain" type="hfield" hfield="hill" pos="0.3 -0.2 0.1"/></worldbody></mujoco>"""
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    rows = geom_rows(m, 0).astype(float)
    assert rows is not None and np.all(rows[:, 5] > 0)          # every facet faces up
    drawn = {(round(px, 6), round(py, 6)): pz for px, py, pz in rows[:, :3]}
    gid = np.zeros(1, np.int32)
    for px, py in [(-1.5, -0.75), (0.0, 0.0), (1.0, 1.125), (0.5, -1.125)]:   # interior grid points
        top = np.array([px + 0.3, py - 0.2, 5.0])
        dist = mujoco.mj_ray(m, d, top, np.array([0.0, 0.0, -1.0]), None, 1, -1, gid)
        assert gid[0] == 0
        assert abs((5.0 - dist) - (drawn[(px, py)] + 0.1)) < 1e-6, (px, py)


LEASH = """<mujoco model="leash">
  <option timestep="0.005"/>
  <worldbody>
    <geom name="floor" type="plane" size="3 3 0.1"/>
    <body name="post" pos="-0.5 0 0.2"><geom type="box" size="0.02 0.02 0.2"/><site name="top" pos="0 0 0.2"/></body>
    <body name="ball" pos="0 0 0.05"><freejoint/><geom type="sphere" size="0.05"/><site name="s"/></body>
  </worldbody>
  <tendon><spatial name="leash" limited="true" range="0 1.2" width="0.004" rgba="1 1 0 1">
    <site site="top"/><site site="s"/></spatial></tendon>
</mujoco>
"""


def test_the_video_draws_a_spatial_tendon_as_mujoco_lays_it(tmp_path):
    """A leash (a spatial tendon with a width, which MuJoCo's viewer draws) was not drawn. Each frame
    now holds its segment between the wrap points: its length is MuJoCo's own ten_length at that
    state, within 1e-9 m, and the ball's end is where the ball's site is."""
    import mujoco

    from nbst.render.scene.motion import record

    fates = _write(tmp_path, "leash", LEASH, {"format": "nbst-fates", "version": 1, "scene": "leash.xml",
                                              "duration": 0.5, "controls": {"ball": {"linvel": [[1, 2], [0, 1], [0, 1]]}},
                                              "fates": {"ball": {"rest_in": {"center": [0, 0, 0], "radius": 3}}}})
    sol = tmp_path / "sol.json"
    assert main(["scene", "solve", str(fates), "-o", str(sol), "--seed", "1", "--jobs", "1", "--max-rollouts", "8",
                 "-q", "--no-ladder"]) == 0
    times = np.array([0.0, 0.25, 0.5])
    motion, _, m = record(sol, times)
    assert motion.tendon_segs is not None and motion.tendon_slots[0] == (0, 0.004)
    doc = json.loads(sol.read_text())
    d = mujoco.MjData(m)
    d.qpos[:], d.qvel[:] = doc["qpos0"], doc["qvel0"]
    for k in range(101):   # the frames at 0, 0.25 and 0.5 s: steps 0, 50 and 100 of 5 ms
        if k in (0, 50, 100):
            mujoco.mj_forward(m, d)
            a, b = motion.tendon_segs[(0, 50, 100).index(k), 0]
            assert abs(np.linalg.norm(b - a) - d.ten_length[0]) < 1e-9
            assert np.allclose(b, d.site_xpos[m.site("s").id], atol=1e-12)
        mujoco.mj_step(m, d)


def test_the_verdicts_give_a_kilometre_scene_to_the_millimetre():
    """A crate at x = 1,000.2 m read 'ends at (1000, ...), 0.5 m from the region' (four significant
    digits: the 0.2 m lost beside a 0.5 m miss) and 12 km read '1e+04'; a millimetre scene keeps its
    four digits."""
    from nbst.scene.judge import length_text

    assert length_text(1000.2341) == "1000.234" and length_text(12000.0) == "12000"
    assert length_text(-25.5) == "-25.5" and length_text(1.8642) == "1.864"
    assert length_text(0.0165) == "0.0165" and length_text(3e-12) == "0"


@pytest.mark.parametrize("second, refused", [
    ({"center": [1.0, 0, 0.5], "radius": 0.2}, True),     # two balls apart
    ({"center": [0.25, 0, 0.5], "radius": 0.2}, False),   # two balls that overlap
    ({"min": [0.5, -1, 0], "max": [2, 1, 1]}, True),       # a ball and a box apart
    ({"min": [0.05, -1, 0], "max": [2, 1, 1]}, False),     # a ball reaching into the box
])
def test_two_at_regions_at_one_time_that_share_no_point_are_refused(tmp_path, second, refused):
    """Two `at` entries at the same time in regions apart can never both be met: they were accepted,
    and the search spent its budget on them."""
    from nbst.scene.fates import FatesError, parse_fates

    at = [{"t": 0.5, "in": {"center": [0, 0, 0.5], "radius": 0.1}}, {"t": 0.5, "in": second}]
    doc = {"format": "nbst-fates", "version": 1, "scene": "x.xml", "duration": 1,
           "controls": {"ball": {"linvel": [[0, 1], [0, 0], [0, 0]]}}, "fates": {"ball": {"at": at}}}
    if refused:
        with pytest.raises(FatesError, match=r"fates\.ball\.at\[1\]: .*apart from at\[0\]'s at the same time"):
            parse_fates(doc, "f.json", folder=tmp_path)
    else:
        assert parse_fates(doc, "f.json", folder=tmp_path).fates[0].at[1][0] == 0.5
    at[1]["t"] = 0.6  # at another time, anything goes
    assert len(parse_fates(doc, "f.json", folder=tmp_path).fates[0].at) == 2


#: the crate's scene with two balls: the coin, and the totem where the crate stood
PAIR = AIR.replace('name="ball"', 'name="coin"').replace(
    '<body name="crate" pos="1 1 0.12"><freejoint/><geom type="box" size="0.1 0.1 0.08"/>',
    '<body name="totem" pos="0.5 0 0.05"><freejoint/><geom type="sphere" size="0.05"/>')


@pytest.mark.parametrize("loop", [False, True])
def test_a_touch_of_two_fated_bodies_is_said_once_in_the_contact_sequence(tmp_path, loop):
    """`--answers` listed `coin-totem` and `totem-coin` for one touch when both bodies had fates;
    the touch is said once, from the side that sorts first, on both rollout paths."""
    from nbst.scene.rollout import SceneSim
    from nbst.scene.scenefile import load_fates

    fates = _write(tmp_path, "pair", PAIR, {
        "format": "nbst-fates", "version": 1, "scene": "pair.xml", "duration": 0.5,
        "controls": {"coin": {"linvel": [[2, 3], [0, 0], [0, 0]]}},
        "fates": {"coin": {"hits": ["totem"]}, "totem": {"rest_in": {"center": [1, 0, 0.05], "radius": 0.5}}}})
    f, model = load_fates(fates)
    with SceneSim(f, model, sequences=True, loop=loop) as sim:
        (r,) = sim.run(np.array([[2.5, 0, 0]]))
    assert r.judgement.bodies[0].fates[0].met  # the coin did hit the totem
    said = [t for t in r.sequence if set(t.split("-")) == {"coin", "totem"}]
    assert said == ["coin-totem"], r.sequence
