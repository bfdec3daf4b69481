"""Overlay text cut to its panel: a readout, title or label never runs into another panel or off the
frame, whatever the ``--size`` (pure: no GL; ``nbst.render.core.shapes.Text.fit`` measures the box
in its own cell)."""
from __future__ import annotations

__all__ = ["CUT", "fit_lines"]

#: The end of a line cut to fit its panel.
CUT = ".."


def fit_lines(lines: list[str], cols: int, rows: int) -> list[str]:
    """``lines`` cut to a box of ``cols`` characters by ``rows`` lines, so that an overlay never runs
    into another panel or off the frame (a small ``--size``): a line too long keeps what fits and
    ends in :data:`CUT`; past the last row, the last row kept says how many lines are left out and
    that a larger frame shows them. Nothing is cut that fits. No room at all: no lines."""
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
    return [cut(s) for s in lines[:rows - 1]] + [cut(f"+{left} lines (a larger --size)")]
