"""``report.html``: a self-contained page (inline base64 PNG figures) for a :class:`Validation`.

Compute only: functions return bytes / text; the CLI writes the files.
"""
from __future__ import annotations

import base64
import html
import io
import json

import numpy as np

#: Figure resolution (dots per inch); figures are ~7 in wide.
DPI = 110


def _png(fig) -> str:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=DPI, bbox_inches="tight")
    import matplotlib.pyplot as plt
    plt.close(fig)
    return base64.b64encode(buf.getvalue()).decode("ascii")


def _colors(n):
    import matplotlib
    cmap = matplotlib.colormaps["tab10" if n <= 10 else "tab20"]
    return [cmap(i % cmap.N) for i in range(n)]


def figure_overlay(val) -> str:
    """Trajectories: exact (solid) and MuJoCo (dashed), starts, targets with radius R."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Circle, Rectangle

    p = val.problem
    ex, mj = val.exact, val.mujoco
    ts = np.linspace(0.0, p.t_final, 1500)
    ts = np.union1d(ts, ex.events["time"])
    xe = ex.at(ts)
    xm = mj.at(ts)
    fig, ax = plt.subplots(figsize=(6.5, 6.5 * p.height / p.width))
    ax.add_patch(Rectangle((0, 0), p.width, p.height, fill=False, lw=1.5, color="0.3"))
    cols = _colors(p.n)
    for i in range(p.n):
        c = cols[i]
        ax.plot(xe[:, i, 0], xe[:, i, 1], "-", color=c, lw=1.2, alpha=0.9)
        ax.plot(xm[:, i, 0], xm[:, i, 1], "--", color="k", lw=0.7, alpha=0.6)
        ax.add_patch(Circle(p.target[i], p.target_radius, fill=False, ls=":", color=c, lw=0.8))
        ax.add_patch(Circle(p.start[i], p.radius[i], color=c, alpha=0.35))
        ax.add_patch(Circle(ex.final_positions[i], p.radius[i], fill=False, color=c, lw=1.2))
        ax.annotate(str(i), p.start[i], ha="center", va="center", fontsize=7)
    ax.plot([], [], "-", color="C0", label="exact (nbst)")
    ax.plot([], [], "--", color="k", label="MuJoCo")
    ax.set_xlim(-0.02 * p.width, 1.02 * p.width)
    ax.set_ylim(-0.02 * p.height, 1.02 * p.height)
    ax.set_aspect("equal")
    ax.legend(loc="upper right", fontsize=8)
    ax.set_title("paths: filled = start, ring = exact end, dotted = target radius R", fontsize=9)
    return _png(fig)


def figure_error(val) -> str:
    """Per-disk distance between the two motions over time (log scale), with the tolerance."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    p = val.problem
    fig, ax = plt.subplots(figsize=(7.5, 3.4))
    cols = _colors(p.n)
    floor = 1e-9
    for i in range(p.n):
        ax.semilogy(val.error_curve_t, np.maximum(val.error_curve[:, i], floor), color=cols[i], lw=1, label=str(i))
    ax.axhline(val.tol, color="r", ls="--", lw=1, label=f"tol {val.tol:g}")
    if val.diverge:
        ax.axvline(val.diverge["time"], color="r", lw=0.8)
    for t in val.exact.events["time"]:
        ax.axvline(t, color="0.85", lw=0.5, zorder=0)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("|MuJoCo - exact| (units)")
    ax.set_xlim(0, p.t_final)
    ax.legend(fontsize=6, ncol=min(p.n + 1, 8), loc="upper left")
    return _png(fig)


