"""A bowling ball in the ball maker's units, within USBC's limits.

* **Ball** (:class:`Ball`): weight (lb), RG, RG differential and intermediate differential
  (in), coverstock friction, how fast the cover absorbs the oil it picks up, and the layout
  (pin and mass bias to the PAP, inches of arc), checked against USBC's limits (RG 2.46-2.80
  in, differential <= 0.06 in, friction <= 0.32, at most 16 lb) with one-line errors naming the
  field. Principal moments (:meth:`Ball.principal_inertia`), as ball makers define them
  (differential = high RG - low RG; intermediate differential = high RG - intermediate RG):
  ``m RG^2`` about the low-RG (pin) axis, ``m (RG + diff - intdiff)^2`` about the
  intermediate axis (towards the mass bias), ``m (RG + diff)^2`` about the high axis. Where
  the axes point at release is the layout (:func:`.delivery.principal_axes`). The coverstock
  friction is the ball's friction on the dry lane; on a full film every ball gets
  :data:`MU_OIL` (:class:`.oil.OilLaw`).
* **Balls** (:data:`BALLS`): the named balls, a :class:`nbst.registry.Registry`, each read from
  its data file ``balls/<name>.json``; :data:`DEFAULT_BALL` is the one thrown when none is named
  (``Ball()``'s fields). Adding one is one line and one file.

Pure numpy.
"""
from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, fields
from pathlib import Path

import numpy as np

from nbst.models.bowling import scene
from nbst.models.bowling.lane.oil import MU_DRY, MU_OIL
from nbst.models.bowling.lane.units import LB, LaneError
from nbst.registry import Registry

__all__ = ["RG_RANGE", "DIFF_MAX", "FRICTION_MAX", "WEIGHT_MAX_LB", "Ball", "BALLS", "BALLS_DIR", "DEFAULT_BALL",
           "load_ball"]

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
    intdiff: float = 0.0
    #: Layout (inches of arc from the PAP): the pin (low-RG axis) and the mass bias (asymmetric cores).
    pin_pap_in: float = 4.5
    mb_pap_in: float = 6.0
    #: Seconds in which the cover absorbs all but 1/e of the oil it carries (a reactive cover;
    #: 0: never, a plastic or urethane cover that keeps its oil ring).
    absorb_s: float = 1.0

    def check(self) -> Ball:
        """The ball, or LaneError naming the first field outside USBC's limits."""
        for k in ("weight_lb", "rg", "diff", "friction", "intdiff", "pin_pap_in", "mb_pap_in", "absorb_s"):
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
        if not 0.0 <= self.intdiff <= self.diff:
            raise LaneError(f"ball.intdiff: intermediate differential {self.intdiff:g} in is outside 0..the "
                            f"differential {self.diff:g} in")
        for k in ("pin_pap_in", "mb_pap_in"):
            if not 0.0 <= getattr(self, k) <= 13.35:
                raise LaneError(f"ball.{k}: {getattr(self, k):g} in of arc is outside 0..13.35 in (half the ball's "
                                f"circumference)")
        if not 0.0 <= self.absorb_s <= 1000.0:
            raise LaneError(f"ball.absorb_s: {self.absorb_s:g} s is outside 0..1000 s (0: the cover never absorbs)")
        if self.friction <= MU_OIL:
            raise LaneError(f"ball.friction: coverstock friction {self.friction:g} must exceed the oil's {MU_OIL:g}")
        return self

    @property
    def mass(self) -> float:
        return self.weight_lb * LB

    def principal_inertia(self) -> np.ndarray:
        """(3,) kg m^2: about the pin (low-RG) axis, the intermediate axis, the high axis."""
        lo, hi = self.rg * scene.INCH, (self.rg + self.diff) * scene.INCH
        mid = (self.rg + self.diff - self.intdiff) * scene.INCH
        return self.mass * np.array([lo * lo, mid * mid, hi * hi])

    def to_dict(self) -> dict:
        return asdict(self)


#: Where the balls' data files are: one JSON per ball, ``<name>.json`` (package data).
BALLS_DIR = Path(__file__).with_name("balls")
BALL_FORMAT = "nbst-bowling-ball"


def load_ball(path) -> Ball:
    """A named ball from its data file (``balls/<name>.json``: its :class:`Ball` fields).

    Args:
        path: the ball's JSON file (format ``nbst-bowling-ball``, version 1).

    Returns:
        the :class:`Ball`, checked against USBC's limits.

    Raises:
        LaneError: not a ball file, an unknown field, or a field outside USBC's limits (the
            message names the file and the field).
    """
    p = Path(path)
    doc = json.loads(p.read_text(encoding="utf-8"))
    if not isinstance(doc, dict) or doc.get("format") != BALL_FORMAT or doc.get("version") != 1:
        raise LaneError(f"{p}: format: must be {BALL_FORMAT!r}, version 1")
    keys = {f.name for f in fields(Ball)}
    extra = sorted(set(doc) - keys - {"format", "version", "name", "description"})
    if extra:
        raise LaneError(f"{p}: {extra[0]}: unknown field (a ball's fields are {', '.join(sorted(keys))})")
    try:
        return Ball(**{k: doc[k] for k in keys if k in doc}).check()
    except LaneError as e:
        raise LaneError(f"{p}: {e}") from None


def _help(name: str) -> str:
    return json.loads((BALLS_DIR / f"{name}.json").read_text(encoding="utf-8")).get("description", "")


#: The named balls, registered once each from its data file, in this order.
BALLS: Registry[Ball] = Registry("ball")
for _name in ("reactive",):
    BALLS.register(_name, load_ball(BALLS_DIR / f"{_name}.json"), help=_help(_name))
#: The ball thrown when none is named: ``Ball()``, field for field.
DEFAULT_BALL = "reactive"
