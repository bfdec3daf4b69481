"""The crash video (render/crash/): what a viewer checks, never golden pixels. A vehicle shows
its colour where the replay has it, projected by the renderer's own camera; the impact ring
appears at the contact's time and not before; slow motion adds the frames its windows say; the
readout's marks are the judged fates; the CLI writes a still and a video that decodes with the
frames the frame times give, through the one atomic writer (nothing through a link)."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from nbst.models.crash import crashfile, run, script, space
from nbst.render.core.times import frame_times
from nbst.render.crash import motion as crash_motion, readout as crash_readout, scene as crash_scene, video as crash

SIZE = (800, 450)
#: A short crossing (2.5 s): A eastbound T-bones B northbound at about 1.6 s and brakes; B's fate
#: asks for a rest region and a heading it does not reach (so the readout has a ✗ to show).
SHORT = {
    "kind": "nbst-crash-script", "name": "short",
    "road": {"layout": "intersection", "width": 7, "length": 80},
    "duration": 2.5,
    "vehicles": [
        {"name": "A", "type": "sedan", "start": {"x": -22, "y": -1.75, "heading": 0}, "speed": [45, 55],
         "driver": {"aim": {"x": [0, 4], "y": -1.75}, "arrive": [1.5, 1.8], "after_impact": "brake"},
         "fate": {"hits": ["B"]}},
        {"name": "B", "type": "suv", "start": {"x": 1.75, "y": -22, "heading": 90}, "speed": [45, 55],
         "driver": {"aim": {"x": 1.75, "y": [-2, 2]}, "arrive": [1.5, 1.8]},
         "fate": {"hits": ["A"], "rest": {"x": -20, "y": 20, "radius": 2}, "heading": {"deg": 90, "tol": 30}}},
    ],
}


@pytest.fixture(scope="module")
def crash_file(tmp_path_factory):
    """One rollout of SHORT (seeded intents) written as a crash file, as `nbst crash solve` writes one."""
    s = script.script_from_dict(json.loads(json.dumps(SHORT)), source="short")
    sp = space.space_of(s)
    U = np.random.default_rng(3).random((1, sp.dim))
    R = run.CrashRunner(s, jobs=1, batch=1)
    res = R.run(sp.intents(U))
    d = crashfile.crash_dict(s, R.xml, R.model, sp.intents(U)[0], res.qpos0[0], res.qvel0[0], res.controls[0],
                             res.final_qpos[0], res.outcomes[0], seed=3, period_steps=R.period)
    f = tmp_path_factory.mktemp("crash") / "short.json"
    f.write_text(json.dumps(d, indent=1, allow_nan=False))
    return f


@pytest.fixture(scope="module")
def loaded(crash_file):
    return crash.load(crash_file)


@pytest.fixture(scope="module")
def gl():
    """The only place this file creates a GL context (EGL, headless)."""
    from nbst.render.core.gl import create_context

    ctx = create_context()
    yield ctx
    ctx.release()


@pytest.fixture(scope="module")
def overhead(gl, loaded):
    r = crash.CrashRenderer(gl, *loaded, size=SIZE, camera="overhead")
    yield r
    r.release()


def test_the_recording_is_the_files_own_replay(loaded):
    d, s, model, m = loaded
    assert m.identical                               # the final state bit for bit, the same outcome
    assert np.array_equal(m.qpos[-1], np.array(d["final_qpos"])) and m.times[-1] == pytest.approx(s.duration)
    assert np.array_equal(m.qpos[0], np.array(d["qpos0"]))
    assert np.all(np.diff(m.times) <= crash_motion.POSE_DT + 1e-12)
    assert crash_motion.impact_times(d["outcome"]) == [im.t for im in m.impacts]   # known before the replay
    (hit,) = [im for im in m.impacts if im.what == "vehicle"]
    assert (hit.a, hit.b, hit.t) == (0, 1, d["outcome"]["contacts"][0]["t"])


def test_a_braked_sliding_tyre_marks_the_road_and_a_rolling_one_does_not(loaded):
    """A brakes after the impact (its wheels lock): its skid marks start at the impact and follow
    its path within a tyre's reach; before the impact nobody slides, so the road is clean."""
    d, s, model, m = loaded
    t_hit = d["outcome"]["contacts"][0]["t"]
    skids = [mk for mk in m.marks if mk.kind == "skid"]
    assert all(mk.times[0] >= t_hit - crash_motion.MARK_DT for mk in skids)
    mine = [mk for mk in skids if mk.vehicle == 0]
    assert sum(mk.times[-1] - mk.times[0] for mk in mine) > 0.5         # four tyres, ~0.9 s of braking
    for mk in mine:   # every sample of a mark lies under the car: within its half diagonal of the CoM
        k = [m.index(t) for t in mk.times]
        off = np.hypot(*(mk.xy - m.pos[k, 0, :2]).T)
        assert off.max() < math.hypot(4.88, 1.83) / 2


