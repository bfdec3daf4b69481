"""``nbst render`` and ``nbst plot`` end to end, and the video writer.

Videos are decoded back with imageio-ffmpeg: frame count, size, fps and what
a decoded frame shows. Small sizes and low fps keep this fast.
"""
import subprocess
import sys

import numpy as np
import pytest

from nbst import load_problem, simulate
from nbst.cli import main
from nbst.render.core import style
from nbst.render.core.times import frame_times
from nbst.render.core.video import VideoWriter
from nbst.solution import make_solution, save_solution


@pytest.fixture(scope="module")
def straight(tmp_path_factory):
    p = load_problem("diamond-s14")
    path = tmp_path_factory.mktemp("sol") / "straight.json"
    save_solution(path, make_solution(p, p.straight_velocities()))
    return p, str(path)


def decode(path):
    import imageio_ffmpeg
    gen = imageio_ffmpeg.read_frames(str(path))
    meta = next(gen)
    w, h = meta["size"]
    frames = [np.frombuffer(f, np.uint8).reshape(h, w, 3) for f in gen]
    return meta, frames


def test_frame_times_cover_zero_to_t_final_inclusive():
    t = frame_times(5.0, 60)
    assert len(t) == 301 and t[0] == 0.0 and t[-1] == 5.0
    assert np.allclose(np.diff(t), 1 / 60)
    t = frame_times(5.0, 30, speed=0.5, hold=1.0)
    assert len(t) == 301 + 30 and np.all(t[301:] == 5.0)
    t = frame_times(1.0, 3)  # 1/3 s steps end exactly at 1.0
    assert len(t) == 4 and t[-1] == 1.0
    t = frame_times(1.0, 4, speed=0.3)  # 0.075 s steps do not land on 1.0: t_final appended
    assert t[-1] == 1.0 and t[-2] < 1.0


def test_mp4_decodes_with_expected_count_size_fps(tmp_path, straight, capsys):
    p, sol = straight
    out = tmp_path / "v.mp4"
    rc = main(["render", "diamond-s14", sol, "-o", str(out), "--fps", "20", "--size", "320x240", "--hold", "0.5",
               "--trails", "-q"])
    assert rc == 0, capsys.readouterr().err
    meta, frames = decode(out)
    assert meta["codec"] == "h264" and meta["pix_fmt"].startswith("yuv420p")
    assert meta["size"] == (320, 240) and meta["fps"] == pytest.approx(20.0)
    assert len(frames) == 5 * 20 + 1 + 10
    # a decoded frame shows the disks where simulated (lossy: loose tolerance)
    from test_render import box_from_walls, pixel, world_to_px  # same mapping helpers
    tr = simulate(p, p.straight_velocities())
    k = 60
    f = frames[k]
    box = box_from_walls(f)
    amber = np.array(style.rgb8(style.CUEABLE))
    for c in world_to_px(p, box, tr.at(k / 20)):
        assert np.abs(pixel(f, c).astype(int) - amber).max() < 40
    # flat colours survive the RGBA -> yuv420p conversion, H.264 and decoding closely
    x0, y0, x1, y1 = box
    floor = f[int(y1) - 10:int(y1) - 4, int(x0) + 4:int(x0) + 10].reshape(-1, 3).astype(int)
    assert np.abs(floor - style.rgb8(style.BOX_FLOOR)).max() <= 4
    bg = f[-6:, :6].reshape(-1, 3).astype(int)
    assert np.abs(bg - style.rgb8(style.BACKGROUND)).max() <= 4
    assert capsys.readouterr().err == ""  # -q: silent


def test_gif_by_extension(tmp_path, straight):
    p, sol = straight
    out = tmp_path / "v.gif"
    assert main(["render", "diamond-s14", sol, "-o", str(out), "--fps", "10", "--size", "160x120", "--hold", "0",
                 "-q"]) == 0
    from PIL import Image

    from test_render import box_from_walls
    with Image.open(out) as im:
        assert im.format == "GIF" and im.size == (160, 120)
        assert im.n_frames == 51
        assert im.info.get("duration") == 100  # ms per frame at 10 fps
        im.seek(25)
        f = np.asarray(im.convert("RGB"))
    # colours survive the palette: the floor within 3 levels
    x0, y0, x1, y1 = box_from_walls(f)
    corner = f[int(y1) - 8:int(y1) - 2, int(x0) + 2:int(x0) + 8].reshape(-1, 3)  # bottom left: no text
    assert np.abs(corner.astype(int) - style.rgb8(style.BOX_FLOOR)).max() <= 3


