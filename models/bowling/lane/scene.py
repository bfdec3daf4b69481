"""The lane half's scene: the full lane from the foul line, laid out for the shared scene.

:func:`layout` turns an oil pattern, a ball and a delivery into a
:class:`nbst.models.bowling.scene.LaneLayout`: one friction box per (segment, band) cell of the
pattern, ``mu = mu_dry - (mu_dry - mu_oil) u`` with the ball's coverstock friction as
``mu_dry``, then the dry back end to the pin deck; the foul line and the arrows (visual only);
the camera behind the foul line; the ball at the foul line with the ball maker's inertia, its
pin axis placed for the delivery. The shared :func:`nbst.models.bowling.scene.build_spec` (the
one path that builds a bowling scene) builds it; :func:`build_model` compiles and caches it.

Compute only: functions return values and models.
"""
from __future__ import annotations

from functools import lru_cache

from nbst.models.bowling import scene
from nbst.models.bowling.lane.ball import Ball
from nbst.models.bowling.lane.delivery import Delivery, pin_axis, quat_x_to
from nbst.models.bowling.lane.oil import MU_OIL, Pattern, friction, pattern
from nbst.models.bowling.lane.units import (ARROW_BOARDS, ARROWS_FT, BOARD_WIDTH, FOUL_LINE_X, LANE_START_X, LaneError,
                                            board_to_y, ft_to_x)

__all__ = ["layout", "lane_spec", "build_model"]


def layout(oil: str | Pattern = "house", ball: Ball | None = None, delivery: Delivery | None = None, *,
           mu_oil: float = MU_OIL) -> scene.LaneLayout:
    """The full lane of ``oil`` (a pattern or its name) for ``ball`` (default :class:`Ball`) with
    its pin axis placed for ``delivery``; ``mu_oil``: full-oil friction."""
    pat = pattern(oil) if isinstance(oil, str) else oil
    ball = (ball or Ball()).check()
    delivery = (delivery or Delivery()).check()
    half_w = scene.LANE_WIDTH / 2
    slab = 0.05
    cells = []
    x0 = LANE_START_X
    for k, (to_ft, bands) in enumerate(pat.segments):
        x1 = float(ft_to_x(to_ft))
        for lo, hi, u in bands:
            ya, yb = sorted((float(board_to_y(lo - 0.5)), float(board_to_y(hi + 0.5))))
            cells.append((f"oil_s{k}_b{lo}_{hi}", ((x0 + x1) / 2, (ya + yb) / 2, -slab),
                          ((x1 - x0) / 2, (yb - ya) / 2, slab), scene.OIL_RGBA, friction(u, ball.friction, mu_oil)))
        x0 = x1
    cells.append(("lane_backend", ((x0 + scene.DECK_FRONT_X) / 2, 0, -slab),
                  ((scene.DECK_FRONT_X - x0) / 2, half_w, slab), scene.LANE_RGBA, ball.friction))
    marks = [("foul_line", (FOUL_LINE_X, 0.0, 0.0005), (0.01, half_w, 0.0005))]
    marks += [(f"arrow{b}", (float(ft_to_x(ARROWS_FT)), float(board_to_y(b)), 0.0005), (0.06, BOARD_WIDTH / 3, 0.0005))
              for b in ARROW_BOARDS]
    return scene.LaneLayout(start_x=LANE_START_X, cells=tuple(cells), marks=tuple(marks), camera_x=FOUL_LINE_X - 1.5,
                            center=(FOUL_LINE_X / 2, 0.0, 0.2), extent=12.0,
                            ball_pos=(FOUL_LINE_X, 0.0, scene.BALL_RADIUS), ball_mass=ball.mass,
                            ball_inertia=tuple(ball.principal_inertia()), ball_iquat=tuple(quat_x_to(pin_axis(delivery))))


def lane_spec(oil: str | Pattern = "house", ball: Ball | None = None, delivery: Delivery | None = None, *,
               pins: bool = True, mu_oil: float = MU_OIL):
    """The shared :func:`nbst.models.bowling.scene.build_spec` of :func:`layout` (``pins=False``:
    the ball alone)."""
    return scene.build_spec(layout(oil, ball, delivery, mu_oil=mu_oil), pins=pins)


@lru_cache(maxsize=32)
def _model(oil, ball: Ball, delivery: Delivery, pins: bool, mu_oil: float):
    return lane_spec(oil, ball, delivery, pins=pins, mu_oil=mu_oil).compile()


def build_model(oil: str = "house", ball: Ball | None = None, delivery: Delivery | None = None, *, pins: bool = True,
                mu_oil: float = MU_OIL):
    """The compiled model of :func:`lane_spec` (cached by its arguments)."""
    if not (isinstance(mu_oil, (int, float)) and 0.0 < mu_oil < (ball or Ball()).friction):
        raise LaneError(f"mu_oil: must be in (0, the ball's friction), got {mu_oil!r}")
    return _model(oil, (ball or Ball()).check(), (delivery or Delivery()).check(), pins, float(mu_oil))
