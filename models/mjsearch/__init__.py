"""nbst.models.mjsearch: the one room for searches over MuJoCo rollouts (bowling, the crash, scenes).

Nothing here knows a bowling pin or a car: the caller gives the model, the map from its
parameter vector to an initial state (and controls), and the outcome reader. The room gives
the machinery every rollout search needs, one module each:

* :mod:`.runner` -- :class:`Runner`: rollouts on K threads through ``mujoco.rollout``, one
  ``MjData`` per thread reset before each rollout (results independent of K); open loop, or
  closed loop in chunks with a controller called between them (bit for bit the same as one
  call with the recorded controls); MuJoCo's warnings as :class:`~nbst.errors.MujocoError`.
* :mod:`.batch` -- :class:`~.batch.BatchRunner`: many simulations stepped together on a
  ``mujoco.batch.Batch``, a batch-wide controller every period and an observer every step
  (the crash's drivers and contact sensors); the recorded controls replay by ``mj_step``.
* :mod:`.pool` -- :class:`WorkerPool`: processes for hand-stepped rollouts (checks between
  steps), results in order, workers that die with their parent.
* :mod:`.archive` -- :class:`Archive` keyed by signature, the MAP-Elites emitter
  (:func:`emit`, :func:`grow`) over a :class:`Space`: the atlases' illumination (every
  signature, no target), not a search for one.
* :mod:`.engine` -- :class:`Engine`: **the one rollout-search engine**, in pycma's shape
  (``ask``, ``tell``, ``stop()`` giving reasons, ``result``), keyed by the caller's signature:
  exploration, the paper's GA crossing whole blocks of coordinates (one per body, per driver),
  the archive keyed by cell, and the one CMA-ES restart phase (pycma). Bowling's deck, the
  crash and scenes run on it; the problem's moves (a directed randomize) come in as callables.
* :mod:`.probability` -- noise with common random numbers (:func:`normal_draws`,
  :func:`perturb`), a probability with its Wilson interval (:class:`Probability`).
* :mod:`.robust` -- :func:`robust.maximise`: the vector whose outcome holds most often under
  noise (a (1+lambda) strategy on paired trials with successive halving), and the ladder check
  of the pick.
* :mod:`.ladder` -- the timestep ladder: does the outcome survive h/2 and h/4?
* :mod:`.cluster` -- :class:`ClusterRunner`: the Runner's batches on a Dask cluster.

Example (a closed-loop batch, replayed open loop from its recorded controls)::

    import mujoco, numpy as np
    from nbst.models.mjsearch import Runner

    model = mujoco.MjModel.from_xml_string(XML)          # <flag warmstart="disable"/>
    with Runner(model, jobs=2, duration=6.0) as R:
        s0 = np.array([R.initial_state(q, v) for q, v in starts])
        drive = lambda i, step, data: my_driver(i, data)  # -> (nu,) controls
        out = R.run(s0, controller=drive, chunk=25, sensors=True)
        again = R.run(s0, control=out.control)            # the same final states, bit for bit
        assert np.array_equal(out.final, again.final)

Importing this package imports neither mujoco nor cma; the modules that need them import them
when they run. Users: :mod:`nbst.models.bowling` (both halves), :mod:`nbst.models.crash`
(engine, batch, probability, robust, ladder, cluster) and ``nbst.scene``. docs/architecture.md places the
room; tests/test_mjsearch.py checks it on a small model of its own.
"""
from __future__ import annotations

import importlib

__all__ = ["Engine", "EngineResult", "Runner", "Rollouts", "BatchRunner", "WorkerPool", "Archive", "Space", "box_space", "emit", "grow", "Probability",
           "wilson", "normal_draws", "perturb", "Ladder", "climb", "ClusterRunner",
           "engine", "runner", "batch", "pool", "archive", "probability", "robust", "ladder", "cluster"]

_LAZY = {"Engine": "engine", "EngineResult": "engine", "Runner": "runner", "Rollouts": "runner", "BatchRunner": "batch", "WorkerPool": "pool", "Archive": "archive", "Space": "archive",
         "box_space": "archive", "emit": "archive", "grow": "archive", "Probability": "probability",
         "wilson": "probability", "normal_draws": "probability", "perturb": "probability", "Ladder": "ladder",
         "climb": "ladder", "ClusterRunner": "cluster"}


def __getattr__(name):
    if name in _LAZY:
        return getattr(importlib.import_module(f"nbst.models.mjsearch.{_LAZY[name]}"), name)
    if name in __all__:
        return importlib.import_module(f"nbst.models.mjsearch.{name}")
    raise AttributeError(f"module 'nbst.models.mjsearch' has no attribute {name!r}")
