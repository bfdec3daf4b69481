"""Lane transition: games bowled in order on one lane whose oil every ball wears (issue 34).

* **The lane** is one :class:`.oil.OilField`, fresh from the pattern at the start of a run.
  Every ball (strike and spare balls alike) is a frame of :func:`.frame.run_frame` on it: its
  track takes oil onto the cover and lays some down where the lane is drier than the cover's
  ring (carry-down past the pattern's end), the cover absorbs part of it, and the bowler wipes
  the ball before the next throw (each ball starts with a dry cover; :mod:`.friction`). The
  grid is the lane's own, not the hand's, so a left-hander plays the mirrored side: fresh oil
  for the other hand.
* **The bowlers** (:func:`lineup`): a profile (:mod:`.profiles`), ``n`` bowlers alternating
  frames as in league play, a share of them left-handed. Each throws the profile's strike ball
  (the line it was aimed on over the fresh house shot) with the profile's correlated release
  noise (the strike ball's and, on a spare, the spare ball's: :meth:`.profiles.Profile.spare`),
  drawn from its own stream (``seed``, bowler): the same seed gives the same releases whether
  the bowler moves or not (common random numbers, a paired comparison).
* **Spares**: the straight spare ball (:data:`.spares.SPARE_BALL`, 17 mph, 200 rpm) through the
  middle of the leave, from across the lane, aimed once per leave on the fresh pattern (the
  bowler's spare system, :func:`.spares.straight_at`), under the same noise.
* **Moves** (``move``): ``"none"`` keeps the line; ``"auto"`` reads where the last
  :data:`MOVE_AFTER` strike balls crossed the head pin's line and, when their mean is more than
  :data:`MOVE_MISS` boards and its standard error high (left of the pocket for a right-hander)
  or light, makes the coach's "2 and 1" move: feet 2 boards and target 1 board in the same
  direction (in when high, out when light), one step per :data:`MOVE_BOARDS` boards of miss in
  half steps (:func:`move_for`). One such move shifts the pro's ball at the pins by about 2 boards (1.6-2.7,
  measured on the house shot fresh and after 10-30 identical balls, 2026-12-03; docs/bowling.md).
  A profile that ``reads_lane`` (off for every shipped profile) does not make the "2 and 1" step
  when the mover would move: it reads the lane as it is (:func:`.reading.read_line`: candidate lines with the
  feet moved -4..+4 boards, each re-aimed to the pocket, judged by the strikes its own release noise
  would give on lane's :data:`.reading.STRIKE_BY_BOARD`) and takes the best. Tried for the pro (issue 48,
  2026-12-07; docs/results/bowling.md): it does not gain.
* **Readings**: each ball's board and entry angle at the pins (the frame's), its breakpoint
  (the ball alone, :func:`.phases.throw`, on a copy of the lane as it was: the same ball path),
  whether a strike ball hit the pocket (:data:`POCKET`: boards 16.5-18.5, issue 34's window),
  the pins, and the oil it moved. :func:`summary` gives the per-game figures per hand, and
  :func:`score` USBC's score of a bowler's game.

A run is a plain dict (the series file's ``runs`` entries, :func:`series_dict`); :class:`Run`
builds it ball by ball, so an interrupted run keeps every finished ball. Compute only: no files
written, no printing. Length: the series is one state machine (the lineup, its balls, moves and
the lane they wear) whose parts share the run's state; about 515 lines.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from nbst.models.bowling import lane, scene
from nbst.models.bowling.lane import frame, noise, phases, profiles, spares
from nbst.models.bowling.lane.reading import TARGET_BOARD, read_line
from nbst.models.bowling.lane.noise import Noise
from nbst.models.bowling.lane.oil import CELL_AREA, DX_FT, NX, OilField, OilLaw, Pattern, pattern

__all__ = ["FORMAT", "VERSION", "arrow_board", "MOVES", "POCKET", "TARGET_BOARD", "MOVE_FEET", "MOVE_TARGET", "MOVE_AFTER", "MOVE_MISS", "MOVE_BOARDS",
           "MOVE_SPREAD_SE", "PIN_SPREAD_THROWS", "PIN_SPREAD_SEED", "pin_spread",
           "MAX_GAMES", "MAX_LINEUP", "TransitionError", "Bowler", "lineup", "moved", "move_for",
           "spare_line", "score", "Run", "summary", "series_dict", "check_series", "film_along",
           "lay_band", "track_width", "depleted_share"]

FORMAT = "nbst-bowling-series"
VERSION = 1
MOVES = ("none", "auto")
#: A strike ball hits the pocket when it crosses the head pin's line on these boards (issue 34's window).
POCKET = (16.5, 18.5)
#: "2 and 1": feet and target boards of one move.
MOVE_FEET, MOVE_TARGET = 2.0, 1.0
#: A move follows the mean of the last MOVE_AFTER strike balls missing by more than MOVE_MISS boards and
#: more than its standard error; one "2 and 1" step per MOVE_BOARDS boards of miss, in half steps (issue 48).
MOVE_AFTER, MOVE_MISS = 4, 0.5
MOVE_BOARDS = 2.0
#: ... and more than this many standard errors of the bowler's own spread at the pins (:func:`pin_spread`):
#: a coach's "don't move until you repeat shots" (the league150's 4.0 boards against the pro's 0.64).
MOVE_SPREAD_SE = 2.0
#: :func:`pin_spread`'s noisy ball-alone throws and their seed.
PIN_SPREAD_THROWS, PIN_SPREAD_SEED = 40, 0
MAX_GAMES, MAX_LINEUP = 30, 8
#: Paths are kept every PATH_FT ft; oil maps rounded to MAP_DECIMALS (um).
PATH_FT = 0.5
MAP_DECIMALS = 6
#: The lane kept after each game (``oil.games``) is rounded to GAME_MAP_DECIMALS (um): a 30-game file stays small.
GAME_MAP_DECIMALS = 4
#: Draws per bowler and game: at most 21 balls (9 frames x 2 + 3 in the tenth).
_ROWS_PER_GAME = 21


class TransitionError(lane.LaneError):
    """Bad input to a series: one line naming the field."""


@dataclass(frozen=True)
class Bowler:
    """One bowler of the lineup: the profile's strike ball for ``hand`` and its noise."""

    index: int
    hand: str
    strike: lane.Delivery
    noise: Noise
    spare_noise: Noise | None = None
    reads_lane: bool = False


