"""``report.html``: a self-contained page (inline base64 PNG figures) for a :class:`Validation`.

The figures speak nbst's visual language (:mod:`nbst.palette`; the drawing helpers
are ``nbst.render.figures``'s): class colours, disk numbers at the starts and beside
the targets, and legends outside the axes.

Above :data:`MANY_DISKS` disks (or :data:`MANY_EVENTS` events) the page summarises: statistics
and the worst disks instead of a row per disk, percentile bands instead of a curve per disk,
events per time bin instead of a mark per event.

Compute only: functions return bytes / text; the CLI writes the files.

Length: the page and its four figures, each in a few-disk and a many-disk form that share the
helpers and the visual language; a second module would split each figure's two forms apart.
"""
from __future__ import annotations

import base64
import html
import io

import numpy as np

from nbst import palette
from nbst.solution import dumps_strict

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
#: Lists longer than this in the embedded JSON are summarised (report.json keeps them whole).
JSON_LIST_MAX = 64


def _png(fig) -> str:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=DPI, bbox_inches="tight")
    return base64.b64encode(buf.getvalue()).decode("ascii")


def _figure(size):
    """A figure without pyplot (no global state); constrained layout keeps the
    legends, which sit outside the axes, inside the figure."""
    from matplotlib.figure import Figure
    return Figure(figsize=size, layout="constrained")


def overlay_figure(val):
    """Trajectories, in nbst's visual language (:mod:`nbst.palette`): exact paths in a
    shade of each disk's class colour (solid cueable, dashed noncueable), MuJoCo's
    dotted black over them; each disk filled and numbered at its start, its exact
    final position a thin outline circle (MuJoCo's dotted black), its target a small
    hollow circle numbered with the disk, with the dotted neighbourhood of radius R.
    The legend sits below the box."""
    from matplotlib.patches import Rectangle

    from nbst.render.figures import (circle_handle, draw_final, draw_start, draw_target, legend_below,
                                     line_handle, mark_handles)

    p = val.problem
    if p.n > MANY_DISKS:
        return _overlay_many(val)
    ex, mj = val.exact, val.mujoco
    ts = np.linspace(0.0, p.t_final, 1500)
    ts = np.union1d(ts, ex.events["time"])
    xe = ex.at(ts)
    xm = mj.at(ts)
    fig = _figure((6.5, 6.5 * p.height / p.width + 0.4))
    ax = fig.add_subplot(1, 1, 1)
    ax.set_xlim(-0.02 * p.width, 1.02 * p.width)
    ax.set_ylim(-0.02 * p.height, 1.02 * p.height)
    ax.set_aspect("equal")
    ax.add_patch(Rectangle((0, 0), p.width, p.height, fill=False, lw=1.5, color="0.3"))
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
    from nbst.problem import display_name
    how = (f"aligned stepping, probe step {val.timestep * 1e3:g} ms" if getattr(val, "stepping", "fixed") == "aligned"
           else f"fixed steps of {val.timestep * 1e3:g} ms")
    ax.set_title(f"{display_name(p.name)}: paths, exact (nbst) and MuJoCo ({how})", fontsize=9)
    return fig


