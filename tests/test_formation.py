"""Formations (nbst generate --targets-from, issue 21): disks that end forming a text or an
image by straight shots that never touch, as the pairwise-swap argument of nbst.formation says."""
from __future__ import annotations

import json

import numpy as np
import pytest

from nbst import load_problem, simulate
from nbst.cli.main import main
from nbst.formation import (MAX_FORMATION_DISKS, assign, formation, is_image_source, spacing)


def _pairs_monotone(X, Y) -> float:
    """The least (x_i - x_j) . (y_i - y_j) over all pairs i < j."""
    a = X[:, None, :] - X[None, :, :]
    b = Y[:, None, :] - Y[None, :, :]
    d = (a * b).sum(axis=2)
    return float(d[np.triu_indices(len(X), 1)].min())


def _min_dist(P) -> float:
    d = np.hypot(*(P[:, None, :] - P[None, :, :]).transpose(2, 0, 1))
    return float(d[np.triu_indices(len(P), 1)].min())


def _check_exact_and_untouched(p):
    """The straight shots simulated exactly: no contact, no wall, every disk on its target."""
    v = (p.target - p.start) / p.t_final
    tr = simulate(p, v)
    assert not tr.truncated and tr.n_disk_disk == 0 and tr.n_wall == 0
    assert np.abs(tr.final_positions - p.target).max() <= 1e-9 * max(p.box)
    s = spacing(p.radius[0])
    assert _min_dist(p.start) >= s * (1 - 1e-12) and _min_dist(p.target) >= s * (1 - 1e-12)
    assert _pairs_monotone(p.start, p.target) >= 0.0
    assert p.cueable.all() and (p.radius == p.radius[0]).all()


def _write(tmp_path, name, argv):
    out = tmp_path / f"{name}.json"
    assert main(["generate", *argv, "-o", str(out), "--solution", str(tmp_path / f"{name}-sol.json"), "-q"]) == 0
    return load_problem(str(out)), out


@pytest.mark.parametrize("start", ["grid", "random"])
def test_text_formation_of_200_disks_is_exact_and_collision_free(tmp_path, start):
    p, out = _write(tmp_path, "t", ["--targets-from", "Hi!", "--disks", "200", "--start", start, "--seed", "4"])
    assert p.n == 200 and p.name == "text-hi"
    _check_exact_and_untouched(p)
    raw = json.loads(out.read_text())
    assert raw["formation"] == {**raw["formation"], "source": "text", "text": "Hi!", "start": start, "seed": 4,
                                "disks": 200}
    assert "Hi!" in raw["description"] and "--targets-from" in raw["description"]
    # the targets spell the text: they are spread over the box's width, not piled up
    assert np.ptp(p.target[:, 0]) > 0.6 * p.width
    assert p.target_radius == pytest.approx(spacing(15.0) / 2)


def test_image_formation_from_a_png(tmp_path):
    import imageio.v3 as iio

    img = np.full((40, 60, 3), 255, np.uint8)
    img[5:35, 5:15] = 0        # a thick "L": a bar ...
    img[25:35, 5:50] = 30      # ... and a foot (dark grey is dark too)
    png = tmp_path / "ell.png"
    iio.imwrite(png, img)
    p, _ = _write(tmp_path, "i", ["--targets-from", str(png), "--disks", "60", "--seed", "2", "--radius", "4"])
    assert p.n == 60 and p.name == "image-ell" and p.raw["formation"]["image"] == "ell.png"
    _check_exact_and_untouched(p)
    # every target sits on the L: left bar (x small) or the foot (y small), in picture coordinates
    W, H = p.box
    u = (p.target[:, 0] - p.target[:, 0].min()) / np.ptp(p.target[:, 0])
    w = (p.target[:, 1] - p.target[:, 1].min()) / np.ptp(p.target[:, 1])
    assert np.all((u < 0.3) | (w < 0.4))


