"""How a user's MuJoCo scene is drawn and exported: what nbst leaves out is said, every mark it draws
is labelled and coloured as its readout line, the brief readout where the whole one would hide the
scene, the fixed height fields in the path plots, and only bodies that move counted as moving.

The scenes are small copies of those a user audit found the problems with (a cloth, a ragdoll, a
shelf of five blocks alike, a small frame, a mocap paddle that never moves).
"""
from __future__ import annotations

import json
from types import SimpleNamespace

import numpy as np
import pytest

from nbst.render.scene import readout as ro
from nbst.render.scene.motion import Touch

CLOTH = """<mujoco model="flex cloth">
  <option timestep="0.002"/>
  <worldbody>
    <light pos="0 0 4" dir="0 0 -1"/>
    <geom name="floor" type="plane" size="3 3 0.1" rgba="0.7 0.7 0.7 1"/>
    <flexcomp name="cloth" type="grid" count="6 6 1" spacing="0.08 0.08 0.08" pos="1.0 0 0.02" radius="0.01"
              dim="2" mass="0.2" rgba="0.9 0.4 0.4 1">
      <edge equality="true"/>
      <contact selfcollide="none"/>
    </flexcomp>
    <body name="ball" pos="0 0 0.05">
      <freejoint/>
      <geom name="ballg" type="ellipsoid" size="0.05 0.04 0.03" rgba="0.1 0.3 0.9 1" mass="0.2"/>
    </body>
  </worldbody>
</mujoco>"""
CLOTH_FATES = {"format": "nbst-fates", "version": 1, "scene": "cloth.xml", "duration": 0.4,
               "controls": {"ball": {"linvel": [[1.0, 1.01], [0, 0.01], [0, 0.01]]}},
               "fates": {"ball": {"rest_in": {"center": [0, 0, 0.05], "radius": 5.0}}}}

SHELF = """<mujoco model="shelf">
  <option timestep="0.002"/>
  <default>
    <default class="blk"><geom type="box" size="0.03 0.03 0.06" rgba="0.2 0.7 0.9 1" mass="0.2" friction="0.8"/></default>
    <default class="thrown"><geom type="box" size="0.04 0.04 0.04" rgba="0.95 0.5 0.1 1" mass="0.5"/></default>
  </default>
  <worldbody>
    <light pos="0 0 3" dir="0 0 -1"/>
    <geom name="floor" type="plane" size="3 3 0.1" rgba="0.8 0.8 0.8 1"/>
    <frame name="shelfframe" pos="1 0 0.5" euler="0 0 90">
      <geom name="shelf" type="box" size="0.4 0.1 0.02" rgba="0.5 0.35 0.2 1"/>
      <replicate count="5" offset="0.15 0 0">
        <body name="block" pos="-0.3 0 0.081" childclass="blk"><freejoint/><geom name="b"/></body>
      </replicate>
    </frame>
    <body name="cube" pos="0 0 0.1" childclass="thrown"><freejoint/><geom name="cubeg"/></body>
  </worldbody>
</mujoco>"""
#: the controls about those a user's search found (cube hits block2, every fate met)
SHELF_FATES = {"format": "nbst-fates", "version": 1, "scene": "shelf.xml", "duration": 2.5,
               "controls": {"cube": {"linvel": [[3.9, 3.91], [0, 0.01], [3.4, 3.41]],
                                     "angvel": [[1.74, 1.75], [0.3, 0.31], [0.9, 0.91]]}},
               "fates": {"cube": {"hits": ["block2"], "never_hits": ["block1", "block3", "shelf"]},
                         "block2": {"rest_in": {"min": [1.05, -0.5, 0], "max": [2.0, 0.5, 0.1]}},
                         "block0": {"still": True}, "block1": {"still": True}, "block3": {"still": True},
                         "block4": {"still": True}}}

AMBIGUOUS = """<mujoco model="ambiguous">
  <option timestep="0.002"/>
  <worldbody>
    <light pos="0 0 4" dir="0 0 -1"/>
    <geom name="floor" type="plane" size="3 3 0.1"/>
    <geom name="target" type="box" pos="1.5 0 0.2" size="0.05 0.5 0.2" rgba="0.2 0.8 0.2 1"/>
    <body name="target" pos="-1.5 0 0.1"><freejoint/><geom name="tg" type="box" size="0.1 0.1 0.1" rgba="0.8 0.2 0.2 1"/></body>
    <body name="arm/hand.1" pos="0 0 0.05"><freejoint/><geom name="ballg" type="sphere" size="0.05" rgba="0.2 0.2 0.9 1" mass="0.2"/></body>
  </worldbody>
</mujoco>"""
#: the ball thrown back at the box (a geom named by its own name, "tg", in a body named "target")
AMBIGUOUS_FATES = {"format": "nbst-fates", "version": 1, "scene": "amb.xml", "duration": 1.5,
                   "controls": {"arm/hand.1": {"linvel": [[-3.0, -2.99], [0, 0.001], [0, 0]]}},
                   "fates": {"arm/hand.1": {"hits": ["tg"]}}}

