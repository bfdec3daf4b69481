"""``report.html``: a self-contained page (inline base64 PNG figures) for a :class:`Validation`.

The figures speak nbst's visual language (:mod:`nbst.palette`; the drawing helpers
are ``nbst.render.figures``'s): class colours, disk numbers at the starts and beside
the targets, and legends outside the axes.

Above :data:`MANY_DISKS` disks (or :data:`MANY_EVENTS` events) the page summarises: statistics
and the worst disks instead of a row per disk, percentile bands instead of a curve per disk,
events per time bin instead of a mark per event.

Compute only: functions return bytes / text; the CLI writes the files.

The figures are :mod:`nbst.render.report_figures`'s.
"""
from __future__ import annotations

import html

import numpy as np

from nbst import palette
from nbst.models.validate import describe
from nbst.solution import dumps_strict

from nbst.render.report_figures import (EVENT_ROWS, MANY_DISKS, WORST_ROWS, figure_convergence,
                                        figure_error, figure_overlay, figure_timeline, worst_disks)

__all__ = ["JSON_LIST_MAX", "report_html"]

#: Lists longer than this in the embedded JSON are summarised (report.json keeps them whole).
JSON_LIST_MAX = 64


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
    """The HTML cross-validation report of ``nbst validate --out-dir``, every figure embedded.

    Args:
        val: the validation (:func:`nbst.models.validate.validate`'s result).

    Returns:
        The whole page as text.
    """
    d = val.to_dict()
    esc = html.escape
    p = val.problem
    ev = d["events"]
    same = d["signatures_agree"]
    many = p.n > MANY_DISKS
    rows = []
    for i in (worst_disks(val, WORST_ROWS) if many else range(p.n)):
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