def test_swaps_leave_every_pair_monotone_and_lower_the_total():
    rng = np.random.default_rng(0)
    X, Y = rng.uniform(0, 100, (300, 2)), rng.uniform(0, 100, (300, 2))
    perm, passes, swaps = assign(X, Y)
    assert sorted(perm) == list(range(300)) and passes >= 1 and swaps > 0
    assert _pairs_monotone(X, Y[perm]) >= 0.0
    straight = ((X - Y) ** 2).sum()
    assert ((X - Y[perm]) ** 2).sum() < straight


def test_same_seed_same_problem_and_a_fixed_box_is_used():
    a, va, _ = formation("ok", 50, seed=9, start="random")
    b, vb, _ = formation("ok", 50, seed=9, start="random")
    assert a.raw == b.raw and np.array_equal(va, vb)
    c, _, _ = formation("ok", 50, seed=9, box=(3000.0, 2000.0))
    assert c.box == (3000.0, 2000.0) and c.raw["formation"]["box"] == "given"
    _check_exact_and_untouched(c)


def test_source_rule():
    assert is_image_source("a.PNG") and is_image_source("x/y.tiff") and not is_image_source("hello.world")
    from nbst.cli.generate import FORMATION_DISKS

    assert FORMATION_DISKS.hi == MAX_FORMATION_DISKS  # the CLI's bound (kept light) says the same