PADDLE = """<mujoco model="paddle">
  <option timestep="0.002"/>
  <worldbody>
    <geom name="floor" type="plane" size="4 4 0.1" rgba="0.8 0.85 0.8 1"/>
    <body name="paddle" mocap="true" pos="2.4 0 0.3" euler="0 0 0.785">
      <geom name="paddleg" type="box" size="0.02 0.3 0.3" rgba="0.2 0.2 0.2 1"/>
    </body>
    <body name="ball" pos="0 0 0.05"><freejoint/><geom type="sphere" size="0.05" rgba="0.85 0.1 0.1 1" mass="0.2"/></body>
  </worldbody>
</mujoco>"""
PADDLE_FATES = {"format": "nbst-fates", "version": 1, "scene": "paddle.xml", "duration": 0.5,
                "controls": {"ball": {"linvel": [[1.0, 1.01], [0, 0.01], [0, 0]]}},
                "fates": {"ball": {"rest_in": {"center": [0, 0, 0.05], "radius": 5.0}}}}


def _solution(folder, xml_name, xml, fates):
    """A scene solution of ``fates`` (every control range a hair wide: the first rollouts meet it)."""
    from nbst.scene import solution_dict, solve

    (folder / xml_name).write_text(xml)
    (folder / "fates.json").write_text(json.dumps(fates))
    res = solve(None, folder / "fates.json", seed=1, max_rollouts=8)
    path = folder / "sol.json"
    path.write_text(json.dumps(solution_dict(res)))
    return path


@pytest.fixture(scope="module")
def gl():
    """The only place this file creates a GL context (EGL, headless)."""
    from nbst.render.core.gl import create_context

    ctx = create_context()
    yield ctx
    ctx.release()


def _renderer(gl, path, size):
    from nbst.render.core.times import frame_times
    from nbst.render.scene import motion as sm
    from nbst.render.scene import video as sv

    doc = json.loads(path.read_text())
    motion, fates, model = sm.record(path, frame_times(doc["nstep"] * doc["timestep"], 10.0))
    return sv.SceneRenderer(gl, motion, fates, model, size=size, title="t"), motion


# ------------------------------------------------------------------ 1. a flex is said not drawn

def test_a_flex_is_said_not_drawn_in_the_readout_and_its_bodies_empty_in_the_gltf():
    """A user's flexcomp cloth was drawn nowhere and nothing said so. The readout's last line names
    it (``not drawn: 1 flex (cloth)``); in the glTF, each of its 36 vertex bodies is a node without
    a mesh whose extras say so, and the scene's extras name them."""
    import mujoco

    from nbst.export.gltf import EMPTY, BodyMotion, gltf_document
    from nbst.export.mjbodies import body_poses, model_bodies

    m = mujoco.MjModel.from_xml_string(CLOTH)
    assert ro.not_drawn(m) == "1 flex (cloth)"
    assert ro.not_drawn(mujoco.MjModel.from_xml_string(PADDLE)) == ""
    fates = SimpleNamespace(fates=[])
    judged = SimpleNamespace(bodies=[], signature=(), met=True)
    for brief in (False, True):
        lines = ro.readout("cloth.xml", 0.5, fates, judged, final=False, brief=brief, note=ro.not_drawn(m))
        assert lines[-1] == "not drawn: 1 flex (cloth)"
    qpos = np.tile(m.qpos0, (3, 1))
    qpos[:, -7] += [0.0, 0.1, 0.2]   # the ball moves along x
    pos, quat = body_poses(m, qpos)
    gl, _ = gltf_document(BodyMotion(bodies=model_bodies(m), times=np.array([0.0, 0.1, 0.2]), pos=pos, quat=quat))
    cloth = [n for n in gl.nodes if n.name.startswith("cloth_")]
    assert len(cloth) == 36 and all(n.mesh is None and n.extras == EMPTY for n in cloth)
    ball = next(n for n in gl.nodes if n.name == "ball")
    assert ball.mesh is not None and not ball.extras
    assert gl.scenes[0].extras["nbst"].startswith("36 bodies have no geoms (cloth_0, cloth_1, cloth_2, ...)")


