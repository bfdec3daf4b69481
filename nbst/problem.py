"""The problem model: N disks in a box, their starts and targets.

Format: ``shared/problems/README.md`` (copied in ``docs/formats.md``). Every
invalid input raises :class:`ProblemError`, which names the file, the field as a
path (``disks[3].radius``) and the reason, so the CLI can print one line.
"""
from __future__ import annotations

import difflib
import json
import math
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from nbst import domain as D
from nbst.domain import MAX_DISKS, bad_text, plain
from nbst.errors import InputError
from nbst.files import FileRefused, read_regular
from nbst.overlap import first_overlap
from nbst.problems import PROBLEMS

__all__ = ["SCHEMA_VERSION", "ProblemError", "KernelArrays", "Problem", "builtin_names", "read_bytes_checked",
           "read_json", "parse_json", "load_problem", "problem_from_dict", "box_crossings", "display_name"]

SCHEMA_VERSION = 1


class ProblemError(InputError):
    """Bad input: a problem or solution file (or dict) that nbst refuses.

    Attributes: ``source`` (file path or a label), ``field`` (a path such as
    ``disks[3].radius``, or ``""`` for the whole file) and ``reason``.
    """

    def __init__(self, source: str | Path, field: str, reason: str):
        self.source, self.field, self.reason = str(source), field, reason
        where = f"{self.source}: {field}" if field else self.source
        super().__init__(plain(f"{where}: {reason}"))  # one printable line, whatever the file held


class KernelArrays(NamedTuple):
    """A problem as the numba kernels take it (``Problem.kernel_arrays()``)."""

    start: np.ndarray
    target: np.ndarray
    radius: np.ndarray
    mass: np.ndarray
    W: float
    H: float
    t_final: float
    R: float


def _read_only(a: np.ndarray) -> np.ndarray:
    """A read-only view of ``a``: the kernels see one array type (numba compiles a writable and a
    read-only array as two signatures), whether the problem came from a file or from the constructor."""
    v = a.view()
    v.flags.writeable = False
    return v


@dataclass(frozen=True, eq=False)
class Problem:
    """A validated problem. Arrays are read-only. Build one with :func:`load_problem` or
    :func:`problem_from_dict`, which check every field; the constructor checks nothing.

    Args:
        name: the problem's name (a built-in's, or the file's ``name``).
        box: (W, H), units; the box spans [0, W] x [0, H].
        t_final: seconds.
        target_radius: R, units; disk i is acceptable iff |final_i - target_i| <= R.
        start: (N, 2) float, units: the disks' positions at t = 0.
        target: (N, 2) float, units: where each disk should be at t_final.
        radius: (N,) float, units.
        mass: (N,) float, mass units.
        cueable: (N,) bool: a cueable disk gets an initial velocity; the others start at rest.
        description: free text from the file.
        source: where it came from (a path, ``<built-in NAME>`` or ``<dict>``).
        raw: the decoded JSON object it was built from.

    Returns:
        The problem; ``n``, ``width``, ``height`` and ``straight_velocities()`` derive from it.
    """

    name: str
    box: tuple[float, float]
    t_final: float
    target_radius: float
    start: np.ndarray
    target: np.ndarray
    radius: np.ndarray
    mass: np.ndarray
    cueable: np.ndarray
    description: str = ""
    source: str = "<dict>"
    raw: dict = field(default_factory=dict, repr=False)

    @property
    def n(self) -> int:
        return int(self.start.shape[0])

    @property
    def width(self) -> float:
        return self.box[0]

    @property
    def height(self) -> float:
        return self.box[1]

    def straight_velocities(self) -> np.ndarray:
        """(N, 2) velocities that carry each cueable disk straight to its target
        (the paper's *directed randomize*); zero for noncueable disks."""
        v = (self.target - self.start) / self.t_final
        v[~self.cueable] = 0.0
        return v

    def kernel_arrays(self) -> KernelArrays:
        """The problem as the numba kernels take it (computed once, then cached): start,
        target, radius, mass as C-contiguous float64 arrays (read-only) and W, H, t_final,
        R as floats."""
        ka = self.__dict__.get("_kernel_arrays")
        if ka is None:
            start, target, radius, mass = (_read_only(np.ascontiguousarray(a, dtype=np.float64))
                                           for a in (self.start, self.target, self.radius, self.mass))
            ka = KernelArrays(start, target, radius, mass, float(self.box[0]), float(self.box[1]),
                              float(self.t_final), float(self.target_radius))
            object.__setattr__(self, "_kernel_arrays", ka)  # a cache, not state: the problem stays frozen
        return ka

    def to_dict(self) -> dict:
        """The problem in its JSON format (round-trips through ``problem_from_dict``)."""
        disks = []
        for i in range(self.n):
            disks.append({
                "start": [float(x) for x in self.start[i]],
                "target": [float(x) for x in self.target[i]],
                "radius": float(self.radius[i]),
                "cueable": bool(self.cueable[i]),
                "mass": float(self.mass[i]),
            })
        out = {"name": self.name, "box": list(self.box), "t_final": self.t_final,
               "target_radius": self.target_radius, "disks": disks}
        if self.description:
            out["description"] = self.description
        return out


