"""Bowler profiles (issue 34): a typical strike ball and a correlated release noise per kind of bowler.

:data:`PROFILES` holds four (:class:`Profile`), right-handed (``--hand left`` mirrors them: a
left-hander's lane is a right-hander's mirrored):

=========== ======== ===== ======== ===== ====================================================
profile      mph      rpm   rotation tilt  source
=========== ======== ===== ======== ===== ====================================================
pro          18.6     436   50       12    PBA League 2020, men's means (Pete Dougherty, Albany
                                           Times Union, 2020-09-29); rotation and tilt assumed
league200    17.0     350   45       12    assumed (between the pro and issue 22's 17/300)
league150    15.5     250   30       15    assumed (a stroker)
twohander    18.0     520   40       5     PBA League 2020: 4 of the top 5 rev rates were
                                           two-handers, the top 570 rpm; tilt assumed
=========== ======== ===== ======== ===== ====================================================

Each strike ball's line is its foul-line board (:data:`FOUL_BOARDS`, chosen so the ball breaks
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
league bowlers' sigmas are the shape's times :data:`LEAGUE_SCALE` (1.8 and 3, assumed), for strike
and spare balls alike; the two-hander's are the pro's.

Compute only.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

from nbst.models.bowling import lane
from nbst.models.bowling.lane.noise import Noise

__all__ = ["Profile", "PROFILES", "NAMES", "FOUL_BOARDS", "LEAGUE_SCALE", "NOISE_SHAPE", "PRO_SCALE", "PRO_NOISE",
           "PRO_SPARE_SCALE", "PRO_SPARE_NOISE",
           "profile", "scaled", "strike_ball"]


def scaled(nz: Noise, k: float) -> Noise:
    """``nz`` with every standard deviation times ``k`` (the correlations kept)."""
    return replace(nz, board=nz.board * k, angle=nz.angle * k, mph=nz.mph * k, rpm=nz.rpm * k,
                   rotation=nz.rotation * k, tilt=nz.tilt * k)


#: The assumed shape of a release's noise (see the module docstring): issue 22's sigmas, tilt 2 deg,
#: the two correlations.
NOISE_SHAPE = Noise(board=0.5, angle=0.15, mph=0.3, rpm=15.0, rotation=5.0, tilt=2.0, corr_mph_rpm=0.5,
                    corr_rotation_rpm=-0.3)
#: The pro's strike-ball noise: the shape times PRO_SCALE, fitted so the pro's strike ball hits the pocket
#: (boards 16.5-18.5 at the head pin, entering at 4-6 deg) as often as PBA's televised finalists did, 54 of
#: 66 (82 %; Jason Thomas, PBA.com): 0.5 gives 80.5 % of 200 throws (benchmarks/bench_carry_fit.py).
PRO_SCALE = 0.5
PRO_NOISE = scaled(NOISE_SHAPE, PRO_SCALE)
#: The pro's spare-ball noise: the shape times PRO_SPARE_SCALE, fitted to PBA's televised spares (3-10
#: 48.6 %, 10 pin 95.9 %, 7 pin 95.5 %; ESPN The Magazine, 2011): at the strike ball's noise the 3-10
#: converts 89 of 100 (benchmarks/bench_carry_fit.py, docs/results/bowling.md "Pin carry, fitted").
PRO_SPARE_SCALE = 1.25
PRO_SPARE_NOISE = scaled(NOISE_SHAPE, PRO_SPARE_SCALE)
#: The league bowlers' sigmas, as multiples of the shape (assumed).
LEAGUE_SCALE = {"league200": 1.8, "league150": 3.0}
#: Foul-line boards of the strike balls (right-handed).
FOUL_BOARDS = {"pro": 23.0, "league200": 20.0, "league150": 14.0, "twohander": 26.0}


@dataclass(frozen=True)
class Profile:
    """A kind of bowler: the strike ball (a right-handed :class:`.lane.Delivery` at the foul line)
    and the release noise around it."""

    name: str
    description: str
    strike: lane.Delivery
    noise: Noise
    spare_noise: Noise | None = None

    def delivery(self, hand: str = "right") -> lane.Delivery:
        return replace(self.strike, hand=hand).check()

    def spare(self) -> Noise:
        """The noise of this bowler's spare throws (the strike ball's where none is set)."""
        return self.noise if self.spare_noise is None else self.spare_noise


def _p(name, description, mph, rpm, rotation, tilt, angle, noise, spare_noise=None) -> Profile:
    d = lane.Delivery(board=FOUL_BOARDS[name], at="foul", angle=angle, mph=mph, rpm=rpm, rotation=rotation, tilt=tilt)
    return Profile(name, description, d.check(), noise.check(), None if spare_noise is None else spare_noise.check())


#: The launch angles: ``phases.aim_angle`` to board 17.5 on the fresh house shot, the default ball.
PROFILES = {p.name: p for p in (
    _p("pro", "PBA pro: 18.6 mph, 436 rpm (PBA League 2020 means)", 18.6, 436.0, 50.0, 12.0, 3.0578, PRO_NOISE,
       PRO_SPARE_NOISE),
    _p("league200", "200-average league bowler: 17 mph, 350 rpm (assumed)", 17.0, 350.0, 45.0, 12.0, 2.8188,
       scaled(NOISE_SHAPE, LEAGUE_SCALE["league200"])),
    _p("league150", "150-average league bowler: 15.5 mph, 250 rpm (assumed)", 15.5, 250.0, 30.0, 15.0, 1.3773,
       scaled(NOISE_SHAPE, LEAGUE_SCALE["league150"])),
    _p("twohander", "two-handed: 18 mph, 520 rpm (PBA League 2020's top rev rates)", 18.0, 520.0, 40.0, 5.0, 3.9612,
       PRO_NOISE, PRO_SPARE_NOISE),
)}
NAMES = tuple(PROFILES)


def profile(name: str) -> Profile:
    """The profile called ``name``; LaneError (one line, the names) for any other."""
    if name not in PROFILES:
        raise lane.LaneError(f"bowler: no profile {name!r}; profiles: {', '.join(NAMES)}")
    return PROFILES[name]


def strike_ball(name: str, oil="house", ball: lane.Ball | None = None, hand: str = "right") -> lane.Delivery:
    """The profile's strike ball aimed again (its launch angle) at board 17.5 on ``oil`` with ``ball``."""
    from nbst.models.bowling.lane import phases

    d, _ = phases.aim_angle(profile(name).delivery(hand), 17.5, oil, ball)
    return d
