"""nbst export FILE --gltf OUT.glb: every world's motion as glTF 2.0 node animation.

For each world (a 2D solution, a 5 m and a foul-line bowling throw, a crash file, a scene
solution) the .glb is read back with pygltflib and its keyframes are compared with the world's own
replay: node translations and rotations at the sample times, within float32 storage (positions to
1e-6 of the motion's extent plus 1e-6 relative; rotations as unit quaternions to 1e-6, q and -q
being one rotation; times to 1e-6 relative). The file is checked structurally as the glTF 2.0
specification requires: accessor counts, min/max on every POSITION and animation input accessor,
unit rotations, increasing times, LINEAR samplers, channels naming existing nodes, buffer views
inside the one buffer. Bad input is one line, exit 2, nothing written.
"""
from __future__ import annotations

import json
import os

from pathlib import Path

import numpy as np
import pytest

pygltflib = pytest.importorskip("pygltflib")

from nbst.cli.main import main  # noqa: E402
from nbst.export.gltf import BodyMotion, continuous_quaternions, gltf_document, write_glb  # noqa: E402
from nbst.export.mjbodies import sampled_steps  # noqa: E402
from nbst.export.worlds import file_kind, file_motion  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
#: A short crossing (2.5 s), as tests/test_render_crash.py records one.
CRASH = {
    "kind": "nbst-crash-script", "name": "short",
    "road": {"layout": "intersection", "width": 7, "length": 80},
    "duration": 2.5,
    "vehicles": [
        {"name": "A", "type": "sedan", "start": {"x": -22, "y": -1.75, "heading": 0}, "speed": [45, 55],
         "driver": {"aim": {"x": [0, 4], "y": -1.75}, "arrive": [1.5, 1.8], "after_impact": "brake"},
         "fate": {"hits": ["B"]}},
        {"name": "B", "type": "suv", "start": {"x": 1.75, "y": -22, "heading": 90}, "speed": [45, 55],
         "driver": {"aim": {"x": 1.75, "y": [-2, 2]}, "arrive": [1.5, 1.8]}, "fate": {"hits": ["A"]}},
    ],
}


def _disks(folder):
    from nbst.problem import load_problem

    p = load_problem("over5")
    f = folder / "disks.json"
    f.write_text(json.dumps({"problem": "over5", "velocities": [[1.0, 0.5] if c else [0, 0] for c in p.cueable]}))
    return f


def _scene(folder):
    from nbst.scene import solve
    from nbst.scene.solution import solution_dict

    res = solve(None, "snake-eyes", seed=1, max_rollouts=400)
    f = folder / "scene.json"
    f.write_text(json.dumps(solution_dict(res)))
    return f


def _deck(folder):
    from nbst.models.bowling import pinfall, scene
    from nbst.models.bowling.deck import delivery, throwfile
    from nbst.models.bowling.deck.folder import write_throw

    model = scene.build_model()
    x = np.array([0.0, 7.5, 0.0, 0.0])
    down = throwfile.replay(model, *delivery.initial_qpos_qvel(model, x), delivery.DURATION)
    f = folder / "deck.json"
    write_throw(f, model, x, pinfall.mask_from_pins(down))
    return f


def _lane(folder):
    from nbst.models.bowling import lane
    from nbst.models.bowling.lane import frame, throwfile

    d = lane.Delivery(hand="right", board=20, at="foul", angle=2.82, mph=17, rpm=350, rotation=45, tilt=12)
    f = folder / "lane.json"
    f.write_text(throwfile.dumps(throwfile.throw_dict(frame.run_frame(d, "house"), oil="house")))
    return f


