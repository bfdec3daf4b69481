"""nbst.models.bowling.deck: the deck half, throws from 5 m before the pins.

The simulated lane is the last 5.5 m before the pins (the end of the oil, the dry back end,
the deck); a **delivery** is the ball's state 5 m before the head pin (y, speed, angle, spin),
and the **throw** is its rollout: which pins are down after 2.5 s. Searches find a delivery
for a requested set of pins down, and an atlas one for as many of the 1,023 subsets as a
budget finds; both run on the rollout room (:mod:`nbst.models.mjsearch`). Modules, from the
bottom:

* :mod:`.delivery` -- :class:`Delivery`, its initial state, :class:`DeliveryRunner` (rollouts on K threads);
* :mod:`.cluster` -- the same runner's rollouts on a Dask cluster;
* :mod:`.search` -- a delivery for a requested set of pins (CMA-ES restarts), robustness probes;
* :mod:`.atlas` -- one delivery per subset (MAP-Elites, uniform or targeted);
* :mod:`.shotfile` -- the 5 m throw file, replayable with plain MuJoCo, and its atlas: checked input;
* :mod:`.folder` -- an atlas folder on disk: its throw files, resuming, the summaries;
* :mod:`.figure` -- the atlas's picture.

This package re-exports :mod:`.delivery`'s names (``deck.Delivery``, ``deck.DeliveryRunner``,
``deck.BOUNDS``). Importing it imports numpy, not mujoco.
"""
from __future__ import annotations

from nbst.models.bowling.deck.delivery import *  # noqa: F401,F403
from nbst.models.bowling.deck.delivery import __all__ as _delivery

__all__ = list(_delivery)