def test_a_vehicle_shows_its_colour_where_the_replay_has_it(overhead):
    """Overhead: the pixel at the centre of each vehicle's roof, placed by MuJoCo's kinematics from
    the replay's state at that time, is of the vehicle's hue (A red, B blue), before, during and
    after the crash."""
    import mujoco

    r = overhead
    data = mujoco.MjData(r.model)
    for t in (0.4, 1.2, 2.5):
        frame = r.render(t)
        data.qpos[:] = r.motion.qpos[r.motion.index(t)]
        mujoco.mj_kinematics(r.model, data)
        (cam, vp, vpm, _), = r.views(t)
        for i, hue in enumerate((0, 2)):
            g = r.model.geom(f"v{i}_cabin").id
            roof = data.geom_xpos[g] + data.geom_xmat[g].reshape(3, 3) @ [0.0, 0.0, r.model.geom_size[g][2]]
            col, row, front = r.to_pixel(vp, vpm, roof)
            assert front and r._inside(vp, col, row)
            rgb = frame[int(row), int(col)].astype(int)
            assert np.argmax(rgb) == hue and rgb[hue] > rgb.min() + 40, (t, i, rgb)


def _ring_pixels(r, frame, t, im) -> int:
    """Pixels of the impact colour in the ring around impact ``im`` (overhead)."""
    (cam, vp, vpm, _), = r.views(t)
    col, row, _ = r.to_pixel(vp, vpm, im.pos)
    _, ppm = crash.top_view(r.bounds, vp)
    yy, xx = np.mgrid[0:frame.shape[0], 0:frame.shape[1]]
    d = np.hypot(xx + 0.5 - col, yy + 0.5 - row) / ppm
    edge = 0.7 / ppm                                   # a pixel clear of the ring's anti-aliased edges
    ring = (d > crash_scene.IMPACT_RING[0] + edge) & (d < crash_scene.IMPACT_RING[1] - edge)
    orange = np.abs(frame.astype(int) - np.array([255, 140, 20])).max(axis=2) < 40
    return int((ring & orange).sum()), int(ring.sum())


def test_the_impact_marker_appears_at_the_impact_and_not_before(overhead):
    r = overhead
    (im,) = [m for m in r.motion.impacts if m.what == "vehicle"]
    before, n = _ring_pixels(r, r.render(im.t - 0.05), im.t - 0.05, im)
    assert n > 50 and before == 0
    for t in (im.t + 0.01, r.motion.duration):
        got, n = _ring_pixels(r, r.render(t), t, im)
        assert got > 0.8 * n                          # drawn over the vehicles in the overhead view


def test_slow_motion_adds_the_frames_its_windows_say():
    fps, T = 30.0, 6.0
    w = crash_motion.slow_windows([2.0, 2.3, 5.9], T)
    a, b = crash_motion.SLOW_WINDOW
    assert w == [(2.0 - a, 2.3 + b), (5.9 - a, T)]     # overlapping windows merge; clipped to the end
    plain = frame_times(T, fps, hold=0.0)
    slow = frame_times(T, fps, windows=w, slow=crash_motion.SLOW, hold=0.0)
    extra = (crash_motion.SLOW - 1) * fps * sum(e - s for s, e in w)
    assert abs(len(slow) - len(plain) - extra) <= 1
    assert slow[0] == 0.0 and slow[-1] == T and np.all(np.diff(slow) > 0)
    inside = np.diff(slow)[(slow[:-1] >= w[0][0] + 1e-9) & (slow[1:] <= w[0][1] - 1e-9)]
    assert np.allclose(inside, 1 / (fps * crash_motion.SLOW))
    held = frame_times(T, fps, windows=w, slow=crash_motion.SLOW, hold=1.0)
    assert len(held) == len(slow) + 30 and np.all(held[len(slow):] == T)


def _marks_of(lines):
    return [(s, crash_readout.OK in s, crash_readout.NO in s) for s in lines]


