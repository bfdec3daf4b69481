"""Progress for long work: a tqdm bar on a terminal, plain lines in a log.

A carriage-return bar is noise in a file or a CI log, so when the stream is not a
terminal :func:`progress_bar` returns a :class:`LineProgress` instead: the same calls
(``update``, ``set_postfix_str``, ``close``, ``n``), one line every
``LOG_INTERVAL`` seconds and one at the end, never a ``\\r``.
"""
from __future__ import annotations

import sys
import time

#: Seconds between two progress lines when stderr is not a terminal (a log, a pipe, CI):
#: often enough to see a run is alive, rare enough to keep a 10-minute run to ~60 lines.
LOG_INTERVAL = 10.0


def _is_tty(stream) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):
        return False


class LineProgress:
    """tqdm's interface as used by nbst, written as whole lines (for non-terminals)."""

    def __init__(self, total=None, *, desc: str = "", unit: str = "it", file=None, initial: int = 0,
                 interval: float = LOG_INTERVAL, disable: bool = False, **_ignored):
        self.total = total
        self.desc = desc
        self.unit = unit
        self.file = file if file is not None else sys.stderr
        self.n = initial
        self.disable = disable
        self.interval = interval
        self.postfix = ""
        self._t0 = time.monotonic()
        self._last = self._t0
        self._closed = False

    def _line(self) -> str:
        elapsed = time.monotonic() - self._t0
        done = f"{self.n:,}" + (f"/{self.total:,}" if self.total else "") + f" {self.unit}s"
        pct = f" ({100.0 * self.n / self.total:.0f}%)" if self.total else ""
        post = f", {self.postfix}" if self.postfix else ""
        eta = (f", ETA {elapsed * (self.total - self.n) / self.n:.0f} s"  # at the mean rate so far
               if self.total and 0 < self.n < self.total else "")
        return f"{self.desc + ': ' if self.desc else ''}{done}{pct} in {elapsed:.0f} s{eta}{post}"

    def _emit(self) -> None:
        if not self.disable:
            print(self._line(), file=self.file, flush=True)
        self._last = time.monotonic()

    def update(self, n: int = 1) -> None:
        self.n += n
        if time.monotonic() - self._last >= self.interval:
            self._emit()

    def set_postfix_str(self, s: str = "", refresh: bool = True) -> None:
        self.postfix = str(s)

    def close(self) -> None:
        if not self._closed:
            self._closed = True
            self._emit()



def progress_bar(**kw):
    """``tqdm(**kw)`` when the stream (``file=``, default stderr) is a terminal, else a
    :class:`LineProgress` with the same keywords."""
    stream = kw.get("file") or sys.stderr
    if _is_tty(stream):
        from tqdm import tqdm

        return tqdm(**kw)
    return LineProgress(**kw)
