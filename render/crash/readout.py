"""The crash video's readout: per vehicle, what the script asked and what happened.

A reconstructionist's units: metres, km/h, degrees, seconds. One block per vehicle, a result
on the left and, where the script asks something of it, a mark and what was asked on the right:

* ``hit B 3.08 s Δv 27.8 km/h`` one line per vehicle it hits, in order, as they happen (the
  delta-V is this vehicle's in that contact: |impulse| / its mass); asked: whom, in order;
* ``impact 53.8 km/h`` and ``Δv 27.8 km/h`` (its first impact) where the script asks for them
  (then the first hit's line leaves its delta-V to that line: each hit's delta-V said once);
* ``0 quarter turns, upright`` (roll so far, unwrapped); asked: the turns and/or the attitude;
* ``spun 361°`` (yaw turned), ``curb 3.41 s`` (strikes) where asked;
* ``at (x, y) 48.2 km/h`` while it moves, ``rest (x, y) 146°`` at the end; asked: the region
  and the heading (``facing 146°`` on its own line where a heading is asked).

The marks (✓ the fate holds, ✗ it does not) and the signature line (one character per
vehicle, 1 = every fate of that vehicle holds, the search's signature) appear on the last
frame: the fates are judged at the end (a vehicle still moving then has no rest: its rest and heading
fates are unmet, and its last line reads ``end (x, y)``). They are the replay's own judgement
(:func:`nbst.models.crash.outcome.judge`), which a faithful replay shares with the file.

Compute only: :func:`readout` returns text lines.
"""
from __future__ import annotations

import math

from nbst.render.crash.motion import SLOW, slowed

__all__ = ["COS45", "DEG", "DV", "FATES", "PM", "RESULT_CHARS", "asked_of", "colour_rows", "mark_masks", "readout",
           "vehicle_lines", "widest"]

OK, NO = "\u2713", "\u2717"
DV = "\u0394v"
DEG = "\u00b0"
PM = "\u00b1"
#: Characters of the result column (longer results push the mark right).
RESULT_CHARS = 25
#: Vertical share of the up axis that splits upright / side / roof (the outcome's rule).
COS45 = math.sqrt(0.5)


def _deg(x: float) -> str:
    """Degrees, whole, never "-0"."""
    return f"{round(x) + 0:.0f}{DEG}"


def _g(x: float) -> str:
    return f"{x:.3g}" if abs(x) < 100 else f"{x:.0f}"


def _range(r, unit: str) -> str:
    lo, hi = r
    return f"{_g(lo)} {unit}" if abs(hi - lo) < 1e-9 else f"{_g(lo)}-{_g(hi)} {unit}"


def asked_of(fate: dict) -> dict:
    """What a fate (``crashfile.fate_dict``: user units) asks, as short texts keyed by line."""
    a: dict = {}
    if "hits" in fate:
        a["hits"] = ", ".join(fate["hits"]) or "nobody"
    if "impact_speed_kmh" in fate:
        a["impact"] = _range(fate["impact_speed_kmh"], "km/h")
    if "delta_v_kmh" in fate:
        a["dv"] = _range(fate["delta_v_kmh"], "km/h")
    turns = []
    if "quarter_turns" in fate:
        lo, hi = fate["quarter_turns"]
        turns.append(f"{lo} qt" if lo == hi else f"{lo}-{hi} qt")
    if "attitude" in fate:
        turns.append(fate["attitude"])
    if turns:
        a["turns"] = ", ".join(turns)
    if "spin" in fate:
        a["spin"] = f"{_g(fate['spin']['deg'])}{PM}{_g(fate['spin']['tol'])}{DEG}"
    for k, want in fate.get("strikes", {}).items():
        a[k] = k if want else f"no {k}"
    if "rest" in fate:
        r = fate["rest"]
        a["rest"] = f"{_g(r['radius'])} m of ({_g(r['x'])}, {_g(r['y'])})"
    if "heading" in fate:
        a["heading"] = f"{_g(fate['heading']['deg'])}{PM}{_g(fate['heading']['tol'])}{DEG}"
    return a


#: The fates (outcome.judge's keys) each line's mark stands for.
FATES = {"hits": ("hits",), "impact": ("impact_speed",), "dv": ("delta_v",), "turns": ("quarter_turns", "attitude"),
         "spin": ("spin",), "curb": ("curb",), "barrier": ("barrier",), "rest": ("rest",), "heading": ("heading",)}


def _line(result: str, key: str | None, asked: dict, fates: dict | None) -> str:
    if key is None or key not in asked:
        return result
    mark = " "
    if fates is not None:
        held = [fates[f] for f in FATES[key] if f in fates]
        mark = OK if held and all(held) else NO
    return f"{result:<{RESULT_CHARS}} {mark} {asked[key]}"


