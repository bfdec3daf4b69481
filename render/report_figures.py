"""The four figures of the validation report (``report.html``, :mod:`nbst.render.report`).

Each figure has a few-disk and a many-disk form (above :data:`MANY_DISKS` disks or
:data:`MANY_EVENTS` events: statistics, percentile bands and the worst disks instead of a
curve or mark per disk) and speaks nbst's visual language (:mod:`nbst.palette`; the drawing
helpers are :mod:`nbst.render.figures`'s): class colours, disk numbers at the starts and
beside the targets, and legends outside the axes. ``figure_*`` return base64 PNG for the page.
"""
from __future__ import annotations

import base64
import io

import numpy as np

from nbst import palette
from nbst.problem import display_name
from nbst.render.figures import (circle_handle, draw_final, draw_start, draw_target, legend_below, line_handle,
                                 mark_handles)

__all__ = ["DPI", "EVENT_ROWS", "MANY_DISKS", "MANY_EVENTS", "WORST_CURVES", "WORST_ROWS", "convergence_figure",
           "error_figure", "error_floor", "figure_convergence", "figure_error", "figure_overlay", "figure_timeline",
           "overlay_figure", "timeline_figure", "worst_disks"]

#: Figure resolution (dots per inch); figures are ~7 in wide.
DPI = 110
#: Above this many disks the report summarises: the final positions as statistics and the worst
#: disks (:data:`WORST_ROWS`), the error over time as percentile bands and the worst curves, the
#: overlay without numbers except on the worst disks; a legend naming every disk stops being read
#: at a few dozen entries.
MANY_DISKS = 30
#: Disks named (curves, paths, table rows) in a summarised report.
WORST_ROWS = 10
WORST_CURVES = 5
#: Above this many events (both motions) the timeline shows events per time bin and the event
#: table the first :data:`EVENT_ROWS` rows and the first mismatches; report.json keeps every event.
MANY_EVENTS = 150
EVENT_ROWS = 40
def _png(fig) -> str:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=DPI, bbox_inches="tight")
    return base64.b64encode(buf.getvalue()).decode("ascii")


def _figure(size):
    """A figure without pyplot (no global state); constrained layout keeps the
    legends, which sit outside the axes, inside the figure."""
    from matplotlib.figure import Figure
    return Figure(figsize=size, layout="constrained")


def _box_figure(p):
    """A figure of the problem's box to scale (the overlay's both forms): (figure, its axes)."""
    from matplotlib.patches import Rectangle

    fig = _figure((6.5, 6.5 * p.height / p.width + 0.4))
    ax = fig.add_subplot(1, 1, 1)
    ax.set_xlim(-0.02 * p.width, 1.02 * p.width)
    ax.set_ylim(-0.02 * p.height, 1.02 * p.height)
    ax.set_aspect("equal")
    ax.add_patch(Rectangle((0, 0), p.width, p.height, fill=False, lw=1.5, color="0.3"))
    return fig, ax


def overlay_figure(val):
    """Trajectories, in nbst's visual language (:mod:`nbst.palette`): exact paths in a
    shade of each disk's class colour (solid cueable, dashed noncueable), MuJoCo's
    dotted black over them; each disk filled and numbered at its start, its exact
    final position a thin outline circle (MuJoCo's dotted black), its target a small
    hollow circle numbered with the disk, with the dotted neighbourhood of radius R.
    The legend sits below the box."""

    p = val.problem
    if p.n > MANY_DISKS:
        return _overlay_many(val)
    ex, mj = val.exact, val.mujoco
    ts = np.linspace(0.0, p.t_final, 1500)
    ts = np.union1d(ts, ex.events["time"])
    xe = ex.at(ts)
    xm = mj.at(ts)
    fig, ax = _box_figure(p)
    shades = palette.disk_shades(p.cueable)
    mj_ink = palette.hex_color(palette.INK)
    for i in range(p.n):
        ax.plot(xe[:, i, 0], xe[:, i, 1], palette.path_style(p.cueable[i]), color=palette.hex_color(shades[i]),
                lw=1.3, zorder=3)
        ax.plot(xm[:, i, 0], xm[:, i, 1], ":", color=mj_ink, lw=0.8, alpha=0.7, zorder=3.5)
        draw_target(ax, p.target[i], p.radius[i], i, R=p.target_radius)
        draw_final(ax, ex.final_positions[i], p.radius[i], shades[i], zorder=4)
        draw_final(ax, mj.final_positions[i], p.radius[i], mj_ink, ls=":", zorder=4)
        draw_start(ax, p.start[i], p.radius[i], p.cueable[i], i)
    entries = mark_handles(p, paths=True, final=True, ring=True, path_prefix="exact ",
                           final_label="final position, exact")
    entries += [(line_handle(mj_ink, ":", lw=1.0), "MuJoCo path"),
                (circle_handle(ec=mj_ink, lw=1.0, ls=":"), "final position, MuJoCo")]
    legend_below(fig, entries)
    how = (f"aligned stepping, probe step {val.timestep * 1e3:g} ms" if getattr(val, "stepping", "fixed") == "aligned"
           else f"fixed steps of {val.timestep * 1e3:g} ms")
    ax.set_title(f"{display_name(p.name)}: paths, exact (nbst) and MuJoCo ({how})", fontsize=9)
    return fig