def test_still_png_at_t0_shows_the_starts(tmp_path, straight):
    p, sol = straight
    out = tmp_path / "s.png"
    assert main(["render", "diamond-s14", sol, "--still", "0", "-o", str(out), "--size", "400x300", "--no-labels",
                 "-q"]) == 0  # no number on the disks' centres (legible at this size: on by default)
    from PIL import Image

    from test_render import box_from_walls, pixel, world_to_px
    f = np.asarray(Image.open(out).convert("RGB"))
    assert f.shape == (300, 400, 3)
    box = box_from_walls(f)
    amber = style.rgb8(style.CUEABLE)
    for c in world_to_px(p, box, p.start):
        assert np.abs(pixel(f, c).astype(int) - amber).max() <= 3


@pytest.mark.parametrize("argv, msg", [
    (["--still", "1", "-o", "x.mp4"], "--still writes a PNG"),
    (["-o", "x.png"], "needs --still"),
    (["-o", "x.avi"], "unknown output format"),
    (["-o", "x.mp4", "--size", "321x240"], "even width and height"),
    (["-o", "x.mp4", "--size", "big"], "WIDTHxHEIGHT"),
    (["-o", "x.mp4", "--fps", "0"], "--fps"),
    (["-o", "x.mp4", "--speed", "-1"], "--speed"),
    (["--still", "9", "-o", "x.png"], "t_final"),
])
def test_bad_options_give_one_line_and_exit_2(tmp_path, straight, capsys, argv, msg):
    p, sol = straight
    argv = [a if not a.startswith("x.") else str(tmp_path / a) for a in argv]
    try:
        rc = main(["render", "diamond-s14", sol, *argv, "-q"])
    except SystemExit as e:  # a flag outside its domain: refused by its argparse type (usage error, exit 2)
        rc = e.code
    err = capsys.readouterr().err.strip()
    assert rc == 2 and msg in err and len(err.splitlines()) == 1, err
    assert not list(tmp_path.iterdir())  # nothing written


@pytest.mark.parametrize("argv", [["chain3.jsn"], ["chain3.jsn", "-o", "v.mp4"], ["chain3.jsn", "s.json", "-o", "v.mp4"]])
def test_a_missing_input_file_is_named_with_what_render_takes(tmp_path, capsys, argv, monkeypatch):
    """A typo (chain3.jsn for chain3.json) says the file does not exist and which files render takes,
    with or without -o, exit 2, one line, nothing written."""
    monkeypatch.chdir(tmp_path)
    try:
        rc = main(["render", *argv, "-q"])
    except SystemExit as e:
        rc = e.code
    err = capsys.readouterr().err.strip()
    assert rc == 2 and len(err.splitlines()) == 1, err
    assert "chain3.jsn: no such file" in err
    assert "crash file" in err and "solution" in err and "throw file" in err
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("name", ["v.mov", "v.m4v", "v.avi", "v"])
def test_an_unlisted_output_extension_is_refused_for_every_input(tmp_path, straight, capsys, name):
    """The help lists .mp4 and .gif (and .png with --still): -o v.mov is refused in one line, exit
    2, before any work, for a problem and a crash file alike (not written as QuickTime)."""
    p, sol = straight
    crash = tmp_path / "crash.json"
    crash.write_text('{"kind": "nbst-crash", "version": 1}')
    for inputs in (["diamond-s14", sol], [str(crash)]):
        rc = main(["render", *inputs, "-o", str(tmp_path / name), "-q"])
        err = capsys.readouterr().err.strip()
        assert rc == 2 and "unknown output format" in err and ".mp4 or .gif" in err and len(err.splitlines()) == 1
    assert sorted(f.name for f in tmp_path.iterdir()) == ["crash.json"]


def test_the_video_writer_takes_only_the_listed_extensions(tmp_path):
    from nbst.errors import RenderError
    from nbst.render.core.video import video_kind

    assert video_kind("a.MP4") == "mp4" and video_kind("a.gif") == "gif"
    for name in ("a.mov", "a.m4v", "a.png", "a"):
        with pytest.raises(RenderError, match="unknown video extension"):
            video_kind(tmp_path / name)


