"""Bowling pictures of the ball's path and of the lane's transition (matplotlib, no pyplot).

* :func:`path_figure`: a Specto-style path plot: the ball's board against its distance from the
  foul line, the lane's 39 boards drawn across (the width exaggerated: the 41.5 in lane over
  60 ft drawn several times wider than to scale), over the oil the ball met (film in um, darker = more),
  with the arrows, the pattern's end, the pocket and each path's breakpoint marked. One throw or
  many (a series' strike balls, coloured by ball number). Boards are the lane's, numbered from
  the right-hander's edge: a left-hander's path is drawn where it ran.
* :func:`transition_figure`: a series' drift: board at the pins, breakpoint board, entry angle and
  the pocket-hit rate (per game, with its 95 % interval) against the ball's number on the lane, one
  colour per run (moves none / auto); the lane before and after each run (a power scale, so that
  carry-down's thin film past the pattern shows), the share of its oil each board lost at 10, 20
  and 30 ft after each game (the track widening), and the oil laid past the pattern's end after
  each game (carry-down).

Both return a ``matplotlib.figure.Figure`` (Agg; nothing global); :func:`save` writes one through
the atomic writer. matplotlib is imported inside the functions (``import nbst.render`` stays light).
"""
from __future__ import annotations

import numpy as np

from nbst.models.bowling.lane.oil import CELL_AREA
from nbst.models.bowling.lane.units import ARROW_BOARDS, ARROWS_FT
from nbst.outputs import atomic_path

__all__ = ["PATH_FIGSIZE", "TRACK_GAMMA", "TRACK_FT", "path_figure", "transition_figure", "save", "lane_board"]

PATH_FIGSIZE = (12.0, 4.6)
#: Run colours by move policy.
COLOURS = {"none": "#c0392b", "auto": "#1f6fb4"}
POCKET_BOARD = 17.5


def lane_board(board, hand: str):
    """A board in the hand's numbering as the lane's (the right-hander's): board b of a left-hander is 40 - b."""
    b = np.asarray(board, dtype=float)
    return b if hand == "right" else 40.0 - b


def _oil(ax, film, dx_ft: float, vmax: float | None = None, gamma: float = 1.0):
    f = np.asarray(film, dtype=float)
    ext = (0.0, f.shape[1] * dx_ft, 0.5, f.shape[0] + 0.5)
    top = vmax if vmax is not None else max(float(f.max()), 1e-9)
    if gamma != 1.0:
        from matplotlib.colors import PowerNorm

        return ax.imshow(f, origin="lower", extent=ext, aspect="auto", cmap="Greys",
                         norm=PowerNorm(gamma, vmin=0.0, vmax=top), interpolation="nearest")
    return ax.imshow(f, origin="lower", extent=ext, aspect="auto", cmap="Greys", vmin=0.0, vmax=top,
                     interpolation="nearest")


#: The lane pictures of a series draw film^TRACK_GAMMA (a power scale), so that carry-down's tenths of
#: a micrometre past the pattern show beside the pattern's micrometres.
TRACK_GAMMA = 0.35
#: Where the track's width is read across the lane (ft past the foul line).
TRACK_FT = (10.0, 20.0, 30.0)


def _track_by_game(ax, before, games, dx: float, move: str) -> None:
    """The share of its oil each board lost, at :data:`TRACK_FT`, after each game: the track widening."""
    from matplotlib import colormaps

    cmap = colormaps["viridis"]
    boards = np.arange(1, before.shape[0] + 1)
    styles = ("-", "--", ":")
    for g in games:
        m = np.asarray(g["map"], dtype=float)
        c = cmap((g["game"] - 1) / max(len(games) - 1, 1))
        for ft, ls in zip(TRACK_FT, styles):
            j = min(int(ft / dx), before.shape[1] - 1)
            ok = before[:, j] > 0
            share = np.where(ok, (before[:, j] - m[:, j]) / np.where(ok, before[:, j], 1.0), np.nan)
            ax.plot(boards, 100 * share, ls, color=c, lw=1.3,
                    label=f"game {g['game']}" if ft == TRACK_FT[0] else None)
    for ft, ls in zip(TRACK_FT, styles):
        ax.plot([], [], ls, color="0.3", label=f"at {ft:g} ft")
    ax.set_xlim(0.5, before.shape[0] + 0.5)
    ax.set_xticks([1, 5, 10, 15, 20, 25, 30, 35, 39])
    ax.set_xlabel("board (lane's, from the right edge)")
    ax.set_ylabel("oil lost (% of the fresh film)")
    ax.set_title(f"the track after each game (move {move}): the share of its oil each board lost", fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, ncol=2, loc="upper right")


