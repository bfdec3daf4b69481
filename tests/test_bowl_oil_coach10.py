"""A coach's audit of oil sheets (coach10): ``--oil`` takes a sheet whatever its suffix and refuses a
special file in one line; a missing field says "missing" with the domain the value check uses; a
board range written right to left is refused (docs/formats.md: boards from the first to the last,
as the machine lays them, ``2L-2R``)."""
from __future__ import annotations

import argparse
import json
import os

import numpy as np
import pytest

from nbst.models.bowling.lane import oil


def _row(boards="2L-2R", loads=2, ul=50, start=0, end=10, **kw):
    return {"pass": "forward", "boards": boards, "loads": loads, "ul": ul, "speed": 14, "start_ft": start,
            "end_ft": end, **kw}


def _buff(**kw):
    return {"pass": "reverse", "buff": True, "start_ft": 42, "end_ft": 30, **kw}


def _sheet(rows, name="mine"):
    return {"format": oil.FORMAT, "version": 2, "name": name, "description": "coach10", "rows": rows}


def _write(path, doc):
    path.write_text(json.dumps(doc))
    return path


def _ml_per_board(pat) -> np.ndarray:
    """The oil (ml) on each of the lane's boards, index 0 = board 1 (the right-hander's right edge)."""
    return pat.grid().sum(axis=1) * oil.CELL_AREA


def _expect(lo, hi, ml):
    """``ml`` on each of the lane's boards lo..hi (1 = the right edge), none elsewhere."""
    e = np.zeros(oil.N_BOARDS)
    e[lo - 1:hi] = ml
    return e


def _refused(capsys, argv, out, *words):
    """``nbst`` ``argv`` ends at exit 2 with one line holding ``words``, and ``out`` is not written."""
    from nbst.cli import main

    with pytest.raises(SystemExit) as e:
        main([str(a) for a in argv])
    err = capsys.readouterr().err
    assert e.value.code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    for w in words:
        assert w in lines[0], (w, lines[0])
    assert not os.path.lexists(out)
    return lines[0]


# --------------------------------------------------------------------------- 1: --oil FILE, any suffix


def test_a_sheet_without_the_json_suffix_is_read_as_a_sheet(tmp_path, monkeypatch, capsys):
    """`--oil mine_noext` and `--oil ./mine_noext` (an existing valid sheet) said "unknown oil pattern"."""
    from nbst.cli import main

    monkeypatch.chdir(tmp_path)
    _write(tmp_path / "mine_noext", _sheet([_row("2L-2R", 3, 50, 0, 38)]))
    assert main(["bowl", "throw", "--oil", "mine_noext", "-o", "t.json"]) == 0
    capsys.readouterr()
    assert json.loads((tmp_path / "t.json").read_text())["oil"] == "mine"   # the sheet's name: thrown on it
    for v in ("./mine_noext", str(tmp_path / "mine_noext")):
        got = _ml_per_board(oil.pattern(v))   # 3 loads x 50 ul on boards 2L-2R (lane boards 2..38)
        assert np.allclose(got, _expect(2, 38, 0.15), rtol=1e-9, atol=1e-12), got


def test_a_file_named_like_a_shipped_pattern_is_that_file_and_the_default_stays_shipped(tmp_path, monkeypatch):
    """The user typed a path: a file `flat` in the folder is that sheet, not the shipped `flat`; a file
    `house` there does not replace the default pattern of a throw given no --oil."""
    from nbst.cli.bowl.args import oil_flag

    monkeypatch.chdir(tmp_path)
    _write(tmp_path / "flat", _sheet([_row("7L-7R", 4, 25, 0, 20)]))
    (tmp_path / "house").write_text("not a sheet")
    p = argparse.ArgumentParser()
    oil_flag(p)
    pat = oil.pattern(p.parse_args(["--oil", "flat"]).oil)
    assert pat.name == "mine"
    assert np.allclose(_ml_per_board(pat), _expect(7, 33, 0.1), rtol=1e-9, atol=1e-12)
    assert oil.pattern(p.parse_args([]).oil) is oil.PATTERNS["house"]
    assert oil.pattern(p.parse_args(["--oil", "sport"]).oil) is oil.PATTERNS["sport"]   # no such path: the name


