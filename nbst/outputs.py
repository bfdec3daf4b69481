"""Output paths, checked before the work that fills them.

A long solve or render must not end in a traceback because ``-o`` names a folder that
cannot be written: commands call ``prepare_output`` first, which creates missing parent
folders and proves the folder writable by creating (and removing) a scratch file there.
The CLI turns ``OutputError`` into one line and exit status 2.
"""
from __future__ import annotations

import os
import tempfile
from pathlib import Path


class OutputError(Exception):
    """An output path that cannot be written; the message names the path and the reason."""


def prepare_output(path, *, directory: bool = False, option: str = "-o") -> Path:
    """Make ``path``'s folder (or ``path`` itself with ``directory=True``) exist and be writable.

    Returns ``path`` as a Path; raises OutputError naming ``option``, the path and the reason.
    """
    p = Path(path)
    folder = p if directory else (p.parent if str(p.parent) else Path("."))
    try:
        if p.is_dir() and not directory:
            raise OutputError(f"{option} {path}: is a folder; expected a file name")
        if p.exists() and directory and not p.is_dir():
            raise OutputError(f"{option} {path}: is a file; expected a folder")
        folder.mkdir(parents=True, exist_ok=True)
        fd, scratch = tempfile.mkstemp(prefix=".nbst-write-test.", dir=folder)
        os.close(fd)
        os.unlink(scratch)
    except OSError as e:
        raise OutputError(f"{option} {path}: cannot write there ({e.strerror or e})") from None
    return p
