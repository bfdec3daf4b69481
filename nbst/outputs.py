"""Output paths and the one way nbst writes a file.

Checked before the work (``prepare_output``): a long solve or render must not end in a
traceback because ``-o`` names a folder that cannot be written, a special file, or the
command's own input. ``prepare_output`` creates missing parent folders and proves the
folder writable by creating (and removing) a scratch file there.

Written atomically (``atomic_path``, ``write_bytes_atomic``, ``write_text_atomic``,
``write_json_atomic``): every writer fills a hidden partial file beside the target,
fsyncs it and renames it over the target, so ``path`` holds the old file or the whole
new one, never a truncated one (a full disk leaves the previous file byte-identical).

* Nothing is written through a symbolic link: an output path that is a link (to a file, a
  folder or nothing) is refused, as are special files (FIFO, device, socket: rename would swap
  ``/dev/null`` for a regular file) and folders where a file is expected; one line, exit 2, the
  link and what it points to untouched. (A folder on the way to the path may be a link: the file
  is written in that folder. If a link appears at the path after the check, the rename replaces
  the link itself, never the file it points to.)
* Partial files are named ``.STEM.partial-PID[-TAG]SUFFIX``; one whose PID is no longer
  alive (a writer killed by SIGKILL) is removed by the next write to the same target.

The CLI turns ``OutputError`` into one line and exit status 2. This module also holds
the signal helpers the writers need: ``interrupt_once`` (every command runs inside it: the
first SIGINT, SIGTERM or SIGHUP stops the work like Ctrl-C, later ones wait for the cleanup,
so partial files are removed and the best-so-far file written), ``signals_deferred`` (the
signals held while a result file is written), ``signals_blocked`` and ``die_with_parent``
(worker processes that never outlive their parent, even after SIGKILL).

Length: the writer and the signal handling it relies on (a signal during the rename waits for it,
partial files of killed writers are removed) are one contract; split, each half would have to
restate the other's rules.
"""
from __future__ import annotations

import json
import math
import os
import re
import secrets
import signal
import stat
import threading
import time
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Iterator

import numpy as np
from nbst.errors import OutputError  # re-exported here


__all__ = ["not_a_file", "refuse_not_a_file", "refuse_special", "refuse_same_file", "prepare_output", "partial_path",
           "remove_stale_partials", "PartialFile", "atomic_path", "write_bytes_atomic", "write_text_atomic",
           "json_safe", "dumps_strict", "write_json_atomic", "STOP_SIGNALS", "INSIST_S", "interrupt_once",
           "ignore_stop_signals", "stop_requested", "sigterm_as_interrupt", "signals_deferred", "signals_blocked", "PARENT_POLL_S",
           "die_with_parent"]

