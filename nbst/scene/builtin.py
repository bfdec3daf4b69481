"""The built-in example scenes: ``nbst/scene/examples/NAME.json`` (a fates file) beside its MJCF.

Each is after the literature on constrained rigid-body animation (docs/scene.md): ``snake-eyes``
(Barzel, Hughes & Wood 1996: two dice knocked off a table come up 1-1 in a marked square) and
``egg-in-cup`` (Popovic et al. 2000: a thrown egg lands and stays in a cup), ``bank-shot`` (a
ball comes off the backboard and drops through the hoop: ``hits`` and ``through``), ``billiards``
(the cue ball hits the 3, then the 8, which drops in the called pocket; no scratch) and
``dominoes`` (a row of 10 falls in order and the last knocks a bell off its post). A fates path that is
not a file but names one of these loads it (``nbst scene solve snake-eyes``).
"""
from __future__ import annotations

import json
from pathlib import Path

__all__ = ["EXAMPLES_DIR", "example_names", "example_path", "example_description"]

#: The folder of the built-in examples (package data).
EXAMPLES_DIR = Path(__file__).resolve().parent / "examples"


def example_names() -> list[str]:
    """The built-in examples' names, sorted."""
    return sorted(p.stem for p in EXAMPLES_DIR.glob("*.json"))


def example_path(name: str) -> Path | None:
    """The fates file of the built-in example ``name``, or None when there is none by that name."""
    p = EXAMPLES_DIR / f"{name}.json"
    return p if name in example_names() and p.is_file() else None


def example_description(name: str) -> str:
    """The example's ``"description"`` (first line), or "" when it has none."""
    p = example_path(name)
    if p is None:
        return ""
    return str(json.loads(p.read_text(encoding="utf-8")).get("description", "")).splitlines()[0]
