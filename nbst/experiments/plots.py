"""Tables and figures of ``nbst experiment``: the thin writers (CSV, Markdown, PNG + SVG).

The rows come from ``nbst.experiments.runs`` (pure summaries); here they are only drawn or
written. matplotlib is imported lazily, with the Agg backend (no display needed).
"""
from __future__ import annotations

import csv
import io
from pathlib import Path

from nbst.experiments.runs import fmt, solver_entries
from nbst.outputs import atomic_path, write_text_atomic

__all__ = ["FIG_SIZE", "DPI", "CURVE_FLOOR", "COLORS", "FAMILY_WORDS", "HATCH", "write_csv", "markdown_table",
           "write_markdown", "MEMBER_SHADES", "MEMBER_STYLES", "entry_style", "save_figure", "plot_curves",
           "plot_ablation"]

#: Figure size (inches) and raster resolution: small files for the docs (tens of kB).
FIG_SIZE = (7.0, 4.2)
DPI = 110
#: Log axes: costs below this (e.g. 1e-27 for an exact solution) are drawn at it.
CURVE_FLOOR = 1e-3
#: Bar colours by family (Okabe & Ito's colour-blind-safe set: the three stay apart in a
#: simulated deuteranopia view, tests/cvd.py): the paper's variants A-H blue, nbst's own
#: searches green (nbst-noplan, nbst without its planner, a lighter green with hatching),
#: the baselines orange.
COLORS = {"variant": "#0072b2", "nbst": "#009e73", "nbst-ablated": "#8fd6bf", "baseline": "#e69f00"}
#: Legend words of each family.
FAMILY_WORDS = {"variant": "the paper's search (A-H)", "nbst": "nbst", "nbst-ablated": "nbst with a part off",
                "baseline": "baselines"}
HATCH = {"nbst-ablated": "///"}


