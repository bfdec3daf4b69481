"""Names of hits and leaves as bowlers say them: a plain function of (pins standing before the
throw, pins left, the ball's board and entry angle at the head pin's line, the hand).

**The hit** (:func:`hit_name`, right-hander's boards: board 1 at the hand's edge, the head pin
on board 20): ``pocket`` on boards 17-18 (the USBC pocket, docs/bowling.md), ``light`` below
it (more 3 pin than head pin), ``high`` between the pocket and the nose, ``nose`` within a
board of the head pin's centre, ``Brooklyn`` across it (the 1-2 pocket of a right-hander);
``missed the head pin`` beyond :data:`HEAD_PIN_REACH` boards, where the ball passes the head pin
without touching it (ball radius + the pin's widest radius). Beyond :data:`FRONT_REACH` boards
(6.2 past the head pin's reach: half a pin spacing more) a ball heading down the lane misses
the 2 or 3 pin too and meets only the side of the rack behind it (the 4-7 or the 6-10):
``wide left`` / ``wide right`` (the hand's side is the right of a right-hander), "missed the
head pin and the 2 pin" (the 3 on the right); beyond :data:`PINS_REACH` (the corner pin's
spot, three half spacings out, plus the reach: off the lane) it misses the rack: ``missed the
pins``. A ball on board 38 meets the 7 pin alone, not the 1-2 pocket (a coach read
"Brooklyn" there); one on board 1 the 10, not the 3 ("light"). Bowlers' usage: "more 3 pin than
head pin: light; more head pin: high; only the head pin: through the nose; the left side of the
head pin: Brooklyn". The entry angle is ``flat`` below :data:`FLAT_DEG` (the low edge of the 4-6
deg window of the USBC pocket).

**The leave** (:func:`leave_names`):

* ``split`` by the USBC Playing Rules' definition (bowl.com, "split"): the head pin is down and
  either (a) at least one pin is down between two or more pins standing (7-9, 3-10), or (b) at
  least one pin is down immediately ahead of two or more pins standing (5-6). "Between" here:
  a pin down whose spot lies sideways strictly between two standing pins, in the rows they
  span, within 6 in (half the pin spacing) of the line joining them; so the 2-8 and 3-9
  "sleepers" (a pin hidden straight behind another) are not splits, while the 4-9 is.
  ``washout``: the same gap with the head pin standing (1-2-10, 1-2-4-10; not a split, USBC).
* Leaves with names of their own: ``bedposts`` (7-10), ``baby split`` (2-7, 3-10), ``big
  four`` (4-6-7-10), ``greek church`` (4-6-7-8-10, 4-6-7-9-10), ``bucket`` (2-4-5-8;
  3-5-6-9 for a left-hander), ``picket fence`` (1-2-4-7, 1-3-6-10), ``sleeper`` (2-8, 3-9,
  1-5), ``lily`` (5-7-10).
* A lone corner pin after a strike ball (a full rack), by its hit: ``flat 10`` when the ball
  came in flat (below FLAT_DEG: the 6 falls weakly in front of the 10), ``solid 10`` on a
  pocket hit with angle (everything looked right), ``ringing 10`` on a light or high hit with
  angle (the 6 flies round the 10 off the kickback); ``solid 4`` for the 4 alone on a pocket
  hit. A left-hander's names mirror the pins (``flat 7``, ``ringing 7``, ``solid 6``).

Left-handed leaves are mirrored to the right-handed rack before they are named (the 3 pin is a
left-hander's 2), and the names are given in the bowler's own pin numbers.

Pure Python: no numpy, no MuJoCo.
"""
from __future__ import annotations

import math

__all__ = ["POCKET", "FLAT_DEG", "HEAD_PIN_REACH", "FRONT_REACH", "PINS_REACH", "LATTICE", "MIRROR", "is_split", "is_washout", "hit_name",
           "leave_names", "names", "text"]

