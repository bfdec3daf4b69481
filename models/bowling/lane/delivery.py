"""The lane half's delivery: what the bowler does, in a bowler's units, and the release it gives.

* **Delivery** (:class:`Delivery`): hand, board at the foul line (or at the arrows), launch
  angle (degrees from straight down the lane, + towards board 1: out towards the gutter on
  the hand side, as a hook is thrown out to its breakpoint), speed (mph), rev rate (rpm),
  axis rotation (0 = end over end, 90 = pure side spin about the travel direction) and axis
  tilt (0 = a horizontal spin axis, 90 = spinning like a top). The ball's centre starts over
  the foul line on the lane (no loft), with the spin vector ``omega = rpm * (cos(tilt)
  (cos(rot) a_roll + sin(rot) a_side) + sin(tilt) a_up)``: ``a_roll`` the forward-roll axis,
  ``a_side`` along the travel direction with the sign that hooks towards the pocket
  (opposite the travel for a right-hander), ``a_up`` vertical with the PAP end tipped up.

The ball's layout (:func:`principal_axes`): its pin (low-RG) axis is placed ``pin_pap_in``
inches of arc from the positive axis point (PAP, the hand-side end of the release's spin
axis), towards the top of the ball (default :data:`PIN_TO_PAP_IN`: an assumed layout); its
intermediate axis (towards the mass bias, which matters when the core is asymmetric) is
placed ``mb_pap_in`` inches of arc from the PAP, a quarter turn round the PAP from the pin,
then made square to the pin axis; the high axis completes the frame.

Pure numpy.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from nbst.models.bowling import scene
from nbst.models.bowling.lane.units import ARROWS_FT, BOARD_WIDTH, FOUL_LINE_X, FT, MPH, LaneError, board_to_y, hand_sign

__all__ = ["PIN_TO_PAP_IN", "MB_TO_PAP_IN", "Delivery", "spin_axes", "quat_x_to", "quat_of_mat", "quat_to_mat",
           "pin_axis", "principal_axes", "initial_state"]

#: Assumed layout: the pin (low-RG axis) 4 1/2 in of arc from the PAP, towards the top of the ball,
#: and the mass bias 6 in from the PAP.
PIN_TO_PAP_IN = 4.5
MB_TO_PAP_IN = 6.0


@dataclass(frozen=True)
class Delivery:
    """A delivery in a bowler's units (see the module docstring for every convention)."""

    hand: str = "right"
    board: float = 12.5
    at: str = "foul"  # "foul": board at the foul line; "arrows": board where it crosses the arrows
    angle: float = 1.5
    mph: float = 17.0
    rpm: float = 300.0
    rotation: float = 45.0
    tilt: float = 15.0

    def check(self) -> Delivery:
        hand_sign(self.hand)
        if self.at not in ("foul", "arrows"):
            raise LaneError(f"at: must be 'foul' or 'arrows', got {self.at!r}")
        lim = {"board": (1.0, 39.0), "angle": (-10.0, 10.0), "mph": (5.0, 30.0), "rpm": (0.0, 800.0),
               "rotation": (0.0, 90.0), "tilt": (0.0, 90.0)}
        for k, (lo, hi) in lim.items():
            v = getattr(self, k)
            if not isinstance(v, (int, float)) or isinstance(v, bool) or not math.isfinite(v) or not lo <= v <= hi:
                raise LaneError(f"{k}: must be a number in [{lo:g}, {hi:g}], got {v!r}")
        if not 1.0 <= self.foul_board() <= 39.0:
            raise LaneError(f"board: {self.board:g} at the arrows, {self.angle:g} deg out, is board "
                            f"{self.foul_board():.1f} at the foul line: off the lane (1..39)")
        return self

    def foul_board(self) -> float:
        """Board at the foul line (from the arrows: the straight line back, 15 ft)."""
        if self.at == "foul":
            return float(self.board)
        return float(self.board + math.tan(math.radians(self.angle)) * ARROWS_FT * FT / BOARD_WIDTH)

    def to_dict(self) -> dict:
        return asdict(self)