def lineup(profile: str, n: int = 1, lefty_share: float = 0.0, noise_scale: float = 1.0, oil="house",
           ball: lane.Ball | None = None) -> list[Bowler]:
    """``n`` bowlers of ``profile``, ``lefty_share`` of them left-handed (a whole number of them;
    the left-handers bowl after the right-handers in each frame). The strike ball is the profile's
    line, aimed again at board 17.5 on the fresh ``oil`` with ``ball`` when they are not the house
    shot and the default ball it was aimed for."""
    p = profiles.profile(profile)
    if not (isinstance(n, int) and 1 <= n <= MAX_LINEUP):
        raise TransitionError(f"lineup: must be a whole number of bowlers in 1..{MAX_LINEUP}, got {n!r}")
    if not (isinstance(lefty_share, (int, float)) and 0.0 <= lefty_share <= 1.0):
        raise TransitionError(f"lefty-share: must be a share in [0, 1], got {lefty_share!r}")
    lefties = lefty_share * n
    if abs(lefties - round(lefties)) > 1e-9:
        raise TransitionError(f"lefty-share: {lefty_share:g} of {n} bowler{'s' if n > 1 else ''} is {lefties:g} "
                              f"left-handers; give a share that makes a whole number (e.g. --lineup 4 --lefty-share 0.25)")
    k = int(round(lefties))
    nz = profiles.scaled(p.noise, float(noise_scale)).check()
    nzs = profiles.scaled(p.spare(), float(noise_scale)).check()
    ball = (ball or lane.Ball()).check()
    same = pattern(oil) == pattern("house") and ball == lane.Ball()
    line = {h: p.delivery(h) if same else profiles.strike_ball(profile, oil, ball, h) for h in {"right", "left"}}
    return [Bowler(i, "left" if i >= n - k else "right", line["left" if i >= n - k else "right"], nz, nzs,
                   reads_lane=p.reads_lane) for i in range(n)]


