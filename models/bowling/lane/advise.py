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
  interval). Where no line converts (a 7-9, a big four) it says so and gives the line that takes
  the most pins; a slide (the 4 driven into the 9) is among the lines tried.
* **The stance at the edge**: boards are numbered 1-39 on the approach as on the lane; a ball
  released within :data:`STANCE_SEP` boards of the far edge would need the slide foot off the
  numbered boards, so the advice stands the bowler on board 39 and says how close to the foot
  the ball is released (:func:`stance_text`).
* **Strike advice after a frame** (:func:`move_after`): the hit named (:mod:`.names`), and the
  move the coaching rule gives: *move in the direction of the miss* -- a light hit (the ball
  right of the pocket, for a right-hander) moves feet and eyes right, towards the hand; a high
  or Brooklyn hit moves them left -- in the **2-and-1** ratio (feet 2 boards, target 1 board,
  the same way: "The fundamentals of target line adjustments", Bowling This Month,
  2017-03-20), one step per :data:`BOARDS_PER_STEP` boards the ball missed the pocket's middle
  by (at least one). The advice is checked on the lane: the moved line is thrown (the ball
  alone, no noise) and its board at the pins reported beside the old one.

Compute only: no files, no printing.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace

from nbst.models.bowling import lane
from nbst.models.bowling.lane import names as _names, spares, noise as _noise

__all__ = ["STANCE_SEP", "ARROW_BOARDS", "BOARDS_PER_STEP", "POCKET_MIDDLE", "stance_of", "arrow_text", "line_of",
           "aim_target", "Move", "move_after", "LeaveAdvice", "advise_leave", "SAMPLE_NOTE", "stance_text",
           "pins_text"]

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
            "entry_angle_deg": float(r.entry_angle_deg), "hit": _names.hit_name(r.board_at_pins)}


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
    """A strike-line move after a frame: the names of the hit and leave, the steps (2-and-1, +
    left: towards higher boards, away from the hand), the new stance and target, and the moved
    line's board at the pins (the ball alone) beside the old one."""

    names: dict
    steps: int
    direction: str
    stance_board: float
    target_board: float
    new_stance_board: float
    new_target_board: float
    board_at_pins: float | None
    new_board_at_pins: float | None
    delivery: dict
    text: str

    def to_dict(self) -> dict:
        return asdict(self)


def move_after(frame_doc: dict, oil="house", ball=None, *, check: bool = True) -> Move:
    """The move after a frame (a throw file's dict, :mod:`.throwfile`): see the module docstring.
    ``check``: throw the moved line (the ball alone) and report its board at the pins."""
    d = lane.Delivery(**frame_doc["delivery"])
    o = frame_doc["outcome"]
    nm = _names.names(frame_doc["standing"], o["leave"], o["board_at_pins"], o["entry_angle_deg"], d.hand)
    b = o["board_at_pins"]
    miss = 0.0 if b is None else float(b) - POCKET_MIDDLE   # + high (left of the pocket for a right-hander)
    steps = 0 if nm["hit"] == "pocket" or b is None else max(1, int(round(abs(miss) / BOARDS_PER_STEP)))
    sign = 1.0 if miss > 0 else -1.0    # high: left (higher boards); light: right (towards the hand)
    here = lane.throw(d, oil, ball)
    stance, target = stance_of(here.board_at_foul_line), float(here.board_at_arrows)
    ns, nt = stance + sign * 2 * steps, target + sign * steps
    nd = d
    new_b = None
    if steps:
        nd = aim_target(replace(d, board=ns - STANCE_SEP, at="foul"), nt, oil, ball)
        if check:
            new_b = float(lane.throw(nd, oil, ball).board_at_pins)
    way = ("left" if sign > 0 else "right") if d.hand == "right" else ("right" if sign > 0 else "left")
    phrase = _names.text(nm)
    if steps:
        txt = (f"{phrase}: move {steps} {way} (feet {2 * steps} boards, eyes {steps}: "
               f"{stance_text(ns - STANCE_SEP, 0)}, look at {arrow_text(nt)})")
    else:
        txt = f"{phrase}: stay ({stance_text(stance - STANCE_SEP, 0)}, look at {arrow_text(target)})"
    return Move(names=nm, steps=steps, direction=way if steps else "stay", stance_board=stance, target_board=target,
                new_stance_board=ns, new_target_board=nt, board_at_pins=None if b is None else float(b),
                new_board_at_pins=new_b, delivery=nd.to_dict(), text=txt)


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
    it takes. Where no line converted a screening throw the advice says so and gives the line
    that takes the most pins, with that figure; where the best converting line takes fewer pins
    than another, that line is given too, for the count.

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
    d = lane.Delivery(**res.best)
    r = lane.throw(d, runner.oil, runner.ball)
    e = res.estimate
    shown = spares.mirrored(leave) if mirror else leave   # the bowler's own pins
    standing = spares.leave_pins(shown)
    nm = _names.leave_names(range(1, 11), standing)
    leave = shown
    # on the numbered boards, as the text says it (stance_text; a demanding coach's JSON read 41)
    stance, target = min(stance_of(r.board_at_foul_line), float(lane.N_BOARDS)), float(r.board_at_arrows)
    head = f"leave {leave}{' (' + ', '.join(nm) + ')' if nm else ''}"
    screened = sum(c[2] for c in res.candidates)
    most = res.most_pins
    count_text = ""
    if res.converts:
        txt = (f"{head}: {_line_text(d, r, res.best_label)}: converts {100 * e['p']:.0f}% ({e['k']}/{e['n']}; 95% CI "
               f"{100 * e['lo']:.0f}-{100 * e['hi']:.0f}%)" + (f"; {pins_text(res.pins)}" if res.pins else ""))
    else:
        txt = (f"{head}: no line converts: none of {len(res.candidates)} lines converted any of their {screened} "
               f"screening throws (95% CI of a line's rate 0-{100 * _noise.wilson(0, screen)[1]:.0f}% each); the most "
               f"pins: {_line_text(d, r, res.best_label)}: " + (pins_text(res.pins) if res.pins else ""))
    # another line took more pins on the same fresh throws (spares.best_spare's count lines): given for the count
    if most is not None and res.pins is not None and most["label"] != res.best_label \
            and most["pins"]["mean"] > res.pins["mean"]:
        dm = lane.Delivery(**most["delivery"])
        count_text = (f"for the count: {_line_text(dm, lane.throw(dm, runner.oil, runner.ball), most['label'])}: "
                      f"{pins_text(most['pins'])}")
        cleared = int(most["pins"]["counts"].get(str(most["pins"]["of"]), 0))
        if cleared > int(e["k"]):  # measured on the same throws: the pick was ranked on the screening alone
            count_text += (f"; it converted more of these same {e['n']} throws ({cleared} against {e['k']}): "
                           f"the pick was ranked on the screening (--screen {screen}; a larger one ranks on more "
                           f"throws)")
    spare = spares.mirror_doc(res.to_dict()) if mirror else res.to_dict()
    return LeaveAdvice(leave=leave, names=nm, stance_board=stance, target_board=target, target=arrow_text(target),
                       delivery=spare["best"], estimate=e, label=res.best_label, spare=spare, text=txt,
                       converts=res.converts, pins=res.pins, most_pins=spare["most_pins"], count_text=count_text)