def spin_axes(d: Delivery) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(travel direction, unit spin vector (right-hand rule), PAP direction) at release, world frame.

    Args:
        d: the delivery (its hand, angle, axis rotation and tilt).

    Returns:
        three (3,) float64 unit vectors.
    """
    s = hand_sign(d.hand)
    a = math.radians(d.angle)
    t = np.array([math.cos(a), -s * math.sin(a), 0.0])  # + angle: towards board 1
    z = np.array([0.0, 0.0, 1.0])
    a_roll = np.cross(z, t)  # forward roll: omega = z x v / R
    a_side = -s * t  # a right-hander's side spin: about -t, which hooks to +y (the pocket)
    a_up = -s * z  # so that the PAP end (-s * omega) tips up
    rot, tilt = math.radians(d.rotation), math.radians(d.tilt)
    w = math.cos(tilt) * (math.cos(rot) * a_roll + math.sin(rot) * a_side) + math.sin(tilt) * a_up
    w /= np.linalg.norm(w)
    pap = -s * w  # the hand-side end of the axis
    return t, w, pap


def quat_x_to(p: np.ndarray) -> list:
    """Unit quaternion (w, x, y, z) rotating the x axis onto the unit vector ``p``."""
    x = np.array([1.0, 0.0, 0.0])
    c = float(np.dot(x, p))
    if c < -1 + 1e-12:
        return [0.0, 0.0, 0.0, 1.0]
    v = np.cross(x, p)
    q = np.array([1.0 + c, *v])
    return list(q / np.linalg.norm(q))


def pin_axis(d: Delivery, pin_pap_in: float = PIN_TO_PAP_IN) -> np.ndarray:
    """The ball's pin (low-RG) axis at release: ``pin_pap_in`` of arc from the PAP, towards the top."""
    return principal_axes(d, pin_pap_in)[:, 0]


def principal_axes(d: Delivery, pin_pap_in: float = PIN_TO_PAP_IN, mb_pap_in: float = MB_TO_PAP_IN) -> np.ndarray:
    """(3, 3) world-frame principal axes of the ball at release, as columns: the pin (low RG),
    the intermediate axis (towards the mass bias) and the high axis (see the module docstring)."""
    _, w, pap = spin_axes(d)
    z = np.array([0.0, 0.0, 1.0])
    n = z - np.dot(z, w) * w
    n = n / np.linalg.norm(n) if np.linalg.norm(n) > 1e-9 else np.cross(w, [0.0, 1.0, 0.0])
    r_in = scene.BALL_RADIUS / scene.INCH
    beta = pin_pap_in / r_in
    e_pin = math.cos(beta) * pap + math.sin(beta) * n
    side = np.cross(pap, n)
    gam = mb_pap_in / r_in
    mb = math.cos(gam) * pap + math.sin(gam) * side
    e_mid = mb - np.dot(mb, e_pin) * e_pin
    if np.linalg.norm(e_mid) < 1e-9:  # the mass bias on the pin: any axis square to it
        e_mid = np.cross(e_pin, n if abs(np.dot(e_pin, n)) < 0.9 else side)
    e_mid /= np.linalg.norm(e_mid)
    return np.column_stack([e_pin, e_mid, np.cross(e_pin, e_mid)])


def quat_of_mat(R: np.ndarray) -> np.ndarray:
    """Unit quaternion (w, x, y, z) of a rotation matrix (Shepperd's method), w >= 0."""
    R = np.asarray(R, dtype=float)
    tr = R[0, 0] + R[1, 1] + R[2, 2]
    if tr > 0:
        s = 2.0 * math.sqrt(1.0 + tr)
        q = [s / 4, (R[2, 1] - R[1, 2]) / s, (R[0, 2] - R[2, 0]) / s, (R[1, 0] - R[0, 1]) / s]
    elif R[0, 0] > R[1, 1] and R[0, 0] > R[2, 2]:
        s = 2.0 * math.sqrt(1.0 + R[0, 0] - R[1, 1] - R[2, 2])
        q = [(R[2, 1] - R[1, 2]) / s, s / 4, (R[0, 1] + R[1, 0]) / s, (R[0, 2] + R[2, 0]) / s]
    elif R[1, 1] > R[2, 2]:
        s = 2.0 * math.sqrt(1.0 + R[1, 1] - R[0, 0] - R[2, 2])
        q = [(R[0, 2] - R[2, 0]) / s, (R[0, 1] + R[1, 0]) / s, s / 4, (R[1, 2] + R[2, 1]) / s]
    else:
        s = 2.0 * math.sqrt(1.0 + R[2, 2] - R[0, 0] - R[1, 1])
        q = [(R[1, 0] - R[0, 1]) / s, (R[0, 2] + R[2, 0]) / s, (R[1, 2] + R[2, 1]) / s, s / 4]
    qa = np.array(q)
    qa = qa if qa[0] >= 0 else -qa
    return qa / np.linalg.norm(qa)


def initial_state(d: Delivery) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The ball's state at release, at the foul line, world frame.

    Args:
        d: the delivery (checked by the caller).

    Returns:
        (position (3,), linear velocity (3,), angular velocity (3,)) float64 arrays, world frame.
    """
    t, w, _ = spin_axes(d)
    y = float(board_to_y(d.foul_board(), d.hand))
    pos = np.array([FOUL_LINE_X, y, scene.BALL_RADIUS])
    return pos, d.mph * MPH * t, d.rpm * 2 * math.pi / 60 * w


def quat_to_mat(q: np.ndarray) -> np.ndarray:
    """(n, 4) unit quaternions (w, x, y, z) -> (n, 3, 3) rotation matrices."""
    w, x, y, z = q.T
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1)], -2)
