"""Which subsets of pins down can a throw give? Rules from the pin deck's geometry alone.

Pure numpy (no MuJoCo): the numbers are those of :mod:`.scene` and :mod:`.pin` (USBC):
pin spots 12 in apart on a triangle, pin belly :data:`PIN_RADIUS` (4.766 in across), ball
:data:`BALL_RADIUS` (8.5 in across), lane 41.5 in wide; the deck half's delivery bounds (:data:`.deck.delivery.BOUNDS`).

A **ball path** across the deck is a straight line ``y = y0 + x tan(theta)`` (x from the
head pin's spot): the ball's centre stays on the lane or in a gutter, at most as far out as
the gutter's middle, over the deck (|y| <= :data:`Y_MAX`), and ``|theta| <=``
:data:`THETA_MAX` (the 5 m delivery's 3 degrees plus the strongest hook measured in
docs/bowling.md, 6.4 degrees at the deck: a gently hooking ball is straight over the 0.8 m
of the deck to within a few mm). The ball's **corridor** is the
band within ``BALL_RADIUS + PIN_RADIUS`` of the path: a pin whose axis is in it is touched
if the ball goes straight on. Three facts and two rules:

* fact: the gap between two neighbouring pins (12 in - one belly) is smaller than the ball,
  so the ball cannot pass between two pins of a row without touching one;
* fact: every path on the lane has at least one pin in its corridor (the columns are 6 in
  apart, closer than ``BALL_RADIUS + PIN_RADIUS``, and the outer ones are within reach of
  the lane's edge): only a gutter ball leaves all pins standing;
* **corridor rule**: the pins the ball must touch are down: the front-most corridor pin of
  each column (pins behind it may be knocked away before the ball arrives);
* **reach rule**: a pin falls only when something hits it: every down pin is in the
  corridor, or joined to a down corridor pin through a chain of down neighbours (a pin is
  15 in tall, neighbours stand 12 in apart, so a falling pin reaches its neighbours and no
  further; anything else takes a pin that flies, slides or rebounds off a wall).

A subset is **corridor-consistent** (class a) when some path satisfies both rules; else it
**needs a flying pin or breaks the corridor rule** (class b: ``"corridor"`` when no path
satisfies the corridor rule, ``"reach"`` when some does but none with the reach rule too).
The ball deflects on each impact and pins fly, so these are hypotheses to test against the
atlas: a rule that a found subset breaks is not a rule (:func:`compare`).
"""
from __future__ import annotations

import math

import numpy as np

from nbst.errors import InputError

__all__ = ["INCH", "PIN_SPACING", "PIN_RADIUS", "BALL_RADIUS", "LANE_WIDTH", "Y_LANE", "GUTTER_WIDTH", "Y_MAX",
           "THETA_MAX", "REACH", "Y_STEP", "THETA_STEP", "PINS", "ALL_DOWN", "N_SUBSETS", "pin_spots",
           "neighbours", "gap", "columns", "paths", "corridors", "classify", "size_of", "counts", "compare",
           "summary_lines"]

INCH = 0.0254
#: Pin spacing (USBC: 12 in between neighbouring spots) = scene.PIN_SPACING.
PIN_SPACING = 12.0 * INCH
#: Pin belly radius (USBC 4.766 in across) = the largest of pin.profile().
PIN_RADIUS = 4.766 / 2 * INCH
#: Ball radius (8.5 in across) = scene.BALL_RADIUS.
BALL_RADIUS = 4.25 * INCH
#: Lane width (41.5 in) = scene.LANE_WIDTH; the ball's centre stays |y| <= Y_LANE on it.
LANE_WIDTH = 41.5 * INCH
Y_LANE = LANE_WIDTH / 2 - BALL_RADIUS
#: Gutter width (9.25 in) = scene.GUTTER_WIDTH. A path may run off the lane's edge into the
#: gutter as far as the gutter's middle (|y| <= Y_MAX): a ball there, lower by up to the
#: gutter's depth, still clips pin 7 or 10 (taken as if it were on the lane: generous).
GUTTER_WIDTH = 9.25 * INCH
Y_MAX = LANE_WIDTH / 2 + GUTTER_WIDTH / 2
#: Largest angle of the ball's path to the lane axis over the deck (deg): the 5 m delivery's 3 deg
#: (deck.BOUNDS) plus the entry angle of the strongest hook measured (6.4 deg at -30 rad/s).
THETA_MAX = 3.0 + 6.4
#: Pins within this distance of the ball's path are touched (ball radius + pin radius).
REACH = BALL_RADIUS + PIN_RADIUS
#: Path grid: lateral step (m) and angle step (deg) of :func:`paths`.
Y_STEP = 0.001
THETA_STEP = 0.25

