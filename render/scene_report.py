"""The scene validation report: ``index.html`` and its pictures for a
:class:`~nbst.scene.validate.SceneValidation` (``nbst scene validate --out-dir D``).

The page tables the solution's fates under each setting (a table per group: the integrators,
the solvers, the cones, the timestep ladder; the scene's own setting first), each fate met or not
with its graded cost, and the noise row's probability with its 95 % Wilson interval. Its pictures,
one PNG per group, draw each fated body's path seen from above under each setting of the group
(a panel per setting), over the fates' regions (``rest_in`` solid, ``at`` dashed, ``through``
dotted); ``noise.png`` marks where each body ends in every noisy rollout (met or not).

Compute only: :func:`scene_report_files` returns each file's bytes; the CLI writes them.
"""
from __future__ import annotations

import html
import io
from typing import Any

import numpy as np

from nbst.outputs import dumps_strict
from nbst.scene.validate import GROUPS, SceneValidation, SettingRow

__all__ = ["REPORT_FILES", "scene_report_files", "scene_report_html"]

#: The files the report writes in its folder: the page, the JSON of its table, the pictures.
REPORT_FILES = ("index.html", "report.json", *(f"paths-{g}.png" for g in GROUPS), "noise.png")

_CSS = """body{font-family:system-ui,sans-serif;max-width:64em;margin:1.5em auto;padding:0 1em;color:#222}
h1{font-size:1.4em}h2{font-size:1.1em;margin-top:1.5em}table{border-collapse:collapse;font-size:.85em}
td,th{border:1px solid #ccc;padding:.2em .5em;text-align:right}th{background:#f3f3f3}td.l,th.l{text-align:left}
.ok{color:#176317}.bad{color:#b00}img{max-width:100%}.small{font-size:.85em;color:#555}"""

_TITLES = {"integrator": "Integrators", "solver": "Constraint solvers", "cone": "Friction cones",
           "timestep": "The timestep ladder"}
_COLOURS = ("#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2", "#17becf")


#: The fixed geoms' footprints from above: fill and edge.
_STATIC_FILL, _STATIC_EDGE = "#dcdcdc", "#9a9a9a"


def _fates_columns(val: SceneValidation) -> list[tuple[str, str]]:
    """(body, fate) of each fate, in the judgement's order."""
    return [(b.body, v.fate) for b in val.scene_row.rollout.judgement.bodies for v in b.fates]


def _verdict(met: bool, text: str = "") -> str:
    return f"<span class={'ok' if met else 'bad'}>{'met' if met else 'NOT met'}</span>{text}"


def _row_html(r: SettingRow, cols: list[tuple[str, str]]) -> str:
    got = {(b.body, v.fate): v for b in r.rollout.judgement.bodies for v in b.fates}
    cells = []
    for c in cols:
        v = got[c]
        cells.append(f"<td title='{html.escape(v.happened, quote=True)}'>{_verdict(v.met)}"
                     + ("" if v.met else f" {v.cost:.3g}") + "</td>")
    warn = html.escape(", ".join(r.rollout.warnings)) or "&ndash;"
    same = " <span class=small>(the scene's)</span>" if r.same_as_scene and r.group != "scene" else ""
    return (f"<tr><td class=l>{html.escape(r.setting)}{same}</td><td class=l>{r.integrator}, {r.solver}, {r.cone}"
            f"</td><td>{r.timestep * 1e3:g} ms</td><td>{r.nstep:,}</td><td>{_verdict(r.met)}</td>"
            f"<td><code>{''.join('1' if b else '0' for b in r.rollout.signature)}</code></td>"
            f"<td>{r.rollout.cost:.3g}</td><td>{warn}</td>{''.join(cells)}</tr>")


def _table_html(rows: list[SettingRow], cols: list[tuple[str, str]]) -> str:
    head = "".join(f"<th>{html.escape(b)}<br>{html.escape(f)}</th>" for b, f in cols)
    return ("<table><tr><th class=l>setting</th><th class=l>integrator, solver, cone</th><th>timestep</th>"
            f"<th>steps</th><th>all fates</th><th>signature</th><th>cost</th><th>MuJoCo warned</th>{head}</tr>"
            + "".join(_row_html(r, cols) for r in rows) + "</table>")