def _crash(folder):
    from nbst.models.crash import crashfile, run, script, space

    s = script.script_from_dict(json.loads(json.dumps(CRASH)), source="short")
    sp = space.space_of(s)
    U = np.random.default_rng(3).random((1, sp.dim))
    R = run.CrashRunner(s, jobs=1, batch=1)
    res = R.run(sp.intents(U))
    d = crashfile.crash_dict(s, R.xml, R.model, sp.intents(U)[0], res.qpos0[0], res.qvel0[0], res.controls[0],
                             res.final_qpos[0], res.outcomes[0], seed=3, period_steps=R.period)
    f = folder / "crash.json"
    f.write_text(json.dumps(d, indent=1, allow_nan=False))
    return f


MAKERS = {"disks": _disks, "scene": _scene, "deck": _deck, "lane": _lane, "crash": _crash}


class _Files(dict):
    """Each world's file, made when a test first asks for it (the fast tier makes only its own)."""

    def __init__(self, folder):
        super().__init__()
        self.folder = folder

    def __missing__(self, kind):
        self[kind] = MAKERS[kind](self.folder)
        return self[kind]


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    return _Files(tmp_path_factory.mktemp("export"))


#: The bowling replays take seconds each: the slow tier.
WORLDS = ["disks", "scene", "crash", pytest.param("deck", marks=pytest.mark.slow),
          pytest.param("lane", marks=pytest.mark.slow)]


def _read(gl, acc_i: int) -> np.ndarray:
    """An accessor's values as float64 (n, k), with the structural checks the spec asks of it."""
    acc = gl.accessors[acc_i]
    view = gl.bufferViews[acc.bufferView]
    blob = gl.binary_blob()
    assert view.buffer == 0 and view.byteOffset + view.byteLength <= gl.buffers[0].byteLength == len(blob)
    k = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}[acc.type]
    dtype = {pygltflib.FLOAT: np.float32, pygltflib.UNSIGNED_INT: np.uint32}[acc.componentType]
    assert view.byteOffset % 4 == 0 and view.byteLength == acc.count * k * 4
    a = np.frombuffer(blob, dtype=dtype, count=acc.count * k, offset=view.byteOffset).reshape(acc.count, k)
    if acc.min:  # pygltflib reads an absent min as []
        assert np.array_equal(np.asarray(acc.min, np.float32), a.min(axis=0))
        assert np.array_equal(np.asarray(acc.max, np.float32), a.max(axis=0))
    return a.astype(np.float64)


def _check_structure(gl, motion) -> dict:
    """The spec's structure; returns {node index: {path: (times, values)}}."""
    assert gl.asset.version == "2.0" and gl.scene == 0 and len(gl.scenes[0].nodes) == 1
    root = gl.nodes[gl.scenes[0].nodes[0]]             # the bodies under one root that stands z-up as y-up
    assert root.children == list(range(len(motion.bodies))) and root.mesh is None
    x, y, z, w = root.rotation
    up = 2 * np.array([x * z + w * y, y * z - w * x, 0.5 - x * x - y * y])  # the rotation's image of +z
    assert np.allclose(up, [0.0, 1.0, 0.0], atol=1e-12)                  # glTF's up (spec 3.4: +Y up)
    for mesh in gl.meshes:
        for prim in mesh.primitives:
            pos_acc = gl.accessors[prim.attributes.POSITION]
            assert len(pos_acc.min) == len(pos_acc.max) == 3  # required on POSITION
            v = _read(gl, prim.attributes.POSITION)
            n = _read(gl, prim.attributes.NORMAL)
            assert len(n) == len(v) and np.allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-3)
            idx = _read(gl, prim.indices)
            assert len(idx) % 3 == 0 and idx.max() < len(v)
            rgba = gl.materials[prim.material].pbrMetallicRoughness.baseColorFactor
            assert len(rgba) == 4 and all(0 <= c <= 1 for c in rgba)
    (anim,) = gl.animations
    out: dict = {}
    for ch in anim.channels:
        s = anim.samplers[ch.sampler]
        assert s.interpolation == "LINEAR" and 0 <= ch.target.node < len(gl.nodes)
        t_acc = gl.accessors[s.input]
        assert len(t_acc.min) == len(t_acc.max) == 1  # required on an animation input
        t = _read(gl, s.input)[:, 0]
        y = _read(gl, s.output)
        assert len(y) == len(t) and (np.diff(t) > 0).all() and t[0] >= 0
        if ch.target.path == "rotation":
            assert np.allclose(np.linalg.norm(y, axis=1), 1.0, atol=1e-6)
        out.setdefault(ch.target.node, {})[ch.target.path] = (t, y)
    return out