# --------------------------------------------------------------------------- built-ins

def builtin_names() -> list[str]:
    """Names of the built-in problems (registered in ``nbst.problems.PROBLEMS``), sorted.

    Args:
        (none)

    Returns:
        list of str: the names ``load_problem`` takes besides a path.
    """
    return sorted(PROBLEMS.names())


def _builtin_text(name: str) -> str:
    return resources.files("nbst.problems").joinpath(PROBLEMS[name]).read_text(encoding="utf-8")


# --------------------------------------------------------------------------- loading

def read_bytes_checked(path: str | Path) -> bytes:
    """The bytes of a regular file of at most ``MAX_JSON_BYTES``, or a one-line ProblemError: the one
    bounded, non-blocking read of ``nbst.files.read_regular`` (a directory, FIFO, device or socket
    refused without being opened, the size checked before and after)."""
    try:
        return read_regular(path, max_bytes=D.MAX_JSON_BYTES, what="JSON file")
    except FileRefused as e:
        raise ProblemError(e.path, "", e.reason) from None


def read_json(path: str | Path) -> Any:
    """Read a JSON file through nbst's input gate (``read_bytes_checked``, then ``parse_json``),
    turning every failure into a one-line ProblemError."""
    p = Path(path)
    data = read_bytes_checked(p)
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        raise ProblemError(p, "", "not a text file (not UTF-8)") from None
    return parse_json(text, str(p))


def _check_shape(text: str, source: str) -> None:
    """Cheap checks on the raw text before the parser builds anything: at most MAX_JSON_VALUES
    values (see ``nbst.domain``), counted with C-speed ``str.count`` calls."""
    n = 0
    for ch in ",:[{":
        n += text.count(ch)
        if n > D.MAX_JSON_VALUES:
            break
    if n > D.MAX_JSON_VALUES:
        raise ProblemError(source, "", f"more than {D.MAX_JSON_VALUES:,} JSON values (counting the ',', ':', '[' "
                                       f"and '{{' characters); nbst reads files of at most {D.MAX_JSON_VALUES:,}")


class _LongInt(Exception):
    pass


def _parse_int(s: str) -> int:
    if len(s) > D.MAX_INT_DIGITS:  # before int(): long literals are slow and may pass Python's own limit
        raise _LongInt(len(s.lstrip("-")))
    return int(s)


