"""Which pins are down: the rule both halves count by, and the 10-bit signature of a set of pins.

A pin is **down** when its axis tilts more than :data:`DOWN_TILT_DEG` from vertical, or it has
left the deck: its base more than :data:`LEFT_DECK_DEPTH` below the lane (a gutter, the pit),
past the pit edge, or over the lane's edge. (A frame from the foul line adds USBC's dead wood,
a pin leaning on a partition: :mod:`.lane.frame`.) The **signature** of a throw is its set of
pins down as a 10-bit mask, bit n-1 for pin n (USBC numbers, 1 in front, 7 back left, 10 back
right, seen by a right-handed bowler).

Pure numpy: poses come from a qpos vector of any bowling scene (the pins' free joints are
found by name).
"""
from __future__ import annotations

import math

import numpy as np

from nbst.models.bowling import scene

__all__ = ["DOWN_TILT_DEG", "LEFT_DECK_DEPTH", "pin_addresses", "poses", "cos_tilt", "tilted", "off_deck",
           "pins_down", "mask_of", "pins_of", "mask_from_pins"]

#: Tilt beyond which a pin counts as down (degrees from vertical).
DOWN_TILT_DEG = 45.0
#: A pin whose base is this far below the deck (m) has left it (gutter, pit).
LEFT_DECK_DEPTH = 0.02


def pin_addresses(model) -> np.ndarray:
    """(10,) int: qpos address of each pin's free joint, pins 1..10."""
    return np.array([int(model.joint(f"pin{n}_free").qposadr[0]) for n in scene.PIN_NUMBERS])


def poses(model, qpos) -> np.ndarray:
    """(..., 10, 7): each pin's position and quaternion (w, x, y, z) in ``qpos`` (..., nq)."""
    adr = pin_addresses(model)
    return np.asarray(qpos, dtype=float)[..., adr[:, None] + np.arange(7)]


def cos_tilt(p) -> np.ndarray:
    """(..., 10): the z-component of each pin's axis, from poses ``p`` (..., 10, 7)."""
    qw, qx, qy, qz = p[..., 3], p[..., 4], p[..., 5], p[..., 6]
    return 1.0 - 2.0 * (qx**2 + qy**2) / (qw**2 + qx**2 + qy**2 + qz**2)


def tilted(p) -> np.ndarray:
    """(..., 10) bool: tilted past :data:`DOWN_TILT_DEG`."""
    return cos_tilt(p) < math.cos(math.radians(DOWN_TILT_DEG))


def off_deck(p) -> np.ndarray:
    """(..., 10) bool: below the deck, past the pit edge, or over the lane's edge."""
    x, y, z = p[..., 0], p[..., 1], p[..., 2]
    return (z < -LEFT_DECK_DEPTH) | (x > scene.PIT_EDGE_X) | (np.abs(y) > scene.LANE_WIDTH / 2)


def pins_down(model, qpos) -> np.ndarray:
    """(..., 10) bool: pin n-1 down in each final ``qpos`` (..., nq) (tilted or off the deck)."""
    p = poses(model, qpos)
    return tilted(p) | off_deck(p)


def mask_of(down) -> np.ndarray:
    """10-bit signature(s) from (..., 10) bool: bit n-1 set when pin n is down."""
    return (np.asarray(down, dtype=np.int64) << np.arange(10)).sum(axis=-1)


def pins_of(mask: int) -> list[int]:
    """Pin numbers in a 10-bit mask, ascending."""
    return [n for n in scene.PIN_NUMBERS if int(mask) >> (n - 1) & 1]


def mask_from_pins(pins) -> int:
    """The 10-bit mask of pin numbers ``pins``."""
    return int(sum(1 << (int(n) - 1) for n in set(pins)))
