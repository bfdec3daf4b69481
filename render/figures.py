"""Figures in the manner of the paper (matplotlib, no pyplot: no global state).

* :func:`plot_problem` - Figures 1-2: disks at their starts, small circles at the
  targets, an arrow from each disk to its target, broken for noncueable disks.
* :func:`plot_trajectories` - Figures 3-4: each disk's exact path (straight
  between events), wall bounces and disk-disk collisions marked.

Both return a ``matplotlib.figure.Figure``; :func:`save_figure` writes it.

Every mark means what it means in the video and the validation report
(:mod:`nbst.palette`): colour = class, number = disk index (on the disk at its
start; small beside its target), filled disk = start, hollow small circle =
target, dotted ring = neighbourhood of radius R, thin outline circle = final
position, solid / dashed paths = cueable / noncueable. The helpers below
(:func:`draw_start`, :func:`draw_target`, :func:`legend_below`, ...) are shared
with the validation report (``nbst.render.report``).
"""
from __future__ import annotations

import numpy as np

from nbst import palette
from nbst.problem import display_name

__all__ = ["DISK_NUMBER_PT", "FIG_INCHES", "LEGEND_PT", "MANY_STAR_MS", "MIN_DISK_PT", "NUMBERS_MAX_DISKS",
           "NUMBER_Z", "STAR_MS", "TARGET_NUMBER_PT", "TITLE_PT", "TITLE_SIGNATURE_MAX", "circle_handle",
           "disk_paths", "draw_final", "draw_start", "draw_target", "event_points", "legend_below", "line_handle",
           "mark_handles", "numbered", "plot_problem", "plot_trajectories", "save_figure", "target_marker_radius"]

#: Figure size in inches for a square box; scaled to the box's aspect.
FIG_INCHES = 6.0
#: Font sizes (points): disk numbers on the disks, target numbers, legends, titles.
DISK_NUMBER_PT = (5.0, 8.0)  # smallest, largest
TARGET_NUMBER_PT = 6.5
LEGEND_PT = 7.5
TITLE_PT = 9.0
#: Smallest drawn disk radius (points): smaller disks are drawn as a marker this size.
MIN_DISK_PT = 2.5
#: Disk numbers sit above everything (paths, disks, event marks).
NUMBER_Z = 9
#: Collision star size (points, matplotlib ``ms``).
STAR_MS = 8.0
#: Target marker radius: this fraction of the disk radius, at least TARGET_MIN (units).
TARGET_FRAC, TARGET_MIN = 0.3, 3.0
#: Longest signature written out in a title (one character a disk): beyond it (many disks)
#: the title gives the order only; ``nbst simulate`` prints the whole signature.
TITLE_SIGNATURE_MAX = 40
#: Figures number the disks (on each start, beside each target) up to this many disks. Beyond
#: it the numbers, written beside disks too small to hold them, cover the figure (1,000 disks
#: in a 6-inch figure are 3 pt across and their 3-digit numbers 15 pt wide): the disks, paths
#: and targets are drawn without them, and collision stars shrink to MANY_STAR_MS.
NUMBERS_MAX_DISKS = 100
MANY_STAR_MS = 3.5


def _figure(problem):
    """A figure with one equal-aspect axes showing the box and room for a title;
    :func:`legend_below` makes the figure taller for its legend; constrained layout
    keeps everything inside the figure."""
    from matplotlib.figure import Figure
    from matplotlib.patches import Rectangle

    W, H = problem.box
    fig = Figure(figsize=(FIG_INCHES, FIG_INCHES * H / W + 0.45), layout="constrained")
    ax = fig.add_subplot(1, 1, 1)
    ax.set_aspect("equal")
    pad = 0.02 * max(W, H)
    ax.set_xlim(-pad, W + pad)
    ax.set_ylim(-pad, H + pad)
    ax.set_xticks([])
    ax.set_yticks([])
    for s in ax.spines.values():
        s.set_visible(False)
    ax.add_patch(Rectangle((0, 0), W, H, fill=False, lw=1.6, ec="black", zorder=1))
    return fig, ax


# --------------------------------------------------------------------------- marks

def target_marker_radius(r) -> float:
    return max(TARGET_FRAC * float(r), TARGET_MIN)