def worst_disks(val, k: int) -> np.ndarray:
    """Indices of the k disks with the largest final error, worst first."""
    return np.argsort(-np.asarray(val.final_error), kind="stable")[:k]


def _how(val) -> str:
    return (f"aligned stepping, probe step {val.timestep * 1e3:g} ms" if getattr(val, "stepping", "fixed") == "aligned"
            else f"fixed steps of {val.timestep * 1e3:g} ms")


def _overlay_many(val):
    """The overlay for many disks: every exact path thin in its class colour (one LineCollection),
    every start a filled disk and every target a grey dot; only the :data:`WORST_ROWS` disks with the
    largest final error are numbered, with their MuJoCo path dotted black over a thicker exact path
    and their final positions as outline circles."""
    from matplotlib.collections import LineCollection, PatchCollection
    from matplotlib.patches import Circle


    p = val.problem
    ex, mj = val.exact, val.mujoco
    # the exact paths are straight between events: their keyframes plus t_final draw them exactly
    ts = np.union1d(np.linspace(0.0, p.t_final, 200), ex.events["time"])
    fig, ax = _box_figure(p)
    cols = [palette.hex_color(c) for c in palette.class_colors(p.cueable)]
    lw = float(np.clip(60.0 / np.sqrt(p.n), 0.25, 1.0))
    xe = ex.at(ts)  # (T, N, 2): T ~ 200 + events (48 MB at 1,000 disks and 3,000 events)
    ax.add_collection(LineCollection(list(np.transpose(xe, (1, 0, 2))), colors=cols, linewidths=lw, alpha=0.4,
                                     zorder=2))
    ax.add_collection(PatchCollection([Circle(tuple(c), r) for c, r in zip(p.start, p.radius)], facecolors=cols,
                                      edgecolors="none", alpha=0.9, zorder=3))
    ax.plot(p.target[:, 0], p.target[:, 1], ".", color=palette.hex_color(palette.TARGET_INK), ms=1.5, zorder=3)
    worst = worst_disks(val, WORST_ROWS)
    mj_ink = palette.hex_color(palette.INK)
    xm = mj.at(ts)[:, worst] if worst.size else None
    for k, i in enumerate(worst):
        ax.plot(xe[:, i, 0], xe[:, i, 1], palette.path_style(p.cueable[i]),
                color=palette.hex_color(palette.shade(palette.class_color(p.cueable[i]), 0.42)), lw=1.6, zorder=4)
        ax.plot(xm[:, k, 0], xm[:, k, 1], ":", color=mj_ink, lw=1.0, zorder=4.5)
        for xy, ls in ((ex.final_positions[i], "-"), (mj.final_positions[i], ":")):
            ax.add_patch(Circle(tuple(xy), p.radius[i], fill=False, ec=mj_ink if ls == ":" else cols[i], ls=ls,
                                lw=0.9, zorder=5))
        ax.annotate(str(int(i)), xy=tuple(p.start[i]), xytext=(3, 3), textcoords="offset points", fontsize=7,
                    color="black", zorder=6)
    entries = []
    if p.cueable.any():
        entries.append((line_handle(palette.hex_color(palette.CUEABLE), "-", lw=1.0), "exact path, cueable disk"))
    if (~p.cueable).any():
        entries.append((line_handle(palette.hex_color(palette.NONCUEABLE), "-", lw=1.0),
                        "exact path, noncueable disk"))
    entries += [(circle_handle(fc=palette.hex_color(palette.CUEABLE), ec="none"), "disk at its start"),
                (line_handle(palette.hex_color(palette.TARGET_INK), "none", marker=".", ms=4), "target"),
                (line_handle(mj_ink, ":", lw=1.0), f"MuJoCo path of the {worst.size} worst disks (numbered)"),
                (circle_handle(ec=mj_ink, lw=1.0, ls=":"), "their final position, MuJoCo (solid: exact)")]
    legend_below(fig, entries)
    ax.set_title(f"{display_name(p.name)}: {p.n} disks, exact paths (nbst); the {worst.size} disks with the largest "
                 f"final error also under MuJoCo ({_how(val)})", fontsize=9, wrap=True)
    return fig