@pytest.mark.parametrize("kind", WORLDS)
def test_the_glb_holds_the_replays_keyframes(files, kind, tmp_path, capsys):
    src = files[kind]
    assert file_kind(src) == kind
    out = tmp_path / f"{kind}.glb"
    if kind in ("disks", "crash"):   # the command, then the replay again as the writer got it
        assert main(["export", str(src), "--gltf", str(out), "--fps", "50"]) == 0
        assert "wrote" in capsys.readouterr().err
        _, motion = file_motion(src, fps=50)
    else:                            # the command's two steps, the replay run once
        kind_, motion = file_motion(src, fps=50)
        assert kind_ == kind and write_glb(out, motion, name=kind) == out.stat().st_size
    gl = pygltflib.GLTF2().load(str(out))
    anim = _check_structure(gl, motion)
    extent = float(np.abs(motion.pos).max()) + 1.0
    moving = [b for b, body in enumerate(motion.bodies) if body.moves]
    assert sorted(anim) == moving and moving
    quat = continuous_quaternions(motion.quat)
    for b in moving:
        assert gl.nodes[b].name == motion.bodies[b].name
        node = gl.nodes[b]
        for path, held in (("translation", node.translation), ("rotation", node.rotation)):
            if path not in anim[b]:   # no channel: a value that never changes, the node's own
                anim[b][path] = (np.asarray(motion.times), np.tile(np.asarray(held, float), (len(motion.times), 1)))
        t, y = anim[b]["translation"]
        assert np.allclose(t, motion.times, rtol=1e-6, atol=1e-7)
        assert np.abs(y - motion.pos[:, b]).max() <= 1e-6 * extent
        t, r = anim[b]["rotation"]
        wxyz = r[:, [3, 0, 1, 2]]
        assert np.abs(wxyz - quat[:, b]).max() <= 1e-6
        assert np.allclose(np.abs(np.sum(wxyz * motion.quat[:, b], axis=1)), 1.0, atol=1e-6)
    # keyframes at the asked rate: the last at the motion's end, none further apart than a frame
    # plus one recorded step
    assert np.diff(motion.times).max() <= 1 / 50 + 2e-3 and motion.times[0] == 0.0


@pytest.mark.parametrize("kind", ["disks", "scene", "crash"])
def test_bodies_alike_share_a_mesh_and_each_node_draws_its_own_solids(files, kind):
    """A mesh is shared only by bodies whose solids are alike to the float32 byte: every node's mesh,
    read back and unrolled by its indices, is its own body's triangles in its own colours, and there
    are as many meshes as distinct bodies (over5's four amber pucks share one, its blue one not)."""
    from nbst.export.gltf import _drawable

    _, motion = file_motion(files[kind], fps=10)
    gl, data = gltf_document(motion)
    gl.set_binary_blob(data)
    kinds = set()
    for b, body in enumerate(motion.bodies):
        solids = [sd for sd in body.solids if _drawable(sd)]
        node = gl.nodes[b]
        assert node.name == body.name
        if not solids:
            assert node.mesh is None
            continue
        kinds.add(tuple((np.asarray(sd.rows, np.float32).tobytes(), tuple(np.round(sd.rgba, 6))) for sd in solids))
        prims = gl.meshes[node.mesh].primitives
        assert len(prims) == len(solids)
        for prim, sd in zip(prims, solids):
            corners = _read(gl, prim.attributes.POSITION)[_read(gl, prim.indices)[:, 0].astype(int)]
            assert np.array_equal(corners, np.asarray(sd.rows, np.float32)[:, :3].astype(np.float64))
            rgba = gl.materials[prim.material].pbrMetallicRoughness.baseColorFactor
            assert np.allclose(rgba, sd.rgba, atol=1e-6)
            if sd.colors is None:
                assert prim.attributes.COLOR_0 is None
            else:   # the renderer's colour of every corner
                col = _read(gl, prim.attributes.COLOR_0)[_read(gl, prim.indices)[:, 0].astype(int)]
                assert np.array_equal(col, np.asarray(sd.colors, np.float32).astype(np.float64))
    assert len(gl.meshes) == len(kinds)
    if kind == "disks":   # the floor, the amber puck, the blue puck
        assert len(gl.meshes) == 3 < len(motion.bodies) == 6


