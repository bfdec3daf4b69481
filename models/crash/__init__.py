"""nbst.models.crash: the paper's second challenge, a multi-vehicle crash scripted and solved on MuJoCo.

Rooms, bottom up (the layer contract in pyproject.toml lists them):

* :mod:`.vehicle`: the built-in vehicle types (sedan, SUV, van) and their MuJoCo bodies;
* :mod:`.road`: the road layouts (straight, 4-way intersection, curve), curbs and barriers;
* :mod:`.scene`: a road and its vehicles as one MuJoCo model, with the contact sensors;
* :mod:`.checks`: the physics checks (braking, tilt table, restitution, the NCAP pulse);
* :mod:`.fields`, :mod:`.script`: the ``nbst-crash-script`` file and its input gate;
* :mod:`.driver`: the partially autonomous drivers; :mod:`.outcome`: what happened, the fates,
  the signature; :mod:`.space`: the drivers' intents as a search space;
* :mod:`.run`: closed-loop rollouts (on the rollout room's batch runner); :mod:`.crashfile`: the
  crash file and its replay;
* :mod:`.search`: the paper's signature search over per-vehicle blocks; :mod:`.robust`: noise,
  probability, the ladder, the robust maximiser; :mod:`.reconstruct`: rest poses back to speeds;
  :mod:`.planted`: scripts and cases with a known answer.

Importing this package imports nothing heavy; the submodules that need MuJoCo import it.
"""