def pin_spread(strike: lane.Delivery, noise: Noise, oil="house", ball: lane.Ball | None = None) -> float:
    """The bowler's own scatter at the pins: the standard deviation (boards) of the board where
    ``strike`` crosses the head pin's line under ``noise`` on the fresh ``oil``, over
    :data:`PIN_SPREAD_THROWS` noisy ball-alone throws of seed :data:`PIN_SPREAD_SEED` (gutter balls
    left out; 0 when fewer than 2 reach the pins). About a second of one core; a left-hander's is
    the right-hander's mirror image (the same), and each is worked out once per process."""
    from nbst.models.bowling.lane import noise as _noise

    key: tuple | None = (replace(strike, hand="right"), noise, oil if isinstance(oil, (str, Pattern)) else str(oil),
                         ball)
    try:
        if key in _SPREADS:
            return _SPREADS[key]
    except TypeError:   # an unhashable oil: worked out each time
        key = None
    boards = []
    for d in _noise.sample(strike, PIN_SPREAD_THROWS, PIN_SPREAD_SEED, noise):
        try:
            boards.append(lane.throw(d, oil, ball).board_at_pins)
        except lane.LaneError:
            continue
    out = float(np.std(boards, ddof=1)) if len(boards) >= 2 else 0.0
    if key is not None:
        _SPREADS[key] = out
    return out


_SPREADS: dict = {}


def arrow_board(d: lane.Delivery) -> float:
    """The board ``d``'s straight line crosses at the arrows (its foul-line board and launch angle)."""
    return d.foul_board() - math.tan(math.radians(d.angle)) * lane.ARROWS_FT * lane.FT / lane.BOARD_WIDTH


def moved(strike: lane.Delivery, feet: float, target: float) -> lane.Delivery:
    """``strike`` with the feet moved ``feet`` boards and the target arrow ``target`` boards, in the
    bowler's own boards (+: in, away from the hand's gutter): the foul-line board and the launch
    angle of the line through the two."""
    fb = strike.foul_board() + feet
    ab = arrow_board(strike) + target
    angle = math.degrees(math.atan((fb - ab) * lane.BOARD_WIDTH / (lane.ARROWS_FT * lane.FT)))
    return replace(strike, board=float(fb), at="foul", angle=float(angle))


def move_for(boards, spread: float = 0.0) -> float:
    """The bowler's move after strike balls that crossed the head pin's line on ``boards`` (the
    latest last; None for a ball that never got there), in "2 and 1" steps: + in (the last
    MOVE_AFTER hit high on average), - out (light), 0 stay. A move needs the mean miss to exceed
    MOVE_MISS, its standard error, and MOVE_SPREAD_SE standard errors of the bowler's own
    ``spread`` at the pins (boards, :func:`pin_spread`): a miss the bowler's own scatter explains is
    not read as the lane's (issue 48: noise-driven moves cost a league bowler a game); its size is
    one step per MOVE_BOARDS boards of miss, rounded to a half step (feet 1 board, target 1/2), at
    least a half."""
    last = [b for b in list(boards)[-MOVE_AFTER:] if b is not None]
    if len(last) < MOVE_AFTER:
        return 0
    miss = float(np.mean(last)) - TARGET_BOARD
    se = float(np.std(last, ddof=1)) / math.sqrt(len(last))
    if abs(miss) <= max(MOVE_MISS, se, MOVE_SPREAD_SE * float(spread) / math.sqrt(len(last))):
        return 0
    return float(math.copysign(max(0.5, round(2 * abs(miss) / MOVE_BOARDS) / 2), miss))