def test_bad_solution_is_a_one_line_error(tmp_path, capsys):
    bad = tmp_path / "bad.json"
    bad.write_text('{"velocities": [[1, 2]]}')
    rc = main(["render", "diamond-s14", str(bad), "-o", str(tmp_path / "v.mp4"), "-q"])
    err = capsys.readouterr().err.strip()
    assert rc == 2 and "velocities" in err and len(err.splitlines()) == 1


def test_mujoco_source_renders_or_says_why(tmp_path, straight, capsys):
    """With nbst.models.rollout present: disks drawn from the MuJoCo replay sit where the
    exact simulator puts them early on (before any contact can make them drift apart).
    Without it: one line saying what is missing."""
    p, sol = straight
    out = tmp_path / "m.png"
    t = 0.2
    rc = main(["render", "diamond-s14", sol, "--still", str(t), "-o", str(out), "--size", "480x360",
               "--source", "mujoco", "--no-labels", "-q"])
    err = capsys.readouterr().err.strip()
    try:
        from nbst.models import rollout  # noqa: F401
    except ImportError:
        assert rc == 2 and "nbst.models.rollout" in err and len(err.splitlines()) == 1
        return
    assert rc == 0, err
    from PIL import Image

    from test_render import box_from_walls, pixel, world_to_px
    tr = simulate(p, p.straight_velocities())
    assert tr.events["time"].min() > t  # no contact yet: MuJoCo and exact agree closely
    f = np.asarray(Image.open(out).convert("RGB")).astype(int)
    box = box_from_walls(f)
    amber = np.array(style.rgb8(style.CUEABLE))
    for c in world_to_px(p, box, tr.at(t)):
        assert np.abs(pixel(f, c) - amber).max() <= 3


def test_video_writer_recycles_its_buffers_and_copies_foreign_frames(tmp_path):
    out = tmp_path / "w.mp4"
    with VideoWriter(out, (64, 48), 10, buffers=2) as w:
        seen = set()
        for k in range(6):
            b = w.acquire()
            seen.add(id(b))
            b[:] = k * 40
            w.submit(b)
        w.submit(np.full((48, 64, 3), 255, np.uint8))  # not from the pool: copied
    assert len(seen) <= 2 and w.frames == 7
    meta, frames = decode(out)
    assert len(frames) == 7
    assert [int(f.mean() + 0.5) for f in frames[:6]] == pytest.approx([k * 40 for k in range(6)], abs=3)
    assert frames[-1].mean() > 250


# --------------------------------------------------------------------------- figures

def test_plot_problem_arrows_broken_for_noncueable_disks(tmp_path):
    from matplotlib.patches import FancyArrowPatch

    from nbst.render.figures import plot_problem
    p = load_problem("over5")
    fig = plot_problem(p)
    arrows = [a for a in fig.axes[0].patches if isinstance(a, FancyArrowPatch)]
    assert len(arrows) == p.n
    dashed = [a for a in arrows if a.get_linestyle() not in ("-", "solid")]
    assert len(dashed) == int((~p.cueable).sum())
    out = tmp_path / "fig.png"
    assert main(["plot", "problem", "over5", "-o", str(out), "--dpi", "60"]) == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_plot_trajectories_marks_every_collision_and_bounce(tmp_path, straight):
    from nbst.render.figures import plot_trajectories
    p, sol = straight
    tr = simulate(p, p.straight_velocities())
    fig = plot_trajectories(p, tr)
    lines = {ln.get_label(): ln for ln in fig.axes[0].get_lines()}
    coll = [ln for k, ln in lines.items() if k.startswith("disk-disk")]
    wall = [ln for k, ln in lines.items() if k.startswith("wall")]
    assert len(coll[0].get_xdata()) == tr.n_disk_disk == 17
    assert len(wall[0].get_xdata()) == tr.n_wall
    # each path starts at the start and ends at the simulated final position
    paths = [ln for ln in fig.axes[0].get_lines() if ln.get_label().startswith("_path")]
    assert len(paths) == p.n
    for i, ln in enumerate(paths):
        xy = np.c_[ln.get_xdata(), ln.get_ydata()]
        assert np.allclose(xy[0], p.start[i]) and np.allclose(xy[-1], tr.final_positions[i])
    out = tmp_path / "traj.svg"
    assert main(["plot", "trajectories", "diamond-s14", sol, "-o", str(out)]) == 0
    assert b"<svg" in out.read_bytes()[:500]


