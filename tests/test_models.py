"""MuJoCo scenes (nbst.models): the generated MJCF and its physics against the exact simulator.

Measured facts these tests pin (MuJoCo 4.0.0, Euler, solref = (-2/h^2, 0)):
* a wall bounce or a head-on collision reverses/exchanges the normal velocity exactly
  (to round-off), but one step late: the MuJoCo motion is the exact one with each
  impact delayed by one timestep h, i.e. a disk ends 2 * v_n * h further along the
  normal per wall bounce, independent of the phase of the impact within the step;
* oblique collisions err in direction by ~0.1 deg at h = 0.25 ms.
"""
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))
from conftest import make_problem  # noqa: E402

mujoco = pytest.importorskip("mujoco")

from nbst import simulate  # noqa: E402
from nbst.models.mjrun import rollout, run_mujoco  # noqa: E402
from nbst.models.scene import scene_xml  # noqa: E402

H = 0.00025


def test_import_is_light():
    import subprocess
    code = "import nbst.models, sys; assert 'mujoco' not in sys.modules; print(callable(nbst.models.rollout))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "True"


def test_generated_mjcf_loads(tmp_path):
    from nbst import load_problem
    p = load_problem("over5")
    path = tmp_path / "scene.xml"
    path.write_text(scene_xml(p, p.straight_velocities()), encoding="utf-8")
    m = mujoco.MjModel.from_xml_path(str(path))
    assert m.nq == 2 * p.n and m.nkey == 1
    assert np.allclose(m.opt.gravity, 0.0)
    # the keyframe holds the velocities in m/s (1 unit = 1 mm); XML keeps 6 significant digits
    assert np.allclose(m.key_qvel[0].reshape(-1, 2), p.straight_velocities() * 1e-3, rtol=1e-5, atol=1e-9)
    # masses from the problem (the visual puck adds none)
    assert np.allclose(m.body_mass[1:], p.mass)


@pytest.mark.parametrize("h", [1e-3, 2.5e-4])
def test_contact_stiffness_follows_the_timestep(h):
    # k = 2/h^2 must be computed from h (a k off by 1% changes the speed ~1.6% per bounce):
    # every colliding geom carries solref (-2/h^2, 0), condim 1 and zero margin and gap
    from nbst.models.scene import build_model
    p = make_problem([[100, 100], [300, 300]], 10.0)
    m = build_model(p, timestep=h)
    hit = m.geom_contype > 0
    assert hit.sum() == 4 + 2
    assert np.allclose(m.geom_solref[hit], [-2 / h**2, 0.0], rtol=1e-12)
    assert np.all(m.geom_condim[hit] == 1) and np.all(m.geom_margin == 0) and np.all(m.geom_gap == 0)
    assert m.opt.timestep == h and m.opt.integrator == mujoco.mjtIntegrator.mjINT_EULER


@pytest.mark.parametrize("name", ['x"/><geom name="evil', "</mujoco><!--", "a--b & <c> 'é' ]]>", ""])
def test_hostile_problem_name_cannot_break_xml(name):
    p = make_problem([[100, 100]], 10.0, name=name or "x")  # control characters: refused when read
    xml = scene_xml(p, [[1.0, 2.0]])
    m = mujoco.MjModel.from_xml_string(xml)
    assert m.ngeom == 1 + 4 + 2  # floor, 4 walls, one disk's sphere and puck: nothing injected


def test_wall_bounces_are_exact_reflections_one_step_late():
    # A bounce delayed by one step h is an exact reflection off a wall v*h further out. So the
    # MuJoCo motion of one disk must equal, to 1e-6 units (round-off over 20,000 steps), the exact
    # motion in a box widened by v*h on each side; and its speed must survive to 1e-9 (relative).
    vx, vy = 333.3, 121.7
    p = make_problem([[400.0, 300.0]], 10.0, t_final=5.0)
    v = np.array([[vx, vy]])
    r = run_mujoco(p, v, timestep=H)
    dx, dy = vx * H, vy * H
    wide = make_problem([[400.0 + dx, 300.0 + dy]], 10.0, t_final=5.0, box=(800 + 2 * dx, 800 + 2 * dy))
    tr = simulate(wide, v)
    assert tr.n_wall >= 3 and len(r.events) == tr.n_wall
    assert abs(r.energy[-1] / r.energy[0] - 1) < 1e-9
    ts = np.linspace(0, 5.0, 101)
    assert np.abs(r.at(ts) - (tr.at(ts) - [dx, dy])).max() < 1e-6
    # and against the true box the error is 2*v*h per bounce at most
    assert np.abs(r.final_positions - simulate(p, v).final_positions).max() <= 2 * vx * H * tr.n_wall