_SPECIAL = ((stat.S_ISFIFO, "a named pipe (FIFO)"), (stat.S_ISCHR, "a character device"),
            (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"))


def _special_kind(path) -> str | None:
    """What special file ``path`` is (following symlinks), or None for a regular file, folder or nothing."""
    try:
        mode = os.stat(path).st_mode
    except OSError:
        return None
    for test, name in _SPECIAL:
        if test(mode):
            return name
    return None


def _why(e: OSError) -> str:
    return e.strerror or str(e)


def not_a_file(path) -> str | None:
    """Why nbst will not write a file at ``path``, or None: "a symbolic link (to X)", a special file's
    kind, "a folder". The path itself is looked at (``lstat``): a link is never followed."""
    try:
        mode = os.lstat(path).st_mode
    except OSError:
        return None
    if stat.S_ISLNK(mode):
        try:
            to = os.readlink(path)
        except OSError:
            to = "?"
        return f"a symbolic link (to {to})"
    if stat.S_ISDIR(mode):
        return "a folder"
    for test, name in _SPECIAL:
        if test(mode):
            return name
    return None


def _refuse_slash(path, option: str) -> None:
    """OutputError if the name ``path`` ends in a slash (a folder's name; ``Path()`` would drop the
    slash and write the file it names)."""
    if isinstance(path, str) and path.endswith(("/", os.sep)):
        raise OutputError(f"{option} {path}: ends in a slash, which names a folder; expected a file name")


def refuse_not_a_file(path, *, option: str = "-o") -> None:
    """OutputError (one line) if ``path`` is a symbolic link, a FIFO, device or socket, or a folder:
    nbst writes regular files only, and never through a link. Every writer of nbst calls it."""
    _refuse_slash(path, option)
    kind = not_a_file(path)
    if kind is None:
        return
    if kind.startswith("a symbolic link"):
        raise OutputError(f"{option} {path}: is {kind}; nbst never writes through a link (that would replace "
                          f"the file it points to): remove the link or give another file name")
    if kind == "a folder":
        raise OutputError(f"{option} {path}: is a folder; expected a file name")
    raise OutputError(f"{option} {path}: is {kind}, not a regular file; nbst writes regular files only "
                      f"(it never replaces special files): give a file name")


#: The older name of :func:`refuse_not_a_file`.
refuse_special = refuse_not_a_file


def refuse_same_file(path, inputs=(), *, option: str = "-o", outputs=()) -> None:
    """OutputError if output ``path`` is the same file as one of ``inputs`` (files the command
    reads; a name that is not an existing file, such as a built-in problem name, is skipped) or
    of ``outputs`` (the command's other output files, existing or not). None entries are skipped.

    Compared by ``os.path.samefile`` when both exist (so symlinks and hard links count), else
    by resolved path.
    """
    for other, must_exist in [(x, True) for x in inputs] + [(x, False) for x in outputs]:
        if other is None or (must_exist and not os.path.isfile(other)):
            continue
        try:
            same = (os.path.samefile(path, other) if os.path.exists(path) and os.path.exists(other)
                    else os.path.realpath(path) == os.path.realpath(other))
        except OSError:
            same = False
        if same:
            raise OutputError(f"{option} {path}: is the same file as {other}, which this command also reads or "
                              f"writes; give another file name")


def prepare_output(path, *, directory: bool = False, option: str = "-o", inputs=(), outputs=(),
                   files=()) -> Path:
    """Make ``path``'s folder (or ``path`` itself with ``directory=True``) exist and be writable.

    Refuses (OutputError naming ``option``, the path and the reason) what ``refuse_not_a_file``
    refuses (a symbolic link, a special file, a folder where a file is expected), a file where a
    folder is expected, and an output that is the same file as one of ``inputs`` (files the command
    reads) or ``outputs`` (its other outputs): see ``refuse_same_file``. With ``directory=True``,
    ``files`` names the files the command will write in the folder: each is checked the same way
    before any work. Returns ``path`` as a Path.
    """
    p = Path(path)
    if not directory:
        _refuse_slash(path, option)   # before Path() drops it: "sol.json/" names a folder, not a file
        refuse_same_file(p, inputs, option=option, outputs=outputs)  # first: "the same file as the input" says more
        refuse_not_a_file(p, option=option)
        folder = p.parent
    else:
        folder = p
        for name in files:
            refuse_not_a_file(p / name, option=option)
    if directory and p.is_symlink() and not p.exists():
        raise OutputError(f"{option} {path}: is a symbolic link to nothing (to {os.readlink(p)}); give a folder, "
                          f"or a link to one")
    try:
        if p.exists() and directory and not p.is_dir():
            raise OutputError(f"{option} {path}: is {_special_kind(p) or 'a file'}; expected a folder")
        folder.mkdir(parents=True, exist_ok=True)
        fd, scratch = _mkpartial(folder / ".nbst-write-test")
        os.close(fd)
        os.unlink(scratch)
    except OSError as e:
        raise OutputError(f"{option} {path}: cannot write there ({_why(e)})") from None
    return p


# --------------------------------------------------------------------------- partial files

def partial_path(target, *, tag: str = "", suffix: str | None = None) -> Path:
    """The hidden partial file for ``target`` written by this process: ``.STEM.partial-PID[-TAG]SUFFIX``
    beside it (``suffix``: by default the target's, so writers that pick the format by extension,
    matplotlib and ffmpeg, pick the one the user named)."""
    t = Path(target)
    return t.with_name(f".{t.stem}.partial-{os.getpid()}{'-' + tag if tag else ''}"
                       f"{t.suffix if suffix is None else suffix}")


def _pid_alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OSError):
        return True  # exists (someone else's) or cannot tell: leave its file alone
    return True


def remove_stale_partials(target, *, suffix: str | None = None) -> list[Path]:
    """Remove partial files of ``target`` left by writers that no longer run (killed by SIGKILL);
    returns the removed paths. Files of live processes are left alone. ``suffix``: also those
    with this extension (see ``partial_path``)."""
    t = Path(target)
    sufs = "|".join(re.escape(x) for x in {t.suffix, t.suffix if suffix is None else suffix})
    pat = re.compile(r"\." + re.escape(t.stem) + r"\.partial-(\d+)(?:-[0-9A-Za-z]+)?(?:" + sufs + ")$")
    removed: list = []
    try:
        names = os.listdir(t.parent if str(t.parent) else ".")
    except OSError:
        return removed
    for name in names:
        m = pat.match(name)
        if m and not _pid_alive(int(m.group(1))):
            f = t.with_name(name)
            try:
                if stat.S_ISREG(os.lstat(f).st_mode):
                    os.unlink(f)
                    removed.append(f)
            except OSError:
                pass
    return removed


def _mkpartial(target, suffix: str | None = None):
    """Create a fresh partial file for ``target`` (O_EXCL): (fd, path)."""
    for _ in range(100):
        p = partial_path(target, tag=secrets.token_hex(3), suffix=suffix)
        try:
            return os.open(p, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600), str(p)
        except FileExistsError:
            continue
    raise FileExistsError(f"no free partial file name beside {target}")


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _fsync_dir(folder) -> None:
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


class PartialFile:
    """The one way nbst makes an output file: a hidden partial file beside ``path``, filled by the
    caller (``.path``, which exists and is empty), then :meth:`commit` (checked, fsynced, renamed
    over ``path``) or :meth:`discard`. Refuses what ``refuse_not_a_file`` refuses; removes the
    partial files of dead writers of the same target first. ``atomic_path`` wraps it for a block;
    the video writer holds one while ffmpeg runs.
    """

    def __init__(self, path, *, option: str = "-o"):
        refuse_not_a_file(path, option=option)
        self.target = Path(path)
        self.option = option
        self.existed = self.target.exists()
        self.done = False
        try:
            self.target.parent.mkdir(parents=True, exist_ok=True)
            remove_stale_partials(self.target)
            fd, self.path = _mkpartial(self.target)
            os.close(fd)
        except OSError as e:
            raise OutputError(f"{option} {path}: cannot write there ({_why(e)})") from None

    def kept(self) -> str:
        """What is at the target after a failed write: the previous file, or nothing."""
        return "the previous file is unchanged" if self.existed else "nothing was written"

    def commit(self, check=None) -> None:
        """``check(partial path)`` (raises OutputError or returns a reason it is bad, or None), then fsync
        and rename over the target, signals held. Any failure: the partial file is removed, the target
        untouched, and OutputError (one line) raised."""
        try:
            why = check(self.path) if check is not None else None
            if why:
                raise OutputError(f"{self.option} {self.target}: the written file is damaged ({why}); {self.kept()}")
            with signals_deferred():  # the file is finished: a signal now waits for the rename
                try:
                    st = os.lstat(self.target)
                    mode = stat.S_IMODE(st.st_mode) if stat.S_ISREG(st.st_mode) else 0o666 & ~_umask()
                except OSError:
                    mode = 0o666 & ~_umask()
                os.chmod(self.path, mode)  # the partial file is 0600; the result gets the old file's or the usual mode
                fd = os.open(self.path, os.O_RDONLY)
                try:
                    os.fsync(fd)
                finally:
                    os.close(fd)
                os.replace(self.path, self.target)  # a link that appeared at the target is replaced, not followed
                self.done = True
                _fsync_dir(self.target.parent)
        except BaseException as e:
            self.discard()
            if isinstance(e, OSError):
                raise OutputError(f"{self.option} {self.target}: cannot write ({_why(e)}); {self.kept()}") from None
            raise

    def discard(self) -> None:
        """Remove the partial file (a no-op once committed); a second signal cannot stop it."""
        if self.done:
            return
        self.done = True
        with signals_deferred(reraise=False):
            try:
                os.unlink(self.path)
            except OSError:
                pass


@contextmanager
def atomic_path(path, *, option: str = "-o", check=None) -> Iterator[str]:
    """Yield a partial file's path for a writer that wants a file name (savefig, PIL).

    The partial file sits beside ``path``, has its suffix (so writers that pick the format by
    extension still do), and exists, empty, when yielded. When the block ends it is checked
    (``check``, see ``PartialFile.commit``), fsynced and renamed over ``path``; if the block raises
    it is removed, and an OSError (a full disk) becomes one-line OutputError.
    """
    part = PartialFile(path, option=option)
    try:
        yield part.path
    except BaseException as e:
        part.discard()
        if isinstance(e, OSError):
            raise OutputError(f"{option} {path}: cannot write ({_why(e)}); {part.kept()}") from None
        raise
    part.commit(check)


def write_bytes_atomic(path, data: bytes, *, option: str = "-o") -> None:
    """Write ``data`` to ``path`` atomically (see the module doc); OutputError on failure."""
    with atomic_path(path, option=option) as tmp:
        fd = os.open(tmp, os.O_WRONLY)
        try:
            view = memoryview(data)
            while view:
                view = view[os.write(fd, view):]
        finally:
            os.close(fd)


def write_text_atomic(path, text: str, *, option: str = "-o") -> None:
    """Write ``text`` (UTF-8) to ``path`` atomically; OutputError on failure."""
    write_bytes_atomic(path, text.encode("utf-8"), option=option)


def json_safe(x):
    """``x`` with every non-finite float made strict-JSON: NaN -> null, +/-inf -> the strings
    "inf" / "-inf" (numpy scalars and arrays become Python values). Every JSON nbst writes or
    prints goes through this (``docs/formats.md``)."""
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


def dumps_strict(obj: Any, **kw) -> str:
    """JSON text that any strict parser reads (see :func:`json_safe`)."""
    return json.dumps(json_safe(obj), allow_nan=False, **kw)


def write_json_atomic(path, obj: Any, *, option: str = "-o") -> None:
    """Write ``obj`` as strict JSON (indent 1; :func:`dumps_strict`) atomically; OutputError on failure.
    The one JSON writer of nbst (``nbst.solution.save_solution`` uses it)."""
    write_text_atomic(path, dumps_strict(obj, indent=1) + "\n", option=option)


# --------------------------------------------------------------------------- signals

#: The signals nbst handles like Ctrl-C: SIGINT (Ctrl-C), SIGTERM (kill) and SIGHUP (the
#: terminal closed). The first one stops the work (KeyboardInterrupt: the best so far is
#: written, partial files removed, workers stopped; the CLI exits 130); later ones within
#: INSIST_S seconds only wait for that cleanup to finish. SIGKILL cannot be handled: workers die with their parent
#: (``die_with_parent``) and stale partial files are removed by the next write.
STOP_SIGNALS = tuple(getattr(signal, n) for n in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, n))