def test_the_readout_marks_are_the_judged_fates(loaded):
    """At rest each asked fate's line carries ✓ where the replay's judgement holds it, ✗ where it
    does not (B: hits A ✓, rest and heading ✗), the vehicles' headers their signature bits, and
    the signature line the outcome's; before the end no line is marked."""
    d, s, model, m = loaded
    fates = [crashfile.fate_dict(s, i) for i in range(s.n)]
    labels = [v.vtype.label for v in s.vehicles]
    w = crash_motion.slow_windows([im.t for im in m.impacts], m.duration)
    end = crash_readout.readout(m.duration, m, s, fates, labels, w)
    assert f"signature {m.outcome.signature_text(s.n)}" in "\n".join(end) and d["outcome"]["signature"] == "10"
    key = {"hit ": "hits", "rest ": "rest", "end ": "rest", "facing ": "heading"}
    for i, (name, vo) in enumerate(zip(s.names(), m.outcome.vehicles)):
        block = end[end.index(next(x for x in end if x.startswith(f"{name} \u00b7 "))):]
        head = block[0]
        assert (crash_readout.OK in head) == all(vo.fates.values()) and (crash_readout.NO in head) != all(vo.fates.values())
        seen = set()
        for line in block[1:]:
            if not line:
                break
            fate = next((f for p, f in key.items() if line.startswith(p)), None)
            if fate in vo.fates and fate not in seen:
                seen.add(fate)
                assert (crash_readout.OK in line, crash_readout.NO in line) == (vo.fates[fate], not vo.fates[fate]), line
        assert seen == set(vo.fates) - {"delta_v", "impact_speed"}
    assert m.outcome.vehicles[1].fates == {"hits": True, "rest": False, "heading": False}
    early = crash_readout.readout(1.0, m, s, fates, labels, w)
    assert not any(crash_readout.OK in x or crash_readout.NO in x for x in early)
    assert "no hit yet" in "\n".join(early) and any("hit B 1.58 s" in x for x in end)


def test_the_readout_says_each_hits_delta_v_once(loaded):
    """Whether or not the script asks a delta-V band, each vehicle's block gives the delta-V of
    each hit once: with the band asked, the first hit's is on the asked line, not also on its hit line."""
    d, s, model, m = loaded
    labels = [v.vtype.label for v in s.vehicles]
    w = crash_motion.slow_windows([im.t for im in m.impacts], m.duration)
    for ask in (False, True):
        fates = [crashfile.fate_dict(s, i) for i in range(s.n)]
        if ask:
            for f in fates:
                f["delta_v_kmh"] = [5.0, 40.0]
        end = crash_readout.readout(m.duration, m, s, fates, labels, w)
        for i, (name, vo) in enumerate(zip(s.names(), m.outcome.vehicles)):
            at = end.index(next(x for x in end if x.startswith(f"{name} \u00b7 ")))
            block = end[at:end.index("", at) if "" in end[at:] else len(end)]
            assert vo.hits, "the short crash's vehicles meet"
            assert sum(x.count(crash_readout.DV) for x in block) == len(vo.hits), block
            first = f"{crash_readout.DV} {d['outcome']['contacts'][0]['delta_v_kmh'][name]:.1f} km/h"
            assert sum(first in x for x in block) == 1 and any(x.startswith(first) for x in block) == ask, block


@pytest.mark.parametrize("size, camera", [((640, 360), "both"), ((1280, 720), "both"), ((640, 360), "overhead")])
def test_the_readout_fits_its_box_and_labels_stay_in_their_panels(gl, loaded, size, camera):
    """Every readout line fits the column and every row the box under the overhead panel (which
    gives way on a small frame); the labels drawn in a panel stay inside it."""
    r = crash.CrashRenderer(gl, *loaded, size=size, camera=camera, follow=1)
    try:
        cw, ch = r.text.cell
        for t in (0.0, r.motion.duration):
            lines = r.readout(t)
            assert max(len(x) for x in lines) * cw <= r.text_box[2] and len(lines) * ch <= r.text_box[3]
        boxes = []
        r._label = (lambda f: lambda vp, *a: boxes.append((vp, f(vp, *a))) or boxes[-1][1])(r._label)
        r.render(r.motion.duration)
        assert boxes
        for vp, (x0, y0, x1, y1) in boxes:
            assert vp[0] <= x0 and x1 <= vp[0] + vp[2] and vp[1] <= y0 and y1 <= vp[1] + vp[3]
    finally:
        r.release()