def _points_per_unit(ax) -> float:
    """Points per data unit of an equal-aspect axes, from its current size (an estimate
    before the final layout; used only to choose font sizes and offsets)."""
    fig = ax.figure
    pos = ax.get_position()
    x0, x1 = ax.get_xlim()
    y0, y1 = ax.get_ylim()
    return 72.0 * min(fig.get_figwidth() * pos.width / abs(x1 - x0), fig.get_figheight() * pos.height / abs(y1 - y0))


def draw_start(ax, xy, r, cueable, i, *, color=None, zorder=5, avoid=None, avoid_pt: float = 0.0,
               number: bool = True):
    """The disk at its start: filled in its class colour (or ``color``), black edge,
    its number on it (unless ``number`` is False); beside it, upper right, where the number
    does not fit.
    ``avoid``: points (M, 2, data units) of marks drawn over the figure (collision stars)
    of radius ``avoid_pt`` points; a number one of them would cover moves beside the
    disk, on the side away from the nearest such mark."""
    from matplotlib import patheffects
    from matplotlib.patches import Circle

    col = palette.hex_color(color if color is not None else palette.class_color(cueable))
    ppu = _points_per_unit(ax)
    r_pt = r * ppu
    away = None
    if avoid is not None and len(avoid):
        d = np.asarray(avoid, float) - np.asarray(xy, float)
        dist = np.hypot(d[:, 0], d[:, 1]) * ppu
        k = int(np.argmin(dist))
        if dist[k] < max(r_pt, MIN_DISK_PT) + avoid_pt + 6.0:  # the star reaches the number (on or beside)
            away = -d[k] / max(np.hypot(*d[k]), 1e-12)
    label = str(i)
    # digits are about 0.6 em wide and 0.73 em tall: the size whose digits fill ~80% of
    # the disk's width; written on the disk only if that is at least the smallest size
    raw = 1.6 * r_pt / max(0.6 * len(label), 0.73)
    on_disk = raw >= DISK_NUMBER_PT[0]
    if r_pt >= MIN_DISK_PT:
        ax.add_patch(Circle(xy, r, fc=col, ec="black", lw=0.8, zorder=zorder))
    else:  # a disk too small to see (diamond-s14-tiny): a marker of MIN_DISK_PT radius
        ax.plot([xy[0]], [xy[1]], "o", ms=2 * MIN_DISK_PT, mfc=col, mec="black", mew=0.6, zorder=zorder)
        r_pt, on_disk = MIN_DISK_PT, False
    if not number:
        return
    if away is not None:  # a collision star on or by the disk: the number beside it, away from the star
        size = DISK_NUMBER_PT[0] + 1.5
        off = away * (r_pt + 0.45 * size * len(label) + 1.5)
        ax.annotate(label, xy, xytext=tuple(off), textcoords="offset points", fontsize=size, fontweight="bold",
                    color="black", ha="center", va="center", zorder=NUMBER_Z,
                    path_effects=[patheffects.withStroke(linewidth=2, foreground="white")])
    elif on_disk:
        ax.text(xy[0], xy[1], label, ha="center", va="center_baseline", fontsize=min(raw, DISK_NUMBER_PT[1]),
                color="black", zorder=NUMBER_Z)
    else:  # too small to write on: beside it, with a white halo
        ax.annotate(label, xy, xytext=(r_pt * 0.7 + 1, r_pt * 0.7 + 1), textcoords="offset points",
                    fontsize=DISK_NUMBER_PT[0] + 1.5, fontweight="bold", color="black", ha="left", va="bottom",
                    zorder=NUMBER_Z,
                    path_effects=[patheffects.withStroke(linewidth=2, foreground="white")])


def draw_target(ax, xy, r, i, *, R=None, zorder=4, number: bool = True):
    """A target: a hollow small circle, its disk's number beside it (upper right; unless
    ``number`` is False) and, given R, its dotted neighbourhood ring."""
    from matplotlib import patheffects
    from matplotlib.patches import Circle

    ink = palette.hex_color(palette.TARGET_INK)
    m = target_marker_radius(r)
    ax.add_patch(Circle(xy, m, fill=False, ec=ink, lw=0.9, zorder=zorder))
    if R is not None:
        ax.add_patch(Circle(xy, R, fill=False, ec=palette.hex_color(palette.RING_INK), lw=0.7, ls=":", zorder=2))
    if not number:
        return
    off = m * _points_per_unit(ax) * 0.72 + 0.8
    ax.annotate(str(i), xy, xytext=(off, off), textcoords="offset points", fontsize=TARGET_NUMBER_PT, color=ink,
                ha="left", va="bottom", zorder=zorder + 2,
                path_effects=[patheffects.withStroke(linewidth=1.8, foreground="white")])


