"""``nbst.scene.solve``: the one typed way in to the scene search (docs/scene.md).

Loads and checks the fates (``nbst.scene.scenefile.load_fates``), rolls the scene out on ``jobs``
threads (``nbst.scene.rollout.SceneSim``) or a Dask cluster (``nbst.scene.cluster``) and runs the
paper's per-body signature search (``nbst.scene.search.signature_search``) from one seed
(``nbst.seeds``), by default until the answer also meets every fate at h/2 and h/4 (the ladder);
on request, the robust maximiser (``nbst.scene.robust``) and the probability that the answer holds
under the fates' noise (``nbst.scene.search.noisy_probability``).
"""
from __future__ import annotations

import copy
import dataclasses
import numbers
import os
from pathlib import Path
from typing import Any, Callable

import numpy as np

from nbst.errors import SolveError
from nbst.parallel import JOBS_MAX
from nbst.scene.cluster import ClusterSceneSim
from nbst.scene.fates import Fates
from nbst.scene.judge import signature_text
from nbst.scene.robust import DEFAULT_ROBUST_SAMPLES, SceneRobustProblem
from nbst.scene.scenefile import check_against_model, compile_scene, load_fates
from nbst.scene.rollout import SceneSim, quiet_mujoco_warnings
from nbst.scene.search import DEFAULT_MAX_ROLLOUTS, SceneProgress, noisy_probability, signature_search
from nbst.scene.solution import SceneResult
from nbst.seeds import check_random_state, resolve_seed

__all__ = ["solve", "LADDER", "ANSWERS_MAX"]

#: The finer steps of ``ladder=True``: h/2 and h/4.
LADDER = (2, 4)
#: The most answers one search looks for (``answers``; ``nbst scene solve --answers``).
ANSWERS_MAX = 100


