"""A scene video's readout: per fated body, each fate asked and, on the last frames, what happened.

One block per body with fates (its name in the body's mark colour), one line per fate saying what
was asked (``rest_in box (0.70, -0.10, 0.00)-(0.90, 0.10, 0.05)``); from the motion's end on, a
line under each saying what happened (the judge's own words, ``nbst.scene.judge``) with a check
mark (met) or a cross (not met), and the signature line: one bit per body, 1 when every fate of
that body is met (the search's signature). The fates are judged on the replay, at the end.

A scene with parts nbst does not draw (a flex, such as cloth; a skin) says so in a last line,
``not drawn: 1 flex (cloth)`` (:func:`not_drawn`), on every frame.

Compute only: :func:`readout` returns text lines; :func:`marks` splits the marks out for colour;
:func:`mark_colours` gives each fated body its mark colour, :func:`name_tags` the bodies whose
name is drawn beside them in it; :func:`drawn_touches` picks the first touches marked in the
frame and :func:`touch_label` writes each one's label.
"""
from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from nbst.scene.fates import AT_REST_SPEED, AT_REST_SPIN, STILL_DISTANCE, Fate, Fates, Region
from nbst.scene.judge import Judgement, length_text, signature_text

__all__ = ["OK", "NO", "COMPACT_AFTER", "MARKS", "VIVID_SAT", "VIVID_MAX", "legible", "mark_colours", "region_text",
           "asked", "readout", "widest", "marks", "body_rows", "not_drawn", "own_colour", "name_tags",
           "drawn_touches", "touch_label"]

OK, NO = "\u2713", "\u2717"
_DEG = "\u00b0"
#: Past this many bodies with fates, the readout gives one line per fate (a row of dominoes).
COMPACT_AFTER = 3


def _v(p, text=length_text) -> str:
    return "(" + ", ".join(text(c) for c in p) + ")"


def _given(v: float) -> str:
    """A number of the fates file as its user wrote it, to the nanometre (the shortest text that
    reads back as it at 9 decimals): a region 1,000.5 m away reads ``1000.5``, not ``1000``; 12 km
    ``12000``, not ``1.2e+04``; a file's ``0.29000000000000004`` (0.35 - 0.06 in Python) ``0.29``."""
    v = float(v)
    if v and abs(v) < 1e-6:   # below a micrometre: every digit it has
        return np.format_float_positional(v, trim="-")
    return np.format_float_positional(v, precision=9, unique=True, trim="-")


def region_text(r: Region) -> str:
    """A region in a few words, its numbers as given: ``ball r 0.06 at (2, 0, 1.62)`` or ``box (lo)-(hi)``."""
    if r.center is not None:
        return f"ball r {_given(r.radius)} at {_v(r.center, _given)}"
    return f"box {_v(r.lo, _given)}-{_v(r.hi, _given)}"


def asked(f: Fate) -> list[tuple[str, str]]:
    """(fate, what it asks) for each fate of one body, in the judge's order."""
    out: list[tuple[str, str]] = []
    if f.rest_in is not None:
        out.append(("rest_in", region_text(f.rest_in)))
    if f.at:
        out.append(("at", "; ".join(f"t {t:g} s in {region_text(r)}" for t, r in f.at)))
    if f.through:
        out.append(("through", f"{len(f.through)} region{'s' if len(f.through) > 1 else ''} in order "
                               f"(numbered in the view)"))
    if f.up is not None:
        (ax, within) = f.up
        out.append(("up", f"axis {_v(ax)} up within {within:g}{_DEG} (arrow)"))
    if f.hits:
        out.append(("hits", "first touches " + ", then ".join(f.hits)))
    if f.never_hits:
        out.append(("never_hits", "never touches " + ", ".join(f.never_hits)))
    if f.at_rest:
        out.append(("at_rest", f"ends at rest (under {AT_REST_SPEED:g} m/s and {AT_REST_SPIN:g} rad/s)"))
    if f.still:
        out.append(("still", f"never moves over {STILL_DISTANCE * 100:g} cm"))
    return out


def not_drawn(model: Any) -> str:
    """What of ``model`` nbst does not draw, in a few words (``1 flex (cloth)``, ``2 flexes (rope,
    cloth) and 1 skin``), or "" when it draws everything: nbst draws geoms only (and spatial tendons)."""
    import mujoco

    parts = []
    for n, kind, obj in ((int(model.nflex), "flex", mujoco.mjtObj.mjOBJ_FLEX),
                         (int(model.nskin), "skin", mujoco.mjtObj.mjOBJ_SKIN)):
        if n:
            names = [mujoco.mj_id2name(model, obj, i) or f"#{i}" for i in range(n)]
            plural = "es" if kind == "flex" else "s"
            parts.append(f"{n} {kind}{plural if n > 1 else ''} ({', '.join(names[:3])}{', ...' if n > 3 else ''})")
    return " and ".join(parts)