def figure_timeline(val) -> str:
    """Events on a time axis: exact above, MuJoCo below, matched pairs joined."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ex, mj = val.exact.events, val.mujoco.events
    fig, ax = plt.subplots(figsize=(7.5, 2.4))
    me = {a for a, _ in val.matches}
    mm = {b for _, b in val.matches}
    for a, b in val.matches:
        ax.plot([ex["time"][a], mj["time"][b]], [1, 0], color="0.6", lw=0.6)
    for evs, y, matched in ((ex, 1, me), (mj, 0, mm)):
        for k, e in enumerate(evs):
            m = "o" if e["kind"] == 0 else "s"
            c = "C0" if e["kind"] == 0 else "C2"
            if k not in matched:
                c = "r"
            ax.plot(e["time"], y, m, color=c, ms=5, mfc=c if k in matched else "none")
    ax.plot([], [], "o", color="C0", label="disk-disk")
    ax.plot([], [], "s", color="C2", label="wall")
    ax.plot([], [], "o", color="r", mfc="none", label="unmatched")
    ax.set_yticks([0, 1], ["MuJoCo", "exact"])
    ax.set_ylim(-0.5, 1.5)
    ax.set_xlim(0, val.problem.t_final)
    ax.set_xlabel("time (s)")
    ax.legend(fontsize=7, ncol=3, loc="upper center", bbox_to_anchor=(0.5, 1.35))
    return _png(fig)


_CSS = """body{font-family:system-ui,sans-serif;max-width:60em;margin:1.5em auto;padding:0 1em;color:#222}
h1{font-size:1.4em}h2{font-size:1.1em;margin-top:1.5em}table{border-collapse:collapse;font-size:.85em}
td,th{border:1px solid #ccc;padding:.2em .5em;text-align:right}th{background:#f3f3f3}
.ok{color:#176317}.bad{color:#b00}pre{background:#f6f6f6;padding:.6em;font-size:.85em;overflow-x:auto}
img{max-width:100%}.small{font-size:.85em;color:#555}"""


def report_html(val) -> str:
    """The whole page as text (every figure embedded)."""
    d = val.to_dict()
    esc = html.escape
    p = val.problem
    ev = d["events"]
    same = d["signatures_agree"]
    rows = []
    for i in range(p.n):
        e = val.exact.final_positions[i]
        m = val.mujoco.final_positions[i]
        rows.append(f"<tr><td>{i}</td><td>{e[0]:.3f}, {e[1]:.3f}</td><td>{m[0]:.3f}, {m[1]:.3f}</td>"
                    f"<td>{val.final_error[i]:.4g}</td><td>{d['exact']['signature'][i]}</td>"
                    f"<td>{d['mujoco_result']['signature'][i]}</td></tr>")

    def ev_rows():
        out = []
        ex, mj = val.exact.events, val.mujoco.events
        for a, b in val.matches:
            out.append((float(ex["time"][a]), esc(d["events"]["exact"][a]["text"]),
                        f"{(mj['time'][b] - ex['time'][a]) * 1e3:+.3f} ms"))
        me = {a for a, _ in val.matches}
        mm = {b for _, b in val.matches}
        out += [(float(ex["time"][k]), esc(d["events"]["exact"][k]["text"]), "<b class=bad>exact only</b>")
                for k in range(len(ex)) if k not in me]
        out += [(float(mj["time"][k]), esc(d["events"]["mujoco"][k]["text"]), "<b class=bad>MuJoCo only</b>")
                for k in range(len(mj)) if k not in mm]
        out.sort(key=lambda r: r[0])
        return "".join(f"<tr><td style='text-align:left'>{t}</td><td>{o}</td></tr>" for _, t, o in out)

    div = d["divergence"]
    div_html = (f"<p>Disk <b>{div['disk']}</b> first parts from its exact path by more than {val.tol:g} units at "
                f"<b>t = {div['time']:.4f} s</b>. Cause: {esc(div['cause'])}. Chaos makes late divergence normal: "
                f"a small error at one collision grows at every later one.</p>" if div else
                f"<p class=ok>No divergence: every disk stays within {val.tol:g} units of its exact path "
                f"up to t_final.</p>")
    json_text = esc(json.dumps({k: v for k, v in d.items() if k not in ("events", "velocities")}, indent=1))
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>nbst validate: {esc(p.name)}</title>
<style>{_CSS}</style></head><body>
<h1>nbst validate: {esc(p.name)}</h1>
<p class=small>{esc(p.description)}</p>
<p>{p.n} disks, t_final = {p.t_final:g} s. MuJoCo {esc(d['mujoco']['version'])}, timestep
{val.timestep * 1e3:g} ms ({d['mujoco']['steps']} steps), 1 unit = {val.unit:g} m.</p>
<h2>Verdict</h2>
<p class="{'ok' if same else 'bad'}"><b>Signature {'the same' if same else 'DIFFERENT'}</b>:
exact {d['exact']['signature']} (order {d['exact']['order']}, cost {d['exact']['cost']:.6g}),
MuJoCo {d['mujoco_result']['signature']} (order {d['mujoco_result']['order']}, cost {d['mujoco_result']['cost']:.6g}).</p>
<p>Largest final position error {d['final_error']['max']:.4g} units. Events: {ev['matched']} matched in order,
{ev['exact_only']} exact only, {ev['mujoco_only']} MuJoCo only. Kinetic energy drift
{d['energy']['drift_max_contact_free']:.3g} (largest, over contact-free steps).</p>
{div_html}
<h2>Trajectories</h2><img alt="trajectory overlay" src="data:image/png;base64,{figure_overlay(val)}">
<h2>Per-disk error over time</h2><img alt="error over time" src="data:image/png;base64,{figure_error(val)}">
<p class=small>MuJoCo resolves each impact one step late (an exact reflection delayed by the timestep), so each
impact adds about |&Delta;v|&middot;h; oblique collisions also err in direction by ~0.1&deg; at 0.25 ms.</p>
<h2>Event timeline</h2><img alt="event timeline" src="data:image/png;base64,{figure_timeline(val)}">
<h2>Final positions</h2>
<table><tr><th>disk</th><th>exact</th><th>MuJoCo</th><th>error</th><th>exact sig</th><th>MuJoCo sig</th></tr>
{''.join(rows)}</table>
<h2>Events (matched in order; offset = MuJoCo time &minus; exact time)</h2>
<table><tr><th>event (exact time)</th><th>offset</th></tr>{ev_rows()}</table>
<h2>Summary data</h2><pre>{json_text}</pre>
</body></html>
"""
