"""Overlay text cut to its panel: a readout, title or label never runs into another panel or off the
frame, whatever the ``--size`` (pure: no GL; ``nbst.render.core.shapes.Text.fit`` measures the box
in its own cell)."""
from __future__ import annotations

__all__ = ["CUT", "fit_lines", "more_lines"]

#: The end of a line cut to fit its panel.
CUT = ".."


def more_lines(left: int, cols: int) -> str:
    """The last row of a readout with ``left`` lines left out, in ``cols`` characters: the longest
    of ``+N lines (a larger --size)``, ``+N lines`` and ``+N`` that fits (never cut mid-word), else
    :data:`CUT` alone (no room for the count)."""
    for s in (f"+{left} lines (a larger --size)", f"+{left} lines", f"+{left}"):
        if len(s) <= cols:
            return s
    return CUT[:cols]


def fit_lines(lines: list[str], cols: int, rows: int) -> list[str]:
    """``lines`` cut to a box of ``cols`` characters by ``rows`` lines, so that an overlay never runs
    into another panel or off the frame (a small ``--size``): a line too long keeps what fits and
    ends in :data:`CUT`; past the last row, the last row kept says how many lines are left out and
    that a larger frame shows them (:func:`more_lines`, shorter where the box is narrow). Nothing is
    cut that fits. No room at all: no lines."""
    cols, rows = int(cols), int(rows)
    if cols < 1 or rows < 1:
        return []

    def cut(s: str) -> str:
        if len(s.rstrip()) <= cols:
            return s[:cols]
        return (s[:max(0, cols - len(CUT))] + CUT)[:cols]

    if len(lines) <= rows:
        return [cut(s) for s in lines]
    left = len(lines) - rows + 1
    return [cut(s) for s in lines[:rows - 1]] + [more_lines(left, cols)]
