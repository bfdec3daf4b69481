"""Bowler profiles (issue 34): a typical strike ball and a correlated release noise per kind of bowler.

:data:`PROFILES` (a :class:`nbst.registry.Registry`) holds five (:class:`Profile`), each read from its data
file ``bowlers/<name>.json``, right-handed (``--hand left`` mirrors them: a
left-hander's lane is a right-hander's mirrored):

=========== ======== ===== ======== ===== ====================================================
profile      mph      rpm   rotation tilt  source
=========== ======== ===== ======== ===== ====================================================
pro          18.6     436   50       12    PBA League 2020, men's means (Pete Dougherty, Albany
                                           Times Union, 2020-09-29); rotation and tilt assumed
league200    17.0     350   55       12    assumed (between the pro and issue 22's 17/300)
league150    15.5     250   45       15    assumed (a stroker)
twohander    18.0     520   60       5     PBA League 2020: 4 of the top 5 rev rates were
                                           two-handers, the top 570 rpm; rotation and tilt assumed
cranker      18.0     450   60       10    assumed (a one-handed high-rev player, issue 48)
=========== ======== ===== ======== ===== ====================================================

Each strike ball's line is its foul-line board (:attr:`Profile.foul_board`, chosen so the ball breaks
on the house shot's outside boards) and the launch angle that brings the ball alone to board
17.5 at the head pin on the fresh house shot (``phases.aim_angle``; the angles are stored,
:func:`strike_ball` re-aims for another pattern or ball).

**Noise** (:class:`.noise.Noise`, one multivariate normal per throw). No published spread of
release speed, revs, axis or launch angle was found, nor a speed-rev correlation, so its shape is
assumed (:data:`NOISE_SHAPE`): issue 22's sigmas (board 1/2, launch angle 0.15 deg, 0.3 mph,
15 rpm, rotation 5 deg) with a tilt of 2 deg; speed and revs correlate +0.5 (a harder swing gives
both), axis rotation and revs -0.3 (turning the hand more trades revs for side roll). Its size is
fitted for the pro (issue 34's carry fit): the strike ball's to PBA's pocket-hit rate
(:data:`PRO_SCALE`), the spare ball's to PBA's televised spares (:data:`PRO_SPARE_SCALE`). The
league bowlers' sigmas are the shape's times their :attr:`Profile.noise_scale`, for strike and spare
balls alike, fitted (issue 48) to the averages their names say over 3-game blocks with transition
and the mover (seeds 101-103; held out: benchmarks/bench_bowling_calibration.py ``--part games``):
``league200`` x 0.55 (refitted on seeds 101-106 once the series' spare ball took a pin at a bare
split: x 0.5 gave 203.7 there, 0.55 199.5, 0.6 195.7), ``league150`` x 1.65; their axis rotations (55 and 45 deg, from 45 and 30) were
raised first, so that their strike balls enter at 4.6 and 3.1 deg and carry. The two-hander's and
the cranker's noises are the pro's.

Compute only.
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass, replace
from pathlib import Path

from nbst.models.bowling import lane
from nbst.models.bowling.lane.noise import Noise
from nbst.registry import Registry
from nbst.models.bowling.lane import phases

__all__ = ["Profile", "PROFILES", "NAMES", "DEFAULT_PROFILE", "HOUSE_PROFILE", "house_release", "PROFILES_DIR", "NOISE_SHAPE", "PRO_SCALE", "PRO_NOISE",
           "PRO_SPARE_SCALE", "PRO_SPARE_NOISE", "load_profile", "profile", "scaled", "strike_ball"]


def scaled(nz: Noise, k: float) -> Noise:
    """``nz`` with every standard deviation times ``k`` (the correlations kept).

    Args:
        nz: the noise to scale.
        k: the factor of every standard deviation (board, angle, mph, rpm, rotation, tilt).

    Returns:
        a new :class:`.noise.Noise`; ``nz`` itself is unchanged.
    """
    return replace(nz, board=nz.board * k, angle=nz.angle * k, mph=nz.mph * k, rpm=nz.rpm * k,
                   rotation=nz.rotation * k, tilt=nz.tilt * k)


#: The assumed shape of a release's noise (see the module docstring): issue 22's sigmas, tilt 2 deg,
#: the two correlations.
NOISE_SHAPE = Noise(board=0.5, angle=0.15, mph=0.3, rpm=15.0, rotation=5.0, tilt=2.0, corr_mph_rpm=0.5,
                    corr_rotation_rpm=-0.3)


@dataclass(frozen=True)
class Profile:
    """A kind of bowler: the strike ball (a right-handed :class:`.lane.Delivery` at the foul line)
    and the release noise around it.

    ``foul_board`` is the strike ball's board at the foul line; ``noise_scale`` and
    ``spare_noise_scale`` are its sigmas as multiples of :data:`NOISE_SHAPE` (the strike ball's,
    and the spare throws', None: the strike ball's), as its data file states them. ``reads_lane``
    (the file's optional ``"reads_lane"``, default false): with moves on, the bowler picks its line
    by reading the worn lane (:func:`.reading.read_line`) instead of the "2 and 1" mover.
    """

    name: str
    description: str
    strike: lane.Delivery
    noise: Noise
    spare_noise: Noise | None = None
    foul_board: float = 0.0
    noise_scale: float = 1.0
    spare_noise_scale: float | None = None
    reads_lane: bool = False

    def delivery(self, hand: str = "right") -> lane.Delivery:
        """The strike ball thrown with ``hand`` (a left-hander's is the mirror image).

        Raises:
            LaneError: ``hand`` is neither "right" nor "left".
        """
        return replace(self.strike, hand=hand).check()

    def spare(self) -> Noise:
        """The noise of this bowler's spare throws (the strike ball's where none is set)."""
        return self.noise if self.spare_noise is None else self.spare_noise


#: Where the profiles' data files are: one JSON per profile, ``<name>.json`` (package data).
PROFILES_DIR = Path(__file__).with_name("bowlers")
#: A profile file's format and the fields it holds, each a number but name and description.
PROFILE_FORMAT = "nbst-bowler-profile"
_NUMBERS = ("foul_board", "angle", "mph", "rpm", "rotation", "tilt", "noise_scale")


def load_profile(path) -> Profile:
    """A bowler profile from its data file (``bowlers/<name>.json``): the strike ball's line and
    release, and its noise as multiples of :data:`NOISE_SHAPE`.

    Args:
        path: the profile's JSON file (format ``nbst-bowler-profile``, version 1).

    Returns:
        the :class:`Profile`, its strike ball and noises checked.

    Raises:
        LaneError: a field is missing, not a finite number, or outside the delivery's or the
            noise's limits (the message names the file and the field).
    """
    p = Path(path)
    doc = json.loads(p.read_text(encoding="utf-8"))
    if not isinstance(doc, dict) or doc.get("format") != PROFILE_FORMAT or doc.get("version") != 1:
        raise lane.LaneError(f"{p}: format: must be {PROFILE_FORMAT!r}, version 1")
    for k in ("name", "description", *_NUMBERS):
        if k not in doc:
            raise lane.LaneError(f"{p}: {k}: missing")
        v = doc[k]
        if k in _NUMBERS and (isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v)):
            raise lane.LaneError(f"{p}: {k}: must be a finite number, got {v!r}")
    spare_k = doc.get("spare_noise_scale")
    reads = doc.get("reads_lane", False)
    if not isinstance(reads, bool):
        raise lane.LaneError(f"{p}: reads_lane: must be true or false, got {reads!r}")
    try:
        strike = lane.Delivery(board=doc["foul_board"], at="foul", angle=doc["angle"], mph=doc["mph"], rpm=doc["rpm"],
                               rotation=doc["rotation"], tilt=doc["tilt"]).check()
        nz = scaled(NOISE_SHAPE, doc["noise_scale"]).check()
        spare = None if spare_k is None else scaled(NOISE_SHAPE, spare_k).check()
    except lane.LaneError as e:
        raise lane.LaneError(f"{p}: {e}") from None
    return Profile(doc["name"], doc["description"], strike, nz, spare, foul_board=doc["foul_board"],
                   noise_scale=doc["noise_scale"], spare_noise_scale=spare_k, reads_lane=reads)


#: The bowler profiles by name, registered once each from its data file, in this order. Adding one
#: is one line here and one file in ``bowlers/``. The launch angles in the files are
#: ``phases.aim_angle`` to board 17.5 on the fresh house shot with the default ball.
PROFILES: Registry[Profile] = Registry("bowler profile")
for _name in ("pro", "league200", "league150", "twohander", "cranker"):
    _prof = load_profile(PROFILES_DIR / f"{_name}.json")
    if _prof.name != _name:
        raise lane.LaneError(f"{_name}.json: name: {_prof.name!r} must be the file's name {_name!r}")
    PROFILES.register(_name, _prof, help=_prof.description)
NAMES = PROFILES.names()
#: The profile ``bowl series`` bowls when none is named.
DEFAULT_PROFILE = "pro"
#: The typical house bowler: its strike ball is the release of a delivery whose flags are left out
#: (``bowl throw`` and ``bowl frame`` without ``--bowler``); its noise is not used there (the
#: default release noise is, :data:`.noise.DEFAULT`).
HOUSE_PROFILE = "league200"


def house_release() -> lane.Delivery:
    """The default release: :data:`HOUSE_PROFILE`'s strike ball, right-handed, board at the foul line.

    Returns:
        the :class:`.lane.Delivery` (checked).
    """
    return PROFILES[HOUSE_PROFILE].delivery("right")

#: The pro's strike-ball noise: the shape times PRO_SCALE, fitted so the pro's strike ball hits the pocket
#: (boards 16.5-18.5 at the head pin, entering at 4-6 deg) as often as PBA's televised finalists did, 54 of
#: 66 (82 %; Jason Thomas, PBA.com): 0.5 gives 80.5 % of 200 throws (benchmarks/bench_carry_fit.py).
#: The pro's data file holds it (``noise_scale``).
PRO_SCALE = PROFILES["pro"].noise_scale
PRO_NOISE = PROFILES["pro"].noise
#: The pro's spare-ball noise: the shape times PRO_SPARE_SCALE, fitted to PBA's televised spares (3-10
#: 48.6 %, 10 pin 95.9 %, 7 pin 95.5 %; ESPN The Magazine, 2011): at the strike ball's noise the 3-10
#: converts 89 of 100 (benchmarks/bench_carry_fit.py, docs/results/bowling.md "Pin carry, fitted").
PRO_SPARE_SCALE = PROFILES["pro"].spare_noise_scale
PRO_SPARE_NOISE = PROFILES["pro"].spare()


def profile(name: str) -> Profile:
    """The profile called ``name`` (any case).

    Args:
        name: a name of :data:`PROFILES`.

    Returns:
        the :class:`Profile`.

    Raises:
        LaneError: no profile has that name (one line, the names).
    """
    if name not in PROFILES:
        raise lane.LaneError(f"bowler: no profile {name!r}; profiles: {', '.join(NAMES)}")
    return PROFILES[name]


def strike_ball(name: str, oil="house", ball: lane.Ball | None = None, hand: str = "right") -> lane.Delivery:
    """The profile's strike ball aimed again (its launch angle) at board 17.5 on ``oil`` with ``ball``.

    Args:
        name: the profile's name.
        oil: the oil pattern (a name of :data:`.oil.PATTERNS` or a pattern).
        ball: the ball (default: :class:`.lane.Ball`'s defaults).
        hand: "right" or "left".

    Returns:
        the strike ball's :class:`.lane.Delivery`, its launch angle re-aimed.

    Raises:
        LaneError: an unknown profile or hand.
    """
    d, _ = phases.aim_angle(profile(name).delivery(hand), 17.5, oil, ball)
    return d