@pytest.mark.parametrize("size", [(16, 16), (32, 18), (1000, 20), (16, 400), (48, 27)])
@pytest.mark.parametrize("camera", ["overhead", "both"])
def test_any_size_the_cli_takes_draws(gl, loaded, size, camera):
    """Every frame size ``--size`` accepts (16 to 8192 a side) draws a crash, however little of the
    readout fits (an audit's 16x16 raised IndexError where no line fitted)."""
    r = crash.CrashRenderer(gl, *loaded, size=size, camera=camera, follow=0)
    try:
        frame = r.render(r.motion.duration / 2)
        assert frame.shape == (size[1], size[0], 3)
    finally:
        r.release()


def test_the_atlas_writes_the_readout_signs(gl):
    from nbst.render.core.shapes import Text, glyph_index

    t = Text(gl, 20)
    try:
        cw, ch = t.cell
        # the readout's signs, and Latin-1's letters (a user's die named "w\u00fcrfel" was written "w rfel")
        for c in "\u2713\u2717\u0394\u00b0\u00b1\u00d7" "\u00fc\u00e8\u00f1\u00df\u00c5":
            g = glyph_index(c)
            assert g is not None, c
            r, k = divmod(g, 16)
            assert t._atlas[r * ch:(r + 1) * ch, k * cw:(k + 1) * cw].max() > 200, c   # ink in its cell
        assert glyph_index(" ") is None and glyph_index("\u2603") is None and glyph_index("A") == ord("A") - 32
    finally:
        t.release()


def test_crash_kind_sniffs_files_and_scripts(crash_file, tmp_path):
    assert crash.crash_kind(crash_file) == "crash"
    f = tmp_path / "s.json"
    f.write_text(json.dumps(SHORT))
    assert crash.crash_kind(f) == "script"
    (tmp_path / "p.json").write_text('{"kind": "problem"}')
    assert crash.crash_kind(tmp_path / "p.json") is None and crash.crash_kind(tmp_path / "none.json") is None


@pytest.mark.slow
def test_cli_writes_a_still_and_a_video_with_the_frames_its_times_give(crash_file, tmp_path, capsys):
    import imageio

    from nbst.cli.main import main

    png = tmp_path / "s.png"
    assert main(["render", str(crash_file), "--still", "1.6", "-o", str(png), "--size", "320x180",
                 "--follow", "B"]) == 0
    from PIL import Image

    assert Image.open(png).size == (320, 180)
    mp4 = tmp_path / "v.mp4"
    assert main(["render", str(crash_file), "-o", str(mp4), "--size", "320x180", "--fps", "12", "--hold", "0.5"]) == 0
    err = capsys.readouterr().err
    assert "bit for bit" in err and "slow motion around 1 impact" in err
    d, s, model, m = crash.load(crash_file)
    want = len(frame_times(m.duration, 12.0, windows=crash_motion.slow_windows([im.t for im in m.impacts], m.duration),
                           slow=crash_motion.SLOW, hold=0.5))
    rd = imageio.get_reader(mp4)
    assert sum(1 for _ in rd) == want and rd.get_meta_data()["fps"] == 12.0
    assert f"{want} frames" in err and not list(tmp_path.glob(".*partial*"))


def test_cli_refuses_bad_flags_and_links_in_one_line(crash_file, tmp_path, capsys):
    from nbst.cli.main import main

    target = tmp_path / "kept.png"
    target.write_bytes(b"previous")
    link = tmp_path / "link.png"
    link.symlink_to(target)
    cases = [
        (["--still", "1", "-o", str(link)], "link"),
        (["--still", "9", "-o", str(tmp_path / "a.png")], "--still 9"),
        (["--still", "1", "-o", str(tmp_path / "a.png"), "--follow", "Z"], "--follow 'Z'"),
        (["-o", str(tmp_path / "a.mp4"), "--trails"], "--trails"),
        (["-o", str(tmp_path / "a.txt")], ".mp4 or .gif"),
        (["-o", str(tmp_path / "a.mp4"), "--follow", "A", "--camera", "overhead"], "--follow"),
    ]
    for extra, why in cases:
        capsys.readouterr()
        assert main(["render", str(crash_file), *extra]) == 2, extra
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and why in err and "Traceback" not in err, err
    assert target.read_bytes() == b"previous" and link.is_symlink()
    s = tmp_path / "script.json"
    s.write_text(json.dumps(SHORT))
    assert main(["render", str(s), "-o", str(tmp_path / "a.mp4")]) == 2
    assert "crash solve" in capsys.readouterr().err
    (tmp_path / "p.json").write_text("{}")
    assert main(["render", str(tmp_path / "p.json"), "-o", str(tmp_path / "a.mp4"), "--follow", "A"]) == 2
    assert "crash files only" in capsys.readouterr().err