def _worst(val, k: int) -> np.ndarray:
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
    from matplotlib.patches import Circle, Rectangle

    from nbst.problem import display_name
    from nbst.render.figures import circle_handle, legend_below, line_handle

    p = val.problem
    ex, mj = val.exact, val.mujoco
    # the exact paths are straight between events: their keyframes plus t_final draw them exactly
    ts = np.union1d(np.linspace(0.0, p.t_final, 200), ex.events["time"])
    fig = _figure((6.5, 6.5 * p.height / p.width + 0.4))
    ax = fig.add_subplot(1, 1, 1)
    ax.set_xlim(-0.02 * p.width, 1.02 * p.width)
    ax.set_ylim(-0.02 * p.height, 1.02 * p.height)
    ax.set_aspect("equal")
    ax.add_patch(Rectangle((0, 0), p.width, p.height, fill=False, lw=1.5, color="0.3"))
    cols = [palette.hex_color(c) for c in palette.class_colors(p.cueable)]
    lw = float(np.clip(60.0 / np.sqrt(p.n), 0.25, 1.0))
    xe = ex.at(ts)  # (T, N, 2): T ~ 200 + events (48 MB at 1,000 disks and 3,000 events)
    ax.add_collection(LineCollection(list(np.transpose(xe, (1, 0, 2))), colors=cols, linewidths=lw, alpha=0.4,
                                     zorder=2))
    ax.add_collection(PatchCollection([Circle(tuple(c), r) for c, r in zip(p.start, p.radius)], facecolors=cols,
                                      edgecolors="none", alpha=0.9, zorder=3))
    ax.plot(p.target[:, 0], p.target[:, 1], ".", color=palette.hex_color(palette.TARGET_INK), ms=1.5, zorder=3)
    worst = _worst(val, WORST_ROWS)
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
    from nbst.render.figures import legend_below, line_handle

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
    ax.axhline(val.tol, color="black", ls="-.", lw=0.9)
    at_floor = bool((np.asarray(val.error_curve) < floor).any())
    if at_floor:
        ax.axhline(floor, color="0.55", ls=(0, (1, 2)), lw=0.9, zorder=0)
    if val.diverge:
        ax.axvline(val.diverge["time"], color="black", ls=":", lw=1.1)
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
    from nbst.render.figures import legend_below, line_handle

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
    worst = _worst(val, WORST_CURVES)
    cols = [palette.hex_color(c) for c in palette.class_colors(p.cueable)]
    for i in worst:
        ax.semilogy(ts, err[:, i], palette.path_style(p.cueable[i]), color=cols[i], lw=0.9, zorder=2.5)
    ax.axhline(val.tol, color="black", ls="-.", lw=0.9)
    at_floor = bool((np.asarray(val.error_curve) < floor).any())
    if at_floor:
        ax.axhline(floor, color="0.55", ls=(0, (1, 2)), lw=0.9, zorder=0)
    if val.diverge:
        ax.axvline(val.diverge["time"], color="black", ls=":", lw=1.1)
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
    from nbst.render.figures import legend_below, line_handle

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
    from nbst.render.figures import legend_below, line_handle

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
    from nbst.render.figures import legend_below, line_handle

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


_CSS = """body{font-family:system-ui,sans-serif;max-width:60em;margin:1.5em auto;padding:0 1em;color:#222}
h1{font-size:1.4em}h2{font-size:1.1em;margin-top:1.5em}table{border-collapse:collapse;font-size:.85em}
td,th{border:1px solid #ccc;padding:.2em .5em;text-align:right}th{background:#f3f3f3}
.ok{color:#176317}.bad{color:#b00}pre{background:#f6f6f6;padding:.6em;font-size:.85em;overflow-x:auto}
img{max-width:100%}.small{font-size:.85em;color:#555}"""


def _error_note(val) -> str:
    """What the error curve shows, for the stepping used."""
    if getattr(val, "stepping", "fixed") == "aligned":
        return ("Aligned stepping resolves each impact at its touch (late by overlap / speed, ~1e-12 units); what "
                "remains grows only through the motion's own sensitivity (its amplification, above).")
    return ("MuJoCo resolves each impact one step late (an exact reflection delayed by the timestep), so each "
            "impact adds about |&Delta;v|&middot;h; oblique collisions also err in direction by ~0.1&deg; at "
            "0.25 ms.")


def _num(x, fmt=".3g") -> str:
    return "&ndash;" if x is None else format(x, fmt)


def _stepping_html(val, d) -> str:
    """The stepping mode and, for aligned stepping, its cost."""
    st = d["stepping"]
    why = (f"<p>Why this stepping: {html.escape(st['reason'])}.</p>" if st.get("reason") else "")
    stride = st.get("record_stride", 1)
    rec = (f"<p class=small>Positions were recorded every {stride} steps ({val.problem.n} disks; "
           f"<code>nbst.models.mjrun.RECORD_FLOATS</code> bounds the memory): the divergence time is located to "
           f"that resolution; the final positions, energy and events use every step.</p>" if stride > 1 else "")
    if st["mode"] != "aligned" or not st["cost"]:
        return (f"<h2>Stepping: fixed</h2><p>Fixed steps of h = {val.timestep * 1e3:g} ms ({st['steps']} steps, "
                f"{st['stepping_wall_time_s']:.2f} s): MuJoCo resolves each impact one step late. "
                f"<code>--stepping aligned</code> ends a step at each touch instead.</p>{why}{rec}")
    c = st["cost"]
    rows = "".join(f"<tr><td style='text-align:left'>{k}</td><td>{v}</td></tr>" for k, v in (
        ("accepted steps (h, or shortened to end at a touch)", c["steps"]),
        ("impact micro-steps (one per impact)", c["impacts"]),
        ("&nbsp;&nbsp;of them in the same instant as the previous one", c["simultaneous"]),
        ("&nbsp;&nbsp;capped at h (grazing)", c["capped"]),
        ("trial steps locating touches (regula falsi)", c["bisections"]),
        ("trial steps checking grazes inside a step", c["graze_checks"]),
        ("all mj_step calls (trials + micro-steps)", c["trials"] + c["impacts"]),
        ("deepest overlap resolved (m)", f"{c['max_overlap']:.3g}"),
        ("wall time (s)", f"{c['wall_time']:.3f}")))
    return (f"<h2>Stepping: aligned</h2><p>Probe step h = {val.timestep * 1e3:g} ms; every step that would "
            f"cross a touch is shortened to end just past it (MuJoCo's own collision detection), and each "
            f"impact is resolved by one micro-step whose contact stiffness matches it "
            f"(<code>nbst.models.stepping</code>). Fixed stepping takes "
            f"{int(np.ceil(val.problem.t_final / val.timestep - 1e-9))} steps for the same motion.</p>{why}"
            f"<table><tr><th>cost</th><th></th></tr>{rows}</table>{rec}")