def _reference_lines(ax, val, floor: float) -> bool:
    """The error plot's reference lines: the tolerance, the round-off floor (where a curve
    reaches it) and the first divergence. Returns whether the floor is drawn (its legend entry)."""
    ax.axhline(val.tol, color="black", ls="-.", lw=0.9)
    at_floor = bool((np.asarray(val.error_curve) < floor).any())
    if at_floor:
        ax.axhline(floor, color="0.55", ls=(0, (1, 2)), lw=0.9, zorder=0)
    if val.diverge:
        ax.axvline(val.diverge["time"], color="black", ls=":", lw=1.1)
    return at_floor


def _spread(y, gap: float, hi: float = 1.0) -> np.ndarray:
    """Positions near ``y`` (axes fractions), at least ``gap`` apart and at most ``hi``:
    where to write the numbers at the ends of curves so that none overlap."""
    y = np.asarray(y, float)
    order = np.argsort(y, kind="stable")
    out = y[order].copy()
    for k in range(1, len(out)):
        out[k] = max(out[k], out[k - 1] + gap)
    if len(out) and out[-1] > hi:  # crowded at the top: push down from there
        out[-1] = hi
        for k in range(len(out) - 2, -1, -1):
            out[k] = min(out[k], out[k + 1] - gap)
    res = np.empty_like(out)
    res[order] = out
    return res


def error_floor(val) -> float:
    """The log axis's floor of the error figure: errors below it (MuJoCo and the exact motion
    agreeing to round-off, or exactly) are drawn at it. Aligned stepping agrees to ~1e-12."""
    return 1e-13 if getattr(val, "stepping", "fixed") == "aligned" else 1e-9