#: How far to either side of a straight spare ball's line (its centre) a pin's spot may stand and
#: still be struck (m): the ball's radius plus the pin's widest (4.766 in across, USBC).
SPARE_REACH = scene.BALL_RADIUS + 0.5 * 4.766 * 0.0254


def spare_target(pins, hand: str) -> tuple[int, ...]:
    """The pins of a leave the series' spare ball is aimed through (its middle: :func:`spare_line`):
    of the leave's pins and every group of them, the one whose middle has the most pins within
    :data:`SPARE_REACH` of it, across the lane (ties: the whole leave, then the larger group, then
    the one nearer the lane's middle, then the one on the side away from the bowler's hand, which
    a cross-lane ball reaches best). A leave whose middle a ball can reach with a pin keeps it (the
    3-10, the 4-7; a slide of one pin into another can come of it); at a wide split, whose middle
    is bare wood (the 4-10, the 7-10), the ball takes a pin for the count, as a coach would."""
    pins = sorted(int(p) for p in pins)
    spots = scene.pin_spots()
    ys = {p: float(spots[p - 1][1]) for p in pins}
    s = lane.hand_sign(hand)
    groups = [tuple(p for k, p in enumerate(pins) if m >> k & 1) for m in range(1, 1 << min(len(pins), 10))]

    def rank(g: tuple[int, ...]) -> tuple:
        mid = float(np.mean([ys[p] for p in g]))
        reached = sum(1 for p in pins if abs(ys[p] - mid) <= SPARE_REACH)
        return (reached, len(g) == len(pins), len(g), -round(abs(mid), 6), s * mid)

    return max(groups, key=rank)


def spare_line(pins, hand: str, oil, ball: lane.Ball | None = None) -> lane.Delivery:
    """The straight spare ball (:data:`.spares.SPARE_BALL`: 17 mph, 200 rpm) through the middle of
    the pins of ``pins`` it can reach most of (:func:`spare_target`: the whole leave unless its
    middle is bare wood), from across the lane, aimed on the fresh ``oil`` (:func:`.spares.straight_at`)."""
    x, y = spares.aim_point(spare_target(pins, hand))
    return spares.straight_at(x, y, hand=hand, oil=oil, ball=ball)


def score(rolls) -> list[int]:
    """USBC's running score after each frame of a game, from its rolls (pins down per ball, in order)."""
    rolls = list(rolls)
    out, total, i = [], 0, 0
    for _ in range(10):
        if i >= len(rolls):
            break
        if rolls[i] == 10:
            total += 10 + sum(rolls[i + 1:i + 3])
            i += 1
        elif i + 1 < len(rolls) and rolls[i] + rolls[i + 1] == 10:
            total += 10 + sum(rolls[i + 2:i + 3])
            i += 2
        else:
            total += sum(rolls[i:i + 2])
            i += 2
        out.append(total)
    return out


def film_along(field: OilField, ft: np.ndarray, board: np.ndarray, hand: str, at_ft: float) -> float:
    """The film (um) on ``field`` under a path (``ft``, ``board`` in ``hand``'s boards) at ``at_ft``."""
    b = phases.board_at(np.asarray(ft), np.asarray(board), at_ft)
    y = float(lane.board_to_y(b, hand))
    i = min(max(int(math.floor((y + scene.LANE_WIDTH / 2) / lane.BOARD_WIDTH)), 0), lane.N_BOARDS - 1)
    return float(field.h[i, min(int(at_ft / DX_FT), NX - 1)])