#: Seconds after a stop signal during which further ones only wait for the cleanup. A signal
#: after that stops the work again: a library may have swallowed the first KeyboardInterrupt
#: (numba compiling, say), and the user who insists must not need SIGKILL. The cleanups that
#: must finish (result files, partial files, workers) hold the signals (``signals_deferred``).
INSIST_S = 2.0


class _Once:
    active = False  # an ``interrupt_once`` block is running in the main thread
    received = 0  # signals received inside it
    stopped_at = 0.0  # time.monotonic() of the last signal that raised KeyboardInterrupt
    told = False  # the "still finishing" line was printed


def _main_thread() -> bool:
    return threading.current_thread() is threading.main_thread()


def _say_finishing() -> None:
    if not _Once.told:
        _Once.told = True
        try:  # os.write, not print: the signal may have landed inside a write to sys.stderr
            os.write(2, b"\nnbst: stopping: finishing the result file and removing partial files first\n")
        except OSError:
            pass


@contextmanager
def interrupt_once() -> Iterator[None]:
    """While the block runs, the first SIGINT, SIGTERM or SIGHUP raises KeyboardInterrupt (as
    Ctrl-C does) and later ones within INSIST_S seconds are only noted: the cleanup that the first
    started (the best-so-far file written, partial files removed, workers stopped) is not cut
    short by a second Ctrl-C. A signal after that raises again. ``nbst.cli.main`` runs every
    command inside it. A no-op outside the main thread, and inside another such block."""
    if not _main_thread() or _Once.active:
        yield
        return

    def handler(signum, frame):
        now = time.monotonic()
        _Once.received += 1
        if _Once.received == 1 or now - _Once.stopped_at > INSIST_S:
            _Once.stopped_at = now
            raise KeyboardInterrupt
        _say_finishing()

    old = {s: signal.signal(s, handler) for s in STOP_SIGNALS}
    _Once.active, _Once.received, _Once.told, _Once.stopped_at = True, 0, False, 0.0
    try:
        yield
    finally:
        for s, h in old.items():
            signal.signal(s, h)
        _Once.active = False


