"""Frames of the 2D and 3D renderers: properties a user sees, not golden pixels.

The GL context is made in exactly one place, the ``gl`` fixture below.
Disk positions come from the exact simulator (``Trajectory.at``); where a
frame is checked against positions, the world-to-pixel mapping is recovered
from the frame itself (its walls), not taken from the renderer.
"""
import numpy as np
import pytest

from nbst import load_problem, simulate
from nbst.render.core import style
from nbst.render.motion2d import SampledMotion, trail_points
from nbst.render.scene2d import Layout, Renderer2D

SIZE = (480, 360)


@pytest.fixture(scope="module")
def gl():
    """The only place a GL context is created in the tests (EGL, headless)."""
    from nbst.render.core.gl import create_context
    ctx = create_context()
    yield ctx
    ctx.release()


@pytest.fixture(scope="module")
def diamond():
    p = load_problem("diamond-s14")
    return p, simulate(p, p.straight_velocities())


def over5_motion():
    """over5 with two shots that strike noncueable disks (so they move)."""
    p = load_problem("over5")
    v = np.zeros((p.n, 2))
    v[0] = (45.0, 3.0)  # disk 0 drives into noncueable disk 2, right beside it
    v[1] = (90.0, 20.0)
    tr = simulate(p, v)
    assert tr.n_disk_disk >= 1  # the test needs a struck noncueable disk
    return p, tr


def close(a, b, tol):
    return np.abs(np.asarray(a, int) - np.asarray(b, int)).max() <= tol


