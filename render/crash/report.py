"""A reconstructionist's report of a crash file (``nbst crash report CRASH.json -o report.html``).

One self-contained HTML page (figures inline as base64 PNG), in a reconstructionist's units
(km/h, metres, degrees, seconds, clock directions):

* **per vehicle**: the speed at its first impact, its Delta-v (the magnitude of its velocity
  change over that impact's contact episode, and the contact impulse's share |J| / m), the PDOF
  (the direction the force comes from, as a clock direction and in degrees clockwise from
  straight ahead), EES and residual crush when the file records crush (else "not recorded"), and
  the 90 % intervals of a reconstruction when the file carries one (else the point value, said
  to have no interval); every number from :func:`nbst.models.crash.impact.crash_impacts`;
* **every impact** (each contact episode of a vehicle pair): its time and length, each vehicle's
  speed before and after, Delta-v in its own frame, PDOF, and how far the two m Delta-v balance;
* **the speed-time diagram** (km/h against s per vehicle, the impacts marked) and **the sequence
  diagram** (a lane per vehicle: driving, perception-reaction, braking, impact, post-impact, rest;
  an arrow from the striking to the struck vehicle at each impact);
* **the scene diagram**: overhead, to scale in metres: the road, curbs and barriers, each
  vehicle's path, its outline at the start, at its first impact and at rest, the impact points,
  the skid marks and scrapes the replay left (:mod:`.motion`), and the evidence's regions (rest
  regions, impact positions, headings at rest);
* **evidence against fit**: every fate of the script (a reconstruction's evidence): asked, got,
  tolerance, met (the replay's own judgement, :func:`nbst.models.crash.outcome.judge`).

The perception-reaction phase is not in the file: it is drawn as :data:`PERCEPTION_S` s before
a driver's reaction stop (``brake_at``) or else its first lasting braking, an assumed median, and
labelled as such.

Compute only: :func:`crash_report` returns the figures' data and :func:`report_html` the page;
the CLI writes it.

Length: one page of three figures and three tables, each a short function over the same
:class:`CrashReport`; apart, they would only pass it around.
"""
from __future__ import annotations

import base64
import html
import io
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from nbst.models.crash import impact as impact_mod
from nbst.models.crash import outcome as out_mod
from nbst.models.crash.script import Script
from nbst.models.crash.vehicle import G

from nbst.render.crash import motion as motion_mod

__all__ = ["BRAKE_ON", "DPI", "MAX_IMPACT_ROWS", "MINOR_DV_KMH", "MIN_PHASE_S", "PERCEIVED_S", "PERCEPTION_S", "PHASES",
           "SCENE_ASPECT", "STRIKE_S", "ZOOM", "CrashReport", "crash_report", "evidence_rows", "phases", "report_html",
           "striker", "strikes"]

#: Figure resolution (dots per inch); figures are ~8 in wide.
DPI = 100
#: The perception-reaction time drawn before a reaction stop (s): the median brake reaction time
#: to an unexpected signal, 0.9 s (Johansson and Rumar, *Drivers' brake reaction times*, Human
#: Factors 13, 1971). Assumed: the crash file holds when the driver braked, not when the hazard
#: appeared.
PERCEPTION_S = 0.9
#: The impact table lists at most this many contact episodes (the rest are counted).
MAX_IMPACT_ROWS = 40
#: Contact episodes in which neither vehicle's Delta-v reaches this (km/h) are grazes: counted,
#: not listed, not drawn.
MINOR_DV_KMH = 1.0
#: The scene diagram adds a panel around the impacts and rest positions when the whole crash
#: spans more than this many times that region.
ZOOM = 2.0
#: The scene diagram's height over its width stays in this range (the shorter side grows).
SCENE_ASPECT = (0.4, 1.3)
#: The sequence diagram's phases, in drawing order, with their colours.
PHASES = (("driving", "#d9d9d9"), ("perception-reaction (assumed)", "#fde68a"), ("braking", "#f59e0b"),
          ("impact", "#dc2626"), ("post-impact", "#60a5fa"), ("rest", "#16a34a"))

_CSS = """body{font-family:system-ui,sans-serif;max-width:72em;margin:1.5em auto;padding:0 1em;color:#222}
h1{font-size:1.4em}h2{font-size:1.1em;margin-top:1.5em}table{border-collapse:collapse;font-size:.85em}
td,th{border:1px solid #ccc;padding:.2em .5em;text-align:right}th{background:#f3f3f3}td.l,th.l{text-align:left}
.ok{color:#176317}.bad{color:#b00}img{max-width:100%}.small{font-size:.85em;color:#555}"""