def readout(title: str, t: float, fates: Fates, judgement: Judgement, *, final: bool,
            brief: bool = False, width: int | None = None, note: str = "") -> list[str]:
    """The readout's lines at time ``t``: the title and time, then per body its fates asked and,
    when ``final``, what happened with a mark, and the signature. Past :data:`COMPACT_AFTER`
    bodies, one line per fate (the body's name first, what happened after what was asked).
    ``brief`` (a frame too small for the rest at a legible size): one line per body, its fates'
    names, each with its mark when ``final`` (``gem: ✓ rest_in ✓ at_rest``), then the signature; a
    line past ``width`` characters goes on under the first name. ``note`` (what :func:`not_drawn`
    says): a last line ``not drawn: NOTE``, on every frame."""
    lines = [title, f"t = {t:5.2f} s"]
    tail = [f"not drawn: {note}"] if note else []
    verdicts = {b.body: {v.fate: v for v in b.fates} for b in judgement.bodies}
    if brief:
        for f in fates.fates:
            names = [name for name, _ in asked(f)]
            got = [verdicts.get(f.body, {}).get(n) for n in names]
            items = [f"{OK if v.met else NO} {n}" if final and v is not None else n for n, v in zip(names, got)]
            line = f"{f.body}:"
            for it in items:
                if width is not None and len(line) > len(f.body) + 1 and len(line) + 1 + len(it) > width:
                    lines.append(line)
                    line = " " * (len(f.body) + 1)
                line += " " + it
            lines.append(line)
        if final:
            lines.append(f"signature {signature_text(judgement.signature)}")
        return lines + tail
    compact = len(fates.fates) > COMPACT_AFTER
    for f in fates.fates:
        if not compact:
            lines.append(f.body)
        for name, text in asked(f):
            v = verdicts.get(f.body, {}).get(name)
            said = f"{OK if v.met else NO} {v.happened}" if final and v is not None else ""
            if compact:
                lines.append(f"{f.body} {name}: {text}" + (f"  {said}" if said else ""))
            else:
                lines.append(f"  {name}: {text}")
                if said:
                    lines.append(f"    {said}")
    if final:
        sig = signature_text(judgement.signature)
        lines.append(f"signature {sig}: " + ("every fate met" if judgement.met else "not every fate met"))
    return lines + tail


def body_rows(lines: list[str], fates: Fates) -> list[tuple[int, int]]:
    """Per line, (the index of the fated body whose name it starts with, the name's length), drawn
    in the body's mark colour; (-1, 0) for the others (the title and the time, the first two lines,
    never: a scene file may share a body's name)."""
    out = [(-1, 0)] * min(2, len(lines))
    for s in lines[2:]:
        hit = next(((i, len(f.body)) for i, f in enumerate(fates.fates)
                    if s == f.body or s.startswith(f.body + " ") or s.startswith(f.body + ": ")),
                   (-1, 0))
        out.append(hit)
    return out


def widest(title: str, fates: Fates, judgement: Judgement, duration: float, *, brief: bool = False,
           width: int | None = None, note: str = "") -> tuple[int, int]:
    """(characters, lines) of the longest readout: the final one."""
    lines = readout(title, duration, fates, judgement, final=True, brief=brief, width=width, note=note)
    return max(len(s) for s in lines), len(lines)


def marks(lines: list[str]) -> tuple[list[str], list[str], list[str]]:
    """(the lines without marks, only the check marks, only the crosses): drawn in three colours
    at the same place."""
    def keep(s: str, chars: str) -> str:
        return "".join(c if c in chars else " " for c in s)

    return ([s.replace(OK, " ").replace(NO, " ") for s in lines], [keep(s, OK) for s in lines],
            [keep(s, NO) for s in lines])


#: The fated bodies' mark colours (regions, arrows, names), in the fates' order, repeated, for a body
#: whose own colour is not vivid or is another's (:func:`mark_colours`).
MARKS = ((0.95, 0.45, 0.10), (0.15, 0.55, 0.95), (0.85, 0.20, 0.60), (0.25, 0.70, 0.30), (0.55, 0.35, 0.85),
         (0.80, 0.15, 0.20), (0.10, 0.65, 0.60), (0.70, 0.75, 0.10))