PINS = tuple(range(1, 11))
#: The strike: every pin down, as a 10-bit mask (bit n-1 = pin n).
ALL_DOWN = (1 << len(PINS)) - 1
#: Non-empty subsets of pins down (the masks 1..ALL_DOWN): what an atlas can hold.
N_SUBSETS = ALL_DOWN


def pin_spots() -> np.ndarray:
    """(10, 2) float, m: (x, y) of pins 1..10 (as scene.pin_spots: 1 at the origin, 7 back left)."""
    dx = PIN_SPACING * math.sqrt(3) / 2
    return np.array([(r * dx, (r / 2 - k) * PIN_SPACING) for r in range(4) for k in range(r + 1)])


def neighbours() -> np.ndarray:
    """(10, 10) bool: pins one spacing apart (the triangle's edges; 18 pairs)."""
    s = pin_spots()
    d = np.linalg.norm(s[:, None] - s[None], axis=-1)
    return np.isclose(d, PIN_SPACING)


def gap(a: int, b: int) -> float:
    """Clear gap (m) between the bellies of pins a and b."""
    s = pin_spots()
    return float(np.linalg.norm(s[a - 1] - s[b - 1]) - 2 * PIN_RADIUS)


def columns() -> np.ndarray:
    """(10,) int: the column of each pin, numbered from the left (+y): 7 | 4 | 2 8 | 1 5 | 3 9 | 6 | 10."""
    y = pin_spots()[:, 1]
    ys = np.unique(np.round(y, 9))[::-1]
    return np.array([int(np.argmin(np.abs(ys - v))) for v in y])


def paths() -> np.ndarray:
    """(P, 2) float: (y0 m, theta rad) of the ball paths on a grid, each keeping the ball's
    centre on the lane or in a gutter across the pin deck (|y| <= Y_MAX from the head pin to
    the back row)."""
    x_back = pin_spots()[:, 0].max()
    y0 = np.arange(-Y_MAX, Y_MAX + 1e-12, Y_STEP)
    th = np.radians(np.arange(-THETA_MAX, THETA_MAX + 1e-9, THETA_STEP))
    Y0, TH = np.meshgrid(y0, th, indexing="ij")
    Y0, TH = Y0.ravel(), TH.ravel()
    ok = np.abs(Y0 + x_back * np.tan(TH)) <= Y_MAX + 1e-12
    return np.column_stack([Y0[ok], TH[ok]])