@dataclass(frozen=True)
class CrashReport:
    """What the page shows: the file, its replayed impacts and motion."""

    d: dict
    script: Script
    model: Any
    impacts: impact_mod.CrashImpacts
    motion: motion_mod.CrashMotion
    source: str

    @property
    def names(self) -> list:
        return self.script.names()

    def major(self) -> list:
        """The impacts at least one of whose vehicles changes speed by :data:`MINOR_DV_KMH` or more."""
        return [p for p in self.impacts.impacts if max(v.dv for v in p.vehicles) * impact_mod.KMH >= MINOR_DV_KMH]

    def opening(self) -> list:
        """The first major impact of each vehicle pair (the ones labelled in the figures)."""
        seen: set = set()
        out = []
        for p in self.major():
            if (p.a, p.b) not in seen:
                seen.add((p.a, p.b))
                out.append(p)
        return out

    @property
    def friction(self) -> float:
        """The road's friction in the scene the file ran (a reconstruction draws its own)."""
        return float(self.model.geom("ground").friction[0])

    def reach(self, p: impact_mod.PairImpact) -> float:
        """The most the road can unbalance the pair's m dv over the impact, mu g tau (m_a + m_b)
        (the friction cone; tau from the state before the first touch to after the last), as a
        share of the mean m |dv|: the imbalance stays under it."""
        tau = p.t_end - p.t + float(self.model.opt.timestep)
        ma, mb = self.impacts.mass[p.a], self.impacts.mass[p.b]
        mean = 0.5 * (ma * p.of(p.a).dv + mb * p.of(p.b).dv)
        return float(self.friction * G * tau * (ma + mb) / mean) if mean > 0 else math.inf

    def first(self, i: int):
        """Vehicle ``i``'s first major impact: (PairImpact, VehicleImpact) or None."""
        for p in self.major():
            if i in (p.a, p.b):
                return p, p.of(i)
        return None


def crash_report(d: dict, script, model, *, source: str = "") -> CrashReport:
    """Replay a checked crash file (``crashfile.load``'s values) for the report.

    Args:
        d, script, model: the crash file, its Script and MjModel.
        source: the file's name, for the page.

    Returns:
        The :class:`CrashReport`.
    """
    motion = motion_mod.record(d, script, model)
    return CrashReport(d=d, script=script, model=model, impacts=motion.reading, motion=motion, source=source)


# --------------------------------------------------------------------------- helpers

def _colour(rep: CrashReport, i: int):
    c = rep.d["vehicles"][i].get("colour") or [0.3, 0.3, 0.3, 1.0]
    return tuple(float(x) for x in c[:3])


def _png(fig) -> str:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=DPI)
    return base64.b64encode(buf.getvalue()).decode("ascii")


def _figure(size):
    from matplotlib.figure import Figure

    return Figure(figsize=size, layout="constrained")


def _deg(x: float) -> int:
    return int(round(x)) % 360


def striker(p: impact_mod.PairImpact) -> int | None:
    """The striking vehicle of an impact: the one whose force comes more nearly from straight ahead
    (its front took the blow), when the other's comes more from a side or the back; None when both
    are struck in the front within 45 deg (head-on) or neither is."""
    off = [min(v.pdof_deg, 360 - v.pdof_deg) if math.isfinite(v.pdof_deg) else 180.0 for v in p.vehicles]
    if off[0] <= 45 and off[1] <= 45:
        return None
    k = int(np.argmin(off))
    return p.vehicles[k].vehicle if off[k] <= 60 else None


def strikes(rep: CrashReport, i: int | None = None) -> list:
    """The curb and barrier strikes (:class:`nbst.render.crash.motion.Impact`, ``b`` None) of
    vehicle ``i`` (every vehicle's: None), in time order."""
    return [im for im in rep.motion.impacts if im.what != "vehicle" and (i is None or im.a == i)]


#: A brake command at or above this (0..1) is braking in the sequence diagram (the drivers' pacing
#: brakes lightly; a reaction stop, a panicking follower or a locked wheel brakes at 1).
BRAKE_ON = 0.5
#: Phases shorter than this (s) before the first impact are not drawn (a follower's brake pulses).
MIN_PHASE_S = 0.1
#: Without a reaction stop, the perception-reaction time is drawn before the first braking that
#: lasts this long (s) or runs into the impact.
PERCEIVED_S = 0.5
#: A curb or barrier strike is drawn this long (s) in the sequence diagram (its contact is not timed).
STRIKE_S = 0.05


