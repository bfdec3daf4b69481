"""A lane in a bowler's units: boards, feet from the foul line, mph, the hand.

Axes as :mod:`nbst.models.bowling.scene`: x down the lane, y to the bowler's left, z up, the
head pin's spot at the origin. The foul line is 60 ft before it (:data:`FOUL_LINE_X` =
-18.288 m).

* **Boards** (:func:`board_to_y`): 39 across the 41.5 in lane (1.0641 in each), numbered as
  bowlers number them: board 1 at the edge on the bowler's hand side (the right edge,
  y < 0, for a right-hander), board 20 the middle (the head pin's board), 39 the far edge.
  A left-hander's board 1 is the left edge: the left-hander's lane is the right-hander's
  mirrored in y. Boards are continuous: board b's centre is ``b - 0.5`` board widths from the
  hand-side edge (board 17.5, the pocket, is 2.5 boards right of the head pin for a
  right-hander). The arrows are on boards 5, 10, ... 35, 15 ft past the foul line.

Pure numpy.
"""
from __future__ import annotations

import numpy as np

from nbst.errors import InputError
from nbst.models.bowling import scene

__all__ = ["FT", "MPH", "LB", "LANE_LENGTH_FT", "FOUL_LINE_X", "ARROWS_FT", "ARROW_BOARDS", "N_BOARDS", "BOARD_WIDTH",
           "APPROACH", "LANE_START_X", "LaneError", "GutterBall", "hand_sign", "board_to_y", "y_to_board", "ft_to_x", "x_to_ft"]

FT = 0.3048
MPH = 0.44704
LB = 0.45359237
#: USBC: 60 ft from the foul line to the head pin's spot; the arrows 15 ft past the foul line.
LANE_LENGTH_FT = 60.0
FOUL_LINE_X = -LANE_LENGTH_FT * FT
ARROWS_FT = 15.0
ARROW_BOARDS = (5, 10, 15, 20, 25, 30, 35)
N_BOARDS = 39
BOARD_WIDTH = scene.LANE_WIDTH / N_BOARDS
#: The lane box starts this far before the foul line (the ball's centre starts on the line).
APPROACH = 0.3
LANE_START_X = FOUL_LINE_X - APPROACH


class LaneError(InputError):
    """Bad input to the lane (a pattern, a ball, a delivery): one line naming the field."""


class GutterBall(LaneError):
    """The ball left the lane before the pins: a result (no pinfall, USBC rule 6b.1), not bad input;
    raised where phases are asked for (there are none past the gutter). ``side``: "left" or
    "right" (the bowler's view); ``ft``: feet past the foul line where it left."""

    def __init__(self, side: str, ft: float) -> None:
        self.side, self.ft = side, float(ft)
        super().__init__(f"delivery: a gutter ball: it left the lane into the {side} gutter "
                         f"{self.ft:.1f} ft past the foul line; no phases to report")


def hand_sign(hand: str) -> int:
    """+1 for a right-hander, -1 for a left-hander (the mirror in y).

    Args:
        hand: "right" or "left".

    Returns:
        +1 or -1.

    Raises:
        LaneError: any other ``hand``.
    """
    if hand not in ("right", "left"):
        raise LaneError(f"hand: must be 'right' or 'left', got {hand!r}")
    return 1 if hand == "right" else -1


def board_to_y(board, hand: str = "right"):
    """Lateral position (m, + = bowler's left) of a (continuous) board number for ``hand``.

    Args:
        board: a board number or an array of them (board 1 at the bowling hand's edge).
        hand: "right" or "left" (a left-hander's boards are mirrored).

    Returns:
        y (m), a float64 array of ``board``'s shape.

    Raises:
        LaneError: ``hand`` is neither "right" nor "left".
    """
    return hand_sign(hand) * (-scene.LANE_WIDTH / 2 + (np.asarray(board, dtype=float) - 0.5) * BOARD_WIDTH)


def y_to_board(y, hand: str = "right"):
    """The (continuous) board number of a lateral position ``y`` (m) for ``hand``.

    Args:
        y: lateral positions (m, + = bowler's left), a number or an array.
        hand: "right" or "left".

    Returns:
        the board numbers, a float64 array of ``y``'s shape (the inverse of :func:`board_to_y`).

    Raises:
        LaneError: ``hand`` is neither "right" nor "left".
    """
    return (hand_sign(hand) * np.asarray(y, dtype=float) + scene.LANE_WIDTH / 2) / BOARD_WIDTH + 0.5


def ft_to_x(ft):
    """x (m) of a distance in feet past the foul line.

    Args:
        ft: feet past the foul line, a number or an array.

    Returns:
        x (m) in the scene's frame, a float64 array of ``ft``'s shape.
    """
    return FOUL_LINE_X + np.asarray(ft, dtype=float) * FT


def x_to_ft(x):
    """Feet past the foul line of an x (m) in the scene's frame (the inverse of :func:`ft_to_x`).

    Args:
        x: x (m), a number or an array.

    Returns:
        feet past the foul line, a float64 array of ``x``'s shape.
    """
    return (np.asarray(x, dtype=float) - FOUL_LINE_X) / FT
