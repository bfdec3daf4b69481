"""What bowlers ask of a lane: the pocket map, carry, and the best throw at any spare leave.

* **Aiming** (:func:`aim_entry`): a delivery that reaches a given board at the head pin's line
  with a given entry angle. The release is the typical one (:data:`STRIKE`: 17 mph, 350 rpm,
  12 deg tilt); the axis rotation (which sets the entry angle) and the launch angle (which
  sets the board) are found by Newton's method with finite differences on :func:`.lane.throw`
  (the ball alone), started from the nearest throws of a coarse table over foul board,
  rotation and launch angle.
* **Pocket map** (:func:`pocket_map`): for each (board, entry angle) cell, the strike
  probability of the aimed delivery under the release noise of :mod:`.noise`. The same noisy
  frames, pooled and binned by where each ball actually crossed the deck front (its board
  carried to the head pin's line, and its heading), give the strike share by actual entry:
  **carry**, the share of pocket hits (actual board 17-18, the USBC pocket) that strike.
* **Spares** (:func:`best_spare`): for a leave (any pins standing but all ten; the common ones
  of :data:`LEAVES` have their aim pins and 3-6-9 moves tabled, others aim at the mean of
  their pins, :func:`leave_spec`), candidate throws are the 3-6-9 system's line
  (:func:`system_369`) with the strike ball (a bowler's, when given), and a straight spare ball (end over end, 200 rpm):
  cross-lane at 17 and 21 mph at the leave's aim point and at points 1 and 2 boards either
  side (3 too at 17 mph on a multi-pin leave), and at 17 mph from the middle (board 20) and
  from the aim point's own board (straight down the boards) at the aim point and 1 board
  either side. Each is screened on a few noisy throws, the best three on more and on the
  timestep ladder (:func:`best_spare`); the pick is then **polished** by
  :func:`.robust.maximise` (an evolution strategy over the release on common noisy throws,
  ``polish`` frames) unless it converted every screening throw, or no candidate converted
  any (nothing to climb); the polished throw, if it keeps its outcome on the ladder,
  replaces the pick. The pick is measured afresh on ``n``, before and after the polish.
* **Splits and the count** (issue 48): on a leave of several pins the candidates also hold the
  **slide** (:func:`slide_at`: the straight spare ball through the spot where, touching a front
  pin, the line of centres points at a pin behind it, so the front pin is driven into the back
  one: the 4 into the 9) and, for the count, the straight ball at **each pin alone**. Every
  candidate is ranked by its conversions, then by the **pins it takes** (the mean over its
  noisy throws, :func:`pins_estimate`), and the final pick on the measured throws, the same for
  each line measured (the screening's best three, the 3-6-9 line, the lines for the count).
  Where no candidate converts a single screening throw the
  pick is the line that takes the most pins, and :class:`SpareResult` says so (``converts``
  False); the line taking the most pins is also measured beside the pick (``most_pins``).

The 3-6-9 system (talkbowling.co.uk, "Spare systems"): keep the strike line's target arrow
and move the feet 3 boards (2 pin), 6 (4 pin) or 9 (7 pin) towards the hand side for the
left-side pins. For the right-side pins the source gives no moves; we mirror them (3 boards
the other way for the 3 pin, 6 for the 6 pin, 9 for the 10 pin): an assumption. Boards are
moved at the foul line, the release board standing in for the feet.

Compute only: no files, no printing.

Length: the spare lines (straight, slide, each pin alone) and their ranking by conversions and
pins are one decision; split, the ranking would read lines it cannot see.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace

import numpy as np

from nbst.errors import SolveError
from nbst.models.bowling import lane, scene
from nbst.models.bowling import pin as pinmod
from nbst.models.bowling.lane import frame, noise, robust

__all__ = ["STRIKE", "STRIKE_FOUL", "STRIKE_ARROW", "SPARE_BALL", "POCKET_BOARDS", "POCKET_PEAK", "POCKET_CELL",
           "LEAVES", "leave_spec", "leave_pins", "TABLE_FOUL", "TABLE_ROTATION", "TABLE_ANGLE", "aim_table",
           "aim_entry", "PocketMap", "pocket_map", "system_369", "aim_point", "straight_at", "SpareResult",
           "MIRROR", "mirrored", "mirror_doc", "candidates", "candidate_count", "SCREEN", "POLISH_PER_SCREEN", "best_spare", "pocket_figure", "CONTACT_REACH", "slide_at",
           "pins_estimate"]

#: The strike line: the typical (league-200) release, 17 mph, 350 rpm, 45 deg rotation, 12 deg tilt,
#: from board 20 at the foul line, 2.82 deg out: the ball alone reaches board 17.5 at the head pin
#: (docs/bowling.md; ``phases.aim_angle``). Its target arrow is where the straight line crosses the arrows.
STRIKE = lane.Delivery(board=20.0, at="foul", angle=2.82, mph=17.0, rpm=350.0, rotation=45.0, tilt=12.0)
STRIKE_FOUL = STRIKE.foul_board()
STRIKE_ARROW = STRIKE_FOUL - math.tan(math.radians(STRIKE.angle)) * lane.ARROWS_FT * lane.FT / lane.BOARD_WIDTH
#: The straight spare ball: end over end, no tilt, 200 rpm, 17 mph.
SPARE_BALL = dict(mph=17.0, rpm=200.0, rotation=0.0, tilt=0.0)
#: The USBC pocket: boards 17-18 at 4-6 deg entry; board 17.5 at ~6 deg is the published peak.
POCKET_BOARDS = (17.0, 18.0)
POCKET_PEAK = (17.5, 6.0)
#: The published pocket's cell: the typical release (17 mph, 350 rpm, tilt 12) aimed at board 17.5
#: at 6 deg by the launch angle and the axis rotation (``aim_entry(17.5, 6.0)``; it strikes without noise).
POCKET_CELL = lane.Delivery(board=26.0, at="foul", angle=3.4196087627856704, mph=17.0, rpm=350.0,
                            rotation=77.99200056425856, tilt=12.0)

#: The common leaves of issue 22 (pins standing), the pins whose mean is the aim point, and the
#: 3-6-9 system's move of the feet in boards (+ towards the hand side, as the system's "right").
LEAVES = {
    "10": ((10,), -9), "7": ((7,), 9), "4": ((4,), 6), "6": ((6,), -6), "2-4-5-8": ((2, 4, 5, 8), 3),
    "3-6-10": ((3, 6, 10), -3), "1-2-4": ((1, 2, 4), 3), "1-3-6": ((1, 3, 6), -3), "2-8": ((2, 8), 3),
    "3-9": ((3, 9), -3), "7-10": ((7,), 9),
}


def leave_spec(name: str) -> tuple[tuple, int]:
    """(the pins whose mean is the aim point, the 3-6-9 move in boards) of a leave: the table's for
    the common leaves (:data:`LEAVES`), else every pin standing, and 3 boards per half pin
    spacing of their mean off the 1-5 line (the system's 2/4/7 and 3/6/10 steps), at most 9."""
    if name in LEAVES:
        return LEAVES[name]
    pins = leave_pins(name)
    spots = scene.pin_spots()
    y = float(np.mean([spots[p - 1][1] for p in pins]))   # + towards the 7 pin (a right-hander's left)
    halves = int(round(y / (scene.PIN_SPACING / 2)))
    return tuple(pins), int(max(-9, min(9, 3 * halves)))


def leave_pins(name: str) -> list[int]:
    try:
        pins = sorted(int(p) for p in name.split("-"))
    except ValueError:
        raise lane.LaneError(f"leave: pins must be numbers 1..10 joined by '-', got {name!r}") from None
    if not pins or any(not 1 <= p <= 10 for p in pins) or len(set(pins)) != len(pins):
        raise lane.LaneError(f"leave: pins must be distinct numbers 1..10 joined by '-', got {name!r}")
    return pins


# --------------------------------------------------------------------------- aiming


#: The coarse table that starts :func:`aim_entry`'s search: foul boards, axis rotations (more
#: rotation hooks harder: the entry angle's knob) and launch angles.
TABLE_FOUL = (16.0, STRIKE_FOUL, 23.0, 26.0)
TABLE_ROTATION = tuple(range(10, 91, 10))
TABLE_ANGLE = tuple(np.arange(-1.0, 5.01, 0.5))


def aim_table(oil: str = "house", ball: lane.Ball | None = None, base: lane.Delivery = STRIKE) -> list:
    """(foul board, rotation, angle, board at the pins, entry angle) of every throw of the coarse
    table that reaches the pins (~470 ball-alone throws, ~15 s)."""
    key = (oil, ball, base)
    if key not in _TABLES:
        rows = []
        for foul in TABLE_FOUL:
            for rot in TABLE_ROTATION:
                for ang in TABLE_ANGLE:
                    d = replace(base, board=float(foul), at="foul", rotation=float(rot), angle=float(ang))
                    try:
                        d.check()
                        r = lane.throw(d, oil, ball)
                    except lane.LaneError:
                        continue
                    rows.append((float(foul), float(rot), float(ang), r.board_at_pins, r.entry_angle_deg))
        _TABLES[key] = rows
    return _TABLES[key]


_TABLES: dict = {}


def aim_entry(board: float, entry_deg: float, *, oil: str = "house", ball: lane.Ball | None = None,
              base: lane.Delivery = STRIKE, tol=(0.15, 0.2), iters: int = 8):
    """(delivery, ThrowResult): a release (the typical one's speed, revs and tilt) whose ball,
    alone, crosses the head pin's line on ``board`` at ``entry_deg``: from the nearest throws of
    :func:`aim_table`, Newton's method on (axis rotation, launch angle) at their foul board; SolveError
    (one line) when none converges."""
    table = aim_table(oil, ball, base)
    near = sorted(table, key=lambda t: (t[3] - board) ** 2 + (4 * (t[4] - entry_deg)) ** 2)[:3]
    step = np.array([2.0, 0.05])
    lo, hi = np.array([0.0, -6.0]), np.array([90.0, 6.0])
    for foul, rot0, ang0, _, _ in near:

        def f(v):
            d = replace(base, board=foul, at="foul", rotation=float(v[0]), angle=float(v[1]))
            r = lane.throw(d, oil, ball)
            return np.array([r.board_at_pins - board, r.entry_angle_deg - entry_deg]), d, r

        x = np.array([rot0, ang0])
        for _ in range(iters):
            try:
                e, d, r = f(x)
                if abs(e[0]) <= tol[0] and abs(e[1]) <= tol[1]:
                    return d, r
                J = np.empty((2, 2))
                for j in range(2):
                    J[:, j] = (f(x + step * np.eye(2)[j])[0] - e) / step[j]
                dx = np.linalg.solve(J, -e)
            except (lane.LaneError, np.linalg.LinAlgError):
                break
            x = np.clip(x + np.clip(dx, -np.array([10.0, 0.5]), np.array([10.0, 0.5])), lo, hi)
    raise SolveError(f"aim: no release reaches board {board:g} at {entry_deg:g} deg (from the {len(near)} nearest "
                     f"table throws, {iters} Newton steps each)")


# --------------------------------------------------------------------------- pocket map


@dataclass
class PocketMap:
    boards: list
    angles: list
    p: np.ndarray  # (len(angles), len(boards)) strike probability of the aimed throw, NaN if not aimed
    k: np.ndarray
    n: int
    deliveries: dict  # "board,angle" -> delivery dict
    hits: list  # (actual board, actual entry angle, strike) of every noisy frame
    seed: int
    noise: dict

    def carry(self, boards=POCKET_BOARDS, angles=None) -> tuple[int, int]:
        """(strikes, pocket hits): frames whose ball actually crossed on ``boards`` (and angles)."""
        sel = [h for h in self.hits if h[0] is not None and boards[0] <= h[0] <= boards[1]
               and (angles is None or angles[0] <= h[1] <= angles[1])]
        return sum(1 for h in sel if h[2]), len(sel)

    def best(self):
        """(board, angle, p, k) of the best aimed cell."""
        j, i = np.unravel_index(np.nanargmax(self.p), self.p.shape)
        return self.boards[i], self.angles[j], float(self.p[j, i]), int(self.k[j, i])

    def to_dict(self) -> dict:
        d = asdict(self)
        d["p"] = [[None if not np.isfinite(v) else float(v) for v in row] for row in self.p]
        d["k"] = self.k.tolist()
        return d


def pocket_map(boards, angles, n: int, seed: int, *, runner: frame.FrameRunner, nz: noise.Noise = noise.DEFAULT,
               on_cell=None, on_done=None, base: lane.Delivery = STRIKE) -> PocketMap:
    """Strike probability over (board at the pins x entry angle), ``n`` noisy throws per cell
    (cell c's throws are seeded ``seed + c``); ``base``: the release aimed (its speed, revs, tilt).

    Args:
        boards: boards at the head pin's line, the map's columns.
        angles: entry angles (deg), its rows.
        n: noisy throws per cell.
        seed: the seed of the first cell.
        runner: the :class:`.frame.FrameRunner`.
        nz: the release noise.
        on_cell: called with (board, angle, estimate or None: no release reaches the cell) per cell.
        on_done: called after each frame.
        base: the release aimed at each cell.

    Returns:
        a :class:`PocketMap`: p (len(angles), len(boards)) float64 array (NaN where no release
        reaches the cell) and its counts.
    """
    p = np.full((len(angles), len(boards)), np.nan)
    k = np.zeros((len(angles), len(boards)), dtype=int)
    deliveries, hits = {}, []
    c = 0
    for j, a in enumerate(angles):
        for i, b in enumerate(boards):
            try:
                d, _ = aim_entry(b, a, oil=runner.oil, ball=runner.ball, base=base)
            except SolveError:
                c += 1
                if on_cell is not None:
                    on_cell(b, a, None)
                continue
            deliveries[f"{b:g},{a:g}"] = d.to_dict()
            est, res = noise.probability(d, n, seed + c, runner=runner, noise=nz, on_done=on_done)
            p[j, i], k[j, i] = est.p, est.k
            hits += [(r.board_at_pins, r.entry_angle_deg, r.strike) for r in res]
            c += 1
            if on_cell is not None:
                on_cell(b, a, est)
    return PocketMap(boards=list(boards), angles=list(angles), p=p, k=k, n=n, deliveries=deliveries, hits=hits,
                     seed=int(seed), noise=nz.to_dict())


# --------------------------------------------------------------------------- spares


def system_369(name: str, strike: lane.Delivery = STRIKE) -> lane.Delivery:
    """The 3-6-9 system's throw at a leave: the strike ball (default :data:`STRIKE`; a bowler's) from
    its foul board moved by the system's boards, over the same target arrow (its straight line's)."""
    _, move = leave_spec(name)
    s_foul = strike.foul_board()
    s_arrow = s_foul - math.tan(math.radians(strike.angle)) * lane.ARROWS_FT * lane.FT / lane.BOARD_WIDTH
    foul = float(np.clip(s_foul - move, 1.0, 39.0))
    angle = math.degrees(math.atan((foul - s_arrow) * lane.BOARD_WIDTH / (lane.ARROWS_FT * lane.FT)))
    return replace(strike, board=float(foul), at="foul", angle=float(angle))


def aim_point(pins) -> tuple[float, float]:
    """(x, y) of the mean of ``pins``' spots (m)."""
    spots = scene.pin_spots()
    xy = np.mean([spots[p - 1] for p in pins], axis=0)
    return float(xy[0]), float(xy[1])


def straight_at(x: float, y: float, *, hand: str = "right", oil: str = "house", ball=None, foul: float | None = None,
                mph: float = SPARE_BALL["mph"]) -> lane.Delivery:
    """The straight spare ball thrown through (x, y): from ``foul`` (default cross-lane: the aim's
    board mirrored about the middle), its angle corrected once on :func:`.lane.throw` so the ball
    alone crosses the head pin's line where the straight line does."""
    b_aim = float(lane.y_to_board(y, hand))
    foul = float(np.clip(40.0 - b_aim if foul is None else foul, 6.0, 34.0))
    y_f = float(lane.board_to_y(foul, hand))
    s = lane.hand_sign(hand)
    dx = x - lane.FOUL_LINE_X
    angle = math.degrees(math.atan2(-s * (y - y_f), dx))
    y0 = y_f + (y - y_f) * (0 - lane.FOUL_LINE_X) / dx  # the line at the head pin's line
    want = float(lane.y_to_board(y0, hand))
    d = lane.Delivery(hand=hand, board=foul, at="foul", angle=angle, **{**SPARE_BALL, "mph": float(mph)})
    try:
        got = lane.throw(d, oil, ball).board_at_pins
    except lane.LaneError:
        return d
    per_deg = math.radians(1.0) * (0 - lane.FOUL_LINE_X) / lane.BOARD_WIDTH  # boards per degree
    return replace(d, angle=float(np.clip(angle + (got - want) / per_deg, -10, 10)))


#: Besides the pick, the lines measured afresh for the count: this many of those that took the most
#: pins in the screening, and the best line at one pin alone (:func:`best_spare`).
COUNT_LINES = 2


@dataclass
class SpareResult:
    leave: str
    system_369: dict
    system_369_estimate: dict
    best: dict
    best_label: str
    estimate: dict
    candidates: list  # (label, screened k, n, mean pins taken in the screening)
    ladder: list  # the best throw without noise: (timestep, leave) at h = 1, 0.5, 0.25 ms, then ("+2 s", leave)
    screened: dict  # the screening's pick before the polish: label, delivery, fresh estimate (seed, n)
    polish: dict | None  # robust.maximise's account (None: not polished, see ``polish_note``)
    polish_note: str
    converts: bool = True  # some candidate converted a screening throw (False: the pick is for the count)
    pins: dict | None = None  # the pick's pins taken on the fresh measure (:func:`pins_estimate`)
    most_pins: dict | None = None  # the line taking the most pins: label, delivery, pins (fresh measure)
    ranked_note: str = ""  # where the measured throws ranked another line over the screening's pick

    def to_dict(self) -> dict:
        return asdict(self)


#: Centre to centre (m) of the ball and a pin touching, at the ball centre's height: the ball's radius
#: and the pin's, interpolated in the USBC profile (``pin.PROFILE_IN``: 4.71 in across at 4.25 in up).
CONTACT_REACH = scene.BALL_RADIUS + 0.5 * pinmod.INCH * float(np.interp(
    scene.BALL_RADIUS / pinmod.INCH, [h for h, _ in pinmod.PROFILE_IN], [dia for _, dia in pinmod.PROFILE_IN]))
#: Slides are tried on leaves of at most this many pins (a front pin driven into one behind it).
SLIDE_MAX_PINS = 4


def slide_at(front: int, back: int) -> tuple[float, float]:
    """(x, y) of the ball's centre (m) touching pin ``front`` so that the line of centres, the
    direction the pin is driven, points at pin ``back``: the front pin's spot less
    :data:`CONTACT_REACH` along the unit vector from the front pin to the back one.

    Args:
        front: the pin hit (1..10).
        back: the pin it should be driven into (1..10, not ``front``).

    Returns:
        (x, y) in the scene's frame (m); a straight ball through it, heading down the lane,
        touches ``front`` first there when the back pin is behind it.
    """
    spots = scene.pin_spots()
    a, b = np.asarray(spots[front - 1], float), np.asarray(spots[back - 1], float)
    u = (b - a) / np.linalg.norm(b - a)
    c = a - CONTACT_REACH * u
    return float(c[0]), float(c[1])


def _slides(pins) -> list[tuple[int, int]]:
    """(front, back) pairs of a leave's pins: the back pin a row or more behind the front one and off
    its line (a pin straight behind is the aim point's, not a slide)."""
    spots = scene.pin_spots()
    out = []
    for a in pins:
        for b in pins:
            dx, dy = spots[b - 1][0] - spots[a - 1][0], spots[b - 1][1] - spots[a - 1][1]
            if dx > 0.1 and abs(dy) > 0.1:
                out.append((a, b))
    return out


#: A left-hander's pins as a right-hander's on the mirror-image lane (the 7 for the 10, the 4 for the 6).
MIRROR = {1: 1, 2: 3, 3: 2, 4: 6, 5: 5, 6: 4, 7: 10, 8: 9, 9: 8, 10: 7}


def mirrored(name: str) -> str:
    """Leave ``name`` ('-' joined pins) seen from the other hand: the mirror image's pins, sorted."""
    return "-".join(map(str, sorted(MIRROR[p] for p in leave_pins(name))))


def mirror_doc(d: dict) -> dict:
    """A :class:`SpareResult`'s dict (worked out on the mirrored lane with ``mirror``) as the
    left-hander's: its leave and every leave of its ladder in the left-hander's pins, its
    deliveries left-handed (the same boards and angles, counted from the left-hander's gutter)."""
    out = dict(d)
    out["leave"] = mirrored(d["leave"])
    out["ladder"] = [[t, sorted(MIRROR[p] for p in lv)] for t, lv in d["ladder"]]
    for k in ("best", "system_369"):
        out[k] = {**d[k], "hand": "left"}
    for k in ("screened", "most_pins"):
        if isinstance(d.get(k), dict):
            out[k] = {**d[k], "delivery": {**d[k]["delivery"], "hand": "left"}}
    return out


def _plan(name: str, mirror: bool = False) -> list[tuple[str, float, float, float | None, float]]:
    """(kind, x, y, foul or None: cross-lane, mph) of every straight ball :func:`candidates` throws at
    leave ``name``, after the 3-6-9 line (no throw run: :func:`candidate_count` counts them);
    ``mirror``: the labels name the pins as a left-hander sees them (the lane mirrored)."""
    say = MIRROR if mirror else {p: p for p in MIRROR}
    key, _ = leave_spec(name)
    pins = leave_pins(name)
    x, y = aim_point(key)
    wide = (0.0, -1.0, 1.0, -2.0, 2.0) + ((-3.0, 3.0) if len(pins) > 1 else ())
    down_board = float(lane.y_to_board(y))  # straight down the boards: drives a front pin into the one behind
    edge = scene.LANE_WIDTH / 2 - 0.02
    out: list[tuple[str, float, float, float | None, float]] = []
    for offs, foul, mph in ((wide, None, 17.0), (wide[:5], None, 21.0), ((0.0, -1.0, 1.0), 20.0, 17.0),
                            ((0.0, -1.0, 1.0), down_board, 17.0)):
        for off in offs:
            yy = y + off * lane.BOARD_WIDTH
            if abs(yy) < edge:
                out.append(("straight", x, yy, foul, mph))
    if len(pins) > 1:
        if len(pins) <= SLIDE_MAX_PINS:
            for a, b in _slides(pins):
                sx, sy = slide_at(a, b)
                for foul2 in (None, float(lane.y_to_board(sy))):
                    for off in (0.0, -0.5, 0.5):
                        yy = sy + off * lane.BOARD_WIDTH
                        if abs(yy) < edge:
                            out.append((f"slide the {say[a]} into the {say[b]}", sx, yy, foul2, SPARE_BALL["mph"]))
        for p in pins:
            px, py = aim_point((p,))
            out.append((f"the {say[p]} alone", px, py, None, SPARE_BALL["mph"]))
    return out


def candidate_count(name: str) -> int:
    """How many throws :func:`candidates` tries at leave ``name`` (none run)."""
    return 1 + len(_plan(name))


def candidates(name: str, *, oil: str = "house", ball=None, strike: lane.Delivery = STRIKE,
               mirror: bool = False) -> list:
    """(label, delivery) of every throw :func:`best_spare` tries at leave ``name``: the 3-6-9 line
    (from ``strike``) first, then the straight spare balls (aim offsets up to 2 boards, 3 on a
    multi-pin leave); on a multi-pin leave also the slides (:func:`slide_at`, from across the lane
    and straight down the boards, on the spot and 1/2 board either side; leaves of at most
    :data:`SLIDE_MAX_PINS` pins) and the straight ball at each pin alone (for the count)."""
    out = [("3-6-9", system_369(name, strike))]
    for kind, x, y, foul, mph in _plan(name, mirror):
        d = straight_at(x, y, oil=oil, ball=ball, foul=foul, mph=mph)
        at = f"from board {d.board:.1f} aimed at board {lane.y_to_board(y):.1f}"
        out.append((f"straight {mph:g} mph {at}" if kind == "straight" else f"{kind}: straight {at}", d))
    return out


def pins_estimate(results, standing) -> dict:
    """The pins a line takes over noisy frames: the mean (of the pins in ``standing`` down), a 95 %
    interval, and how many frames took each count.

    The interval is the normal one, mean +- 1.96 s / sqrt(n), clipped to [0, pins standing]; where
    every frame took the same count k (s = 0) it is the range the Wilson interval of "takes k"
    allows, the other frames taking none or all: [k lo, k + (m - k)(1 - lo)], lo the Wilson
    lower bound of n in n.

    Args:
        results: the :class:`.frame.FrameResult` of the noisy frames (at least one).
        standing: the pins standing before the throw.

    Returns:
        {"mean", "lo", "hi", "n", "of", "counts"}: ``of`` the pins standing, ``counts`` the frames
        per pins taken ({"1": 11, "0": 1}).
    """
    m = len(standing)
    took = np.array([len(r.down) for r in results], dtype=float)
    n = len(took)
    mean = float(took.mean())
    sd = float(took.std(ddof=1)) if n > 1 else 0.0
    if sd > 0:
        lo, hi = mean - noise.Z95 * sd / math.sqrt(n), mean + noise.Z95 * sd / math.sqrt(n)
    else:
        w = noise.wilson(n, n)[0]
        lo, hi = mean * w, mean + (m - mean) * (1 - w)
    counts: dict = {}
    for t in sorted(took, reverse=True):
        counts[str(int(t))] = counts.get(str(int(t)), 0) + 1
    return {"mean": mean, "lo": float(max(0.0, lo)), "hi": float(min(m, hi)), "n": n, "of": m, "counts": counts}


#: Noisy throws per candidate in the screening when none is given (``bowl spares|advise --screen``'s default).
SCREEN = 12
#: The polish's default budget, in frames per leave: this many times ``screen``.
POLISH_PER_SCREEN = 40


def best_spare(name: str, n: int, seed: int, *, runner: frame.FrameRunner, screen: int = SCREEN,
               nz: noise.Noise = noise.DEFAULT, on_done=None, polish: int | None = None,
               strike: lane.Delivery | None = None, mirror: bool = False) -> SpareResult:
    """The candidate of :func:`candidates` that converts leave ``name`` best. Screening: ``screen``
    noisy throws each; the best three get ``2 * screen`` more and their noise-free throw is run
    at h = 1, 0.5 and 0.25 ms; the pick is the most conversions among those three whose ladder
    converts at every step (any of the three if none does), ties going to the most pins taken.
    Its probability is then measured afresh on ``n`` throws (seed ``seed``; screening used other
    seeds), as are the 3-6-9 line's and the other two of the three, and so are the pins each takes
    (:func:`pins_estimate`). Where no candidate converted a screening throw, the pick is the line
    taking the most pins (``converts`` False). For the count, the :data:`COUNT_LINES` other lines
    that took the most pins in the screening and the best line at one pin alone are measured on the
    same ``n`` throws; ``most_pins`` is the measured line that takes the most there (a coach's 4-9:
    the slide 0.95 pins a throw against the 9 alone's 1.0; a 4-10 whose slide took 1.5 pins over 6
    screening throws and 0.2 on 20 fresh ones, against the 4 alone's 1.0). Where any measured line
    converted, the pick is the measured line that converts the most of those same throws, then
    takes the most pins (``ranked_note`` says when that is not the screening's pick: a coach's 4-9
    at ``--screen 12``, 19 of 40 against a second slide's 22), so no line measured beside it
    converts more.

    **Polish**: :func:`.robust.maximise` from the pick, ``polish`` noisy frames (default
    ``POLISH_PER_SCREEN * screen``; 0: none), fresh estimate on ``n`` throws of seed ``seed``
    (the same throws' noise as the pick's measurement: a paired before/after). Skipped when the
    pick converted all of its ``3 * screen`` screening throws, or no candidate converted any.
    The polished throw replaces the pick when its noise-free throw converts at every timestep
    of the ladder and it ranks no lower on the measured throws (conversions, then pins).

    Args:
        name: the leave, pins standing joined by '-' ("3-10").
        n: throws of each fresh measure.
        seed: the seed of the measures (the screening uses seeds derived from it).
        runner: the :class:`.frame.FrameRunner` (its oil and ball).
        screen: noisy throws per candidate in the screening.
        nz: the release noise.
        on_done: called after each frame.
        polish: noisy frames of the polish (None: ``POLISH_PER_SCREEN * screen``; 0: none).
        strike: the bowler's strike ball, for the 3-6-9 line (None: :data:`STRIKE`).

    Returns:
        a :class:`SpareResult`.

    Raises:
        LaneError: a leave that is not distinct pins 1..10, or all ten.
    """
    standing = leave_pins(name)
    if len(standing) == 10:
        raise lane.LaneError(f"leave: {name!r} is all ten pins: a first ball, not a spare")
    cands = candidates(name, oil=runner.oil, ball=runner.ball, strike=STRIKE if strike is None else strike,
                       mirror=mirror)
    k, took = {}, {}
    for c, (label, d) in enumerate(cands):
        est, rs = noise.probability(d, screen, seed + 1000 + c, runner=runner, standing=standing, noise=nz,
                                    on_done=on_done)
        k[c] = [est.k, screen]
        took[c] = [len(r.down) for r in rs]
    top = sorted(k, key=lambda c: (-k[c][0], -float(np.mean(took[c])), c))[:3]
    ladders = {}
    for c in top:
        est, rs = noise.probability(cands[c][1], 2 * screen, seed + 2000 + c, runner=runner, standing=standing,
                                    noise=nz, on_done=on_done)
        k[c] = [k[c][0] + est.k, 3 * screen]
        took[c] += [len(r.down) for r in rs]
        ladders[c] = [[r.timestep, r.leave] for r in frame.ladder(cands[c][1], runner.oil, runner.ball,
                                                                  standing=standing)]
    converts = any(k[c][0] for c in k)
    holds = [c for c in top if all(not lv for _, lv in ladders[c])]
    best_i = max(holds or top, key=lambda c: (k[c][0], float(np.mean(took[c])), -c))
    # the measured throws (the same n throws of seed ``seed`` for each line): the 3-6-9 line, the screening's
    # top three, and for the count the lines that took the most pins in the screening (a screening of a few
    # throws flatters a lucky line: a slide at 1.5 pins over 6 throws took 0.2 on 20): the two best others and
    # the best line at one pin alone (a sure pin)
    def most_key(c):
        return float(np.mean(took[c])), " alone: " in cands[c][0], -c

    others = sorted((c for c in k if c != best_i), key=most_key, reverse=True)
    alone = [c for c in others if " alone: " in cands[c][0]]
    tried = list(dict.fromkeys(others[:COUNT_LINES] + alone[:1]))
    measured = {}
    for c in dict.fromkeys([0, best_i, *top, *tried]):
        measured[c] = noise.probability(cands[c][1], n, seed, runner=runner, standing=standing, noise=nz,
                                        on_done=on_done)
    e369 = measured[0][0]
    fresh = {c: pins_estimate(rs, standing) for c, (_, rs) in measured.items()}
    # the pick is ranked on those throws, conversions then pins (docs/bowling.md), where any converted: the
    # screening's pick is kept only when no measured line beats it (a coach's 4-9: 19/40 against 22/40)
    ranked_note = ""
    if any(measured[c][0].k for c in measured):
        pick = max(measured, key=lambda c: (measured[c][0].k, fresh[c]["mean"], c == best_i, c in holds, -c))
        if pick != best_i:
            ranked_note = (f"ranked on the same {n} measured throws: {cands[pick][0]} converted {measured[pick][0].k} "
                           f"({fresh[pick]['mean']:.2f} pins a throw) against {measured[best_i][0].k} "
                           f"({fresh[best_i]['mean']:.2f}) for the screening's pick, {cands[best_i][0]}")
            best_i = pick
            if pick not in ladders:
                ladders[pick] = [[r.timestep, r.leave] for r in frame.ladder(cands[pick][1], runner.oil, runner.ball,
                                                                             standing=standing)]
    converts = converts or any(measured[c][0].k for c in measured)
    eb, pins = measured[best_i][0], fresh[best_i]
    # the count: the most fresh pins (ties to the pick, then a line at one pin alone, then the first)
    most_i = max(fresh, key=lambda c: (fresh[c]["mean"], c == best_i, " alone: " in cands[c][0], -c))
    most = {"label": cands[most_i][0], "delivery": cands[most_i][1].to_dict(), "pins": fresh[most_i]}
    best, label, lad0 = cands[best_i][1], cands[best_i][0], ladders[best_i]
    screened = {"label": label, "delivery": best.to_dict(), "estimate": eb.to_dict()}
    budget = POLISH_PER_SCREEN * screen if polish is None else int(polish)
    pol, note = None, ""
    if budget <= 0:
        note = "not polished: --polish 0"
    elif k[best_i][0] == k[best_i][1]:
        note = f"not polished: the pick converted all {k[best_i][1]} of its screening throws"
    elif all(k[c][0] == 0 for c in k):
        note = "not polished: no candidate converted any screening throw (nothing to climb)"
    else:
        rr = robust.maximise(best, standing=standing, runner=runner, budget=budget, seed=seed, noise=nz,
                             on_done=on_done, n=n)
        pol = {"budget": budget, "frames": rr.frames, "start_screen": rr.start_screen.to_dict(),
               "screen": rr.screen.to_dict(), "ladder_holds": rr.ladder_holds,
               "generations": len(rr.history) - 1, "accepted": sum(1 for h in rr.history[1:] if h["accepted"])}
        moved = rr.delivery != rr.start
        if moved and rr.ladder_holds:   # kept where it ranks no lower on the same measured throws
            ep, rp = noise.probability(rr.delivery, n, seed, runner=runner, standing=standing, noise=nz,
                                       on_done=on_done)
            pp = pins_estimate(rp, standing)
            if (ep.k, pp["mean"]) >= (eb.k, pins["mean"]):
                best, label, lad0, eb, pins = rr.delivery, f"polished {label}", [x[:2] for x in rr.ladder], ep, pp
                note = "polished: the pick of robust.maximise replaces the screening's"
            else:
                note = (f"polished: the polished release converted {ep.k} of the {n} measured throws "
                        f"({pp['mean']:.2f} pins a throw) against the pick's {eb.k}; the pick stays")
        elif moved:
            note = "polished: no better release kept its outcome on the ladder; the screening's pick stays"
        else:
            note = "polished: no better release found on the polish's screen; the screening's pick stays"
    lad = lad0 + [["+2 s", frame.run_frame(best, runner.oil, runner.ball, standing=standing, extra_s=2.0).leave]]
    return SpareResult(leave=name, system_369=cands[0][1].to_dict(), system_369_estimate=e369.to_dict(),
                       best=best.to_dict(), best_label=label, estimate=eb.to_dict(),
                       candidates=[[cands[c][0], *k[c], float(np.mean(took[c]))] for c in range(len(cands))],
                       ladder=lad, screened=screened, polish=pol, polish_note=note, converts=converts, pins=pins,
                       most_pins=most, ranked_note=ranked_note)


# --------------------------------------------------------------------------- the picture


def pocket_figure(pm: PocketMap, *, title: str = ""):
    """A matplotlib Figure: left, the strike probability of the aimed throw per (board, entry
    angle) cell; right, the strike share of all its noisy frames binned by where each ball
    actually entered. The published pocket (board 17.5, ~6 deg) is marked on both."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(13, 5.6), dpi=100, layout="constrained")
    axs = fig.subplots(1, 2)
    db = pm.boards[1] - pm.boards[0] if len(pm.boards) > 1 else 1.0
    da = pm.angles[1] - pm.angles[0] if len(pm.angles) > 1 else 1.0
    ext = (pm.boards[0] - db / 2, pm.boards[-1] + db / 2, pm.angles[0] - da / 2, pm.angles[-1] + da / 2)
    im = axs[0].imshow(np.ma.masked_invalid(pm.p), origin="lower", extent=ext, aspect="auto", vmin=0, vmax=1,
                       cmap="viridis")
    for j, a in enumerate(pm.angles):
        for i, b in enumerate(pm.boards):
            v = pm.p[j, i]
            axs[0].text(b, a, "not\naimed" if not np.isfinite(v) else f"{100 * v:.0f}%", ha="center", va="center",
                        fontsize=7, color="white" if not np.isfinite(v) or v < 0.6 else "black")
    axs[0].set_title(f"aimed at the cell: strike probability\n({pm.n} noisy throws per cell; blank: no release aimed)",
                     fontsize=9)
    # actual entry, binned on the same grid
    k = np.zeros((len(pm.angles), len(pm.boards)))
    n = np.zeros_like(k)
    for b, a, s in pm.hits:
        if b is None:
            continue
        i, j = int(round((b - pm.boards[0]) / db)), int(round((a - pm.angles[0]) / da))
        if 0 <= i < len(pm.boards) and 0 <= j < len(pm.angles):
            n[j, i] += 1
            k[j, i] += s
    share = np.where(n >= 5, k / np.maximum(n, 1), np.nan)
    axs[1].imshow(np.ma.masked_invalid(share), origin="lower", extent=ext, aspect="auto", vmin=0, vmax=1,
                  cmap="viridis")
    for j, a in enumerate(pm.angles):
        for i, b in enumerate(pm.boards):
            txt = f"{100 * share[j, i]:.0f}%\nn={int(n[j, i])}" if np.isfinite(share[j, i]) else f"n={int(n[j, i])}"
            axs[1].text(b, a, txt, ha="center", va="center", fontsize=7,
                        color="white" if not np.isfinite(share[j, i]) or share[j, i] < 0.6 else "black")
    axs[1].set_title("every frame binned by where the ball actually entered:\nstrike share and frames n (shown when n >= 5)",
                     fontsize=9)
    for ax in axs:
        ax.plot(*POCKET_PEAK, marker="*", ms=16, mfc="none", mec="red", mew=1.5, ls="none",
                label="published pocket: board 17.5, ~6 deg (USBC)")
        ax.set_xlabel("board at the head pin (right-hander; 17.5 = pocket, 20 = head pin)")
        ax.set_ylabel("entry angle (deg)")
        ax.set_xticks(pm.boards)
        ax.set_yticks(pm.angles)
    fig.legend(*axs[0].get_legend_handles_labels(), loc="outside lower center", fontsize=8)
    fig.colorbar(im, ax=list(axs), label="strike probability", shrink=0.9)
    fig.suptitle(title or "Pocket map from the foul line (house oil, 17 mph, 350 rpm, default release noise)",
                 fontsize=11)
    return fig