def _carry_by_game(ax, before, games, dx: float, length, move: str) -> None:
    """Carry-down: the oil laid past the pattern's end (summed across the lane) against distance, after each game."""
    from matplotlib import colormaps

    cmap = colormaps["viridis"]
    n = before.shape[1]
    ft = (np.arange(n) + 0.5) * dx
    j0 = 0 if length is None else max(int(length / dx) - int(4 / dx), 0)
    for g in games:
        m = np.asarray(g["map"], dtype=float)
        laid = np.clip(m - before, 0.0, None).sum(axis=0) * CELL_AREA * 1e3 / dx  # ul per ft of lane
        c = cmap((g["game"] - 1) / max(len(games) - 1, 1))
        ax.plot(ft[j0:], laid[j0:], color=c, lw=1.5,
                label=f"game {g['game']}: {1e3 * g['past_end_ml']:.0f} ul past the end")
    if length is not None:
        ax.axvline(length, color="#8e6c2f", lw=0.8, ls="--")
    ax.set_xlim(ft[j0], 60.5)
    ax.set_xlabel("distance from the foul line (ft)")
    ax.set_ylabel("oil laid down (ul per ft)")
    ax.set_title(f"carry-down (move {move}): oil the balls laid where the lane was drier than their covers", fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="upper right")





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
    the ball's number on the lane, one colour per run; right, the oil before and after each run and,
    when the run kept the lane after each game (``oil.games``), the track and the carry-down by game."""
    from matplotlib.figure import Figure

    runs = doc["runs"]
    rows = 1 + min(len(runs), 2) + (2 if runs[0]["oil"].get("games") else 0)
    fig = Figure(figsize=(14.0, 2.75 * max(rows, 4)), dpi=100, layout="constrained")
    gs = fig.add_gridspec(max(rows, 4), 2, width_ratios=(1.15, 1.0))
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
    before = np.asarray(runs[0]["oil"]["before"], dtype=float)
    dx = runs[0]["oil"].get("dx_ft", 0.25)
    length = runs[0]["oil"].get("length_ft")
    vmax = max(float(before.max()), 1e-9)
    maps = [("before: the fresh pattern", before, None)]
    maps += [(f"after {r['games']} games, move {r['move']}", np.asarray(r["oil"]["after"], dtype=float), r) for r in runs[:2]]
    for i, (name, m, _) in enumerate(maps):
        ax = fig.add_subplot(gs[i, 1])
        im = _oil(ax, m, dx, vmax, gamma=TRACK_GAMMA)
        _lane_marks(ax, length)
        past = "" if length is None else f", {m[:, int(np.ceil(length / dx)):].sum() * CELL_AREA * 1e3:.0f} ul past its end"
        ax.set_title(f"oil {name}: {m.sum() * CELL_AREA:.2f} ml on the lane{past}", fontsize=9)
        fig.colorbar(im, ax=ax, pad=0.01, fraction=0.04).set_label(f"um (grey ~ film^{TRACK_GAMMA:g})", fontsize=7)
    run = runs[0]
    games = run["oil"].get("games") or []
    if games:
        _track_by_game(fig.add_subplot(gs[len(maps), 1]), before, games, dx, run["move"])
        _carry_by_game(fig.add_subplot(gs[len(maps) + 1, 1]), before, games, dx, length, run["move"])
    fig.suptitle(title or f"{doc.get('bowler', '')}: {doc.get('games', '?')} games by {doc.get('lineup', 1)} "
                          f"bowler(s) on one lane of {doc.get('oil', '')} oil, seed {doc.get('seed')}", fontsize=10)
    return fig


def save(fig, path, *, option: str = "-o") -> None:
    """Write ``fig`` as PNG to ``path`` through the one atomic writer."""

    with atomic_path(path, option=option) as tmp:
        fig.savefig(tmp, format="png")