def write_csv(path: str | Path, rows: list[dict], columns: list[str]) -> None:
    """Write rows (dicts) with the given columns; missing values as empty cells."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(columns)
    for r in rows:
        w.writerow(["" if r.get(c) is None else r.get(c) for c in columns])
    _write_text(path, buf.getvalue())


def _write_text(path: str | Path, text: str) -> None:
    write_text_atomic(path, text, option="--out")


def markdown_table(rows: list[dict], columns: list[tuple[str, str]]) -> str:
    """A Markdown table: columns = [(key, header)]; numbers right-aligned."""
    head = "| " + " | ".join(h for _, h in columns) + " |"
    align = "|" + "|".join("---" if k in ("entry", "problem") else "---:" for k, _ in columns) + "|"
    body = ["| " + " | ".join(fmt(r.get(k)) for k, _ in columns) + " |" for r in rows]
    return "\n".join([head, align, *body]) + "\n"


def write_markdown(path: str | Path, text: str) -> None:
    _write_text(path, text)


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    plt.rcParams.update({"svg.fonttype": "none", "svg.hashsalt": "nbst", "path.simplify": True, "font.size": 9})
    return plt


def _kind(entry: str) -> str:
    """The entry's family: "baseline", "nbst", "nbst-ablated" (nbst-noplan and any other
    nbst-* ablation) or "variant" (the paper's A-H)."""
    if entry in solver_entries():
        return "baseline"
    if entry == "nbst":
        return "nbst"
    if entry.startswith("nbst-"):
        return "nbst-ablated"
    return "variant"


#: Within a family, the k-th entry's colour is the family's mixed towards black by
#: MEMBER_SHADES[k] and drawn in MEMBER_STYLES[k]: told apart by lightness and by dashes.
MEMBER_SHADES = (0.0, 0.45, 0.25, 0.62)
MEMBER_STYLES = ("-", "--", "-.", ":")


def entry_style(entry: str, entries: list[str]) -> tuple[str, str]:
    """(colour, line style) of an entry in the curves figure: its family's colour (as the
    ablation's bars: variants blue, nbst green, baselines orange), shaded and dashed by its
    rank among the entries of its family in ``entries``."""
    from matplotlib.colors import to_hex, to_rgb

    kind = _kind(entry)
    family = [e for e in entries if _kind(e) == kind]
    k = family.index(entry) if entry in family else 0
    base = to_rgb(COLORS["nbst"] if kind == "nbst-ablated" else COLORS[kind])
    if kind == "nbst-ablated":
        k += 1  # never the plain nbst green
    f = 1.0 - MEMBER_SHADES[k % len(MEMBER_SHADES)]
    r, g, b = (c * f for c in base)
    return to_hex((r, g, b)), MEMBER_STYLES[k % len(MEMBER_STYLES)]


def save_figure(fig, stem: str | Path) -> list[Path]:
    """Write ``stem.png`` and ``stem.svg``; returns the paths."""
    stem = Path(stem)
    stem.parent.mkdir(parents=True, exist_ok=True)
    out = []
    for ext in ("png", "svg"):
        p = stem.with_suffix(f".{ext}")
        with atomic_path(p, option="--out") as tmp:  # whole figure or the previous one (a full disk)
            fig.savefig(tmp, dpi=DPI, bbox_inches="tight", metadata={"Date": None} if ext == "svg" else None)
        out.append(p)
    _plt().close(fig)
    return out


def plot_curves(rows: list[dict], *, title: str):
    """Best-so-far cost against trials (both log), one step line per run; each entry in its
    family's colour (as the ablation's bars), shaded and dashed within a family (``entry_style``)."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=FIG_SIZE)
    entries = list(dict.fromkeys(r["entry"] for r in rows))
    for e in entries:
        color, ls = entry_style(e, entries)
        runs = list(dict.fromkeys(r["run"] for r in rows if r["entry"] == e))
        for j, run in enumerate(runs):
            pts = [(r["trial"], r["best_cost"]) for r in rows if r["entry"] == e and r["run"] == run]
            xs, ys = zip(*pts)
            ax.step(xs, [max(y, CURVE_FLOOR) for y in ys], where="post", color=color, ls=ls, lw=1.0, alpha=0.85,
                    label=f"{e} ({len(runs)} runs)" if j == 0 else None)
    ax.set_yscale("log")
    ax.set_xscale("log")
    ax.set_xlabel("trials (simulations), log scale")
    ax.set_ylabel(f"best L2 cost so far (below {CURVE_FLOOR:g} drawn at {CURVE_FLOOR:g})")
    ax.set_title(title)
    ax.grid(True, which="major", alpha=0.3)
    ax.legend(loc="lower left", frameon=True, framealpha=0.85)
    ax.set_xlim(left=1)
    return fig


def plot_ablation(rows: list[dict], *, title: str):
    """Bars: mean final cost per entry, whiskers from the best to the worst run (log scale)."""
    import numpy as np

    plt = _plt()
    fig, ax = plt.subplots(figsize=FIG_SIZE)
    x = np.arange(len(rows))
    mean = np.array([r["mean"] for r in rows])
    lo = np.array([r["best"] for r in rows])
    hi = np.array([r["worst"] for r in rows])
    floor = CURVE_FLOOR
    mean_d, lo_d, hi_d = (np.maximum(a, floor) for a in (mean, lo, hi))
    kinds = [_kind(r["entry"]) for r in rows]
    bars = ax.bar(x, mean_d, color=[COLORS[k] for k in kinds], width=0.7, edgecolor="white", linewidth=0.0)
    for b, k in zip(bars, kinds):
        if k in HATCH:
            b.set_hatch(HATCH[k])
            b.set_edgecolor(COLORS["nbst"])
    ax.errorbar(x, mean_d, yerr=[mean_d - lo_d, hi_d - mean_d], fmt="none", ecolor="black", capsize=3, lw=0.9)
    ax.set_yscale("log")
    names = [r["entry"] for r in rows]
    if max(len(n) for n in names) * len(names) > 60:  # long names side by side would overlap: two rows
        ax.set_xticks(x[::2], names[::2])
        ax.set_xticks(x[1::2], names[1::2], minor=True)
        ax.tick_params(axis="x", which="minor", length=16, pad=3)  # the second row below the first
    else:
        ax.set_xticks(x, names)
    from matplotlib.patches import Patch
    seen = list(dict.fromkeys(kinds))
    words = dict(FAMILY_WORDS)
    ablated = [n for n, k in zip(names, kinds) if k == "nbst-ablated"]
    if ablated == ["nbst-noplan"]:
        words["nbst-ablated"] = "nbst without its planner"
    handles = [Patch(facecolor=COLORS[k], edgecolor=COLORS["nbst"] if k in HATCH else COLORS[k], hatch=HATCH.get(k),
                     label=words[k]) for k in ("variant", "nbst", "nbst-ablated", "baseline") if k in seen]
    ax.legend(handles=handles, loc="upper left", fontsize=7, frameon=True, framealpha=0.9, ncol=len(handles))
    ax.set_ylabel("final L2 cost (mean; whiskers best..worst)")
    ax.set_title(title)
    ax.grid(True, axis="y", which="major", alpha=0.3)
    for xi, r in zip(x, rows):
        ax.annotate(f"{r['full_order']}/{r['runs']}", (xi, hi_d[xi]), textcoords="offset points", xytext=(0, 3),
                    ha="center", fontsize=7)
    ax.set_ylim(top=float(hi_d.max()) * 60)  # room above the whiskers for the counts and the legend
    ax.set_xlabel(f"n/m above a bar: runs ending with every disk within R; costs below {floor:g} drawn at {floor:g}",
                  fontsize=7)
    return fig