def box_from_walls(frame):
    """Inner edges of the box (x0, y0, x1, y1 in px) found from wall-coloured
    pixels along the middle row and column, independent of the renderer's layout."""
    wall = np.array(style.rgb8(style.BOX_WALL))
    h, w, _ = frame.shape

    def inner(line):
        hit = np.nonzero(np.abs(line.astype(int) - wall).max(axis=1) <= 24)[0]
        assert hit.size >= 2, "no walls found"
        left = hit[0]
        while left + 1 < len(line) and left + 1 in hit:
            left += 1
        right = hit[-1]
        while right - 1 in hit:
            right -= 1
        return left + 1.0, float(right)  # first floor pixel .. first wall pixel of the far side

    x0, x1 = inner(frame[h // 2])
    y0, y1 = inner(frame[:, w // 2])
    return x0, y0, x1, y1


def world_to_px(problem, box_px, xy):
    x0, y0, x1, y1 = box_px
    W, H = problem.box
    xy = np.asarray(xy, float)
    return np.stack([x0 + xy[..., 0] / W * (x1 - x0), y0 + (H - xy[..., 1]) / H * (y1 - y0)], axis=-1)


def pixel(frame, pt):
    c, r = int(np.floor(pt[0])), int(np.floor(pt[1]))
    return frame[r, c]


# --------------------------------------------------------------------------- 2D frames

@pytest.mark.parametrize("t", [0.0, 1.3, 2.71, 5.0])
def test_each_disk_has_its_colour_at_its_simulated_centre(gl, diamond, t):
    p, tr = diamond
    r = Renderer2D(gl, p, tr, size=SIZE, trails=True)
    try:
        f = r.render(t)
    finally:
        r.release()
    assert f.shape == (SIZE[1], SIZE[0], 3) and f.dtype == np.uint8
    box = box_from_walls(f)
    centres = world_to_px(p, box, tr.at(t))
    targets = world_to_px(p, box, p.target)
    amber = style.rgb8(style.CUEABLE)
    for i, c in enumerate(centres):
        if np.linalg.norm(targets - c, axis=1).min() < style.MIN_MARKER_PX + 6:
            continue  # a target marker lies on this disk (drawn above it: test_targets_are_never_hidden)
        # 3x3 around the centre: all fill colour (disk radius ~8 px here, rim 1 px)
        for dc in (-1, 0, 1):
            for dr in (-1, 0, 1):
                assert close(pixel(f, c + (dc, dr)), amber, 3), (i, t, pixel(f, c + (dc, dr)))


def test_noncueable_disks_have_a_distinct_colour_where_simulated(gl):
    p, tr = over5_motion()
    r = Renderer2D(gl, p, tr, size=SIZE)
    try:
        for t in (0.0, 2.5, 5.0):
            f = r.render(t)
            box = box_from_walls(f)
            for i, c in enumerate(world_to_px(p, box, tr.at(t))):
                want = style.CUEABLE if p.cueable[i] else style.NONCUEABLE
                other = style.NONCUEABLE if p.cueable[i] else style.CUEABLE
                assert close(pixel(f, c), style.rgb8(want), 3), (i, t)
                assert not close(pixel(f, c), style.rgb8(other), 60)
    finally:
        r.release()
    # the struck noncueable disk really moved, so the check followed a moving disk
    assert np.abs(tr.final_positions[~p.cueable] - p.start[~p.cueable]).max() > 20


def test_background_where_no_disk_is(gl, diamond):
    p, tr = diamond
    t = 2.0
    r = Renderer2D(gl, p, tr, size=SIZE)
    try:
        f = r.render(t)
    finally:
        r.release()
    box = box_from_walls(f)
    pos = tr.at(t)
    gx, gy = np.meshgrid(np.linspace(15, p.width - 15, 40), np.linspace(15, p.height - 15, 40))
    pts = np.stack([gx.ravel(), gy.ravel()], axis=1)
    d_disk = np.linalg.norm(pts[:, None] - pos[None], axis=2).min(axis=1)
    d_tgt = np.linalg.norm(pts[:, None] - p.target[None], axis=2)
    far = (d_disk > p.radius.max() + 12) & (np.abs(d_tgt - p.target_radius).min(axis=1) > 10) \
        & (d_tgt.min(axis=1) > 20)
    assert far.sum() > 500
    floor = style.rgb8(style.BOX_FLOOR)
    px = world_to_px(p, box, pts[far])
    bad = [tuple(pixel(f, q)) for q in px if not close(pixel(f, q), floor, 2)]
    assert not bad, bad[:5]
    # outside the box, away from the readout (top-left) and legend (bottom-right): background
    bg = style.rgb8(style.BACKGROUND)
    h, w, _ = f.shape
    assert close(f[h - 3, 2], bg, 2) and close(f[2, w - 3], bg, 2)


def test_target_rings_light_up_while_their_disk_is_inside(gl, diamond):
    p, tr = diamond
    t = p.t_final
    inside = np.linalg.norm(tr.at(t) - p.target, axis=1) <= p.target_radius
    assert 0 < inside.sum() < p.n  # straight shots: 3 of 14 end inside
    r = Renderer2D(gl, p, tr, size=SIZE)
    try:
        f = r.render(t)
    finally:
        r.release()
    box = box_from_walls(f)
    s = (box[2] - box[0]) / p.width
    amber = np.array(style.rgb8(style.CUEABLE))
    pos = tr.at(t)
    for i in range(p.n):
        # a ring pixel (mid-stroke, inside radius R) away from every disk and every other ring
        best = None
        for ang in np.linspace(0, 2 * np.pi, 72, endpoint=False):
            q = p.target[i] + (p.target_radius - 0.5 * style.RING_LIT_PX / s) * np.array([np.cos(ang), np.sin(ang)])
            if np.linalg.norm(pos - q, axis=1).min() < p.radius.max() + 6:
                continue
            others = np.abs(np.linalg.norm(p.target - q, axis=1) - p.target_radius)
            others[i] = np.inf
            if others.min() > 8 and np.linalg.norm(p.target - q, axis=1).min() > 12:
                best = q
                break
        assert best is not None
        c = pixel(f, world_to_px(p, box, best)).astype(int)
        if inside[i]:
            assert np.abs(c - amber).max() < 40, (i, c)
        else:
            assert np.abs(c - amber).max() > 100, (i, c)


def test_still_at_t0_shows_the_starts_not_the_targets(gl, diamond):
    p, tr = diamond
    r = Renderer2D(gl, p, tr, size=SIZE)
    try:
        f = r.render(0.0)
    finally:
        r.release()
    box = box_from_walls(f)
    amber = style.rgb8(style.CUEABLE)
    for c in world_to_px(p, box, p.start):
        assert close(pixel(f, c), amber, 3)
    far = np.linalg.norm(p.target[:, None] - p.start[None], axis=2).min(axis=1) > 2 * p.radius.max()
    assert far.sum() >= 5
    for c in world_to_px(p, box, p.target[far]):
        assert not close(pixel(f, c), amber, 60)


def test_time_readout_changes_with_time(gl, diamond):
    p, tr = diamond
    r = Renderer2D(gl, p, tr, size=SIZE)
    try:
        a, b = r.render(1.0).copy(), r.render(3.0).copy()
        a2 = r.render(1.0)
    finally:
        r.release()
    box = box_from_walls(a)
    x0 = int(box[0]) - 8  # the readout lives in the left margin
    top = slice(0, SIZE[1] // 3)
    text = np.array(style.rgb8(style.TEXT))
    lit_a = np.abs(a[top, :x0].astype(int) - text).max(axis=2) < 40
    assert lit_a.sum() > 30  # there is text
    assert (a[top, :x0] != b[top, :x0]).any()  # and it says something else at t = 3
    assert np.array_equal(a, a2)  # rendering is a pure function of t


def test_trails_fade_behind_a_moving_disk(gl, mk):
    p = mk([[100.0, 400.0]], radii=20.0, targets=[[700.0, 400.0]])
    tr = simulate(p, [[200.0, 0.0]])
    r = Renderer2D(gl, p, tr, size=SIZE, trails=True)
    r0 = Renderer2D(gl, p, tr, size=SIZE, trails=False)
    try:
        f, g = r.render(2.0), r0.render(2.0)
    finally:
        r.release()
        r0.release()
    box = box_from_walls(f)
    x_now = tr.at(2.0)[0, 0]
    floor = np.array(style.rgb8(style.BOX_FLOOR))
    amber = np.array(style.rgb8(style.CUEABLE))

    def sample(frame, dx):
        return pixel(frame, world_to_px(p, box, np.array([x_now - dx, 400.0]))).astype(int)

    near, far = sample(f, 40.0), sample(f, 200.0)  # 0.2 s and 1.0 s old
    assert np.abs(sample(g, 40.0) - floor).max() <= 2  # no trail without --trails
    assert np.abs(near - floor).max() > 40  # a trail behind the disk ...
    assert np.abs(near - amber).max() < np.abs(far - amber).max()  # ... fading with age
    ahead = sample(f, -60.0)
    assert np.abs(ahead - floor).max() <= 2  # and none in front of it


def test_ghost_rings_follow_the_second_motion(gl, diamond):
    p, tr = diamond
    ts = np.linspace(0, p.t_final, 51)
    shifted = SampledMotion(ts, tr.at(ts) + np.array([60.0, 0.0]))  # a deliberately wrong replay
    r = Renderer2D(gl, p, tr, size=SIZE, ghost=shifted)
    try:
        f = r.render(1.0)
    finally:
        r.release()
    box = box_from_walls(f)
    ghost = np.array(style.rgb8(style.GHOST))
    amber = style.rgb8(style.CUEABLE)
    s = (box[2] - box[0]) / p.width
    hits = 0
    pos = tr.at(1.0)
    for i, c in enumerate(world_to_px(p, box, pos)):
        on_ring = np.abs(np.linalg.norm(pos[i] - (pos + (60.0, 0.0)), axis=1) - p.radius).min() < 8
        if not on_ring:  # the exact disk is unchanged where no ghost ring crosses it
            assert close(pixel(f, c), amber, 3)
        q = world_to_px(p, box, tr.at(1.0)[i] + (60.0 + p.radius[i] - 1.0 / s, 0.0))
        hits += np.abs(pixel(f, q).astype(int) - ghost).max() < 60
    assert hits >= p.n - 3  # ring pixels at the shifted positions (a few hidden by other disks)


def test_sampled_motion_is_exact_at_samples_and_linear_between():
    ts = np.array([0.0, 1.0, 3.0])
    pos = np.array([[[0.0, 0.0]], [[10.0, 0.0]], [[10.0, 20.0]]])
    m = SampledMotion(ts, pos)
    assert np.allclose(m.at(1.0), [[10.0, 0.0]])
    assert np.allclose(m.at(2.0), [[10.0, 10.0]])
    assert np.allclose(m.at(np.array([0.5, 3.0])), [[[5.0, 0.0]], [[10.0, 20.0]]])


def test_trail_points_are_the_exact_path(diamond):
    p, tr = diamond
    pts, times = trail_points(tr, 3.0, 1.0)
    assert times[0] == pytest.approx(2.0) and times[-1] == 3.0
    assert np.all(np.diff(times) >= 0)
    assert np.allclose(pts, tr.at(times), atol=1e-9)
    # between consecutive points each disk moves in a straight line: midpoints agree
    mid = 0.5 * (times[1:] + times[:-1])
    assert np.allclose(0.5 * (pts[1:] + pts[:-1]), tr.at(mid), atol=1e-9)


def test_layout_fits_the_box_centred():
    L = Layout((800.0, 400.0), (1280, 720))
    x0, y0, x1, y1 = L.box_rect
    assert x0 > 0 and y0 > 0 and x1 < 1280 and y1 < 720
    assert (x1 - x0) / (y1 - y0) == pytest.approx(2.0)
    assert (x0 + x1) / 2 == pytest.approx(640) and (y0 + y1) / 2 == pytest.approx(360)
    assert np.allclose(L.to_image([[0.0, 400.0], [800.0, 0.0]]), [[x0, y0], [x1, y1]])


def test_tiny_disks_stay_visible(gl):
    p = load_problem("diamond-s14-tiny")
    tr = simulate(p, p.straight_velocities())
    r = Renderer2D(gl, p, tr, size=SIZE)
    try:
        f = r.render(0.0)
    finally:
        r.release()
    box = box_from_walls(f)
    amber = style.rgb8(style.CUEABLE)
    assert all(close(pixel(f, c), amber, 3) for c in world_to_px(p, box, p.start))


# --------------------------------------------------------------------------- 3D frames

def test_3d_pucks_sit_where_simulated(gl):
    from nbst.render.scene3d import Renderer3D
    p, tr = over5_motion()
    r = Renderer3D(gl, p, tr, size=SIZE)
    try:
        for t in (0.0, 3.0):
            f = r.render(t)
            assert f.shape == (SIZE[1], SIZE[0], 3)
            tops = r.to_pixels(tr.at(t))  # projected centres of the pucks' top faces
            for i, c in enumerate(tops):
                px = pixel(f, c).astype(int)
                if p.cueable[i]:  # amber: red > green > blue
                    assert px[0] > px[1] > px[2] and px[0] > 120, (i, t, px)
                else:  # blue: blue > red
                    assert px[2] > px[0] + 40, (i, t, px)
    finally:
        r.release()


@pytest.mark.parametrize("view", ["2d", "3d"])
def test_trails_fade_smoothly_through_keyframes(gl, mk, view):
    """Keyframes are global (every event of any disk), so a straight trail is made of
    many segments; its colour must still fall steadily with age, with no seams at
    the joints (3D once had dark seams where a segment's depth hid its neighbour)."""
    from nbst.render.scene3d import Renderer3D
    p = mk([[100.0, 400.0], [700.0, 100.0], [760.0, 700.0]], radii=10.0)
    tr = simulate(p, [[200.0, 0.0], [0.0, 4100.0], [0.0, -3300.0]])  # two fast bouncers: many keyframes
    t = 2.0
    lo, hi = np.searchsorted(tr.times, [t - style.TRAIL_SECONDS, t])
    assert hi - lo >= 10  # the trail window holds many joints
    R = Renderer3D if view == "3d" else Renderer2D
    r = R(gl, p, tr, size=SIZE, trails=True)
    try:
        f = r.render(t).astype(int)
        x_now = tr.at(t)[0, 0]
        xs = np.linspace(x_now - 16.0, x_now - 200.0 * (style.TRAIL_SECONDS - 0.1), 80)  # ages 0.08 .. 1.1 s
        pts = np.stack([xs, np.full_like(xs, 400.0)], axis=1)
        px = r.to_pixels(pts, z=1.05) if view == "3d" else r.to_pixels(pts)
    finally:
        r.release()
    red = np.array([f[int(q[1]), int(q[0]), 0] for q in px])
    assert red[0] > red[-1] + 40  # it fades ...
    assert np.all(np.diff(red) <= 3), red  # ... steadily: no dip or bead at any joint


def test_labels_write_dark_digits_on_the_disks_only_when_asked(gl, diamond):
    p, tr = diamond
    size = (800, 600)  # disks ~13 px in radius: room for two digits
    frames = {}
    for labels in (False, True):
        r = Renderer2D(gl, p, tr, size=size, labels=labels)
        try:
            frames[labels] = r.render(1.0).astype(int)
        finally:
            r.release()
    f = frames[True]
    box = box_from_walls(f)
    s = (box[2] - box[0]) / p.width
    label = np.array(style.rgb8(style.LABEL))
    for i, c in enumerate(world_to_px(p, box, tr.at(1.0))):
        k = int(0.6 * p.radius[i] * s)
        win = lambda fr: fr[int(c[1]) - k:int(c[1]) + k, int(c[0]) - k:int(c[0]) + k]  # noqa: E731
        dark = lambda fr: (np.abs(win(fr) - label).max(axis=2) < 60).sum()  # noqa: E731
        assert dark(f) >= 4, i  # digits inside the disk
        assert dark(frames[False]) == 0  # none without --labels


@pytest.mark.parametrize("view", ["2d", "3d"])
def test_rgba_frames_are_the_rgb_frames_plus_opaque_alpha(gl, diamond, view):
    """Videos read frames as RGBA (the cheap readback): the same pixels, alpha 255."""
    from nbst.render.scene3d import Renderer3D
    p, tr = diamond
    R = Renderer3D if view == "3d" else Renderer2D
    r = R(gl, p, tr, size=(320, 240), trails=True)
    try:
        rgb = r.render(2.2).copy()
        rgba = r.render_rgba(2.2).copy()
    finally:
        r.release()
    assert rgba.shape == (240, 320, 4)
    assert np.array_equal(rgba[..., :3], rgb)
    assert (rgba[..., 3] == 255).all()


# --------------------------------------------------------------------------- one visual language

def test_video_class_colours_are_the_shared_palette(gl):
    """The video's disk colours are nbst.palette's (the figures, report and MuJoCo scenes
    import the same constants): each disk's centre pixel is rgb8 of its class colour."""
    from nbst import palette
    assert style.CUEABLE == palette.CUEABLE and style.NONCUEABLE == palette.NONCUEABLE
    p, tr = over5_motion()
    r = Renderer2D(gl, p, tr, size=SIZE)
    try:
        f = r.render(0.0)
    finally:
        r.release()
    box = box_from_walls(f)
    for i, c in enumerate(world_to_px(p, box, p.start)):
        assert close(pixel(f, c), style.rgb8(palette.class_color(p.cueable[i])), 3), i


def _number_box(centre, marker_px, cell):
    """Rows and columns (slices) where a target's number is written: just above and
    right of its marker, two digits wide."""
    cw, ch = cell
    x0, y1 = int(centre[0] + 0.75 * marker_px), int(np.ceil(centre[1] - 0.75 * marker_px + 0.3 * ch))
    return slice(max(0, y1 - int(1.3 * ch) - 2), y1 + 2), slice(x0 - 1, x0 + int(2.5 * cw) + 3)  # 1 px halo


def test_labels_number_each_target_with_its_disk(gl, mk):
    """With --labels every target carries its disk's number beside its marker; what
    --labels changes lies beside the targets and on the disks, nowhere else. Disks
    start far from every target, so no disk covers a number."""
    starts = [[100.0 + 150 * k, 700.0] for k in range(5)] + [[100.0 + 150 * k, 560.0] for k in range(5)] \
        + [[100.0, 420.0], [250.0, 420.0]]
    targets = [[100.0 + 130 * (k % 6), 80.0 + 120 * (k // 6)] for k in range(12)]
    p = mk(starts, radii=15.0, targets=targets)
    tr = simulate(p, np.zeros((p.n, 2)))
    frames = {}
    for labels in (False, True):
        r = Renderer2D(gl, p, tr, size=(800, 800), labels=labels)
        try:
            frames[labels] = r.render(0.0)
            if labels:
                centres, marker_px, cell = r.target_px.copy(), r.marker_px.copy(), r.target_text.cell
                disks = r.to_pixels(p.start), r.rpx.copy()
        finally:
            r.release()
    changed = (frames[True] != frames[False]).any(axis=2)
    expected = np.zeros_like(changed)
    for i in range(p.n):
        rows, cols = _number_box(centres[i], marker_px[i], cell)
        assert changed[rows, cols].sum() >= 4, i  # a number beside every target
        expected[rows, cols] = True
    yy, xx = np.mgrid[:changed.shape[0], :changed.shape[1]]
    for c, rad in zip(*disks):
        expected |= (xx + 0.5 - c[0]) ** 2 + (yy + 0.5 - c[1]) ** 2 <= (rad + 1) ** 2  # the disks' own numbers
    for c, m in zip(centres, marker_px):  # markers widened to ring a number written on its disk
        expected |= (xx + 0.5 - c[0]) ** 2 + (yy + 0.5 - c[1]) ** 2 <= (m + style.MARKER_HALO_PX + 2) ** 2
    assert changed.any() and not (changed & ~expected).any()
    # the numbers are the disk indices: one glyph per digit, "10" and "11" two each
    from nbst.render.scene2d import target_label_instances
    from nbst.render.core.shapes import FIRST_CHAR, Text
    t = Text(gl, 12)
    try:
        inst = target_label_instances(t, centres, marker_px)
    finally:
        t.release()
    assert "".join(chr(int(g) + FIRST_CHAR) for g in inst["glyph"]) == "".join(str(i) for i in range(p.n))


@pytest.mark.parametrize("view", ["2d", "3d"])
def test_legend_under_the_readout_shows_the_classes_present(gl, view):
    """1280x720 leaves room left of the box: the legend's swatches there are filled
    with the palette's class colours, a noncueable swatch only where the problem has
    noncueable disks; the legend stays out of the box."""
    from nbst import palette
    from nbst.render.scene3d import Renderer3D
    R = Renderer3D if view == "3d" else Renderer2D
    seen = {}
    for name in ("diamond-s14", "over5"):
        p = load_problem(name)
        tr = simulate(p, np.zeros((p.n, 2)))
        r = R(gl, p, tr, size=(1280, 720), labels=True)
        try:
            f = r.render(0.0).astype(int)
        finally:
            r.release()
        region = f[90:300, :260]  # under the readout, left of the box (2D: 306 px margin; 3D: the far rail at ~360)
        seen[name] = {c: int((np.abs(region - np.array(style.rgb8(col))).max(axis=2) <= 3).sum())
                      for c, col in (("cue", palette.CUEABLE), ("non", palette.NONCUEABLE))}
    assert seen["diamond-s14"]["cue"] > 20 and seen["diamond-s14"]["non"] == 0
    assert seen["over5"]["cue"] > 20 and seen["over5"]["non"] > 20


@pytest.mark.parametrize("size", [(360, 360), (480, 360), (320, 480)])
def test_legend_stays_out_of_the_box(gl, diamond, size):
    """Wherever the frame has no room for a legend beside, below or above the box there is
    none, and a legend that is drawn never reaches into the box."""
    p, tr = diamond
    r = Renderer2D(gl, p, tr, size=size)
    try:
        f = r.render(0.0)
        drawn = r.legend_drawn
    finally:
        r.release()
    box = box_from_walls(f)
    outside = f.astype(int)
    outside[int(box[1]) - 8:int(box[3]) + 8, int(box[0]) - 8:int(box[2]) + 8] = 0  # around the box: readout, legend
    swatch = (np.abs(outside - np.array(style.rgb8(style.CUEABLE))).max(axis=2) <= 3).sum()
    assert (swatch > 0) == drawn
    # inside the box, above the disks' starts, the legend's words (TEXT_DIM) never appear
    inner = f[int(box[1]) + 2:int(box[3]) - 2, int(box[0]) + 2:int(box[2]) - 2].astype(int)
    assert (np.abs(inner - np.array(style.rgb8(style.TEXT_DIM))).max(axis=2) <= 2).sum() < 5


@pytest.mark.parametrize("size", [(800, 600), (640, 480), (1280, 720)])
def test_readout_keeps_clear_of_the_box(gl, diamond, size):
    """At 4:3 as at 16:9, no readout pixel comes within a few px of the box's wall."""
    p, tr = diamond
    r = Renderer2D(gl, p, tr, size=size)
    try:
        img = r.render(2.5).copy()
        x_wall = int(r.layout.box_rect[0] - r.layout.wall)
    finally:
        r.release()
    text = np.array(style.rgb8(style.TEXT))
    lit = np.abs(img[: size[1] // 4].astype(int) - text).max(axis=2) < 60
    cols = np.flatnonzero(lit[:, :x_wall].any(axis=0))
    assert cols.size > 0 and cols.max() < x_wall - 3


# --------------------------------------------------------------------------- pictures that explain themselves

def _marker_ring_pixels(r, i, n=24):
    """Pixels on target i's marker ring (mid-stroke), as (row, col) ints."""
    c, m = r.target_px[i], r.marker_px[i] - 0.5 * style.MARKER_PX
    ang = np.linspace(0, 2 * np.pi, n, endpoint=False)
    pts = c + m * np.stack([np.cos(ang), np.sin(ang)], axis=1)
    return np.floor(pts[:, ::-1]).astype(int)


@pytest.mark.parametrize("labels", [False, True])
def test_targets_are_never_hidden_under_disks(gl, mk, labels):
    """A disk resting on its own target (t = 0 and t_final) and a disk parked over another
    disk's target: every target marker still shows its colour (drawn above the disks), and
    with --labels every target's number is drawn at both times."""
    # disk 0 rests on its target; disk 1 rests on disk 2's target; disk 2 rests far away
    p = mk([[400.0, 400.0], [200.0, 200.0], [650.0, 650.0]], radii=20.0,
           targets=[[400.0, 400.0], [600.0, 200.0], [200.0, 200.0]])
    tr = simulate(p, np.zeros((p.n, 2)))
    r = Renderer2D(gl, p, tr, size=(800, 800), labels=labels)
    try:
        marker = np.array(style.rgb8(style.MARKER))
        for t in (0.0, p.t_final):
            f = r.render(t).astype(int)
            for i in (0, 2):  # the covered targets
                px = np.array([f[a, b] for a, b in _marker_ring_pixels(r, i)])
                near = (np.abs(px - marker).max(axis=1) < 60).mean()
                assert near > 0.5, (t, i, near)  # most of the ring shows the marker's colour
                amber_blue = style.rgb8(style.CUEABLE)[2]
                assert px[:, 2].mean() > amber_blue + 80  # not the disk's fill under it
    finally:
        r.release()


def test_readout_states_each_count_on_one_line(gl, diamond):
    """One fact a line: the "on target" words and their count share a line, and with a
    second motion (--source both) a second line counts the rings, with that motion's own
    count; every line fits left of the box."""
    import re
    p, tr = diamond
    ts = np.linspace(0, p.t_final, 51)
    ghost = SampledMotion(ts, np.broadcast_to(p.target, (len(ts), p.n, 2)))  # a "replay" sitting on the targets
    for g in (None, ghost):
        r = Renderer2D(gl, p, tr, size=(1280, 720), ghost=g)
        try:
            pos = tr.at(p.t_final)
            inside = r.inside(pos)
            lines = r.readout(p.t_final, inside, r.inside(p.target) if g is not None else None)
            width = max(len(s) for s in lines) * r.text.cell[0]
            room = r.layout.box_rect[0] - r.layout.wall - r._readout_origin()[0]
            text_px = r.text.cell[1]
        finally:
            r.release()
        counts = [ln for ln in lines if "on target" in ln]
        assert all(re.search(r"on target +\d+/\d+$", ln) for ln in counts), lines
        assert not any(re.fullmatch(r"\s*\d+/\d+", ln) for ln in lines), lines  # no count alone on a line
        assert width < room and text_px >= style.MIN_READOUT_PX
        if g is None:
            assert len(counts) == 1 and counts[0].endswith(f"{int(inside.sum())}/{p.n}")
        else:
            assert len(counts) == 2
            assert counts[0].startswith("exact") and counts[0].endswith(f"{int(inside.sum())}/{p.n}")
            assert counts[1].startswith("MuJoCo") and counts[1].endswith(f"{p.n}/{p.n}")


@pytest.mark.parametrize("size", [(1280, 720), (640, 480), (480, 360)])
def test_readout_never_shrinks_below_legible(gl, size):
    """Where the margin is narrow the box makes room: the readout keeps MIN_READOUT_PX and
    still ends left of the box."""
    p = load_problem("over5")
    tr = simulate(p, np.zeros((p.n, 2)))
    ts = np.linspace(0, p.t_final, 11)
    r = Renderer2D(gl, p, tr, size=size, ghost=SampledMotion(ts, tr.at(ts)))
    try:
        f = r.render(p.t_final).copy()
        x_wall = int(r.layout.box_rect[0] - r.layout.wall)
        px = r.text.cell[1]
    finally:
        r.release()
    assert px >= style.MIN_READOUT_PX
    text = np.array(style.rgb8(style.TEXT))
    lit = np.abs(f[: size[1] // 3].astype(int) - text).max(axis=2) < 60
    cols = np.flatnonzero(lit[:, :x_wall].any(axis=0))
    assert cols.size and cols.max() < x_wall - 3


@pytest.mark.parametrize("size", [(1280, 720), (480, 360)])
def test_disk_numbers_are_legible_at_every_disk_size(gl, size):
    """over5's radius-10 disks are ~8 px on screen at 720p: their numbers are still at least
    9 px tall (a digit's ink; "0" read as "8" at 6 px), on the disk where they fit and beside
    it where they do not; the dark digits on a disk are really there, that tall."""
    from nbst.render.core.shapes import digit_height
    p = load_problem("over5")
    tr = simulate(p, np.zeros((p.n, 2)))
    r = Renderer2D(gl, p, tr, size=size, labels=True)
    r0 = Renderer2D(gl, p, tr, size=size, labels=False)
    try:
        f, g = r.render(0.0).astype(int), r0.render(0.0).astype(int)
        lab = r.labels
        centres = r.to_pixels(p.start)
    finally:
        r.release()
        r0.release()
    assert lab.px >= style.MIN_LABEL_PX and digit_height(lab.px) >= 9
    label = np.array(style.rgb8(style.LABEL))
    for i, c in enumerate(centres):
        if not lab.on_disk[i]:
            # beside the disk: new pixels in the disk's colour above-left of it, at least 9 rows tall
            k = int(lab.rpx[i] + 2 * lab.text.cell[1])
            win = (slice(max(0, int(c[1]) - k), int(c[1])), slice(max(0, int(c[0]) - k), int(c[0])))
            col = np.array(style.rgb8(style.disk_colors(p.cueable)[i]))
            # glyph pixels: new with --labels, nearer the disk's colour than the background is
            hit = (np.abs(f[win] - g[win]).max(axis=2) > 30) & \
                (np.abs(f[win] - col).sum(axis=2) < np.abs(g[win] - col).sum(axis=2) - 60)
        else:
            k = int(lab.rpx[i])
            win = (slice(int(c[1]) - k, int(c[1]) + k + 1), slice(int(c[0]) - k, int(c[0]) + k + 1))
            hit = np.abs(f[win] - label).max(axis=2) < 90
        rows = np.flatnonzero(hit.any(axis=1))
        assert rows.size and rows.max() - rows.min() + 1 >= 9, (i, lab.on_disk[i], rows)


def test_ghost_rings_carry_their_disk_numbers_and_a_legend(gl):
    """--source both --labels: each MuJoCo ring has its disk's number beside it (white), and
    the legend names the rings."""
    from nbst.render.scene2d import ghost_label_instances, legend_entries
    from nbst.render.core.shapes import FIRST_CHAR
    p = load_problem("over5")
    tr = simulate(p, np.zeros((p.n, 2)))
    ts = np.linspace(0, p.t_final, 11)
    shifted = SampledMotion(ts, tr.at(ts) + np.array([0.0, -120.0]))
    words = [e[0] for e in legend_entries(p, ghost=True, labels=True)]
    assert any("MuJoCo" in w and "ring" in w for w in words) and any("within R" in w for w in words)
    frames = {}
    for labels in (False, True):
        r = Renderer2D(gl, p, tr, size=(1280, 720), labels=labels, ghost=shifted)
        try:
            frames[labels] = r.render(1.0).astype(int)
            if labels:
                inst = ghost_label_instances(r.target_text, r.to_pixels(shifted.at(1.0)), r.rpx)
                cell = r.target_text.cell
        finally:
            r.release()
    assert "".join(chr(int(gl_) + FIRST_CHAR) for gl_ in inst["glyph"]) == "".join(str(i) for i in range(p.n))
    white = np.array(style.rgb8(style.GHOST_LABEL))
    for i, (x, y) in enumerate(inst["pos"]):
        win = (slice(int(y), int(y) + cell[1]), slice(int(x), int(x) + cell[0]))
        new = (np.abs(frames[True][win] - white).max(axis=2) < 40) & \
            (np.abs(frames[False][win] - white).max(axis=2) >= 40)
        assert new.sum() >= 5, i


@pytest.mark.parametrize("case", ["over5", "diamond"])
def test_trajectory_figure_stars_never_cover_a_start_number(case):
    """`nbst plot trajectories`: a disk-disk collision at (or by) a disk's start would hide
    the number on it under its red star; the number then moves beside the disk. No star's
    box overlaps any start number's box."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.text import Text

    from nbst import palette
    from nbst.render.figures import STAR_MS, plot_trajectories
    if case == "over5":
        p, tr = over5_motion()  # disk 0 strikes disk 2 right beside their starts
    else:
        p = load_problem("diamond-s14")
        tr = simulate(p, p.straight_velocities())
    assert tr.n_disk_disk >= 1
    fig = plot_trajectories(p, tr)
    FigureCanvasAgg(fig).draw()
    r = fig.canvas.get_renderer()
    ax = fig.axes[0]
    stars = [ln for ln in ax.get_lines() if ln.get_marker() == palette.COLLISION_MARKER]
    assert len(stars) == 1
    pts = ax.transData.transform(np.stack([stars[0].get_xdata(), stars[0].get_ydata()], axis=1))
    half = 0.5 * STAR_MS * fig.dpi / 72.0
    numbers = [t for t in ax.texts if t.get_text() in {str(i) for i in range(p.n)}]
    starts = ax.transData.transform(p.start)
    near_start = []
    for t in numbers:  # the start numbers: anchored at a disk's start
        xy = t.xy if hasattr(t, "xy") else t.get_position()
        if np.isclose(ax.transData.transform(xy), starts).all(axis=1).any():
            near_start.append(Text.get_window_extent(t, r))
    assert len(near_start) == p.n
    for b in near_start:
        for c in pts:
            assert not (b.x0 < c[0] + half and c[0] - half < b.x1 and b.y0 < c[1] + half and c[1] - half < b.y1), \
                (b, c)


def _ablation_rows(entries):
    rows = []
    for k, e in enumerate(entries):
        m = 10.0 ** (2 + (k * 7 % 5) * 0.6)
        rows.append(dict(entry=e, mean=m, best=m / 3, worst=m * 2, full_order=k % 6, runs=5))
    return rows


def test_ablation_figure_labels_apart_and_nbst_family_colours():
    """`nbst experiment ablation` with every entry: no two x labels overlap; nbst-noplan is
    drawn in nbst's family (a green, hatched), not in the paper variants' blue; a legend names
    the families; the families stay apart in a deuteranope's view."""
    from cvd import delta_e, deuteranopia
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.colors import to_rgb

    from nbst.experiments import plots as P
    from nbst.experiments.runs import entries
    ENTRIES = entries()
    assert "nbst-noplan" in ENTRIES
    fig = P.plot_ablation(_ablation_rows(ENTRIES), title="t")
    FigureCanvasAgg(fig).draw()
    r = fig.canvas.get_renderer()
    ax = fig.axes[0]
    boxes = [t.get_window_extent(r) for minor in (False, True) for t in ax.get_xticklabels(minor=minor)
             if t.get_text()]
    assert len(boxes) == len(ENTRIES)
    assert not any(a.overlaps(b) for k, a in enumerate(boxes) for b in boxes[k + 1:])
    bars = {e: b for e, b in zip(ENTRIES, ax.patches)}
    green, blue = to_rgb(P.COLORS["nbst"]), to_rgb(P.COLORS["variant"])
    noplan = bars["nbst-noplan"]
    assert to_rgb(bars["nbst"].get_facecolor()) == pytest.approx(green)
    assert noplan.get_hatch() and to_rgb(noplan.get_edgecolor()) == pytest.approx(green)
    face = np.array(to_rgb(noplan.get_facecolor()))
    assert face[1] > face[0] and face[1] > face[2]  # a green
    assert delta_e(face, blue) > 30 and delta_e(face, to_rgb(bars["A"].get_facecolor())) > 30
    words = [t.get_text() for t in ax.get_legend().get_texts()]
    assert len(words) == 4 and any("planner" in w for w in words)
    cols = [deuteranopia(to_rgb(c)) for c in (P.COLORS["variant"], P.COLORS["nbst"], P.COLORS["baseline"])]
    assert min(delta_e(a, b) for k, a in enumerate(cols) for b in cols[k + 1:]) > 30


def test_curves_figure_colours_entries_by_family():
    """`nbst experiment curves`: an entry has its family's colour there as in the ablation
    (nbst green, the paper's A-H blue, baselines orange); entries of one family differ in
    line style."""
    from matplotlib.colors import to_rgb

    from nbst.experiments import plots as P
    rows = [dict(entry=e, run=k, trial=t, best_cost=c) for e in ("A", "B", "nbst", "nbst-noplan", "cma", "de")
            for k in range(2) for t, c in ((1, 1e5), (1000, 1e3))]
    fig = P.plot_curves(rows, title="t")
    lines = {ln.get_label().split(" (")[0]: ln for ln in fig.axes[0].get_lines() if not ln.get_label().startswith("_")}
    assert to_rgb(lines["nbst"].get_color()) == pytest.approx(to_rgb(P.COLORS["nbst"]))
    assert to_rgb(lines["A"].get_color()) == pytest.approx(to_rgb(P.COLORS["variant"]))
    assert to_rgb(lines["cma"].get_color()) == pytest.approx(to_rgb(P.COLORS["baseline"]))
    g = np.array(to_rgb(lines["nbst-noplan"].get_color()))
    assert g[1] > g[0] and g[1] > g[2]  # a green
    for a, b in (("A", "B"), ("nbst", "nbst-noplan"), ("cma", "de")):
        assert lines[a].get_linestyle() != lines[b].get_linestyle()


def test_3d_target_markers_show_over_the_pucks(gl, mk):
    """The 3D view draws target markers over everything too: a puck resting on its target
    (t = 0 and t_final) leaves the marker's ring in the marker's colour."""
    from nbst.render.scene3d import Renderer3D
    p = mk([[400.0, 400.0], [200.0, 200.0]], radii=20.0, targets=[[400.0, 400.0], [600.0, 600.0]])
    tr = simulate(p, np.zeros((p.n, 2)))
    r = Renderer3D(gl, p, tr, size=(800, 600), labels=True)
    try:
        marker = np.array(style.rgb8(style.MARKER))
        c, m = r._target_centre_px[0], r._target_marker_px[0] - 0.5 * style.MARKER_PX
        ang = np.linspace(0, 2 * np.pi, 24, endpoint=False)
        ring = np.floor((c + m * np.stack([np.cos(ang), np.sin(ang)], axis=1))[:, ::-1]).astype(int)
        for t in (0.0, p.t_final):
            f = r.render(t).astype(int)
            px = np.array([f[a, b] for a, b in ring])
            assert (np.abs(px - marker).max(axis=1) < 70).mean() > 0.5, t
    finally:
        r.release()


# ------------------------------------------------------------------ many disks (issue 21)


def grid_problem(n: int):
    """``benchmarks/bench_render.py``'s many-disk problem: ``n`` radius-1 disks on a jittered
    grid at 8 % density, random velocities, targets where the motion ends (an exact solution)."""
    import importlib.util
    from pathlib import Path

    path = Path(__file__).resolve().parents[1] / "benchmarks" / "bench_render.py"
    spec = importlib.util.spec_from_file_location("bench_render", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.grid_problem(n)


@pytest.fixture(scope="module")
def thousand():
    p, v, tr = grid_problem(1000)
    assert tr.n_disk_disk > 500 and tr.n_wall > 50  # collisions and bounces to draw
    return p, tr


def test_a_thousand_disks_are_each_drawn_once_where_simulated(gl, thousand):
    """All 1,000 instances are drawn: at t = 0 (starts at least 7 px apart at 720p) the
    frame holds exactly 1,000 separate blobs of the disk fill colour inside the box, one
    within 1.5 px of each simulated centre (the scale recovered from the walls); their fill
    area is N x pi (r_px - rim - 0.5)^2 within 10 % (a pixel is counted when it is the fill
    colour within 3 levels: the anti-aliased edge is half a pixel)."""
    from scipy import ndimage
    from scipy.spatial import cKDTree

    p, tr = thousand
    r = Renderer2D(gl, p, tr, size=(1280, 720), labels=None)
    try:
        f = r.render(0.0).astype(int)
    finally:
        r.release()
    x0, y0, x1, y1 = box_from_walls(f)
    fill = np.zeros(f.shape[:2], bool)
    inner = np.abs(f - style.rgb8(style.CUEABLE)).max(axis=2) <= 3
    fill[int(y0):int(y1), int(x0):int(x1)] = inner[int(y0):int(y1), int(x0):int(x1)]
    lab, k = ndimage.label(fill)
    assert k == p.n
    cents = np.array(ndimage.center_of_mass(fill, lab, range(1, k + 1)))[:, ::-1] + 0.5  # (x, y) px
    dist, idx = cKDTree(cents).query(world_to_px(p, (x0, y0, x1, y1), tr.at(0.0)))
    assert dist.max() <= 1.5 and len(set(idx)) == p.n
    rpx = p.radius[0] * (x1 - x0) / p.width
    core = rpx - max(1.0, style.DISK_RIM_FRAC * rpx) - 0.5
    assert abs(fill.sum() / (p.n * np.pi * core ** 2) - 1.0) <= 0.10


def test_disk_numbers_default_to_where_they_are_legible(gl, thousand, diamond):
    """Without --labels/--no-labels the disks are numbered only when every disk is at least
    LABELS_MIN_DISK_PX across: not 1,000 disks at 720p (8 px), but diamond-s14's 14. The
    default frame is pixel for pixel the frame of that choice, and differs from the other."""
    from nbst.render.scene2d import auto_labels

    for (p, tr), on in ((thousand, False), (diamond, True)):
        assert auto_labels(p, (1280, 720)) is on
        frames = {}
        for labels in (None, False, True):
            r = Renderer2D(gl, p, tr, size=(1280, 720), labels=labels)
            try:
                if labels is None:
                    assert bool(2 * r.rpx.min() >= style.LABELS_MIN_DISK_PX) is on
                frames[labels] = r.render(0.5 * p.t_final).copy()
            finally:
                r.release()
        assert np.array_equal(frames[None], frames[on])
        assert not np.array_equal(frames[None], frames[not on])


def test_a_thousand_disk_frame_explains_itself(gl, thousand):
    """At N = 1,000 the frame still says what it shows: the readout (name, time, the count
    on target, every disk at t_final), the legend beside the box, and every target visible
    as a grey ring around its disk when the disk rests on it (the disk hides none of it)."""
    p, tr = thousand
    r = Renderer2D(gl, p, tr, size=(1280, 720))
    try:
        f = r.render(p.t_final).astype(int)
        assert r.readout(p.t_final, r.inside(tr.at(p.t_final))) == [p.name, "t =  5.00 s", "on target 1000/1000"]
        assert r.legend_drawn
        assert r.marker_outside.all() and (r.marker_px > r.rpx + 1).all()
        marker = np.array(style.rgb8(style.MARKER))
        ang = np.linspace(0, 2 * np.pi, 12, endpoint=False)
        seen = []
        for c, m in zip(r.target_px, r.marker_px):
            pts = c + (m - 0.5 * style.MARKER_OUTSIDE_PX) * np.stack([np.cos(ang), np.sin(ang)], 1)
            px = np.array([f[int(y), int(x)] for x, y in pts])
            seen.append((np.abs(px - marker).max(axis=1) < 70).mean())
        seen = np.array(seen)
        assert np.median(seen) >= 0.5 and (seen > 0).all(), np.sort(seen)[:10]  # neighbours may cross a ring
    finally:
        r.release()


def test_trails_are_exact_segments_between_each_disks_own_events(thousand):
    """A trail is each disk's path through its own events only: every segment starts and
    ends on the exact motion, its midpoint lies on it too (straight flight between a disk's
    events), and there are N + (disk appearances in events inside the window) segments at
    most, not N x (all events)."""
    from nbst.render.motion2d import trail_segments

    p, tr = thousand
    t, w = 2.5, style.TRAIL_SECONDS
    a, b, ta, tb, disk = trail_segments(tr, t, w)
    for pts, ts in ((a, ta), (b, tb), (0.5 * (a + b), 0.5 * (ta + tb))):
        exact = np.array([tr.at(x)[i] for x, i in zip(ts, disk)])
        assert np.abs(pts - exact).max() <= 1e-9 * max(p.box)
    ev = tr.events[(tr.events["time"] > t - w) & (tr.events["time"] < t)]
    appearances = len(ev) + int((ev["kind"] == 0).sum())
    assert p.n <= len(disk) <= p.n + appearances
    assert np.all(np.bincount(disk, minlength=p.n) >= 1)


def test_glyph_runs_lay_out_as_text_layout_does(gl):
    """The one-gather layout of many numbers gives the same glyph instances as laying out
    each number on its own; the halo atlas is the union of the glyph shifted by 1 px."""
    from nbst.render.core.shapes import Text

    t = Text(gl, 12)
    try:
        rng = np.random.default_rng(0)
        n = 120
        x, y = rng.uniform(0, 500, n), rng.uniform(0, 300, n)
        runs = t.numbers(n)
        which = rng.random(n) < 0.5
        fast = runs.layout(x, y, which)
        slow = np.concatenate([t.layout([str(i)], x[i], y[i]) for i in range(n) if which[i]])
        assert fast.tobytes() == slow.tobytes()
        t._make_halo(1)
        cw, ch = t.cell
        glyph = ord("8") - 32
        gr, gc = divmod(glyph, 16)
        cell = t._atlas[gr * ch:(gr + 1) * ch, gc * cw:(gc + 1) * cw].astype(int)
        union = np.zeros((ch + 2, cw + 2), int)
        for dy in (0, 1, 2):
            for dx in (0, 1, 2):
                union[dy:dy + ch, dx:dx + cw] = np.maximum(union[dy:dy + ch, dx:dx + cw], cell)
        halo = np.frombuffer(t._halo[1].read(), np.uint8).reshape(t._halo[1].height, t._halo[1].width)
        assert np.array_equal(halo[gr * (ch + 2):(gr + 1) * (ch + 2), gc * (cw + 2):(gc + 1) * (cw + 2)], union)
    finally:
        t.release()


def test_figures_of_many_disks_leave_the_numbers_out_and_say_so():
    """Over NUMBERS_MAX_DISKS disks the figures write no disk or target numbers (at 150 disks
    they would cover the figure), the legend says why, and the title counts the signature's
    order from its bits (every disk ends on target in this exact solution)."""
    from nbst.render import figures

    p, v, tr = grid_problem(150)
    for fig in (figures.plot_problem(p), figures.plot_trajectories(p, tr)):
        ax = fig.axes[0]
        digits = [t.get_text() for t in ax.texts if t.get_text().isdigit()]
        assert digits == []
        words = [t.get_text() for t in fig.legends[0].get_texts()]
        assert any("no numbers over 100 disks" in w for w in words), words
    assert ax.get_title().endswith("order 150/150")


def test_crowded_numbers_never_run_together(gl):
    """200 disks forming a text (issue 35: the numbers ran together, "113115116"): at every
    moment no drawn number, a disk's or a target's, covers another; the lower numbers are kept."""
    from nbst.formation import formation
    from nbst.render.scene2d import keep_apart, target_label_boxes

    p, v, _ = formation("nbst", 200, seed=1)
    tr = simulate(p, v)
    r = Renderer2D(gl, p, tr, size=(1280, 720), labels=True)
    try:
        ch = r.target_text.cell[1]
        w = r.target_text.numbers(p.n).width
        for t in np.linspace(0.0, p.t_final, 6):
            centers = r.layout.to_image(tr.at(t))
            drawn = r.labels.drawn(centers)
            disks = r.labels.boxes(centers, drawn)
            x, y, keep = target_label_boxes(r.target_text, r.target_px, r.marker_px, avoid=disks)
            boxes = np.concatenate([disks, np.stack([x, y, x + w, y + ch], axis=1)[keep]])
            assert keep_apart(boxes, gap=0.0).all(), t  # no drawn box overlaps an earlier one
            assert drawn.sum() + keep.sum() >= p.n  # most numbers are still written
    finally:
        r.release()
    boxes = np.array([[0, 0, 10, 10], [5, 5, 15, 15], [20, 0, 30, 10], [0, 0, 2, 2]], float)
    assert keep_apart(boxes).tolist() == [True, False, True, False]
    assert keep_apart(boxes, taken=[[0, 0, 3, 3]]).tolist() == [False, True, True, False]


def test_a_character_the_font_lacks_is_drawn_as_a_mark_not_a_gap(gl):
    """A demanding user's body named 球 vanished from the scene readout (DejaVu Sans Mono has no CJK):
    such a character lays out as '?' in its cell; spaces and Latin-1 letters as before."""
    from nbst.render.core.shapes import FIRST_CHAR, Text, glyph_index

    t = Text(gl, 12)
    try:
        inst = t.layout(["球 ü-x"], 0, 0)
    finally:
        t.release()
    cw = t.cell[0]
    assert [int(g) for g in inst["glyph"]] == [ord("?") - FIRST_CHAR, glyph_index("ü"), ord("-") - FIRST_CHAR,
                                                ord("x") - FIRST_CHAR]
    assert [int(p[0]) for p in inst["pos"]] == [0, 2 * cw, 3 * cw, 4 * cw]