def stop_requested() -> bool:
    """True once a stop signal has raised KeyboardInterrupt in this ``interrupt_once`` block. A loop
    that must end on Ctrl-C checks it each round and raises KeyboardInterrupt itself: Python drops
    an exception raised while a finalizer (``__del__``) or a weakref callback runs ("Exception
    ignored in ..."), so a signal that lands there stops nothing, and the ones after it within
    INSIST_S are only noted. False outside such a block."""
    return _Once.active and _Once.stopped_at > 0.0 and _Once.received > 0


def ignore_stop_signals() -> None:
    """Ignore SIGINT, SIGTERM and SIGHUP from now on (the CLI, once its command has ended and the
    process only exits). A no-op outside the main thread."""
    if _main_thread():
        for s in STOP_SIGNALS:
            signal.signal(s, signal.SIG_IGN)


@contextmanager
def sigterm_as_interrupt() -> Iterator[None]:
    """While the block runs, SIGTERM and SIGHUP raise KeyboardInterrupt (like Ctrl-C), so the
    cleanup that Ctrl-C gets (partial files removed, worker processes stopped) runs on ``kill``
    and on a closed terminal too; the CLI then exits 130. Inside ``interrupt_once`` (every CLI
    command) that block's handling applies instead (a second signal never interrupts the
    cleanup). A no-op outside the main thread."""
    if not _main_thread() or _Once.active:
        yield
        return

    def handler(signum, frame):
        raise KeyboardInterrupt

    old = {s: signal.signal(s, handler) for s in STOP_SIGNALS if s != signal.SIGINT}
    try:
        yield
    finally:
        for s, h in old.items():
            signal.signal(s, h)


