"""The lane half's scene: the full lane from the foul line, laid out for the shared scene.

:func:`layout` turns a ball and a delivery into a :class:`nbst.models.bowling.scene.LaneLayout`:
the lane from the approach to the pin deck as one surface, the foul line and the arrows (visual
only), the camera behind the foul line, the ball at the foul line with the ball maker's inertia,
its principal axes placed for the delivery (:func:`.delivery.principal_axes`). The shared
:func:`nbst.models.bowling.scene.build_spec` (the one path that builds a bowling scene) builds it,
and :func:`lane_spec` makes the ball's contact with the lane **frictionless** (``condim 1``: the
lane carries the ball; its friction is Coulomb's, applied at the contact point by
:mod:`.friction` from the oil under it), while the pins meet a second, coincident surface with
the deck's friction (collision bits: ball-lane 2, pin-lane 4, everything else 1); the pin deck is
split the same way (the ball at ``scene.MU_DECK``, the pins at ``scene.LANE_PINS.mu_deck``). The oil is no
longer in the model: it is the :class:`.oil.OilField` the step loops carry, so one compiled
model serves every pattern. :func:`build_model` compiles and caches it.

Compute only: functions return values and models.
"""
from __future__ import annotations

from functools import lru_cache

from nbst.models.bowling import scene
from nbst.models.bowling.lane.ball import Ball
from nbst.models.bowling.lane.delivery import Delivery, principal_axes, quat_of_mat
from nbst.models.bowling.lane.units import (ARROW_BOARDS, ARROWS_FT, BOARD_WIDTH, FOUL_LINE_X, LANE_START_X,
                                            board_to_y, ft_to_x)

__all__ = ["SCENE", "EARLIER_SCENES", "LANE_GEOM", "PIN_LANE_GEOM", "DECK_GEOM", "PIN_DECK_GEOM", "layout",
           "lane_spec", "build_model", "ball_quat"]

#: The lane half's scene, as throw and atlas files name it: "lane-4" is this one (lane-3's with the pins'
#: friction on the deck 0.1, ``scene.LANE_PINS``, issue 48; the ball meets the deck at lane-3's 0.2, so a
#: ball's path to the pins is lane-3's); "lane-3" had the pin deck at 0.2 for both (lane-2's lane
#: with the pins fitted to carry, issue 34); "lane-2" had a frictionless lane contact
#: with Coulomb friction from the oil film and issue 22's pins; "lane-1" (files without a scene) was
#: issue 22's (MuJoCo's soft friction on boxes of relative oil).
SCENE = "lane-4"
#: The scenes before it, oldest first (throw files name them; they replay only on their own).
EARLIER_SCENES = ("lane-1", "lane-2", "lane-3")
LANE_GEOM = "lane_surface"
PIN_LANE_GEOM = "lane_surface_pins"
#: The pin deck as the ball meets it (``scene.MU_DECK``) and as the pins meet it (``scene.LANE_PINS.mu_deck``).
DECK_GEOM = "lane_deck"
PIN_DECK_GEOM = "lane_deck_pins"


def ball_quat(delivery: Delivery, ball: Ball):
    """The quaternion of the ball's principal axes (pin, intermediate, high) at release."""
    return quat_of_mat(principal_axes(delivery, ball.pin_pap_in, ball.mb_pap_in))