def test_head_on_collision_exact_velocities():
    # unequal masses, head-on: the exchanged velocities must match the exact ones to 1e-8 units/s
    p = make_problem([[300, 400], [500, 400]], 10.0, t_final=2.0, masses=[1.0, 2.0])
    v = np.array([[100.0, 0], [-50.0, 0]])
    tr = simulate(p, v)
    r = run_mujoco(p, v, timestep=H)
    vm = (r.positions[-1] - r.positions[-2]) / H
    assert np.abs(vm - tr.final_velocities).max() < 1e-8
    assert abs(r.energy[-1] / r.energy[0] - 1) < 1e-9
    # MuJoCo reports the contact at the first overlapping step state: within [0, h] after the exact time
    # (h exactly here: the disks touch, distance 0, at the step state t = 1.2 s and overlap one step later)
    assert len(r.events) == 1 and 0 <= r.events["time"][0] - tr.events["time"][0] <= H * (1 + 1e-9)
    # the impact is one step late: each disk ends |dv| * h from its exact position (to 1e-9)
    dv = np.abs(tr.final_velocities - v).max(axis=1)
    assert np.abs(np.hypot(*(r.final_positions - tr.final_positions).T) - dv * H).max() < 1e-9


def test_oblique_collision_direction():
    # impact parameter = radius (30 deg): direction within 0.2 deg, speed within 0.5% at h = 0.25 ms
    p = make_problem([[300, 400], [500, 410]], 10.0, t_final=2.0)
    v = np.array([[100.0, 0], [0, 0]])
    tr = simulate(p, v)
    r = run_mujoco(p, v, timestep=H)
    vm = (r.positions[-1] - r.positions[-2]) / H
    va = tr.final_velocities
    ang = np.degrees(np.arctan2(vm[:, 1], vm[:, 0]) - np.arctan2(va[:, 1], va[:, 0]))
    assert np.abs(ang).max() < 0.2
    assert np.abs(np.hypot(*vm.T) / np.hypot(*va.T) - 1).max() < 5e-3


def test_rollout_shape_and_free_flight():
    # no events: MuJoCo free flight is exact (to 1e-9 units) at any requested time
    p = make_problem([[100, 100], [600, 600]], 10.0, t_final=1.0)
    v = np.array([[50.0, 20.0], [-30.0, 10.0]])
    ts = np.array([0.0, 0.1, 0.33333, 1.0])
    x = rollout(p, v, ts)
    assert x.shape == (4, 2, 2)
    assert np.abs(x - simulate(p, v).at(ts)).max() < 1e-9