def lay_band(h: np.ndarray, before: np.ndarray, ft, y, band_in: float) -> float:
    """Lay one ball's oil change across the boards its contact band covers (``h`` changed in place).

    The contact kernel (:mod:`.friction`) trades oil with the one cell under the ball's centre; the
    band is ``band_in`` wide (:attr:`.oil.OilLaw.band_in`, 1 in: about a board), so a ball between two
    boards takes (and lays) oil on both. Per 0.25 ft column the ball's net change (``h - before``) is
    spread over the boards in proportion to their overlap with the band centred on the ball's lane
    ``y`` (m) at that distance (``ft``, ``y``: its path). Each column keeps its total: oil is conserved
    to rounding. A board that would go below zero gives what it has and the rest of the band the
    remainder; a column where even that fails keeps the kernel's change. Returns the oil (ml) moved
    between boards."""
    d = h - before
    cols = np.nonzero(np.abs(d).max(axis=0) > 0)[0]
    if len(cols) == 0 or len(ft) < 2:
        return 0.0
    half = band_in * scene.INCH / 2 / lane.BOARD_WIDTH
    edges = np.arange(lane.N_BOARDS + 1, dtype=float)
    c = (np.interp((cols + 0.5) * DX_FT, ft, y) + scene.LANE_WIDTH / 2) / lane.BOARD_WIDTH
    moved = 0.0
    for j, cj in zip(cols, c):
        w = np.clip(np.minimum(edges[1:], cj + half) - np.maximum(edges[:-1], cj - half), 0.0, None)
        if w.sum() <= 0:
            continue
        w /= w.sum()
        tot = float(d[:, j].sum())
        new = before[:, j] + tot * w
        if new.min() < 0.0:  # a board gives what it has; the band's others the rest, in proportion to their oil
            short = -float(new[new < 0].sum())
            new = np.maximum(new, 0.0)
            rest = (w > 0) & (new > 0)
            if not rest.any() or new[rest].sum() < short:
                continue
            new[rest] -= short * new[rest] / new[rest].sum()
        moved += float(np.abs(new - h[:, j]).sum()) / 2 * CELL_AREA
        h[:, j] = new
    return moved


#: A board is in the track when it lost at least this share of its fresh film (:func:`track_width`).
TRACK_LOSS = 0.10


def track_width(before: np.ndarray, after: np.ndarray, at_ft: float, share: float = TRACK_LOSS) -> int:
    """The width (boards) of the track at ``at_ft``: the run of neighbouring boards around the board
    that lost the largest share of its film, each of which lost at least ``share`` of its fresh film."""
    j = min(int(at_ft / DX_FT), NX - 1)
    b = np.asarray(before)[:, j]
    a = np.asarray(after)[:, j]
    lost = np.where(b > 0, (b - a) / np.where(b > 0, b, 1.0), 0.0)
    k = int(np.argmax(lost))
    if lost[k] < share:
        return 0
    lo = hi = k
    while lo > 0 and lost[lo - 1] >= share:
        lo -= 1
    while hi < len(lost) - 1 and lost[hi + 1] >= share:
        hi += 1
    return hi - lo + 1


def depleted_share(before: np.ndarray, after: np.ndarray, at_ft: float) -> float:
    """The largest share of its oil any board lost at ``at_ft`` (0..1): how dry the track's driest board is."""
    j = min(int(at_ft / DX_FT), NX - 1)
    b = np.asarray(before)[:, j]
    a = np.asarray(after)[:, j]
    ok = b > 0
    return float(((b[ok] - a[ok]) / b[ok]).max()) if ok.any() else 0.0


def _path(r: phases.ThrowResult) -> dict:
    ft = np.arange(0.0, r.path["ft"][-1], PATH_FT)
    return {"ft": [float(v) for v in ft], "board": [round(float(v), 3) for v in np.interp(ft, r.path["ft"], r.path["board"])]}


def _map(field: OilField, decimals: int = MAP_DECIMALS) -> list:
    return [[round(float(v), decimals) for v in row] for row in field.h]


