"""nbst.models.bowling: ten-pin bowling synthesized on MuJoCo rollouts (docs/bowling.md).

The words, one per idea: a **delivery** is what the bowler does; a **throw** is its result
(the ball's run and the pins down); a throw file records both; a **frame** is a throw into the
pins from the foul line, run until they settle.

Two halves over a shared core:

* :mod:`.deck` -- the deck half: deliveries 5 m before the pins (the ball's y, speed, angle and
  spin there), the search for a requested set of pins, the atlas, the 5 m throw file;
* :mod:`.lane` -- the lane half: deliveries from the foul line in a bowler's units over an oil
  pattern, frames with USBC pinfall, release noise and probabilities, the robust search,
  spares and the pocket map, the foul-line atlas, the foul-line throw file;
* the core both import: :mod:`.pin` (the pin's solid, trimesh), :mod:`.scene` (the one path
  that builds a bowling MjSpec, USBC dimensions), :mod:`.geometry` (which subsets the deck's
  geometry allows), :mod:`.pinfall` (which pins are down, masks), :mod:`.subsets` (Hamming
  distance, the archive keyed by subset), :mod:`.files` (the input gate of every bowling file).

The machinery every rollout search shares (the runner, the archive, the noise and
probability, the robust maximiser, the ladder, the cluster hooks) is the rollout room's,
:mod:`nbst.models.mjsearch`. The layers are pyproject's ``bowling-layers`` contracts: the
halves never import each other. Importing this package imports neither mujoco nor trimesh.
"""

__all__ = ["deck", "lane", "pin", "scene", "geometry", "pinfall", "subsets", "files"]