def test_a_rendered_cloth_scene_ends_its_readout_with_what_is_not_drawn(gl, tmp_path):
    path = _solution(tmp_path, "cloth.xml", CLOTH, CLOTH_FATES)
    r, motion = _renderer(gl, path, (640, 360))
    try:
        r.render(motion.duration)
        assert r.readout(0.0)[-1] == r.readout(motion.duration)[-1] == "not drawn: 1 flex (cloth)"
    finally:
        r.release()


# ------------------------------------------------------------------ 2. height fields in the path plots

def test_a_height_field_fixed_to_the_world_has_its_rectangle_in_the_path_plots():
    """docs/scene.md says the path plots draw the geoms fixed to the world; a terrain of
    ``type="hfield"`` was left out. Its footprint from above is its hfield_size rectangle (x radius
    2 m, y radius 1.5 m), turned 90 degrees with the geom and centred at its position."""
    import mujoco

    from nbst.scene.validate import static_footprints

    xml = """<mujoco><asset><hfield name="hill" nrow="3" ncol="3" size="2 1.5 0.4 0.05"
      elevation="0 0.5 0 0.5 1 0.5 0 0.5 0"/></asset><worldbody>
      <geom type="plane" size="5 5 0.1"/>
      <geom name="terrain" type="hfield" hfield="hill" pos="0.3 -0.2 0.1" euler="0 0 90"/>
      <body name="ball" pos="0 0 1"><freejoint/><geom type="sphere" size="0.05"/></body>
    </worldbody></mujoco>"""
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    mujoco.mj_kinematics(m, d)
    (terrain,) = static_footprints(m, d)
    assert len(terrain) == 4
    assert np.allclose(terrain.min(axis=0), [0.3 - 1.5, -0.2 - 2.0], atol=1e-6)
    assert np.allclose(terrain.max(axis=0), [0.3 + 1.5, -0.2 + 2.0], atol=1e-6)
    assert static_footprints(m, d, names={"terrain"})[0].shape == (4, 2)


# ------------------------------------------------------------------ 3. marks: colours and labels

def test_six_bodies_have_six_mark_colours_and_the_palettes_are_named_in_the_frame(tmp_path):
    """A shelf of five blocks alike in cyan and a thrown orange cube: the fourth still block was
    marked in the cube's orange. Every fated body now has its own mark colour (no two within 0.15 in
    a channel); the cube and block2 keep their own colours, and the four blocks marked in a
    palette's colour, with no region or arrow of it, are named beside them in it."""
    from nbst.scene.scenefile import load_fates

    (tmp_path / "shelf.xml").write_text(SHELF)
    (tmp_path / "fates.json").write_text(json.dumps(SHELF_FATES))
    fates, m = load_fates(tmp_path / "fates.json")
    colours = ro.mark_colours(m, fates)
    names = [f.body for f in fates.fates]
    for i in range(len(colours)):
        for j in range(i):
            assert np.abs(np.subtract(colours[i], colours[j])).max() >= 0.15, (names[i], names[j])
    assert np.allclose(colours[names.index("cube")], (0.95, 0.5, 0.1), atol=1e-6)
    assert np.allclose(colours[names.index("block2")], (0.2, 0.7, 0.9), atol=1e-6)
    tags = ro.name_tags(m, fates, colours)
    assert [name for _, name, _ in tags] == ["block0", "block1", "block3", "block4"]
    assert all(rgb == colours[names.index(name)] for _, name, rgb in tags)
    # a white die whose turn in the palette is the colour of a ball of that colour takes the next
    import mujoco

    sky = ro.MARKS[1]
    m = mujoco.MjModel.from_xml_string(f"""<mujoco><worldbody>
      <body name="ball"><freejoint/><geom type="sphere" size="0.1" rgba="{sky[0]} {sky[1]} {sky[2]} 1"/></body>
      <body name="die" pos="1 0 0"><freejoint/><geom type="box" size="0.1 0.1 0.1" rgba="0.95 0.95 0.95 1"/></body>
    </worldbody></mujoco>""")
    ball, die = ro.mark_colours(m, SimpleNamespace(fates=[SimpleNamespace(body="ball"), SimpleNamespace(body="die")]))
    assert np.allclose(ball, sky, atol=1e-6) and die == ro.MARKS[2]