#: A body's own colour marks it when its saturation (max - min of RGB) and brightness reach these.
VIVID_SAT, VIVID_MAX = 0.35, 0.5


def legible(rgb, least: float = 0.4) -> tuple[float, float, float]:
    """``rgb`` mixed with white until its luminance (Rec. 709) reaches ``least``: a dark blue body's
    name readable on the readout's dark panel, its hue kept."""
    c = np.asarray(rgb, float)[:3]
    lum = float(c @ (0.2126, 0.7152, 0.0722))
    if lum >= least:
        return tuple(float(v) for v in c)   # type: ignore[return-value]
    k = (least - lum) / (1.0 - lum)
    return tuple(float(v) for v in c + (1.0 - c) * k)   # type: ignore[return-value]


def _close(rgb, taken, within: float = 0.15) -> bool:
    """Whether ``rgb`` is less than ``within`` from a colour in ``taken`` in every channel (reads as the same)."""
    return any(np.abs(np.subtract(rgb, o)).max() < within for o in taken)


def own_colour(model: Any, body: int) -> tuple[float, float, float] | None:
    """Body ``body``'s first visible geom's colour (its material's, else its own) when vivid
    (:data:`VIVID_SAT`, :data:`VIVID_MAX`), else None."""
    for g in range(int(model.ngeom)):
        if int(model.geom_bodyid[g]) == body and int(model.geom_group[g]) <= 2 and model.geom_rgba[g, 3] > 0:
            m = int(model.geom_matid[g])
            c = np.asarray(model.mat_rgba[m] if m >= 0 else model.geom_rgba[g], float)[:3]
            if c.max() - c.min() >= VIVID_SAT and c.max() >= VIVID_MAX:
                return tuple(float(v) for v in c)   # type: ignore[return-value]
            return None
    return None


def mark_colours(model: Any, fates: Fates) -> list[tuple[float, float, float]]:
    """Each fated body's mark colour: its own vivid colour (:func:`own_colour`) when not within 0.15
    of another body's, else :data:`MARKS` from the body's turn on, the first not within 0.1 of
    another body's (a ball named `green`, green in the model, is marked green, not in the palette's
    blue; a white body is never marked in the palette's orange, 0.05 from a thrown orange cube's).
    Two bodies share a colour only when every colour of the palette is taken."""
    import mujoco

    out: list[tuple[float, float, float]] = []
    for i, f in enumerate(fates.fates):
        rgb = own_colour(model, int(mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, f.body)))
        if rgb is None or _close(rgb, out):
            turn = [MARKS[(i + k) % len(MARKS)] for k in range(len(MARKS))]
            rgb = next((c for c in turn if not _close(c, out, 0.1)), turn[0])
        out.append(rgb)
    return out


def name_tags(model: Any, fates: Fates, colours: list) -> list[tuple[int, str, tuple[float, float, float]]]:
    """(body id, name, mark colour) of each fated body marked in a colour that nothing else in the
    frame carries: not its own colour (:func:`own_colour`), and no region or ``up`` arrow drawn in
    it (a ``still`` block of five alike, in the palette's): its name is drawn beside it in that
    colour, as the readout's is."""
    import mujoco

    out = []
    for f, rgb in zip(fates.fates, colours):
        b = int(mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, f.body))
        if (f.rest_in is None and not f.at and not f.through and f.up is None
                and own_colour(model, b) != tuple(rgb)):
            out.append((b, f.body, tuple(rgb)))
    return out


def drawn_touches(touches: Any, fates: Fates) -> list[Any]:
    """The first touches marked in the frame (:class:`~nbst.render.scene.motion.Touch`): after the
    start (a contact at t = 0 is a body at rest), each pair once, those a fate's ``hits`` or
    ``never_hits`` names (every one where none names any), each the way round the fate asks it (the
    cube's touch of block2, not block2's of the cube, where the cube must hit block2)."""
    asked = {f.body: {*f.hits, *f.never_hits} for f in fates.fates}
    seen: set[frozenset[str]] = set()
    out = []
    for im in touches:
        pair = frozenset((im.body, im.other))
        if im.t <= 0 or pair in seen:
            continue
        seen.add(pair)
        if im.body in asked.get(im.other, ()) and im.other not in asked.get(im.body, ()):
            im = replace(im, body=im.other, other=im.body)
        if im.other in asked.get(im.body, ()) or not any(asked.values()):
            out.append(im)
    return out


def touch_label(im: Any) -> str:
    """A first touch's label: the body, what it touched and when (``cube-block2 0.24 s``)."""
    return f"{im.body}-{im.other} {im.t:.2f} s"
