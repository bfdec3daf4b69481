"""The input gate of every bowling file: both halves' throw files, their atlases and checkpoints.

Every bowling file comes in through :func:`read_doc`: a regular file only (checked by ``stat``
before it is opened: a FIFO would block, a device never end), nbst's core JSON reader
(:func:`nbst.problem.read_json`: a size cap first, strict JSON, a depth cap, integers of at
most 400 digits), then no number that is not a finite float64: an integer too large for a
float (a 320-digit ``qpos0`` entry, a 400-digit ``rpm``) is refused here, naming its field, as
the problem reader refuses one, before any checker turns it into a float. The format's own
checker (:mod:`.deck.shotfile`, :mod:`.lane.throwfile`) then checks every field. Every failure
is one :class:`BowlingFileError` line naming the file and the field.
"""
from __future__ import annotations

import math
import os
import stat
from pathlib import Path
from typing import NoReturn

from nbst.errors import InputError
from nbst.problem import ProblemError, read_json

__all__ = ["BowlingFileError", "regular_file", "read_doc", "fail", "non_finite", "too_large"]


class BowlingFileError(InputError):
    """A bowling file (a throw file of either half, an atlas, a checkpoint) that cannot be read: one line naming the
    file and the field."""


def regular_file(path, what: str = "") -> Path:
    """``path`` if it is a regular file (stat, before any open), else BowlingFileError: a FIFO,
    device, socket or directory is refused without being opened."""
    p = Path(path)
    where = f"{p}: {what}: " if what else f"{p}: "
    try:
        st = os.stat(p)
    except FileNotFoundError:
        raise BowlingFileError(f"{where}no such file") from None
    except (OSError, ValueError) as e:  # ValueError: a NUL in the name
        raise BowlingFileError(f"{where}cannot read ({getattr(e, 'strerror', None) or e})") from None
    if stat.S_ISDIR(st.st_mode):
        raise BowlingFileError(f"{where}is a directory, not a file")
    if not stat.S_ISREG(st.st_mode):
        raise BowlingFileError(f"{where}is not a regular file (a FIFO, device or socket); nbst reads regular "
                               f"files only")
    return p


def fail(src, field: str, why: str) -> NoReturn:
    raise BowlingFileError(f"{src}: {field}: {why}" if field else f"{src}: {why}")


def _walk(obj, path: str):
    stack = [(obj, path)]
    while stack:
        o, p = stack.pop()
        yield o, p
        if isinstance(o, dict):
            stack.extend((v, f"{p}.{k}" if p else str(k)) for k, v in o.items())
        elif isinstance(o, list):
            stack.extend((v, f"{p}[{i}]") for i, v in enumerate(o))


def non_finite(obj, path: str = ""):
    """First (path, value) of a non-finite float in decoded JSON (NaN, Infinity), or None."""
    for o, p in _walk(obj, path):
        if isinstance(o, float) and not math.isfinite(o):
            return p, o
    return None


def too_large(obj, path: str = ""):
    """First (path, digits) of an integer too large for a float64 in decoded JSON, or None."""
    for o, p in _walk(obj, path):
        if isinstance(o, int) and not isinstance(o, bool):
            try:
                float(o)
            except OverflowError:
                return p, len(str(abs(o)))
    return None


def read_doc(path):
    """Decoded JSON of a bowling file through the gate (see the module docstring)."""
    regular_file(path)
    try:
        doc = read_json(path)
    except ProblemError as e:
        raise BowlingFileError(str(e)) from None
    big = too_large(doc)
    if big:
        fail(path, big[0], f"is too large ({big[1]} digits); numbers must be finite float64 values")
    return doc
