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


def _subcommands(parser=None, prefix=()):
    import argparse

    from nbst.cli.main import build_parser

    parser = parser or build_parser()
    found = False
    for a in parser._actions:
        if isinstance(a, argparse._SubParsersAction):
            found = True
            for name, sp in a.choices.items():
                yield from _subcommands(sp, prefix + (name,))
    if not found and prefix:
        yield prefix, parser


def _visible(parser):
    import argparse

    return {o: a for a in parser._actions if a.help != argparse.SUPPRESS for o in a.option_strings}


OLD = {"--out": "--out-dir", "--report": "--out-dir", "--dir": "--out-dir", "--workers": "--jobs",
       "--trials": "--max-trials"}


def test_one_name_per_idea_across_every_subcommand():
    seen = 0
    for cmd, p in _subcommands():
        opts = _visible(p)
        assert not set(opts) & set(OLD), f"nbst {' '.join(cmd)} shows an old spelling"
        if "--seed" in opts:
            h = opts["--seed"].help
            # a seed's default is said: 1, drawn and recorded, or the one the input file records
            assert "default 1" in h or "drawn at random and recorded" in h or "the solution's seed" in h, cmd
        seen += 1
    assert seen >= 14


@pytest.mark.parametrize("cmd", [("solve",), ("experiment", "curves"), ("experiment", "ablation"),
                                 ("experiment", "compare"), ("validate",), ("gallery",), ("bowl", "solve"),
                                 ("bowl", "atlas"), ("render",), ("plot", "problem"), ("plot", "trajectories")])
def test_every_command_with_progress_or_a_summary_has_q(cmd):
    p = dict(_subcommands())[cmd]
    assert {"-q", "--quiet"} <= set(_visible(p)), cmd


@pytest.mark.parametrize("argv, dest, value, new", [
    (["experiment", "curves", "over5", "--out", "D"], "out", "D", "--out-dir"),
    (["experiment", "curves", "over5", "--workers", "3"], "workers", 3, "--jobs"),
    (["experiment", "ablation", "over5", "--trials", "500"], "trials", 500, "--max-trials"),
    (["validate", "over5", "s.json", "--report", "R"], "report", "R", "--out-dir"),
    (["gallery", "--dir", "G"], "dir", "G", "--out-dir"),
    (["bowl", "atlas", "--out", "A"], "out", "A", "--out-dir"),
])
def test_old_spellings_still_work_with_a_note(argv, dest, value, new, capsys):
    from nbst.cli.main import build_parser

    args = build_parser().parse_args(argv)
    assert getattr(args, dest) == value
    err = capsys.readouterr().err
    assert f"is deprecated; use {new}" in err and len(err.strip().splitlines()) == 1
    new_argv = [new if a == argv[-2] else a for a in argv]
    assert getattr(build_parser().parse_args(new_argv), dest) == value


@pytest.mark.parametrize("kind, what", [("nbst-bowling-shot", "a bowling throw file"),
                                        ("nbst-bowling-atlas", "an atlas of bowling throws")])
def test_a_bowling_file_given_as_a_problem_says_what_it_is(kind, what, tmp_path):
    import json

    from nbst.problem import ProblemError, load_problem

    f = tmp_path / "shot.json"
    f.write_text(json.dumps({"kind": kind, "scene": "scene.xml"}))
    with pytest.raises(ProblemError, match=f"kind: this is {what}, not a problem"):
        load_problem(str(f))


def test_descriptions_and_epilogs_print_percent_signs_once():
    """argparse expands %-escapes in argument help only: a description or epilog says "%" as
    written, so a "%%" there prints doubled in --help."""
    bad = [" ".join(cmd) for cmd, p in _subcommands() if "%%" in (p.description or "") + (p.epilog or "")]
    assert not bad, f"'%%' in the description of: {bad}"
