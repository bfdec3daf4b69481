"""The throw down the lane: the ball alone from the foul line to the pins, and its phases.

* **Throw** (:func:`throw`): the ball alone (no pins: the phases end where the pins would
  start) is stepped with h = 1 ms until its centre crosses the head pin's spot line (x = 0),
  recording its state each step; :class:`ThrowResult` holds the phases in bowler's units. Its phases: where the skid ends and the hook starts, the breakpoint, where
the ball rolls, its entry angle, board and speed at the pins (:class:`ThrowResult`).

Compute only: no files written, no printing.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, replace

import numpy as np

from nbst.models.bowling import scene
from nbst.models.bowling.lane.ball import Ball
from nbst.models.bowling.lane.delivery import Delivery, initial_state, quat_to_mat
from nbst.models.bowling.lane.oil import MU_OIL
from nbst.models.bowling.lane.scene import build_model
from nbst.models.bowling.lane.units import ARROWS_FT, MPH, LaneError, hand_sign, x_to_ft, y_to_board

__all__ = ["TIMESTEP", "MAX_SECONDS", "ROLL_SLIP", "HOOK_SHARE", "BREAKPOINT_MIN", "AIM_TOL", "ThrowResult", "run",
           "throw", "board_at", "aim_at_arrows"]

#: Step and the longest run (s): a ball released at 5 mph (the slowest Delivery) takes ~11 s.
TIMESTEP = scene.TIMESTEP
MAX_SECONDS = 15.0
#: The ball rolls when its contact point slides slower than this (m/s): MuJoCo's soft
#: contact leaves a creep of ~1e-3 m/s in pure roll.
ROLL_SLIP = 0.02
#: The hook starts (the skid ends) where the ball's sideways acceleration towards the pocket
#: first reaches this share of its peak.
HOOK_SHARE = 0.5
#: A breakpoint needs the ball to move out at least this many boards from its release.
BREAKPOINT_MIN = 0.25


@dataclass
class ThrowResult:
    """The phases of a throw in bowler's units (feet past the foul line, boards, mph, degrees).

    ``skid_ft``: where the hook starts (sideways acceleration towards the pocket first reaches
    HOOK_SHARE of its peak); ``breakpoint_ft``/``breakpoint_board``: where the ball is farthest
    out (its board stops falling; None when it never moves out); ``roll_ft``: where the contact
    point's slip first drops below ROLL_SLIP (None if it never rolls before the pins);
    ``entry_angle_deg``: the ball's heading where its centre crosses the head pin's line,
    + towards the pocket side; ``board_at_pins``: its board there.
    """

    oil: str
    ball: dict
    delivery: dict
    board_at_foul_line: float
    board_at_arrows: float
    skid_ft: float | None
    breakpoint_ft: float | None
    breakpoint_board: float | None
    roll_ft: float | None
    entry_angle_deg: float
    board_at_pins: float
    speed_release_mph: float
    speed_pins_mph: float
    speed_lost_mph: float
    seconds_to_pins: float
    timestep: float = TIMESTEP
    path: dict = field(default_factory=dict, repr=False)  # per-step arrays (not in to_dict)

    def to_dict(self) -> dict:
        d = asdict(self)
        d.pop("path")
        return d


def run(delivery: Delivery, oil: str = "house", ball: Ball | None = None, *, mu_oil: float = MU_OIL):
    """Step the ball alone from the foul line until its centre crosses x = 0 (or leaves the lane
    over a gutter, or MAX_SECONDS pass): (t, pos (n,3), vel (n,3), omega_world (n,3)) per step,
    the release state first."""
    import mujoco

    from nbst.models.mjsearch.runner import mujoco_warnings_raise

    delivery = delivery.check()
    model = build_model(oil, ball, delivery, pins=False, mu_oil=mu_oil)
    data = mujoco.MjData(model)
    pos0, v0, w0 = initial_state(delivery)
    data.qpos[:7] = [*pos0, 1.0, 0.0, 0.0, 0.0]
    data.qvel[:3] = v0
    data.qvel[3:6] = w0  # body frame = world frame at the identity orientation
    n_max = int(round(MAX_SECONDS / model.opt.timestep))
    qp = np.empty((n_max + 1, 7))
    qv = np.empty((n_max + 1, 6))
    qp[0], qv[0] = data.qpos[:7], data.qvel[:6]
    n = 0
    with mujoco_warnings_raise():
        while n < n_max and data.qpos[0] < 0.0 and abs(data.qpos[1]) < scene.LANE_WIDTH / 2:
            mujoco.mj_step(model, data)
            n += 1
            qp[n], qv[n] = data.qpos[:7], data.qvel[:6]
    qp, qv = qp[:n + 1], qv[:n + 1]
    omega = np.einsum("nij,nj->ni", quat_to_mat(qp[:, 3:7]), qv[:, 3:6])
    return np.arange(n + 1) * model.opt.timestep, qp[:, :3], qv[:, :3], omega


def throw(delivery: Delivery, oil: str = "house", ball: Ball | None = None, *, mu_oil: float = MU_OIL) -> ThrowResult:
    """Run ``delivery`` down the lane with ``oil`` and ``ball``; its phases (see ThrowResult).

    Args:
        delivery: what the bowler does (:class:`Delivery`: hand, board, angle, mph, rpm, axis
            rotation and tilt); checked first.
        oil: the name of a registered oil pattern (``nbst.models.bowling.lane.oil.PATTERNS``).
        ball: the ball (:class:`Ball`, within USBC's limits; None: the default ball).
        mu_oil: the ball-lane friction coefficient on oil (the dry lane's is fixed).

    Returns:
        A :class:`ThrowResult` in bowler's units: the skid, breakpoint and roll (feet past the
        foul line, boards), the entry angle (degrees) and the board at the pins.
    """
    delivery = delivery.check()
    ball = (ball or Ball()).check()
    t, p, v, w = run(delivery, oil, ball, mu_oil=mu_oil)
    if abs(p[-1, 1]) >= scene.LANE_WIDTH / 2:
        side = "left" if p[-1, 1] > 0 else "right"
        raise LaneError(f"delivery: a gutter ball: it left the lane into the {side} gutter "
                        f"{float(x_to_ft(p[-1, 0])):.1f} ft past the foul line; no phases to report")
    if p[-1, 0] < 0.0:
        raise LaneError(f"delivery: the ball did not reach the pins within {MAX_SECONDS:g} s "
                        f"(it was {-p[-1, 0]:.2f} m short, on board {float(y_to_board(p[-1, 1], delivery.hand)):.1f})")
    s = hand_sign(delivery.hand)
    R = scene.BALL_RADIUS
    slip = v + np.cross(w, np.array([0.0, 0.0, -R]))
    slip_h = np.hypot(slip[:, 0], slip[:, 1])
    speed = np.linalg.norm(v[:, :2], axis=1)
    ft = x_to_ft(p[:, 0])
    board = y_to_board(p[:, 1], delivery.hand)
    # sideways acceleration towards the pocket side, across the heading (central differences over 10 ms)
    k = 10
    a = np.zeros_like(v)
    a[k:-k] = (v[2 * k:] - v[:-2 * k]) / (2 * k * TIMESTEP)
    a_perp = s * (v[:, 0] * a[:, 1] - v[:, 1] * a[:, 0]) / np.maximum(speed, 1e-9)
    peak = a_perp.max()
    skid_i = int(np.argmax(a_perp >= HOOK_SHARE * peak)) if peak > 0.05 else None
    # breakpoint: the ball's farthest board out, if it went out at least BREAKPOINT_MIN boards
    bp_i = int(np.argmin(board))
    bp_i = bp_i if board[0] - board[bp_i] >= BREAKPOINT_MIN and bp_i < len(board) - 1 else None
    rolled = np.flatnonzero(slip_h < ROLL_SLIP)
    roll_i = int(rolled[0]) if len(rolled) else None
    # at the head pin's line: interpolate between the last two steps
    f = -p[-2, 0] / (p[-1, 0] - p[-2, 0])
    y_pin = p[-2, 1] + f * (p[-1, 1] - p[-2, 1])
    v_pin = v[-2] + f * (v[-1] - v[-2])
    return ThrowResult(
        oil=oil if isinstance(oil, str) else oil.name, ball=ball.to_dict(), delivery=delivery.to_dict(),
        board_at_foul_line=float(board[0]), board_at_arrows=board_at(ft, board, ARROWS_FT),
        skid_ft=None if skid_i is None else float(ft[skid_i]),
        breakpoint_ft=None if bp_i is None else float(ft[bp_i]),
        breakpoint_board=None if bp_i is None else float(board[bp_i]),
        roll_ft=None if roll_i is None else float(ft[roll_i]),
        entry_angle_deg=float(math.degrees(math.atan2(s * v_pin[1], v_pin[0]))),
        board_at_pins=float(y_to_board(y_pin, delivery.hand)),
        speed_release_mph=float(speed[0] / MPH), speed_pins_mph=float(np.hypot(*v_pin[:2]) / MPH),
        speed_lost_mph=float((speed[0] - np.hypot(*v_pin[:2])) / MPH),
        seconds_to_pins=float(t[-2] + f * TIMESTEP),
        path={"t": t, "ft": ft, "board": board, "speed_mph": speed / MPH, "slip": slip_h, "a_hook": a_perp,
              "y": p[:, 1]})


def board_at(ft, board, at_ft: float) -> float:
    """The ball's board where its path crosses ``at_ft`` feet past the foul line, interpolated
    between the two steps around it (``ft``, ``board``: the path's per-step arrays)."""
    i = int(np.argmax(ft >= at_ft))
    if i == 0:
        return float(board[0])
    f = (at_ft - ft[i - 1]) / (ft[i] - ft[i - 1])
    return float(board[i - 1] + f * (board[i] - board[i - 1]))


#: How close (boards) the ball's real path must cross the arrows to the board asked.
AIM_TOL = 0.01


def aim_at_arrows(delivery: Delivery, oil: str = "house", ball: Ball | None = None, *, mu_oil: float = MU_OIL,
                  tol: float = AIM_TOL, iters: int = 8) -> Delivery:
    """A delivery given at the arrows (``at="arrows"``), aimed along the ball's real path: the
    foul-line delivery (``at="foul"``) whose ball, thrown on ``oil`` with ``ball``, crosses the
    asked board 15 ft out within ``tol`` boards. ``Delivery.foul_board`` carries the board back
    along a straight line; a hooking ball is off that line before the arrows (0.07 board for the
    typical release, 2.1 boards at 500 rpm), so the foul board is corrected by what the run
    shows (Newton's step with slope 1: a board moved at the foul line moves the crossing by about
    a board), each correction one run of the ball alone. A delivery given at the foul line is
    returned as it is. LaneError when the ball leaves the lane before the arrows or no foul
    board within ``iters`` runs crosses there."""
    delivery = delivery.check()
    if delivery.at != "arrows":
        return delivery
    want = float(delivery.board)
    b = delivery.foul_board()
    for _ in range(iters):
        d = replace(delivery, board=float(b), at="foul").check()
        _, p, _, _ = run(d, oil, ball, mu_oil=mu_oil)
        ft = x_to_ft(p[:, 0])
        if ft[-1] < ARROWS_FT:
            raise LaneError(f"board: the ball aimed at board {want:g} at the arrows leaves the lane "
                            f"{float(ft[-1]):.1f} ft past the foul line, before the arrows")
        off = board_at(ft, y_to_board(p[:, 1], d.hand), ARROWS_FT) - want
        if abs(off) <= tol:
            return d
        b -= off
        if not 1.0 <= b <= 39.0:
            break
    raise LaneError(f"board: no board at the foul line puts this ball on board {want:g} at the arrows "
                    f"({iters} runs of the ball alone)")
