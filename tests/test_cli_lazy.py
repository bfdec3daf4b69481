"""The parser builds only the command asked for (nbst.cli.main): ``nbst --help`` lists every
command from the modules' ``COMMANDS`` without building their arguments, and the listing and
the parse of a command are the same as the fully built parser's."""
import argparse
import importlib
import subprocess
import sys

import pytest

from nbst.cli.main import COMMAND_MODULES, asked_command, build_parser


def _listing(parser: argparse.ArgumentParser) -> list[tuple[str, str]]:
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return [(a.dest, a.help) for a in sub._choices_actions]


def test_the_lazy_listing_is_the_full_one():
    full = build_parser()
    assert _listing(build_parser(only="")) == _listing(full)
    assert build_parser(only="").format_help() == full.format_help()


@pytest.mark.parametrize("module_name", COMMAND_MODULES)
def test_each_module_declares_the_commands_it_registers(module_name):
    module = importlib.import_module(module_name)
    parser = argparse.ArgumentParser()
    module.register(parser.add_subparsers())
    assert _listing(parser) == list(module.COMMANDS.items())


@pytest.mark.parametrize("argv", [
    ["solve", "diamond-s14", "-o", "x.json", "--seed", "3", "--max-trials", "50"],
    ["render", "diamond-s14", "s.json", "-o", "m.mp4", "--fps", "24"],
    ["bowl", "throw", "--board", "10", "--mph", "17"],
    ["crash", "solve", "t-bone", "-o", "c.json"],
])
def test_a_command_parses_as_under_the_full_parser(argv):
    lazy = build_parser(only=asked_command(argv)).parse_args(argv)
    full = build_parser().parse_args(argv)
    assert vars(lazy) == vars(full)


def test_asked_command_is_the_first_word():
    assert asked_command(["--version"]) == ""
    assert asked_command(["-h", "bowl", "throw"]) == "bowl"
    assert asked_command(["solve", "-o", "x"]) == "solve"


def test_help_builds_no_command_and_loads_no_registry():
    """`nbst --help` imports none of the registry owners that the commands' choices read."""
    heavy = ["nbst.solvers", "nbst.search.variants", "nbst.experiments.runs", "nbst.models.bowling.lane"]
    code = ("import sys\nfrom nbst.cli.main import main\ntry:\n    main(['--help'])\nexcept SystemExit:\n    pass\n"
            f"print([m for m in {heavy!r} if m in sys.modules])")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip().splitlines()[-1] == "[]"
