"""Bowling pictures of the ball's path and of the lane's transition (matplotlib, no pyplot).

* :func:`path_figure`: a Specto-style path plot: the ball's board against its distance from the
  foul line, the lane's 39 boards drawn across (the width exaggerated: the 41.5 in lane over
  60 ft drawn several times wider than to scale), over the oil the ball met (film in um, darker = more),
  with the arrows, the pattern's end, the pocket and each path's breakpoint marked. One throw or
  many (a series' strike balls, coloured by ball number). Boards are the lane's, numbered from
  the right-hander's edge: a left-hander's path is drawn where it ran.
* :func:`transition_figure`: a series' drift: board at the pins, breakpoint board, entry angle and
  the pocket-hit rate (per game, with its 95 % interval) against the ball's number on the lane, one
  colour per run (moves none / auto), and the oil maps before and after each run.

Both return a ``matplotlib.figure.Figure`` (Agg; nothing global); :func:`save` writes one through
the atomic writer. matplotlib is imported inside the functions (``import nbst.render`` stays light).
"""
from __future__ import annotations

import numpy as np

from nbst.models.bowling.lane.oil import CELL_AREA
from nbst.models.bowling.lane.units import ARROW_BOARDS, ARROWS_FT
from nbst.outputs import atomic_path

__all__ = ["PATH_FIGSIZE", "path_figure", "transition_figure", "save", "lane_board"]

PATH_FIGSIZE = (12.0, 4.6)
#: Run colours by move policy.
COLOURS = {"none": "#c0392b", "auto": "#1f6fb4"}
POCKET_BOARD = 17.5


def lane_board(board, hand: str):
    """A board in the hand's numbering as the lane's (the right-hander's): board b of a left-hander is 40 - b."""
    b = np.asarray(board, dtype=float)
    return b if hand == "right" else 40.0 - b


def _oil(ax, film, dx_ft: float, vmax: float | None = None):
    f = np.asarray(film, dtype=float)
    ext = (0.0, f.shape[1] * dx_ft, 0.5, f.shape[0] + 0.5)
    return ax.imshow(f, origin="lower", extent=ext, aspect="auto", cmap="Greys", vmin=0.0,
                     vmax=vmax if vmax is not None else max(float(f.max()), 1e-9), interpolation="nearest")


def _lane_marks(ax, length_ft: float | None) -> None:
    ax.set_xlim(0, 60.5)
    ax.set_ylim(0.5, 39.5)
    ax.set_yticks([1, 5, 10, 15, 20, 25, 30, 35, 39])
    ax.set_xticks(range(0, 61, 5))
    ax.plot([ARROWS_FT] * len(ARROW_BOARDS), ARROW_BOARDS, "^", color="#8e6c2f", ms=6, zorder=3)
    if length_ft:
        ax.axvline(length_ft, color="#8e6c2f", lw=0.8, ls="--", zorder=2)
        ax.text(length_ft, 39.2, f" pattern end {length_ft:g} ft", fontsize=7, va="top", color="#8e6c2f")
    ax.axvline(60.0, color="0.3", lw=0.8)
    for b in (POCKET_BOARD, 40 - POCKET_BOARD):  # a right-hander's pocket and a left-hander's
        ax.plot([60.0], [b], "o", mfc="none", mec="#2e7d32", ms=8, zorder=4)
    ax.text(60.3, POCKET_BOARD, "pocket", fontsize=7, va="center", color="#2e7d32")
    ax.set_xlabel("distance from the foul line (ft)")
    ax.set_ylabel("board (lane's, from the right edge)")


