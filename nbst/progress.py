"""Progress for long work: one bar for every command, on a terminal or in a log.

The rules (issue 35, "progress that tells the truth"):

* **A line at once.** A bar on a terminal draws itself when it is made (in a log, after
  :data:`FIRST_LINE_S`, unless the work is done by then), so a command that makes its bar before the
  slow part (compiling, loading, a blocking stage) shows a line within 2 s of its start; while no
  update comes, a ticker thread keeps the elapsed time moving.
* **One clock.** The command's clock starts when the command starts (:func:`start_clock`, called
  by ``nbst.cli.main``); a bar made with ``start=command_start()`` counts from there, so the bar and
  the summary that quotes :attr:`Bar.seconds` read the same clock.
* **An ETA only from measured rates.** Nothing is estimated until the first update has come (the
  warm-up: compiling, building a scene, the first trial all happen before it) and
  :data:`ETA_MIN_S` seconds of work after it have been measured; the rate is that of the last
  :data:`ETA_WINDOW_S` seconds. A bar whose total is a bound, not the work that will be done
  (``bound=True``: a budget the search may stop short of), never shows an ETA.
* **The last line is the summary's state.** :meth:`Bar.close` draws the final line from the
  bar's own count, clock and note; :attr:`Bar.seconds` and :attr:`Bar.n` are what the command's
  summary quotes (formatted by :func:`seconds_text` and :func:`count_text`, the same functions), so
  the two cannot disagree.

On a terminal the bar is one line redrawn with a carriage return; in a file or a pipe (a log,
CI) it is whole lines, one every :data:`LOG_INTERVAL` seconds, never a ``\\r``. Both end with the
final line. ``quiet=True`` prints nothing but still counts, so the summary reads the same values.

Use::

    from nbst import progress
    with progress.Bar("render v.mp4", total=len(times), unit="frame") as bar:
        for ...:
            bar.update()
            bar.note(f"best cost {c:.6g}")
    print(f"wrote v.mp4: {progress.count_text(bar.n)} frames in {progress.seconds_text(bar.seconds)}")

:func:`progress_bar` keeps the older tqdm-style keywords (``total=, desc=, unit=, file=, disable=,
initial=``; tqdm's display options are accepted and ignored) and returns a :class:`Bar`.
"""
from __future__ import annotations

import shutil
import sys
import threading
import time
from collections import deque

__all__ = ["LOG_INTERVAL", "TTY_INTERVAL", "TICK_S", "FIRST_LINE_S", "ETA_MIN_S", "ETA_WINDOW_S", "start_clock",
           "command_start", "since_start", "seconds_text", "count_text", "Bar", "progress_bar", "LineProgress"]

#: Seconds between two progress lines when the stream is not a terminal (a log, a pipe, CI):
#: often enough to see a run is alive, rare enough to keep a 10-minute run to ~60 lines.
LOG_INTERVAL = 10.0
#: Seconds between two redraws of a terminal bar (updates in between only count).
TTY_INTERVAL = 0.2
#: Seconds between two ticks of the elapsed time while no update comes (a terminal bar).
TICK_S = 1.0
#: Seconds after its clock's start (``start``) at which a bar in a log writes its first line (work
#: that ends sooner writes only its final line: a log is not filled with the starts of short
#: stages; a bar whose clock started with the command writes it as soon as it is made); a
#: terminal bar shows at once.
FIRST_LINE_S = 1.0
#: Seconds of work measured after the first update before an ETA is shown (the warm-up before
#: the first update, compiling say, is never part of a rate).
ETA_MIN_S = 2.0
#: The ETA's rate is that of the last this-many seconds (a search that slows, a render whose
#: scenes grow, is followed within this long).
ETA_WINDOW_S = 30.0

_now = time.monotonic  # the clock of every bar (a test may replace it)
_start = _now()


def start_clock(t: float | None = None) -> float:
    """Start the command's clock now (or at ``t``, a ``time.monotonic()`` value); returns it.
    ``nbst.cli.main`` calls it first thing."""
    global _start
    _start = _now() if t is None else float(t)
    return _start


def command_start() -> float:
    """``time.monotonic()`` when the command started (:func:`start_clock`)."""
    return _start


