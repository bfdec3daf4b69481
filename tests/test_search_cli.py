"""``nbst solve``'s progress tells the truth (issue 35, item 4): its last progress line says what the
summary says (trials, best cost, disks on target), for a plain solve, nbst's portfolio, robust mode
(whose written solution is chosen after the search) and the many-body search."""
from __future__ import annotations

import json
import re

import pytest

from nbst.cli import main


def _last_bar_and_summary(err: str):
    lines = [ln for ln in err.splitlines() if ln.strip()]
    bar = [ln for ln in lines if ln.startswith("solve ")]
    summary = [ln for ln in lines if ln.startswith("nbst solve: cost")]
    assert bar and summary, err
    b = re.search(r"([\d,]+)(?: of at most [\d,]+)? trials in ([\d.]+ s).*best cost ([0-9.e+-]+), (\d+)/(\d+) disks "
                  r"on target", bar[-1])
    s = re.search(r"cost ([0-9.e+-]+), (\d+)/(\d+) disks on target .* after ([\d,]+) trials in ([\d.]+ s)", summary[-1])
    assert b and s, (bar[-1], summary[-1])
    return ((int(b.group(1).replace(",", "")), b.group(2), b.group(3), b.group(4)),
            (int(s.group(4).replace(",", "")), s.group(5), s.group(1), s.group(2)))


@pytest.mark.parametrize("argv", [
    ["diamond-s14", "--max-trials", "5000", "--variant", "A"],
    ["over5", "--max-trials", "20000"],  # the portfolio: two islands in turns, one core
    ["over5", "--max-trials", "20000", "--robust"],  # the written solution is the robust choice, not the best
])
def test_the_last_progress_line_is_the_summary(tmp_path, capsys, argv):
    out = tmp_path / "s.json"
    assert main(["solve", *argv, "-o", str(out), "--seed", "2", "--jobs", "1"]) == 0
    bar, summary = _last_bar_and_summary(capsys.readouterr().err)
    assert bar == summary
    d = json.loads(out.read_text())
    assert (summary[0], *summary[2:]) == (d["trials"], f"{d['cost']:.6g}", str(d["order"]))


def test_the_many_body_search_ends_its_bar_at_the_summary(tmp_path, capsys):
    from nbst.planted import planted

    p, _ = planted(80, seed=2)
    f = tmp_path / "p.json"
    f.write_text(json.dumps(p.to_dict()))
    assert main(["solve", str(f), "-o", str(tmp_path / "s.json"), "--seed", "1", "--max-trials", "200",
                 "--jobs", "1"]) == 0
    bar, summary = _last_bar_and_summary(capsys.readouterr().err)
    assert bar == summary
