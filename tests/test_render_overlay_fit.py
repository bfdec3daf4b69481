"""Overlay text at a small frame (issue 46's animator: 320x180): titles, readouts and labels keep to
their panels and to the frame, and no two pieces of text are drawn over each other.

Each still is drawn through the command with ``Text.layout`` (and the disk numbers' ``GlyphRuns``)
watched: every glyph cell it lays out is checked against the frame and against the cells of the other
texts drawn in the same face (a readout's coloured layers fill cells their plain layer leaves blank,
so they never share one; two cells may share their blank margins, a quarter cell, as the numbers of
close pins do) and against every cell of the other faces (a label of one face was drawn over a
readout of another)."""
from __future__ import annotations

import json
import re

import numpy as np
import pytest

from nbst.cli.main import main
from nbst.render.core.textfit import CUT, fit_lines, more_lines

W, H = 320, 180


def test_fit_lines_cuts_what_does_not_fit_and_says_so():
    assert fit_lines(["short", "a line that is too long"], 10, 5) == ["short", "a line t" + CUT]
    assert fit_lines(["trailing    "], 8, 1) == ["trailing"]       # blanks past the edge are not a cut
    out = fit_lines([f"line {k}" for k in range(6)], 30, 3)
    assert out == ["line 0", "line 1", "+4 lines (a larger --size)"]
    assert all(len(s) <= 12 for s in fit_lines(["x" * 40] * 9, 12, 4))
    assert fit_lines(["anything"], 0, 3) == fit_lines(["anything"], 5, 0) == []
    assert fit_lines(["fits"], 4, 1) == ["fits"]                     # nothing cut that fits


def test_the_marker_of_lines_left_out_shortens_whole_words():
    """The animator: at a narrow width the marker itself was cut ("+10 lines (a larger..")."""
    many = [f"line {k}" for k in range(12)]
    assert fit_lines(many, 26, 3)[-1] == "+10 lines" == more_lines(10, 26)       # never "+10 lines (a larger --siz"
    assert fit_lines(many, 27, 3)[-1] == "+10 lines (a larger --size)"
    assert fit_lines(many, 22, 3) == ["line 0", "line 1", "+10 lines"]
    assert fit_lines(many, 9, 3)[-1] == "+10 lines"
    assert fit_lines(many, 8, 3)[-1] == "+10"
    assert fit_lines(many, 3, 2)[-1] == "+11"
    assert fit_lines(many, 2, 2)[-1] == CUT                        # no room for the count: the cut mark
    assert all(len(s) <= c for c in range(1, 30) for s in fit_lines(many, c, 4))


class Cells(list):
    """The glyph cells laid out, (face id, layout call, x, y, cell width, cell height), and each
    ``Text.layout`` call's lines (``texts``: (face id, layout call, lines))."""

    def __init__(self):
        super().__init__()
        self.texts: list = []

    def add(self, face, data, cell) -> int:
        cw, ch = cell
        call = len({c[1] for c in self})
        self.extend((face, call, float(px), float(py), cw, ch) for px, py in data["pos"])
        return call

    def box(self, call) -> tuple[float, float, float, float]:
        """(x0, y0, x1, y1) px around the cells of one layout call."""
        a = np.array([c[2:] for c in self if c[1] == call])
        return a[:, 0].min(), a[:, 1].min(), (a[:, 0] + a[:, 2]).max(), (a[:, 1] + a[:, 3]).max()


@pytest.fixture
def watched(monkeypatch):
    """Every glyph cell laid out by ``Text.layout`` and by the ``GlyphRuns`` of ``Text.numbers`` (disk
    and target numbers), each under its face."""
    from nbst.render.core import shapes

    cells = Cells()
    layout, numbers, runs_layout = shapes.Text.layout, shapes.Text.numbers, shapes.GlyphRuns.layout

    def spy(self, lines, x, y):
        data = layout(self, lines, x, y)
        cells.texts.append((id(self), cells.add(id(self), data, self.cell), list(lines)))
        return data

    def spy_numbers(self, n):
        runs = numbers(self, n)
        runs.watched_face = (id(self), self.cell)
        return runs

    def spy_runs(self, x, y, which=None):
        data = runs_layout(self, x, y, which)
        if getattr(self, "watched_face", None) is not None:
            cells.add(self.watched_face[0], data, self.watched_face[1])
        return data

    monkeypatch.setattr(shapes.Text, "layout", spy)
    monkeypatch.setattr(shapes.Text, "numbers", spy_numbers)
    monkeypatch.setattr(shapes.GlyphRuns, "layout", spy_runs)
    return cells