@pytest.mark.parametrize("kind", ["device", "fifo", "folder", "unreadable", "missing"])
def test_a_special_unreadable_or_missing_oil_file_is_refused_in_one_line(tmp_path, monkeypatch, capsys, kind):
    """`--oil /dev/null` (and a FIFO, a folder, an unreadable file, none of them *.json) said "unknown
    oil pattern"; `./gone` (written as a path) said so too."""
    monkeypatch.chdir(tmp_path)
    if kind == "device":
        path, why = "/dev/null", "not a regular file"
    elif kind == "fifo":
        os.mkfifo(tmp_path / "pipe")
        path, why = "pipe", "not a regular file"
    elif kind == "folder":
        (tmp_path / "adir").mkdir()
        path, why = "adir", "is a directory"
    elif kind == "unreadable":   # chmod 000 does not stop root: refuse the open itself
        _write(tmp_path / "locked", _sheet([_row()]))
        real_open = os.open

        def deny(p, *a, **kw):
            if os.path.basename(os.fspath(p)) == "locked":
                raise PermissionError(13, "Permission denied", os.fspath(p))
            return real_open(p, *a, **kw)

        monkeypatch.setattr(os, "open", deny)
        path, why = "locked", "permission denied"
    else:
        path, why = "./gone", "no such file"
    line = _refused(capsys, ["bowl", "throw", "--oil", path, "-o", tmp_path / "t.json"], tmp_path / "t.json",
                    "--oil", os.path.basename(path), why)
    assert "unknown oil pattern" not in line


# --------------------------------------------------------------------------- 2: missing says missing, one domain


@pytest.mark.parametrize("field, bad, domain", [
    ("loads", 0, "(0, 100]"), ("ul", 0, "(0, 500]"), ("speed", 0, "[1, 60]"), ("start_ft", -1, "[0, 59]"),
    ("end_ft", 99, "[0, 59]"),
])
def test_a_missing_number_says_missing_with_the_domain_the_value_check_uses(tmp_path, capsys, field, bad, domain):
    """A missing rows[0].ul said "missing (a number in [0, 500])" but 0 was refused as needing (0, 500]."""
    out = tmp_path / "t.json"
    row = _row()
    del row[field]
    gone = _refused(capsys, ["bowl", "throw", "--oil", _write(tmp_path / "miss.json", _sheet([row])), "-o", out],
                    out, "miss.json: rows[0]." + field + ": missing (a number in " + domain + ")")
    row[field] = bad
    wrong = _refused(capsys, ["bowl", "throw", "--oil", _write(tmp_path / "bad.json", _sheet([row])), "-o", out],
                     out, "bad.json: rows[0]." + field + ": must be in " + domain + ", got")
    row[field] = "3"
    _refused(capsys, ["bowl", "throw", "--oil", _write(tmp_path / "str.json", _sheet([row])), "-o", out], out,
             "str.json: rows[0]." + field + ": must be a number in " + domain + ", got '3'")
    assert "got None" not in gone and "missing" not in wrong


def _without(row, key):
    return {k: v for k, v in row.items() if k != key}


@pytest.mark.parametrize("rows, where, says", [
    ([_without(_row(), "pass")], "rows[0].pass", "missing ('forward' or 'reverse')"),
    ([_without(_row(), "boards")], "rows[0].boards", "missing ('FROM-TO'"),
    ([_row(), _without(_buff(), "pass")], "rows[1].pass", "missing ('forward' or 'reverse')"),
    ([_row(), _without(_buff(), "start_ft")], "rows[1].start_ft", "missing (a number in [0, 59])"),
    ([_row(), _without(_buff(), "end_ft")], "rows[1].end_ft", "missing (a number in [0, 59])"),
])
def test_a_missing_pass_boards_or_buff_field_says_missing(tmp_path, capsys, rows, where, says):
    """A missing rows[0].pass said "must be 'forward' or 'reverse', got None"."""
    out = tmp_path / "t.json"
    line = _refused(capsys, ["bowl", "throw", "--oil", _write(tmp_path / "miss.json", _sheet(rows)), "-o", out],
                    out, f"miss.json: {where}: {says}")
    assert "got None" not in line


# --------------------------------------------------------------------------- 3: boards run left to right


@pytest.mark.parametrize("boards, fix", [("30L-10L", "10L-30L"), ("2R-2L", "2L-2R"), ("10-20", "20-10")])
def test_a_board_range_written_right_to_left_is_refused(tmp_path, capsys, boards, fix):
    """`30L-10L` was read as boards 10-30 and `2R-2L` as 2L-2R; the sheet writes its boards left to right."""
    out = tmp_path / "t.json"
    _refused(capsys, ["bowl", "throw", "--oil", _write(tmp_path / "rev.json", _sheet([_row(boards)])), "-o", out],
             out, "rev.json: rows[0].boards: must run left to right", repr(boards), repr(fix))


@pytest.mark.parametrize("boards, lo, hi", [("2L-15L", 25, 38), ("10L-30L", 10, 30), ("5L-5L", 35, 35),
                                            ("20-10", 10, 20), ("2L-2R", 2, 38)])
def test_a_left_to_right_range_lays_its_oil_on_its_boards(tmp_path, boards, lo, hi):
    pat = oil.load_pattern(_write(tmp_path / "ok", _sheet([_row(boards, 3, 40, 0, 30)])))
    assert np.allclose(_ml_per_board(pat), _expect(lo, hi, 0.12), rtol=1e-9, atol=1e-12), boards
    assert pat.volume_ml == pytest.approx(0.12 * (hi - lo + 1), rel=1e-9)
