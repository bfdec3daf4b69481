"""The ``nbst`` command line.

Exit codes: 0 success, 1 a check failed (e.g. ``validate --strict``), 2 bad input
or usage (one line on stderr, never a traceback), 130 interrupted.

Each feature registers its own subcommands: a module listed in ``COMMAND_MODULES``
defines ``COMMANDS`` (its top-level command names and their help lines) and
``register(subparsers)``, which adds parsers whose ``func(args) -> int`` does the work.
Registration must stay light (no mujoco/moderngl/numba import): heavy imports go
inside ``func``. A run builds the arguments of the command asked for only; the other
commands are listed by name and help line (``nbst --help`` builds none), so a command's
registry lookups (solver, variant, oil-pattern names) cost nothing to the others.
"""
from __future__ import annotations

import argparse
import importlib
import sys

from nbst._version import __version__
from nbst.domain import plain
from nbst.errors import NbstError
from nbst.outputs import interrupt_once
from nbst.progress import start_clock

__all__ = ["COMMAND_MODULES", "build_parser", "asked_command", "main"]

#: Modules whose ``register(subparsers)`` adds subcommands, in ``--help`` order.
COMMAND_MODULES = (
    "nbst.cli.core",
    "nbst.cli.solve",
    "nbst.cli.generate",
    "nbst.cli.experiment",
    "nbst.cli.mujoco",
    "nbst.cli.bowl",
    "nbst.cli.crash",
    "nbst.cli.scene",
    "nbst.cli.render",
    "nbst.cli.export",
)


class _Parser(argparse.ArgumentParser):
    """argparse, but usage errors exit 2 with one line naming the command, and an option is
    spelled out: no prefix of a longer one is taken for it (``--max-trial`` is not ``--max-trials``)."""

    def __init__(self, *args, **kwargs):
        kwargs.setdefault("allow_abbrev", False)
        super().__init__(*args, **kwargs)

    def error(self, message):
        self.exit(2, f"{self.prog}: error: {plain(message)} (see `{self.prog} --help`)\n")


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    """The ``nbst`` parser. ``only=None`` builds every command's arguments (the docs and the
    tests walk them); ``only="NAME"`` builds that command's module and lists the other
    commands by name and help line; ``only=""`` lists them all, building none (``nbst --help``).
    The listing is the same either way (tests/test_cli_lazy.py)."""
    parser = _Parser(
        prog="nbst",
        description="N-body spacetime constraints: find initial velocities that bring N colliding disks "
                    "to their targets at t_final, check the motion in MuJoCo, render it to video.",
        epilog="Problems are given by built-in name (see `nbst problems`) or by path to a JSON file. "
               "Run `nbst COMMAND --help` for each command.",
    )
    parser.add_argument("--version", action="version", version=f"nbst {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    for name in COMMAND_MODULES:
        module = importlib.import_module(name)
        if only is None or only in module.COMMANDS:
            module.register(sub)
        else:
            for command, line in module.COMMANDS.items():
                sub.add_parser(command, help=line, add_help=False)
    return parser


def _innermost(parser: argparse.ArgumentParser, words: list[str]) -> argparse.ArgumentParser:
    """The (sub)parser of the command ``words`` name: each word in turn that names a subcommand."""
    for w in words:
        subs = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
        if subs and w in subs[0].choices:
            parser = subs[0].choices[w]
    return parser


def asked_command(argv: list[str]) -> str:
    """The command named in ``argv`` (the first word that is not an option: the top-level
    options take no value), or "" when there is none."""
    return next((word for word in argv if not word.startswith("-")), "")


def main(argv=None) -> int:
    """Run one command; returns the exit code. Every command runs inside
    ``nbst.outputs.interrupt_once``: the first SIGINT, SIGTERM or SIGHUP stops it (exit 130,
    the best so far written and partial files removed), later ones wait for that cleanup.
    Called as the program (``argv`` None), the signals are ignored from the moment the command
    ends (Python's shutdown would restore their default, fatal action), so a late signal cannot
    change the exit status; called with ``argv`` (tests), the handlers are restored."""
    start_clock()  # every progress line and summary counts from here
    guard = interrupt_once()
    guard.__enter__()
    try:
        words = sys.argv[1:] if argv is None else list(argv)
        parser = build_parser(only=asked_command(words))
        args, extra = parser.parse_known_args(words)
        if extra:   # named by the command that took the rest (`nbst bowl advise --help`, not `nbst --help`)
            _innermost(parser, words).error(f"unrecognized arguments: {' '.join(extra)}")
        if not getattr(args, "func", None):
            parser.print_help(sys.stderr)
            return 2
        return _run(args)
    except KeyboardInterrupt:  # the first signal landed outside the command (parsing, an error message)
        print("nbst: interrupted", file=sys.stderr)
        return 130
    finally:
        if argv is not None:
            guard.__exit__(None, None, None)
        else:  # the program exits now: a late signal must not kill it during interpreter shutdown
            from nbst.outputs import ignore_stop_signals, signals_blocked

            with signals_blocked():
                guard.__exit__(None, None, None)
                ignore_stop_signals()


def _run(args) -> int:
    try:
        return int(args.func(args) or 0)
    except NbstError as e:  # every error nbst raises on purpose: one line, its exit status (2: bad input)
        print(f"nbst: error: {plain(e)}", file=sys.stderr)
        return e.exit_code
    except KeyboardInterrupt:
        print("nbst: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        return 0
    except OSError as e:  # an I/O failure after the up-front checks (disk full, folder removed)
        if e.filename is None:
            raise
        print(f"nbst: error: {plain(e.filename)}: {plain(e.strerror or e)}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