def test_plot_trajectories_breaks_noncueable_paths():
    from nbst.render.figures import plot_trajectories
    p = load_problem("over5")
    fig = plot_trajectories(p, simulate(p, np.zeros((p.n, 2)) + np.where(p.cueable[:, None], 30.0, 0.0)))
    paths = [ln for ln in fig.axes[0].get_lines() if ln.get_label().startswith("_path")]
    assert [ln.get_linestyle() == "-" for ln in paths] == list(p.cueable)


def test_plot_rejects_unknown_format(tmp_path, capsys):
    assert main(["plot", "problem", "over5", "-o", str(tmp_path / "f.bmpx")]) == 2
    assert "unknown figure format" in capsys.readouterr().err


def test_registration_and_import_stay_light():
    code = ("import sys, nbst, nbst.render, nbst.cli.render; from nbst.cli import build_parser; build_parser(); "
            "heavy = [m for m in ('moderngl', 'imageio', 'imageio_ffmpeg', 'matplotlib', 'trimesh', 'PIL') "
            "if m in sys.modules]; print(heavy); sys.exit(1 if heavy else 0)")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr


def test_3d_view_writes_a_still_and_a_short_video(tmp_path, straight):
    p, sol = straight
    out = tmp_path / "s3.png"
    assert main(["render", "diamond-s14", sol, "--view", "3d", "--trails", "--still", "2.5", "-o", str(out),
                 "--size", "320x180", "-q"]) == 0
    from PIL import Image
    f = np.asarray(Image.open(out).convert("RGB")).astype(int)
    amber = np.array(style.rgb8(style.CUEABLE))
    # lit pucks: many pixels of the puck colour family (red > green > blue, bright)
    puck = (f[..., 0] > f[..., 1] + 20) & (f[..., 1] > f[..., 2] + 20) & (f[..., 0] > 150)
    assert puck.sum() > 14 * 20
    assert np.abs(f[puck].mean(axis=0) - amber).max() < 70
    out = tmp_path / "v3.mp4"
    assert main(["render", "diamond-s14", sol, "--view", "3d", "-o", str(out), "--size", "160x96", "--fps", "4",
                 "--hold", "0", "-q"]) == 0
    meta, frames = decode(out)
    assert len(frames) == 21 and meta["size"] == (160, 96)


def test_a_failed_render_leaves_no_video(tmp_path):
    out = tmp_path / "fail.mp4"
    with pytest.raises(RuntimeError, match="boom"):
        with VideoWriter(out, (64, 48), 10) as w:
            for k in range(3):
                w.submit(np.zeros((48, 64, 3), np.uint8))
            raise RuntimeError("boom")
    assert list(tmp_path.iterdir()) == []  # neither the video nor its temporary file


@pytest.mark.parametrize("source", ["mujoco", "both"])
def test_mujoco_sources_use_the_replay(tmp_path, straight, monkeypatch, source):
    """The MuJoCo plumbing with a stand-in replay: the exact motion shifted by 40 units
    in x, so frames tell which motion was drawn."""
    import nbst.cli.render as rcli
    p, sol = straight
    tr = simulate(p, p.straight_velocities())
    calls = []

    def fake(problem, velocities, times):
        calls.append(np.asarray(times))
        return tr.at(np.asarray(times)) + np.array([40.0, 0.0])

    monkeypatch.setattr(rcli, "mujoco_positions", fake)
    out = tmp_path / "m.png"
    assert main(["render", "diamond-s14", sol, "--still", "1.5", "-o", str(out), "--size", "480x360",
                 "--source", source, "--no-labels", "-q"]) == 0
    assert calls and 1.5 in calls[0]  # sampled at the frame's time
    from PIL import Image

    from test_render import box_from_walls, pixel, world_to_px
    f = np.asarray(Image.open(out).convert("RGB")).astype(int)
    box = box_from_walls(f)
    amber = np.array(style.rgb8(style.CUEABLE))
    exact = world_to_px(p, box, tr.at(1.5))
    shifted = world_to_px(p, box, tr.at(1.5) + (40.0, 0.0))
    on_exact = sum(np.abs(pixel(f, c) - amber).max() <= 3 for c in exact)
    on_shifted = sum(np.abs(pixel(f, c) - amber).max() <= 3 for c in shifted)
    if source == "mujoco":  # disks drawn at the replay's positions
        assert on_shifted == p.n and on_exact < p.n
    else:  # exact disks, replay as rings
        assert on_exact >= p.n - 3
    out = tmp_path / "m.mp4"
    assert main(["render", "diamond-s14", sol, "-o", str(out), "--size", "160x120", "--fps", "10", "--hold", "0",
                 "--source", source, "--trails", "-q"]) == 0  # trails of a sampled motion: uniform samples
    assert len(decode(out)[1]) == 51