def error_figure(val):
    """Per-disk distance between the two motions over time (log scale), with the
    tolerance: one curve per disk in a shade of its class colour (solid cueable,
    dashed noncueable) carrying the disk's own hollow mark (``palette.disk_marker``),
    so curves are told apart by shape as well as colour (colour-blind readers), and
    numbered at its right end; errors below the floor (``error_floor``) are drawn on
    it, and the legend says so. The legend below names every disk."""

    p = val.problem
    if p.n > MANY_DISKS:
        return _error_many(val)
    fig = _figure((7.5, 3.4))
    ax = fig.add_subplot(1, 1, 1)
    shades = palette.disk_shades(p.cueable)
    floor = error_floor(val)
    err = np.maximum(val.error_curve, floor)
    ts = np.asarray(val.error_curve_t, float)
    marks = 5  # per curve, staggered so that marks of different disks do not sit on one another
    for i in range(p.n):
        at = (np.arange(marks) + (i + 0.5) / p.n) * (p.t_final / marks)
        idx = np.unique(np.clip(np.searchsorted(ts, at), 0, len(ts) - 1))
        col = palette.hex_color(shades[i])
        ax.semilogy(ts, err[:, i], palette.path_style(p.cueable[i]), color=col, lw=1, label=f"_disk {i}",
                    marker=palette.disk_marker(i), markevery=list(idx), ms=4.5, mfc="white", mec=col, mew=1.0)
    at_floor = _reference_lines(ax, val, floor)
    for t in val.exact.events["time"]:
        ax.axvline(t, color="0.88", lw=0.5, zorder=0)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("|MuJoCo - exact| (units)")
    ax.set_xlim(0, p.t_final)
    lo, hi = ax.get_ylim()
    ax.set_ylim(lo, hi)
    # each curve's disk number just right of its end, spread so that numbers never overlap
    end = (np.log10(err[-1]) - np.log10(lo)) / (np.log10(hi) - np.log10(lo))
    at = _spread(end, gap=0.066)  # 7 pt numbers on an axes ~160 pt tall
    for i in range(p.n):
        ax.annotate(str(i), xy=(1.0, end[i]), xycoords="axes fraction", xytext=(1.025, at[i]),
                    textcoords="axes fraction", va="center", ha="left", fontsize=7,
                    color=palette.hex_color(palette.shade(shades[i], 0.25)),
                    arrowprops=dict(arrowstyle="-", lw=0.5, color=palette.hex_color(shades[i]), shrinkA=0,
                                    shrinkB=1.5))
    entries = []
    for i in range(p.n):
        col = palette.hex_color(shades[i])
        entries.append((line_handle(col, palette.path_style(p.cueable[i]), lw=1, marker=palette.disk_marker(i),
                                    ms=4.5, mfc="white", mec=col, mew=1.0), f"disk {i}"))
    entries.append((line_handle("black", "-.", lw=0.9), f"tolerance {palette.units(val.tol)}"))
    if val.diverge:
        entries.append((line_handle("black", ":", lw=1.1), f"first divergence (disk {val.diverge['disk']})"))
    entries.append((line_handle("0.8", "-", lw=0.8), "event (exact)"))
    if at_floor:
        entries.append((line_handle("0.55", (0, (1, 2)), lw=0.9), f"floor: error < {floor:g} (round-off) drawn here"))
    classes = []
    if p.cueable.any():
        classes.append("amber solid: cueable")
    if (~p.cueable).any():
        classes.append("blue dashed: noncueable")
    ncol = min(7, max(3, p.n))
    legend_below(fig, entries, ncol=ncol, grow=True, fontsize=7.0,
                 title=f"one curve per disk, its number at the right end ({'; '.join(classes)})")
    return fig


def _error_many(val):
    """The error over time for many disks: the largest over all disks, the median, the band of the
    10th-90th percentiles, and the :data:`WORST_CURVES` disks with the largest final error as
    numbered curves; the tolerance and the first divergence as in the per-disk figure."""

    p = val.problem
    fig = _figure((7.5, 3.4))
    ax = fig.add_subplot(1, 1, 1)
    floor = error_floor(val)
    err = np.maximum(np.asarray(val.error_curve, float), floor)
    ts = np.asarray(val.error_curve_t, float)
    band = ax.fill_between(ts, np.percentile(err, 10, axis=1), np.percentile(err, 90, axis=1), color="0.82",
                           lw=0, zorder=1)
    ax.semilogy(ts, np.median(err, axis=1), color="0.35", lw=1.2, zorder=2)
    ax.semilogy(ts, err.max(axis=1), color="black", lw=1.2, zorder=3)
    worst = worst_disks(val, WORST_CURVES)
    cols = [palette.hex_color(c) for c in palette.class_colors(p.cueable)]
    for i in worst:
        ax.semilogy(ts, err[:, i], palette.path_style(p.cueable[i]), color=cols[i], lw=0.9, zorder=2.5)
    at_floor = _reference_lines(ax, val, floor)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("|MuJoCo - exact| (units)")
    ax.set_xlim(0, p.t_final)
    lo, hi = ax.get_ylim()
    end = (np.log10(err[-1, worst]) - np.log10(lo)) / (np.log10(hi) - np.log10(lo))
    for i, y, at in zip(worst, end, _spread(end, gap=0.066)):
        ax.annotate(str(int(i)), xy=(1.0, y), xycoords="axes fraction", xytext=(1.025, at),
                    textcoords="axes fraction", va="center", ha="left", fontsize=7, color=cols[i],
                    arrowprops=dict(arrowstyle="-", lw=0.5, color=cols[i], shrinkA=0, shrinkB=1.5))
    entries = [(line_handle("black", "-", lw=1.2), f"largest over all {p.n} disks"),
               (line_handle("0.35", "-", lw=1.2), "median disk"),
               (band, "10th-90th percentile of the disks"),
               (line_handle(cols[int(worst[0])] if worst.size else "0.5", "-", lw=0.9),
                f"the {worst.size} disks with the largest final error (number at the right end)"),
               (line_handle("black", "-.", lw=0.9), f"tolerance {palette.units(val.tol)}")]
    if val.diverge:
        entries.append((line_handle("black", ":", lw=1.1), f"first divergence (disk {val.diverge['disk']})"))
    if at_floor:
        entries.append((line_handle("0.55", (0, (1, 2)), lw=0.9), f"floor: error < {floor:g} (round-off) drawn here"))
    legend_below(fig, entries, ncol=2, grow=True, fontsize=7.0)
    return fig