#: The USBC pocket (right-hander's boards at the head pin's line).
POCKET = (17.0, 18.0)
#: Below this entry angle (deg) the ball comes in flat: the low edge of USBC's 4-6 deg window.
FLAT_DEG = 4.0
#: The head pin's board, and how far from it (boards) the ball still touches the head pin:
#: ball radius 4.25 in + the pin's widest radius 2.383 in (USBC: 4.766 in across), over a board
#: of 41.5/39 in.
HEAD_PIN_BOARD = 20.0
HEAD_PIN_REACH = (4.25 + 4.766 / 2) / (41.5 / 39)
#: Beyond this many boards from the head pin's a ball heading down the lane misses the 2 or 3 pin
#: too (their spots half a pin spacing, 6 in, further out): ~11.9 boards.
FRONT_REACH = HEAD_PIN_REACH + 6.0 / (41.5 / 39)
#: Beyond this many boards it misses the corner pin (7 or 10, 18 in out) and so every pin: ~23.2
#: boards, off the lane (a ball on the lane at the pins always meets one).
PINS_REACH = HEAD_PIN_REACH + 18.0 / (41.5 / 39)
#: Pin spots on the lattice: (sideways, in half pin spacings, + towards board 1 of a right-hander
#: (the 3 pin's side); row, 0 = the head pin).
LATTICE = {1: (0, 0), 2: (-1, 1), 3: (1, 1), 4: (-2, 2), 5: (0, 2), 6: (2, 2), 7: (-3, 3), 8: (-1, 3), 9: (1, 3),
           10: (3, 3)}
#: A left-hander's pin for each right-hander's pin (the rack mirrored about the 1-5 line).
MIRROR = {1: 1, 2: 3, 3: 2, 4: 6, 5: 5, 6: 4, 7: 10, 8: 9, 9: 8, 10: 7}
_HALF_IN = 6.0   # half the pin spacing (in)
_ROW_IN = 12.0 * math.sqrt(3) / 2


def _xy(p: int) -> tuple[float, float]:
    a, r = LATTICE[p]
    return a * _HALF_IN, r * _ROW_IN


def _between(c: int, a: int, b: int) -> bool:
    (ax, ar), (bx, br), (cx, cr) = LATTICE[a], LATTICE[b], LATTICE[c]
    if not (min(ax, bx) < cx < max(ax, bx) and min(ar, br) <= cr <= max(ar, br)):
        return False
    (x0, y0), (x1, y1), (x, y) = _xy(a), _xy(b), _xy(c)
    dx, dy = x1 - x0, y1 - y0
    return abs(dx * (y - y0) - dy * (x - x0)) / math.hypot(dx, dy) <= _HALF_IN + 1e-9