def draw_final(ax, xy, r, color, *, ls="-", zorder=4):
    """The final position: a thin outline circle of the disk's radius."""
    from matplotlib.patches import Circle
    ax.add_patch(Circle(xy, r, fill=False, ec=palette.hex_color(color) if not isinstance(color, str) else color,
                        lw=1.0, ls=ls, zorder=zorder))


# --------------------------------------------------------------------------- legends

class _HandlerCircle:
    """Legend handler drawing a Circle handle as a circle (not matplotlib's default
    rectangle), scaled by the handle's radius: 1 = the legend row's height."""

    def legend_artist(self, legend, orig_handle, fontsize, handlebox):
        from matplotlib.patches import Circle
        w, h = handlebox.width, handlebox.height
        r = 0.5 * h * 1.3 * float(orig_handle.get_radius())
        c = Circle((w / 2 - handlebox.xdescent, h / 2 - handlebox.ydescent), r,
                   fc=orig_handle.get_facecolor() if orig_handle.get_fill() else "none",
                   fill=orig_handle.get_fill(), ec=orig_handle.get_edgecolor(), lw=orig_handle.get_linewidth(),
                   ls=orig_handle.get_linestyle(), transform=handlebox.get_transform())
        handlebox.add_artist(c)
        return c


def circle_handle(*, radius=1.0, fc=None, ec="black", lw=0.8, ls="-"):
    """A legend handle drawn as a circle (radius 1 = the row's height)."""
    from matplotlib.patches import Circle
    return Circle((0, 0), radius, fc=fc if fc is not None else "none", fill=fc is not None, ec=ec, lw=lw, ls=ls)


def line_handle(color, ls="-", *, lw=1.4, **marker):
    """A legend handle drawn as a line (and/or a marker: ``marker=``, ``ms=``, ``mec=``, ...)."""
    from matplotlib.lines import Line2D
    return Line2D([], [], color=color, ls=ls, lw=lw, **marker)


def mark_handles(problem, *, paths: bool, final: bool, ring: bool, final_label=None,
                 path_prefix: str = "", numbers: bool = True) -> list[tuple]:
    """(handle, words) of the marks a figure of ``problem`` uses: start disks by class,
    target, ring, final position, paths by class (their words after ``path_prefix``)."""
    cue = bool(problem.cueable.any())
    non = bool((~problem.cueable).any())
    out = []
    if cue:
        out.append((circle_handle(fc=palette.hex_color(palette.CUEABLE)),
                    f"{palette.LEGEND_CUEABLE} {_start_words(numbers)}"))
    if non:
        out.append((circle_handle(fc=palette.hex_color(palette.NONCUEABLE)),
                    f"{palette.LEGEND_NONCUEABLE} {_start_words(numbers)}"))
    out.append((circle_handle(radius=0.45, ec=palette.hex_color(palette.TARGET_INK), lw=0.9),
                palette.LEGEND_TARGET if numbers else "target"))
    if ring:
        out.append((circle_handle(radius=1.15, ec=palette.hex_color(palette.RING_INK), lw=0.9, ls=":"),
                    palette.LEGEND_RING))
    if final:
        out.append((circle_handle(ec="0.25", lw=1.0), final_label or palette.LEGEND_FINAL))
    if paths:
        if cue:
            out.append((line_handle(palette.hex_color(palette.CUEABLE), palette.PATH_CUEABLE),
                        path_prefix + palette.LEGEND_PATH_CUEABLE + " (solid)"))
        if non:
            out.append((line_handle(palette.hex_color(palette.NONCUEABLE), palette.PATH_NONCUEABLE),
                        path_prefix + palette.LEGEND_PATH_NONCUEABLE + " (dashed)"))
    return out


def _start_words(numbers: bool) -> str:
    """The legend's words for a start disk: with its number, or saying why there is none."""
    return palette.LEGEND_START if numbers else f"disk at its start (no numbers over {NUMBERS_MAX_DISKS} disks)"


def numbered(problem) -> bool:
    """Whether figures of ``problem`` number its disks (NUMBERS_MAX_DISKS)."""
    return problem.n <= NUMBERS_MAX_DISKS


