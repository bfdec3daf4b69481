"""nbst render SOL.json: a scene solution drawn with moderngl (nbst.render.scene).

Physical and visual facts on frames: a pixel at a body's projected centre has its colour (every
geom type, a material's colour, a model camera by name), hidden groups and clear geoms are not
drawn, the frame count is frame_times', a --clean frame differs from the annotated one only where
the readout and labels are, the impacts are the judge's first touches, the replay is bit for bit;
a bad camera name is one line, exit 2, nothing written.
"""
from __future__ import annotations

import json
import re

import numpy as np
import pytest

from nbst.cli.main import main
from nbst.render.core.times import frame_times
from nbst.render.scene import motion as sm
from nbst.render.scene import video as sv
from nbst.scene import solution_dict, solve

SHAPES = """<mujoco model="shapes">
  <option timestep="0.002"/>
  <asset>
    <mesh name="ico" file="ico.stl"/>
    <material name="amber" rgba="0.9 0.5 0.1 1"/>
  </asset>
  <worldbody>
    <light pos="0 0 4" dir="0.3 0.3 -1" directional="true"/>
    <camera name="top" pos="0 0 4" fovy="60"/>
    <geom name="floor" type="plane" size="3 3 0.05" rgba="0.5 0.5 0.5 1"/>
    <geom name="cap" type="capsule" size="0.1" fromto="-1 0.6 0.1 -0.6 0.6 0.1" rgba="0.9 0.1 0.1 1"/>
    <geom name="ell" type="ellipsoid" size="0.2 0.12 0.08" pos="0 0.6 0.08" rgba="0.1 0.8 0.1 1"/>
    <geom name="cyl" type="cylinder" size="0.15 0.1" pos="0.8 0.6 0.1" rgba="0.1 0.1 0.9 1"/>
    <geom name="box" type="box" size="0.15 0.15 0.1" pos="-0.8 -0.6 0.1" rgba="0.1 0.1 0.9 1" material="amber"/>
    <geom name="mesh" type="mesh" mesh="ico" pos="0 -0.6 0.15" rgba="0.1 0.8 0.8 1"/>
    <geom name="hidden" type="box" size="0.15 0.15 0.1" pos="0.8 -0.6 0.1" rgba="0.9 0.1 0.9 1" group="4"/>
    <geom name="clear" type="sphere" size="0.15" pos="-0.8 0 0.15" rgba="0.9 0.1 0.1 0"/>
    <body name="ball" pos="0.8 0 0.1">
      <freejoint/>
      <geom name="ball_g" type="sphere" size="0.1" rgba="0.6 0.2 0.8 1"/>
    </body>
  </worldbody>
</mujoco>
"""
SHAPES_FATES = {"format": "nbst-fates", "version": 1, "scene": "shapes.xml", "duration": 0.2,
                "controls": {"ball": {"linvel": [[-0.01, 0.01], [-0.01, 0.01], [0, 0]]}},
                "fates": {"ball": {"rest_in": {"center": [-0.4, 0, 0.1], "radius": 0.05}}}}


def _write(res, path):
    path.write_text(json.dumps(solution_dict(res)))
    return path


@pytest.fixture(scope="module")
def solutions(tmp_path_factory):
    """Each built-in's solution at seed 1 on a small budget (met or not: either is drawn), and the
    shapes scene's."""
    import trimesh

    d = tmp_path_factory.mktemp("scene")
    out = {name: _write(solve(None, name, seed=1, max_rollouts=budget), d / f"{name}.json")
           for name, budget in (("snake-eyes", 16), ("bank-shot", 16), ("egg-in-cup", 4))}
    (d / "shapes.xml").write_text(SHAPES)
    trimesh.creation.icosphere(subdivisions=2, radius=0.15).export(d / "ico.stl")
    (d / "shapes.json").write_text(json.dumps(SHAPES_FATES))
    out["shapes"] = _write(solve(None, d / "shapes.json", seed=1, max_rollouts=4), d / "shapes-sol.json")
    return out


@pytest.fixture(scope="module")
def gl():
    """The only place this file creates a GL context (EGL, headless)."""
    from nbst.render.core.gl import create_context

    ctx = create_context()
    yield ctx
    ctx.release()


