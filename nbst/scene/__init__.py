"""nbst.scene: bring your own MuJoCo scene (docs/scene.md).

The scene is the user's MJCF; what must happen is a small JSON file, the fates file
(``"format": "nbst-fates"``). Underneath runs the paper's per-body signature search over the
initial velocities of the scene's free bodies. One module each, top to bottom:

* :mod:`.api` -- :func:`solve`, the one typed way in;
* :mod:`.validate` -- ``validate_solution``: the fates under MuJoCo's other integrators,
  solvers, cones, finer steps and noise (``nbst scene validate``);
* :mod:`.solution` -- the solution file (``"nbst-scene-solution"``), :class:`SceneResult`,
  :func:`replay_solution` (bit for bit with a plain ``mj_step`` loop), ``export_scene`` (the
  scene with a keyframe holding the initial state);
* :mod:`.search` -- the signature search (:func:`~.search.signature_search`);
* :mod:`.rollout` -- controls to initial state, the recorded rollout (:class:`SceneSim`);
* :mod:`.judge` -- each fate met or not, graded, and the signature;
* :mod:`.scenefile` -- the scene side: its files, MuJoCo's compilation, the names (:func:`load_fates`);
* :mod:`.fates` -- the fates file, every bad input refused;
* :mod:`.builtin` -- the built-in examples (``nbst scene examples``).

Example::

    from nbst.scene import solve
    res = solve(None, "snake-eyes", seed=1, max_rollouts=2000)
    print(res.met, res.rollouts, res.best.judgement.to_dict()["signature"])

Importing this package imports neither mujoco nor numba; the modules that need MuJoCo import it
when they run.
"""
from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

if TYPE_CHECKING:   # what a type checker sees: the lazy names' own signatures, not `object`
    from nbst.scene import api, builtin, fates, judge, rollout, scenefile, search, solution, validate
    from nbst.scene.api import solve
    from nbst.scene.builtin import example_names
    from nbst.scene.fates import Fates, FatesError
    from nbst.scene.rollout import SceneSim
    from nbst.scene.scenefile import load_fates
    from nbst.scene.search import DEFAULT_MAX_ROLLOUTS, signature_search
    from nbst.scene.solution import (SceneReplay, SceneResult, export_scene, read_solution, replay_solution,
                                     solution_dict)
    from nbst.scene.validate import validate_solution

__all__ = ["solve", "SceneResult", "SceneReplay", "replay_solution", "solution_dict", "read_solution", "export_scene",
           "load_fates", "Fates", "FatesError", "SceneSim", "signature_search", "example_names",
           "DEFAULT_MAX_ROLLOUTS", "validate_solution", "api", "validate", "solution", "search", "rollout", "judge", "scenefile", "fates", "builtin"]

_LAZY = {"solve": "api", "SceneResult": "solution", "SceneReplay": "solution", "replay_solution": "solution",
         "solution_dict": "solution", "read_solution": "solution", "export_scene": "solution",
         "load_fates": "scenefile", "Fates": "fates",
         "FatesError": "fates", "SceneSim": "rollout", "signature_search": "search",
         "example_names": "builtin", "DEFAULT_MAX_ROLLOUTS": "search",
         "validate_solution": "validate"}


def __getattr__(name: str) -> object:
    if name in _LAZY:
        return getattr(importlib.import_module(f"nbst.scene.{_LAZY[name]}"), name)
    if name in __all__:
        return importlib.import_module(f"nbst.scene.{name}")
    raise AttributeError(f"module 'nbst.scene' has no attribute {name!r}")