class Run:
    """One run of a series: ``games`` games by ``bowlers`` on one lane of ``oil``, moving as ``move``
    says. :meth:`play` adds every ball to :attr:`balls` as it finishes (an interrupted run keeps
    them); :meth:`to_dict` is the run as the series file holds it."""

    def __init__(self, bowlers: list[Bowler], games: int, seed: int, move: str = "none", oil="house",
                 ball: lane.Ball | None = None, law: OilLaw = lane.LAW):
        if move not in MOVES:
            raise TransitionError(f"move: must be one of {', '.join(MOVES)}, got {move!r}")
        if not (isinstance(games, int) and 1 <= games <= MAX_GAMES):
            raise TransitionError(f"games: must be a whole number in 1..{MAX_GAMES}, got {games!r}")
        self.bowlers, self.games, self.seed, self.move = bowlers, games, int(seed), move
        self.pattern = pattern(oil)
        self.ball = (ball or lane.Ball()).check()
        self.law = law.check(self.ball.friction)
        self.field = OilField.fresh(self.pattern)
        self.before = _map(self.field)
        self._done = self.field.h.copy()  # the lane after the last finished ball
        self.balls: list[dict] = []
        self.rolls: dict[tuple[int, int], list] = {(b.index, g): [] for b in bowlers for g in range(games)}
        self.lines = {b.index: [0.0, 0.0] for b in bowlers}  # feet, target
        self.readings: dict = {b.index: [] for b in bowlers}
        self.moves: list[dict] = []
        # each bowler's own scatter at the pins, which a move must pass (move_for): only a mover needs it
        self.spread = {b.index: pin_spread(b.strike, b.noise, self.pattern, self.ball) if move == "auto" else 0.0
                       for b in bowlers}
        self._reads = {b.index: 0 for b in bowlers}
        self.games_oil: list[dict] = []  # the lane after each game: its oil, past the pattern's end, and its map
        self._spares: dict = {}
        self._draws = {}
        for b in bowlers:
            rng = np.random.default_rng([self.seed, b.index])  # the correlations are the shape's, both noises
            self._draws[b.index] = b.noise.mix(rng.standard_normal((games * _ROWS_PER_GAME, len(noise.KEYS))))
        self._used = {b.index: 0 for b in bowlers}

    def _noisy(self, b: Bowler, d: lane.Delivery, spare: bool) -> lane.Delivery:
        row = self._draws[b.index][self._used[b.index]]
        self._used[b.index] += 1
        nz = b.spare_noise if spare and b.spare_noise is not None else b.noise
        x = noise.perturb([getattr(d, k) for k in noise.KEYS], [getattr(nz, k) for k in noise.KEYS], row[None],
                          [noise.CLIP[k][0] for k in noise.KEYS], [noise.CLIP[k][1] for k in noise.KEYS])[0]
        fields: dict[str, Any] = {k: float(v) for k, v in zip(noise.KEYS, x)}
        return replace(d, **fields).check()

    def _aimed(self, b: Bowler, standing) -> lane.Delivery:
        if len(standing) == 10:
            return moved(b.strike, *self.lines[b.index])
        key = (tuple(standing), b.hand)
        if key not in self._spares:
            self._spares[key] = spare_line(standing, b.hand, self.pattern, self.ball)
        return self._spares[key]

    def _ball(self, b: Bowler, game: int, frame_no: int, roll: int, standing: list) -> dict:
        full = len(standing) == 10
        d = self._noisy(b, self._aimed(b, standing), spare=not full)
        try:  # the ball alone on the lane as it is now (a copy): breakpoint and path
            t = phases.throw(d, self.pattern, self.ball, law=self.law, field=self.field.copy())
        except lane.LaneError:
            t = None
        h0 = self.field.h.copy()
        r = frame.run_frame(d, self.pattern, self.ball, standing=standing, law=self.law, field=self.field)
        if t is not None:
            lay_band(self.field.h, h0, t.path["ft"], t.path["y"], self.law.band_in)
        board = r.board_at_pins
        rec = {"n": len(self.balls) + 1, "game": game + 1, "frame": frame_no, "roll": roll, "bowler": b.index,
               "hand": b.hand, "standing": list(standing), "line": list(self.lines[b.index]) if full else None,
               "delivery": d.to_dict(), "down": r.down, "leave": r.leave, "board_at_pins": board,
               "entry_angle_deg": r.entry_angle_deg,
               "breakpoint_ft": None if t is None else t.breakpoint_ft,
               "breakpoint_board": None if t is None else t.breakpoint_board,
               "pocket": (board is not None and POCKET[0] <= board <= POCKET[1]) if full else None,
               "strike": full and not r.leave, "oil": {k: float(v) for k, v in r.oil_ml.items()},
               "path": _path(t) if (t is not None and full) else None}
        self.balls.append(rec)
        self.rolls[(b.index, game)].append(len(r.down))
        self._done = self.field.h.copy()
        if full and self.move == "auto" and b.reads_lane:
            self.readings[b.index].append(board)
            if move_for(self.readings[b.index], self.spread[b.index]):
                self._read(b, len(self.balls))
        elif full and self.move == "auto":
            self.readings[b.index].append(board)
            m = move_for(self.readings[b.index], self.spread[b.index])
            if m:
                ln = self.lines[b.index]
                ln[0] += m * MOVE_FEET
                ln[1] += m * MOVE_TARGET
                self.readings[b.index] = []
                self.moves.append({"after_ball": rec["n"], "bowler": b.index, "feet": ln[0], "target": ln[1]})
        return rec

    def _read(self, b: Bowler, after: int) -> None:
        """A reading bowler's move (:func:`read_line`) on the lane as it is, after ball ``after``."""
        self._reads[b.index] += 1
        now = moved(b.strike, *self.lines[b.index])
        try:
            got = read_line(now, b.noise, self.field, self.pattern, self.ball, law=self.law,
                            seed=[self.seed, b.index, self._reads[b.index]])
        except lane.LaneError:  # no candidate line reaches the pocket: stay
            return
        d = got["delivery"]
        ln = [float(d.foul_board() - b.strike.foul_board()), float(arrow_board(d) - arrow_board(b.strike))]
        self.readings[b.index] = []
        if max(abs(ln[0] - self.lines[b.index][0]), abs(ln[1] - self.lines[b.index][1])) > 1e-6:
            self.lines[b.index] = ln
            self.moves.append({"after_ball": after, "bowler": b.index, "feet": ln[0], "target": ln[1], "read": True})

    def _frame(self, b: Bowler, game: int, k: int, on_ball) -> None:
        standing = list(range(1, 11))
        rolls = 3 if k == 10 else 2
        for roll in range(1, rolls + 1):
            rec = self._ball(b, game, k, roll, standing)
            if on_ball is not None:
                on_ball(rec)
            left = rec["leave"]
            if k < 10:
                if not left:
                    return
                standing = left
                continue
            # the tenth frame: a fresh rack after a strike or a spare; a third ball only after one
            if roll == 1:
                standing = left or list(range(1, 11))
            elif roll == 2:
                first_strike = self.balls[-2]["strike"]
                if not first_strike and left:
                    return
                standing = left or list(range(1, 11))

    def play(self, on_ball=None, on_frame=None) -> None:
        """Bowl the games: frame by frame, each bowler in turn; ``on_ball(record)`` after each ball
        and ``on_frame()`` after each bowler's frame."""
        for g in range(self.games):
            for k in range(1, 11):
                for b in self.bowlers:
                    self._frame(b, g, k, on_ball)
                    if on_frame is not None:
                        on_frame()
            f = OilField(self._done)
            self.games_oil.append({"game": g + 1, "lane_ml": f.total_ml(), "past_end_ml": f.ml_past(self.pattern.length_ft),
                                   "map": _map(f, GAME_MAP_DECIMALS)})

    def to_dict(self) -> dict:
        """The run: its settings, every ball, the moves, the oil before and after, the scores and the summary."""
        scores = {f"{b.index}": [score(self.rolls[(b.index, g)]) for g in range(self.games)] for b in self.bowlers}
        d = {"move": self.move, "seed": self.seed, "games": self.games,
             "bowlers": [{"index": b.index, "hand": b.hand, "strike": b.strike.to_dict(), "noise": b.noise.to_dict(),
                          "spare_noise": (b.spare_noise or b.noise).to_dict(), "spread_boards": self.spread[b.index]}
                         for b in self.bowlers],
             "balls": self.balls, "moves": self.moves, "scores": scores,
             "oil": {"pattern": self.pattern.name, "length_ft": self.pattern.length_ft, "dx_ft": DX_FT,
                     "before": self.before, "after": _map(OilField(self._done)), "games": self.games_oil}}
        d["summary"] = summary(d)
        return d