def test_gallery_scenes_load_and_match_their_solutions():
    # every gallery folder: scene.xml loads; its keyframe holds solution.json's velocities (m/s; the
    # XML keeps 6 significant digits, so rtol 1e-5); problem.json is the built-in problem
    import json

    from nbst import load_problem
    from nbst.models.gallery import GALLERY_DIR
    from nbst.solution import load_solution
    if not GALLERY_DIR.is_dir():
        pytest.skip("no models/scenes here (an installed wheel without the gallery)")
    folders = sorted(p for p in GALLERY_DIR.iterdir() if p.is_dir())
    assert folders, "the gallery is empty: run python -m nbst.models.gallery"
    for f in folders:
        p = load_problem(f.name)
        assert json.loads((f / "problem.json").read_text()) == json.loads(json.dumps(p.to_dict()))
        m = mujoco.MjModel.from_xml_path(str(f / "scene.xml"))
        assert m.nkey == 1 and m.nbody == 1 + p.n
        sol = load_solution(f / "solution.json", p)
        assert np.allclose(m.key_qvel[0].reshape(-1, 2), sol.velocities * 1e-3, rtol=1e-5, atol=1e-9)
        assert (f / "preview.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


# --------------------------------------------------------------------------- one visual language

def test_mjcf_disks_wear_the_palette_class_colours():
    """Disk geoms in nbst.palette's class colours (the video's amber and blue); targets
    neutral: their colour is no class colour."""
    from nbst import load_problem, palette
    from nbst.models.scene import build_model
    p = load_problem("over5")
    m = build_model(p)
    for i in range(p.n):
        want = palette.class_color(p.cueable[i])
        puck = m.geom_rgba[m.geom(f"disk{i}_puck").id]
        assert np.allclose(puck, (*want, 1.0), atol=1e-6), i
        assert np.allclose(m.geom_rgba[m.geom(f"disk{i}_collision").id][:3], want, atol=1e-6)
        for site in (f"target{i}", f"target{i}_dot"):
            rgb = m.site_rgba[m.site(site).id][:3]
            assert not any(np.allclose(rgb, c, atol=0.1) for c in (palette.CUEABLE, palette.NONCUEABLE))


def test_gallery_scenes_and_previews_show_the_palette_colours():
    """The committed gallery matches the palette: scene.xml's pucks carry the class colours,
    and preview.png shows each puck's top face in its class colour (the preview is lit so
    that a face lit straight from above shows its rgba). Pixel positions come from the top
    camera's pinhole projection (fovy 50 deg, straight down), not from the renderer."""
    from PIL import Image

    from nbst import load_problem, palette
    from nbst.models.gallery import GALLERY_DIR
    from nbst.models.scene import DEFAULT_UNIT, PUCK_HALF_HEIGHT_RADII
    if not (GALLERY_DIR / "over5").is_dir():
        pytest.skip("no models/scenes here (an installed wheel without the gallery)")
    for name in ("over5", "diamond-s14"):
        p = load_problem(name)
        m = mujoco.MjModel.from_xml_path(str(GALLERY_DIR / name / "scene.xml"))
        for i in range(p.n):
            assert np.allclose(m.geom_rgba[m.geom(f"disk{i}_puck").id][:3], palette.class_color(p.cueable[i]),
                               atol=1e-5)  # the XML keeps 6 significant digits
        img = np.asarray(Image.open(GALLERY_DIR / name / "preview.png").convert("RGB")).astype(int)
        S = img.shape[1]  # the square top view; the caption band lies below it
        u = DEFAULT_UNIT
        W, H = p.box[0] * u, p.box[1] * u
        cam_z = 1.2 * max(W, H)
        f = 0.5 * S / np.tan(np.radians(25.0))
        for i in range(p.n):
            top = p.radius[i] * u * (1 + PUCK_HALF_HEIGHT_RADII)
            x, y = p.start[i] * u
            col = S / 2 + f * (x - W / 2) / (cam_z - top)
            row = S / 2 - f * (y - H / 2) / (cam_z - top)
            px = img[int(row), int(col)]
            # 8 levels: MuJoCo's rasterizer and the PNG round-trip; the old palette was > 100 away
            assert np.abs(px - np.array(palette.rgb8(palette.class_color(p.cueable[i])))).max() <= 8, \
                (name, i, px)


@pytest.fixture(scope="module")
def validation():
    """A MuJoCo validation with both classes and both kinds of event (nbst.planted seed 4:
    3 noncueable disks, each struck by a cueable one)."""
    from nbst.models.validate import validate
    from nbst.planted import planted
    p, v = planted(5, noncue=3, radius=10.0, seed=4)
    val = validate(p, v)
    assert val.exact.n_disk_disk >= 3 and p.cueable.any() and (~p.cueable).any()
    return val


def _drawn(fig):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    FigureCanvasAgg(fig).draw()
    return fig.canvas.get_renderer()


@pytest.mark.parametrize("which", ["overlay_figure", "error_figure", "timeline_figure"])
def test_report_legends_never_cover_data(validation, which):
    """Each report figure has a legend, outside its axes and inside the figure."""
    from nbst.render import report_figures as report
    fig = getattr(report, which)(validation)
    r = _drawn(fig)
    assert len(fig.legends) == 1
    lb = fig.legends[0].get_window_extent(r)
    for ax in fig.axes:
        assert not lb.overlaps(ax.get_window_extent(r))
    assert fig.bbox.x0 - 1 <= lb.x0 and lb.x1 <= fig.bbox.x1 + 1 and fig.bbox.y0 - 1 <= lb.y0


def test_report_overlay_speaks_the_palette(validation):
    """The overlay's start disks are filled with the palette's class colours and numbered;
    each target carries its disk's number; exact and MuJoCo paths are both in the legend."""
    from matplotlib.patches import Circle
    from matplotlib.text import Annotation

    from nbst import palette
    from nbst.render.report_figures import overlay_figure
    val = validation
    p = val.problem
    fig = overlay_figure(val)
    ax = fig.axes[0]
    for i in range(p.n):
        disk = [c for c in ax.patches if isinstance(c, Circle) and c.get_fill()
                and np.allclose(c.center, p.start[i]) and abs(c.get_radius() - p.radius[i]) < 1e-9]
        assert len(disk) == 1 and np.allclose(disk[0].get_facecolor()[:3], palette.class_color(p.cueable[i]),
                                              atol=0.5 / 255), i
        texts = {(t.get_text(), tuple(np.round(t.xy if isinstance(t, Annotation) else t.get_position(), 6)))
                 for t in ax.texts}
        assert (str(i), tuple(np.round(p.start[i], 6))) in texts and (str(i), tuple(np.round(p.target[i], 6))) in texts
    words = [t.get_text() for t in fig.legends[0].get_texts()]
    assert "MuJoCo path" in words and any(w.startswith("exact path") for w in words)
    assert palette.LEGEND_TARGET in words


def test_report_error_curves_are_numbered_outside_the_axes(validation):
    """One curve per disk in a shade of its class colour; each disk's number just right of
    the axes, none overlapping another."""
    from matplotlib.colors import to_rgb

    from nbst import palette
    from nbst.render.report_figures import error_figure
    val = validation
    p = val.problem
    fig = error_figure(val)
    ax = fig.axes[0]
    curves = [ln for ln in ax.get_lines() if ln.get_label().startswith("_disk")]
    assert [to_rgb(ln.get_color()) for ln in curves] == [pytest.approx(c, abs=0.5 / 255)
                                                        for c in palette.disk_shades(p.cueable)]
    r = _drawn(fig)
    axb = ax.get_window_extent(r)
    nums = [t for t in ax.texts if t.get_text().isdigit()]
    assert sorted(int(t.get_text()) for t in nums) == list(range(p.n))
    from matplotlib.text import Text
    boxes = [Text.get_window_extent(t, r) for t in nums]  # the words, without their leader lines
    assert all(b.x0 >= axb.x1 for b in boxes)
    assert not any(a.overlaps(b) for k, a in enumerate(boxes) for b in boxes[k + 1:])


def test_report_error_curves_differ_in_shape_and_in_a_deuteranopes_view(validation):
    """Curves are told apart without colour (each disk its own hollow mark) and, in colour,
    also by a deuteranope: every two disk shades of one class differ by at least 15 CIELAB
    units in the simulated deuteranopia view (tests/cvd.py), and the classes by far more."""
    from cvd import delta_e, deuteranopia

    from nbst import palette
    from nbst.render.report_figures import error_figure
    val = validation
    p = val.problem
    fig = error_figure(val)
    curves = [ln for ln in fig.axes[0].get_lines() if ln.get_label().startswith("_disk")]
    assert [ln.get_marker() for ln in curves] == [palette.disk_marker(i) for i in range(p.n)]
    assert len({palette.disk_marker(i) for i in range(len(palette.DISK_MARKERS))}) == len(palette.DISK_MARKERS)
    assert not {"*", "."} & set(palette.DISK_MARKERS)  # the marks of a collision and a bounce stay theirs
    words = [t.get_text() for t in fig.legends[0].get_texts()]
    assert all(f"disk {i}" in words for i in range(p.n))
    for cls in (palette.CUEABLE, palette.NONCUEABLE):
        shades = [deuteranopia(palette.shade(cls, s)) for s in palette.SHADE_STEPS]
        gaps = [delta_e(a, b) for k, a in enumerate(shades) for b in shades[k + 1:]]
        assert min(gaps) >= 15, (cls, gaps)  # the old steps (0, .38, .18, .55): 13.2 for blue
    assert delta_e(deuteranopia(palette.CUEABLE), deuteranopia(palette.NONCUEABLE)) > 40


def test_report_error_floor_is_explained(mk):
    """Errors of exactly zero (no impact yet: MuJoCo's free flight is exact) cannot sit on a
    log axis: they are drawn on the floor, and the legend says what the floor means."""
    from nbst.models.validate import validate
    from nbst.render.report_figures import error_figure, error_floor
    p = mk([[100.0, 400.0], [400.0, 100.0]], radii=10.0, targets=[[600.0, 400.0], [400.0, 600.0]])
    val = validate(p, np.array([[100.0, 0.0], [0.0, 100.0]]))  # no collision, no bounce
    assert (val.error_curve < error_floor(val)).any()
    fig = error_figure(val)
    words = " ".join(t.get_text() for t in fig.legends[0].get_texts())
    assert f"{error_floor(val):g}" in words and "floor" in words
    floor_lines = [ln for ln in fig.axes[0].get_lines() if np.allclose(ln.get_ydata(), error_floor(val))
                   and not ln.get_label().startswith("_disk")]
    assert floor_lines  # the floor is drawn, not only named


def test_report_page_reads_well(validation):
    """"1 unit", never "1 units"; the summary JSON folded away under <details>, after the
    last figure, not a wall of text at the end of the page."""
    import re

    from nbst.render.report import report_html
    page = report_html(validation)
    assert not re.search(r"\b1 units\b", page)
    assert validation.tol != 1 or "1 unit" in page
    tail = page[page.index("Summary data"):]
    assert "<details>" in tail and tail.index("<details>") < tail.index("<pre>") < tail.index("</details>")
    assert 'href="report.json"' in tail


def test_gallery_previews_number_every_puck_and_target_and_say_what_they_show():
    """preview.png numbers each puck (upper left, black) and each target (upper right of its
    dot, green) with its disk's index, and carries a caption band below the square view. The
    numbers are found where the top camera's projection puts them, as dark glyph pixels that
    the bare MuJoCo render does not have."""
    from PIL import Image

    from nbst import load_problem
    from nbst.models.gallery import GALLERY_DIR, PREVIEW_INK, PREVIEW_NUMBER_PX, PREVIEW_TARGET_INK
    from nbst.models.scene import DEFAULT_UNIT, PUCK_HALF_HEIGHT_RADII
    if not (GALLERY_DIR / "over5").is_dir():
        pytest.skip("no models/scenes here (an installed wheel without the gallery)")
    for name in ("over5", "diamond-s14", "diamond-s14-tiny"):
        p = load_problem(name)
        img = np.asarray(Image.open(GALLERY_DIR / name / "preview.png").convert("RGB")).astype(int)
        S = img.shape[1]
        assert img.shape[0] > S + 3 * 12  # a caption of three lines or more below the view
        caption = img[S:]
        assert (np.abs(caption - np.array(PREVIEW_INK)).max(axis=2) < 60).sum() > 500  # words in it
        u = DEFAULT_UNIT
        W, H = p.box[0] * u, p.box[1] * u
        cam_z = 1.2 * max(W, H)
        f = 0.5 * S / np.tan(np.radians(25.0))

        def px(xy, z):
            return S / 2 + f * (xy[0] - W / 2) / (cam_z - z), S / 2 - f * (xy[1] - H / 2) / (cam_z - z)

        n_px = PREVIEW_NUMBER_PX
        for i in range(p.n):
            r = p.radius[i] * u
            c, rr = px(p.start[i] * u, r * (1 + PUCK_HALF_HEIGHT_RADII)), f * r / cam_z
            off = 0.72 * max(rr, 3.0) + 1
            box = img[int(c[1] - off - 1.4 * n_px):int(c[1] - off + 2), int(c[0] - off - 2.2 * n_px):int(c[0] - off + 2)]
            assert (np.abs(box - np.array(PREVIEW_INK)).max(axis=2) < 50).sum() >= 6, (name, "puck", i)
            t = px(p.target[i] * u, 0.0)
            box = img[int(t[1] - 4 - 1.4 * n_px):int(t[1]), int(t[0] + 2):int(t[0] + 4 + 2.2 * n_px)]
            assert (np.abs(box - np.array(PREVIEW_TARGET_INK)).max(axis=2) < 50).sum() >= 6, (name, "target", i)
