"""One list of each choice: a small registry of named things (solvers, variants, built-in problems, ...).

Each list is made once, in the module that owns what it lists, and everything that offers the
choice reads it from there: the command line's options and their help, the experiments' entries,
the docs. Adding an entry is one call::

    from nbst.registry import Registry

    SOLVERS: Registry[Solver] = Registry("algorithm")
    SOLVERS.register("cma", solve_cma, help="CMA-ES, IPOP restarts from the straight-line velocities")

    SOLVERS.names()            # ("cma", ...), in registration order
    SOLVERS["cma"]             # solve_cma
    SOLVERS.parse(" CMA ", source="<arguments>", field="--algorithm")   # "cma", or an InputError

Names are matched without regard to case or surrounding blanks; ``parse`` returns the registered
spelling. An alias (``aliases=``) reads as its entry's name. Registration order is the order the
choices are listed in. A registry holds any value; its ``help`` texts are for people.

This module sits in the lowest layer (it imports only ``nbst.errors``), so every room may keep
a registry. A registry is filled when its owning module is imported: that module must stay light
(no numba, MuJoCo or GL at import) when the command line reads its names.
"""
from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Generic, TypeVar

from nbst.errors import InputError

__all__ = ["Entry", "Registry"]

T = TypeVar("T")


@dataclass(frozen=True)
class Entry(Generic[T]):
    """One registered choice: its name, its value, a one-line help and other spellings."""

    name: str
    value: T
    help: str = ""
    aliases: tuple[str, ...] = ()


class Registry(Generic[T]):
    """Named values in registration order, each registered once.

    what : what one entry is, for messages ("algorithm", "variant", "built-in problem")
    """

    def __init__(self, what: str) -> None:
        self.what = what
        self._entries: dict[str, Entry[T]] = {}
        self._keys: dict[str, str] = {}  # folded spelling (name or alias) -> name

    @staticmethod
    def _fold(text: str) -> str:
        return str(text).strip().lower()

    def register(self, name: str, value: T, *, help: str = "", aliases: tuple[str, ...] = ()) -> T:
        """Add ``value`` under ``name`` (and ``aliases``); returns ``value``. A name or alias that
        is already taken raises InputError (each choice is registered once)."""
        if not name or name != name.strip():
            raise InputError(f"{self.what} name {name!r}: must be non-empty, without surrounding blanks")
        for key in (name, *aliases):
            if self._fold(key) in self._keys:
                raise InputError(f"{self.what} {key!r} is already registered")
        self._entries[name] = Entry(name, value, help, tuple(aliases))
        for key in (name, *aliases):
            self._keys[self._fold(key)] = name
        return value

    def unregister(self, name: str) -> None:
        """Remove ``name`` and its aliases (tests that register a dummy entry undo it with this)."""
        entry = self._entries.pop(name)
        for key in (entry.name, *entry.aliases):
            self._keys.pop(self._fold(key), None)

    def names(self) -> tuple[str, ...]:
        """The registered names, in registration order (aliases not included)."""
        return tuple(self._entries)

    def entries(self) -> tuple[Entry[T], ...]:
        return tuple(self._entries.values())

    def entry(self, name: str) -> Entry[T]:
        """The entry of ``name`` (or of an alias); KeyError if there is none."""
        return self._entries[self._keys[self._fold(name)]]

    def __getitem__(self, name: str) -> T:
        return self.entry(name).value

    def __contains__(self, name: object) -> bool:
        return isinstance(name, str) and self._fold(name) in self._keys

    def __iter__(self) -> Iterator[str]:
        return iter(self.names())

    def __len__(self) -> int:
        return len(self._entries)

    def parse(self, text: str, *, source: str = "<arguments>", field: str = "") -> str:
        """The registered name that ``text`` spells (any case, an alias too); an unknown name raises
        :class:`~nbst.errors.InputError` naming ``source`` and ``field`` and listing the choices."""
        name = self._keys.get(self._fold(text))
        if name is None:
            where = f"{source}: {field}" if field else source  # as nbst.problem.ProblemError words it
            raise InputError(f"{where}: unknown {self.what} {text!r}; choose one of {', '.join(self.names())}")
        return name

    def argtype(self, field: str) -> Callable[[str], str]:
        """An argparse ``type=``: :meth:`parse` with argparse's usage error for an unknown name."""
        def parse(text: str) -> str:
            import argparse

            name = self._keys.get(self._fold(text))
            if name is None:
                raise argparse.ArgumentTypeError(f"unknown {self.what} {text!r}; choose one of "
                                                 f"{' '.join(self.names())}")
            return name

        parse.__name__ = self.what  # argparse names the type in its messages
        return parse

    def help_text(self, sep: str = "; ") -> str:
        """``name: help`` for every entry, joined (for ``--help`` and the docs)."""
        return sep.join(f"{e.name}: {e.help}" if e.help else e.name for e in self._entries.values())