def _check(cells, W=W, H=H, *, across=True, halo=0):
    """Every cell inside the frame (``halo`` px in from its edges), and no two texts drawn over each
    other: within a face, cells of different layout calls; ``across``: cells of different faces too
    (a cell's last quarter is its blank margin: labels on close pins may share it)."""
    assert cells
    a = np.array([c[2:] for c in cells])
    assert (a[:, 0] >= halo - 0.5).all() and (a[:, 0] + a[:, 2] <= W - halo + 0.5).all(), "text runs off the frame's side"
    assert (a[:, 1] >= halo - 0.5).all() and (a[:, 1] + a[:, 3] <= H - halo + 0.5).all(), "text runs off the frame's foot"
    face = np.array([c[0] for c in cells])
    call = np.array([c[1] for c in cells])
    x, y, cw, ch = a.T
    for i in range(len(a) - 1):
        j = slice(i + 1, None)
        same = (face[j] == face[i]) & (call[j] != call[i])
        clash = same & (np.abs(x[j] - x[i]) < 0.75 * cw[i]) & (np.abs(y[j] - y[i]) < 0.75 * ch[i])
        assert not clash.any(), ("two texts drawn over each other", a[i], a[j][clash][:3])
        if across:
            other = face[j] != face[i]
            clash = (other & (x[j] < x[i] + 0.75 * cw[i]) & (x[i] < x[j] + 0.75 * cw[j])
                     & (y[j] < y[i] + 0.75 * ch[i]) & (y[i] < y[j] + 0.75 * ch[j]))
            assert not clash.any(), ("texts of two faces drawn over each other", a[i], a[j][clash][:3])


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


@pytest.fixture(scope="module")
def worlds_dir(tmp_path_factory):
    return tmp_path_factory.mktemp("worlds")


@pytest.fixture(scope="module")
def foul_line_throw(worlds_dir):
    import test_export_gltf as worlds

    return worlds._lane(worlds_dir)


@pytest.mark.parametrize("camera,size", [("both", (200, 120)), ("overhead", (200, 120)), ("deck", (W, H))])
def test_a_foul_line_readout_is_never_drawn_over_the_labels(camera, size, foul_line_throw, tmp_path, watched):
    """The animator: at 200x120 the readout lay over the overhead view's "60 ft / 50 ft" ticks,
    "pins" and the pin numbers (the small face), and in the deck view at 320x180 a pin's number read
    inside a readout line ("house (740 ft2 22 ml)"). Labels that do not fit clear of it are left out."""
    argv = ["bowl", "replay", str(foul_line_throw), "--still", str(tmp_path / "s.png"), "--size", "%dx%d" % size,
            "--camera", camera]
    assert main(argv) == 0
    _check(watched, *size)


@pytest.fixture(scope="module")
def dominoes(worlds_dir):
    """The dominoes scene's solution on a tiny budget (met or not: either is drawn): 11 fated bodies."""
    from nbst.scene import solve
    from nbst.scene.solution import solution_dict

    f = worlds_dir / "dominoes.json"
    f.write_text(json.dumps(solution_dict(solve(None, "dominoes", seed=1, max_rollouts=2))))
    return f


@pytest.mark.parametrize("size", [(W, H), (200, 120)])
def test_a_scenes_readout_too_tall_ends_in_the_marker(size, dominoes, tmp_path, watched):
    """The animator: the dominoes' readout ran off the frame's foot with no word (at 200x120
    only d1..d6 of 11 bodies), and the first touches' labels ("d6-d7 0.56 s") ran to the frame's edge
    and over each other. Now the readout ends in "+N lines" and every label keeps inside the frame,
    its halo too, clear of the readout and the other labels."""
    doc = json.loads(dominoes.read_text())
    end = doc["nstep"] * doc["timestep"]
    argv = ["render", str(dominoes), "--still", f"{end:g}", "-o", str(tmp_path / "d.png"), "--size", "%dx%d" % size,
            "-q"]
    assert main(argv) == 0
    _check(watched, *size, halo=1)
    readout = next(lines for _, _, lines in watched.texts if lines and lines[0] == "dominoes.xml")
    assert re.fullmatch(r"\+\d+ lines( \(a larger --size\))?", readout[-1]), readout


