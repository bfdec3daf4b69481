"""Helpers shared by every subcommand: argparse types with their domains, JSON on stdout,
the ``--cluster`` connection. Light: no numba, MuJoCo or moderngl at import."""
from __future__ import annotations

import argparse
import sys

from nbst.problem import ProblemError


def int_at_least(lo: int, what: str):
    """argparse type: an integer >= lo (underscores allowed); ``what`` names it in errors."""
    def parse(text: str) -> int:
        try:
            v = int(text.replace("_", ""))
        except ValueError:
            raise argparse.ArgumentTypeError(f"{what} must be an integer, got {text!r}") from None
        if v < lo:
            raise argparse.ArgumentTypeError(f"{what} must be >= {lo}, got {v}")
        return v
    return parse


def nonnegative_cost(text: str) -> float:
    """argparse type: a target cost, a number >= 0."""
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"target cost must be a number, got {text!r}") from None
    if not v >= 0.0:
        raise argparse.ArgumentTypeError(f"target cost must be >= 0, got {text!r}")
    return v


def cluster_client(args):
    """The Dask client of ``--cluster`` (None without it); ProblemError when unreachable."""
    if args.cluster is None:
        return None
    from nbst.cluster import connect

    try:
        return connect(args.cluster)
    except ValueError as e:
        raise ProblemError("<arguments>", "--cluster", str(e)) from None


def print_json(obj) -> None:
    """Print ``obj`` as strict JSON: NaN -> null, +/-inf -> "inf"/"-inf" (``docs/formats.md``)."""
    from nbst.solution import dumps_strict
    sys.stdout.write(dumps_strict(obj, indent=1) + "\n")