@pytest.mark.parametrize("size", [(1280, 720), (640, 360)])
def test_the_overhead_view_takes_at_least_half_the_frame(gl, loaded, size):
    """With the chase view beside it (camera both) and alone, the overhead panel covers at least
    half the frame, and a car in it is drawn at least 60 px long at 720p (the issue's 460x325 panel
    drew it ~40 px long)."""
    for camera in ("both", "overhead"):
        r = crash.CrashRenderer(gl, *loaded, size=size, camera=camera, follow=1)
        try:
            _, _, w, h = r.panels["overhead"]
            assert w * h >= 0.5 * size[0] * size[1]
            _, ppm = crash.top_view(r.bounds, r.panels["overhead"])
            length = 2 * float(r.model.geom_size[r.model.geom("v0_lower").id][0])
            if size == (1280, 720):
                assert length * ppm >= 60
        finally:
            r.release()


def _yellow(frame, vp) -> int:
    x, y, w, h = vp
    sub = frame[y:y + h, x:x + w].astype(int)
    return int((np.abs(sub - np.array([255, 230, 26])).max(axis=2) < 45).sum())


def test_velocity_and_pdof_arrows_appear_at_the_impact(gl, loaded):
    """Overhead, clean (no labels): the PDOF arrows' yellow is absent before the impact and drawn from
    its time on; each vehicle's PDOF is a clock hour whose direction is its velocity change's
    reverse in its own frame (A, hitting B with its front, from ahead: 11, 12 or 1 o'clock), and the
    two changes are opposed (momentum: m_A dv_A ~ -m_B dv_B within 30 %, tyre forces aside)."""
    d, s, model, m = loaded
    (im,) = [x for x in m.impacts if x.what == "vehicle"]
    assert set(im.pdof) == {0, 1} and im.t <= im.t_end < im.t + 0.3
    assert im.pdof[0] in (11, 12, 1)
    mass = [float(model.body_subtreemass[model.body(f"v{i}").id]) for i in range(2)]
    pa, pb = (mass[i] * np.array(im.dv[i]) for i in range(2))
    assert np.linalg.norm(pa + pb) < 0.3 * np.linalg.norm(pa)
    # the arrows' delta-V is the report's (models/crash/impact.py), from the step before the first
    # touch: each vehicle's |dv| within 10 % of its contact impulse / mass (the tyres' share aside)
    from nbst.models.crash import impact as impact_mod
    (p,) = impact_mod.crash_impacts(d, s, model).impacts
    for v in p.vehicles:
        assert im.dv[v.vehicle] == v.dv_world and im.pdof[v.vehicle] == v.pdof_clock
        assert abs(v.dv - v.dv_impulse) < 0.1 * v.dv_impulse
    r = crash.CrashRenderer(gl, *loaded, size=SIZE, camera="overhead", clean=True)
    try:
        vp = r.panels["overhead"]
        assert _yellow(r.render(im.t - 0.05), vp) == 0
        for t in (im.t + 0.01, m.duration):
            assert _yellow(r.render(t), vp) > 30
    finally:
        r.release()
    assert crash_motion.clock_of((-1.0, 0.0)) == 12 and crash_motion.clock_of((0.0, 1.0)) == 3
    assert crash_motion.clock_of((1.0, 0.0)) == 6 and crash_motion.clock_of((0.0, -1.0)) == 9


@pytest.mark.slow
def test_the_chase_camera_keeps_both_vehicles_in_view(gl, loaded):
    """At every frame time, each vehicle's CoM projects inside the chase panel, in front of the
    camera, for either vehicle followed."""
    d, s, model, m = loaded
    times = frame_times(m.duration, 30.0, hold=0.0)
    for follow in (0, 1):
        r = crash.CrashRenderer(gl, *loaded, size=SIZE, camera="both", follow=follow)
        try:
            assert r.partner == 1 - follow
            for t in times:
                (cam, vp, vpm, _), = [v for v in r.views(t) if v[0] == "behind"]
                k = m.index(t)
                for i in (0, 1):
                    col, row, front = r.to_pixel(vp, vpm, m.pos[k, i])
                    assert front and r._inside(vp, col, row), (follow, t, i)
        finally:
            r.release()