def test_spin_shows_in_the_glb_as_in_the_videos(files):
    """What makes a turn visible in the videos is in the file: a crash's tyres carry the video's two
    light spokes a face (per-corner COLOR_0) and its cabins their glass; the pins their red neck
    stripes (the animator's 'no spin cues')."""
    from nbst.export.worlds import _pin_skins
    from nbst.models.bowling import scene
    from nbst.render.bowling.deck import PIN_RED, PIN_WHITE
    from nbst.render.crash import scene as cs

    _, motion = file_motion(files["crash"], fps=10)
    gl, data = gltf_document(motion)
    gl.set_binary_blob(data)

    def key(rgb):   # a colour to the thousandth (float32 in the file)
        return tuple(int(round(float(c) * 1000)) for c in rgb)

    def colours(name):
        node = next(n for n in gl.nodes if n.name == name)
        return {key(c) for prim in gl.meshes[node.mesh].primitives if prim.attributes.COLOR_0 is not None
                for c in _read(gl, prim.attributes.COLOR_0)}

    for wheel in ("A_wheel_fl", "A_wheel_rr", "B_wheel_fl"):
        assert {key(cs.SPOKE), key(cs.HUB), key(cs.TYRE)} <= colours(wheel), wheel
    assert key(cs.GLASS) in colours("A")
    (pin,) = _pin_skins(scene.build_model())[1]
    assert {key(PIN_RED), key(PIN_WHITE)} <= {key(c) for c in pin.colors}


@pytest.mark.slow
def test_the_foul_line_ball_wears_its_videos_texture(files, tmp_path):
    """The ball's grip holes, pin dot and track are in the file as in the video: a PNG texture on a
    sphere whose every corner's TEXCOORD_0 is its direction's equirectangular place, and the texel
    at each grip hole's direction (the video's assumed layout) is the hole's colour."""
    import io

    from PIL import Image

    from nbst.models.bowling import lane
    from nbst.models.bowling.lane import throwfile
    from nbst.render.bowling.throw import HOLE_RGB, grip_holes

    out = tmp_path / "lane.glb"
    assert main(["export", str(files["lane"]), "--gltf", str(out), "--fps", "20"]) == 0
    gl = pygltflib.GLTF2().load(str(out))
    (prim,) = gl.meshes[next(n for n in gl.nodes if n.name == "ball").mesh].primitives
    pos, uv = _read(gl, prim.attributes.POSITION), _read(gl, prim.attributes.TEXCOORD_0)
    d = pos / np.linalg.norm(pos, axis=1, keepdims=True)
    inner = (np.abs(d[:, 2]) < 0.999) & (uv[:, 0] > 1e-6) & (uv[:, 0] < 1 - 1e-6)   # not on a pole or the seam
    assert inner.sum() > 1000
    assert np.allclose(uv[inner, 0], np.arctan2(d[inner, 1], d[inner, 0]) / (2 * np.pi) + 0.5, atol=1e-5)
    assert np.allclose(uv[inner, 1], np.arccos(np.clip(d[inner, 2], -1, 1)) / np.pi, atol=1e-5)
    tex = gl.textures[gl.materials[prim.material].pbrMetallicRoughness.baseColorTexture.index]
    view = gl.bufferViews[gl.images[tex.source].bufferView]
    img = np.asarray(Image.open(io.BytesIO(gl.binary_blob()[view.byteOffset:view.byteOffset + view.byteLength])))
    h, w = img.shape[:2]
    delivery = lane.Delivery(**throwfile.load(files["lane"])["delivery"])
    for p, _ in grip_holes(delivery):
        u, v = np.arctan2(p[1], p[0]) / (2 * np.pi) + 0.5, np.arccos(np.clip(p[2], -1, 1)) / np.pi
        assert np.abs(img[int(v * h), int(u * w) % w].astype(int) - np.round(np.array(HOLE_RGB) * 255)).max() <= 1


