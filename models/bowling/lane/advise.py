"""A bowler's line and a coach's advice: where to stand and where to look.

* **The line** (:func:`line_of`): a throw's stance board, target at the arrows (the board where
  the ball's *real* path crosses 15 ft, named by its nearest arrow), breakpoint, and board and
  entry angle at the head pin's line. The stance is the board of the slide foot on the
  approach: the ball is released :data:`STANCE_SEP` boards towards the bowling hand (a medium
  men's frame, about 7 boards between the ball and the slide foot: Rich Jacobson, "How to know
  you're lined up properly", richjacobsonbowling.com; assumed for every bowler, and a straight
  walk, no drift).
* **Aiming through a target** (:func:`aim_target`): the launch angle that makes the ball's real
  path, from a given board at the foul line, cross a given board at the arrows (Newton's step
  with the straight-line slope, each step one run of the ball alone).
* **Spare advice** (:func:`advise_leave`): the spare tool's best line at the leave
  (:func:`.spares.best_spare` under the bowler's noise), said as stance and target, with the
  conversion probability and its 95 % Wilson interval and the pins it takes (mean, counts, 95 %
  interval). Where no line converts (a 7-9, a big four), or the pick converts none of its
  measured throws, it says so and gives the line that takes the most pins on the measured
  throws; a slide (the 4 driven into the 9) is among the lines tried.
* **The stance at the edge**: boards are numbered 1-39 on the approach as on the lane; a ball
  released within :data:`STANCE_SEP` boards of the far edge would need the slide foot off the
  numbered boards, so the advice stands the bowler on board 39 and says how close to the foot
  the ball is released (:func:`stance_text`).
* **Strike advice after a frame** (:func:`move_after`): the hit named (:mod:`.names`); a strike
  stays (one ball is no reason to move). Else *move in the direction of the miss* -- light (right
  of the pocket, for a right-hander): feet and eyes right; high or Brooklyn: left -- by **2-and-1**
  (feet 2 boards, target 1, the same way: "The fundamentals of target line adjustments", Bowling
  This Month, 2017-03-20), in half steps up to one step per :data:`BOARDS_PER_STEP` boards of miss
  (at least one), each checked on the lane (thrown, the ball alone, no noise): the one meeting the
  pins nearest the pocket, where nearer than the frame's ball, else stay. After a **gutter ball**
  at a full rack, 2-and-1 the way the ball went (the hand's gutter: towards the hand), the steps
  on the lane whose line, thrown, ends nearest the pocket (up to :data:`GUTTER_STEPS`); where none
  reaches the pins, the feet kept (else moved away from that gutter) and the eyes on the board, on
  the lane, whose line meets the pocket (:func:`aim_through`).
* **Spare advice after a frame**: never the pocket. A converted spare: stay. A missed one (or
  a gutter ball): where the ball passed the leave's aim point (:func:`spare_aim`: the spare
  tool's, the mean of the leave's key pins; the ball's heading at the head pin's line carried
  straight on to the aim's row) against the aim's board, and the eyes
  moved with the feet kept (a spare ball's stance is often at the lane's edge, where a 2-and-1
  move of the feet has no room): the target whose line, the ball alone, passes the aim point
  (:func:`aim_through`), checked on the lane.

Compute only: no files, no printing.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace

from nbst.models.bowling import lane
from nbst.models.bowling.lane import names as _names, spares, noise as _noise

__all__ = ["STANCE_SEP", "ARROW_BOARDS", "BOARDS_PER_STEP", "POCKET_MIDDLE", "stance_of", "arrow_text", "line_of",
           "aim_target", "Move", "GUTTER_STEPS", "board_past", "spare_aim", "aim_through", "move_after",
           "LeaveAdvice", "advise_leave", "SAMPLE_NOTE", "stance_text", "pins_text", "pins_rate"]

#: Boards from the slide foot to the ball at release (assumed; see the module docstring).
STANCE_SEP = 7.0
#: The arrows' boards (counted from the bowling hand's edge), 15 ft past the foul line: the lane's
#: (:data:`.units.ARROW_BOARDS`).
ARROW_BOARDS = lane.ARROW_BOARDS
#: One 2-and-1 step per this many boards of miss at the pins (assumed: a step moves the target
#: one board, and a board at the arrows is about two at the pins for a ball that hooks back).
BOARDS_PER_STEP = 2.0
#: The pocket's middle (right-hander's board at the head pin's line).
POCKET_MIDDLE = 17.5
#: What every readout says of one throw.
SAMPLE_NOTE = ("one throw's outcome is a sample (a timestep or a hair of release changes it); its probability "
               "over noisy throws is the result")


def stance_of(foul_board: float) -> float:
    """The stance (slide-foot board) of a ball released on ``foul_board``."""
    return float(foul_board) + STANCE_SEP


def arrow_text(board: float) -> str:
    """``board 13.4 (1.6 boards outside the 3rd arrow)``: a board at the arrows and its nearest arrow,
    as a coach says it (boards count from the bowling hand's gutter: fewer is outside, more inside)."""
    i = min(range(len(ARROW_BOARDS)), key=lambda k: abs(ARROW_BOARDS[k] - board))
    nth = ("1st", "2nd", "3rd", "4th", "5th", "6th", "7th")[i]
    off = board - ARROW_BOARDS[i]
    if abs(off) < 0.05:
        return f"board {board:.1f} ({nth} arrow)"
    return (f"board {board:.1f} ({abs(off):.1f} board{'' if round(abs(off), 1) == 1 else 's'} "
            f"{'inside' if off > 0 else 'outside'} the {nth} arrow)")


def line_of(r) -> dict:
    """The line of a ball-alone throw (:class:`.lane.ThrowResult`): stance, release board, target
    at the arrows (the real path's crossing), breakpoint, entry board and angle, and their names."""
    stance = min(stance_of(r.board_at_foul_line), float(lane.N_BOARDS))   # on the numbered boards (stance_text)
    return {"stance_board": stance, "separation_boards": stance - float(r.board_at_foul_line),
            "foul_board": float(r.board_at_foul_line), "target_board": float(r.board_at_arrows),
            "target": arrow_text(r.board_at_arrows), "breakpoint_ft": r.breakpoint_ft,
            "breakpoint_board": r.breakpoint_board, "entry_board": float(r.board_at_pins),
            "entry_angle_deg": float(r.entry_angle_deg),
            "hit": _names.hit_name(r.board_at_pins, (r.delivery or {}).get("hand", "right"))}


def aim_target(delivery: lane.Delivery, target: float, oil="house", ball=None, *, tol: float = 0.05,
               iters: int = 8) -> lane.Delivery:
    """``delivery`` (its board at the foul line kept) with the launch angle whose ball, alone,
    crosses board ``target`` at the arrows within ``tol`` boards; LaneError (one line) otherwise."""
    d = replace(delivery.check(), board=delivery.foul_board(), at="foul")
    per_deg = lane.ARROWS_FT * lane.FT * math.radians(1.0) / lane.BOARD_WIDTH   # boards per degree, straight
    a = math.degrees(math.atan((d.board - target) * lane.BOARD_WIDTH / (lane.ARROWS_FT * lane.FT)))
    for _ in range(iters):
        d = replace(d, angle=float(min(10.0, max(-10.0, a)))).check()
        _, p, _, _, _ = lane.run(d, oil, ball)
        ft = lane.x_to_ft(p[:, 0])
        if ft[-1] < lane.ARROWS_FT:
            raise lane.LaneError(f"target: from board {d.board:.1f} the ball leaves the lane before the arrows")
        off = lane.board_at(ft, lane.y_to_board(p[:, 1], d.hand), lane.ARROWS_FT) - target
        if abs(off) <= tol:
            return d
        a += off / per_deg
    raise lane.LaneError(f"target: no launch angle from board {d.board:.1f} crosses board {target:g} at the arrows")


@dataclass
class Move:
    """A move after a frame: the names of the hit and leave, the steps (2-and-1, in half steps; 0
    for a move of the eyes alone, or of the feet away from a gutter), the direction
    ("stay" where nothing is to move), the new stance and target, and the moved line's board at the
    pins (the ball alone) beside the old one; ``aim``: what the ball had to meet (the pocket, or a
    spare's aim point, :func:`spare_aim`) on board ``aim_board`` at ``aim_ft`` past the head pin's
    line, ``board_at_aim``/``new_board_at_aim`` the frame's ball and the moved line's there (their
    heading at the head pin's line carried straight on); ``gutter``: side and ft of a gutter ball."""

    names: dict
    steps: float   # 2-and-1 steps: 0.5 is half a step (feet 1 board, eyes 0.5)
    direction: str
    stance_board: float
    target_board: float
    new_stance_board: float | None   # None: no line on the lane to advise
    new_target_board: float | None
    board_at_pins: float | None
    new_board_at_pins: float | None
    delivery: dict
    text: str
    aim: str = "the pocket 17-18"
    aim_board: float = POCKET_MIDDLE
    aim_ft: float = 0.0
    board_at_aim: float | None = None
    new_board_at_aim: float | None = None
    gutter: dict | None = None
    check_text: str = ""

    def to_dict(self) -> dict:
        return asdict(self)


#: The most 2-and-1 steps tried after a gutter ball (:func:`move_after`): 10 steps move the feet 20 boards.
GUTTER_STEPS = 10
#: What the check after a frame says of the moved line, before its board at the pins.
CHECKED = "the moved line, the ball alone, meets the pins on board"


def board_past(board: float, entry_deg: float, x: float) -> float:
    """The board ``x`` m past the head pin's line of a ball on ``board`` there heading ``entry_deg``
    (+ towards higher boards), carried straight on."""
    return float(board) + math.tan(math.radians(entry_deg)) * x / lane.BOARD_WIDTH


def spare_aim(standing, hand: str = "right") -> tuple[tuple, float, float]:
    """(pins aimed through, x m past the head pin's line, board) of a spare ball at the pins
    ``standing``: the spare tool's aim point (``bowl spares``, ``advise --leave``: the mean of the
    leave's key pins, :func:`.spares.leave_spec` and :func:`.spares.aim_point`; a left-hander's
    leave looked up as its mirror image), boards counted from ``hand``'s gutter."""
    name = "-".join(str(p) for p in sorted(int(p) for p in standing))
    if hand == "left":
        key = tuple(sorted(spares.MIRROR[p] for p in spares.leave_spec(spares.mirrored(name))[0]))
    else:
        key = tuple(spares.leave_spec(name)[0])
    x, y = spares.aim_point(key)
    return key, x, float(lane.y_to_board(y, hand))


def aim_through(delivery: lane.Delivery, board: float, x: float, oil="house", ball=None, *, tol: float = 0.25,
                iters: int = 8):
    """(delivery, ThrowResult): ``delivery`` (its board at the foul line kept) with the launch angle
    whose ball, alone, is on ``board`` ``x`` m past the head pin's line (:func:`board_past`): Newton's
    step with the straight-line slope, halving back from a gutter ball; LaneError (one line) otherwise."""
    d = replace(delivery.check(), board=delivery.foul_board(), at="foul")
    dist = x - lane.FOUL_LINE_X
    per_deg = dist * math.radians(1.0) / lane.BOARD_WIDTH   # boards per degree there, straight
    a, prev = math.degrees(math.atan((d.board - board) * lane.BOARD_WIDTH / dist)), None
    for _ in range(iters):
        d = replace(d, angle=float(min(10.0, max(-10.0, a)))).check()
        try:
            r = lane.throw(d, oil, ball)
        except lane.GutterBall as g:   # halving back; with no line on the lane yet, half a degree off that gutter
            a = (a + prev) / 2 if prev is not None else a + (-0.5 if g.side == d.hand else 0.5)
            continue
        off = board_past(r.board_at_pins, r.entry_angle_deg, x) - board
        if abs(off) <= tol:
            return d, r
        prev, a = a, a + off / per_deg
    raise lane.LaneError(f"target: no launch angle from board {d.board:.1f} puts the ball on board {board:.1f} "
                         f"at the aim")


def _here(d: lane.Delivery, oil, ball):
    """(stance, target at the arrows, gutter dict or None) of the frame's line, the ball alone: a
    gutter ball's target is where its path crossed the arrows (the straight line's, gone before)."""
    try:
        r = lane.throw(d, oil, ball)
        return stance_of(r.board_at_foul_line), float(r.board_at_arrows), None
    except lane.GutterBall as g:
        _, p, _, _, _ = lane.run(d, oil, ball)
        ft, foul = lane.x_to_ft(p[:, 0]), d.foul_board()
        t = (lane.board_at(ft, lane.y_to_board(p[:, 1], d.hand), lane.ARROWS_FT) if ft[-1] >= lane.ARROWS_FT
             else foul - math.tan(math.radians(d.angle)) * lane.ARROWS_FT * lane.FT / lane.BOARD_WIDTH)
        return stance_of(foul), float(t), {"side": g.side, "ft": round(g.ft, 2)}


def _way(sign: float, hand: str) -> str:
    """The bowler's word for a move towards higher boards (sign > 0: away from the hand) or lower."""
    return ("left" if sign > 0 else "right") if hand == "right" else ("right" if sign > 0 else "left")


def move_after(frame_doc: dict, oil="house", ball=None, *, check: bool = True) -> Move:
    """The move after a frame (a throw file's dict, :mod:`.throwfile`): see the module docstring.
    ``check``: throw the moved line (the ball alone) and report its board at the pins."""
    d = lane.Delivery(**frame_doc["delivery"])
    o = frame_doc["outcome"]
    standing = frame_doc["standing"]
    nm = _names.names(standing, o["leave"], o["board_at_pins"], o["entry_angle_deg"], d.hand)
    b = None if o["board_at_pins"] is None else float(o["board_at_pins"])
    stance, target, gutter = _here(d, oil, ball)
    phrase = (_names.text(nm) if gutter is None
              else f"a gutter ball (the {gutter['side']} gutter at {gutter['ft']:.1f} ft)")
    if len(set(standing)) < 10:
        return _spare_move(d, frame_doc, nm, phrase, stance, target, gutter, oil, ball, check)
    if gutter is not None:
        return _gutter_move(d, nm, phrase, stance, target, gutter, oil, ball)
    common = dict(names=nm, stance_board=stance, target_board=target, board_at_pins=b, board_at_aim=b)
    here = f"{stance_text(stance - STANCE_SEP, 0)}, look at {arrow_text(target)}"
    miss = 0.0 if b is None else b - POCKET_MIDDLE   # + high (left of the pocket for a right-hander)
    strike = not o["leave"]   # one ball is no reason to move
    rule = 0 if strike or nm["hit"] == "pocket" or b is None else max(1, int(round(abs(miss) / BOARDS_PER_STEP)))
    sign, near = (1.0 if miss > 0 else -1.0), None   # high: left (higher boards); light: right (towards the hand)
    # half steps up to the rule's, each thrown (the ball alone): the one nearest the pocket, if nearer than the frame
    for k in ([i / 2 for i in range(1, 2 * rule + 1)] if check else [rule] if rule else []):
        ns, nt = stance + sign * 2 * k, target + sign * k
        if not _on_lane(ns, nt):
            break
        try:
            kd = aim_target(replace(d, board=ns - STANCE_SEP, at="foul"), nt, oil, ball)
            kb = float(lane.throw(kd, oil, ball).board_at_pins) if check else None
        except lane.LaneError:
            continue
        if kb is None or near is None or near[1] is None or abs(kb - POCKET_MIDDLE) < abs(near[1] - POCKET_MIDDLE):
            near = (k, kb, kd)
    way, of = _way(sign, d.hand), f"(this frame's: {b or 0:.1f}; the pocket 17-18)"
    if near is None or (near[1] is not None and abs(near[1] - POCKET_MIDDLE) >= abs(miss)):
        chk = "" if near is None else (f"no 2-and-1 move {way} of half a step to {rule} checks nearer the pocket: the "
                                       f"nearest, {near[0]:g}, meets the pins on board {near[1]:.1f} {of}")
        return Move(steps=0, direction="stay", new_stance_board=stance, new_target_board=target, new_board_at_pins=None,
                    delivery=d.to_dict(), text=f"{phrase}: stay{': a strike; one ball is no reason to move' * strike} "
                    f"({here})", check_text=chk, **common)
    k, new_b, nd = near
    ns, nt = stance + sign * 2 * k, target + sign * k
    return Move(steps=k, direction=way, new_stance_board=ns, new_target_board=nt, new_board_at_pins=new_b,
                delivery=nd.to_dict(), text=_move_text(phrase, k, way, ns, nt), new_board_at_aim=new_b,
                check_text="" if new_b is None else f"{CHECKED} {new_b:.1f} {of}", **common)


def _on_lane(stance: float, target: float) -> bool:
    """Whether a stance (its release :data:`STANCE_SEP` boards towards the hand) and a target are on boards 1..39."""
    return 1.0 <= stance - STANCE_SEP <= lane.N_BOARDS and 1.0 <= target <= lane.N_BOARDS


def _move_text(phrase: str, k: float, way: str, ns: float, nt: float) -> str:
    """``high: move 1 left (feet 2 boards, eyes 1: stand on 29, look at ...)``: ``k`` 2-and-1 steps (0.5: half a step)."""
    return (f"{phrase}: move {'half a step' if k == 0.5 else f'{k:g}'} {way} (feet {2 * k:g} board"
            f"{'' if k == 0.5 else 's'}, eyes {k:g}: {stance_text(ns - STANCE_SEP, 0)}, look at {arrow_text(nt)})")


def _gutter_move(d, nm, phrase, stance, target, gutter, oil, ball) -> Move:
    """After a gutter ball at a full rack: the 2-and-1 move the way the ball went (into the hand's
    gutter: towards the hand), as many steps (up to :data:`GUTTER_STEPS`, on the lane) as bring the
    moved line, the ball alone and thrown, nearest the pocket's middle; where none does, the thrown
    line said as thrown and the eyes aimed through the pocket (see the module docstring)."""
    sign = -1.0 if gutter["side"] == ("right" if d.hand == "right" else "left") else 1.0
    best, fit = None, 0   # (miss, steps, delivery, board at the pins); the steps on the lane from this stance
    for k in range(1, GUTTER_STEPS + 1):
        ns, nt = stance + sign * 2 * k, target + sign * k
        if not _on_lane(ns, nt):
            break
        fit = k
        try:
            nd = aim_target(replace(d, board=ns - STANCE_SEP, at="foul"), nt, oil, ball)
            nb = float(lane.throw(nd, oil, ball).board_at_pins)
        except lane.LaneError:   # gutter again (or no angle crosses the target): a bigger move
            continue
        if best is not None and abs(nb - POCKET_MIDDLE) >= best[0]:
            break   # past the pocket: the previous step was nearest
        best = (abs(nb - POCKET_MIDDLE), k, nd, nb)
    way = _way(sign, d.hand)
    common = dict(names=nm, stance_board=stance, target_board=target, board_at_pins=None, gutter=gutter)
    frame_at = f"this frame's: the {gutter['side']} gutter; the pocket 17-18"
    if best is not None:
        _, k, nd, nb = best
        ns, nt = stance + sign * 2 * k, target + sign * k
        return Move(steps=k, direction=way, new_stance_board=ns, new_target_board=nt, new_board_at_pins=nb,
                    delivery=nd.to_dict(), text=_move_text(phrase, k, way, ns, nt), new_board_at_aim=nb,
                    check_text=f"{CHECKED} {nb:.1f} ({frame_at})", **common)
    # no 2-and-1 step that fits keeps the ball on the lane: the feet kept (else moved away from the gutter, 2
    # boards at a time) and the eyes on the target, on the lane, whose line, the ball alone, meets the pocket
    foul, crossed, away = d.foul_board(), 1.0 <= target <= lane.N_BOARDS, _way(-sign, d.hand)
    thrown = (f"thrown standing on board {min(stance, lane.N_BOARDS):.0f} (released on board {foul:.1f}, {abs(d.angle):.2f} "
              f"deg {'out' if d.angle >= 0 else 'in'}), " + (f"over {arrow_text(target)}" if crossed else
                                                              "off the lane before the arrows"))
    room = (f"no 2-and-1 move {way} of up to {fit} step{'' if fit == 1 else 's'} (all that fit on the lane from there) "
            f"keeps the ball alone on the lane to the pins" if fit else f"no 2-and-1 step {way} fits on the lane from there")
    for rel in [f for f in (foul - sign * 2 * j for j in range(GUTTER_STEPS + 1)) if 1.0 <= f <= lane.N_BOARDS]:
        try:
            nd, r = aim_through(replace(d, board=rel, at="foul"), POCKET_MIDDLE, 0.0, oil, ball)
        except lane.LaneError:
            continue
        if 1.0 <= r.board_at_arrows <= lane.N_BOARDS:
            nt, nb, feet = float(r.board_at_arrows), float(r.board_at_pins), abs(rel - foul)
            return Move(steps=0, direction=away if feet else _way(nt - target, d.hand), new_stance_board=stance_of(rel),
                        new_target_board=nt, new_board_at_pins=nb, delivery=nd.to_dict(), new_board_at_aim=nb,
                        text=(f"{phrase}: {thrown}; {room}: " + (f"move the feet {feet:g} boards {away}" if feet else
                              "keep the feet") + f" ({stance_text(rel, 0)}), look at {arrow_text(nt)}"),
                        check_text=f"{CHECKED} {nb:.1f} ({frame_at})", **common)
    return Move(steps=0, direction="stay", new_stance_board=None, new_target_board=None, new_board_at_pins=None,
                delivery=d.to_dict(), text=f"{phrase}: {thrown}; {room}, nor does a line to the pocket: change the "
                f"release", **common)


def _spare_move(d, frame_doc, nm, phrase, stance, target, gutter, oil, ball, check) -> Move:
    """After a spare ball: converted, stay; missed (or a gutter ball), the eyes moved with the feet
    kept, to the target whose line, the ball alone, meets the leave's aim point (:func:`spare_aim`),
    never the pocket; the frame's ball and the moved line's said at the aim point's row."""
    o = frame_doc["outcome"]
    b, e = o["board_at_pins"], o["entry_angle_deg"]
    key, x, aim_b = spare_aim(frame_doc["standing"], d.hand)
    where = f"the {key[0]} pin" if len(key) == 1 else f"the middle of the {'-'.join(map(str, key))}"
    aim = f"{where}, board {aim_b:.1f}"
    at = None if b is None or e is None else board_past(b, e, x)
    common = dict(names=nm, steps=0, stance_board=stance, target_board=target, new_stance_board=stance,
                  board_at_pins=None if b is None else float(b), aim=aim, aim_board=aim_b, aim_ft=x / lane.FT,
                  board_at_aim=at, gutter=gutter)
    if not o["leave"]:
        txt = f"{phrase}: stay ({stance_text(stance - STANCE_SEP, 0)}, look at {arrow_text(target)})"
        return Move(direction="stay", new_target_board=target, new_board_at_pins=None, delivery=d.to_dict(),
                    text=txt, **common)
    there = (f"the ball passed {where} on board {at:.1f}, {abs(at - aim_b):.1f} boards {_way(at - aim_b, d.hand)} "
             f"of its board {aim_b:.1f}" if at is not None else f"the ball must pass {aim}")
    try:
        nd, r = aim_through(d, aim_b, x, oil, ball)
    except lane.LaneError:
        txt = (f"{phrase}: {there}; no launch angle from this stance ({stance_text(stance - STANCE_SEP, 0)}) "
               f"reaches it: move the feet")
        return Move(direction="stay", new_target_board=target, new_board_at_pins=None, delivery=d.to_dict(),
                    text=txt, **common)
    nt = float(r.board_at_arrows)
    way = _way(nt - target, d.hand)
    new_b = float(r.board_at_pins) if check else None
    new_at = board_past(r.board_at_pins, r.entry_angle_deg, x) if check else None
    txt = (f"{phrase}: {there}: keep the feet ({stance_text(stance - STANCE_SEP, 0)}), move the eyes "
           f"{abs(nt - target):.1f} boards {way}: look at {arrow_text(nt)}")
    chk = "" if new_at is None else (
        f"the moved line, the ball alone, passes {where} on board {new_at:.1f} (this frame's: "
        + (f"{at:.1f}" if at is not None else f"the {gutter['side']} gutter") + f"; {aim})")
    return Move(direction=way, new_target_board=nt, new_board_at_pins=new_b, delivery=nd.to_dict(), text=txt,
                new_board_at_aim=new_at, check_text=chk, **common)


@dataclass
class LeaveAdvice:
    """Where to stand and look at a leave, the conversion probability (k of n, 95 % Wilson), the
    pins the line takes (:func:`.spares.pins_estimate`), whether any line converted, the line that
    takes the most pins (for the count), the ball, and the spare tool's account
    (:class:`.spares.SpareResult` as a dict)."""

    leave: str
    names: list
    stance_board: float
    target_board: float
    target: str
    delivery: dict
    estimate: dict
    label: str
    spare: dict
    text: str
    converts: bool = True
    pins: dict | None = None
    most_pins: dict | None = None
    count_text: str = ""

    def to_dict(self) -> dict:
        return asdict(self)


def stance_text(foul_board: float, digits: int = 1) -> str:
    """Where to stand for a ball released on ``foul_board``, said honestly at the lane's edge: the
    slide foot :data:`STANCE_SEP` boards inside the release, or, where that is past board
    :data:`.units.N_BOARDS` (off the approach's numbered boards), on the last board with the ball
    released closer to the foot (the separation said)."""
    stance = stance_of(foul_board)
    if stance <= lane.N_BOARDS:
        return f"stand on {stance:.{digits}f}"
    return (f"stand on {lane.N_BOARDS} (the last board; the ball released on {foul_board:.1f}, "
            f"{lane.N_BOARDS - foul_board:.1f} boards from the slide foot)")


def pins_text(p: dict) -> str:
    """``1.0 pins a throw (11 of 12 took 1; 95% CI 0.8-1.1)``: a :func:`.spares.pins_estimate`."""
    counts = ", ".join(f"{v} took {k}" for k, v in p["counts"].items())
    return f"{p['mean']:.2f} of {p['of']} pins a throw ({counts}; 95% CI {p['lo']:.2f}-{p['hi']:.2f})"


def _line_text(d: lane.Delivery, r, label: str) -> str:
    return (f"{stance_text(r.board_at_foul_line)}, look at {arrow_text(float(r.board_at_arrows))}, {d.mph:.1f} mph "
            f"{d.rpm:.0f} rpm ({label})")


def advise_leave(leave: str, n: int, seed: int, *, runner, noise=None, strike=None, screen: int = spares.SCREEN,
                 polish: int | None = None, on_done=None, mirror: bool = False) -> LeaveAdvice:
    """The advice at ``leave`` ('-' joined pins): :func:`.spares.best_spare` under ``noise`` (a
    bowler's), said as stance and target (the real path's crossing of the arrows), with the pins
    it takes. Where no line converted a screening throw, or the screening's pick converts none of
    its measured throws, the advice says so and gives the line that takes the most pins on the
    measured throws (:attr:`.spares.SpareResult.most_pins`, ranked on the figure printed, never the
    screening's), with that figure; where the best converting line takes fewer pins than another,
    that line is given too, for the count.

    Args:
        leave: the pins standing, '-' joined ("4-9").
        n: throws of each fresh measure.
        seed: the seed of the measures.
        runner: the :class:`.frame.FrameRunner`.
        noise: the release noise (None: :data:`.noise.DEFAULT`).
        strike: the bowler's strike ball (the 3-6-9 line's; None: :data:`.spares.STRIKE`).
        screen: noisy throws per candidate in the screening.
        polish: noisy frames of the polish (None: the spare tool's default; 0: none).
        on_done: called after each frame.
        mirror: advise a left-hander: ``leave`` is its right-handed mirror image (:func:`.spares.mirrored`),
            worked out on the mirrored lane; the advice names the left-hander's pins and its boards
            (counted from its own gutter, as a right-hander's from its), and its delivery is left-handed.

    Returns:
        a :class:`LeaveAdvice`.

    Raises:
        LaneError: a leave that is not distinct pins 1..10, or all ten.
    """
    nz = noise if noise is not None else _noise.DEFAULT
    res = spares.best_spare(leave, n, seed, runner=runner, screen=screen, nz=nz, on_done=on_done, polish=polish,
                            strike=strike, mirror=mirror)
    spare = spares.mirror_doc(res.to_dict()) if mirror else res.to_dict()
    e, most = res.estimate, res.most_pins
    shown = spares.mirrored(leave) if mirror else leave   # the bowler's own pins
    standing = spares.leave_pins(shown)
    nm = _names.leave_names(range(1, 11), standing)
    leave = shown
    head = f"leave {leave}{' (' + ', '.join(nm) + ')' if nm else ''}"
    screened = sum(c[2] for c in res.candidates)
    # nothing converted (the screening, or the pick's measured throws): the line said is the one that took the
    # most pins on the measured throws (spares.best_spare's most_pins), the figure printed, not the screening's
    lead = most if most is not None and (not res.converts or int(e["k"]) == 0) else None
    if lead is not None and lead["label"] != res.best_label:
        d, label, pins, delivery = lane.Delivery(**lead["delivery"]), lead["label"], lead["pins"], \
            spare["most_pins"]["delivery"]
        e = pins_rate(pins, e)
    else:
        d, label, pins, delivery = lane.Delivery(**res.best), res.best_label, res.pins, spare["best"]
    r = lane.throw(d, runner.oil, runner.ball)
    # on the numbered boards, as the text says it (stance_text; a demanding coach's JSON read 41)
    stance, target = min(stance_of(r.board_at_foul_line), float(lane.N_BOARDS)), float(r.board_at_arrows)
    line = f"{_line_text(d, r, label)}: " + (pins_text(pins) if pins else "")
    count_text, converts = "", res.converts
    if lead is None:
        txt = (f"{head}: {_line_text(d, r, label)}: converts {100 * e['p']:.0f}% ({e['k']}/{e['n']}; 95% CI "
               f"{100 * e['lo']:.0f}-{100 * e['hi']:.0f}%)" + (f"; {pins_text(pins)}" if pins else ""))
    elif not res.converts:
        txt = (f"{head}: no line converts: none of {len(res.candidates)} lines converted any of their {screened} "
               f"screening throws (95% CI of a line's rate 0-{100 * _noise.wilson(0, screen)[1]:.0f}% each); the most "
               f"pins on the {res.estimate['n']} measured throws: {line}")
    else:   # the screening's pick converted none of the measured throws
        n0, hi0 = int(res.estimate["n"]), 100 * res.estimate["hi"]
        pick = f"the screening's pick ({res.best_label}) converted 0 of the {n0} (95% CI 0-{hi0:.0f}%)"
        if int(e["k"]) == 0 and int(res.system_369_estimate["k"]) == 0:
            converts = False
            txt = f"{head}: no line converted in the {n0} measured throws: {pick}; the most pins: {line}"
        else:
            txt = (f"{head}: {pick}; the most pins, converting {e['k']} of the same {n0}: {line}"
                   if int(e["k"]) else f"{head}: {pick}; the most pins: {line}")
    # another line took more pins on the same fresh throws (spares.best_spare's count lines): given for the count
    if lead is None and most is not None and res.pins is not None and most["label"] != res.best_label \
            and most["pins"]["mean"] > res.pins["mean"]:
        dm = lane.Delivery(**most["delivery"])
        count_text = (f"for the count: {_line_text(dm, lane.throw(dm, runner.oil, runner.ball), most['label'])}: "
                      f"{pins_text(most['pins'])}")
    return LeaveAdvice(leave=leave, names=nm, stance_board=stance, target_board=target, target=arrow_text(target),
                       delivery=delivery, estimate=e, label=label, spare=spare, text=txt,
                       converts=converts, pins=pins, most_pins=spare["most_pins"], count_text=count_text)


def pins_rate(p: dict, e: dict) -> dict:
    """The conversion estimate (``e``'s form) of a line from its :func:`.spares.pins_estimate` on the
    measured throws: the throws that took every pin standing (``leaves`` not kept: None)."""
    k, n = int(p["counts"].get(str(p["of"]), 0)), int(p["n"])
    lo, hi = _noise.wilson(k, n)
    return {**e, "k": k, "n": n, "p": k / n, "lo": float(lo), "hi": float(hi), "leaves": None}