def test_no_egl_is_a_one_line_error_naming_the_packages(tmp_path, straight, monkeypatch, capsys):
    import moderngl

    def broken(*a, **k):
        raise Exception("eglGetDisplay failed\nmore detail")

    monkeypatch.setattr(moderngl, "create_context", broken)
    p, sol = straight
    rc = main(["render", "diamond-s14", sol, "--still", "0", "-o", str(tmp_path / "s.png"), "-q"])
    err = capsys.readouterr().err.strip()
    assert rc == 2 and len(err.splitlines()) == 1
    assert "eglGetDisplay failed" in err and "libegl1 libgl1 libgl1-mesa-dri" in err


# --------------------------------------------------------------------------- one visual language in figures

def _drawn(fig):
    """Lay the figure out and draw it (Agg), so that window extents are final."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    FigureCanvasAgg(fig).draw()
    return fig


def _legend_clear_of_data(fig):
    """Every legend lies outside every axes' data area, and inside the figure."""
    _drawn(fig)
    r = fig.canvas.get_renderer()
    assert fig.legends or any(ax.get_legend() for ax in fig.axes), "no legend"
    legends = list(fig.legends) + [ax.get_legend() for ax in fig.axes if ax.get_legend()]
    for lg in legends:
        lb = lg.get_window_extent(r)
        for ax in fig.axes:
            assert not lb.overlaps(ax.get_window_extent(r)), (lb, ax.get_window_extent(r))
        fb = fig.bbox
        assert fb.x0 - 1 <= lb.x0 and lb.x1 <= fb.x1 + 1 and fb.y0 - 1 <= lb.y0 and lb.y1 <= fb.y1 + 1


def _start_disks(ax, problem):
    """Filled circles centred on the starts, one per disk (disk i -> its patch)."""
    from matplotlib.patches import Circle
    out = {}
    for c in ax.patches:
        if isinstance(c, Circle) and c.get_fill():
            hit = np.nonzero(np.hypot(*(problem.start - np.array(c.center)).T) < 1e-9)[0]
            if len(hit) == 1 and abs(c.get_radius() - problem.radius[hit[0]]) < 1e-9:
                out[int(hit[0])] = c
    return out


def _numbers(ax):
    """{(text, (x, y)) } of the axes' texts and annotations, positions in data units."""
    from matplotlib.text import Annotation
    out = set()
    for t in ax.texts:
        xy = t.xy if isinstance(t, Annotation) else t.get_position()
        out.add((t.get_text(), (round(float(xy[0]), 6), round(float(xy[1]), 6))))
    return out


@pytest.mark.parametrize("which", ["problem", "trajectories"])
def test_figures_use_the_palette_and_number_starts_and_targets(which):
    """Start disks filled with nbst.palette's class colour (the video's), the number of
    each disk on it at its start, and beside its target the same number."""
    from matplotlib.colors import to_rgb

    from nbst import palette
    from nbst.render.figures import plot_problem, plot_trajectories
    p = load_problem("over5")
    tr = simulate(p, np.zeros((p.n, 2)) + np.where(p.cueable[:, None], 30.0, 0.0))
    fig = plot_problem(p) if which == "problem" else plot_trajectories(p, tr)
    ax = fig.axes[0]
    disks = _start_disks(ax, p)
    assert sorted(disks) == list(range(p.n))
    for i, c in disks.items():
        assert np.allclose(c.get_facecolor()[:3], palette.class_color(p.cueable[i]), atol=0.5 / 255), i
    nums = _numbers(ax)
    for i in range(p.n):
        assert (str(i), tuple(np.round(p.start[i], 6))) in nums, i
        assert (str(i), tuple(np.round(p.target[i], 6))) in nums, i
    if which == "trajectories":  # paths in a shade of the class colour; final positions as outline circles
        from matplotlib.patches import Circle
        paths = [ln for ln in ax.get_lines() if ln.get_label().startswith("_path")]
        for i, ln in enumerate(paths):
            assert np.allclose(to_rgb(ln.get_color()), palette.disk_shades(p.cueable)[i], atol=0.5 / 255)
        outlines = [c for c in ax.patches if isinstance(c, Circle) and not c.get_fill()]
        for i in range(p.n):
            assert any(np.allclose(c.center, tr.final_positions[i]) and abs(c.get_radius() - p.radius[i]) < 1e-9
                       for c in outlines), i