def solve(scene: str | os.PathLike | None, fates: str | os.PathLike | Fates, *, seed: int | None = None,
          max_rollouts: int = DEFAULT_MAX_ROLLOUTS, jobs: int = 1, samples: int = 0, answers: int = 1,
          ladder: bool = True, robust: int | None = None, cluster: str | Any | None = None,
          callback: Callable[[SceneProgress], None] | None = None) -> SceneResult:
    """Find initial velocities (and offsets) of a scene's free bodies that meet their fates.

    Args:
        scene: the MJCF file, overriding the fates' ``"scene"``; None: the fates' own.
        fates: a fates file (``"format": "nbst-fates"``), a built-in example's name
            (``nbst scene examples``), or already checked :class:`~nbst.scene.fates.Fates`.
        seed: the seed (an integer in [0, 2^63-1]); None draws one (recorded in the result).
        max_rollouts: the rollout budget, >= 1.
        jobs: threads rolling the scene out (>= 1); any value gives the same result.
        samples: after the search (unless interrupted), estimate from this many noisy rollouts how
            often the best controls meet every fate under the fates' ``"noise"`` (0: none); each
            answer's too.
        answers: look for up to this many solutions, each with a contact sequence of its own
            (>= 1; see ``nbst.scene.search.signature_search``); the first is the best.
        ladder: accept only answers that also meet every fate at h/2 and h/4 (the same initial
            state rolled out at the finer steps; those rollouts count in the budget); ``met`` then
            says that the best does (default; False: met at h is enough).
        robust: after a search that met every fate (not interrupted), move the answer to where
            it holds most often under the fates' noise with the rollout room's robust maximiser,
            this many noisy rollouts (>= 12; None: not); the pick is the latest that keeps every
            fate at h, h/2 and h/4 (with ``ladder``), its probability measured afresh from
            ``samples`` copies (default ``nbst.scene.robust.DEFAULT_ROBUST_SAMPLES``).
        cluster: run the batches on the workers of this Dask scheduler (an address such as
            ``tcp://host:8786``, or a ``dask.distributed.Client``) instead of ``jobs`` threads;
            the same result for the same seed.
        callback: called with a :class:`~nbst.scene.search.SceneProgress` after each batch.

    Returns:
        the :class:`~nbst.scene.solution.SceneResult`: the best rollout (every fate met when
        ``met``), the rollouts spent (the search's; the samples apart), why it stopped, the seed,
        the probability when ``samples`` > 0.

    Raises:
        FatesError: the fates file or its scene is refused (one line naming the file and field).
        InputError: the seed is not an integer in range.
        SolveError: ``max_rollouts``, ``jobs`` (at most ``nbst.parallel.JOBS_MAX``) or ``answers``
            (at most :data:`ANSWERS_MAX`) is not an integer >= 1 (numpy's too), ``samples`` one >= 0,
            or ``robust`` one >= 12; ``ladder`` is not a bool (numpy's too); ``callback`` is not
            callable; ``cluster`` is not an address (a string) or a ``dask.distributed.Client``;
            ``fates`` or ``scene`` is of another type.
        InputError: the cluster cannot be reached (one line).
    """
    for name, v, least, most in (("max_rollouts", max_rollouts, 1, None), ("jobs", jobs, 1, JOBS_MAX),
                                 ("samples", samples, 0, None), ("answers", answers, 1, ANSWERS_MAX)):
        if isinstance(v, bool) or not isinstance(v, numbers.Integral) or v < least or (most and v > most):
            raise SolveError(f"{name} must be an integer >= {least}" + (f" and <= {most}" if most else "")
                             + f", got {v!r}")
    max_rollouts, jobs, samples, answers = int(max_rollouts), int(jobs), int(samples), int(answers)
    if robust is not None and (isinstance(robust, bool) or not isinstance(robust, numbers.Integral) or robust < 12):
        raise SolveError(f"robust must be None or an integer >= 12 (noisy rollouts), got {robust!r}")
    robust = None if robust is None else int(robust)
    if not isinstance(ladder, (bool, np.bool_)):  # "false" or None read as truth would turn it on or off unasked
        raise SolveError(f"ladder must be True or False, got {ladder!r}")
    ladder = bool(ladder)
    if callback is not None and not callable(callback):
        raise SolveError(f"callback must be None or a function of a SceneProgress, got {type(callback).__name__}")
    if cluster is not None and not isinstance(cluster, str) and not hasattr(cluster, "scheduler_info"):
        raise SolveError(f"cluster must be None, a Dask scheduler's address (a string) or a "
                         f"dask.distributed.Client, got {type(cluster).__name__}")
    if not isinstance(fates, (str, os.PathLike, Fates)):
        raise SolveError(f"fates must be a fates file's path, a built-in's name or a checked Fates (the first of "
                         f"load_fates' pair), got {type(fates).__name__}")
    if scene is not None and not isinstance(scene, (str, os.PathLike)):
        raise SolveError(f"scene must be None or an MJCF file's path, got {type(scene).__name__}")
    s = resolve_seed(seed)
    if isinstance(fates, Fates):
        f = fates if scene is None else dataclasses.replace(fates, scene=Path(scene))
        model = compile_scene(f)
        check_against_model(f, model)
    else:
        f, model = load_fates(fates, scene=scene)
    p = None
    ps: list = []
    stopped = "budget"
    finer = []
    if ladder:
        for k in LADDER:
            mk = copy.copy(model)
            mk.opt.timestep = model.opt.timestep / k
            check_against_model(f, mk)  # the step cap, at this rung
            finer.append(SceneSim(f, mk, sequences=answers > 1))
    extra: dict | None = None
    seqs = answers > 1
    sim = (ClusterSceneSim(f, model, cluster, sequences=seqs) if cluster is not None
           else SceneSim(f, model, jobs=jobs, sequences=seqs))
    with quiet_mujoco_warnings(), sim:
        r = signature_search(sim, rng=check_random_state(s), max_rollouts=max_rollouts, answers=answers,
                             ladder=tuple(finer), callback=callback)
        stopped = r.stopped
        best, held = r.best, r.best_held
        found = list(r.answers) if answers > 1 else []

        def say(phase: str) -> None:  # the search is over: what comes next, for a progress bar
            if callback is not None:
                callback(SceneProgress(r.rollouts, best.cost, signature_text(best.signature), 0, r.signatures, phase))
        cut: str | None = None   # the phase after the search an interrupt would cut short
        try:
            if robust is not None and stopped == "met":
                cut = "robust"
                say(f"robust: up to {robust} noisy rollouts")
                from nbst.models.mjsearch.robust import Interrupted, maximise

                P: Any = SceneRobustProblem(sim, tuple(finer))  # the maximiser's RobustProblem (credit a float)
                try:
                    mx = maximise(P, [best.x], budget=robust, seed=s, n=samples or DEFAULT_ROBUST_SAMPLES,
                                  ladder=ladder)
                except Interrupted:
                    raise KeyboardInterrupt from None
                if mx.best is not best.x:
                    best = sim.rollout(P.value(mx.best))
                    held = bool(mx.ladder_holds) if ladder else None
                p = mx.fresh
                extra = {"budget": robust, "rollouts": mx.frames, "screen": [mx.screen.k, mx.screen.n],
                         "start_screen": [mx.start_screen.k, mx.start_screen.n], "screen_seed": mx.screen_seed,
                         **({"ladder": mx.ladder} if mx.ladder else {})}
            elif samples and stopped != "interrupted":
                cut = "samples"
                say(f"P from {samples} noisy rollouts")
                p = noisy_probability(sim, best.x, n=samples, seed=s)
            if best is not r.best and found:  # the robust pick is the file's own motion: the answer it moved
                found = [best if a is r.best else a for a in found]
                found = [a for a in found if a is best or a.sequence != best.sequence]  # a sequence once
            if samples and answers > 1 and stopped != "interrupted":
                cut = "answers' samples"
                say(f"P of {len(found)} answers from {samples} noisy rollouts each")
                ps = [p if a is best else noisy_probability(sim, a.x, n=samples, seed=s) for a in found]
        except KeyboardInterrupt:   # after the search: its own stop is kept, what was cut short said
            interrupted = cut if stopped != "interrupted" else None
            stopped = stopped if interrupted else "interrupted"
            p, ps = None, []
        else:
            interrupted = None
        nstep, key = sim.nstep, sim.key
    met = best.judgement.met and not best.warnings and (not ladder or held is True)
    return SceneResult(fates=f, model=model, best=best, met=met,
                       rollouts=r.rollouts, stopped=stopped, seed=s, max_rollouts=max_rollouts,
                       wall_time=r.wall_time, signatures=r.signatures, nstep=nstep, key=key, probability=p,
                       answers=tuple(found), answer_probabilities=tuple(ps),
                       ladder=tuple(float(model.opt.timestep) / k for k in (1, *LADDER)) if ladder else (),
                       ladder_held=held, robust=extra, interrupted=interrupted)