def test_the_pins_wear_two_neck_stripes_cut_exactly():
    """The pin's mesh has rings of vertices wider apart than a stripe: its triangles are cut at each
    stripe's edges (``split_at_height``: no triangle crosses a cut, the surface area kept to 1e-6)
    and coloured whole, so the video and the glTF show the two red stripes of STRIPES_IN, no red
    elsewhere (an audit saw one pink band 3.5 cm wide)."""
    from nbst.models.bowling import scene
    from nbst.render.bowling.deck import PIN_RED, STRIPES_IN, _visible_of, pin_solid, split_at_height
    from nbst.render.core import geoms as cg

    model = scene.build_model()
    tri = pin_solid(model).reshape(-1, 3, 9).astype(float)
    red = np.all(np.abs(tri[:, :, 6:9] - np.array(PIN_RED)) < 1e-6, axis=(1, 2))
    z = tri[:, :, 2] / scene.INCH
    for lo, hi in STRIPES_IN:   # each stripe wholly red, bounded by its edges
        inside = (z.mean(axis=1) > lo) & (z.mean(axis=1) < hi)
        assert inside.any() and red[inside].all()
    assert all(any(lo - 1e-4 <= zz.min() and zz.max() <= hi + 1e-4 for lo, hi in STRIPES_IN) for zz in z[red])

    def area(t):
        return 0.5 * np.linalg.norm(np.cross(t[:, 1, :3] - t[:, 0, :3], t[:, 2, :3] - t[:, 0, :3]), axis=1).sum()

    rows = np.concatenate([cg.body_rows(model, g) for g in _visible_of(model, "pin1")])
    cut = split_at_height(rows, 9.4 * scene.INCH).reshape(-1, 3, 6)
    zc = cut[:, :, 2] - 9.4 * scene.INCH
    assert not ((zc > 1e-9).any(axis=1) & (zc < -1e-9).any(axis=1)).any()
    assert area(cut) == pytest.approx(area(rows.reshape(-1, 3, 6)), rel=1e-6)


