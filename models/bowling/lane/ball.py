"""A bowling ball in the ball maker's units, within USBC's limits.

* **Ball** (:class:`Ball`): weight (lb), RG and RG differential (in), coverstock friction,
  checked against USBC's limits (RG 2.46-2.80 in, differential <= 0.06 in, friction <= 0.32,
  at most 16 lb) with one-line errors naming the field. Inertia: ``I = m RG^2`` about the
  low-RG (pin) axis and ``m (RG + diff)^2`` about the two axes across it (a symmetric core:
  differential = high RG - low RG). The pin axis is placed :data:`PIN_TO_PAP_IN` inches of arc
  from the positive axis point (PAP, the hand-side end of the release's spin axis), towards
  the top of the ball: an assumed layout. The coverstock friction is the ball's friction on
  the dry lane (the back end); on full oil every ball gets :data:`MU_OIL`.

Pure numpy.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from nbst.models.bowling import scene
from nbst.models.bowling.lane.oil import MU_DRY, MU_OIL
from nbst.models.bowling.lane.units import LB, LaneError

__all__ = ["RG_RANGE", "DIFF_MAX", "FRICTION_MAX", "WEIGHT_MAX_LB", "Ball"]

#: USBC ball limits.
RG_RANGE = (2.46, 2.80)
DIFF_MAX = 0.06
FRICTION_MAX = 0.32
WEIGHT_MAX_LB = 16.0


@dataclass(frozen=True)
class Ball:
    """A ball in the ball maker's units: weight (lb), RG and differential (in), coverstock friction."""

    weight_lb: float = 15.0
    rg: float = 2.50
    diff: float = 0.040
    friction: float = MU_DRY

    def check(self) -> Ball:
        """The ball, or LaneError naming the first field outside USBC's limits."""
        for k in ("weight_lb", "rg", "diff", "friction"):
            v = getattr(self, k)
            if not isinstance(v, (int, float)) or isinstance(v, bool) or not math.isfinite(v):
                raise LaneError(f"ball.{k}: must be a finite number, got {v!r}")
        if not 6.0 <= self.weight_lb <= WEIGHT_MAX_LB:
            raise LaneError(f"ball.weight_lb: {self.weight_lb:g} lb is outside 6..{WEIGHT_MAX_LB:g} lb (USBC: at most 16 lb)")
        if not RG_RANGE[0] <= self.rg <= RG_RANGE[1]:
            raise LaneError(f"ball.rg: {self.rg:g} in is outside USBC's {RG_RANGE[0]:.2f}..{RG_RANGE[1]:.2f} in")
        if not 0.0 <= self.diff <= DIFF_MAX:
            raise LaneError(f"ball.diff: RG differential {self.diff:g} in is outside USBC's 0..{DIFF_MAX:.2f} in")
        if not 0.0 < self.friction <= FRICTION_MAX:
            raise LaneError(f"ball.friction: coverstock friction {self.friction:g} is outside USBC's (0, {FRICTION_MAX:.2f}]")
        if self.friction <= MU_OIL:
            raise LaneError(f"ball.friction: coverstock friction {self.friction:g} must exceed the oil's {MU_OIL:g}")
        return self

    @property
    def mass(self) -> float:
        return self.weight_lb * LB

    def principal_inertia(self) -> np.ndarray:
        """(3,) kg m^2: about the pin (low-RG) axis, then the two high axes."""
        lo, hi = self.rg * scene.INCH, (self.rg + self.diff) * scene.INCH
        return self.mass * np.array([lo * lo, hi * hi, hi * hi])

    def to_dict(self) -> dict:
        return asdict(self)
