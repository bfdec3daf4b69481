"""Solutions: the initial velocities, read and written in the JSON solution format.

Only ``velocities`` is required when reading. ``cost``, ``signature`` and
``order`` in a file are never trusted: recompute them with ``nbst.simulate``.
Keys nbst does not know are kept in ``Solution.meta`` and written back.
"""
from __future__ import annotations

import math
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from nbst.domain import MAX_BOX_CROSSINGS
from nbst.errors import InputError
from nbst.outputs import dumps_strict, json_safe, write_json_atomic  # noqa: F401 - dumps_strict re-exported
from nbst.problem import Problem, ProblemError, _Checker, box_crossings, read_json

__all__ = ["SCHEMA_VERSION", "named_problem", "Solution", "HistoryPoint", "RESULT_KEYS", "SolveResult", "signature_string",
           "solution_from_dict", "load_solution", "make_solution", "checked_velocities", "save_solution"]

SCHEMA_VERSION = 1


@dataclass(frozen=True, eq=False)
class Solution:
    """Initial velocities for a problem, plus what the solver knows about them.

    Args:
        problem: the problem the velocities are for.
        velocities: (N, 2) float64 array, units/s; zero rows for noncueable disks.
        meta: every other key of the file (cost, signature, seed, history, ...).

    Returns:
        The solution; ``save_solution`` writes it, ``load_solution`` reads it back.
    """

    problem: str
    velocities: np.ndarray
    meta: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        out = {"schema_version": SCHEMA_VERSION, "problem": self.problem,
               "velocities": [[float(x), float(y)] for x, y in self.velocities]}
        for k, v in self.meta.items():
            if k not in out:
                out[k] = v
        return out


#: One improvement of a search's best: (trial, cost, order).
HistoryPoint = tuple[int, float, int]

#: The ``meta`` keys that :class:`SolveResult` holds as typed attributes (always present).
RESULT_KEYS = ("algorithm", "cost", "signature", "order", "trials", "seed", "variant", "stopped", "wall_time",
               "history")