def _brake(rep: CrashReport, i: int) -> np.ndarray:
    """Vehicle ``i``'s strongest brake command (0..1) at each recorded time (the file's controls)."""
    c = rep.d["controls"]
    idx = [k for k, a in enumerate(c["actuators"]) if a.startswith(f"v{i}_brake")]
    rows = np.asarray(c["rows"], float)
    if not idx or not len(rows):
        return np.zeros(len(rep.impacts.times))
    per = rows[:, idx].max(axis=1)
    dt = float(rep.model.opt.timestep)
    k = np.minimum((np.round(rep.impacts.times / dt).astype(int) - 1).clip(0) // int(c["period_steps"]), len(per) - 1)
    return per[k]


def _before(rep: CrashReport, i: int, end: float) -> list:
    """Vehicle ``i``'s phases from the start to ``end`` (its first impact, else its rest or the end):
    driving, braking (the brakes at :data:`BRAKE_ON` or more), at rest (below the outcome's rest
    speed), each held :data:`MIN_PHASE_S` at least, and the assumed perception-reaction time before
    the braking of the driver's reaction stop, or else its first braking of :data:`PERCEIVED_S` or
    more, or one that runs into the impact."""
    times = rep.impacts.times
    n = int(np.searchsorted(times, end))
    if n == 0:
        return []
    sp, br = rep.impacts.speed[:n, i], _brake(rep, i)[:n]
    lab = np.where(sp <= out_mod.REST_SPEED, 2, np.where(br >= BRAKE_ON, 1, 0))
    starts = np.concatenate([[0], np.nonzero(np.diff(lab))[0] + 1])
    runs = [[int(lab[k]), float(times[k]), float(times[starts[j + 1]]) if j + 1 < len(starts) else end]
            for j, k in enumerate(starts)]
    merged: list = []
    for r in runs:       # a run too short to draw belongs to the one before it (a follower's brake pulses)
        if merged and (r[2] - r[1] < MIN_PHASE_S or merged[-1][0] == r[0]):
            merged[-1][2] = r[2]
        else:
            merged.append(r)
    names = ("driving", "braking", "rest")
    out = [(names[r[0]], r[1], r[2]) for r in merged]
    cols = rep.d["intents"]["columns"]
    got = rep.d["intents"]["rows"][i][cols.index("brake_at")] if "brake_at" in cols else None
    stop = math.inf if got is None else float(got)          # the driver's reaction stop, if any
    for j, (name, t0, t1) in enumerate(out):
        # the reaction stop, else the first braking that lasts or runs into the impact: perceived before it
        if name == "braking" and (t0 - 0.05 <= stop < t1 if math.isfinite(stop) and stop < end
                                  else t1 - t0 >= PERCEIVED_S or t1 >= end):
            p0 = max(0.0, t0 - PERCEPTION_S)
            keep = [(nm, a, min(b, p0)) for nm, a, b in out[:j] if a < p0]
            return keep + [(PHASES[1][0], p0, t0)] + out[j:]
    return out


def phases(rep: CrashReport, i: int) -> list[tuple[str, float, float]]:
    """Vehicle ``i``'s phases [(name, start s, end s)] in time order (names of :data:`PHASES`): its
    vehicle impacts and its curb and barrier strikes are impacts, the first of them ends the driver's
    part (before it: driving, braking and at rest from the realised controls and speed, and the
    assumed perception-reaction time before the first braking), rest is the stretch below the
    outcome's rest speed that lasts to the end."""
    T = float(rep.motion.duration)
    events = sorted([(p.t, max(p.t_end, p.t + 0.01)) for p in rep.major() if i in (p.a, p.b)]
                    + [(im.t, im.t + STRIKE_S) for im in strikes(rep, i)])
    t_hit = events[0][0] if events else math.inf
    sp = rep.impacts.speed[:, i]
    moving = np.nonzero(sp > out_mod.REST_SPEED)[0]
    times = rep.impacts.times
    if not moving.size:
        t_rest = 0.0
    elif moving[-1] + 1 < len(times):
        t_rest = float(times[moving[-1] + 1])
    else:
        t_rest = math.inf                                     # still moving at the end
    pre_end = min(t_hit, t_rest, T)
    out = _before(rep, i, pre_end)
    for k, (t0, t1) in enumerate(events):
        out.append(("impact", t0, t1))
        nxt = events[k + 1][0] if k + 1 < len(events) else min(max(t_rest, t1), T)
        if nxt > t1:
            out.append(("post-impact", t1, nxt))
    if t_rest < T:
        out.append(("rest", max(t_rest, events[-1][1] if events else 0.0), T))
    return out


# --------------------------------------------------------------------------- the figures

def figure_speed(rep: CrashReport) -> str:
    """The speed-time diagram (base64 PNG)."""
    fig = _figure((8.0, 3.6))
    ax = fig.add_subplot(1, 1, 1)
    t = rep.impacts.times
    for i, nm in enumerate(rep.names):
        ax.plot(t, rep.impacts.speed[:, i] * impact_mod.KMH, color=_colour(rep, i), lw=1.6, label=nm)
    top = float(rep.impacts.speed.max()) * impact_mod.KMH
    opening = rep.opening()
    for p in rep.major():
        ax.axvline(p.t, color="0.4", lw=0.8, ls="--" if p in opening else ":")
        if p in opening:
            ax.text(p.t, top * 1.13, f" {rep.names[p.a]}-{rep.names[p.b]} {p.t:.2f} s", fontsize=7, ha="right",
                    va="top", color="0.25", rotation=90)
        for v in p.vehicles:
            ax.plot([p.t, p.t_end], [v.speed_before * impact_mod.KMH, v.speed_after * impact_mod.KMH], "o",
                    ms=3.5, color=_colour(rep, v.vehicle), mec="k", mew=0.5)
    for im in strikes(rep):
        ax.axvline(im.t, color=_colour(rep, im.a), lw=0.9, ls="-.")
        ax.text(im.t, top * 1.13, f" {rep.names[im.a]} {im.what} {im.t:.2f} s", fontsize=7, ha="right", va="top",
                color="0.25", rotation=90)
    ax.set_xlim(0, rep.motion.duration)
    ax.set_ylim(0, max(top * 1.15, 1.0))
    ax.set_title("vehicle impacts dashed (the first of each pair labelled; dots: the speeds before and after), "
                 "curb and barrier strikes dash-dotted", fontsize=8)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("speed of the centre of mass (km/h)")
    ax.grid(alpha=0.3)
    ax.legend(loc="upper right", fontsize=8, title="vehicle", title_fontsize=8)
    return _png(fig)


def figure_sequence(rep: CrashReport) -> str:
    """The sequence diagram (base64 PNG)."""
    from matplotlib.patches import Patch

    n = rep.script.n
    fig = _figure((8.0, 1.0 + 0.55 * n))
    ax = fig.add_subplot(1, 1, 1)
    colours = dict(PHASES)
    opening = rep.opening()
    lane = {i: n - 1 - i for i in range(n)}
    for i in range(n):
        for name, a, b in phases(rep, i):
            ax.broken_barh([(a, max(b - a, 1e-3))], (lane[i] - 0.3, 0.6), facecolors=colours[name],
                           edgecolors="0.3", lw=0.4)
    for p in rep.major():
        s = striker(p)
        src, dst = (p.a, p.b) if s is None or s == p.a else (p.b, p.a)
        y0, y1 = lane[src], lane[dst]
        style = "<|-|>" if s is None else "-|>"
        ax.annotate("", xy=(p.t, y1 + (0.3 if y1 < y0 else -0.3)), xytext=(p.t, y0 + (-0.3 if y1 < y0 else 0.3)),
                    arrowprops={"arrowstyle": style, "color": "k", "lw": 1.4, "mutation_scale": 12})
        if p in opening:
            what = "head-on" if s is None else f"{rep.names[src]} hits {rep.names[dst]}"
            ax.text(p.t + 0.005 * rep.motion.duration, (y0 + y1) / 2, f"{what} {p.t:.2f} s", fontsize=7,
                    va="center", bbox={"facecolor": "w", "edgecolor": "none", "alpha": 0.8, "pad": 1})
    ax.set_yticks([lane[i] for i in range(n)], [f"{nm}" for nm in rep.names])
    ax.set_xlim(0, rep.motion.duration)
    ax.set_ylim(-0.6, n - 0.4)
    ax.set_xlabel("time (s)")
    ax.legend(handles=[Patch(facecolor=c, edgecolor="0.3", label=nm) for nm, c in PHASES], fontsize=7,
              loc="upper center", bbox_to_anchor=(0.5, -0.35 if n < 3 else -0.25), ncol=3, frameon=False)
    return _png(fig)


def _outline(model, data, qpos, i: int) -> np.ndarray:
    """(4, 2) corners of vehicle ``i``'s lower body seen from above at state ``qpos``."""
    import mujoco

    data.qpos[:] = qpos
    mujoco.mj_kinematics(model, data)
    g = model.geom(f"v{i}_lower").id
    c, R, s = data.geom_xpos[g], data.geom_xmat[g].reshape(3, 3), model.geom_size[g]
    pts = [c + R @ np.array([sx * s[0], sy * s[1], 0.0]) for sx, sy in ((1, 1), (1, -1), (-1, -1), (-1, 1))]
    return np.array(pts)[:, :2]


def _extent(pts: list, margin: float) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi) of the points with a margin, the shorter side grown so that height / width stays
    within :data:`SCENE_ASPECT`."""
    P = np.vstack(pts)
    lo, hi = P.min(axis=0) - margin, P.max(axis=0) + margin
    span = hi - lo
    want = np.clip(span[1] / span[0], *SCENE_ASPECT)
    grow = np.array([max(0.0, span[1] / want - span[0]), max(0.0, span[0] * want - span[1])])
    return lo - grow / 2, hi + grow / 2


def _regions(rep: CrashReport) -> list:
    """Corner pairs of every rest region and impact position the script asks for."""
    out = []
    for f in (v["fate"] for v in rep.d["vehicles"]):
        for k in ("rest", "impact_at"):
            if k in f:
                r = f[k]["radius"]
                out.append(np.array([[f[k]["x"] - r, f[k]["y"] - r], [f[k]["x"] + r, f[k]["y"] + r]]))
    return out


def figure_scene(rep: CrashReport) -> str:
    """The scene diagram: overhead, to scale in metres (base64 PNG): the whole crash, and where the
    paths reach far beyond the impacts and the rest positions, those first, zoomed (:data:`ZOOM`)."""
    import mujoco
    from matplotlib.lines import Line2D
    from matplotlib.patches import Polygon

    m = rep.motion
    n = rep.script.n
    whole = _extent([m.pos[:, i, :2] for i in range(n)] + _regions(rep), 6.0)
    near = [m.pos[-1:, i, :2] for i in range(n)] + [np.array([p.pos[:2]]) for p in rep.major()] + _regions(rep) \
        + [np.array([im.pos[:2]]) for im in strikes(rep) if all(math.isfinite(x) for x in im.pos[:2])]
    for i in range(n):
        first = rep.first(i)
        if first is not None:
            near.append(m.pos[max(0, int(np.searchsorted(m.times, first[0].t)) - 1):][:1, i, :2])
    zoom = _extent(near, 6.0)
    views = [zoom, whole] if (whole[1] - whole[0]).max() > ZOOM * (zoom[1] - zoom[0]).max() else [whole]
    k = len(views)
    aspect = [(hi[1] - lo[1]) / (hi[0] - lo[0]) for lo, hi in views]     # height per width
    if k == 1 or min(aspect) < 0.8:                     # wide views: one above the other, 8 in wide
        fig = _figure((8.8, sum(7.2 * a for a in aspect) + 0.7 * k + 1.0))
        axes = fig.subplots(k, 1, gridspec_kw={"height_ratios": aspect}, squeeze=False)[:, 0]
    else:                                               # tall ones side by side, 5 in high
        fig = _figure((sum(5.0 / a for a in aspect) + 1.6, 6.4))
        axes = fig.subplots(1, k, gridspec_kw={"width_ratios": [1 / a for a in aspect]}, squeeze=False)[0]
    data = mujoco.MjData(rep.model)
    for ax, (lo, hi), title in zip(axes, views, ("around the impacts and the rest positions", "the whole crash")):
        _draw_scene(ax, rep, data)
        ax.set_xlim(lo[0], hi[0])
        ax.set_ylim(lo[1], hi[1])
        if len(views) > 1:
            ax.set_title(title, fontsize=9)
    handles = [Line2D([], [], color="0.3", lw=1.2, label="path of the centre of mass"),
               Line2D([], [], color="0.3", lw=1.0, ls=":", label="start"),
               Line2D([], [], color="0.3", lw=1.4, label="at its first impact"),
               Polygon([[0, 0]], facecolor="0.6", edgecolor="0.3", label="at the end (at rest, or still moving)"),
               Line2D([], [], marker="*", color="#dc2626", mec="k", ls="none", ms=10, label="impact point"),
               Line2D([], [], marker="D", color="w", mec="0.3", mew=1.4, ls="none", ms=6,
                      label="curb or barrier strike"),
               Line2D([], [], color="k", lw=1.2, label="skid mark"),
               Line2D([], [], color="0.3", lw=1.2, ls="--", label="rest region asked (wedge: heading)"),
               Line2D([], [], color="0.3", lw=1.0, ls=":", label="impact position asked")]
    if any(mk.kind == "scrape" for mk in m.marks):
        handles.append(Line2D([], [], color="#7a4a1e", lw=1.2, label="scrape"))
    fig.legend(handles=handles, fontsize=7, loc="outside lower center", ncol=3, frameon=False)
    return _png(fig)


def _draw_scene(ax, rep: CrashReport, data) -> None:
    """Draw the road, the marks, the vehicles and the evidence's regions on ``ax`` (metres)."""
    import mujoco
    from matplotlib.patches import Circle, Polygon, Wedge

    model, m = rep.model, rep.motion
    mujoco.mj_kinematics(model, data)
    ax.set_facecolor((0.86, 0.89, 0.83))
    for g in range(model.ngeom):
        name = model.geom(g).name
        if model.geom_bodyid[g] >= 0 and model.geom_type[g] == mujoco.mjtGeom.mjGEOM_BOX and \
                name.startswith(("road", "curb", "barrier")):
            c, R, s = data.geom_xpos[g], data.geom_xmat[g].reshape(3, 3), model.geom_size[g]
            poly = [(c + R @ np.array([sx * s[0], sy * s[1], 0.0]))[:2]
                    for sx, sy in ((1, 1), (1, -1), (-1, -1), (-1, 1))]
            col = {"road": "0.55", "curb": "0.8", "barrier": "#d08a2a"}[name.rstrip("0123456789")]
            ax.add_patch(Polygon(poly, closed=True, facecolor=col, edgecolor="none", zorder=1))
    for line in rep.script.road.centreline():
        ax.plot(line[:, 0], line[:, 1], color="w", lw=0.8, ls=(0, (6, 6)), zorder=2)
    for mk in m.marks:
        ax.plot(mk.xy[:, 0], mk.xy[:, 1], color="k" if mk.kind == "skid" else "#7a4a1e", lw=1.2, alpha=0.8,
                solid_capstyle="butt", zorder=3)
    qpos = m.qpos
    for i in range(rep.script.n):
        col = _colour(rep, i)
        ax.plot(m.pos[:, i, 0], m.pos[:, i, 1], color=col, lw=1.2, zorder=4)
        ax.add_patch(Polygon(_outline(model, data, qpos[0], i), closed=True, fill=False, edgecolor=col, lw=1.0,
                             ls=":", zorder=5))
        first = rep.first(i)
        if first is not None:
            kf = max(0, int(np.searchsorted(m.times, first[0].t)) - 1)
            ax.add_patch(Polygon(_outline(model, data, qpos[kf], i), closed=True, fill=False, edgecolor=col, lw=1.4,
                                 zorder=6))
        ax.add_patch(Polygon(_outline(model, data, qpos[-1], i), closed=True, facecolor=col + (0.55,), edgecolor=col,
                             lw=1.4, zorder=6))
        x, y = m.pos[-1, i, :2]
        ax.text(x, y, rep.names[i], fontsize=8, ha="center", va="center", weight="bold", zorder=9, clip_on=True)
        x0, y0 = m.pos[0, i, :2]
        ax.text(x0, y0, rep.names[i], fontsize=7, ha="center", va="center", color=col, zorder=9, clip_on=True)
        f = rep.d["vehicles"][i]["fate"]
        if "rest" in f:
            r = f["rest"]
            ax.add_patch(Circle((r["x"], r["y"]), r["radius"], fill=False, edgecolor=col, lw=1.2, ls="--", zorder=7))
            if "heading" in f:
                h, tol = f["heading"]["deg"], f["heading"]["tol"]
                ax.add_patch(Wedge((r["x"], r["y"]), r["radius"], h - tol, h + tol, facecolor=col + (0.15,),
                                   edgecolor=col, lw=0.6, zorder=7))
        if "impact_at" in f:
            r = f["impact_at"]
            ax.add_patch(Circle((r["x"], r["y"]), r["radius"], fill=False, edgecolor=col, lw=1.0, ls=":", zorder=7))
    for im in strikes(rep):
        if all(math.isfinite(x) for x in im.pos[:2]):
            ax.plot(im.pos[0], im.pos[1], marker="D", ms=6, color="w", mec=_colour(rep, im.a), mew=1.4, zorder=8)
            ax.text(im.pos[0] + 0.5, im.pos[1] - 0.5, f"{im.what} {im.t:.2f} s", fontsize=7, va="top", zorder=9,
                    clip_on=True)
    opening = rep.opening()
    for p in rep.major():
        ax.plot(p.pos[0], p.pos[1], marker="*", ms=12 if p in opening else 7, color="#dc2626", mec="k", mew=0.6,
                zorder=8)
        if p in opening:
            ax.text(p.pos[0] + 0.6, p.pos[1] + 0.6, f"{rep.names[p.a]}-{rep.names[p.b]} {p.t:.2f} s", fontsize=7,
                    zorder=9, clip_on=True)
    ax.set_aspect("equal")
    ax.set_xlabel("x, east (m)")
    ax.set_ylabel("y, north (m)")
    ax.grid(alpha=0.25, zorder=0)