def _frame(gl, path, t, *, size=(640, 360), **kw):
    doc = json.loads(path.read_text())
    motion, fates, model = sm.record(path, frame_times(doc["nstep"] * doc["timestep"], 30.0))
    r = sv.SceneRenderer(gl, motion, fates, model, size=size, title="t", **kw)
    try:
        return r, r.render(t), r.view(t)[0], motion, model
    finally:
        r.release()


def _chroma(c):
    c = np.asarray(c, float)[:3]
    return (c - c.min()) / max(c.max() - c.min(), 1e-9)


def _has_colour(pixel, rgb, tol=0.2) -> bool:
    """The pixel is lit ``rgb``: the same hue and saturation order, whatever its brightness."""
    p = np.asarray(pixel, float) / 255
    return bool(p.max() - p.min() > 0.15 and np.abs(_chroma(p) - _chroma(rgb)).max() < tol)


def test_every_geom_type_in_its_colour_from_the_model_camera(gl, solutions):
    """From the model's camera "top", each geom's top has its colour (a material's over the geom's
    rgba); a group-4 geom and an alpha-0 geom are not drawn (the floor shows there)."""
    r, img, vpm, motion, model = _frame(gl, solutions["shapes"], 0.0, camera="top", clean=True)
    checks = {"cap": ((-0.8, 0.6, 0.2), (0.9, 0.1, 0.1)), "ell": ((0, 0.6, 0.16), (0.1, 0.8, 0.1)),
              "cyl": ((0.8, 0.6, 0.2), (0.1, 0.1, 0.9)), "box": ((-0.8, -0.6, 0.2), (0.9, 0.5, 0.1)),
              "mesh": ((0, -0.6, 0.3), (0.1, 0.8, 0.8)), "ball": ((0.8, 0, 0.2), (0.6, 0.2, 0.8))}
    for name, (p, rgb) in checks.items():
        col, row, front = r.to_pixel(vpm, p)
        assert front
        assert _has_colour(img[int(row), int(col)], rgb), (name, img[int(row), int(col)])
    for p in ((0.8, -0.6, 0.2), (-0.8, 0.0, 0.3), (0.0, 0.0, 0.0)):   # hidden, clear, bare floor: grey
        col, row, _ = r.to_pixel(vpm, p)
        px = img[int(row), int(col)].astype(int)
        assert px.max() - px.min() < 12 and px.min() > 60, px


def test_ball_pixel_impacts_and_replay(gl, solutions):
    """bank-shot: the ball in flight is drawn in its material's orange where it projects, from the
    framing camera; the impacts drawn are the judge's first touches, at the same times; the
    recorded replay ends in the solution's final state bit for bit."""
    path = solutions["bank-shot"]
    r, img, vpm, motion, model = _frame(gl, path, 0.3, clean=True)
    assert motion.same
    k = motion.index(0.3)
    col, row, front = r.to_pixel(vpm, motion.body_xpos[k, model.body("ball").id])
    assert front and 0 <= col < 640 and 0 <= row < 360
    assert _has_colour(img[int(row), int(col)], (0.85, 0.4, 0.1)), img[int(row), int(col)]
    hits = next(v for b in motion.judgement.bodies for v in b.fates if v.fate == "hits")
    said = dict(re.findall(r"(\w+) at ([0-9.]+) s", hits.happened))
    drawn = {t.other: f"{t.t:.3f}" for t in motion.touches if t.body == "ball"}
    for name, when in said.items():
        assert drawn[name] == when


def test_clean_differs_only_under_the_readout(gl, solutions):
    """A --clean frame is the annotated one without its text: equal outside the readout panel and
    the labels, different inside the panel; the readout says asked and, on the last frame, what
    happened with a mark per fate."""
    path = solutions["snake-eyes"]
    doc = json.loads(path.read_text())
    end = doc["nstep"] * doc["timestep"]
    r, text, _, motion, _ = _frame(gl, path, end, size=(1280, 720))   # the whole readout
    _, clean, _, _, _ = _frame(gl, path, end, clean=True, size=(1280, 720))
    boxes = r.overlay_boxes
    assert boxes
    mask = np.zeros(text.shape[:2], bool)
    for x0, y0, x1, y1 in boxes:
        mask[max(0, int(y0) - 1):int(np.ceil(y1)) + 2, max(0, int(x0) - 1):int(np.ceil(x1)) + 2] = True
    assert np.array_equal(text[~mask], clean[~mask])
    x0, y0, x1, y1 = boxes[-1]   # the readout's panel, drawn last
    assert (text[int(y0):int(y1), int(x0):int(x1)] != clean[int(y0):int(y1), int(x0):int(x1)]).any()
    lines = r.readout(end)
    nfates = sum(len(b.fates) for b in motion.judgement.bodies)
    assert sum(s.strip().startswith(("\u2713", "\u2717")) for s in lines) == nfates
    assert lines[-1].startswith("signature ")