@dataclass(frozen=True, eq=False)
class SolveResult:
    """What a solver returns: the best velocities and what the search knows about them.

    Attributes, as a fitted estimator's (every solver of ``nbst.solvers`` and ``nbst.search.solve``
    sets all of them):

    problem    : the problem's name
    velocities : (N, 2) float, units/s, read-only; zero rows for noncueable disks
    cost       : sum over disks of the squared distance from the target at t_final, units^2
                 (the problem's R; inf for a truncated simulation)
    signature  : N characters, '1' where the disk ends within R of its target
    order      : how many disks end within R
    trials     : simulations spent (initialize, a planner and every island included)
    seed       : the seed the run was made from (drawn and recorded when none was given)
    stopped    : why it stopped: "max_trials", "patience", "target_cost", "callback",
                 "interrupted", a baseline's "converged"; None if nothing stopped it
    wall_time  : seconds the search ran
    history    : (trial, cost, order) at every improvement of the best
    algorithm  : the file's name of the search ("nbst-signature-search", "nbst-many", "cma-es", ...)
    variant    : the signature search's variant asked for, None for a baseline
    meta       : every key the solution file holds besides problem and velocities, in the file's
                 order (the attributes above included; run statistics, ``params``, ``islands``,
                 ...); read it, do not change it (use :meth:`with_meta`)

    :meth:`to_solution` and :meth:`to_dict` give the solution file (its format is the one of
    ``nbst.solution``); :meth:`from_solution` reads one back.
    """

    problem: str
    velocities: np.ndarray
    cost: float
    signature: str
    order: int
    trials: int
    seed: int
    stopped: str | None
    wall_time: float
    history: tuple[HistoryPoint, ...]
    algorithm: str
    variant: str | None
    meta: dict = field(repr=False)

    def __post_init__(self) -> None:
        """The typed attributes and ``meta`` say the same (a ``dataclasses.replace`` that changes
        one without the other is refused: use :meth:`with_meta`)."""
        typed = _typed(self.meta)
        for key in RESULT_KEYS:
            mine = getattr(self, key)
            if not _same(mine, typed[key]):
                raise InputError(f"SolveResult.{key} = {mine!r} but meta[{key!r}] = {typed[key]!r}: "
                                 "build a result with SolveResult.from_meta or with_meta")

    @classmethod
    def from_meta(cls, problem: Problem, velocities, meta: Mapping[str, Any]) -> "SolveResult":
        """A result from velocities and a solver's ``meta`` (which must hold every key of
        ``RESULT_KEYS``); the velocities are checked as a solution file's are."""
        return cls._of(Solution(problem=problem.name, velocities=checked_velocities(problem, velocities),
                                meta=dict(meta)))

    @classmethod
    def from_solution(cls, solution: Solution) -> "SolveResult":
        """A solution written by nbst's solvers, read back (``meta`` must hold every key of
        ``RESULT_KEYS``: an InputError names the first one missing or of the wrong type)."""
        return cls._of(solution)

    @classmethod
    def _of(cls, sol: Solution) -> "SolveResult":
        meta = dict(sol.meta)
        t = _typed(meta, source=sol.problem)
        return cls(problem=sol.problem, velocities=sol.velocities, cost=t["cost"], signature=t["signature"],
                   order=t["order"], trials=t["trials"], seed=t["seed"], stopped=t["stopped"],
                   wall_time=t["wall_time"], history=t["history"], algorithm=t["algorithm"], variant=t["variant"],
                   meta=meta)

    def with_meta(self, changes: Mapping[str, Any]) -> "SolveResult":
        """This result with some of ``meta``'s keys changed or added (key order kept, new keys last)."""
        meta = dict(self.meta)
        meta.update(changes)
        return SolveResult._of(Solution(problem=self.problem, velocities=self.velocities, meta=meta))

    def to_solution(self) -> Solution:
        """The :class:`Solution` (what a solution file holds)."""
        return Solution(problem=self.problem, velocities=self.velocities, meta=dict(self.meta))

    def to_dict(self) -> dict:
        """The solution file's JSON object (``Solution.to_dict``)."""
        return self.to_solution().to_dict()

    # Optional parts of ``meta``, typed: present only for the solvers that write them.

    @property
    def trials_per_s(self) -> float | None:
        v = self.meta.get("trials_per_s")
        return None if v is None else float(v)

    @property
    def island(self) -> int | None:
        """Islands (``nbst.solvers.islands.solve_islands``): the island whose solution this is."""
        v = self.meta.get("island")
        return None if v is None else int(v)

    @property
    def islands(self) -> tuple[Mapping[str, Any], ...]:
        """Islands: one entry per island (island, seed, trials, cost, stopped; a portfolio's variant)."""
        return tuple(self.meta.get("islands") or ())

    @property
    def configuration(self) -> str | None:
        """nbst's portfolio: the variant of the search that produced these velocities."""
        v = self.meta.get("configuration")
        return None if v is None else str(v)

    @property
    def robust(self) -> Mapping[str, Any] | None:
        """Robust mode (``nbst.search.robust``): how the velocities were chosen (score, samples, ...)."""
        return self.meta.get("robust") or None

    @property
    def many(self) -> Mapping[str, Any] | None:
        """The many-body search (``nbst.search.many``): its statistics (rounds, conflicts, ...)."""
        return self.meta.get("many")

    @property
    def params(self) -> Mapping[str, Any]:
        """The parameters of the search that produced these velocities (as the file writes them)."""
        return self.meta.get("params") or {}


def _same(a: Any, b: Any) -> bool:
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    return bool(a == b)


def _typed(meta: Mapping[str, Any], *, source: str = "<solver result>") -> dict:
    """The typed attributes of a result from its ``meta`` (InputError naming a missing or bad key)."""
    def get(key: str, conv, *, optional: bool = False):
        if key not in meta:
            raise ProblemError(source, key, "missing: a solver's result records it")
        v = meta[key]
        if v is None and optional:
            return None
        try:
            return conv(v)
        except (TypeError, ValueError, OverflowError):
            raise ProblemError(source, key, f"{v!r} is not what a solver records there") from None

    def cost(v) -> float:
        return math.inf if v == "inf" else float(v)  # a strict JSON file writes inf as "inf"

    return {"algorithm": get("algorithm", str), "cost": get("cost", cost), "signature": get("signature", str),
            "order": get("order", int), "trials": get("trials", int), "seed": get("seed", int),
            "variant": get("variant", str, optional=True), "stopped": get("stopped", str, optional=True),
            "wall_time": get("wall_time", float),
            "history": get("history", lambda h: tuple((int(t), cost(c), int(o)) for t, c, o in h))}


def signature_string(sig: int, n: int) -> str:
    """Bitmask -> the file's signature string: character i is '1' iff bit i is set."""
    return "".join("1" if (sig >> i) & 1 else "0" for i in range(n))


