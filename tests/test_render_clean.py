"""``--clean``: every renderer draws its picture with no overlay text (disks in 2D and 3D, the 5 m
throw, the throw down the full lane, the crash; scenes: tests/test_render_scene.py).

For each world the same frame is drawn twice, annotated and clean. The glyphs the annotated frame
draws (recorded from the core's text batches) mark where the overlay is; there, the annotated
frame has text-coloured ink and the clean frame has none, and the clean frame draws no glyph at all.
"""
from __future__ import annotations

import numpy as np
import pytest

from nbst.render.core import shapes, style
from tests.test_render_crash import crash_file, loaded  # noqa: F401  (the crash file and its replay, as there)

SIZE = (640, 360)
TEXT = np.array(style.rgb8(style.TEXT))


@pytest.fixture(scope="module")
def gl():
    """The only place this file creates a GL context (EGL, headless)."""
    from nbst.render.core.gl import create_context

    ctx = create_context()
    yield ctx
    ctx.release()


@pytest.fixture
def glyphs(monkeypatch):
    """The boxes (x0, y0, x1, y1) px of every glyph drawn through the core's text (halos included)."""
    boxes: list = []
    draw, batch_draw = shapes.Text.draw, shapes._Instanced.draw

    def text_draw(self, size, data, color):
        cw, ch = self.cell
        boxes.extend((float(x), float(y), float(x) + cw, float(y) + ch) for x, y in np.asarray(data["pos"]))
        return draw(self, size, data, color)

    def instanced_draw(self, data):   # the halos' batches draw glyph instances too
        if data.dtype == shapes.TEXT_DTYPE:
            boxes.extend((float(x), float(y), float(x) + 1, float(y) + 1) for x, y in np.asarray(data["pos"]))
        return batch_draw(self, data)

    monkeypatch.setattr(shapes.Text, "draw", text_draw)
    monkeypatch.setattr(shapes._Instanced, "draw", instanced_draw)
    return boxes


def _text_ink(frame, boxes, tol=8) -> np.ndarray:
    """Pixels of the readout's colour inside the glyph boxes."""
    h, w, _ = frame.shape
    mask = np.zeros((h, w), bool)
    for x0, y0, x1, y1 in boxes:
        mask[max(0, int(y0)):min(h, int(np.ceil(y1))), max(0, int(x0)):min(w, int(np.ceil(x1)))] = True
    return mask & (np.abs(frame.astype(int) - TEXT).max(axis=2) <= tol)


def _check(make, t, glyphs) -> None:
    """The annotated frame has text where its glyphs are; the clean one draws no glyph and has none there."""
    plain = make(False)
    try:
        glyphs.clear()
        a = plain.render(t)
        boxes = list(glyphs)
    finally:
        plain.release()
    assert len(boxes) > 20
    ink = _text_ink(a, boxes)
    assert ink.sum() > 30                       # the overlay is there to be left out
    clean = make(True)
    try:
        glyphs.clear()
        b = clean.render(t)
        assert glyphs == []                     # not one glyph
    finally:
        clean.release()
    assert not (ink & (np.abs(b.astype(int) - TEXT).max(axis=2) <= 8)).any()
    assert b.shape == a.shape


@pytest.mark.parametrize("view", ["2d", "3d"])
def test_a_clean_disk_frame_has_no_text(gl, glyphs, view):
    from nbst import load_problem, simulate
    from nbst.cli.render import make_renderer

    p = load_problem("over5")
    tr = simulate(p, p.straight_velocities())
    _check(lambda clean: make_renderer(gl, p, tr, view=view, size=SIZE, labels=True, clean=clean), 0.5, glyphs)


def test_a_clean_5m_throw_frame_has_no_text(gl, glyphs):
    """A still rack and a ball in front of it, in the 5 m scene's own model."""
    import mujoco

    from nbst.models.bowling import pinfall, scene
    from nbst.render.bowling import deck

    model = scene.build_model()
    d = mujoco.MjData(model)
    adr = pinfall.pin_addresses(model)
    ba = int(model.joint("ball_free").qposadr[0])
    q = np.repeat(d.qpos[None], 3, axis=0)
    q[:, ba:ba + 3] = (-2.0, 0.0, scene.BALL_RADIUS)
    motion = deck.Motion(times=np.arange(3) * 1e-3, ball=q[:, ba:ba + 7], pins=q[:, adr[:, None] + np.arange(7)],
                         impact=float("nan"), down=[], model=model)
    throw = {"requested": [1, 2, 4]}
    _check(lambda clean: deck.BowlingRenderer(gl, motion, size=SIZE, camera="both", throw=throw, clean=clean),
           0.001, glyphs)


@pytest.mark.slow
def test_a_clean_lane_frame_has_no_text(gl, glyphs):
    from nbst.models.bowling import lane
    from nbst.render.bowling import lane as bl, throw as bt

    th = bt.record_throw(lane.Delivery(hand="right", board=20, at="foul", angle=2.82, mph=17, rpm=350, rotation=45,
                                       tilt=12), "house")
    _check(lambda clean: bl.LaneRenderer(gl, th, size=SIZE, camera="both", clean=clean), 1.0, glyphs)


@pytest.mark.slow
@pytest.mark.parametrize("camera", ["both", "overhead"])
def test_a_clean_crash_frame_has_no_text_and_the_views_fill_it(gl, glyphs, loaded, camera):
    from nbst.render.crash import video as crash

    _check(lambda clean: crash.CrashRenderer(gl, *loaded, size=SIZE, camera=camera, follow=1, clean=clean),
           loaded[3].duration, glyphs)
    r = crash.CrashRenderer(gl, *loaded, size=SIZE, camera=camera, follow=1, clean=True)
    try:   # no readout column: the views cover the frame
        assert sum(vp[2] * vp[3] for vp in r.panels.values()) == SIZE[0] * SIZE[1]
    finally:
        r.release()