def _sensitivity_html(d) -> str:
    """A short table: amplification, velocity tolerance, predicted against measured fixed-step error."""
    sens, pc = d.get("sensitivity"), d.get("prediction_check")
    if not sens:
        return ""
    if sens.get("skipped"):
        return (f"<h2>Sensitivity</h2><p>Not run: {html.escape(sens['skipped'])} "
                f"(<code>--sensitivity on</code> forces it).</p>")
    if sens.get("error"):
        return f"<h2>Sensitivity</h2><p>No sensitivity analysis: {html.escape(sens['error'])}.</p>"
    rows = [("amplification (largest singular value of d final / d initial velocities)",
             f"{_num(sens['amplification'])} s"),
            ("velocity tolerance (keeps every disk on its side of R)", f"{_num(sens['velocity_tolerance'])} units/s")]
    if pc:
        def yn(x):
            return "yes" if x else "no"
        rows += [(f"fixed steps of {pc['timestep'] * 1e3:g} ms: predicted max error, linear / worst case",
                  f"{_num(pc['predicted_error_linear_max'])} / {_num(pc['predicted_error_max'])} units"),
                 (f"measured max error ({html.escape(pc['fixed_run'])})", f"{_num(pc['measured_error_max'])} units"),
                 ("measured / predicted (linear)", _num(pc["measured_over_linear"])),
                 ("keeps the signature: predicted (worst case) / measured",
                  f"{yn(pc['keeps_signature_predicted'])} / {yn(pc['keeps_signature_measured'])} "
                  f"(<b class={'bad' if pc['verdict'] == 'wrong' else 'ok'}>{pc['verdict']}</b>)")]
    body = "".join(f"<tr><td style='text-align:left'>{k}</td><td>{v}</td></tr>" for k, v in rows)
    return (f"<h2>Sensitivity and the fixed-step prediction</h2><table>{body}</table>"
            f"<p class=small>First order, from the analytic Jacobian of the exact event chain "
            f"(<code>nbst.sim.sensitivity</code>); the prediction models each impact resolved one step late.</p>")


def _convergence_html(val, d) -> str:
    """The convergence plot, its entries and the fitted order."""
    conv = d.get("convergence")
    if not conv:
        return ""
    co = d.get("convergence_order") or {}
    rows = []
    for e in conv:
        h = "aligned" if e["h"] is None else f"{e['h'] * 1e3:.4g} ms (h/{e['divisor']})"
        if e["skipped"]:
            rows.append(f"<tr><td style='text-align:left'>{h}</td><td colspan=4>skipped: "
                        f"{html.escape(e['skipped'])}</td></tr>")
            continue
        rows.append(f"<tr><td style='text-align:left'>{h}</td><td>{_num(e['max_error'])}</td>"
                    f"<td>{html.escape(e['signature'])}{'' if e['same_signature'] else ' <b class=bad>differs</b>'}"
                    f"</td><td>{e['steps']}</td><td>{e['wall_time']:.2f}</td></tr>")
    used = ", ".join(f"{h * 1e3:.4g}" for h in co.get("points_h") or [])
    fit = (f"Fitted order <b>{co['order']:.2f}</b> (least-squares slope of log error on log h) on h = {used} ms: "
           if co.get("order") is not None else "No order fitted (fewer than two points qualify): ")
    return (f"<h2>Convergence</h2><img alt='error against step size' "
            f"src='data:image/png;base64,{figure_convergence(val)}'>"
            f"<p>{fit}{html.escape(co.get('rule', ''))}.</p>"
            f"<table><tr><th>step</th><th>max final error (units)</th><th>signature</th><th>steps</th>"
            f"<th>wall time (s)</th></tr>{''.join(rows)}</table>")