def solution_from_dict(d: Any, problem: Problem, *, source: str = "<dict>") -> Solution:
    """Validate a decoded solution object against ``problem``."""
    c = _Checker(source)
    c.obj(d, "")
    if "problem" in d:
        name = c.string(d["problem"], "problem")
        if name != problem.name:
            c.fail("problem", f"this solution is for problem {name!r}, not {problem.name!r}")
    vel = c.get(d, "velocities", "")
    if not isinstance(vel, list):
        c.fail("velocities", f"must be a list of [vx, vy] pairs, got a {type(vel).__name__}")
    if len(vel) != problem.n:
        c.fail("velocities", f"has {len(vel)} entries but problem {problem.name!r} has {problem.n} disks")
    v = np.empty((problem.n, 2))
    for i, pair in enumerate(vel):
        v[i] = c.pair(pair, f"velocities[{i}]")
        if not problem.cueable[i] and (v[i, 0] != 0.0 or v[i, 1] != 0.0):
            c.fail(f"velocities[{i}]", f"disk {i} is noncueable and must start at rest, got "
                                       f"[{v[i, 0]:g}, {v[i, 1]:g}]")
    k = box_crossings(problem, v)
    i = int(np.argmax(k))
    if k[i] > MAX_BOX_CROSSINGS:
        c.fail(f"velocities[{i}]", f"[{v[i, 0]:g}, {v[i, 1]:g}] crosses the box {k[i]:.3g} times in t_final = "
                                   f"{problem.t_final:g} s; at most {MAX_BOX_CROSSINGS:,} fit the simulator's "
                                   f"event cap: lower this velocity")
    v.setflags(write=False)
    meta = {k: val for k, val in d.items() if k not in ("velocities", "problem", "schema_version")}
    return Solution(problem=problem.name, velocities=v, meta=meta)


def named_problem(path: str | os.PathLike) -> str | None:
    """The problem a solution file names (``nbst solve -o``: ``"problem"`` beside ``"velocities"``), or None
    for any other file, one that cannot be read included (its own reader says why)."""
    p = Path(str(path))
    if p.suffix.lower() != ".json" or not p.is_file():
        return None
    try:
        doc = read_json(p)
    except InputError:
        return None
    named = doc.get("problem") if isinstance(doc, dict) and "velocities" in doc else None
    return named if isinstance(named, str) else None


def load_solution(path: str | Path, problem: Problem) -> Solution:
    """Read and validate a solution file for ``problem``.

    Args:
        path: the solution file (``nbst solve -o``'s JSON).
        problem: the problem it solves; its disk count and cueable disks are checked.

    Returns:
        The :class:`Solution`: ``velocities`` (N, 2), read-only, and every other key in ``meta``.

    Raises:
        ProblemError: one line naming the file, the field and the problem.
    """
    return solution_from_dict(read_json(path), problem, source=str(path))


def make_solution(problem: Problem, velocities, **meta) -> Solution:
    """Build a Solution from an (N, 2) array, checking it like a file would be checked."""
    return Solution(problem=problem.name, velocities=checked_velocities(problem, velocities), meta=dict(meta))


def checked_velocities(problem: Problem, velocities) -> np.ndarray:
    """An (N, 2) array of velocities for ``problem``, checked as a solution file's are (read-only copy)."""
    v = np.asarray(velocities, dtype=float)
    if v.shape != (problem.n, 2):
        raise ProblemError("<velocities>", "velocities", f"shape {v.shape}, expected ({problem.n}, 2)")
    d = {"problem": problem.name, "velocities": v.tolist()}
    return solution_from_dict(d, problem).velocities


# json_safe and dumps_strict (strict JSON: NaN -> null, +/-inf -> "inf"/"-inf") and the one atomic
# writer live in nbst.outputs; their names stay importable from here.
_json_safe = json_safe  # the name nbst/cli/mujoco.py imports


def save_solution(path: str | Path, solution: Solution, *, option: str = "-o") -> None:
    """Write ``solution`` in the JSON solution format with nbst's one atomic writer
    (``nbst.outputs.write_json_atomic``: a partial file beside the target, fsynced, renamed over it,
    the folder fsynced, stale partial files of killed writers removed).

    Args:
        path: the file to write (never written through a symbolic link).
        solution: what to write (:class:`Solution`; ``SolveResult.to_solution()`` gives one).
        option: the command-line option named in an error (``-o``).

    Returns:
        None. On failure an OutputError names ``option`` and the path, and the previous file is
        unchanged.
    """
    write_json_atomic(path, solution.to_dict(), option=option)