# --------------------------------------------------------------------------- the tables

def _interval(rec: dict | None, i: int, key: str, fmt=".1f") -> str:
    """A reconstruction's interval of vehicle ``i``'s ``key``, in words."""
    if not rec:
        return "no interval (one crash: the point value)"
    vs = rec.get("vehicles") or []
    q = vs[i].get(key) if i < len(vs) and isinstance(vs[i], dict) else None
    if not isinstance(q, dict) or q.get("lo") is None or q.get("hi") is None:
        return "no interval in the reconstruction"
    level = rec.get("level", 0.9)
    txt = f"{format(q['lo'], fmt)}&ndash;{format(q['hi'], fmt)} ({100 * level:.0f} %)"
    if q.get("median") is not None:
        txt += f", median {format(q['median'], fmt)}"
    if q.get("identifiable") is False:
        txt += " <b class=bad>not identifiable</b>"
    return txt


def _ees(v: dict) -> str:
    cr = v.get("crush")
    if not isinstance(cr, dict) or cr.get("ees_kmh") is None:
        return "not recorded"
    zones = cr.get("zones") or {}
    res = ", ".join(f"{z} {100 * float(q.get('residual_m', 0.0)):.0f} cm" for z, q in zones.items()
                    if float(q.get("residual_m", 0.0)) >= 0.005)
    return f"{float(cr['ees_kmh']):.1f}" + (f" <span class=small>(residual crush: {res})</span>" if res else "")