def parse_json(text: str, source: str) -> Any:
    """Decode JSON text with nbst's limits (``nbst.domain``): at most MAX_JSON_DEPTH
    levels of nesting and MAX_INT_DIGITS digits per integer. Every failure, the
    parser's own limits included, is a one-line ProblemError naming ``source``."""
    if len(text) > D.MAX_JSON_BYTES:
        raise ProblemError(source, "", f"{len(text):,} characters; nbst reads JSON of at most "
                                       f"{D.MAX_JSON_BYTES:,}")
    _check_shape(text, source)
    try:
        obj = json.loads(text, parse_int=_parse_int)
    except json.JSONDecodeError as e:
        raise ProblemError(source, "", f"not valid JSON: {e.msg} at line {e.lineno} column {e.colno}") from None
    except _LongInt as e:
        raise ProblemError(source, "", f"an integer literal of {e.args[0]} digits; at most {D.MAX_INT_DIGITS} "
                                       f"are read (write large numbers as floats, e.g. 1e300)") from None
    except RecursionError:
        raise ProblemError(source, "", f"nested too deeply for the JSON parser; at most {D.MAX_JSON_DEPTH} "
                                       f"levels of lists/objects are read") from None
    except (ValueError, OverflowError) as e:  # any other parser limit
        raise ProblemError(source, "", f"not valid JSON: {e}") from None
    depth = _depth(obj)
    if depth > D.MAX_JSON_DEPTH:
        raise ProblemError(source, "", f"nested {depth} levels deep; at most {D.MAX_JSON_DEPTH} levels of "
                                       f"lists/objects are read")
    return obj


def _depth(obj: Any) -> int:
    """Nesting depth of decoded JSON (a scalar is 0), without recursion; empty containers are
    counted without being visited (a file of a million ``[]`` stays quick)."""
    best = 0
    stack = [(obj, 1)] if isinstance(obj, (list, dict)) else []
    while stack:
        o, k = stack.pop()
        if k > best:
            best = k
            if k > D.MAX_JSON_DEPTH:
                return k
        for v in (o.values() if isinstance(o, dict) else o):
            if isinstance(v, (list, dict)):
                if v:
                    stack.append((v, k + 1))
                elif k + 1 > best:
                    best = k + 1
    return best


def load_problem(name_or_path: str | Path) -> Problem:
    """Load a problem by built-in name (``diamond-s14``) or by path to a JSON file.

    An existing file wins over a built-in of the same name.

    Args:
        name_or_path: a built-in name (``nbst problems`` lists them) or a path to a problem file
            (a :class:`~pathlib.Path` is always read as a path).

    Returns:
        The checked :class:`Problem`.

    Raises:
        ProblemError: one line naming the file, the field and the problem (an unknown name, an
            unreadable or invalid file).
    """
    s = str(name_or_path)
    p = Path(s)
    if p.is_file() or isinstance(name_or_path, Path):
        return problem_from_dict(read_json(p), source=str(p), default_name=p.stem)
    names = builtin_names()
    if s in names:
        return problem_from_dict(parse_json(_builtin_text(s), f"<built-in {s}>"), source=f"<built-in {s}>")
    if p.suffix.lower() == ".json" or "/" in s or "\\" in s or p.exists():
        return problem_from_dict(read_json(p), source=str(p), default_name=p.stem)
    close = difflib.get_close_matches(s, names, n=3, cutoff=0.4)
    hint = f"; did you mean {', '.join(close)}?" if close else ""
    raise ProblemError(s, "", f"no such file and no built-in problem of that name "
                              f"(built-ins: {', '.join(names)}){hint}")


# --------------------------------------------------------------------------- validation

