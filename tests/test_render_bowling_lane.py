"""The picture of a throw from the foul line (render/bowling/lane.py): what a viewer checks,
never golden pixels. Marks are found where the renderer's own camera projects them (the
projection is the camera's; the marks' world positions come from models/bowling/lane.py), the
pin numbers where the diagram puts them, the ball's marks turning with its quaternion, and the
CLI's video decoding with the frame count the frame times give."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from nbst.models.bowling import lane, scene
from nbst.models.bowling.lane import frame, spares
from nbst.render.bowling import lane as bl
from nbst.render.bowling import throw as bt
from nbst.models.bowling import pinfall

SIZE = (960, 540)
TYPICAL = lane.Delivery(hand="right", board=20, at="foul", angle=2.82, mph=17, rpm=350, rotation=45, tilt=12)


@pytest.fixture(scope="module")
def gl():
    """The only place this file creates a GL context (EGL, headless)."""
    from nbst.render.core.gl import create_context

    ctx = create_context()
    yield ctx
    ctx.release()


@pytest.fixture(scope="module")
def throw():
    return bt.record_throw(TYPICAL, "house")


@pytest.fixture(scope="module")
def behind(gl, throw):
    r = bl.LaneRenderer(gl, throw, size=SIZE, camera="behind")
    yield r
    r.release()


def _px(r, t, p):
    vp, vpm, _, _ = r.views(t)[0]
    col, row, front = r.to_pixel(vp, vpm, p, r.size[1])
    assert front
    return int(round(col)), int(round(row))


def _lane_like(rgb) -> bool:
    """Wood: red over green over blue, bright."""
    r, g, b = (int(c) for c in rgb)
    return r > g > b and r > 150


def test_the_motion_starts_at_the_foul_line_and_ends_with_the_frame(throw):
    m = throw.motion
    assert m.ball[0, 0] == pytest.approx(lane.FOUL_LINE_X) and m.ball[0, 0] < -18.0     # 60 ft from the head pin
    assert throw.result is not None and abs(throw.result.seconds_to_pins - m.impact) < 0.1
    # it ends where the frame ends: settled (or at the cap), one recorded pose per step
    fr = throw.frame
    assert 0 < m.impact < m.times[-1] and len(m.times) == round(fr.seconds / throw.timestep) + 1
    assert fr.settled != fr.cap_hit and m.times[-1] == pytest.approx(fr.seconds, abs=1e-9)
    assert m.down == fr.down == sorted(m.down) and m.down_masks.shape == m.times.shape
    # the ball is drawn relative to its release orientation: the identity at the release
    assert np.allclose(m.ball[0, 3:7], [1.0, 0.0, 0.0, 0.0], atol=1e-12)


SPARE_10 = spares.straight_at(*spares.aim_point((10,)))


@pytest.mark.parametrize("delivery, standing", [(spares.STRIKE, None), (SPARE_10, [10])], ids=["strike", "spare-10"])
def test_the_recording_is_the_frame_run_frame_runs(delivery, standing):
    """The picture records frame.run_frame itself (its model, initial state, steps and stop rule):
    the same pins down and leave and the same final state, bit for bit, as the frame without
    the recording hook; the last recorded poses are that final state."""
    
    fr = frame.run_frame(delivery, standing=standing)
    th = bt.record_throw(delivery, "house", standing=standing)
    assert (th.frame.down, th.frame.leave) == (fr.down, fr.leave) and th.motion.down == fr.down
    assert np.array_equal(th.frame.final_qpos, fr.final_qpos) and th.frame.settle_s == fr.settle_s
    m = frame.frame_model()
    adr = pinfall.pin_addresses(m)
    assert np.array_equal(th.motion.pins[-1], fr.final_qpos[adr[:, None] + np.arange(7)])
    ba = int(m.joint("ball_free").qposadr[0])
    assert np.array_equal(th.motion.ball[-1, :3], fr.final_qpos[ba:ba + 3])
    assert pinfall.pins_of(int(th.motion.down_masks[-1])) == fr.down
    assert th.in_play == tuple(fr.in_play)
    if standing:                               # pins not in play stay parked, never counted down
        parked = [k for k, n in enumerate(scene.PIN_NUMBERS) if n not in standing]
        assert np.abs(th.motion.pins[:, parked, :2] - th.motion.pins[0, parked, :2]).max() < 1e-3   # within 1 mm
        assert (th.motion.pins[:, parked, 0] < lane.FOUL_LINE_X - 1.0).all()     # behind the approach
        assert all(pinfall.pins_of(int(x)) == [] or set(pinfall.pins_of(int(x))) <= set(standing)
                   for x in th.motion.down_masks)


def test_foul_line_is_drawn_where_the_behind_camera_sees_it(behind):
    frame = behind.render(0.0)
    ball_col, _ = _px(behind, 0.0, [lane.FOUL_LINE_X, lane.board_to_y(TYPICAL.foul_board()), scene.BALL_RADIUS])
    checked = 0
    for board in (2, 5, 8, 25, 30, 35, 38):
        col, row = _px(behind, 0.0, [lane.FOUL_LINE_X, float(lane.board_to_y(board)), 0.0])
        if abs(col - ball_col) < 80:
            continue
        r, g, b = frame[row, col].astype(int)
        assert r > 1.6 * g and r > 1.6 * b, (board, (r, g, b))            # the red foul line
        above = frame[row - 8, col]                                          # the lane just past it
        below = frame[row + 8, col]                                          # the approach before it
        assert _lane_like(above) and _lane_like(below), (board, above, below)
        checked += 1
    assert checked >= 5


def test_arrows_are_drawn_at_15_ft_on_their_boards(behind, throw):
    # 0.3 s after the release the camera is 4 m from the arrows; the ball (on boards 13-20) is
    # nearer the camera, so the arrows clear of its disc are checked (those outside, both sides)
    t = 0.3
    frame = behind.render(t)
    k = behind.step_at(t)
    ball_col, ball_row = _px(behind, t, throw.motion.ball[k, :3])
    xa = float(lane.ft_to_x(lane.ARROWS_FT))
    seen = 0
    for board in lane.ARROW_BOARDS:
        y = float(lane.board_to_y(board))
        col, row = _px(behind, t, [xa - 0.08 / 3, y, 0.0])                  # the arrow's centroid
        if abs(col - ball_col) < 70:
            continue
        patch = frame[row - 1:row + 2, col - 1:col + 2].reshape(-1, 3).astype(int)
        assert patch.sum(axis=1).min() < 0.45 * (255 * 3), board          # dark paint
        # half a board beside it, and 0.2 m before and after it: the lane
        for p in ([xa, y + 0.6 * lane.BOARD_WIDTH * 2.2, 0.0], [xa - 0.2, y, 0.0], [xa + 0.2, y, 0.0]):
            c2, r2 = _px(behind, t, p)
            assert _lane_like(frame[r2, c2]), (board, p, frame[r2, c2])
        seen += 1
    assert seen >= 2


def test_ten_pin_numbers_in_the_diagram_lit_while_standing_dim_when_down(gl, throw):
    r = bl.LaneRenderer(gl, throw, size=SIZE, camera="both")
    try:
        vp = r.panels["overhead"]
        diag = r.pin_diagram(vp)
        assert sorted(n for n, _, _ in diag) == list(range(1, 11))
        pos = {n: (c, w) for n, c, w in diag}
        # laid out as the deck seen from the bowler: 7 left of 10 on the back row, 1 alone in front
        assert pos[7][0] < pos[8][0] < pos[9][0] < pos[10][0] and pos[7][1] == pos[10][1] < pos[4][1] < pos[2][1] < pos[1][1]
        assert pos[2][0] < pos[1][0] < pos[3][0]
        cw, ch = r.small.cell

        def ink(frame, n):
            c, w = pos[n]
            box = frame[int(w):int(w + ch), int(c):int(c + cw * len(str(n)))].astype(int)
            return box.sum(axis=2).max()

        first = r.render(0.0)
        last = r.render(float(throw.motion.times[-1]))
        down = set(throw.motion.down)
        assert down, "the typical release knocks pins down"
        for n in range(1, 11):
            assert ink(first, n) > 600, n                                     # every number drawn, bright
            assert (ink(last, n) < 400) == (n in down), n                     # dim once down
    finally:
        r.release()


def test_ball_marks_turn_with_the_quaternion(gl, throw):
    """The dark grip holes inside the ball's disc move between frames 20 ms apart while the
    ball spins (300 rpm: 36 deg); with its orientation frozen they stay put."""
    frozen_ball = throw.motion.ball.copy()
    frozen_ball[:, 3:7] = [1.0, 0.0, 0.0, 0.0]
    frozen = dataclasses.replace(throw, motion=dataclasses.replace(throw.motion, ball=frozen_ball))

    def dark_masks(th, times):
        r = bl.LaneRenderer(gl, th, size=SIZE, camera="behind")
        try:
            out = []
            for t in times:
                frame = r.render(t).astype(int)
                k = r.step_at(t)
                c, w = _px(r, t, th.motion.ball[k, :3])
                c2, _ = _px(r, t, th.motion.ball[k, :3] + [0.0, scene.BALL_RADIUS, 0.0])
                rad = int(abs(c2 - c) * 0.9)
                disc = frame[w - rad:w + rad + 1, c - rad:c + rad + 1]
                yy, xx = np.mgrid[-rad:rad + 1, -rad:rad + 1]
                out.append((disc.sum(axis=2) < 60) & (xx * xx + yy * yy <= rad * rad))
            return out
        finally:
            r.release()

    times = [0.10 + 0.02 * i for i in range(8)]
    spun = dark_masks(throw, times)
    still = dark_masks(frozen, times)

    def centroids(masks):
        """Centre of the dark pixels relative to the ball's projected centre (px), per frame with any."""
        out = []
        for m in masks:
            if m.sum() >= 10:
                yy, xx = np.nonzero(m)
                out.append((xx.mean() - m.shape[1] // 2, yy.mean() - m.shape[0] // 2))
        return np.array(out)

    cs, cf = centroids(spun), centroids(still)
    assert len(cf) == len(times) and len(cs) >= 2            # the holes face the camera when frozen at release
    assert np.abs(np.diff(cf, axis=0)).max() < 2.0, cf        # frozen: they stay within 2 px
    assert np.hypot(*np.diff(cs, axis=0).T).max() > 8.0, cs   # spinning: they move (36 deg a frame)


def test_texture_has_the_grip_holes_and_the_track(throw):
    tex = bt.ball_texture(throw)
    h, w, _ = tex.shape
    dirs = bt._texel_dirs((w, h)).reshape(-1, 3)
    flat = tex.reshape(-1, 3).astype(int)
    for p, rad in bt.grip_holes(throw.delivery):
        inside = dirs @ p > np.cos(rad * 0.8)
        assert inside.any() and (flat[inside].sum(axis=1) < 40).all()         # dark holes
    track = np.abs(flat - np.round(np.array(bt.TRACK_RGB) * 255)).sum(axis=1) <= 1
    # the release's contact point (straight down at the identity orientation) is on the track
    down = dirs @ np.array([0.0, 0.0, -1.0]) > np.cos(np.radians(1.0))
    assert track[down].any() and 0.02 < track.mean() < 0.6


def test_readout_names_the_throw_and_adds_asked_and_probability_only_when_given(gl, throw):
    r = bl.LaneRenderer(gl, throw, size=(320, 180), camera="overhead")
    try:
        text = "\n".join(r.readout(float(throw.motion.times[-1])))
        assert "17.0 mph" in text and "350 rpm" in text and "rotation 45" in text and "tilt 12" in text
        assert "board 20.0 at the foul line" in text and "break   40.6 ft" in text and "entry 3.5 deg" in text
        assert "result  down" in text and "asked" not in text and "chance" not in text
    finally:
        r.release()
    r = bl.LaneRenderer(gl, throw, size=(320, 180), camera="overhead", asked=range(1, 11), probability=0.72,
                        probability_note="n = 200")
    try:
        text = "\n".join(r.readout(float(throw.motion.times[-1])))
        assert "asked   down 1,2,3,4,5,6,7,8,9,10 (a strike)" in text and "chance  72% (n = 200)" in text
        assert "file" not in text
    finally:
        r.release()


def test_cli_writes_a_still_and_an_mp4_with_the_expected_frames(gl, throw, tmp_path, capsys):
    import imageio_ffmpeg
    from PIL import Image

    from nbst.cli.main import main

    png, mp4 = tmp_path / "t.png", tmp_path / "t.mp4"
    # the fixture's delivery, given at the foul line (--at arrows would be aimed along the ball's path)
    assert main(["bowl", "throw", "--board", repr(TYPICAL.foul_board()), "--at", "foul", "--angle", repr(TYPICAL.angle),
                 "--mph", repr(TYPICAL.mph), "--rpm", repr(TYPICAL.rpm), "--rotation", repr(TYPICAL.rotation),
                 "--tilt", repr(TYPICAL.tilt), "--still", str(png), "--size", "320x180", "--video", str(mp4),
                 "--fps", "8"]) == 0
    assert Image.open(png).size == (320, 180)
    expected = len(bt.throw_times(throw, 8.0))
    reader = imageio_ffmpeg.read_frames(str(mp4))
    meta = next(reader)
    assert tuple(meta["size"]) == (320, 180) and meta["fps"] == pytest.approx(8.0)
    assert sum(1 for _ in reader) == expected
    err = capsys.readouterr().err
    assert f"({expected} frames)" in err


@pytest.mark.parametrize("argv, words", [
    (["--video", "x.png"], "--video x.png: use a .mp4 or .gif file"),
    (["--still", "x.mp4"], "--still x.mp4: use a .png file"),
    (["--fps", "10"], "--fps: needs --video or --still"),
    (["--still", "x.png", "--size", "12x9"], "width and height must be 16..8192"),
])
def test_cli_bad_picture_flags_are_one_line(tmp_path, capsys, monkeypatch, argv, words):
    from nbst.cli.main import main

    monkeypatch.chdir(tmp_path)
    assert main(["bowl", "throw", *argv]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and words in err[0]
    assert not list(tmp_path.iterdir())


@pytest.fixture(scope="module")
def spare_file(tmp_path_factory):
    """A 10-pin spare throw file from the CLI, with a 4-throw probability."""
    from nbst.cli.main import main

    path = tmp_path_factory.mktemp("spare") / "spare10.json"
    assert main(["bowl", "frame", "--leave", "10", "--board", "34", "--at", "foul", "--angle", "2.32", "--rpm", "200",
                 "--rotation", "0", "--tilt", "0", "--probability", "4", "-o", str(path)]) == 0
    return path


def test_a_spare_draws_only_the_pins_in_play_and_its_readout_names_rack_ask_result_and_chance(gl, spare_file):
    from nbst.models.bowling.lane import throwfile

    d = throwfile.load(spare_file)
    th = bt.record_throw(lane.Delivery(**d["delivery"]), d["oil"], lane.Ball(**d["ball"]), standing=d["standing"],
                         timestep=d["outcome"]["timestep"])
    assert th.frame.down == d["outcome"]["down"] == [10]
    ro = bt.throw_file_readout(d)
    e = d["probability"]
    r = bl.LaneRenderer(gl, th, size=SIZE, camera="both", **ro)
    try:
        text = "\n".join(r.readout(float(th.motion.times[-1])))
        assert "rack    10 standing before the throw" in text
        assert "asked   no pins named (a throw filmed as it fell)" in text     # bowl frame asks nothing
        assert "result  down 10 (the spare)" in text and "this run differs" not in text
        assert (f"chance  {100 * e['p']:.0f}% (the spare; {e['k']}/{e['n']}, 95% CI {100 * e['lo']:.0f}-"
                f"{100 * e['hi']:.0f}%)") in text
        # the diagram lights the 10 alone before the throw (pins 1-9 are not in play), none at the end
        diag = {n: (c, w) for n, c, w in r.pin_diagram(r.panels["overhead"])}
        cw, ch = r.small.cell

        def ink(img, n):
            c, w = diag[n]
            return img[int(w):int(w + ch), int(c):int(c + cw * len(str(n)))].astype(int).sum(axis=2).max()

        first, last = r.render(0.0), r.render(float(th.motion.times[-1]))
        assert ink(first, 10) > 600 and all(ink(first, n) < 400 for n in range(1, 10))
        assert all(ink(last, n) < 400 for n in range(1, 11))
    finally:
        r.release()
    asked = bt.throw_file_readout({**d, "requested": {"down": [10]}})
    r = bl.LaneRenderer(gl, th, size=(320, 180), camera="overhead", **asked)
    try:
        text = "\n".join(r.readout(float(th.motion.times[-1])))
        assert "asked   down 10 (the spare)" in text and "result  down 10 (the spare) = asked" in text
    finally:
        r.release()
    # a file whose outcome differs from the run says so (the replay exits 1 then)
    r = bl.LaneRenderer(gl, th, size=(320, 180), camera="overhead", expected=[])
    try:
        assert "file    down none: this run differs" in r.readout(float(th.motion.times[-1]))
    finally:
        r.release()


def test_cli_replay_films_a_throw_file_and_refuses_a_shot_file_in_one_line(spare_file, tmp_path, capsys):
    import imageio_ffmpeg
    from PIL import Image

    from nbst.cli.main import main

    png, mp4 = tmp_path / "r.png", tmp_path / "r.mp4"
    capsys.readouterr()
    assert main(["bowl", "replay", str(spare_file), "--still", str(png), "--video", str(mp4), "--size", "160x90",
                 "--fps", "4"]) == 0
    cap = capsys.readouterr()
    assert "pins down  10  (leave none)" in cap.out and "(match)" in cap.out
    assert Image.open(png).size == (160, 90)
    reader = imageio_ffmpeg.read_frames(str(mp4))
    assert tuple(next(reader)["size"]) == (160, 90) and sum(1 for _ in reader) > 4
    assert f"nbst bowl replay: wrote {mp4}" in cap.err
    shot = tmp_path / "shot.json"
    shot.write_text('{"kind": "nbst-bowling-shot"}')
    assert main(["bowl", "replay", str(shot), "--video", str(tmp_path / "s.mp4")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "a 5 m throw file" in err[0] and "nbst render THROW.json" in err[0]
    assert main(["bowl", "replay", str(spare_file), "--video", str(tmp_path / "x.png")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--video" in err[0] and "use a .mp4 or .gif file" in err[0]
    assert not (tmp_path / "s.mp4").exists() and not (tmp_path / "x.png").exists()
    # `nbst render` given a foul-line throw file names the command that films it (it used to say "is a
    # problem: give its SOLUTION too"), in one line, writing nothing
    assert main(["render", str(spare_file), "-o", str(tmp_path / "t.mp4")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "a foul-line throw file" in err[0] and f"nbst bowl replay {spare_file} --video" in err[0]
    assert not (tmp_path / "t.mp4").exists()


@pytest.mark.parametrize("oil", ["house", lane.pattern("house")])
def test_the_oil_line_names_the_pattern_and_stays_in_its_panel(gl, throw, oil):
    """The readout's oil line is what a bowler reads (the pattern's name, length and volume), never a
    raw Pattern object, given a pattern or its name; every line of the text drawn ends inside the
    behind panel, clear of the overhead panel and its pin legend."""
    r = bl.LaneRenderer(gl, dataclasses.replace(throw, oil=oil), size=SIZE, camera="both")
    try:
        cw = r.text.cell[0]
        left, _, width, _ = r.panels["behind"]
        for t in (0.0, 1.5, float(throw.motion.times[-1])):
            lines = r.readout(t)
            (line,) = [s for s in lines if s.startswith("oil")]
            assert line.startswith("oil     house (40 ft, 22 ml); ball 15 lb") and "Pattern(" not in line
            assert left + 0.6 * cw + max(map(len, lines)) * cw <= left + width
    finally:
        r.release()


def test_a_long_pattern_name_is_cut_on_the_oil_line():
    long = dataclasses.replace(lane.pattern("house"), name="a very long pattern name from a pattern file")
    text = bl.oil_summary(long)
    assert text == "a very long pattern n... (40 ft, 22 ml)" and len(text.split(" (")[0]) == bl.OIL_NAME_CHARS