def scene_report_html(val: SceneValidation) -> str:
    """The report's page (its pictures are the PNG files of :data:`REPORT_FILES`, beside it).

    Args:
        val: the validation.

    Returns:
        the HTML text.
    """
    cols = _fates_columns(val)
    p = val.probability
    failed = [f"{r.group} {r.setting}" for r in val.rows if not r.met]
    verdict = ("<p class=ok><b>Every setting meets every fate.</b></p>" if val.all_met else
               f"<p class=bad><b>Not met under: {html.escape(', '.join(failed))}.</b></p>")
    sigma = ", ".join(f"{a:g}" for a in val.fates.noise())
    doc = val.doc
    parts = [f"<!doctype html><html><head><meta charset=utf-8><title>nbst scene validate: "
             f"{html.escape(str(doc.get('fates')))}</title><style>{_CSS}</style></head><body>",
             f"<h1>Physics cross-validation: {html.escape(str(doc.get('fates')))}</h1>",
             f"<p class=small>Solution {html.escape(val.solution)}; scene {html.escape(str(val.fates.scene))}; "
             f"{val.fates.duration:g} s at h = {float(doc['timestep']) * 1e3:g} ms; solution seed {doc.get('seed')}; "
             f"MuJoCo {html.escape(val.mujoco)}. The same controls (the same initial state) rolled out under each "
             "setting, one option of the scene's &lt;option&gt; changed at a time; each fate judged again (hover a "
             "cell for what happened; a fate not met shows its graded cost). A setting is met when every fate is "
             "met and MuJoCo did not warn.</p>",
             verdict,
             "<h2>The scene's own setting (the replay)</h2>", _table_html([val.scene_row], cols)]
    for g in GROUPS:
        parts += [f"<h2>{_TITLES[g]}</h2>", _table_html(val.group(g), cols),
                  f"<p><img src=\"paths-{g}.png\" alt=\"each fated body's path from above under each {g} setting\"></p>"]
    parts += ["<h2>Noise</h2>",
              f"<p>P(every fate met) = <b>{p.p:.3g}</b> (95 % Wilson interval {p.lo:.3g}&ndash;{p.hi:.3g}; {p.k} of "
              f"{p.n} noisy rollouts at the scene's setting; sigma per control [{sigma}]; draws of seed "
              f"{val.noise_seed}, those of <code>nbst scene solve --samples</code>).</p>",
              "<p><img src=\"noise.png\" alt=\"where each fated body ends in each noisy rollout\"></p>",
              "<p class=small>The same table is in report.json.</p></body></html>"]
    return "\n".join(parts)


def _statics(ax: Any, val: SceneValidation) -> None:
    """The geoms fixed to the world, from above, in light grey under the paths."""
    from matplotlib.patches import Polygon

    for poly in val.statics:
        if len(poly) >= 3:
            ax.add_patch(Polygon(poly, closed=True, fc=_STATIC_FILL, ec=_STATIC_EDGE, lw=0.6, zorder=0))