def summary(run: dict) -> list[dict]:
    """Per game and hand: strike balls, pocket hits (and the rate with its 95 % Wilson interval),
    strikes, the mean breakpoint (ft and board), entry angle and board at the pins, the oil on the
    lane and past the pattern's end after the game."""
    out = []
    for g in sorted({b["game"] for b in run["balls"]}):
        for hand in ("right", "left"):
            first = [b for b in run["balls"] if b["game"] == g and b["hand"] == hand and len(b["standing"]) == 10]
            if not first:
                continue
            k = sum(1 for b in first if b["pocket"])
            lo, hi = noise.wilson(k, len(first))

            def mean(key):
                v = [b[key] for b in first if b[key] is not None]
                return float(np.mean(v)) if v else None

            out.append({"game": g, "hand": hand, "strike_balls": len(first), "pocket_hits": k,
                        "pocket_rate": k / len(first), "pocket_lo": lo, "pocket_hi": hi,
                        "strikes": sum(1 for b in first if b["strike"]), "breakpoint_ft": mean("breakpoint_ft"),
                        "breakpoint_board": mean("breakpoint_board"), "entry_angle_deg": mean("entry_angle_deg"),
                        "board_at_pins": mean("board_at_pins"),
                        "oil_taken_ml": float(sum(b["oil"]["taken"] for b in run["balls"] if b["game"] == g))})
    return out


