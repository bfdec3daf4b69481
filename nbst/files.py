"""Reading a file nbst did not write: the one bounded read that cannot block.

Every input file goes through :func:`read_regular` (problems and solutions by way of
``nbst.problem.read_json``, the images of ``nbst generate --targets-from``, bowling shot, throw
and scene files): the path is looked at with ``stat`` before it is opened, so a directory, a FIFO
(which would block), a device (``/dev/zero`` never ends) or a socket is refused without being
opened, as is a file over the size cap; the file is then opened non-blocking and looked at again
(``fstat``: still a regular file, whatever was swapped in between), and at most the cap plus one
byte is read, so a file that grew since is refused too. Every refusal is one line naming the
path (:class:`FileRefused`, an ``InputError``).

This module sits in the lowest layer: it imports nothing of nbst but the errors.
"""
from __future__ import annotations

import os
import stat
from pathlib import Path

from nbst.errors import InputError

__all__ = ["FileRefused", "read_regular", "sniff_kind"]

_NOT_REGULAR = ((stat.S_ISDIR, "is a directory"), (stat.S_ISFIFO, "is a named pipe (FIFO)"),
                (stat.S_ISCHR, "is a character device"), (stat.S_ISBLK, "is a block device"),
                (stat.S_ISSOCK, "is a socket"))


class FileRefused(InputError):
    """A file nbst will not read: ``path`` and ``reason``; the message is ``"PATH: REASON"``."""

    def __init__(self, path, reason: str):
        self.path, self.reason = str(path), reason
        super().__init__(f"{self.path}: {reason}")


def _regular_or_refuse(p: Path, mode: int, what: str) -> None:
    if stat.S_ISREG(mode):
        return
    why = next((w for test, w in _NOT_REGULAR if test(mode)), "is not a regular file")
    raise FileRefused(p, f"{why}, not a {what}; nbst reads regular files only")


def read_regular(path, *, max_bytes: int, what: str = "file", allow_empty: bool = True) -> bytes:
    """The bytes of the regular file ``path`` of at most ``max_bytes`` bytes (module doc), or
    :class:`FileRefused` (one line). ``what`` names the kind of file in the reasons (``"JSON
    file"``, ``"image file"``); ``allow_empty=False`` refuses an empty file."""
    p = Path(path)

    def too_large(size: int) -> FileRefused:
        return FileRefused(p, f"{size:,} bytes, larger than {max_bytes:,}; nbst reads {what}s of at most "
                              f"{max_bytes:,} bytes")

    try:
        st = os.stat(p)
        _regular_or_refuse(p, st.st_mode, what)
        if st.st_size > max_bytes:
            raise too_large(st.st_size)
        fd = os.open(p, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0))
        with open(fd, "rb", closefd=True) as f:
            _regular_or_refuse(p, os.fstat(fd).st_mode, what)
            data = f.read(max_bytes + 1)  # bounded, even if the file grew since stat
    except FileNotFoundError:
        raise FileRefused(p, "no such file") from None
    except NotADirectoryError:
        raise FileRefused(p, "no such file (a part of the path is not a folder)") from None
    except IsADirectoryError:
        raise FileRefused(p, f"is a directory, not a {what}") from None
    except PermissionError:
        raise FileRefused(p, "permission denied") from None
    except OSError as e:
        raise FileRefused(p, f"cannot read: {e.strerror or e}") from None
    except ValueError as e:  # a NUL byte in the name
        raise FileRefused(p, f"cannot read: {e}") from None
    if len(data) > max_bytes:
        raise too_large(len(data))
    if not data and not allow_empty:
        raise FileRefused(p, f"is empty, not a {what}")
    return data


def sniff_kind(path, kinds, *, max_bytes: int = 4096) -> str | None:
    """Which of ``kinds`` ((name, kind string), ...) the .json file ``path`` is, by the first of
    the quoted kind strings to appear in its first ``max_bytes`` bytes (nbst writes ``kind`` in a
    file's first lines; ``"nbst-crash"`` with its quotes is not found in ``"nbst-crash-script"``);
    None for anything else, a file that is not regular (never opened: a FIFO would block) or
    cannot be read. Parses nothing: the file's own loader checks it."""
    p = Path(str(path))
    if p.suffix.lower() != ".json":
        return None
    try:
        if not stat.S_ISREG(os.stat(p).st_mode):
            return None
        with open(p, "rb") as f:
            head = f.read(max_bytes)
    except (OSError, ValueError):
        return None
    found = [(i, name) for name, k in kinds if (i := head.find(f'"{k}"'.encode())) >= 0]
    return min(found)[1] if found else None
