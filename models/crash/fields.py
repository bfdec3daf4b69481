"""Strict, typed access to decoded JSON with error paths: the crash script's input gate.

:class:`Fields` checks one value at a time (its type, its domain) and raises
:class:`ScriptError` (an :class:`nbst.errors.InputError`) naming the file, the field as a path
(``vehicles[1].fate.rest.x``) and the problem, in one printable line; unknown keys are refused
(with the nearest known key as a hint).
"""
from __future__ import annotations

import difflib
import math

from nbst.domain import bad_text, plain
from nbst.errors import InputError

__all__ = ["ScriptError", "Fields", "jtype"]


class ScriptError(InputError):
    """A crash script nbst refuses: ``source``, ``field`` (a path) and ``reason``, one line."""

    def __init__(self, source: str, field: str, reason: str):
        self.source, self.field, self.reason = str(source), field, reason
        where = f"{self.source}: {field}" if field else self.source
        super().__init__(plain(f"{where}: {reason}"))


class Fields:
    """Typed, strict access to a decoded JSON object, with error paths."""

    def __init__(self, source: str):
        self.source = source

    def fail(self, path: str, reason: str):
        raise ScriptError(self.source, path, reason)

    def obj(self, v, path: str, keys: tuple, required: tuple = ()) -> dict:
        if not isinstance(v, dict):
            self.fail(path, f"must be a JSON object, got {jtype(v)}")
        for k in v:
            if k not in keys:
                close = difflib.get_close_matches(str(k), keys, n=1, cutoff=0.6)
                hint = f" (did you mean {close[0]!r}?)" if close else f"; known: {', '.join(keys)}"
                self.fail(_join(path, str(k)[:40]), f"unknown key{hint}")
        for k in required:
            if k not in v:
                self.fail(_join(path, k), "missing (required field)")
        return v

    def number(self, v, path: str, lo: float | None = None, hi: float | None = None, why: str = "") -> float:
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            self.fail(path, f"must be a number, got {jtype(v)}")
        try:
            x = float(v)
        except OverflowError:
            self.fail(path, f"is too large ({len(str(abs(v)))} digits); numbers must be finite float64 values")
        if not math.isfinite(x):
            self.fail(path, f"must be finite, got {v}")
        if lo is not None and hi is not None and not lo <= x <= hi:
            self.fail(path, f"{x:g} is outside [{lo:g}, {hi:g}]" + (f" ({why})" if why else ""))
        return x

    def range(self, v, path: str, lo: float, hi: float, why: str = "") -> tuple[float, float]:
        """A number (fixed) or [lo, hi] with lo <= hi, inside [lo, hi] of the domain."""
        if isinstance(v, list):
            if len(v) != 2:
                self.fail(path, f"a range is a number or a list of 2 numbers [low, high], got a list of {len(v)}")
            a = self.number(v[0], f"{path}[0]", lo, hi, why)
            b = self.number(v[1], f"{path}[1]", lo, hi, why)
            if a > b:
                self.fail(path, f"[{a:g}, {b:g}]: the low end is above the high end")
            return a, b
        x = self.number(v, path, lo, hi, why)
        return x, x

    def integer(self, v, path: str, lo: float, hi: float) -> int:
        if isinstance(v, bool) or not isinstance(v, int):
            self.fail(path, f"must be a whole number, got {jtype(v)}")
        if not lo <= v <= hi:
            self.fail(path, f"{v} is outside [{lo}, {hi}]")
        return v

    def text(self, v, path: str, max_chars: int, allow_newlines: bool = False) -> str:
        if not isinstance(v, str):
            self.fail(path, f"must be a string, got {jtype(v)}")
        if len(v) > max_chars:
            self.fail(path, f"{len(v):,} characters; at most {max_chars:,}")
        why = bad_text(v, allow_newlines=allow_newlines)
        if why:
            self.fail(path, why)
        return v

    def choice(self, v, path: str, options: tuple) -> str:
        if not isinstance(v, str) or v not in options:
            self.fail(path, f"must be one of {', '.join(options)}, got {jtype(v)}")
        return v

    def boolean(self, v, path: str) -> bool:
        if not isinstance(v, bool):
            self.fail(path, f"must be true or false, got {jtype(v)}")
        return v

    def point(self, v, path: str) -> tuple[float, float]:
        if not isinstance(v, list) or len(v) != 2:
            self.fail(path, "must be a list of 2 numbers [x, y] (m)")
        return self.number(v[0], f"{path}[0]"), self.number(v[1], f"{path}[1]")


def _join(path: str, key: str) -> str:
    return f"{path}.{key}" if path else key


def jtype(v) -> str:
    if v is None:
        return "null"
    if isinstance(v, bool):
        return "a boolean"
    if isinstance(v, (int, float)):
        return f"the number {v:g}" if isinstance(v, float) else f"the number {str(v)[:20]}"
    if isinstance(v, str):
        return f"the string {v[:30]!r}"
    return "a list" if isinstance(v, list) else "an object"