def series_dict(runs: list[Run], *, profile: str, lineup_n: int, lefty_share: float, interrupted: bool = False) -> dict:
    """The series file's content (``format`` :data:`FORMAT`): the settings, then each run."""
    r0 = runs[0]
    return {"format": FORMAT, "version": VERSION, "bowler": profile, "lineup": lineup_n, "lefty_share": lefty_share,
            "games": r0.games, "seed": r0.seed, "oil": r0.pattern.name, "ball": r0.ball.to_dict(),
            "law": {"mu_oil": r0.law.mu_oil, "h0_um": r0.law.h0_um, "exchange": r0.law.exchange,
                    "band_in": r0.law.band_in},
            "pocket_boards": list(POCKET), "interrupted": bool(interrupted), "runs": [r.to_dict() for r in runs]}


def check_series(doc, src: str = "<series>") -> dict:
    """A series file's decoded content, checked enough to draw and summarise; TransitionError naming
    ``src`` and the field."""
    if not isinstance(doc, dict):
        raise TransitionError(f"{src}: a series file must be a JSON object")
    if doc.get("format") != FORMAT:
        raise TransitionError(f"{src}: format: must be {FORMAT!r}, got {doc.get('format')!r}")
    if doc.get("version") != VERSION:
        raise TransitionError(f"{src}: version: must be {VERSION}, got {doc.get('version')!r}")
    runs = doc.get("runs")
    if not isinstance(runs, list) or not runs:
        raise TransitionError(f"{src}: runs: must be a non-empty list")
    for k, r in enumerate(runs):
        for key in ("balls", "oil", "move", "summary"):
            if not isinstance(r, dict) or key not in r:
                raise TransitionError(f"{src}: runs[{k}].{key}: missing")
        m = r["oil"].get("before"), r["oil"].get("after")
        if any(np.shape(x) != (lane.N_BOARDS, NX) for x in m):
            raise TransitionError(f"{src}: runs[{k}].oil: before and after must be {lane.N_BOARDS} x {NX} films")
    return doc