def corridors(p: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(in_corridor, must_touch): (P, 10) bool each, for paths ``p`` (default :func:`paths`).
    in_corridor: the pin's axis within REACH of the path; must_touch: corridor pins with no
    corridor pin of the same column in front of them."""
    p = paths() if p is None else np.asarray(p, float)
    s = pin_spots()
    y0, th = p[:, :1], p[:, 1:]
    # distance from a spot to the line y = y0 + x tan(theta)
    dist = np.abs(s[None, :, 1] - y0 - s[None, :, 0] * np.tan(th)) * np.cos(th)
    inside = dist < REACH
    col = columns()
    must = inside.copy()
    for i in range(10):
        for j in range(10):
            if i != j and col[i] == col[j] and s[j, 0] < s[i, 0]:
                must[:, i] &= ~inside[:, j]
    return inside, must


def _masks(b: np.ndarray) -> np.ndarray:
    return (b.astype(np.int64) << np.arange(10)).sum(axis=-1)


def _reached(down: int, seeds: int, adj: np.ndarray) -> int:
    """Pins of ``down`` connected (through down neighbours) to a pin of ``seeds & down``."""
    got = seeds & down
    while True:
        grow = got
        for i in range(10):
            if got >> i & 1:
                grow |= int(_masks(adj[i])) & down
        if grow == got:
            return got
        got = grow


def classify(*, touch: str = "front") -> dict[int, str]:
    """mask (1..N_SUBSETS) -> "a" (corridor-consistent), "corridor" or "reach" (class b; see module).

    ``touch``: which corridor pins the corridor rule wants down: "front" (the front-most of
    each column, the module's rule), "all" (every corridor pin: the ball goes straight through
    the deck), "any" (at least one: the ball hits something)."""
    inside, must = corridors()
    if touch == "all":
        must = inside
    elif touch == "any":
        must = np.zeros_like(inside)
    elif touch != "front":
        raise InputError(f"touch must be front, all or any, got {touch!r}")
    pairs = np.unique(np.column_stack([_masks(inside), _masks(must)]), axis=0)  # distinct corridors
    adj = neighbours()
    out = {}
    for m in range(1, N_SUBSETS + 1):
        ok_corr = ((pairs[:, 1] & m) == pairs[:, 1]) & ((pairs[:, 0] & m) != 0)
        if not ok_corr.any():
            out[m] = "corridor"
            continue
        if any(_reached(m, int(c), adj) == m for c in pairs[ok_corr, 0]):
            out[m] = "a"
        else:
            out[m] = "reach"
    return out


def size_of(m: int) -> int:
    return int(m).bit_count()


def counts(classes: dict[int, str], masks=None) -> dict[str, np.ndarray]:
    """class -> (11,) int counts by subset size, over ``masks`` (default all 1,023)."""
    masks = range(1, N_SUBSETS + 1) if masks is None else masks
    out = {c: np.zeros(11, dtype=int) for c in ("a", "corridor", "reach")}
    for m in masks:
        out[classes[int(m)]][size_of(m)] += 1
    return out


def compare(found, *, touch: str = "front") -> dict:
    """How the atlas's found subsets sit in the classes: counts by class over all subsets and
    over the found ones, and the found subsets that break a rule (their masks)."""
    cl = classify(touch=touch)
    found = sorted(int(m) for m in found if m)
    return {"all": counts(cl), "found": counts(cl, found),
            "breakers": {c: [m for m in found if cl[m] == c] for c in ("corridor", "reach")}}


def summary_lines(found, *, touch: str = "front") -> list[str]:
    """Markdown table: by subset size, found / possible, and the geometry classes (all, found)."""
    r = compare(found, touch=touch)
    a, f = r["all"], r["found"]
    lines = ["| pins down | found / possible | corridor-consistent (found / all) | breaks the corridor rule "
             "(found / all) | needs a flying pin (found / all) |", "|---|---|---|---|---|"]
    for k in range(1, 11):
        tot = math.comb(10, k)
        got = f["a"][k] + f["corridor"][k] + f["reach"][k]
        lines.append(f"| {k} | {got} / {tot} | {f['a'][k]} / {a['a'][k]} | {f['corridor'][k]} / "
                     f"{a['corridor'][k]} | {f['reach'][k]} / {a['reach'][k]} |")
    lines.append(f"| all | {sum(x.sum() for x in f.values())} / {N_SUBSETS} | {f['a'].sum()} / {a['a'].sum()} | "
                 f"{f['corridor'].sum()} / {a['corridor'].sum()} | {f['reach'].sum()} / {a['reach'].sum()} |")
    which = {"front": "the front-most corridor pin of each column", "all": "every corridor pin",
             "any": "at least one corridor pin"}[touch]
    lines += ["", f"Geometry (models/bowling/geometry.py, corridor rule '{touch}'): corridor-consistent = some "
              f"straight ball path on the lane or in a gutter (within {THETA_MAX:g} deg of the lane's axis) has "
              f"{which} down, and every down pin in its corridor or joined to a down corridor pin by down "
              "neighbours. A found subset outside that class shows a rule that does not hold."]
    for c, name in (("corridor", "break the corridor rule"), ("reach", "need a flying pin")):
        ms = r["breakers"][c]
        if ms:
            show = "; ".join("-".join(str(n) for n in PINS if m >> (n - 1) & 1) for m in ms[:12])
            lines.append(f"Found subsets that {name} ({len(ms)}): {show}{' ...' if len(ms) > 12 else ''}.")
    return lines
