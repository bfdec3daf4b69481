"""docs/cli.md's flag tables, written from the parser itself so they cannot go stale.

    python -m nbst.cli.reference > docs/cli.md        # regenerate
(the test suite fails when docs/cli.md differs from what this prints).
"""
from __future__ import annotations

import argparse
import sys

from nbst.cli.flags import SEED_RULE
from nbst.cli.main import build_parser

__all__ = ["INTRO", "markdown"]

INTRO = f"""# Command-line reference

Every subcommand of `nbst` and every flag it takes, written from the parser itself
(`python -m nbst.cli.reference > docs/cli.md`; a test fails when this page and the
tools disagree). `nbst COMMAND --help` says the same with more words.

## One name per idea

| idea | flag |
|---|---|
| one output file | `-o/--output FILE` |
| an output folder | `--out-dir DIR` |
| local parallelism | `--jobs K` (default: every core) |
| a Dask cluster instead | `--cluster ADDRESS` |
| search budget (exact simulations) | `--max-trials N` |
| MuJoCo budget (simulated throws) | `--max-rollouts N` |
| no progress, no summary | `-q/--quiet` |
| reproducibility | `--seed S` |

`--seed` default: {SEED_RULE}.

Old spellings still work, each with a one-line deprecation note: `--out`, `--report`,
`--dir` (now `--out-dir`), `--workers` (now `--jobs`), `experiment --trials` (now
`--max-trials`).

Exit codes: 0 success; 1 a check failed (`validate --strict`, a bowling shot not found);
2 bad input or usage (one line on stderr naming the file, field or flag); 130 interrupted
(the best result so far is written first).
"""


def _cell(text) -> str:
    return " ".join(str(text).split()).replace("|", "\\|")


def _rows(parser: argparse.ArgumentParser) -> list[str]:
    rows = []
    for a in parser._actions:
        if a.help == argparse.SUPPRESS or isinstance(a, (argparse._HelpAction, argparse._SubParsersAction)):
            continue
        if a.option_strings:
            name = "/".join(a.option_strings)
            arg = "" if a.nargs == 0 else (" ".join(a.metavar) if isinstance(a.metavar, tuple)
                                            else a.metavar or (a.dest.upper() if not a.choices else
                                                               "{" + ",".join(map(str, a.choices)) + "}"))
        else:
            name, arg = str(a.metavar or a.dest), ""
        rows.append(f"| `{name}` | {('`' + _cell(arg) + '`') if arg else ''} | {_cell((a.help or '').replace('%%', '%'))} |")  # as --help prints it
    return rows


def _walk(parser: argparse.ArgumentParser, prefix: tuple):
    subs = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    if prefix:
        yield prefix, parser
    for s in subs:
        for name, sp in s.choices.items():
            yield from _walk(sp, prefix + (name,))


def markdown() -> str:
    out = [INTRO]
    for cmd, p in _walk(build_parser(), ()):
        rows = _rows(p)
        if not rows:
            continue
        out.append(f"## `nbst {' '.join(cmd)}`\n")
        desc = _cell(p.description or "")
        if desc:
            out.append(desc + "\n")
        out.append("| flag | argument | meaning |\n|---|---|---|")
        out.extend(rows)
        out.append("")
    return "\n".join(out).rstrip() + "\n"


if __name__ == "__main__":
    sys.stdout.write(markdown())