def test_a_touch_mark_is_drawn_the_way_the_fate_asks_and_labelled_with_both_bodies():
    """Touch labels read ``floor 0.65 s`` where one body had fates, and the blocks' touches of the
    shelf no fate names were marked without a label. A mark is drawn for each first touch a fate
    names (every one where none does), after the start, each pair once, the way round the fate
    asks it; its label names the body and what it touched."""
    shelf = SimpleNamespace(fates=[SimpleNamespace(body="cube", hits=("block2",), never_hits=("shelf",)),
                                   SimpleNamespace(body="block0", hits=(), never_hits=())])
    p = (0.0, 0.0, 0.5)
    touches = [Touch(0.0, p, "block0", "shelf"), Touch(0.01, p, "block0", "shelf"),
               Touch(0.24, p, "block2", "cube"), Touch(0.24, p, "cube", "block2")]
    assert [ro.touch_label(im) for im in ro.drawn_touches(touches, shelf)] == ["cube-block2 0.24 s"]
    rag = SimpleNamespace(fates=[SimpleNamespace(body="torso", hits=(), never_hits=())])
    touches = [Touch(0.64, p, "torso", "mat"), Touch(0.65, p, "torso", "floor")]
    assert [ro.touch_label(im) for im in ro.drawn_touches(touches, rag)] == ["torso-mat 0.64 s", "torso-floor 0.65 s"]


def test_a_touch_of_a_geom_named_in_hits_goes_by_that_name(tmp_path):
    """A ball had to hit ``tg``, the geom of a body named ``target``: its touch went by the body's name
    and so was never marked as the touch asked. It goes by the fate's name, and is drawn."""
    from nbst.render.scene import motion as sm

    path = _solution(tmp_path, "amb.xml", AMBIGUOUS, AMBIGUOUS_FATES)
    motion, fates, _ = sm.record(path, np.array([0.0]))
    assert motion.judgement.met
    drawn = ro.drawn_touches(motion.touches, fates)
    assert [(im.body, im.other) for im in drawn] == [("arm/hand.1", "tg")]


def test_every_drawn_mark_has_its_label_in_the_frame(gl, tmp_path):
    """The shelf at its end, 640x360: one touch mark (the cube's of block2) and four name tags, each
    with its label drawn; a tag's label is drawn in its body's mark colour."""
    path = _solution(tmp_path, "shelf.xml", SHELF, SHELF_FATES)
    r, motion = _renderer(gl, path, (640, 360))
    try:
        img = r.render(motion.duration)
        assert [(im.body, im.other) for im in r.impacts] == [("cube", "block2")]
        assert len(r.tags) == 4 and not r.hoops
        assert len(r.overlay_boxes) == len(r.impacts) + len(r.tags) + 1   # and the readout's panel
        for (x0, y0, x1, y1), (_, _, rgb) in zip(r.overlay_boxes[len(r.impacts):-1], r.tags):
            px = img[int(y0) + 1:int(y1), int(x0) + 1:int(x1)].reshape(-1, 3).astype(float) / 255
            assert (np.abs(px - np.asarray(rgb)).max(axis=1) < 0.08).sum() >= 5, rgb
    finally:
        r.release()


# ------------------------------------------------------------------ 4. the brief readout in a small frame

def test_the_brief_readout_takes_over_where_the_whole_one_would_cover_over_60_percent(gl, tmp_path):
    """At 320x180 the whole readout covered about 70 % of the width and hid the ball. Where the whole
    one would cover more than READOUT_WIDE (0.6) of the width at the least legible size, the brief
    one: its panel is then within that share; at 1280x720 the whole one fits and is kept."""
    path = _solution(tmp_path, "amb.xml", AMBIGUOUS, AMBIGUOUS_FATES)
    for size, brief in (((320, 180), True), ((1280, 720), False)):
        r, motion = _renderer(gl, path, size)
        try:
            r.render(motion.duration)
            x0, _, x1, _ = r.overlay_boxes[-1]   # the readout's panel, drawn last
            assert r.brief is brief and x1 - x0 <= 0.6 * size[0], (size, x1 - x0)
        finally:
            r.release()


# ------------------------------------------------------------------ 5. moving bodies

def test_a_mocap_body_that_never_moves_is_not_counted_moving(tmp_path, capsys):
    """`nbst export` said "4 bodies, 3 moving" where a mocap paddle never moved. A body moves only
    where its pose changes: the paddle's node has no channel and the summary counts the ball alone."""
    import pygltflib

    from nbst.cli.main import main

    path = _solution(tmp_path, "paddle.xml", PADDLE, PADDLE_FATES)
    out = tmp_path / "out.glb"
    assert main(["export", str(path), "--gltf", str(out)]) == 0
    assert "(scene: 3 bodies, 1 moving," in capsys.readouterr().err
    gl = pygltflib.GLTF2().load(str(out))
    moved = {gl.nodes[ch.target.node].name for a in gl.animations for ch in a.channels}
    assert moved == {"ball"}