def since_start() -> float:
    """Seconds since the command started."""
    return _now() - _start


def seconds_text(s: float) -> str:
    """A duration as every progress line and summary writes it: ``0.62 s``, ``12.3 s``, ``451 s``."""
    s = max(0.0, float(s))
    if s < 10:
        return f"{s:.2f} s"
    if s < 100:
        return f"{s:.1f} s"
    return f"{s:.0f} s"


def count_text(n) -> str:
    """A count as every progress line and summary writes it: ``20,024``."""
    return f"{int(n):,}"


def _is_tty(stream) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):
        return False


class Bar:
    """Progress of one piece of work (see the module doc).

    desc  : what runs (``"nbst validate: MuJoCo, fixed steps"``)
    total : the units of work it will take, or None (then no percentage and no ETA)
    unit  : the unit's name, singular (``"step"``; plural by an ``s``); None shows no count
    bound : ``total`` is a budget the work may stop short of: no ETA, "of at most" instead of "/"
    start : ``time.monotonic()`` its clock starts from (default now; ``command_start()``: the command's)
    file  : the stream (default stderr); a terminal gets a redrawn line, anything else whole lines
    quiet : print nothing (the counts and the clock still run: the summary reads them)
    interval : seconds between two lines in a log (default :data:`LOG_INTERVAL`)
    ticker : keep the elapsed time moving while no update comes (a daemon thread)
    """

    def __init__(self, desc: str = "", total=None, *, unit: str | None = "step", bound: bool = False,
                 start: float | None = None, file=None, quiet: bool = False, initial: int = 0,
                 interval: float | None = None, ticker: bool = True):
        self.desc = desc
        self.total = int(total) if total else None
        self.unit = unit
        self.bound = bool(bound)
        self.file = file if file is not None else sys.stderr
        self.quiet = bool(quiet)
        self.n = int(initial)
        self.postfix = ""
        self.t0 = _now() if start is None else float(start)
        self._end: float | None = None
        self.tty = (not self.quiet) and _is_tty(self.file)
        self.interval = (TTY_INTERVAL if self.tty else LOG_INTERVAL) if interval is None else float(interval)
        self._samples: deque = deque()  # (t, n) from the first update on: the measured rates
        self._first: tuple | None = None
        self._last_draw = -1e300
        self._width = 0
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread = None
        if not self.quiet:
            if self.tty or not ticker:
                self._draw(_now())
            else:  # a log: the ticker writes the first line after FIRST_LINE_S, unless the work ended first
                self._last_draw = _now()
            if ticker:
                self._thread = threading.Thread(target=self._tick, name="nbst-progress", daemon=True)
                self._thread.start()

    # ------------------------------------------------------------------ what the bar says

    @property
    def seconds(self) -> float:
        """Seconds on the bar's clock: up to now, or to :meth:`close` once closed."""
        return (_now() if self._end is None else self._end) - self.t0

    @property
    def closed(self) -> bool:
        return self._end is not None

    def eta(self, now: float | None = None) -> float | None:
        """Seconds left at the rate measured over the last :data:`ETA_WINDOW_S` seconds, or None
        (no total, a bound, still warming up, or nothing measured)."""
        if not self.total or self.bound or self._first is None or self.n >= self.total:
            return None
        now = _now() if now is None else now
        if now - self._first[0] < ETA_MIN_S or not self._samples:
            return None
        t_old, n_old = self._samples[0]
        if now - t_old <= 0 or self.n <= n_old:
            return None
        rate = (self.n - n_old) / (now - t_old)
        return (self.total - self.n) / rate

    def line(self, now: float | None = None) -> str:
        """The text the bar shows now."""
        now = _now() if now is None else now
        end = now if self._end is None else self._end
        parts = []
        if self.unit:
            units = self.unit + ("" if self.unit.endswith("s") else "s")
            if self.total:
                sep = " of at most " if self.bound else "/"
                pct = "" if self.bound else f" ({100.0 * self.n / self.total:.0f}%)"
                parts.append(f"{count_text(self.n)}{sep}{count_text(self.total)} {units}{pct} in "
                             f"{seconds_text(end - self.t0)}")
            else:
                parts.append(f"{count_text(self.n)} {units} in {seconds_text(end - self.t0)}")
        else:
            parts.append(seconds_text(end - self.t0))
        if self._end is None:
            eta = self.eta(now)
            if eta is not None:
                parts.append(f"ETA {seconds_text(eta)}")
        if self.postfix:
            parts.append(self.postfix)
        return (f"{self.desc}: " if self.desc else "") + ", ".join(parts)

    # ------------------------------------------------------------------ updating

    def update(self, k: int = 1) -> None:
        """``k`` more units done."""
        self.set(self.n + int(k))

    def set(self, n: int) -> None:
        """``n`` units done in all."""
        now = _now()
        self.n = int(n)
        if self._first is None:
            self._first = (now, self.n)
            self._samples.append((now, self.n))
        elif now - self._samples[-1][0] >= 0.25:
            self._samples.append((now, self.n))
            while len(self._samples) > 2 and now - self._samples[1][0] >= ETA_WINDOW_S:
                self._samples.popleft()
        if not self.quiet and now - self._last_draw >= self.interval:
            self._draw(now)

    def note(self, text: str = "") -> None:
        """The state after the counts (``"best cost 0.017, 2/5 disks on target"``); shown at the next line."""
        self.postfix = str(text)

    def set_postfix_str(self, s: str = "", refresh: bool = True) -> None:
        """tqdm's name for :meth:`note`."""
        self.note(s)

    def write(self, text: str) -> None:
        """Print a line of its own without tearing the bar (a terminal bar is drawn again below it)."""
        if self.quiet:
            return
        with self._lock:
            if self.tty:
                self.file.write("\r" + " " * self._width + "\r")
                self._width = 0
            self.file.write(text + "\n")
            self.file.flush()
        if self.tty and self._end is None:
            self._draw(_now())

    def close(self, *, note: str | None = None, n: int | None = None, end: float | None = None) -> None:
        """Stop the clock (at ``end``, a ``time.monotonic()`` value, default now) and draw the final
        line, with the final count ``n`` and ``note`` if given. Idempotent: one final line."""
        if self._end is not None:
            return
        if n is not None:
            self.n = int(n)
        if note is not None:
            self.postfix = str(note)
        self._end = _now() if end is None else float(end)
        self._stop.set()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join(timeout=2.0)
        if not self.quiet:
            self._draw(self._end, final=True)

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb):
        self.close()

    # ------------------------------------------------------------------ drawing

    def _draw(self, now: float, final: bool = False) -> None:
        with self._lock:
            if self._end is not None and not final:
                return
            text = self.line(now)
            try:
                if self.tty:
                    cols = max(20, shutil.get_terminal_size((100, 24)).columns - 1)
                    text = text if len(text) <= cols else text[: cols - 1] + "…"
                    pad = max(0, self._width - len(text))
                    self.file.write("\r" + text + " " * pad + ("\n" if final else ""))
                    self._width = 0 if final else len(text)
                else:
                    self.file.write(text + "\n")
                self.file.flush()
            except (OSError, ValueError):  # a closed or broken stream: progress is not worth an error
                pass
            self._last_draw = now

    def _tick(self) -> None:
        wait = TICK_S if self.tty else max(self.interval, TICK_S)
        if not self.tty:  # the first line FIRST_LINE_S after the bar's clock started (at once if that has passed)
            if self._stop.wait(max(0.0, self.t0 + FIRST_LINE_S - _now())):
                return
            self._draw(_now())
        while not self._stop.wait(wait):
            now = _now()
            if now - self._last_draw >= wait:
                self._draw(now)


def progress_bar(*, total=None, desc: str = "", unit: str = "it", file=None, disable: bool = False,
                 initial: int = 0, bound: bool = False, start: float | None = None, interval: float | None = None,
                 ticker: bool = True, **_display) -> Bar:
    """A :class:`Bar` from tqdm-style keywords (``leave``, ``unit_scale``, ``dynamic_ncols``,
    ``smoothing`` and other display options are ignored). ``disable`` is ``quiet``."""
    return Bar(desc, total, unit=unit, file=file, quiet=disable, initial=initial, bound=bound, start=start,
               interval=interval, ticker=ticker)


#: The older name of the log form (every Bar writes whole lines when its stream is not a terminal).
LineProgress = Bar