def _timeline_many(val):
    """Events per time bin for many events: exact events matched in the MuJoCo motion, exact events
    it lacks, and MuJoCo events the exact motion lacks (bins of t_final / 100)."""

    ex, mj = val.exact.events, val.mujoco.events
    T = val.problem.t_final
    edges = np.linspace(0.0, T, 101)
    me = np.zeros(len(ex), bool)
    mm = np.zeros(len(mj), bool)
    for a, b in val.matches:
        me[a] = True
        mm[b] = True
    fig = _figure((7.5, 2.6))
    ax = fig.add_subplot(1, 1, 1)
    series = [(ex["time"][me], "0.45", "-", f"matched in order ({int(me.sum()):,})"),
              (ex["time"][~me], palette.hex_color(palette.COLLISION), "-", f"exact only ({int((~me).sum()):,})"),
              (mj["time"][~mm], "black", "--", f"MuJoCo only ({int((~mm).sum()):,})")]
    entries = []
    for t, col, ls, label in series:
        if t.size:
            ax.stairs(np.histogram(t, edges)[0], edges, color=col, ls=ls, lw=1.2)
            entries.append((line_handle(col, ls, lw=1.2), label))
    ax.set_xlim(0, T)
    ax.set_ylim(bottom=0)
    ax.set_xlabel("time (s)")
    ax.set_ylabel(f"events per {T / 100:.3g} s")
    legend_below(fig, entries, ncol=3, grow=False,
                 title=f"{len(ex):,} exact and {len(mj):,} MuJoCo events (disk-disk and wall), counted per bin")
    return fig


def timeline_figure(val):
    """Events on a time axis: exact above, MuJoCo below, matched pairs joined. The
    marks of ``nbst plot trajectories``: a disk-disk collision a red star, a wall
    bounce a black dot; an event only one motion has is drawn hollow."""

    ex, mj = val.exact.events, val.mujoco.events
    if len(ex) + len(mj) > MANY_EVENTS:
        return _timeline_many(val)
    fig = _figure((7.5, 2.0))
    ax = fig.add_subplot(1, 1, 1)
    me = {a for a, _ in val.matches}
    mm = {b for _, b in val.matches}
    for a, b in val.matches:
        ax.plot([ex["time"][a], mj["time"][b]], [1, 0], color="0.6", lw=0.6, zorder=1)
    coll, wall = palette.hex_color(palette.COLLISION), palette.hex_color(palette.WALL_BOUNCE)
    for evs, y, matched in ((ex, 1, me), (mj, 0, mm)):
        for k, e in enumerate(evs):
            is_coll = e["kind"] == 0
            c = coll if is_coll else wall
            m = palette.COLLISION_MARKER if is_coll else palette.WALL_BOUNCE_MARKER
            ms = 9 if is_coll else 5
            if k in matched:
                ax.plot(e["time"], y, m, color=c, ms=ms, mec="black" if is_coll else c, mew=0.4, zorder=3)
            else:
                ax.plot(e["time"], y, m, ms=ms + 2, mfc="white", mec=c, mew=1.3, zorder=3)
    ax.set_yticks([0, 1], ["MuJoCo", "exact"])
    ax.set_ylim(-0.5, 1.5)
    ax.set_xlim(0, val.problem.t_final)
    ax.set_xlabel("time (s)")
    kinds = set(ex["kind"].tolist()) | set(mj["kind"].tolist())
    entries = []
    if 0 in kinds:
        entries.append((line_handle(coll, "none", marker=palette.COLLISION_MARKER, ms=9, mec="black", mew=0.4),
                        palette.LEGEND_COLLISION))
    if 1 in kinds:
        entries.append((line_handle(wall, "none", marker=palette.WALL_BOUNCE_MARKER, ms=5),
                        palette.LEGEND_WALL_BOUNCE))
    if val.matches:
        entries.append((line_handle("0.6", "-", lw=0.6), "matched pair"))
    if len(me) < len(ex) or len(mm) < len(mj):
        entries.append((line_handle("0.3", "none", marker="o", ms=7, mfc="white", mec="0.3", mew=1.3),
                        "hollow: in one motion only"))
    if entries:
        legend_below(fig, entries, ncol=4, grow=False)
    else:
        ax.text(0.5, 0.5, "no events", transform=ax.transAxes, ha="center", va="center", color="0.4")
    return fig