def test_a_small_frame_gets_the_brief_readout_and_it_fits(gl, solutions):
    """A third new user rendered at 320x180 and the readout, at its least legible size, covered the
    frame and ran off its right edge. Where the whole one does not fit, the brief one: per body one
    line, its fates' names with their marks at the end, and the signature. At 640x360 and 1280x720
    the readout is the whole one; at 640x360 it would cover 72 % of the width (a sixth new user: at
    320x180 it hid the ball), and the brief one takes over past 60 % (``READOUT_WIDE``)."""
    path = solutions["snake-eyes"]
    doc = json.loads(path.read_text())
    end = doc["nstep"] * doc["timestep"]
    r, _, _, motion, _ = _frame(gl, path, end, size=(320, 180))
    assert r.brief
    lines = r.readout(end)
    fates = [f for b in motion.judgement.bodies for f in b.fates]
    assert len(lines) == 2 + len(motion.judgement.bodies) + 1
    assert sum(s.count("\u2713") + s.count("\u2717") for s in lines) == len(fates)
    assert lines[2].startswith("die1: ") and lines[-1].startswith("signature ")
    from nbst.render.scene import readout as ro
    narrow = ro.readout("t", end, r.fates, motion.judgement, final=True, brief=True, width=22)
    assert len(narrow) > len(lines) and all(len(s) <= 22 for s in narrow[2:-1]), narrow   # goes on under the name
    assert sum(s.count("\u2713") + s.count("\u2717") for s in narrow) == len(fates)
    for size, brief in (((640, 360), True), ((1280, 720), False)):
        big, _, _, _, _ = _frame(gl, path, end, size=size)
        assert big.brief is brief and (brief or len(big.readout(end)) > len(lines))


def _frames(solutions, tmp_path, name):
    doc = json.loads(solutions[name].read_text())
    duration = doc["nstep"] * doc["timestep"]
    out = tmp_path / f"{name}.mp4"
    n = sv.render_scene(solutions[name], out, size=(160, 96), fps=4.0, hold=0.5)
    assert n == len(frame_times(duration, 4.0, hold=0.5)) and out.stat().st_size > 0


def test_a_video_has_frame_times_frames(solutions, tmp_path):
    """A scene solution renders to a video of exactly frame_times' frames."""
    _frames(solutions, tmp_path, "bank-shot")


@pytest.mark.slow
@pytest.mark.parametrize("name", ["snake-eyes", "egg-in-cup"])
def test_each_builtin_renders(solutions, tmp_path, name):
    """Every built-in's solution renders (the others of the test above)."""
    _frames(solutions, tmp_path, name)


def test_render_says_when_the_scene_changed_since_the_solve(solutions, tmp_path, capsys):
    """A third new user (issue 46) edited a scene after solving, and `nbst render` drew the motion in
    the edited scene with no word; now it notes the change on stderr (not with -q) and draws."""
    import shutil

    for f in solutions["shapes"].parent.iterdir():
        if f.suffix in (".xml", ".json", ".stl"):
            shutil.copy(f, tmp_path / f.name)
    sol = json.loads((tmp_path / solutions["shapes"].name).read_text())
    sol["scene"] = str(tmp_path / "shapes.xml")
    sol["fates_file"] = str(tmp_path / "shapes.json")
    (tmp_path / "sol.json").write_text(json.dumps(sol))
    png = tmp_path / "a.png"
    assert main(["render", str(tmp_path / "sol.json"), "-o", str(png), "--still", "0.1", "--size", "64x36"]) == 0
    assert "changed since" not in capsys.readouterr().err
    (tmp_path / "shapes.xml").write_text((tmp_path / "shapes.xml").read_text() + "\n<!-- edited -->\n")
    assert main(["render", str(tmp_path / "sol.json"), "-o", str(png), "--still", "0.1", "--size", "64x36"]) == 0
    err = capsys.readouterr().err
    assert "note: shapes.xml changed since sol.json was solved" in err, err
    assert main(["render", str(tmp_path / "sol.json"), "-o", str(png), "--still", "0.1", "--size", "64x36",
                 "-q"]) == 0
    assert "changed since" not in capsys.readouterr().err


