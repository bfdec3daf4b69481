"""Helpers shared by every subcommand: argparse types with their domains, JSON on stdout,
the ``--cluster`` connection. Light: no numba, MuJoCo or moderngl at import."""
from __future__ import annotations

import argparse
import sys

from nbst.constants import MAX_EVENTS
from nbst.domain import parse_number
from nbst.errors import InputError
from nbst.problem import ProblemError
from nbst.seeds import SEED_MAX
from nbst.solution import dumps_strict
from nbst import parallel


__all__ = ["TRIALS_MAX", "JOBS_MAX", "RUNS_MAX", "Bounded", "int_at_least", "with_limits", "SEED", "MAX_TRIALS",
           "JOBS", "TARGET_COST", "nonnegative_cost", "Size", "cluster_client", "print_json", "exact_motion"]

#: Limits shared by several commands' flags (each flag's --help states its range).
TRIALS_MAX = 10**12  # a trillion trials: days of search, far past any budget nbst has needed
JOBS_MAX = parallel.JOBS_MAX  # processes on this machine (each a full search or worker)
RUNS_MAX = 100_000  # runs per entry of an experiment


def _fmt(x) -> str:
    """A limit for --help: 2^63-1, 2^62, 100,000, 1e12, 5e8, 0.01."""
    if isinstance(x, int):
        if x == SEED_MAX:
            return "2^63-1"
        if x >= 2**32 and x & (x - 1) == 0:
            return f"2^{x.bit_length() - 1}"
        if abs(x) < 10**7:
            return f"{x:,}"
        x = float(x)
    return f"{x:g}".replace("e+0", "e").replace("e+", "e").replace("e-0", "e-")


class Bounded:
    """argparse type: a finite number (int or float) in [lo, hi], either end open with
    ``lo_open``/``hi_open`` and ``hi=None`` for no upper end. ``limits`` says it in words
    for --help, and every refusal names the flag's ``what``, the value and the range."""

    def __init__(self, what: str, lo, hi=None, *, integer: bool = False, lo_open: bool = False,
                 hi_open: bool = False, unit: str = ""):
        self.what, self.lo, self.hi, self.integer = what, lo, hi, integer
        self.lo_open, self.hi_open, self.unit = lo_open, hi_open, unit
        self.__name__ = what  # argparse names the type in some messages

    @property
    def limits(self) -> str:
        unit = f" {self.unit}" if self.unit else ""
        if self.integer:
            lo = self.lo + 1 if self.lo_open else self.lo
            if self.hi is None:
                return f"an integer >= {_fmt(lo)}{unit}"
            hi = self.hi - 1 if self.hi_open else self.hi
            return f"an integer in {_fmt(lo)}..{_fmt(hi)}{unit}"
        if self.hi is None:
            return f"a finite number {'>' if self.lo_open else '>='} {_fmt(self.lo)}{unit}"
        return (f"a number in {'(' if self.lo_open else '['}{_fmt(self.lo)}, {_fmt(self.hi)}"
                f"{')' if self.hi_open else ']'}{unit}")

    def __call__(self, text: str):
        t = str(text).strip()
        try:
            v = parse_number(t, integer=self.integer)
        except InputError:
            kind = "an integer" if self.integer else "a number"
            raise argparse.ArgumentTypeError(f"{self.what} must be {kind}, got {text!r}") from None
        bad = (not self.integer and v != v) or (not self.integer and abs(v) == float("inf"))
        bad = bad or v < self.lo or (self.lo_open and v == self.lo)
        bad = bad or (self.hi is not None and (v > self.hi or (self.hi_open and v == self.hi)))
        if bad:
            raise argparse.ArgumentTypeError(f"{self.what} must be {self.limits}, got {text!r}")
        return v

    def __repr__(self) -> str:
        return f"Bounded({self.what!r}: {self.limits})"


def int_at_least(lo: int, what: str, hi: int | None = None) -> Bounded:
    """argparse type: an integer >= lo (and <= hi when given; underscores allowed); ``what`` names it in errors."""
    return Bounded(what, lo, hi, integer=True)


def with_limits(text: str, t: Bounded) -> str:
    """A --help text followed by the flag's range: ``"trial budget (default 1000000) [an integer in 1..1e12]"``."""
    return f"{text} [{t.limits}]"


#: The flags every search-running command shares.
SEED = Bounded("seed", 0, SEED_MAX, integer=True)
MAX_TRIALS = Bounded("max-trials", 1, TRIALS_MAX, integer=True)
JOBS = Bounded("jobs", 1, JOBS_MAX, integer=True)
TARGET_COST = Bounded("target cost", 0.0, None)


def nonnegative_cost(text: str) -> float:
    """argparse type: a target cost, a finite number >= 0."""
    return TARGET_COST(text)


class Size:
    """argparse type: a frame size ``WxH`` in pixels, each side in [lo, hi] -> (W, H)."""

    def __init__(self, what: str = "size", lo: int = 16, hi: int = 8192):
        self.what, self.lo, self.hi = what, lo, hi
        self.limits = f"WxH, each side an integer in {lo}..{hi} pixels"
        self.__name__ = "size"

    def __call__(self, text: str) -> tuple[int, int]:
        parts = str(text).lower().replace("*", "x").split("x")
        if len(parts) != 2 or not all(x.strip().isdigit() and len(x.strip()) < 7 for x in parts):
            raise argparse.ArgumentTypeError(f"{self.what} must be WIDTHxHEIGHT in pixels (e.g. 1280x720), "
                                             f"got {text!r}")
        w, h = int(parts[0]), int(parts[1])
        if not (self.lo <= w <= self.hi and self.lo <= h <= self.hi):
            raise argparse.ArgumentTypeError(f"{self.what} must be {self.limits}, got {text!r}")
        return w, h


def cluster_client(args):
    """The Dask client of ``--cluster`` (None without it); InputError (one line naming the address
    and what is there, within ``nbst.cluster.CONNECT_TIMEOUT_S``) when no scheduler answers."""
    if args.cluster is None:
        return None
    from nbst.cluster import connect

    return connect(args.cluster)


def print_json(obj) -> None:
    """Print ``obj`` as strict JSON: NaN -> null, +/-inf -> "inf"/"-inf" (``docs/formats.md``)."""
    sys.stdout.write(dumps_strict(obj, indent=1) + "\n")


def exact_motion(problem, solution_path, velocities):
    """The exact motion of a solution file's velocities, or a ProblemError naming the file (one
    line, exit 2) when nbst cannot follow it to t_final: the event cap (``MAX_EVENTS``) or a jam
    of disks pinned between opposite walls. Every solution a command accepts simulates to the
    end, or is refused here, before any work that would use the motion."""
    from nbst.sim import simulate

    tr = simulate(problem, velocities)
    if tr.truncated:
        why = ("a jam: disks pinned between opposite walls bounce without end" if tr.stalled else
               f"it needs more than {MAX_EVENTS:,} events")
        raise ProblemError(str(solution_path), "velocities",
                           f"the motion stops at t = {tr.end_time:.6g} s, before t_final = {problem.t_final:g} s "
                           f"({why}); nbst cannot simulate it to the end")
    return tr