def layout(ball: Ball | None = None, delivery: Delivery | None = None) -> scene.LaneLayout:
    """The full lane for ``ball`` (default :class:`Ball`) with its axes placed for ``delivery``.

    Args:
        ball: the ball (None: the default ball).
        delivery: the delivery whose release orients the ball's axes (None: the default delivery).

    Returns:
        the shared scene's :class:`nbst.models.bowling.scene.LaneLayout` of the 60 ft lane.

    Raises:
        LaneError: the ball or the delivery outside its limits.
    """
    ball = (ball or Ball()).check()
    delivery = (delivery or Delivery()).check()
    half_w = scene.LANE_WIDTH / 2
    slab = 0.05
    cells = [(LANE_GEOM, ((LANE_START_X + scene.DECK_FRONT_X) / 2, 0.0, -slab),
              ((scene.DECK_FRONT_X - LANE_START_X) / 2, half_w, slab), scene.LANE_RGBA, scene.MU_DECK)]
    marks = [("foul_line", (FOUL_LINE_X, 0.0, 0.0005), (0.01, half_w, 0.0005))]
    marks += [(f"arrow{b}", (float(ft_to_x(ARROWS_FT)), float(board_to_y(b)), 0.0005), (0.06, BOARD_WIDTH / 3, 0.0005))
              for b in ARROW_BOARDS]
    return scene.LaneLayout(start_x=LANE_START_X, cells=tuple(cells), marks=tuple(marks), camera_x=FOUL_LINE_X - 1.5,
                            center=(FOUL_LINE_X / 2, 0.0, 0.2), extent=12.0,
                            ball_pos=(FOUL_LINE_X, 0.0, scene.BALL_RADIUS), ball_mass=ball.mass,
                            ball_inertia=tuple(ball.principal_inertia()),
                            ball_iquat=tuple(float(v) for v in ball_quat(delivery, ball)))


def lane_spec(ball: Ball | None = None, delivery: Delivery | None = None, *, pins: bool = True):
    """The shared :func:`nbst.models.bowling.scene.build_spec` of :func:`layout` (``pins=False``:
    the ball alone), with the lane's contacts split: frictionless for the ball, the deck's
    friction for the pins (see the module docstring); and the pin deck's split: ``scene.MU_DECK`` for
    the ball, ``scene.LANE_PINS.mu_deck`` for the pins."""
    spec = scene.build_spec(layout(ball, delivery), pins=pins)
    _pins_twin(spec, LANE_GEOM, PIN_LANE_GEOM).condim = 1  # the ball's friction is applied by hand
    _pins_twin(spec, DECK_GEOM, PIN_DECK_GEOM).friction = [scene.MU_DECK, 0.0, 0.0]
    b = spec.geom("ball")
    b.contype = b.conaffinity = 1 | 2
    if pins:
        for geom in spec.geoms:
            if geom.name.startswith("pin") and "_c" in geom.name:
                geom.contype = geom.conaffinity = 1 | 4
    return spec


def _pins_twin(spec, name: str, twin: str):
    """Make the static box ``name`` the ball's (collision bit 2) and add ``twin``, coincident and hidden,
    for the pins (bit 4) at ``scene.LANE_PINS.mu_deck``, its contact otherwise ``name``'s. Returns ``name``'s geom."""
    import mujoco

    g = spec.geom(name)
    g.contype = g.conaffinity = 2
    p = spec.worldbody.add_geom(name=twin, type=mujoco.mjtGeom.mjGEOM_BOX, pos=list(g.pos), size=list(g.size),
                                rgba=list(g.rgba), group=3)
    p.contype = p.conaffinity = 4
    p.priority = g.priority
    p.condim = 3
    p.friction = [scene.LANE_PINS.mu_deck, 0.0, 0.0]
    p.solref = list(g.solref)
    p.solimp = list(g.solimp)
    return g


@lru_cache(maxsize=32)
def _model(ball: Ball, delivery: Delivery, pins: bool):
    return lane_spec(ball, delivery, pins=pins).compile()


def build_model(ball: Ball | None = None, delivery: Delivery | None = None, *, pins: bool = True):
    """The compiled model of :func:`lane_spec` (cached by its arguments).

    Args:
        ball: the ball (None: the default ball).
        delivery: the delivery whose release orients the ball (None: the default).
        pins: False for the ball alone (no pins).

    Returns:
        a ``mujoco.MjModel`` (mujoco is imported here, not at import of the package).

    Raises:
        LaneError: the ball or the delivery outside its limits.
    """
    return _model((ball or Ball()).check(), (delivery or Delivery()).check(), pins)