def _verdict_html(val, d, same: bool) -> str:
    """The signatures: both strings up to :data:`MANY_DISKS` disks; counts and the disks that differ above."""
    ex, mj = d["exact"], d["mujoco_result"]
    cls = "ok" if same else "bad"
    head = f"<b>Signature {'the same' if same else 'DIFFERENT'}</b>"
    if val.problem.n <= MANY_DISKS:
        return (f"<p class=\"{cls}\">{head}:\nexact {ex['signature']} (order {ex['order']}, cost {ex['cost']:.6g}),\n"
                f"MuJoCo {mj['signature']} (order {mj['order']}, cost {mj['cost']:.6g}).</p>")
    diff = val.signature_differs_at
    where = ("" if not diff.size else f" It differs at {diff.size:,} disks: "
             + ", ".join(map(str, diff[:20].tolist())) + (" &hellip;" if diff.size > 20 else "") + ".")
    return (f"<p class=\"{cls}\">{head}: {ex['order']:,} of {val.problem.n:,} disks end within R of their targets "
            f"in the exact motion (cost {ex['cost']:.6g}), {mj['order']:,} under MuJoCo (cost {mj['cost']:.6g})."
            f"{where} Both signature strings are in report.json.</p>")


def _final_html(val, d, rows: list, many: bool) -> str:
    """Final positions: every disk up to :data:`MANY_DISKS`; statistics and the worst disks above."""
    head = ("<table><tr><th>disk</th><th>exact</th><th>MuJoCo</th><th>error</th><th>exact sig</th>"
            "<th>MuJoCo sig</th></tr>" + "".join(rows) + "</table>")
    if not many:
        return "<h2>Final positions</h2>" + head
    e = np.asarray(val.final_error, float)
    tol, R = val.tol, float(val.problem.target_radius)
    stats = [("largest", f"{e.max():.4g}"), ("99th percentile", f"{np.percentile(e, 99):.4g}"),
             ("90th percentile", f"{np.percentile(e, 90):.4g}"), ("median", f"{np.median(e):.4g}"),
             ("mean", f"{e.mean():.4g}"), (f"disks within the tolerance {palette.units(tol)}",
                                          f"{int((e <= tol).sum()):,} of {e.size:,}"),
             (f"disks within R = {R:g} of their exact final position", f"{int((e <= R).sum()):,} of {e.size:,}")]
    body = "".join(f"<tr><td style='text-align:left'>{k}</td><td>{v}</td></tr>" for k, v in stats)
    return (f"<h2>Final positions: {val.problem.n:,} disks</h2>"
            f"<table><tr><th>final error |MuJoCo &minus; exact| (units)</th><th></th></tr>{body}</table>"
            f"<h3>The {len(rows)} disks with the largest final error</h3>{head}"
            f"<p class=small>Every disk's final positions and error are in report.json "
            f"(<code>final_error</code>).</p>")


def _short_lists(x):
    """``x`` with every list longer than :data:`JSON_LIST_MAX` replaced by a note (for the page)."""
    if isinstance(x, dict):
        return {k: _short_lists(v) for k, v in x.items()}
    if isinstance(x, list):
        if len(x) > JSON_LIST_MAX:
            return f"[{len(x):,} entries: see report.json]"
        return [_short_lists(v) for v in x]
    return x