def legend_below(fig, entries, *, ncol: int = 2, fontsize: float = LEGEND_PT, grow: bool = True,
                 title: str | None = None):
    """The legend of ``entries`` [(handle, words)] below the axes, outside them
    (constrained layout makes room), so it never covers data. ``grow``: make the
    figure taller by the legend's height, so the axes keep their size."""
    from matplotlib.patches import Circle
    handles = [h for h, _ in entries]
    labels = [w for _, w in entries]
    if grow:
        rows = -(-len(entries) // ncol) + (title is not None)
        w, h = fig.get_size_inches()
        fig.set_size_inches(w, h + rows * fontsize * 1.55 / 72 + 0.15)
    return fig.legend(handles, labels, loc="outside lower center", ncol=ncol, fontsize=fontsize, frameon=False,
                      handler_map={Circle: _HandlerCircle()}, handlelength=2.2, columnspacing=1.6,
                      title=title, title_fontsize=fontsize)


# --------------------------------------------------------------------------- figures

def plot_problem(problem, *, rings: bool = True):
    """The problem as the paper's Figures 1-2: numbered disks at their starts,
    numbered targets, arrows start -> target (broken for noncueable disks).

    Args:
        problem: the :class:`nbst.Problem`.
        rings: also draw each target's neighbourhood of radius R (dotted).

    Returns:
        The matplotlib Figure (no pyplot: :func:`save_figure` writes it).
    """
    from matplotlib.patches import FancyArrowPatch

    p = problem
    fig, ax = _figure(p)
    num = numbered(p)
    for i in range(p.n):
        draw_target(ax, p.target[i], p.radius[i], i, R=p.target_radius if rings else None, number=num)
    for i in range(p.n):
        a, b = p.start[i], p.target[i]
        d = b - a
        L = float(np.hypot(*d))
        if L > p.radius[i] + 1e-9:  # arrow from the disk's edge to the target's small circle
            u = d / L
            tail = a + u * p.radius[i]
            head = b - u * target_marker_radius(p.radius[i])
            ax.add_patch(FancyArrowPatch(tail, head, arrowstyle="-|>", mutation_scale=9, lw=0.9, color="0.2",
                                         ls="-" if p.cueable[i] else (0, (4, 3)), zorder=3))
        draw_start(ax, a, p.radius[i], p.cueable[i], i, number=num)
    ncue = int(p.cueable.sum())
    kinds = f"{ncue} cueable" + (f", {p.n - ncue} noncueable" if ncue < p.n else "")
    ax.set_title(f"{display_name(p.name)}: {p.n} disks, {kinds}; t_final = {p.t_final:g} s, R = {p.target_radius:g}",
                 fontsize=TITLE_PT)
    entries = mark_handles(p, paths=False, final=False, ring=rings, numbers=num)
    entries.append((line_handle("0.2", "-", lw=0.9, marker=">", ms=4), "start -> target"
                    + (" (dashed: noncueable)" if ncue < p.n else "")))
    legend_below(fig, entries)
    return fig


def plot_trajectories(problem, trajectory, *, rings: bool = True):
    """The motion as the paper's Figures 3-4: each disk's exact path (a shade of its
    class colour; dashed for noncueable disks) from its start (filled, numbered) to
    its final position (thin outline circle), wall bounces (black dots) and disk-disk
    collisions (red stars, at the contact point), numbered targets (small circles)
    and, with ``rings``, their dotted neighbourhoods. Each path line is labelled
    ``_path i``; the legend sits below the box.

    Args:
        problem: the :class:`nbst.Problem`.
        trajectory: its exact motion (:func:`nbst.simulate`'s trajectory).
        rings: also draw each target's neighbourhood of radius R (dotted).

    Returns:
        The matplotlib Figure.
    """
    p, tr = problem, trajectory
    fig, ax = _figure(p)
    shades = palette.disk_shades(p.cueable)
    paths = disk_paths(tr)
    ev = tr.events
    wall = ev["kind"] == 1
    stars = np.zeros((0, 2))
    disk, idx, pts = event_points(tr)
    first = np.arange(len(ev))  # event_points lists every event's disk i first, in event order
    if (~wall).any():  # each collision at its contact point
        k = np.nonzero(~wall)[0]
        i, j = ev["i"][k], ev["j"][k]
        pi, pj = pts[first[k]], pts[len(ev):]
        w = (p.radius[i] / (p.radius[i] + p.radius[j]))[:, None]
        stars = pi + (pj - pi) * w
    num = numbered(p)
    star_ms = STAR_MS if num else MANY_STAR_MS
    for i in range(p.n):
        draw_target(ax, p.target[i], p.radius[i], i, R=p.target_radius if rings else None, number=num)
    for i in range(p.n):
        col = palette.hex_color(shades[i])
        # noncueable paths broken, as their arrows in Figure 2; "_" labels stay out of the legend
        ax.plot(paths[i][:, 0], paths[i][:, 1], palette.path_style(p.cueable[i]), color=col, lw=1.4, zorder=3,
                solid_joinstyle="miter", label=f"_path {i}")
        draw_final(ax, tr.final_positions[i], p.radius[i], shades[i], zorder=4)
        # a star on a start disk would cover its number: the number moves beside the disk
        draw_start(ax, p.start[i], p.radius[i], p.cueable[i], i, zorder=5, avoid=stars, avoid_pt=star_ms / 2,
                   number=num)
    entries = mark_handles(p, paths=True, final=True, ring=rings, numbers=num)
    wall_ink, coll_ink = palette.hex_color(palette.WALL_BOUNCE), palette.hex_color(palette.COLLISION)
    if wall.any():
        k = np.nonzero(wall)[0]
        bounce = pts[first[k]]
        label = f"{palette.LEGEND_WALL_BOUNCE} ({len(k)})"
        ax.plot(bounce[:, 0], bounce[:, 1], palette.WALL_BOUNCE_MARKER, ms=3.2, color=wall_ink, zorder=7, label=label)
        entries.append((line_handle(wall_ink, "none", marker=palette.WALL_BOUNCE_MARKER, ms=3.2), label))
    if len(stars):
        label = f"{palette.LEGEND_COLLISION} ({len(stars)})"
        ax.plot(stars[:, 0], stars[:, 1], palette.COLLISION_MARKER, ms=star_ms, color=coll_ink, mec="black",
                mew=0.4 if num else 0.2, zorder=7, label=label)
        entries.append((line_handle(coll_ink, "none", marker=palette.COLLISION_MARKER, ms=STAR_MS, mec="black"),
                        label))
    legend_below(fig, entries)
    s = tr.signature_string
    order = s.count("1")  # from the string: exact for any N
    sig = f"signature {s} (order {order}/{p.n})" if p.n <= TITLE_SIGNATURE_MAX else f"order {order}/{p.n}"
    ax.set_title(f"{display_name(p.name)}: cost {tr.cost:.4g}, {sig}", fontsize=TITLE_PT)
    return fig


def event_points(trajectory):
    """(disk, event index, point) of every disk at every event it takes part in: the
    participants' states after each event (from the event record where the trajectory keeps
    one, else from its keyframes), wall bounces once, collisions once for each disk."""
    tr = trajectory
    ev = tr.events
    e = np.arange(len(ev))
    pair = np.nonzero(ev["kind"] == 0)[0]
    disk = np.concatenate((ev["i"], ev["j"][pair])).astype(np.int64)
    idx = np.concatenate((e, pair))
    state = getattr(tr, "event_state", None)
    if state is not None and len(state) == len(ev):  # (E, 8): xi, yi, vxi, vyi, xj, yj, vxj, vyj
        pts = np.concatenate((state[:, 0:2], state[pair, 4:6]))
    else:
        pts = tr.positions[idx + 1, disk]  # keyframe e + 1: the state after event e
    return disk, idx, pts


def disk_paths(trajectory) -> list[np.ndarray]:
    """Each disk's exact path as a polyline (M_i, 2): its start, its position at each event
    it takes part in (only those bend its path), its final position. For 1,000 disks this is
    N + 2 x events points in all, where every keyframe for every disk would be N x events."""
    tr = trajectory
    n = tr.final_positions.shape[0]
    disk, idx, pts = event_points(tr)
    order = np.lexsort((idx, disk))
    disk, pts = disk[order], pts[order]
    cuts = np.searchsorted(disk, np.arange(1, n))
    start = tr.problem.start
    return [np.concatenate((start[i][None], seg, tr.final_positions[i][None]))
            for i, seg in enumerate(np.split(pts, cuts))]


def save_figure(fig, path, *, dpi: int = 150) -> None:
    """Write a figure, its format from the extension (.png, .pdf, .svg), making its folder.

    Args:
        fig: the matplotlib Figure.
        path: the file to write.
        dpi: dots per inch of a raster format.
    """
    from pathlib import Path
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(str(path), dpi=dpi)