def convergence_figure(val):
    """Max final error against the step size h (log-log): the fixed-step entries (filled:
    used for the fitted order, hollow: not), the fitted line, and aligned stepping's error as
    a horizontal line (it has no single h). Legend below."""

    ink = palette.hex_color(palette.INK)
    fit_ink = palette.hex_color(palette.RING_INK)
    al_ink = palette.hex_color(palette.TARGET_INK)
    conv = val.convergence or []
    order = val.convergence_order or {}
    used = set(order.get("points_h") or [])
    fixed = [e for e in conv if e["stepping"] == "fixed" and e["max_error"] is not None]
    aligned = [e for e in conv if e["stepping"] == "aligned" and e["max_error"] is not None]
    fig = _figure((6.0, 3.6))
    ax = fig.add_subplot(1, 1, 1)
    floor = 1e-13
    hs = np.array([e["h"] for e in fixed]) * 1e3
    errs = np.maximum([e["max_error"] for e in fixed], floor)
    for e, h_ms, y in zip(fixed, hs, errs):
        filled = e["h"] in used
        ax.loglog([h_ms], [y], "o", ms=6, color=ink, mfc=ink if filled else "white", mew=1.2, zorder=3)
    if order.get("order") is not None:
        xs = np.array([min(order["points_h"]), max(order["points_h"])])
        ax.loglog(xs * 1e3, np.exp(order["intercept_log"]) * xs ** order["order"], "--", color=fit_ink, lw=1.2,
                  zorder=2)
    if aligned:
        ax.axhline(max(aligned[0]["max_error"], floor), color=al_ink, ls="-.", lw=1.1)
    ax.set_xlabel("MuJoCo timestep h (ms)")
    ax.set_ylabel("max final error (units)")
    if hs.size:
        ax.set_xlim(hs.min() / 1.6, hs.max() * 1.6)
    entries = [(line_handle(ink, "none", marker="o", ms=6, mfc=ink), "fixed steps (used for the fit)")]
    if len(used) < len(fixed):
        entries.append((line_handle(ink, "none", marker="o", ms=6, mfc="white", mew=1.2),
                        "fixed steps (not used: outside the first-order regime)"))
    if order.get("order") is not None:
        entries.append((line_handle(fit_ink, "--", lw=1.2), f"fit: error ~ h^{order['order']:.2f}"))
    if aligned:
        entries.append((line_handle(al_ink, "-.", lw=1.1), f"aligned stepping ({aligned[0]['max_error']:.2g})"))
    if any(e["max_error"] < floor for e in fixed + aligned):
        entries.append((line_handle("0.55", "none", marker="_", ms=8), f"below {floor:g}: drawn at {floor:g}"))
    legend_below(fig, entries, ncol=2, grow=False)
    return fig


def figure_convergence(val) -> str:
    """:func:`convergence_figure` as base64 PNG."""
    return _png(convergence_figure(val))


def figure_overlay(val) -> str:
    """:func:`overlay_figure` as base64 PNG."""
    return _png(overlay_figure(val))


def figure_error(val) -> str:
    """:func:`error_figure` as base64 PNG."""
    return _png(error_figure(val))


def figure_timeline(val) -> str:
    """:func:`timeline_figure` as base64 PNG."""
    return _png(timeline_figure(val))