def _vehicle_table(rep: CrashReport) -> str:
    rec = rep.d.get("reconstruction")
    K = impact_mod.KMH
    rows = []
    for i, nm in enumerate(rep.names):
        v = rep.d["vehicles"][i]
        first = rep.first(i)
        if first is None:
            cells = "<td>no impact</td><td>&ndash;</td><td>&ndash;</td><td>&ndash;</td>"
        else:
            p, vi = first
            cells = (f"<td data-q='{nm}.impact_speed'>{vi.speed_before * K:.1f}</td>"
                     f"<td data-q='{nm}.delta_v'>{vi.dv * K:.1f}</td>"
                     f"<td data-q='{nm}.delta_v_impulse'>{vi.dv_impulse * K:.1f}</td>"
                     f"<td data-q='{nm}.pdof'>{vi.pdof_clock} o'clock ({_deg(vi.pdof_deg)}&deg;)</td>")
        iv = (f"impact speed: {_interval(rec, i, 'impact_speed_kmh')}<br>Delta-v: {_interval(rec, i, 'delta_v_kmh')}"
              f"<br>PDOF: {_interval(rec, i, 'pdof_clock', '.1f')}" if rec else _interval(rec, i, ""))
        rows.append(f"<tr><td class=l><b>{html.escape(nm)}</b></td><td class=l>{html.escape(str(v.get('type', '')))}"
                    f"</td><td>{rep.impacts.mass[i]:,.0f}</td>{cells}<td data-q='{nm}.ees'>{_ees(v)}</td>"
                    f"<td class=l>{iv}</td></tr>")
    return ("<table><tr><th class=l>vehicle</th><th class=l>type</th><th>mass (kg)</th><th>impact speed (km/h)</th>"
            "<th>&Delta;v (km/h)</th><th>&Delta;v of the contact force, |J|/m (km/h)</th><th>PDOF</th>"
            "<th>EES (km/h)</th><th class=l>intervals</th></tr>" + "".join(rows) + "</table>")