def test_mujoco_worlds_key_the_replays_own_states(files):
    """The scene's keyframes are the plain mj_step loop's states: its last is replay_solution's
    final state, bit for bit; the crash's are the renderer's recording."""
    import mujoco

    from nbst.export.mjbodies import body_poses
    from nbst.render.crash.video import load
    from nbst.scene.solution import replay_solution

    _, motion = file_motion(files["scene"], fps=60)
    rep = replay_solution(files["scene"])
    doc = json.loads(files["scene"].read_text())
    from nbst.scene.scenefile import load_fates

    _, model = load_fates(doc["fates_file"] or doc["fates"], scene=doc["scene"])
    d = mujoco.MjData(model)
    d.qpos[:] = rep.qpos
    mujoco.mj_kinematics(model, d)
    assert np.array_equal(motion.pos[-1], d.xpos) and np.array_equal(motion.quat[-1], d.xquat)
    assert motion.times[-1] == pytest.approx(doc["nstep"] * doc["timestep"], rel=1e-12)

    _, _, cmodel, cm = load(files["crash"])
    _, motion = file_motion(files["crash"], fps=30)
    idx = sampled_steps(cm.times, 30)
    pos, quat = body_poses(cmodel, cm.qpos[idx])
    assert np.array_equal(motion.pos, pos) and np.array_equal(motion.times, cm.times[idx])
    # glTF's (x, y, z, w), read as a rotation matrix the way a viewer does, is MuJoCo's xmat
    from scipy.spatial.transform import Rotation

    gl, blob = gltf_document(motion)
    gl.set_binary_blob(blob)
    d = mujoco.MjData(cmodel)
    d.qpos[:] = cm.qpos[idx[-1]]
    mujoco.mj_kinematics(cmodel, d)
    for ch in gl.animations[0].channels:
        if ch.target.path == "rotation":
            xyzw = _read(gl, gl.animations[0].samplers[ch.sampler].output)[-1]
            want = d.xmat[ch.target.node].reshape(3, 3)
            assert np.abs(Rotation.from_quat(xyzw).as_matrix() - want).max() < 1e-6


@pytest.mark.slow
def test_a_5m_throws_keyframes_are_the_renderers_recording(files):
    from nbst.models.bowling.deck import throwfile
    from nbst.render.bowling.deck import record

    throw, dmodel, _ = throwfile.load_with_scene(files["deck"])
    dm = record(throw, dmodel)
    _, motion = file_motion(files["deck"], fps=60)
    idx = sampled_steps(dm.times, 60)
    ball = int(dmodel.body("ball").id)
    assert np.array_equal(motion.pos[:, ball], dm.ball[idx, :3])
    assert np.abs(motion.quat[:, ball] - dm.ball[idx, 3:]).max() < 1e-12


def test_sampled_steps_are_the_nearest_states_with_both_ends():
    times = np.arange(2501) * 1e-3
    idx = sampled_steps(times, 60)
    assert idx[0] == 0 and idx[-1] == 2500 and (np.diff(idx) > 0).all()
    assert np.abs(times[idx[:-1]] - np.arange(len(idx) - 1) / 60).max() <= 0.5e-3 + 1e-12


