"""nbst.models.bowling.lane: the lane half, bowling from the foul line in a bowler's units.

A **delivery** (what the bowler does: hand, board, angle, mph, rpm, axis rotation and tilt) is
thrown down the full 60 ft lane, over an oil pattern, with a ball in the ball maker's units; the
**throw** is what happens: the ball's phases (:func:`throw`) and, into the pins, a frame
settled and counted as USBC counts pinfall (:mod:`.frame`). Modules, from the bottom:

* :mod:`.units` -- boards, feet, mph, the hand; :class:`LaneError`;
* :mod:`.oil` -- oil pattern files, the film they lay, the film-to-friction law, the lane's
  oil now (:class:`OilField`); the shipped patterns registered once (:data:`PATTERNS`);
* :mod:`.ball` -- :class:`Ball` within USBC's limits (RG, differentials, layout, cover);
* :mod:`.delivery` -- :class:`Delivery` and the release it gives (spin axes, the ball's axes);
* :mod:`.names` -- the names of hits and leaves (pocket, light, split by USBC, ringing 10, ...);
* :mod:`.scene` -- the full lane laid out for the shared scene (:func:`layout`, :func:`build_model`;
  :data:`SCENE` names it in files);
* :mod:`.friction` -- Coulomb friction at the contact and the oil lane and cover trade (numba);
* :mod:`.phases` -- the ball alone down the lane (:func:`throw`, :class:`ThrowResult`);
* :mod:`.frame` -- a throw into the pins, settled, USBC pinfall (:func:`.frame.run_frame`);
* :mod:`.noise` -- the release noise and the probability of an outcome;
* :mod:`.profiles` -- bowler profiles: a strike ball and a correlated release noise each;
* :mod:`.robust` -- the delivery most likely to give an outcome;
* :mod:`.spares` -- aiming, the pocket map, the best delivery at each spare;
* :mod:`.atlas` -- the atlas from the foul line (one delivery per subset, its probability);
* :mod:`.transition` -- games in order on one lane that every ball wears (lane transition, moves);
* :mod:`.throwfile` -- throw files and throw atlases, checked input;
* :mod:`.advise` -- a bowler's line (stance, target, breakpoint, entry) and a coach's advice.

This package re-exports the foundation's names (units, oil, ball, delivery, scene, phases), so
``lane.Delivery``, ``lane.board_to_y``, ``lane.throw`` read as one vocabulary; the modules above
the foundation are imported by name (``from nbst.models.bowling.lane import frame``).
Importing it imports numpy and reads the shipped oil pattern files, not mujoco or numba
(:mod:`.friction` is imported by the step loops when they run).
"""
from __future__ import annotations

from nbst.models.bowling.lane.ball import *  # noqa: F401,F403
from nbst.models.bowling.lane.ball import __all__ as _ball
from nbst.models.bowling.lane.delivery import *  # noqa: F401,F403
from nbst.models.bowling.lane.delivery import __all__ as _delivery
from nbst.models.bowling.lane.oil import *  # noqa: F401,F403
from nbst.models.bowling.lane.oil import __all__ as _oil
from nbst.models.bowling.lane.phases import *  # noqa: F401,F403
from nbst.models.bowling.lane.phases import __all__ as _phases
from nbst.models.bowling.lane.scene import *  # noqa: F401,F403
from nbst.models.bowling.lane.scene import __all__ as _scene
from nbst.models.bowling.lane.units import *  # noqa: F401,F403
from nbst.models.bowling.lane.units import __all__ as _units

__all__ = [*_units, *_oil, *_ball, *_delivery, *_scene, *_phases]
