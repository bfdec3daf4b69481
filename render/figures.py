"""Figures in the manner of the paper (matplotlib, no pyplot: no global state).

* :func:`plot_problem` - Figures 1-2: disks at their starts, small circles at the
  targets, an arrow from each disk to its target, broken for noncueable disks.
* :func:`plot_trajectories` - Figures 3-4: each disk's exact path (straight
  between events), wall bounces and disk-disk collisions marked.

Both return a ``matplotlib.figure.Figure``; :func:`save_figure` writes it.
"""
from __future__ import annotations

import numpy as np

from . import style

#: Figure size in inches for a square box; scaled to the box's aspect.
FIG_INCHES = 6.0


def _figure(problem):
    from matplotlib.figure import Figure

    W, H = problem.box
    aspect = H / W
    fig = Figure(figsize=(FIG_INCHES, FIG_INCHES * aspect + 0.5))
    ax = fig.add_subplot(1, 1, 1)
    ax.set_aspect("equal")
    pad = 0.02 * max(W, H)
    ax.set_xlim(-pad, W + pad)
    ax.set_ylim(-pad, H + pad)
    ax.set_xticks([])
    ax.set_yticks([])
    for s in ax.spines.values():
        s.set_visible(False)
    from matplotlib.patches import Rectangle
    ax.add_patch(Rectangle((0, 0), W, H, fill=False, lw=1.6, ec="black", zorder=1))
    return fig, ax


def _disk(ax, xy, r, cueable, *, alpha=1.0, label=None, zorder=4, fill=True):
    from matplotlib.patches import Circle
    col = style.CUEABLE if cueable else style.NONCUEABLE
    ax.add_patch(Circle(xy, r, fc=col if fill else "none", ec="black", lw=0.9, alpha=alpha, zorder=zorder))
    if label is not None and r > 6:
        ax.text(xy[0], xy[1], label, ha="center", va="center", fontsize=max(5.0, min(8.0, r * 0.35)),
                zorder=zorder + 1, color="black")


def _target(ax, xy, r, R, *, ring=True):
    from matplotlib.patches import Circle
    ax.add_patch(Circle(xy, max(0.3 * r, 3.0), fill=False, ec="black", lw=0.9, zorder=3))
    if ring:
        ax.add_patch(Circle(xy, R, fill=False, ec="0.75", lw=0.6, ls=":", zorder=2))


def plot_problem(problem, *, rings: bool = True):
    """The problem as the paper's Figures 1-2. rings: also draw each target's
    neighbourhood of radius R (dotted)."""
    from matplotlib.patches import FancyArrowPatch

    fig, ax = _figure(problem)
    p = problem
    for i in range(p.n):
        _target(ax, p.target[i], p.radius[i], p.target_radius, ring=rings)
    for i in range(p.n):
        a, b = p.start[i], p.target[i]
        d = b - a
        L = float(np.hypot(*d))
        if L > p.radius[i] + 1e-9:  # arrow from the disk's edge to the target's small circle
            u = d / L
            tail = a + u * p.radius[i]
            head = b - u * max(0.3 * p.radius[i], 3.0)
            ax.add_patch(FancyArrowPatch(tail, head, arrowstyle="-|>", mutation_scale=9, lw=0.9, color="black",
                                         ls="-" if p.cueable[i] else (0, (4, 3)), zorder=3))
        _disk(ax, a, p.radius[i], p.cueable[i], label=str(i))
    ncue = int(p.cueable.sum())
    kinds = f"{ncue} cueable" + (f", {p.n - ncue} noncueable (broken arrows)" if ncue < p.n else "")
    ax.set_title(f"{p.name}: {p.n} disks, {kinds}; t_final = {p.t_final:g} s, R = {p.target_radius:g}",
                 fontsize=9)
    fig.tight_layout()
    return fig


def plot_trajectories(problem, trajectory):
    """The motion as the paper's Figures 3-4: paths from start (faint disk) to
    final position (solid disk; broken paths for noncueable disks), wall bounces
    (black dots) and disk-disk collisions (red stars, at the contact point),
    targets as small circles. Each path line is labelled ``_path i``."""
    from matplotlib import colormaps

    p, tr = problem, trajectory
    fig, ax = _figure(p)
    cmap = colormaps["tab10"] if p.n <= 10 else colormaps["tab20"]  # tab20's pairs look alike: only past 10
    paths = np.concatenate((tr.positions, tr.final_positions[None]), axis=0)  # (K+1, N, 2)
    for i in range(p.n):
        _target(ax, p.target[i], p.radius[i], p.target_radius, ring=False)
    for i in range(p.n):
        col = cmap(i % cmap.N)
        # noncueable paths broken, as their arrows in Figure 2; "_" labels stay out of the legend
        ax.plot(paths[:, i, 0], paths[:, i, 1], "-" if p.cueable[i] else "--", color=col, lw=1.4, zorder=3,
                solid_joinstyle="miter", label=f"_path {i}")
        _disk(ax, p.start[i], p.radius[i], p.cueable[i], alpha=0.25, zorder=2)
        _disk(ax, tr.final_positions[i], p.radius[i], p.cueable[i], label=str(i), zorder=5)
    ev = tr.events
    wall = ev["kind"] == 1
    if wall.any():
        k = np.nonzero(wall)[0]
        pts = tr.positions[k + 1, ev["i"][k]]
        ax.plot(pts[:, 0], pts[:, 1], "o", ms=3.2, color="black", zorder=6, label=f"wall bounce ({len(k)})")
    if (~wall).any():
        k = np.nonzero(~wall)[0]
        i, j = ev["i"][k], ev["j"][k]
        pi, pj = tr.positions[k + 1, i], tr.positions[k + 1, j]
        w = (p.radius[i] / (p.radius[i] + p.radius[j]))[:, None]
        c = pi + (pj - pi) * w
        ax.plot(c[:, 0], c[:, 1], "*", ms=8, color="#d62728", mec="black", mew=0.4, zorder=7,
                label=f"disk-disk collision ({len(k)})")
    if len(ev):
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, 0.0), ncol=2, fontsize=7, frameon=False)
    ax.set_title(f"{p.name}: cost {tr.cost:.4g}, signature {tr.signature_string} "
                 f"(order {tr.order}/{p.n})", fontsize=9)
    fig.tight_layout()
    return fig


def save_figure(fig, path, *, dpi: int = 150) -> None:
    """Write a figure (format from the extension)."""
    from pathlib import Path
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(str(path), dpi=dpi)
