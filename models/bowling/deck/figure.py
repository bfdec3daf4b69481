"""The atlas's picture: every subset found, as a small 10-pin triangle, grouped by size.

One row block per number of pins down (1..10): a triangle per subset found (filled pins
down, open pins standing; seen from the bowler, pin 7 back left). A red frame marks found
subsets that the geometry's reach rule says need a flying pin (:mod:`.geometry`). Compute
apart from I/O: :func:`atlas_figure` returns a matplotlib Figure; the caller saves it.
"""
from __future__ import annotations

import math

from nbst.models.bowling import geometry

__all__ = ["PER_ROW", "atlas_figure", "save"]

#: Triangles per row of a block.
PER_ROW = 16


def atlas_figure(found, *, title: str = ""):
    """A matplotlib Figure of the found subsets (10-bit masks), by size."""
    from matplotlib.figure import Figure
    from matplotlib.patches import Circle, Rectangle

    found = sorted(int(m) for m in found if m)
    by_size = {k: [m for m in found if geometry.size_of(m) == k] for k in range(1, 11)}
    rows = {k: max(1, math.ceil(len(v) / PER_ROW)) for k, v in by_size.items()}
    cls = geometry.classify()
    spots = geometry.pin_spots()
    # drawing coordinates: x to the right = -y (bowler's right), up = down the lane
    px, py = -spots[:, 1] / geometry.PIN_SPACING, spots[:, 0] / geometry.PIN_SPACING
    cell_w, cell_h, label_w = 4.0, 3.4, 5.0
    total_rows = sum(rows.values())
    W, H = label_w + PER_ROW * cell_w, total_rows * cell_h + (1.5 if title else 0.3)
    fig = Figure(figsize=(W * 0.28, H * 0.28), dpi=110)
    ax = fig.add_axes((0, 0, 1, 1))
    ax.set_xlim(0, W)
    ax.set_ylim(-H, 0)
    ax.set_aspect("equal")
    ax.axis("off")
    if title:
        ax.text(W / 2, -0.7, title, ha="center", va="center", fontsize=11)
    top = -(1.5 if title else 0.3)
    for k in range(1, 11):
        n_all = math.comb(10, k)
        ax.text(0.3, top - cell_h / 2, f"{k} down\n{len(by_size[k])} / {n_all}", ha="left", va="center", fontsize=8)
        for i, m in enumerate(by_size[k]):
            cx = label_w + (i % PER_ROW + 0.5) * cell_w
            cy = top - (i // PER_ROW + 0.5) * cell_h
            for n in range(10):
                down = m >> n & 1
                ax.add_patch(Circle((cx + px[n] * 0.95, cy - 1.2 + py[n] * 0.95), 0.36,
                                    facecolor="#1f4e79" if down else "white", edgecolor="#1f4e79", lw=0.6))
            if cls[m] != "a":
                ax.add_patch(Rectangle((cx - 1.9, cy - 1.65), 3.8, 3.3, fill=False, edgecolor="#c0392b", lw=1.0))
        top -= rows[k] * cell_h
        ax.plot([0.2, W - 0.2], [top, top], color="#cccccc", lw=0.5)
    return fig


def save(fig, path, *, dpi: float | None = None) -> None:
    """Write the figure (PNG; ``dpi`` default the figure's, 110)."""
    fig.savefig(str(path), dpi=dpi or fig.dpi)
