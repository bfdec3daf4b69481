"""One flag vocabulary for every subcommand (docs/cli.md lists them all).

The same idea has the same name everywhere:

==================  =====================================================================
``-o/--output``     one output file
``--out-dir DIR``   an output folder (experiment tables, validation report, gallery, atlas)
``--jobs K``        local parallelism (processes or threads; default: every core)
``--cluster ADDR``  run on a Dask scheduler instead of local processes
``--max-trials N``  the search budget (one trial = one exact simulation)
``--max-rollouts N`` the MuJoCo budget (one rollout = one simulated throw)
``-q/--quiet``      no progress, no summary
``--seed S``        see :data:`SEED_RULE`
==================  =====================================================================

Old spellings (``--out``, ``--report``, ``--dir``, ``--workers``, ``--trials``) still work as
hidden aliases and print a one-line deprecation note.
"""
from __future__ import annotations

import argparse
import sys

__all__ = ["SEED_RULE", "old_spelling", "add_out_dir", "add_jobs", "add_quiet", "add_seed"]

#: The one rule for --seed defaults, quoted in every --help.
SEED_RULE = ("a command that makes one result (solve, bowl solve, generate) draws a seed and records it in "
             "the file; a command whose rerun resumes earlier work (experiment, bowl atlas, gallery) starts "
             "from seed 1, so the same command continues the same runs")


class _Deprecated(argparse.Action):
    """A hidden old spelling: stores into the new flag's dest and says so once on stderr."""

    def __init__(self, option_strings, dest, new: str = "", **kw):
        self.new = new
        super().__init__(option_strings, dest, **kw)

    def __call__(self, parser, namespace, values, option_string=None):
        print(f"nbst: note: {option_string} is deprecated; use {self.new}", file=sys.stderr)
        setattr(namespace, self.dest, True if self.nargs == 0 else values)


def old_spelling(p, old: str, new: str, *, dest: str, type=None, flag: bool = False) -> None:
    """Accept ``old`` as a hidden alias of ``new`` (stored in ``dest``)."""
    kw = {"nargs": 0} if flag else {"type": type}
    p.add_argument(old, dest=dest, action=_Deprecated, new=new, help=argparse.SUPPRESS, default=argparse.SUPPRESS,
                   **kw)


def add_out_dir(p, *, dest: str, help: str, default=None, required: bool = False, old=()) -> None:
    """``--out-dir DIR`` (an output folder), with old spellings as hidden aliases."""
    # required: a group, so that an old spelling also satisfies it (argparse checks actions, not dests)
    g = p.add_mutually_exclusive_group(required=True) if required else p
    g.add_argument("--out-dir", dest=dest, metavar="DIR", default=default, help=help)
    for o in old:
        old_spelling(g, o, "--out-dir", dest=dest)


def add_jobs(p, *, dest: str = "jobs", type=None, help: str, old=()) -> None:
    """``--jobs K`` (local parallelism)."""
    p.add_argument("--jobs", dest=dest, type=type, default=None, metavar="K", help=help)
    for o in old:
        old_spelling(p, o, "--jobs", dest=dest, type=type)


def add_quiet(p, help: str = "no progress and no summary") -> None:
    """``-q/--quiet``."""
    p.add_argument("-q", "--quiet", action="store_true", help=help)


def add_seed(p, *, type, resumable: bool, what: str = "random seed") -> None:
    """``--seed S`` with the one documented default rule."""
    if resumable:
        p.add_argument("--seed", type=type, default=1,
                       help=f"{what} (default 1: the same command gives the same results, and a rerun resumes finished work)")
    else:
        p.add_argument("--seed", type=type, default=None,
                       help=f"{what} (default: drawn at random and recorded in the output)")
