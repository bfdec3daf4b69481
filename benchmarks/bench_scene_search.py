"""The scene search's choices, measured: ``nbst.scene.search.signature_search`` on a built-in at a
range of seeds, with the ladder (h/2, h/4) and a budget, one thread, with a variant patched in.
Prints, per seed, the rollouts to meet every fate at h, h/2 and h/4 (-1: not within the budget),
when the first trial met every fate at h (``first_fine``) and how many did (``fine``); then the
seeds solved and the median (a miss counted as the budget). Asserts nothing (not a test).

    python benchmarks/bench_scene_search.py billiards 11-20                 # the search as it is
    python benchmarks/bench_scene_search.py billiards 11-20 --variant before
    python benchmarks/bench_scene_search.py egg-in-cup 11-20 --variant before+pop8
    python benchmarks/bench_scene_search.py dominoes 1-1 --uniform 100   # how often a uniform trial holds

``--uniform N`` instead: N uniform trials (``numpy.random.default_rng(1)``) and the middle of the
ranges, each met at h rolled out at h/2 and h/4 (``ladder_check``): how many are met, and kept.

Variants (joined with ``+``), each patched onto the module for the run:

* ``before``: the one-body search before the engine's ``spent_gain``/``wander`` (any lower cost
  of the best is progress; a spent funnel with no other fine trial is polished again);
* ``centre``: the first exploring trial is the middle of the ranges (the model's nominal);
* ``uni``: exploring trials uniform (no directed aim); ``lhs``: a Latin hypercube of
  ``ONE_BODY_EXPLORE`` points (scipy), no aim; ``lhsdir``: the same, half of them aimed;
* ``pop8``, ``pop16``: the CMA-ES population of one body; ``ex8``, ``ex32``: its exploring trials;
* ``batch8``: one body's exploring trials in batches of 8 (before ``ONE_BODY_EXPLORE_BATCHES``);
* ``near0``, ``near3``: a ``hits`` name never touched costs 1 however near it came (before
  ``nbst.scene.judge.HITS_NEAR``), or 1 plus three times its nearness.

``--engine K=V`` (repeatable) sets an option of the one-body search's engine for the run
(``sigma0=0.06``, ``"schedule=(('best', 5/3), ('cell', 5/9))"``, ``"polish=(1/3, 1/9, 1)"``,
``stall=3``, ``spent=1``), V a Python literal or arithmetic.
"""
from __future__ import annotations

import argparse
import copy
import statistics
import time

import numpy as np

import nbst.scene.judge as J
import nbst.scene.search as S
from nbst.models.mjsearch import engine as E
from nbst.scene.rollout import SceneSim, quiet_mujoco_warnings
from nbst.scene.scenefile import load_fates
from nbst.seeds import check_random_state

_INIT = {"mode": None, "centre": False}


def _before() -> None:
    init = E.Engine.__init__

    def patched(self, *a, **k):
        init(self, *a, **k)
        self.spent_gain, self.wander = 0.0, False
    E.Engine.__init__ = patched


def _explore_init(self, eng):
    """The exploring trial of a variant (``_INIT``), else the search's own."""
    k = getattr(self, "_k", 0)
    self._k = k + 1
    if _INIT["centre"] and k == 0:
        return np.full(len(self.live), 0.5)
    mode = _INIT["mode"]
    if mode is None:
        return _ORIG_INIT(self, eng)
    if mode == "uni":
        return eng.rng.random(len(self.live))
    if not hasattr(self, "_lhs"):
        from scipy.stats import qmc
        self._lhs = qmc.LatinHypercube(d=len(self.live), seed=int(eng.rng.integers(2**31))).random(
            max(S.ONE_BODY_EXPLORE, 16))
    v = self._lhs[(k - (1 if _INIT["centre"] else 0)) % len(self._lhs)].copy()
    if mode == "lhsdir" and eng.rng.random() < 0.5:  # aimed: the linvel of the aim, the rest the hypercube's
        u = self.full(v)
        keep = u.copy()
        self._directed(eng, u, 0)
        parts = [p for p, _ in self.fates.controls[0].parts()]
        if "linvel" in parts:
            a = self.blocks[0].start + 3 * parts.index("linvel")
            keep[a:a + 3] = u[a:a + 3]
        v = keep[self.live]
    return v