def _impact_table(rep: CrashReport) -> str:
    K = impact_mod.KMH
    major = rep.major()
    rows = []
    for p in major[:MAX_IMPACT_ROWS]:
        s = striker(p)
        for k, v in enumerate(p.vehicles):
            nm = rep.names[v.vehicle]
            head = (f"<td rowspan=2>{p.t:.3f}</td><td rowspan=2>{1e3 * (p.t_end - p.t):.0f}</td><td rowspan=2 "
                    f"class=l>{html.escape(rep.names[p.a])}&ndash;{html.escape(rep.names[p.b])}"
                    f"{'' if s is None else ' (' + html.escape(rep.names[s]) + ' strikes)'}</td>"
                    f"<td rowspan=2>{p.closing_speed * K:.1f}</td>" if k == 0 else "")
            tail = (f"<td rowspan=2>{100 * p.momentum_error:.0f} (reach {100 * rep.reach(p):.0f})</td>"
                    if k == 0 else "")
            rows.append(f"<tr>{head}<td class=l>{html.escape(nm)}</td><td>{v.speed_before * K:.1f}</td>"
                        f"<td>{v.speed_after * K:.1f}</td><td>{v.dv_body[0] * K:+.1f}, {v.dv_body[1] * K:+.1f}</td>"
                        f"<td>{v.dv * K:.1f}</td><td>{v.dv_impulse * K:.1f}</td>"
                        f"<td>{v.pdof_clock} ({_deg(v.pdof_deg)}&deg;)</td>{tail}</tr>")
    minor = len(rep.impacts.impacts) - len(major)
    more = len(major) - min(len(major), MAX_IMPACT_ROWS)
    note = []
    if more:
        note.append(f"{more} further impacts not listed")
    note.append("the two vehicles' m&Delta;v differ by what the road gave over the impact, at most &mu; g &tau; "
                "(m<sub>a</sub> + m<sub>b</sub>) over its length &tau;: its reach")
    if minor:
        note.append(f"{minor} grazes (no vehicle's &Delta;v reaches {MINOR_DV_KMH:g} km/h) not listed")
    return ("<table><tr><th>t (s)</th><th>lasts (ms)</th><th class=l>pair</th><th>closing speed (km/h)</th>"
            "<th class=l>vehicle</th>"
            "<th>speed before (km/h)</th><th>after (km/h)</th><th>&Delta;v forward, left (km/h)</th>"
            "<th>|&Delta;v| (km/h)</th><th>|J|/m (km/h)</th><th>PDOF (clock, deg)</th>"
            "<th>m&Delta;v imbalance (the road's reach), % of the mean m|&Delta;v|</th></tr>"
            + "".join(rows) + "</table>"
            + f"<p class=small>{'; '.join(note)[:1].upper()}{'; '.join(note)[1:]}.</p>") if major else \
        "<p>No vehicle touched another.</p>"