def report_html(val) -> str:
    """The whole page as text (every figure embedded)."""
    d = val.to_dict()
    esc = html.escape
    p = val.problem
    ev = d["events"]
    same = d["signatures_agree"]
    many = p.n > MANY_DISKS
    rows = []
    for i in (_worst(val, WORST_ROWS) if many else range(p.n)):
        e = val.exact.final_positions[i]
        m = val.mujoco.final_positions[i]
        rows.append(f"<tr><td>{i}</td><td>{e[0]:.3f}, {e[1]:.3f}</td><td>{m[0]:.3f}, {m[1]:.3f}</td>"
                    f"<td>{val.final_error[i]:.4g}</td><td>{d['exact']['signature'][i]}</td>"
                    f"<td>{d['mujoco_result']['signature'][i]}</td></tr>")
    final_html = _final_html(val, d, rows, many)
    def ev_rows():
        out = []
        ex, mj = val.exact.events, val.mujoco.events
        for a, b in val.matches:
            off = (mj["time"][b] - ex["time"][a]) * 1e3
            out.append((float(ex["time"][a]), a, "exact", f"{off:+.3f} ms" if val.stepping == "fixed" else f"{off:+.3g} ms"))
        me = {a for a, _ in val.matches}
        mm = {b for _, b in val.matches}
        out += [(float(ex["time"][k]), k, "exact", "<b class=bad>exact only</b>") for k in range(len(ex)) if k not in me]
        out += [(float(mj["time"][k]), k, "mujoco", "<b class=bad>MuJoCo only</b>")
                for k in range(len(mj)) if k not in mm]
        out.sort(key=lambda r: r[0])
        note = ""
        if len(out) > 2 * EVENT_ROWS:  # the first rows, then the first mismatches after them
            head = out[:EVENT_ROWS]
            later = [r for r in out[EVENT_ROWS:] if "only" in r[3]]
            rest = later[:EVENT_ROWS]
            then = (f", then the first {len(rest)} of the {len(later):,} later events that only one motion has"
                    if later else " (no later event is missing from either motion)")
            note = (f"<p class=small>{len(out):,} rows: the first {len(head)} in time{then}; every event is in "
                    f"report.json.</p>")
            out = head + [(None, None, None, None)] + rest
        cells = []
        for t, k, side, o in out:
            if t is None:
                cells.append("<tr><td style='text-align:left' colspan=2>&hellip;</td></tr>")
                continue
            text = describe(int(evs[side][k]["kind"]), int(evs[side][k]["i"]), int(evs[side][k]["j"]), t)
            cells.append(f"<tr><td style='text-align:left'>{esc(text)}</td><td>{o}</td></tr>")
        return note + "<table><tr><th>event (exact time)</th><th>offset</th></tr>" + "".join(cells) + "</table>"

    from nbst.models.validate import describe
    evs = {"exact": val.exact.events, "mujoco": val.mujoco.events}

    div = d["divergence"]
    div_html = (f"<p>Disk <b>{div['disk']}</b> first parts from its exact path by more than "
                f"{palette.units(val.tol)} at "
                f"<b>t = {div['time']:.4f} s</b>. Cause: {esc(div['cause'])}. Chaos makes late divergence normal: "
                f"a small error at one collision grows at every later one.</p>" if div else
                f"<p class=ok>No divergence: every disk stays within {palette.units(val.tol)} of its exact path "
                f"up to t_final.</p>")
    json_text = esc(dumps_strict(_short_lists({k: v for k, v in d.items() if k not in ("events", "velocities")}),
                                 indent=1))
    json_lines = json_text.count("\n") + 1
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>nbst validate: {esc(p.name)}</title>
<style>{_CSS}</style></head><body>
<h1>nbst validate: {esc(p.name)}</h1>
<p class=small>{esc(p.description)}</p>
<p>{p.n} disks, t_final = {p.t_final:g} s. MuJoCo {esc(d['mujoco']['version'])}, timestep
{val.timestep * 1e3:g} ms ({d['mujoco']['steps']} steps), <b>{esc(d['stepping']['mode'])} stepping</b>
({'chosen by --stepping auto; why: under Stepping' if d['stepping'].get('requested') == 'auto' else 'requested'}),
1 unit = {val.unit:g} m.</p>
<h2>Verdict</h2>
{_verdict_html(val, d, same)}
<p>Largest final position error {d['final_error']['max']:.4g} units. Events: {ev['matched']} matched in order,
{ev['exact_only']} exact only, {ev['mujoco_only']} MuJoCo only. Kinetic energy drift
{d['energy']['drift_max_contact_free']:.3g} (largest, over contact-free steps).</p>
{div_html}
{_stepping_html(val, d)}
{_sensitivity_html(d)}
{_convergence_html(val, d)}
<h2>Trajectories</h2><img alt="trajectory overlay" src="data:image/png;base64,{figure_overlay(val)}">
<h2>Per-disk error over time</h2><img alt="error over time" src="data:image/png;base64,{figure_error(val)}">
<p class=small>{_error_note(val)}</p>
<h2>Event timeline</h2><img alt="event timeline" src="data:image/png;base64,{figure_timeline(val)}">
{final_html}
<h2>Events (matched in order; offset = MuJoCo time &minus; exact time)</h2>
{ev_rows()}
<h2>Summary data</h2>
<details><summary>The numbers above as JSON ({json_lines} lines; also written beside this page as
<a href="report.json">report.json</a>, with every event)</summary><pre>{json_text}</pre></details>
</body></html>
"""
