"""nbst's one error family: every error nbst raises on purpose derives from :class:`NbstError`.

The command line catches :class:`NbstError` alone and prints its message as one line
(``nbst: error: ...``), exiting with the error's ``exit_code`` (2 unless a class says
otherwise). Library callers can catch the base, or one branch:

- :class:`InputError`: a file, field or argument nbst refuses (problems, solutions, shot and
  throw files, formations, bowling deliveries). Also a ``ValueError``, as it always was.
- :class:`OutputError`: an output path that cannot be written (a folder, a device, a full disk).
- :class:`SolveError`: a search that cannot run as asked. Also a ``ValueError``: a parameter
  out of its domain was one before.
- :class:`MujocoError`: MuJoCo warned (a diverging or non-finite state, a bad model).
- :class:`RenderError`: rendering cannot proceed (no GL, bad size, encoder failure).

This module sits in the lowest layer (it imports nothing of nbst), so every room may use it.
"""
from __future__ import annotations

__all__ = ["NbstError", "InputError", "OutputError", "SolveError", "MujocoError", "RenderError"]


class NbstError(Exception):
    """The base of every error nbst raises on purpose; its message is one printable line."""

    #: the command line's exit status for this error
    exit_code: int = 2


class InputError(NbstError, ValueError):
    """Bad input: a file, field or argument that nbst refuses; the message names them."""


class OutputError(NbstError):
    """An output path that cannot be written; the message names the path and the reason."""


class SolveError(NbstError, ValueError):
    """A search that cannot run as asked (a parameter out of its domain, a solver that does not exist)."""


class MujocoError(NbstError):
    """MuJoCo warned (a diverging or non-finite state, a bad model): our error, one line."""


class RenderError(NbstError, RuntimeError):
    """Rendering cannot proceed (no GL, bad size, encoder failure): one line for the CLI."""
