"""Solutions: the initial velocities, read and written in the JSON solution format.

Only ``velocities`` is required when reading. ``cost``, ``signature`` and
``order`` in a file are never trusted: recompute them with ``nbst.simulate``.
Keys nbst does not know are kept in ``Solution.meta`` and written back.
"""
from __future__ import annotations

import json
import math
import os
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from nbst.domain import MAX_BOX_CROSSINGS
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


def json_safe(x):
    """``x`` with every non-finite float made strict-JSON: NaN -> null, +/-inf ->
    the strings "inf" / "-inf" (numpy scalars and arrays become Python values).
    Every JSON nbst writes or prints goes through this (``docs/formats.md``)."""
    if isinstance(x, float) and not math.isfinite(x):
        return None if math.isnan(x) else ("inf" if x > 0 else "-inf")
    if isinstance(x, dict):
        return {k: json_safe(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [json_safe(v) for v in x]
    if isinstance(x, np.generic):
        return json_safe(x.item())
    if isinstance(x, np.ndarray):
        return json_safe(x.tolist())
    return x


_json_safe = json_safe  # the name nbst/cli/mujoco.py imports


def dumps_strict(obj: Any, **kw) -> str:
    """JSON text that any strict parser reads (see :func:`json_safe`)."""
    return json.dumps(json_safe(obj), allow_nan=False, **kw)


def write_json_atomic(path: str | Path, obj: Any) -> None:
    """Write JSON so that ``path`` holds either the old file or the whole new one.

    The text goes to a temporary file in the same folder, is flushed to disk,
    then renamed over ``path`` (atomic on POSIX).
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    text = dumps_strict(obj, indent=1) + "\n"
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    except OSError as e:  # name the file the caller asked for, not the scratch file
        raise OSError(e.errno, e.strerror, str(path)) from None
    try:
        os.chmod(tmp, 0o666 & ~_umask())  # mkstemp makes 0600; give the file the usual permissions
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def save_solution(path: str | Path, solution: Solution) -> None:
    """Write ``solution`` atomically in the JSON solution format."""
    write_json_atomic(path, solution.to_dict())
