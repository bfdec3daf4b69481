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

Importing this package imports nothing heavy; the submodules that need MuJoCo import it. The
entry points below load their module on first use: :func:`script_from_dict`, :func:`load_script`
and the registered scripts :data:`SCRIPTS` (``nbst.models.crash.script``), :func:`solve` and
:class:`CrashResult` (``nbst.models.crash.search``), :func:`reconstruct` and
:class:`Reconstruction` (``nbst.models.crash.reconstruct``).
"""
from __future__ import annotations

import importlib

__all__ = ["SCRIPTS", "Script", "script_from_dict", "load_script", "solve", "CrashResult", "reconstruct",
           "Reconstruction"]

_LAZY = {"SCRIPTS": "script", "Script": "script", "script_from_dict": "script", "load_script": "script",
         "solve": "search", "CrashResult": "search", "reconstruct": "reconstruct", "Reconstruction": "reconstruct"}


def __getattr__(name):
    if name in _LAZY:
        return getattr(importlib.import_module(f"nbst.models.crash.{_LAZY[name]}"), name)
    raise AttributeError(f"module 'nbst.models.crash' has no attribute {name!r}")