@contextmanager
def signals_deferred(*, reraise: bool = True) -> Iterator[list]:
    """Hold SIGINT, SIGTERM and SIGHUP while the block runs (e.g. writing the best solution after a
    first Ctrl-C), so a second Ctrl-C cannot leave the file unwritten. Yields the list of signals
    that arrived; after the block, if any arrived and ``reraise``, KeyboardInterrupt is raised (the
    CLI exits 130, with the file written), unless an earlier signal already stopped the work (inside
    ``interrupt_once``: the cleanup it started goes on). A no-op outside the main thread."""
    got: list = []
    if not _main_thread():
        yield got
        return
    first = not _Once.active or _Once.received == 0

    def handler(signum, frame):
        got.append(signum)
        if _Once.active:
            _Once.received += 1
            if _Once.received == 1:  # it stops the work once the block is done: later ones wait
                _Once.stopped_at = time.monotonic()
            elif not first:
                _say_finishing()

    old = {s: signal.signal(s, handler) for s in STOP_SIGNALS}
    try:
        yield got
    finally:
        for s, h in old.items():
            signal.signal(s, h)
    if got and reraise and first:
        raise KeyboardInterrupt


@contextmanager
def signals_blocked() -> Iterator[None]:
    """Block the stop signals in this thread while the block runs (e.g. around ``fork``, so a child
    cannot get a Ctrl-C before it has set its own handlers); they are delivered after it. A no-op
    where ``pthread_sigmask`` does not exist."""
    if not hasattr(signal, "pthread_sigmask"):
        yield
        return
    old = signal.pthread_sigmask(signal.SIG_BLOCK, STOP_SIGNALS)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


#: Seconds between a worker's checks that its parent still lives (the portable fallback of
#: PR_SET_PDEATHSIG): an orphan dies within this long of a parent killed by SIGKILL.
PARENT_POLL_S = 0.5


def die_with_parent(parent_pid: int) -> None:
    """Worker setup: ignore the stop signals (the parent decides when its workers stop and stops
    them itself) and die with the parent, even when it is killed by SIGKILL. On Linux the kernel
    sends SIGKILL when the parent dies (``prctl(PR_SET_PDEATHSIG)``); everywhere a daemon thread
    exits the process once ``os.getppid()`` is no longer ``parent_pid`` (re-parented). Also
    unblocks the stop signals (see ``signals_blocked``)."""
    import sys

    for s in STOP_SIGNALS:
        signal.signal(s, signal.SIG_IGN)
    if hasattr(signal, "pthread_sigmask"):
        signal.pthread_sigmask(signal.SIG_UNBLOCK, STOP_SIGNALS)
    if sys.platform.startswith("linux"):
        try:
            import ctypes

            PR_SET_PDEATHSIG = 1
            ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0)
        except (OSError, AttributeError):
            pass
    if os.getppid() != parent_pid:  # the parent died before the line above took effect
        os._exit(1)

    def watch() -> None:
        while os.getppid() == parent_pid:
            time.sleep(PARENT_POLL_S)
        os._exit(1)

    threading.Thread(target=watch, name="nbst-parent-watch", daemon=True).start()