def test_figure_legends_sit_outside_the_box(straight):
    from nbst.render.figures import plot_problem, plot_trajectories
    p, _ = straight
    for p_ in (load_problem("over5"), p):
        _legend_clear_of_data(plot_problem(p_))
    _legend_clear_of_data(plot_trajectories(p, simulate(p, p.straight_velocities())))


def test_figures_legend_says_what_the_marks_mean():
    from nbst import palette
    from nbst.render.figures import plot_trajectories
    p = load_problem("over5")
    v = np.zeros((p.n, 2))
    v[0], v[1] = (45.0, 3.0), (90.0, 20.0)  # disk 0 strikes noncueable disk 2: a collision to mark
    tr = simulate(p, v)
    assert tr.n_disk_disk >= 1 and tr.n_wall >= 1
    fig = plot_trajectories(p, tr)
    words = [t.get_text() for t in fig.legends[0].get_texts()]
    for w in (palette.LEGEND_TARGET, palette.LEGEND_RING, palette.LEGEND_FINAL):
        assert w in words
    assert any(w.startswith(palette.LEGEND_CUEABLE) for w in words)
    assert any(w.startswith(palette.LEGEND_NONCUEABLE) for w in words)
    assert any(w.startswith(palette.LEGEND_COLLISION) for w in words)
    assert any(w.startswith(palette.LEGEND_WALL_BOUNCE) for w in words)


def test_plot_says_what_it_wrote_unless_quiet(tmp_path, capsys):
    out = tmp_path / "p.png"
    assert main(["plot", "problem", "over5", "-o", str(out), "--dpi", "40"]) == 0
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"nbst plot: wrote {out}") and len(err.splitlines()) == 1
    assert main(["plot", "problem", "over5", "-o", str(out), "--dpi", "40", "-q"]) == 0
    assert capsys.readouterr().err == ""


def test_a_thousand_disk_problem_renders_to_mp4_and_png(tmp_path, capsys):
    """``nbst render`` at N = 1,000 (issue 21): a small MP4 decodes with every frame, disks
    where simulated; a 720p still says in its summary why the disks carry no numbers, and
    --labels overrides the size rule."""
    import json

    from PIL import Image

    from test_render import box_from_walls, grid_problem, pixel, world_to_px
    p, v, tr = grid_problem(1000)
    prob, sol = tmp_path / "grid.json", tmp_path / "sol.json"
    prob.write_text(json.dumps(p.raw))
    save_solution(sol, make_solution(p, v))
    out = tmp_path / "g.mp4"
    assert main(["render", str(prob), str(sol), "-o", str(out), "--size", "640x360", "--fps", "6", "--hold", "0",
                 "-q"]) == 0
    meta, frames = decode(out)
    assert len(frames) == len(frame_times(p.t_final, 6)) and meta["size"] == (640, 360)
    png = tmp_path / "g.png"
    capsys.readouterr()
    assert main(["render", str(prob), str(sol), "--still", "2.5", "-o", str(png)]) == 0
    assert "no disk numbers: disks 8 px across, under the 12 px" in capsys.readouterr().err
    f = np.asarray(Image.open(png).convert("RGB")).astype(int)
    amber = np.array(style.rgb8(style.CUEABLE))
    hits = [np.abs(pixel(f, c) - amber).max() <= 3 for c in world_to_px(p, box_from_walls(f), tr.at(2.5))]
    assert all(hits)  # every disk centre shows the fill: nothing (marker, ring, number) is drawn over a disk
    assert main(["render", str(prob), str(sol), "--still", "2.5", "-o", str(png), "--labels"]) == 0
    assert "no disk numbers" not in capsys.readouterr().err
