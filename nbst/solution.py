"""Solutions: the initial velocities, read and written in the JSON solution format.

Only ``velocities`` is required when reading. ``cost``, ``signature`` and
``order`` in a file are never trusted: recompute them with ``nbst.simulate``.
Keys nbst does not know are kept in ``Solution.meta`` and written back.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from nbst.domain import MAX_BOX_CROSSINGS
from nbst.outputs import dumps_strict, json_safe, write_json_atomic  # noqa: F401 - dumps_strict re-exported
from nbst.problem import Problem, ProblemError, _Checker, box_crossings, read_json

SCHEMA_VERSION = 1


@dataclass(frozen=True, eq=False)
class Solution:
    """Initial velocities for a problem, plus what the solver knows about them.

    velocities : (N, 2) float, units/s; zero rows for noncueable disks
    meta       : every other key of the file (cost, signature, seed, history, ...)
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


def load_solution(path: str | Path, problem: Problem) -> Solution:
    """Read and validate a solution file for ``problem``."""
    return solution_from_dict(read_json(path), problem, source=str(path))


def make_solution(problem: Problem, velocities, **meta) -> Solution:
    """Build a Solution from an (N, 2) array, checking it like a file would be checked."""
    v = np.asarray(velocities, dtype=float)
    if v.shape != (problem.n, 2):
        raise ProblemError("<velocities>", "velocities", f"shape {v.shape}, expected ({problem.n}, 2)")
    d = {"problem": problem.name, "velocities": v.tolist()}
    return Solution(problem=problem.name, velocities=solution_from_dict(d, problem).velocities, meta=dict(meta))


# json_safe and dumps_strict (strict JSON: NaN -> null, +/-inf -> "inf"/"-inf") and the one atomic
# writer live in nbst.outputs; their names stay importable from here.
_json_safe = json_safe  # the name nbst/cli/mujoco.py imports


def save_solution(path: str | Path, solution: Solution, *, option: str = "-o") -> None:
    """Write ``solution`` in the JSON solution format with nbst's one atomic writer
    (``nbst.outputs.write_json_atomic``: a partial file beside the target, fsynced, renamed over it,
    the folder fsynced, stale partial files of killed writers removed; OutputError naming
    ``option`` and the path on failure, the previous file then unchanged)."""
    write_json_atomic(path, solution.to_dict(), option=option)
