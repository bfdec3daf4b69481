"""Overlay text at a small frame (issue 46's animator: 320x180): titles, readouts and labels keep to
their panels and to the frame, and no two pieces of text are drawn over each other.

Each still is drawn through the command with ``Text.layout`` watched: every glyph cell it lays out
is checked against the frame and against the cells of the other texts drawn in the same face (a
readout's coloured layers fill cells their plain layer leaves blank, so they never share one; two
cells may share their blank margins, a quarter cell, as the numbers of close pins do)."""
from __future__ import annotations

import numpy as np
import pytest

from nbst.cli.main import main
from nbst.render.core.textfit import CUT, fit_lines

W, H = 320, 180


def test_fit_lines_cuts_what_does_not_fit_and_says_so():
    assert fit_lines(["short", "a line that is too long"], 10, 5) == ["short", "a line t" + CUT]
    assert fit_lines(["trailing    "], 8, 1) == ["trailing"]       # blanks past the edge are not a cut
    out = fit_lines([f"line {k}" for k in range(6)], 30, 3)
    assert out == ["line 0", "line 1", "+4 lines (a larger --size)"]
    assert all(len(s) <= 12 for s in fit_lines(["x" * 40] * 9, 12, 4))
    assert fit_lines(["anything"], 0, 3) == fit_lines(["anything"], 5, 0) == []
    assert fit_lines(["fits"], 4, 1) == ["fits"]                     # nothing cut that fits


@pytest.fixture
def watched(monkeypatch):
    """Every glyph cell laid out: (face id, layout call, x, y, cell width, cell height)."""
    from nbst.render.core import shapes

    cells: list = []
    layout = shapes.Text.layout

    def spy(self, lines, x, y):
        data = layout(self, lines, x, y)
        cw, ch = self.cell
        call = len({c[1] for c in cells})
        cells.extend((id(self), call, float(px), float(py), cw, ch) for px, py in data["pos"])
        return data

    monkeypatch.setattr(shapes.Text, "layout", spy)
    return cells


def _check(cells, W=W, H=H):
    assert cells
    a = np.array([c[2:] for c in cells])
    assert (a[:, 0] >= -0.5).all() and (a[:, 0] + a[:, 2] <= W + 0.5).all(), "text runs off the frame's side"
    assert (a[:, 1] >= -0.5).all() and (a[:, 1] + a[:, 3] <= H + 0.5).all(), "text runs off the frame's foot"
    for face in {c[0] for c in cells}:
        mine = [c for c in cells if c[0] == face]
        for i, (_, call, x, y, cw, ch) in enumerate(mine):
            for _, call2, x2, y2, _, _ in mine[i + 1:]:
                if call2 != call:
                    # a cell's last quarter is its blank margin: labels on close pins may share it
                    assert abs(x - x2) >= 0.75 * cw or abs(y - y2) >= 0.75 * ch, "two texts drawn over each other"


@pytest.mark.parametrize("kind,size", [("deck", (W, H)), ("crash", (W, H)), ("crash", (200, 120))])
def test_small_frames_keep_text_apart_and_inside(kind, size, tmp_path, watched):
    import test_export_gltf as worlds

    src = getattr(worlds, f"_{kind}")(tmp_path)
    argv = ["render", str(src), "-o", str(tmp_path / "s.png"), "--still", "1.0", "--size", "%dx%d" % size, "-q"]
    if kind == "crash":
        argv += ["--camera", "both"]
    assert main(argv) == 0
    _check(watched, *size)


@pytest.mark.slow
def test_a_small_foul_line_throw_keeps_text_apart_and_inside(tmp_path, watched):
    import test_export_gltf as worlds

    src = worlds._lane(tmp_path)
    assert main(["bowl", "replay", str(src), "--still", str(tmp_path / "s.png"), "--size", f"{W}x{H}"]) == 0
    _check(watched)