def _kinds(val: SceneValidation) -> list[Any]:
    """The legend's entries for what the plots draw besides the paths: the region kinds the fates have,
    the fixed geoms when there are some."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    fs = val.fates.fates
    out: list[Any] = []
    for ls, name, has in (("-", "rest_in", any(f.rest_in is not None for f in fs)), ("--", "at", any(f.at for f in fs)),
                          (":", "through", any(f.through for f in fs))):
        if has:
            out.append(Line2D([], [], color="grey", ls=ls, label=name))
    if val.statics:
        out.append(Patch(fc=_STATIC_FILL, ec=_STATIC_EDGE, lw=0.6, label="fixed geoms"))
    return out


def _regions(ax: Any, val: SceneValidation) -> None:
    from matplotlib.patches import Circle, Rectangle

    _statics(ax, val)

    def draw(r: Any, ls: str, colour: str) -> None:
        if r.center is not None:
            ax.add_patch(Circle(r.center[:2], r.radius, fill=False, ls=ls, ec=colour, lw=1.0))
        else:
            ax.add_patch(Rectangle(r.lo[:2], r.hi[0] - r.lo[0], r.hi[1] - r.lo[1], fill=False, ls=ls, ec=colour,
                                   lw=1.0))

    for i, f in enumerate(val.fates.fates):
        c = _COLOURS[i % len(_COLOURS)]
        if f.rest_in is not None:
            draw(f.rest_in, "-", c)
        for _, r in f.at:
            draw(r, "--", c)
        for r in f.through:
            draw(r, ":", c)


def _png(fig: Any) -> bytes:
    import warnings

    buf = io.BytesIO()
    with warnings.catch_warnings():  # a name in a script DejaVu lacks (球) draws as a box; not a warning on stderr
        warnings.filterwarnings("ignore", message="Glyph .* missing from font", category=UserWarning)
        fig.savefig(buf, format="png", dpi=110)
    return buf.getvalue()


def _limits(val: SceneValidation, points: list[np.ndarray]) -> tuple[tuple[float, float], tuple[float, float]]:
    xy = [p.reshape(-1, 3)[:, :2] for p in points] + [np.asarray(a, float) for a in val.aims]  # a wall hit
    for f in val.fates.fates:
        for r in (f.rest_in, *(r for _, r in f.at), *f.through):
            if r is None:
                continue
            if r.center is not None:
                c = np.array(r.center[:2])
                xy.append(np.array([c - r.radius, c + r.radius]))
            else:
                assert r.lo is not None and r.hi is not None  # a box
                xy.append(np.array([r.lo[:2], r.hi[:2]]))
    a = np.concatenate(xy)
    lo, hi = a.min(axis=0), a.max(axis=0)
    pad = 0.08 * max(float((hi - lo).max()), 0.05)
    return (float(lo[0] - pad), float(hi[0] + pad)), (float(lo[1] - pad), float(hi[1] + pad))


def _group_png(val: SceneValidation, group: str) -> bytes:
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D

    rows = val.group(group)
    xlim, ylim = _limits(val, [p for r in rows for p in r.paths.values()])
    tall = min(2.0, max(0.4, (ylim[1] - ylim[0]) / (xlim[1] - xlim[0])))
    fig = Figure(figsize=(3.4 * len(rows), 3.4 * tall + 1.4), layout="constrained")
    axes = fig.subplots(1, len(rows), squeeze=False)[0]
    for ax, r in zip(axes, rows):
        _regions(ax, val)
        for i, f in enumerate(val.fates.fates):
            p = r.paths[f.body]
            c = _COLOURS[i % len(_COLOURS)]
            ax.plot(p[:, 0], p[:, 1], color=c, lw=1.2)
            ax.plot(p[0, 0], p[0, 1], "o", color=c, ms=4)
            ax.plot(p[-1, 0], p[-1, 1], "x", color=c, ms=6, mew=1.6)
        ax.set_xlim(*xlim)
        ax.set_ylim(*ylim)
        ax.set_aspect("equal", adjustable="box")
        ax.set_title(f"{r.setting}: {'met' if r.met else 'NOT met'}", fontsize=9,
                     color="#176317" if r.met else "#b00000")
        ax.tick_params(labelsize=7)
        ax.set_xlabel("x (m)", fontsize=8)
    axes[0].set_ylabel("y (m)", fontsize=8)
    handles = [Line2D([], [], color=_COLOURS[i % len(_COLOURS)], lw=1.2, label=f.body)
               for i, f in enumerate(val.fates.fates)]
    handles += [*_kinds(val),
                Line2D([], [], color="grey", marker="o", ls="", label="start"),
                Line2D([], [], color="grey", marker="x", ls="", label="end")]
    fig.legend(handles=handles, loc="outside lower center", ncol=min(len(handles), 8), fontsize=7, frameon=False)
    fig.suptitle(f"{_TITLES[group]}: each fated body's path from above", fontsize=10)
    return _png(fig)


def _noise_png(val: SceneValidation) -> bytes:
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D

    fig = Figure(figsize=(5.2, 4.6), layout="constrained")
    ax = fig.subplots()
    _regions(ax, val)
    ends = val.noisy_ends
    xlim, ylim = _limits(val, [ends, *val.scene_row.paths.values()])
    for i, f in enumerate(val.fates.fates):
        c = _COLOURS[i % len(_COLOURS)]
        ok = val.noisy_met
        ax.plot(ends[ok, i, 0], ends[ok, i, 1], "o", color=c, ms=3, alpha=0.7)
        ax.plot(ends[~ok, i, 0], ends[~ok, i, 1], "x", color=c, ms=4, alpha=0.7)
    ax.set_xlim(*xlim)
    ax.set_ylim(*ylim)
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel("x (m)", fontsize=8)
    ax.set_ylabel("y (m)", fontsize=8)
    ax.tick_params(labelsize=7)
    p = val.probability
    ax.set_title(f"where each body ends under noise: P = {p.p:.3g} ({p.lo:.3g}-{p.hi:.3g}), {p.k} of {p.n}",
                 fontsize=9)
    handles = [Line2D([], [], color=_COLOURS[i % len(_COLOURS)], marker="o", ls="", label=f.body)
               for i, f in enumerate(val.fates.fates)]
    handles += [Line2D([], [], color="grey", marker="o", ls="", label="every fate met"),
                Line2D([], [], color="grey", marker="x", ls="", label="not met")]
    fig.legend(handles=handles, loc="outside lower center", ncol=min(len(handles), 6), fontsize=7, frameon=False)
    return _png(fig)


def scene_report_files(val: SceneValidation) -> dict[str, bytes]:
    """Every file of the report, by name (:data:`REPORT_FILES`), as bytes.

    Args:
        val: the validation.

    Returns:
        ``{name: bytes}``: ``index.html``, ``report.json`` (:meth:`SceneValidation.to_dict`), one
        ``paths-GROUP.png`` per group and ``noise.png``.
    """
    out = {"index.html": scene_report_html(val).encode("utf-8"),
           "report.json": (dumps_strict(val.to_dict(), indent=2) + "\n").encode("utf-8")}
    for g in GROUPS:
        out[f"paths-{g}.png"] = _group_png(val, g)
    out["noise.png"] = _noise_png(val)
    assert set(out) == set(REPORT_FILES)
    return out