class _Checker:
    """Typed field access with error paths."""

    def __init__(self, source: str):
        self.source = source

    def fail(self, path: str, reason: str):
        raise ProblemError(self.source, path, reason)

    def obj(self, v, path: str) -> dict:
        if not isinstance(v, dict):
            self.fail(path, f"must be a JSON object, got {_jtype(v)}")
        return v

    def get(self, d: dict, key: str, path: str):
        if key not in d:
            self.fail(_join(path, key), "missing (required field)")
        return d[key]

    def number(self, v, path: str, *, positive: bool = False) -> float:
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            self.fail(path, f"must be a number, got {_jtype(v)}")
        try:
            x = float(v)
        except OverflowError:  # an integer beyond float64
            self.fail(path, f"is too large ({len(str(abs(v)))} digits); numbers must be finite float64 values")
        if not math.isfinite(x):
            self.fail(path, f"must be finite, got {v}")
        if positive and x <= 0:
            self.fail(path, f"must be > 0, got {_fmt(x)}")
        return x

    def pair(self, v, path: str) -> tuple[float, float]:
        if not isinstance(v, list) or len(v) != 2:
            got = f"a list of {len(v)}" if isinstance(v, list) else _jtype(v)
            self.fail(path, f"must be a list of 2 numbers [x, y], got {got}")
        return self.number(v[0], f"{path}[0]"), self.number(v[1], f"{path}[1]")

    def boolean(self, v, path: str) -> bool:
        if not isinstance(v, bool):
            self.fail(path, f"must be true or false, got {_jtype(v)}")
        return v

    def string(self, v, path: str) -> str:
        if not isinstance(v, str):
            self.fail(path, f"must be a string, got {_jtype(v)}")
        return v

    def text(self, v, path: str, *, max_chars: int, allow_newlines: bool = False) -> str:
        """A string shown to people (titles, terminal, HTML): bounded, no control characters."""
        s = self.string(v, path)
        if len(s) > max_chars:
            self.fail(path, f"{len(s):,} characters; at most {max_chars:,}")
        why = bad_text(s, allow_newlines=allow_newlines)
        if why:
            self.fail(path, why)
        return s

    def within(self, x: float, lo: float, hi: float, path: str, why: str) -> float:
        if not lo <= x <= hi:
            self.fail(path, f"{_fmt(x)} is outside [{_fmt(lo)}, {_fmt(hi)}] ({why})")
        return x


def _join(path: str, key: str) -> str:
    return f"{path}.{key}" if path else key


def _jtype(v) -> str:
    if v is None:
        return "null"
    if isinstance(v, bool):
        return "a boolean"
    if isinstance(v, (int, float)):
        return f"the number {v}"
    if isinstance(v, str):
        return f"the string {v!r}" if len(v) < 40 else "a string"
    if isinstance(v, list):
        return "a list"
    if isinstance(v, dict):
        return "an object"
    return type(v).__name__


def _fmt(x: float) -> str:
    return f"{x:g}"