def path_figure(paths, *, film=None, dx_ft: float = 0.25, length_ft: float | None = None, title: str = "",
                label_breakpoints: bool | None = None):
    """A Specto-style plot of ``paths``: dicts with ``ft``, ``board`` (the bowler's boards), ``hand``
    and optionally ``breakpoint_ft``/``breakpoint_board`` (marked) and ``n`` (colour by order);
    ``film`` (39 x n um) is drawn underneath. Breakpoints are labelled when there are at most 3 paths."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=PATH_FIGSIZE, dpi=100, layout="constrained")
    ax = fig.add_subplot(1, 1, 1)
    if film is not None:
        im = _oil(ax, film, dx_ft)
        fig.colorbar(im, ax=ax, pad=0.01, fraction=0.03).set_label("oil film (um)", fontsize=8)
    _lane_marks(ax, length_ft)
    paths = list(paths)
    label = len(paths) <= 3 if label_breakpoints is None else label_breakpoints
    cmap = None
    if len(paths) > 3:
        from matplotlib import colormaps

        cmap = colormaps["plasma"]
    for k, p in enumerate(paths):
        c = "#1f6fb4" if cmap is None else cmap(k / max(len(paths) - 1, 1))
        ax.plot(p["ft"], lane_board(p["board"], p.get("hand", "right")), color=c, lw=1.4 if cmap is None else 0.8,
                alpha=1.0 if cmap is None else 0.8, zorder=5)
        if p.get("breakpoint_ft") is not None:
            bb = float(lane_board(p["breakpoint_board"], p.get("hand", "right")))
            ax.plot([p["breakpoint_ft"]], [bb], "D", color=c, mec="black", mew=0.5, ms=6 if cmap is None else 4, zorder=6)
            if label:
                ax.annotate(f"breakpoint {p['breakpoint_ft']:.1f} ft, board {p['breakpoint_board']:.1f}",
                            (p["breakpoint_ft"], bb), xytext=(-10, -16 if bb > 6 else 12), textcoords="offset points",
                            fontsize=8, ha="right")
    if cmap is not None:
        from matplotlib.cm import ScalarMappable
        from matplotlib.colors import Normalize

        ns = [p.get("n", k + 1) for k, p in enumerate(paths)]
        sm = ScalarMappable(norm=Normalize(min(ns), max(ns)), cmap=cmap)
        fig.colorbar(sm, ax=ax, pad=0.01, fraction=0.03).set_label("ball number on the lane", fontsize=8)
    ax.set_title(title or "the ball's path (width exaggerated, not to scale; arrows at 15 ft; diamonds: breakpoints)",
                 fontsize=9)
    return fig


def _per_game(balls, key):
    out = {}
    for b in balls:
        if b.get(key) is not None:
            out.setdefault(b["game"], []).append(b)
    return out


def transition_figure(doc: dict, *, title: str = ""):
    """The drift of a series file's content ``doc`` (:func:`.transition.series_dict`): left, the strike
    balls' board at the pins, breakpoint board, entry angle and the pocket-hit rate per game against
    the ball's number on the lane, one colour per run; right, the oil before and after each run."""
    from matplotlib.figure import Figure

    runs = doc["runs"]
    fig = Figure(figsize=(14.0, 11.0), dpi=100, layout="constrained")
    gs = fig.add_gridspec(4, 2, width_ratios=(1.15, 1.0))
    left = [fig.add_subplot(gs[i, 0]) for i in range(4)]
    lo, hi = doc.get("pocket_boards", (16.5, 18.5))
    for run in runs:
        c = COLOURS.get(run["move"], "0.3")
        first = [b for b in run["balls"] if len(b["standing"]) == 10]
        hands = sorted({b["hand"] for b in first}, reverse=True)  # right first
        lab = f"move {run['move']}" + (f" ({len(run['moves'])} moves)" if run["move"] != "none" else "")
        for hand in hands:
            mine = [b for b in first if b["hand"] == hand]
            n = np.array([b["n"] for b in mine])
            for ax, key in zip(left[:3], ("board_at_pins", "breakpoint_board", "entry_angle_deg")):
                v = np.array([np.nan if b[key] is None else b[key] for b in mine], dtype=float)
                ax.plot(n, v, "o" if hand == "right" else "s", color=c, ms=3, alpha=0.55,
                        mfc=c if hand == "right" else "none")
                w = min(10, len(v))
                if w >= 2:
                    ok = np.isfinite(v)
                    run_mean = np.array([np.nanmean(v[max(0, i - w + 1):i + 1]) if ok[max(0, i - w + 1):i + 1].any()
                                         else np.nan for i in range(len(v))])
                    ax.plot(n, run_mean, color=c, lw=1.6, ls="-" if hand == "right" else ":",
                            label=f"{lab}{', ' + hand + '-handed' if len(hands) > 1 else ''}: mean of the last {w}")
        for s in run["summary"]:
            games = [b for b in first if b["game"] == s["game"] and b["hand"] == s["hand"]]
            if not games:
                continue
            x0, x1 = games[0]["n"], games[-1]["n"]
            left[3].plot([x0, x1], [100 * s["pocket_rate"]] * 2, color=c, lw=2.2,
                         ls="-" if s["hand"] == "right" else ":")
            left[3].fill_between([x0, x1], 100 * s["pocket_lo"], 100 * s["pocket_hi"], color=c, alpha=0.12, lw=0)
            left[3].text((x0 + x1) / 2, 100 * s["pocket_rate"] + 2, f"{s['pocket_hits']}/{s['strike_balls']}",
                         color=c, fontsize=7, ha="center")
        for m in run.get("moves", []):
            for ax in left:
                ax.axvline(m["after_ball"] + 0.5, color=c, lw=0.6, ls=":", alpha=0.7)
    left[0].axhspan(lo, hi, color="#2e7d32", alpha=0.1, lw=0)
    left[0].set_ylabel("board at the pins")
    left[0].set_title(f"strike balls (boards in the bowler's own numbering); green: the pocket {lo:g}-{hi:g}; "
                      f"thin dotted lines: moves", fontsize=9)
    left[1].set_ylabel("breakpoint board")
    left[2].set_ylabel("entry angle (deg)")
    left[3].set_ylabel("pocket hits per game (%)")
    left[3].set_ylim(0, 105)
    left[3].set_xlabel("ball number on the lane (strike and spare balls counted)")
    for ax in left:
        ax.grid(alpha=0.3)
    left[0].legend(fontsize=7, loc="best")
    vmax = max(float(np.max(runs[0]["oil"]["before"])), 1e-9)
    dx = runs[0]["oil"].get("dx_ft", 0.25)
    maps = [("before: the fresh pattern", runs[0]["oil"]["before"])]
    maps += [(f"after {r['games']} games, move {r['move']}", r["oil"]["after"]) for r in runs[:2]]
    before = np.asarray(runs[0]["oil"]["before"], dtype=float)
    after = np.asarray(runs[0]["oil"]["after"], dtype=float)
    for i, (name, m) in enumerate(maps):
        ax = fig.add_subplot(gs[i, 1])
        im = _oil(ax, m, dx, vmax)
        _lane_marks(ax, runs[0]["oil"].get("length_ft"))
        ax.set_title(f"oil {name} (um; {np.asarray(m).sum() * CELL_AREA:.2f} ml on the lane)", fontsize=9)
        fig.colorbar(im, ax=ax, pad=0.01, fraction=0.04)
    ax = fig.add_subplot(gs[len(maps), 1])
    diff = after - before
    lim = max(float(np.abs(diff).max()), 1e-9)
    im = ax.imshow(diff, origin="lower", extent=(0.0, diff.shape[1] * dx, 0.5, diff.shape[0] + 0.5), aspect="auto",
                   cmap="RdBu", vmin=-lim, vmax=lim, interpolation="nearest")
    _lane_marks(ax, runs[0]["oil"].get("length_ft"))
    ax.set_title(f"oil change, move {runs[0]['move']} (um; red: taken, blue: laid down)", fontsize=9)
    fig.colorbar(im, ax=ax, pad=0.01, fraction=0.04)
    fig.suptitle(title or f"{doc.get('bowler', '')}: {doc.get('games', '?')} games by {doc.get('lineup', 1)} "
                          f"bowler(s) on one lane of {doc.get('oil', '')} oil, seed {doc.get('seed')}", fontsize=10)
    return fig


def save(fig, path, *, option: str = "-o") -> None:
    """Write ``fig`` as PNG to ``path`` through the one atomic writer."""

    with atomic_path(path, option=option) as tmp:
        fig.savefig(tmp, format="png")
