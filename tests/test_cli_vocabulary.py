"""One voice on the command line: usage errors exit 2 with one line, help says what the
tools do."""
import pytest

from nbst.cli import main


def test_problems_name_shows_it_with_or_without_show(capsys):
    assert main(["problems", "over5"]) == 0
    a = capsys.readouterr().out
    assert main(["problems", "show", "over5"]) == 0
    assert capsys.readouterr().out == a and '"name": "over5"' in a


@pytest.mark.parametrize("argv", [["problems", "show"], ["problems", "over5", "diamond-s14"]])
def test_problems_usage_errors_exit_2_in_one_line(argv, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("nbst problems")


def test_mjcf_help_says_full_precision(capsys):
    with pytest.raises(SystemExit):
        main(["mjcf", "--help"])
    out = " ".join(capsys.readouterr().out.split())
    assert "full double precision" in out and "6 significant" not in out