def test_every_geom_type_becomes_a_mesh_in_its_bodys_frame():
    import mujoco

    from nbst.export.mjbodies import PLANE_HALF, model_bodies

    xml = """<mujoco><asset><mesh name="tet" vertex="0 0 0  1 0 0  0 1 0  0 0 1"/>
      <material name="red" rgba="1 0 0 1"/></asset><worldbody>
      <geom type="plane" size="2 3 .1" rgba=".2 .3 .4 1"/>
      <geom type="plane" size="0 0 1"/>
      <body name="b" pos="0 0 1"><freejoint/>
        <geom type="sphere" size=".1" pos=".5 0 0"/>
        <geom type="capsule" size=".1 .3" material="red"/>
        <geom type="cylinder" size=".2 .4" euler="90 0 0"/>
        <geom type="ellipsoid" size=".1 .2 .3"/>
        <geom type="box" size=".1 .2 .3"/>
        <geom type="mesh" mesh="tet"/>
        <geom type="box" size="1 1 1" rgba="0 0 0 0"/>
        <geom type="box" size="1 1 1" group="4"/>
      </body>
      <body name="post" pos="3 0 0"><geom type="box" size=".1 .1 .5"/>
        <body name="arm"><joint type="hinge"/><geom type="capsule" size=".02 .2"/></body></body>
      <body name="hand" mocap="true"><geom type="sphere" size=".1"/></body></worldbody></mujoco>"""
    m = mujoco.MjModel.from_xml_string(xml)
    world, b, post, arm, hand = model_bodies(m)
    assert len(world.solids) == 2 and not world.moves and b.moves and len(b.solids) == 6
    # a body welded to the world (a post) never moves: no channel; a jointed child and a mocap body do
    assert not post.moves and arm.moves and hand.moves

    def bounds(solid):
        return np.array([solid.rows[:, :3].min(axis=0), solid.rows[:, :3].max(axis=0)])

    assert np.allclose(bounds(world.solids[0]), [[-2, -3, 0], [2, 3, 0]])
    assert np.allclose(bounds(world.solids[1])[1, :2], PLANE_HALF)
    sphere, capsule, cyl, ell, box, tet = b.solids
    assert np.allclose(bounds(sphere), [[.4, -.1, -.1], [.6, .1, .1]], atol=2e-3)
    assert capsule.rgba == (1.0, 0.0, 0.0, 1.0) and np.allclose(bounds(capsule)[:, 2], [-.4, .4], atol=1e-6)
    assert np.allclose(bounds(cyl)[:, 1], [-.4, .4], atol=1e-6)     # turned about x: its axis along y
    assert np.allclose(bounds(ell), [[-.1, -.2, -.3], [.1, .2, .3]], atol=1e-6)
    assert np.allclose(bounds(box), [[-.1, -.2, -.3], [.1, .2, .3]])
    assert len(tet.rows) == 12
    for s in b.solids:   # unit normals, turned with their geom
        assert np.allclose(np.linalg.norm(s.rows[:, 3:], axis=1), 1.0, atol=1e-5)
    top = cyl.rows[np.argmax(cyl.rows[:, 1])]
    assert np.allclose(top[3:], [0, 1, 0], atol=1e-6)
    # written and read back: every corner once per (position, normal), indexed
    gl, blob = gltf_document(BodyMotion(bodies=[b], times=np.zeros(1), pos=np.zeros((1, 1, 3)),
                                        quat=np.array([[[1.0, 0, 0, 0]]])))
    gl.set_binary_blob(blob)
    prim = gl.meshes[0].primitives[4]
    v, idx = _read(gl, prim.attributes.POSITION), _read(gl, prim.indices)[:, 0].astype(int)
    assert len(v) == 24 and np.allclose(v[idx], box.rows[:, :3], atol=1e-7)


def test_bad_input_is_one_line_exit_2_and_nothing_written(files, tmp_path, capsys):
    out = tmp_path / "x.glb"
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"velocities": [[0, 0]]}))
    fifo = tmp_path / "f.glb"
    os.mkfifo(fifo)
    folder = tmp_path / "d.glb"
    folder.mkdir()
    link = tmp_path / "l.glb"
    link.symlink_to(tmp_path / "target.glb")
    cases = [
        ([str(bad), "--gltf", str(out)], "problem"),
        ([str(files["crash"]), "--problem", "over5", "--gltf", str(out)], "problem"),
        ([str(tmp_path / "none.json"), "--gltf", str(out)], "no such file"),
        ([str(ROOT / "models/crash/scripts/t-bone.json"), "--gltf", str(out)], "solve it first"),
        ([str(ROOT / "nbst/scene/examples/snake-eyes.json"), "--gltf", str(out)], "solve it first"),
        ([str(ROOT / "models/bowling/deck/atlas.json"), "--gltf", str(out)], "one throw file"),
        ([str(files["disks"]), "--gltf", str(tmp_path / "x.gltf")], ".glb"),
        ([str(files["disks"]), "--gltf", str(out), "--fps", "0"], "fps"),
        ([str(files["disks"]), "--gltf", str(fifo)], "FIFO"),
        ([str(files["disks"]), "--gltf", str(folder)], "folder"),
        ([str(files["disks"]), "--gltf", str(link)], "link"),
    ]
    for argv, word in cases:
        with pytest.raises(SystemExit) as e:
            raise SystemExit(main(["export", *argv]))
        err = capsys.readouterr().err.strip()
        assert e.value.code == 2 and len(err.splitlines()) == 1 and word in err, (argv, err)
    assert not out.exists() and not (tmp_path / "target.glb").exists() and not (tmp_path / "x.gltf").exists()