def test_an_odd_size_mp4_of_a_5m_throw_is_refused_before_any_work(worlds_dir, tmp_path, capsys, monkeypatch):
    """The animator: ``--size 321x180`` for a 5 m throw's MP4 was refused only by the encoder,
    after the throw was read and a frame drawn, with a progress line after the error. Like the other
    worlds: one line, exit 2, before the throw file is read, nothing written."""
    import test_export_gltf as worlds

    from nbst.cli import render as cli

    shot = worlds._deck(worlds_dir)

    def read(*a, **k):
        raise AssertionError("the throw was read before the size was refused")

    monkeypatch.setattr(cli, "load_motion", read)
    out = tmp_path / "a.mp4"
    assert main(["render", str(shot), "-o", str(out), "--size", "321x180"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--size 321x180" in err[0] and "even width and height" in err[0], err
    assert not out.exists()


@pytest.mark.parametrize("n, view", [(1000, "2d"), (200, "2d"), (200, "3d")])
def test_forced_disk_numbers_keep_out_of_the_readout(n, view, tmp_path, watched):
    """The animator: ``--labels`` at 200x120 on 1,000 disks drew "105" across the readout's title
    (a small frame's readout overlaps the box's corner; with 200 disks a "1" under its last letters).
    No number, the disks' or the targets', in the readout's box."""
    p, sol = tmp_path / "p.json", tmp_path / "sol.json"
    assert main(["generate", "--planted", str(n), "--radius", "15", "--seed", "1", "-o", str(p), "--solution",
                 str(sol), "-q"]) == 0
    watched.clear()
    assert main(["render", str(p), str(sol), "--still", "5", "-o", str(tmp_path / "x.png"), "--size", "200x120",
                 "--labels", "--view", view, "-q"]) == 0
    _check(watched, 200, 120)
    face, call = next((f, c) for f, c, lines in watched.texts if lines and lines[0].startswith("planted-"))
    x0, y0, x1, y1 = watched.box(call)
    inside = [c for c in watched if c[0] != face and c[2] < x1 and x0 < c[2] + c[4] and c[3] < y1 and y0 < c[3] + c[5]]
    assert not inside, ("a number in the readout's box", (x0, y0, x1, y1), inside[:3])


@pytest.mark.parametrize("view", ["2d", "3d"])
def test_forced_numbers_on_small_disks_never_run_together(view, tmp_path, monkeypatch):
    """Forced ``--labels`` at 200x120 on diamond-s14 read "67" for disks 6 and 7: two numbers a pixel
    apart read as one. Every two numbers drawn, on or beside their disks, are half a character apart
    at least (docs/render.md: "Numbers never run together")."""
    from nbst.render import scene2d

    seen = []
    draw = scene2d.Labels.draw

    def spy(self, size, centers_px, drawn=None):
        d = self.drawn(centers_px) if drawn is None else drawn
        seen.append((self._all_boxes(centers_px)[d], 0.5 * self.text.cell[0]))
        return draw(self, size, centers_px, drawn)

    monkeypatch.setattr(scene2d.Labels, "draw", spy)
    sol = tmp_path / "sol.json"
    assert main(["solve", "diamond-s14", "--seed", "1", "-o", str(sol), "-q", "--max-trials", "200"]) in (0, 1)
    for t in ("0", "1", "2", "3", "4", "5"):
        assert main(["render", "diamond-s14", str(sol), "--still", t, "-o", str(tmp_path / "x.png"), "--size",
                     "200x120", "--labels", "--view", view, "-q"]) == 0
    assert len(seen) == 6
    for boxes, gap in seen:
        for i in range(len(boxes)):
            for j in range(i + 1, len(boxes)):
                a, b = boxes[i], boxes[j]
                apart = max(b[0] - a[2], a[0] - b[2], b[1] - a[3], a[1] - b[3])
                assert apart >= gap - 1e-6, (i, j, a, b, gap)