def evidence_rows(rep: CrashReport) -> list[tuple[str, str, str, str, str, bool]]:
    """Every fate of the script against the replay: [(vehicle, fate, asked, got, tolerance, met)],
    the global order last (vehicle "all")."""
    o: Any = rep.motion.outcome
    names = rep.names
    K = impact_mod.KMH
    out = []
    for i, (vs, vo) in enumerate(zip(rep.script.vehicles, o.vehicles)):
        f, met, nm = vs.fate, vo.fates, names[i]
        end = "still moving at the end: " if vo.moving else ""
        if f.hits is not None:
            out.append((nm, "hits", ", then ".join(names[j] for j in f.hits) or "nobody",
                        ", then ".join(names[j] for j, _ in vo.hits) or "nobody", "the same, in order", met["hits"]))
        for key, label, val in (("impact_speed", "impact speed", vo.impact_speed), ("delta_v", "delta-V", vo.delta_v)):
            b = getattr(f, key)
            if b is not None:
                mid, half = (b.lo + b.hi) / 2 * K, (b.hi - b.lo) / 2 * K
                out.append((nm, label, f"{mid:.1f} km/h", f"{val * K:.1f} km/h" if math.isfinite(val) else "no impact",
                            f"&plusmn; {half:.1f} km/h", met[key]))
        if f.impact_at is not None:
            x, y, r = f.impact_at
            dd = math.hypot(vo.impact_pos[0] - x, vo.impact_pos[1] - y)
            out.append((nm, "position at impact", f"({x:.2f}, {y:.2f}) m",
                        f"({vo.impact_pos[0]:.2f}, {vo.impact_pos[1]:.2f}) m, {dd:.2f} m off" if math.isfinite(dd)
                        else "no impact", f"{r:g} m", met["impact_at"]))
        if f.rest is not None:
            x, y, r = f.rest
            dd = math.hypot(vo.rest[0] - x, vo.rest[1] - y)
            out.append((nm, "rest position", f"({x:.2f}, {y:.2f}) m",
                        f"{end}({vo.rest[0]:.2f}, {vo.rest[1]:.2f}) m, {dd:.2f} m off", f"{r:g} m", met["rest"]))
        if f.heading is not None:
            err = abs((math.degrees(vo.rest[2] - f.heading[0]) + 180) % 360 - 180)
            out.append((nm, "heading at rest", f"{math.degrees(f.heading[0]):.0f}&deg;",
                        f"{end}{math.degrees(vo.rest[2]):.0f}&deg;, {err:.0f}&deg; off",
                        f"&plusmn; {math.degrees(f.heading[1]):.0f}&deg;", met["heading"]))
        if f.quarter_turns is not None:
            lo, hi = f.quarter_turns
            out.append((nm, "quarter turns of roll", f"{lo}" if lo == hi else f"{lo}-{hi}", f"{vo.quarter_turns}",
                        "whole turns", met["quarter_turns"]))
        if f.attitude is not None:
            out.append((nm, "attitude at the end", f.attitude, vo.attitude, "the same", met["attitude"]))
        if f.spin is not None:
            out.append((nm, "spin", f"{math.degrees(f.spin[0]):.0f}&deg;", f"{abs(math.degrees(vo.spin)):.0f}&deg;",
                        f"&plusmn; {math.degrees(f.spin[1]):.0f}&deg;", met["spin"]))
        for key in ("curb", "barrier"):
            want = getattr(f, key)
            if want is not None:
                t = getattr(vo, key)
                out.append((nm, f"{key} strike", "yes" if want else "no",
                            f"yes, {t:.2f} s" if math.isfinite(t) else "no", "&ndash;", met[key]))
    if rep.script.order is not None:
        want = ", ".join(f"{names[a]}-{names[b]}" for a, b in rep.script.order)
        got = ", ".join(f"{names[a]}-{names[b]}" for a, b in o.sequence) or "none"
        out.append(("all", "order of first contacts", want, got, "the same", bool(o.order_ok)))
    return out