def _gap(standing: set) -> bool:
    """USBC's (a) or (b) on the pins ``standing`` (right-handed numbers), the head pin aside."""
    down = set(LATTICE) - standing
    st = sorted(standing)
    for i, a in enumerate(st):
        for b in st[i + 1:]:
            if any(_between(c, a, b) for c in down):
                return True
            (ax, ar), (bx, br) = LATTICE[a], LATTICE[b]
            if ar == br and abs(ax - bx) == 2:   # side by side: the pin immediately ahead of both
                ahead = next((p for p, v in LATTICE.items() if v == ((ax + bx) // 2, ar - 1)), None)
                if ahead in down:
                    return True
    return False


def _rh(pins, hand: str) -> set:
    return {MIRROR[int(p)] for p in pins} if hand == "left" else {int(p) for p in pins}


def is_split(leave, hand: str = "right") -> bool:
    """Whether the pins ``leave`` (standing after the first ball) are a split (USBC; see the module)."""
    s = _rh(leave, hand)
    return 1 not in s and len(s) >= 2 and _gap(s)


def is_washout(leave, hand: str = "right") -> bool:
    """A washout: the head pin standing with a gap that would make the leave a split without it."""
    s = _rh(leave, hand)
    return 1 in s and len(s) >= 3 and _gap(s)


#: Named leaves (right-handed pin numbers; a left-hander's are mirrored).
NAMED = {
    (7, 10): "bedposts", (2, 7): "baby split", (3, 10): "baby split", (4, 6, 7, 10): "big four",
    (4, 6, 7, 8, 10): "greek church", (4, 6, 7, 9, 10): "greek church", (2, 4, 5, 8): "bucket",
    (3, 5, 6, 9): "bucket", (1, 2, 4, 7): "picket fence", (1, 3, 6, 10): "picket fence", (2, 8): "sleeper",
    (3, 9): "sleeper", (1, 5): "sleeper", (5, 7, 10): "lily",
}


def hit_name(board: float | None, hand: str = "right") -> str | None:
    """The hit, from the ball's board at the head pin's line (boards counted from the bowling hand's
    edge, so a left-hander's pocket is on boards 17-18 too; ``hand`` names the sides of a wide
    ball); None without a board."""
    if board is None or not math.isfinite(board):
        return None
    b = float(board)
    off = abs(b - HEAD_PIN_BOARD)
    near = b < HEAD_PIN_BOARD   # the bowling hand's side (a right-hander's right)
    side = ("right" if hand == "right" else "left") if near else ("left" if hand == "right" else "right")
    if off > PINS_REACH:
        return f"missed the pins {side}"
    if off > FRONT_REACH:   # past the 2/3 pin: only the 4-7 or 6-10 side of the rack (the pins as numbered)
        return f"wide {side}, missed the head pin and the {3 if side == 'right' else 2} pin"
    if off > HEAD_PIN_REACH:
        return "light, missed the head pin" if near else "Brooklyn, missed the head pin"
    if b < POCKET[0]:
        return "light"
    if b <= POCKET[1]:
        return "pocket"
    if b < HEAD_PIN_BOARD - 1.0:
        return "high"
    if b <= HEAD_PIN_BOARD + 1.0:
        return "nose"
    return "Brooklyn"


def leave_names(standing, leave, board: float | None = None, angle: float | None = None,
                hand: str = "right") -> list[str]:
    """The leave's names (see the module): ``standing`` the pins before the throw, ``leave`` those
    still standing; ``board``/``angle`` the ball's at the head pin's line (for the corner pins)."""
    lv = sorted(int(p) for p in leave)
    if not lv:
        full = len(set(standing)) == 10
        return ["strike"] if full else ["converted"]
    rh = tuple(sorted(_rh(lv, hand)))
    out = []
    full = len(set(standing)) == 10
    mir = (lambda p: MIRROR[p]) if hand == "left" else (lambda p: p)
    if full and is_split(lv, hand):
        out.append("split")
    if full and is_washout(lv, hand):
        out.append("washout")
    if rh in NAMED:
        out.append(NAMED[rh])
    hit = hit_name(board, hand)
    if full and rh == (10,) and hit is not None:
        corner = mir(10)
        if angle is not None and angle < FLAT_DEG:
            out.append(f"flat {corner}")
        elif hit == "pocket":
            out.append(f"solid {corner}")
        else:
            out.append(f"ringing {corner}")
    if full and rh == (4,) and hit == "pocket":
        out.append(f"solid {mir(4)}")
    if not out and len(lv) == 1:
        out.append(f"{lv[0]} pin")
    return out


def names(standing, leave, board: float | None = None, angle: float | None = None, hand: str = "right") -> dict:
    """``{"hit": ..., "angle": "flat" | None, "leave": [...]}`` for a frame (see the module); the hit
    and angle are named for a strike ball (a full rack) only, None for a spare ball."""
    full = len(set(standing)) == 10
    flat = "flat" if full and angle is not None and math.isfinite(angle) and angle < FLAT_DEG else None
    return {"hit": hit_name(board, hand) if full else None, "angle": flat,
            "leave": leave_names(standing, leave, board, angle, hand)}


def text(n: dict) -> str:
    """One phrase: ``light, ringing 10`` / ``pocket, strike`` / ``split, bedposts``."""
    parts = [] if n.get("hit") is None else [n["hit"] + (" and flat" if n.get("angle") else "")]
    return ", ".join(parts + list(n.get("leave") or [])) or "no names"