def _refused(tmp_path, capsys, argv, *words):
    out = tmp_path / "x.json"
    assert main(["generate", *argv, "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    for w in words:
        assert w in err, err
    assert not out.exists()
    return err


def test_bad_sources_exit_2_with_one_line(tmp_path, capsys, monkeypatch):
    missing = tmp_path / "nope.png"
    _refused(tmp_path, capsys, ["--targets-from", str(missing)], "nope.png", "no such file")
    junk = tmp_path / "junk.jpg"
    junk.write_bytes(b"this is not a jpeg at all")
    _refused(tmp_path, capsys, ["--targets-from", str(junk)], "junk.jpg", "cannot be read as a JPG image")
    (tmp_path / "dir.png").mkdir()
    _refused(tmp_path, capsys, ["--targets-from", str(tmp_path / "dir.png")], "dir.png", "directory")
    _refused(tmp_path, capsys, ["--targets-from", "   "], "text is empty")
    _refused(tmp_path, capsys, ["--targets-from", "nbst", "--disks", "500", "--box", "600", "300"],
             "holds at most", "asked for 500", "larger box")
    _refused(tmp_path, capsys, ["--targets-from", "nbst", "--noncue", "2"], "--noncue applies to --planted only")
    import imageio.v3 as iio

    import nbst.pictures as pictures

    white = tmp_path / "white.png"
    iio.imwrite(white, np.full((8, 8), 255, np.uint8))
    _refused(tmp_path, capsys, ["--targets-from", str(white)], "white.png", "no dark pixels")
    monkeypatch.setattr(pictures, "MAX_IMAGE_PIXELS", 50)  # a picture larger than the cap, refused from its header
    _refused(tmp_path, capsys, ["--targets-from", str(white)], "white.png", "8x8 picture", "at most 50 pixels")


def test_planted_and_targets_from_are_exclusive_and_one_is_required(tmp_path, capsys):
    for argv in (["--planted", "3", "--targets-from", "x"], []):
        with pytest.raises(SystemExit) as e:
            main(["generate", *argv, "-o", str(tmp_path / "x.json")])
        assert e.value.code == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and ("not allowed with" in err or "required" in err), err


def test_cli_progress_names_the_swap_passes_and_quiet_silences_it(tmp_path, capsys, monkeypatch):
    import nbst.cli.generate as g

    monkeypatch.setattr(g, "LONG_STAGE_S", 0.0)
    out = tmp_path / "f.json"
    assert main(["generate", "--targets-from", "ab", "--disks", "40", "--seed", "1", "-o", str(out)]) == 0
    said = capsys.readouterr()
    assert "assigning targets by pairwise swaps:" in said.err and "sweeps" in said.err, said.err
    assert said.out.startswith(f"nbst generate: wrote {out}: 40 disks forming the text 'ab'")
    assert main(["generate", "--targets-from", "ab", "--disks", "40", "--seed", "1", "-o", str(out), "-q"]) == 0
    said = capsys.readouterr()
    assert said.out == "" and said.err == ""


# --------------------------------------------------------------------------- hostile sources (issue 35)

@pytest.mark.parametrize("shape", [(1, 2_000_000), (2_000_000, 1)])
def test_a_picture_too_thin_for_the_disks_is_refused_with_bounded_work(tmp_path, capsys, shape):
    """A 1 x 2,000,000 line ran for over a minute at 420 MB: the target lattice's spacing shrank
    below a pixel and its candidates grew without bound. The lattice is bounded (MAX_LATTICE_POINTS
    candidates, MIN_LATTICE_PX apart), the box by the radius floor: one line, exit 2."""
    import imageio.v3 as iio

    png = tmp_path / "line.png"
    iio.imwrite(png, np.zeros(shape, np.uint8))
    for n in (200, 20_000):
        rc = main(["generate", "--targets-from", str(png), "--disks", str(n), "--seed", "1", "-q",
                   "-o", str(tmp_path / "p.json")])
        err = capsys.readouterr().err
        # a one-pixel line: its box would be over a million radii long
        assert rc == 2 and err.count("\n") == 1 and "Traceback" not in err and "picture" in err, err


def test_the_target_lattice_never_lays_more_than_its_bound():
    from nbst import pictures

    mask = np.ones((1, 5_000_000), bool)  # holds 5,000 targets only at ~2 px: 2.3 million candidates
    assert pictures.lattice_size(mask.shape, 2.1) > pictures.MAX_LATTICE_POINTS
    with pytest.raises(pictures.FormationError, match="too thin"):
        pictures.lattice_for(mask, 5_000)
    with pytest.raises(pictures.FormationError, match="at least 1 pixel apart"):
        pictures.lattice_for(np.ones((4, 4), bool), 100)


@pytest.mark.parametrize("name,exists,words", [("logo.svg", True, "SVG picture"), ("drawing.pdf", False, "PDF"),
                                               ("notes.txt", True, "existing file")])
def test_a_file_that_is_not_an_image_nbst_reads_is_not_drawn_as_its_name(tmp_path, capsys, monkeypatch, name,
                                                                          exists, words):
    monkeypatch.chdir(tmp_path)
    if exists:
        (tmp_path / name).write_text("<svg xmlns='http://www.w3.org/2000/svg'/>")
    assert main(["generate", "--targets-from", name, "--disks", "20", "-o", "p.json", "-q"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and words in err and name in err, err
    assert main(["generate", "--targets-from", "nbst", "--disks", "20", "-o", "p.json", "-q"]) == 0  # a word is text


def test_a_text_that_is_not_printable_utf8_is_one_line(tmp_path):
    """Invalid UTF-8 in argv reaches Python as lone surrogates (matplotlib's TypeError before);
    control characters are refused as in every text field nbst reads."""
    import os
    import subprocess
    import sys

    for text in (b"ab\xff\xfecd", b"a\x1b[31mred", b"a\x01b"):
        r = subprocess.run([os.fsencode(sys.executable), b"-m", b"nbst.cli", b"generate", b"--targets-from", text,
                            b"--disks", b"20", b"-o", os.fsencode(tmp_path / "p.json")],
                           capture_output=True, timeout=120)
        err = r.stderr.decode("utf-8", "replace")
        assert r.returncode == 2 and err.count("\n") == 1 and "Traceback" not in err, err
        assert "UTF-8" in err or "control character" in err, err
    assert not (tmp_path / "p.json").exists()