def _evidence_table(rep: CrashReport) -> str:
    rows = evidence_rows(rep)
    if not rows:
        return "<p>The script asks nothing of the vehicles.</p>"
    body = "".join(
        f"<tr><td class=l>{html.escape(v)}</td><td class=l>{k}</td><td class=l>{a}</td><td class=l>{g}</td>"
        f"<td class=l>{t}</td><td class={'ok' if ok else 'bad'}>{'met' if ok else 'NOT met'}</td></tr>"
        for v, k, a, g, t, ok in rows)
    n_ok = sum(r[5] for r in rows)
    return (f"<p>{n_ok} of {len(rows)} met.</p><table><tr><th class=l>vehicle</th><th class=l>fate / evidence</th>"
            "<th class=l>asked</th><th class=l>got</th><th class=l>tolerance</th><th>met</th></tr>" + body + "</table>")


def _reconstruction_html(rec: dict | None) -> str:
    if not rec:
        return ""
    esc = html.escape
    bits = []
    if rec.get("method"):
        bits.append(f"Method: {esc(str(rec['method']).rstrip('.'))}.")
    if rec.get("accepted") is not None and rec.get("draws") is not None:
        bits.append(f"{rec['accepted']} of {rec['draws']} draws met every piece of evidence.")
    cs = rec.get("closing_speed_kmh")
    if isinstance(cs, dict) and cs.get("lo") is not None:
        bits.append(f"Closing speed {cs['lo']:.1f}&ndash;{cs['hi']:.1f} km/h"
                    + (" (not identifiable)." if cs.get("identifiable") is False else "."))
    unk = rec.get("unknowns")
    if isinstance(unk, dict) and unk:
        bits.append("Over the accepted draws: " + ", ".join(
            f"{esc(str(k).replace('_', ' '))} {v['lo']:.3g}&ndash;{v['hi']:.3g}" for k, v in unk.items()
            if isinstance(v, dict) and v.get("lo") is not None and v.get("hi") is not None) + ".")
    ev = [str(x) for x in rec.get("evidence") or []]
    if ev:
        bits.append(f"Evidence: {esc(', '.join(ev))} (the pieces beyond the script's fates, such as skid marks, an "
                    "event data recorder's speed or residual crush, are judged in the reconstruction's draws; the "
                    "table of evidence below holds the fates).")
    verdicts = "".join(f"<li>{esc(str(v))}</li>" for v in rec.get("verdicts") or [])
    return ("<h2>The reconstruction</h2>" + "".join(f"<p>{b}</p>" for b in bits)
            + (f"<p>Verdicts:</p><ul>{verdicts}</ul>" if verdicts else ""))


def report_html(rep: CrashReport) -> str:
    """The whole page of :func:`crash_report`'s result.

    Args:
        rep: the report's data.

    Returns:
        The HTML text (figures inline).
    """
    d, s = rep.d, rep.script
    esc = html.escape
    o: Any = rep.motion.outcome
    same = ("The replay reproduces the file bit for bit." if rep.motion.identical and rep.impacts.identical
            else f"<b class=bad>Warning</b>: {esc(rep.motion.differs() or 'the replay differs from the file')}; "
                 "the page shows the replay.")
    p = d.get("probability")
    prob = (f" Under {esc(str(p.get('noise_kind', 'retake')))} driver noise, {p['k']} of {p['n']} re-drives met the "
            f"script (P = {100 * p['p']:.0f} %, 95 % Wilson interval {100 * p['lo']:.0f}&ndash;{100 * p['hi']:.0f} %)."
            if isinstance(p, dict) else "")
    rec = d.get("reconstruction")
    road = s.road
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>nbst crash report: {esc(s.name)}</title>
<style>{_CSS}</style></head><body>
<h1>Crash report: {esc(s.name)}</h1>
<p class=small>{esc(rep.source)}{' &middot; ' + esc(s.description.splitlines()[0]) if s.description else ''}</p>
<p>{s.n} vehicles on a {esc(road.layout)} road, {road.width:g} m wide, friction {rep.friction:.3g};
{s.duration:g} s at {1e3 * float(d['timestep']):g} ms steps (MuJoCo {esc(str(d.get('mujoco', '')))}).
{'The script is met' if o.solved else 'The script is not met'} (signature {o.signature_text(s.n)}).{prob} {same}</p>
<h2>Per vehicle, at its first impact</h2>
{_vehicle_table(rep)}
<p class=small>Impact speed: the centre of mass's speed just before the first touch. &Delta;v: the magnitude of
its velocity change from just before the first touch to just after the last of the contact episode (touches
less than {1e3 * impact_mod.CONTACT_GAP:g} ms apart); it holds the tyres' forces over the episode too, which
|J|/m, the contact impulse over the mass, leaves out. PDOF: where the force comes from in the vehicle's frame
(12 o'clock: straight ahead, 3: the right; degrees clockwise from straight ahead; SAE J224). EES: the
energy-equivalent speed of the residual crush, recorded only for crushing vehicle types.</p>
{_reconstruction_html(rec)}
<h2>Impacts</h2>
{_impact_table(rep)}
<h2>Speed against time</h2>
<img alt="speed-time diagram" src="data:image/png;base64,{figure_speed(rep)}">
<h2>Sequence</h2>
<img alt="sequence diagram" src="data:image/png;base64,{figure_sequence(rep)}">
<p class=small>Braking and standing still are read from the realised brake commands and speeds. Perception-reaction
is drawn {PERCEPTION_S:g} s before the driver's reaction stop, or else its first lasting braking (an assumed
median: Johansson and Rumar 1971); the crash file records when the driver braked, not when the hazard
appeared.</p>
<h2>Scene</h2>
<img alt="scene diagram" src="data:image/png;base64,{figure_scene(rep)}">
<h2>Evidence against fit</h2>
{_evidence_table(rep)}
</body></html>
"""