def vehicle_lines(i: int, t: float, motion, script, fate: dict, label: str, *, final: bool) -> list[str]:
    """The block of vehicle ``i`` at time ``t`` (``final``: the last frame, marks shown)."""
    names = script.names()
    me = names[i]
    od = motion.outcome_dict["vehicles"][i]
    vo = motion.outcome.vehicles[i]
    asked = asked_of(fate)
    fates = dict(vo.fates) if final else None
    head = f"{me} \u00b7 {label}"
    if final:
        head += f"  {OK if all(vo.fates.values()) else NO}"
    out = [head]
    k = motion.index(t)
    hits = []
    for c in motion.outcome_dict["contacts"]:
        if me in (c["a"], c["b"]) and c["t"] <= t + 1e-9:
            other = c["b"] if c["a"] == me else c["a"]
            hits.append(f"hit {other} {c['t']:.2f} s")
            if not hits[1:] and "dv" in asked:
                continue  # the first hit's delta-V has its own line, with its mark: said once
            hits[-1] += f" {DV} {c['delta_v_kmh'][me]:.1f} km/h"
    n_hits = max(1, sum(me in (c["a"], c["b"]) for c in motion.outcome_dict["contacts"]))
    hits += [""] * (n_hits - len(hits))
    if not any(hits):
        hits[0] = "no hit" + ("" if final else " yet")
    out.append(_line(hits[0], "hits", asked, fates))
    out += hits[1:]
    first = vo.hits[0][1] if vo.hits else math.inf
    if "impact" in asked:
        v = f"impact {od['impact_speed_kmh']:.1f} km/h" if first <= t + 1e-9 else "impact -"
        out.append(_line(v, "impact", asked, fates))
    if "dv" in asked:
        v = f"{DV} {od['delta_v_kmh']:.1f} km/h" if first <= t + 1e-9 else f"{DV} -"
        out.append(_line(v, "dv", asked, fates))
    if final:
        turns, att = vo.quarter_turns, vo.attitude
    else:
        turns = int(round(abs(float(motion.roll[k, i])) / (math.pi / 2)))
        w, x, y, _ = motion.quat[k, i]
        up = 1 - 2 * (x * x + y * y)
        att = "upright" if up > COS45 else ("roof" if up < -COS45 else "side")
    out.append(_line(f"{turns} quarter turn{'' if turns == 1 else 's'}, {att}", "turns", asked, fates))
    if "spin" in asked:
        spin = vo.spin if final else float(motion.yaw[k, i] - motion.yaw[0, i])
        out.append(_line(f"spun {_deg(abs(math.degrees(spin)))}", "spin", asked, fates))
    for what in ("curb", "barrier"):
        if what in asked:
            ts = getattr(vo, what)
            v = f"{what} {ts:.2f} s" if not math.isnan(ts) and ts <= t + 1e-9 else f"no {what}" + ("" if final else " yet")
            out.append(_line(v, what, asked, fates))
    x, y = motion.pos[k, i, :2]
    if final:
        r = od["rest"]
        v = f"{'rest' if not od['moving_at_end'] else 'end'} ({r['x']:.1f}, {r['y']:.1f})"
        if "heading" not in asked:
            v += f" {_deg(r['heading_deg'])}"
    else:
        v = f"at ({x:.1f}, {y:.1f}) {motion.speed[k, i] * 3.6:.1f} km/h"
    out.append(_line(v, "rest", asked, fates))
    if "heading" in asked:
        h = od["rest"]["heading_deg"] if final else math.degrees(float(motion.yaw[k, i]))
        h = (h + 180.0) % 360.0 - 180.0
        out.append(_line(f"facing {_deg(h)}", "heading", asked, fates))
    return out


def readout(t: float, motion, script, fates: list[dict], labels: list[str], windows) -> list[str]:
    """Every line of the readout at time ``t``: the title and time, slow motion, the signature,
    then one block per vehicle (:func:`vehicle_lines`), blocks separated by a blank line."""
    final = t >= motion.duration - 1e-9
    o = motion.outcome
    lines = [f"{script.name} \u00b7 t = {t:5.2f} s", f"slow motion \u00d7{SLOW:g}" if slowed(t, windows) else "real time"]
    if final:
        sig = o.signature_text(script.n)
        s = f"signature {sig}"
        if script.order is not None:
            s += f" \u00b7 order {OK if o.order_ok else NO}"
        lines.append(s + f" \u00b7 {'met' if o.solved else 'not met'}")
    else:
        lines.append("signature: judged at the end")
    if not motion.identical:
        lines.append(f"{NO} replay {'state' if not motion.same_state else 'outcome'} differs from the file")
    lines.append(f"{'what happened':<{RESULT_CHARS}}   asked")
    for i in range(script.n):
        lines.append("")
        lines += vehicle_lines(i, t, motion, script, fates[i], labels[i], final=final)
    return lines


def widest(motion, script, fates, labels, windows) -> tuple[int, int]:
    """(characters of the longest line, lines) the readout can take: the last frame's, which
    lists every hit and the marks (a frame before it has no more lines and none longer, up to
    the live numbers' digits, which RESULT_CHARS absorbs)."""
    lines = readout(motion.duration, motion, script, fates, labels, windows)
    early = readout(0.0, motion, script, fates, labels, windows)
    return max(len(s) for s in lines + early), max(len(lines), len(early))


def mark_masks(lines: list[str]) -> tuple[list[str], list[str], list[str]]:
    """(text without marks, the ✓ alone, the ✗ alone): three layers drawn in three colours."""
    def keep(s, chars):
        return "".join(c if c in chars else " " for c in s)

    plain = ["".join(" " if c in (OK, NO) else c for c in s) for s in lines]
    return plain, [keep(s, OK) for s in lines], [keep(s, NO) for s in lines]


def colour_rows(lines: list[str], names: list[str]) -> list[int]:
    """For each line, the vehicle whose block header it is (-1: none)."""
    out = []
    for s in lines:
        out.append(next((i for i, nm in enumerate(names) if s.startswith(f"{nm} \u00b7 ")), -1))
    return out