_ORIG_INIT = S._Scene.init
VARIANTS = {
    "before": _before,
    "centre": lambda: _INIT.update(centre=True),
    "uni": lambda: _INIT.update(mode="uni"),
    "lhs": lambda: _INIT.update(mode="lhs"),
    "lhsdir": lambda: _INIT.update(mode="lhsdir"),
    "pop8": lambda: setattr(S, "ONE_BODY_POPSIZE", 8),
    "pop16": lambda: setattr(S, "ONE_BODY_POPSIZE", 16),
    "ex8": lambda: setattr(S, "ONE_BODY_EXPLORE", 8),
    "ex32": lambda: setattr(S, "ONE_BODY_EXPLORE", 32),
    "near0": lambda: setattr(J, "HITS_NEAR", 0.0),
    "near3": lambda: setattr(J, "HITS_NEAR", 3.0),
    "batch8": lambda: setattr(S, "ONE_BODY_EXPLORE_BATCHES", ()),
}


def _engine_options(pairs: list[str]) -> None:
    """``--engine K=V``: the one-body search's engine (``cma_by_key``) gets these options."""
    over = {}
    for kv in pairs:
        k, v = kv.split("=", 1)
        over[k.strip()] = eval(v, {"__builtins__": {}}, {})  # a literal or arithmetic (a benchmark's flag)
    init = E.Engine.__init__

    def patched(self, *a, **kw):
        if kw.get("cma_by_key"):
            kw.update(over)
        init(self, *a, **kw)
    E.Engine.__init__ = patched


def uniform(name: str, n: int) -> None:
    f, model = load_fates(name)
    finer = []
    for k in (2, 4):
        mk = copy.copy(model)
        mk.opt.timestep = model.opt.timestep / k
        finer.append(SceneSim(f, mk))
    with quiet_mujoco_warnings(), SceneSim(f, model) as sim:
        sc = S._Scene(sim, 1, ())
        U = np.vstack([np.random.default_rng(1).random((n, len(sc.live))), np.full((1, len(sc.live)), 0.5)])
        outs = sim.run(np.array([sc.x_of(u) for u in U]))
        met = [r.judgement.met and not r.warnings for r in outs]
        held = [m and S.ladder_check(r.x, tuple(finer))[0] == 0 for m, r in zip(met, outs)]
    print(f"{name}: {n} uniform trials: met at h {sum(met[:n])}, kept at h/2 and h/4 {sum(held[:n])}; "
          f"the middle of the ranges: met at h {met[n]}, kept {held[n]}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0], allow_abbrev=False)
    ap.add_argument("scene")
    ap.add_argument("seeds", help="e.g. 11-20")
    ap.add_argument("--variant", default="", help=f"'+'-joined, of: {', '.join(VARIANTS)}")
    ap.add_argument("--budget", type=int, default=2000)
    ap.add_argument("--uniform", type=int, default=0, help="N uniform trials instead of searches")
    ap.add_argument("--engine", action="append", default=[], metavar="K=V",
                    help="an engine option of the one-body search (repeatable)")
    a = ap.parse_args()
    if a.uniform:
        uniform(a.scene, a.uniform)
        return
    lo, hi = map(int, a.seeds.split("-"))
    for v in filter(None, a.variant.split("+")):
        VARIANTS[v]()
    _engine_options(a.engine)
    label = "+".join(filter(None, [a.variant, *a.engine])) or "as is"
    S._Scene.init = _explore_init
    f, model = load_fates(a.scene)
    finer = []
    for k in (2, 4):
        mk = copy.copy(model)
        mk.opt.timestep = model.opt.timestep / k
        finer.append(SceneSim(f, mk))
    out = []
    evaluate = S._Scene.evaluate
    with quiet_mujoco_warnings(), SceneSim(f, model, jobs=1) as sim:
        for s in range(lo, hi + 1):
            info = {"first_fine": None, "fine": 0, "n": 0}

            def counted(self, U, info=info):
                d = evaluate(self, U)
                for fine in d["fine"]:
                    if fine:
                        info["fine"] += 1
                        info["first_fine"] = info["first_fine"] or info["n"] + 1
                info["n"] += d["rollouts"]
                return d
            S._Scene.evaluate = counted
            t0 = time.perf_counter()
            r = S.signature_search(sim, rng=check_random_state(s), max_rollouts=a.budget, ladder=tuple(finer))
            S._Scene.evaluate = evaluate
            out.append(r.rollouts if r.stopped == "met" else -1)
            print(f"{a.scene} {label} seed {s}: {out[-1]} first_fine={info['first_fine']} "
                  f"fine={info['fine']} [{time.perf_counter() - t0:.0f} s]", flush=True)
    med = statistics.median([n if n > 0 else a.budget for n in out])
    print(f"{a.scene} {label} seeds {a.seeds}: {sum(n > 0 for n in out)}/{len(out)} solved, "
          f"median {med:g}; per seed {out}")


if __name__ == "__main__":
    main()