def problem_from_dict(d: Any, *, source: str = "<dict>", default_name: str = "problem") -> Problem:
    """Validate a decoded problem JSON object and build a :class:`Problem`.

    Checks the format's rules and the accepted domain of ``nbst.domain``.
    """
    c = _Checker(source)
    c.obj(d, "")
    kind = d.get("kind")
    if isinstance(kind, str) and kind.startswith("nbst-bowling-"):  # a bowling throw or atlas file given as a problem
        what = "an atlas of bowling throws" if kind.endswith("atlas") else "a bowling throw file"
        c.fail("kind", f"this is {what}, not a problem: replay it with `nbst bowl replay`, film it with `nbst render`")
    if "name" in d:
        name = c.text(d["name"], "name", max_chars=D.MAX_NAME_CHARS)
    else:  # a file's stem: not the user's JSON, so made printable rather than refused
        name = plain(str(default_name))[: D.MAX_NAME_CHARS]
    description = c.text(d.get("description", ""), "description", max_chars=D.MAX_DESCRIPTION_CHARS,
                         allow_newlines=True)
    W, H = c.pair(c.get(d, "box", ""), "box")
    if W <= 0 or H <= 0:
        c.fail("box", f"width and height must be > 0, got [{_fmt(W)}, {_fmt(H)}]")
    c.within(W, D.BOX_MIN, D.BOX_MAX, "box[0]", "box sides must lie in this range; rescale the length unit")
    c.within(H, D.BOX_MIN, D.BOX_MAX, "box[1]", "box sides must lie in this range; rescale the length unit")
    t_final = c.number(c.get(d, "t_final", ""), "t_final", positive=True)
    c.within(t_final, D.T_FINAL_MIN, D.T_FINAL_MAX, "t_final", "seconds; rescale the time unit")
    R = c.number(c.get(d, "target_radius", ""), "target_radius", positive=True)
    diag = math.hypot(W, H)
    if R > diag:
        c.fail("target_radius", f"{_fmt(R)} exceeds the box diagonal {_fmt(diag)}: every position would be "
                                f"acceptable; use at most the diagonal")
    disks = c.get(d, "disks", "")
    if not isinstance(disks, list):
        c.fail("disks", f"must be a list of disk objects, got {_jtype(disks)}")
    if not disks:
        c.fail("disks", "must hold at least one disk")
    if len(disks) > MAX_DISKS:
        c.fail("disks", f"{len(disks)} disks; nbst reads at most {MAX_DISKS:,} (nbst.domain.MAX_DISKS: file size)")
    n = len(disks)
    start = np.empty((n, 2))
    target = np.empty((n, 2))
    radius = np.empty(n)
    mass = np.empty(n)
    cue = np.empty(n, dtype=bool)
    r_min = D.RADIUS_MIN_FRACTION * max(W, H)
    for i, disk in enumerate(disks):
        p = f"disks[{i}]"
        c.obj(disk, p)
        radius[i] = r = c.number(c.get(disk, "radius", p), f"{p}.radius", positive=True)
        if r < r_min:
            c.fail(f"{p}.radius", f"{_fmt(r)} is below {_fmt(D.RADIUS_MIN_FRACTION)} x the box's longer side "
                                  f"({_fmt(r_min)}): collisions would drown in round-off; use a larger radius")
        if 2 * r > min(W, H):
            c.fail(f"{p}.radius", f"{_fmt(r)} is too large for the {_fmt(W)} x {_fmt(H)} box")
        mass[i] = c.number(disk.get("mass", 1.0), f"{p}.mass", positive=True)
        c.within(mass[i], D.MASS_MIN, D.MASS_MAX, f"{p}.mass", "masses must lie in this range; rescale the unit")
        cue[i] = c.boolean(disk.get("cueable", True), f"{p}.cueable")
        for key, arr in (("start", start), ("target", target)):
            x, y = c.pair(c.get(disk, key, p), f"{p}.{key}")
            if not (r <= x <= W - r and r <= y <= H - r):
                c.fail(f"{p}.{key}", f"[{_fmt(x)}, {_fmt(y)}] is not at least the disk's radius {_fmt(r)} "
                                     f"inside the walls of the {_fmt(W)} x {_fmt(H)} box")
            arr[i] = (x, y)
    ratio = mass.max() / mass.min()
    if ratio > D.MAX_MASS_RATIO:
        c.fail(f"disks[{int(mass.argmax())}].mass", f"{_fmt(mass.max())} is {_fmt(ratio)} x the lightest "
                                                    f"disk's mass (disks[{int(mass.argmin())}]); the ratio "
                                                    f"may be at most {_fmt(D.MAX_MASS_RATIO)}")
    pair = first_overlap(start, radius)
    if pair is not None:
        i, j = pair
        c.fail(f"disks[{j}].start", f"overlaps disks[{i}] (centre distance "
                                    f"{_fmt(math.hypot(*(start[j] - start[i])))} < sum of radii "
                                    f"{_fmt(radius[i] + radius[j])})")
    if not cue.any():
        c.fail("disks", "no disk is cueable: at least one disk must be able to move at t = 0")
    for a in (start, target, radius, mass, cue):
        a.setflags(write=False)
    return Problem(name=name, box=(W, H), t_final=t_final, target_radius=R, start=start, target=target,
                   radius=radius, mass=mass, cueable=cue, description=description, source=source, raw=d)


def box_crossings(problem: Problem, velocities) -> np.ndarray:
    """(N,) how many times each disk would cross the box in t_final if it met no
    other disk: |vx| t / (W - 2r) + |vy| t / (H - 2r) (inf for motion along an
    axis the disk fills). Each crossing is one wall event."""
    gaps = np.stack([problem.width - 2 * problem.radius, problem.height - 2 * problem.radius], axis=1)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        v = np.abs(np.asarray(velocities, dtype=float)) * problem.t_final
        k = np.where(v == 0.0, 0.0, v / gaps)
    k[(v > 0) & (gaps <= 0)] = math.inf
    return k.sum(axis=1)


def display_name(text: str) -> str:
    """User text (a problem's name) for matplotlib: ``$`` escaped so it is never
    read as mathtext, control characters written as escapes."""
    return plain(text).replace("$", r"\$")