def test_cli_camera_by_name_and_a_bad_one(solutions, tmp_path, capsys):
    """`nbst render SOL.json --camera NAME`: a model camera's name draws; another is refused in one
    line (exit 2) naming the cameras there are, and nothing is written; --clean is for scenes."""
    png = tmp_path / "top.png"
    assert main(["render", str(solutions["shapes"]), "-o", str(png), "--still", "0.1", "--camera", "top",
                 "--clean", "-q"]) == 0
    assert png.stat().st_size > 0
    capsys.readouterr()
    bad = tmp_path / "bad.mp4"
    assert main(["render", str(solutions["shapes"]), "-o", str(bad), "--camera", "nope"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "nope" in err[0] and "top" in err[0]
    assert not bad.exists()
    assert main(["render", "over5", "x.json", "-o", str(bad), "--clean"]) == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1


def test_sniff(solutions, tmp_path):
    assert sv.is_scene_solution(solutions["bank-shot"])
    p = tmp_path / "x.json"
    p.write_text('{"format": "nbst-fates"}')
    assert not sv.is_scene_solution(p)


def test_the_framing_camera_tracks_the_bodies(gl, solutions):
    """Snake eyes (16 rollouts: the dice end near their square, not always in it): at the end a die
    is drawn at least 1.3x as wide as when the camera framed the whole fall at once (the table
    beside them; 1.46x at seed 1; 2.1x for the pair solved at seed 1, 108 px against 50 at 720p), and every
    fated body's origin projects inside the frame at every recorded time."""
    path = solutions["snake-eyes"]
    doc = json.loads(path.read_text())
    T = doc["nstep"] * doc["timestep"]
    motion, fates, model = sm.record(path, frame_times(T, 30.0))
    r = sv.SceneRenderer(gl, motion, fates, model, size=(640, 360), title="t", clean=True)
    try:
        die = model.body("die1").id
        g = next(g for g in range(model.ngeom) if model.geom_bodyid[g] == die)
        half = float(model.geom_rbound[g])

        def width(vpm, k):
            p = motion.body_xpos[k, die]
            a, b = r.to_pixel(vpm, p - [half, 0, 0]), r.to_pixel(vpm, p + [half, 0, 0])
            return abs(a[0] - b[0])

        k = len(motion.times) - 1
        assert width(r.view(T)[0], k) >= 1.3 * width(r.vpm, k)
        for k, t in enumerate(motion.times):
            vpm = r.view(float(t))[0]
            for f in fates.fates:
                col, row, front = r.to_pixel(vpm, motion.body_xpos[k, model.body(f.body).id])
                assert front and 0 <= col < 640 and 0 <= row < 360, (t, f.body)
    finally:
        r.release()


def test_the_readout_colours_body_lines_only_never_a_title_named_like_a_body():
    """A scene file may share a fated body's name (coin.xml with a body "coin"): the title line
    stays uncoloured; the body's own line and its fates' lines carry its colour."""
    from nbst.render.scene import readout as ro
    from nbst.scene.scenefile import load_fates

    fates, _ = load_fates("snake-eyes")
    body = fates.fates[0].body
    lines = [body, "t =  0.00 s", body, "  rest_in: ...", "other"]
    rows = ro.body_rows(lines, fates)
    assert rows[0] == (-1, 0) and rows[1] == (-1, 0)  # the title and the time
    assert rows[2] == (0, len(body)) and rows[4] == (-1, 0)


def test_the_readout_writes_a_millimetre_region_in_its_own_digits():
    """Two decimals of a metre turned a 7 mm box 2 cm away into (0.02, -0.00, 0.00)-(0.02, 0.00, 0.01)."""
    from nbst.render.scene.readout import region_text
    from nbst.scene.fates import Region

    assert (region_text(Region(lo=(0.0165, -0.0035, 0.0), hi=(0.0235, 0.0035, 0.005)))
            == "box (0.0165, -0.0035, 0)-(0.0235, 0.0035, 0.005)")
    assert region_text(Region(center=(2.0, 0.0, 1.62), radius=0.06)) == "ball r 0.06 at (2, 0, 1.62)"
    # a fifth new user's file held 0.35 - 0.06 as Python writes it: to the nanometre, as check prints it
    assert (region_text(Region(lo=(1.09, 0.29000000000000004, 0.0), hi=(1.4, 0.5, 0.1)))
            == "box (1.09, 0.29, 0)-(1.4, 0.5, 0.1)")
    assert region_text(Region(center=(1000.5, 0.0, 2e-9), radius=3e-7)) == "ball r 0.0000003 at (1000.5, 0, 0.000000002)"


def test_the_framing_holds_a_long_thin_target_tightly():
    """A wall 2 m long and 10 cm thick that a body must hit is framed by its own box, not by the cube
    of its bounding sphere (2 m of empty air each side of it, which shrank a three-body scene to a
    quarter of the frame); turned 90 degrees, its box turns with it."""
    import types

    import mujoco

    from nbst.render.scene.framing import focus_points
    from nbst.scene.fates import Fate, Fates

    xml = """<mujoco><worldbody><geom name="wall" type="box" pos="2 0 0.3" size="0.05 1 0.3"/>
      <geom name="turned" type="box" pos="0 3 0.3" size="0.05 1 0.3" euler="0 0 90"/>
      <body name="ball"><freejoint/><geom size="0.05"/></body></worldbody></mujoco>"""
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    motion = types.SimpleNamespace(geom_xpos=d.geom_xpos[None].copy(), geom_xmat=d.geom_xmat[None].copy())
    for name, (lo, hi) in (("wall", ([1.95, -1, 0], [2.05, 1, 0.6])), ("turned", ([-1, 2.95, 0], [1, 3.05, 0.6]))):
        fates = Fates(source="mem", scene=None, keyframe=None, timestep=None, duration=1.0,  # type: ignore[arg-type]
                      controls=(), fates=(Fate("ball", hits=(name,)),))
        pts = focus_points(motion, fates, m, bodies=False)  # type: ignore[arg-type]
        assert np.allclose(pts.min(axis=0), lo, atol=1e-9) and np.allclose(pts.max(axis=0), hi, atol=1e-9), name


def test_the_framing_camera_looks_from_a_side_where_no_wall_hides_the_body():
    """A fourth new user's ball hit a door's knob behind the door, seen from the front: the framing
    camera now takes the first of its azimuths with the fewest blocked sightlines. A ball behind a
    tall wall on the front side (-y) is hidden from the three front azimuths (-70, -110 and -30 deg)
    and seen from every side the wall is not on; with the wall gone the front (-70) is kept."""
    from types import SimpleNamespace

    import mujoco

    from nbst.render.scene.framing import AZIMUTH, AZIMUTHS, clear_azimuth, hidden_count

    def motion_of(xml):
        m = mujoco.MjModel.from_xml_string(xml)
        d = mujoco.MjData(m)
        mujoco.mj_kinematics(m, d)
        two = lambda a: np.repeat(np.asarray(a, float)[None], 2, axis=0)  # noqa: E731
        mo = sm.SceneMotion(times=np.array([0.0, 1.0]), geom_xpos=two(d.geom_xpos),
                            geom_xmat=two(d.geom_xmat).reshape(2, -1, 3, 3), body_xpos=two(d.xpos),
                            body_xmat=two(d.xmat).reshape(2, -1, 3, 3), cam_xpos=np.zeros((2, 0, 3)),
                            cam_xmat=np.zeros((2, 0, 3, 3)), touches=(), duration=1.0, same=True, judgement=None)
        return mo, m

    ball = '<body name="ball" pos="0 0 0.05"><freejoint/><geom type="sphere" size="0.05"/></body>'
    wall = '<geom name="wall" type="box" pos="0 -0.3 1" size="1 0.02 1"/>'
    fates = SimpleNamespace(controls=[SimpleNamespace(body="ball")], fates=[])
    boxes = (np.full((2, 3), -0.1), np.full((2, 3), 0.1))
    mo, m = motion_of(f'<mujoco><worldbody><geom type="plane" size="3 3 .1"/>{wall}{ball}</worldbody></mujoco>')
    hidden = {a: hidden_count(mo, fates, m, boxes, a) for a in AZIMUTHS}
    assert hidden[-70.0] == hidden[-110.0] == hidden[-30.0] == 2               # both frames, from the front
    assert hidden[10.0] == hidden[170.0] == hidden[50.0] == hidden[130.0] == 0
    assert clear_azimuth(mo, fates, m, boxes) == 10.0
    mo, m = motion_of(f'<mujoco><worldbody><geom type="plane" size="3 3 .1"/>{ball}</worldbody></mujoco>')
    assert clear_azimuth(mo, fates, m, boxes) == AZIMUTH


def test_a_still_at_t_is_framed_as_the_videos_frame_at_t(gl, solutions):
    """A fifth new user's still at t = 0 differed from the video's first frame by 13 grey levels a
    pixel: the framing was worked out on the frames recorded, 5 fps for the video and 30 for the
    still. It is now worked out on its own 30 fps clock: the view at each of a 5 fps video's frame
    times is the still's at that time, to round-off (1e-9 of each matrix entry's scale)."""
    from nbst.render.scene.framing import track_grid

    path = solutions["snake-eyes"]
    doc = json.loads(path.read_text())
    T = doc["nstep"] * doc["timestep"]
    video = frame_times(T, 5.0)
    views = {}
    for name, times in (("video", video), ("fine", frame_times(T, 60.0))):
        motion, fates, model = sm.record(path, np.union1d(times, track_grid(T)))
        r = sv.SceneRenderer(gl, motion, fates, model, size=(640, 360), title="t")
        try:
            views[name] = [r.view(float(t))[0] for t in video]
        finally:
            r.release()
    for t in video[::4]:   # a still records only its time with the framing's clock
        motion, fates, model = sm.record(path, np.union1d([t], track_grid(T)))
        r = sv.SceneRenderer(gl, motion, fates, model, size=(640, 360), title="t")
        try:
            still = r.view(float(t))[0]
        finally:
            r.release()
        k = int(np.argmin(np.abs(video - t)))
        for other in (views["video"][k], views["fine"][k]):
            assert np.allclose(still, other, rtol=1e-9, atol=1e-9 * np.abs(still).max())


def test_a_body_is_marked_in_its_own_vivid_colour():
    """A fifth new user's ball named `green`, green in the model, was labelled and its bin outlined
    in the palette's blue. A vivid colour of the body's own marks it; a white die, or a second body
    of the same red, takes the palette's."""
    from types import SimpleNamespace

    import mujoco

    xml = """<mujoco><asset><material name="m" rgba="0.1 0.8 0.2 1"/></asset><worldbody>
      <body name="green" pos="0 0 1"><freejoint/><geom type="sphere" size="0.1" material="m"/></body>
      <body name="die" pos="1 0 1"><freejoint/><geom type="box" size="0.1 0.1 0.1" rgba="0.95 0.95 0.95 1"/></body>
      <body name="red1" pos="2 0 1"><freejoint/><geom type="sphere" size="0.1" rgba="0.9 0.1 0.1 1"/></body>
      <body name="red2" pos="3 0 1"><freejoint/><geom type="sphere" size="0.1" rgba="0.9 0.12 0.1 1"/></body>
    </worldbody></mujoco>"""
    m = mujoco.MjModel.from_xml_string(xml)
    fates = SimpleNamespace(fates=[SimpleNamespace(body=n) for n in ("green", "die", "red1", "red2")])
    c = sv.mark_colours(m, fates)
    assert np.allclose(c[0], (0.1, 0.8, 0.2), atol=1e-6) and c[1] == sv.MARKS[1]
    assert np.allclose(c[2], (0.9, 0.1, 0.1), atol=1e-6) and c[3] == sv.MARKS[3]
    # a dark blue body's name is lightened for the dark panel, its hue kept: luminance 0.4, blue the most
    lit = sv.legible((0.1, 0.1, 0.8))
    assert abs(float(np.dot(lit, (0.2126, 0.7152, 0.0722))) - 0.4) < 1e-9 and lit[2] > lit[0] == lit[1]
    assert sv.legible((0.95, 0.45, 0.10)) == (0.95, 0.45, 0.10)
