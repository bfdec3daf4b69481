"""Bring your own scene (issue 46): the rollout rate, the built-ins solved, and nbst's search against
generic optimisers. Prints figures; asserts nothing (not a test).

    python benchmarks/bench_scene.py                          # every part, seeds 1-5, budget 2000
    python benchmarks/bench_scene.py --quick                  # seeds 1-3, budget 1000, 200 rollouts timed
    python benchmarks/bench_scene.py --part rate --scenes snake-eyes,bank-shot
    python benchmarks/bench_scene.py --part builtins --seeds 1-5 --budget 2000
    python benchmarks/bench_scene.py --part versus --seeds 1-3 --budget 1000 --jobs 2
    python benchmarks/bench_scene.py --part versus --scenes bank-shot --seeds 1-20 --methods nbst,pycma

Parts:

* **rate**: open-loop rollouts of a built-in scene (random controls in its ranges) through the
  room's rollout path (``nbst.scene.rollout.SceneSim.run``: the initial state from the controls,
  the steps, the judge) against ``mujoco.rollout.rollout`` alone from the same initial states, on
  the same model, steps and threads (1 and 2), in the same run: rollouts per second and their
  ratio. The room runs on ``mujoco.rollout`` too (``SceneSim.engine``): the path and the first
  touches are read from sensors added to a copy of the scene, written at every step; the ratio
  is what the room adds (the initial state, the sensors, the judge).
* **builtins**: each built-in solved (``nbst.scene.solve``, its default: the ladder asked) at each
  seed: rollouts to meet, their median (a seed not met within the budget counts as the budget in
  the median, and is said), and whether the answer meets every fate at h/2 and h/4 (checked again
  here: the same initial state rolled out anew, the ladder of ``nbst scene replay --ladder``):
  "ladder held k/5".
* **versus**: the same scenes, the same cost and test as ``nbst.scene.solve`` by default (the
  judge's graded cost, every fate met at cost 0; a rollout on which MuJoCo warned costs
  :data:`WARNED_COST`; a rollout that meets every fate is rolled out at h/2 and h/4 too, counted,
  its rungs' misses and graded costs added; solved when every fate is met at all three: the
  ladder), the same budget of rollouts and the same batches of threads, for:

  - **nbst**: the room's signature search (``nbst.scene.solve``);
  - **pycma**: ``cma.CMAEvolutionStrategy`` alone over the controls scaled to [0, 1]^D (bounds
    [0, 1], sigma0 0.3, its default population, restarted from a new uniform point when it
    stops);
  - **PS**: predictive sampling as MuJoCo MPC's planner samples: a nominal (the best so far,
    first a uniform point), each round :data:`PS_SAMPLES` candidates drawn around it from a
    Gaussian of fixed sigma :data:`PS_SIGMA` (in the scaled controls, clipped to [0, 1]), the best
    of nominal and candidates kept as the nominal (the nominal is not rolled out again: the
    scene is deterministic);
  - **CEM**: cross-entropy sampling as MuJoCo MPC's planner samples: a Gaussian (mean: a uniform
    point, sigma :data:`CEM_SIGMA0` per coordinate), each round :data:`CEM_SAMPLES` candidates,
    the :data:`CEM_ELITE` best refit the mean and the per-coordinate sigma (not below
    :data:`CEM_SIGMA_MIN`).

  Each stops after the batch in which a rollout first meets every fate at h, h/2 and h/4, all of
  that batch's rollouts and ladder checks counted (as nbst's engine counts). Printed per scene:
  solved (of the seeds) and the median rollouts to meet (unsolved counted as the budget).
"""
from __future__ import annotations

import argparse
import copy
import statistics
import time
from typing import Callable

import numpy as np

from nbst.scene.builtin import example_names
from nbst.scene.rollout import SceneSim, quiet_mujoco_warnings
from nbst.scene.scenefile import load_fates

#: The cost of a rollout on which MuJoCo warned (a diverging state) for the generic optimisers.
WARNED_COST = 1e3
PS_SAMPLES = 8
PS_SIGMA = 0.1
CEM_SAMPLES = 16
CEM_ELITE = 4
CEM_SIGMA0 = 0.3
CEM_SIGMA_MIN = 0.02
#: Rollouts per batch (all the optimisers roll a batch out on the threads at once).
BATCH = 8


def seeds_of(text: str) -> list[int]:
    if "-" in text:
        a, b = text.split("-")
        return list(range(int(a), int(b) + 1))
    return [int(s) for s in text.split(",")]


# ----------------------------------------------------------------------------------------- rate

def part_rate(scenes: list[str], n: int) -> None:
    import mujoco
    from mujoco import rollout as mjrollout

    print(f"## rate: open-loop rollouts, room's path vs mujoco.rollout alone (MuJoCo {mujoco.__version__})")
    print(f"{'scene':12s} {'steps':>6s} {'thr':>3s} {'room r/s':>9s} {'rollout r/s':>11s} {'ratio':>6s}  room's stepping")
    for name in scenes:
        fates, model = load_fates(name)
        rng = np.random.default_rng(0)
        lo, hi = fates.bounds()
        xs = lo + (hi - lo) * rng.random((n, fates.dim))
        with quiet_mujoco_warnings():
            for threads in (1, 2):
                with SceneSim(fates, model, jobs=threads) as sim:
                    sim.run(xs[:threads * 2])  # warm: the threads' MjData
                    t0 = time.perf_counter()
                    sim.run(xs)
                    room = time.perf_counter() - t0
                    how = sim.engine + (" + path/contact sensors" if sim.per_step or sim.pairs else ", the end only")
                    # the same initial states as full physics states
                    d = mujoco.MjData(model)
                    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
                    size = mujoco.mj_stateSize(model, spec)
                    init = np.empty((n, size))
                    for i, x in enumerate(xs):
                        q, v = sim.initial_state(x)
                        sim._reset(d)
                        d.qpos[:] = q
                        d.qvel[:] = v
                        mujoco.mj_getState(model, d, init[i], spec)
                    nstep = sim.nstep
                datas = [mujoco.MjData(model) for _ in range(threads)]
                mjrollout.rollout(model, datas, init[:threads * 2], nstep=nstep)  # warm
                t0 = time.perf_counter()
                mjrollout.rollout(model, datas, init, nstep=nstep)
                base = time.perf_counter() - t0
                print(f"{name:12s} {nstep:6d} {threads:3d} {n / room:9.1f} {n / base:11.1f} {base / room:6.2f}  {how}")


# ------------------------------------------------------------------------------------- builtins

def _ladder_holds(fates, model, x: np.ndarray) -> tuple[bool, bool]:
    out = []
    for k in (2, 4):
        m = copy.copy(model)
        m.opt.timestep = model.opt.timestep / k
        with quiet_mujoco_warnings(), SceneSim(fates, m) as sim:
            r = sim.rollout(x)
        out.append(bool(r.judgement.met and not r.warnings))
    return out[0], out[1]


_SOLVED: dict[tuple[str, int, int, int], object] = {}


def _solve(name: str, seed: int, budget: int, jobs: int):
    """nbst.scene.solve, once per (scene, seed, budget, jobs) in a run (builtins and versus share it)."""
    from nbst.scene import solve

    key = (name, seed, budget, jobs)
    if key not in _SOLVED:
        _SOLVED[key] = solve(None, name, seed=seed, max_rollouts=budget, jobs=jobs)
    return _SOLVED[key]


def _median(counts: list[int]) -> float:
    return float(statistics.median(counts)) if counts else float("nan")


def part_builtins(scenes: list[str], seeds: list[int], budget: int, jobs: int) -> None:
    print(f"## builtins: nbst.scene.solve at seeds {seeds}, budget {budget} rollouts, {jobs} thread(s)")
    for name in scenes:
        rows, counts, t0 = [], [], time.perf_counter()
        for s in seeds:
            res = _solve(name, s, budget, jobs)
            counts.append(res.rollouts if res.met else budget)
            if res.met:
                h2, h4 = _ladder_holds(res.fates, res.model, res.best.x)
                rows.append(f"s{s}: {res.rollouts} ({'h/2 ' + ('ok' if h2 else 'NO')}, {'h/4 ' + ('ok' if h4 else 'NO')})")
            else:
                rows.append(f"s{s}: not met")
        met = sum(1 for r in rows if "not met" not in r)
        held = sum(1 for r in rows if "h/2 ok, h/4 ok" in r)
        print(f"{name:12s} met {met}/{len(seeds)}, median {_median(counts):g} rollouts, ladder held {held}/{len(seeds)}; "
              f"{'; '.join(rows)}  [{time.perf_counter() - t0:.0f} s]")


# --------------------------------------------------------------------------------------- versus

class _Budget(Exception):
    pass


class Objective:
    """The room's cost over controls scaled to [0, 1]^D, counting rollouts; stops at the first solved.

    The same cost and the same test as ``nbst.scene.solve`` (its default ladder): the judge's graded
    cost; a rollout that meets every fate at h is rolled out at h/2, and at h/4 if it held there
    (``nbst.scene.search.ladder_check``, counted), and adds ``LADDER_PENALTY`` per rung missed plus
    each rung's graded cost (at most ``LADDER_FAR``, and that for a rung not rolled out); it solves
    when it meets every fate at all three. Counted as nbst's engine counts: every rollout of the
    batch in which the first such rollout came, its ladder checks included."""

    def __init__(self, sim: SceneSim, budget: int, ladder: tuple = ()):
        self.sim, self.budget, self.ladder = sim, budget, ladder
        self.lo, self.hi = sim.fates.bounds()
        self.used = 0
        self.met_at: int | None = None

    def __call__(self, us: np.ndarray) -> np.ndarray:
        from nbst.scene.search import LADDER_PENALTY, ladder_check

        us = np.clip(np.asarray(us, dtype=float).reshape(-1, self.sim.fates.dim), 0.0, 1.0)
        us = us[:self.budget - self.used]
        if not len(us):
            raise _Budget
        outs = self.sim.run(self.lo + (self.hi - self.lo) * us)
        costs, held = [], False
        for r in outs:
            self.used += 1
            c = WARNED_COST if r.warnings else r.judgement.cost
            if r.judgement.met and not r.warnings and self.ladder:
                misses, far, n = ladder_check(r.x, self.ladder)
                self.used += n
                c += LADDER_PENALTY * misses + far
                held = held or misses == 0
            elif r.judgement.met and not r.warnings:
                held = True
            costs.append(c)
        if held:  # the whole batch counts, its ladder checks too: as nbst's engine counts
            self.met_at = self.used
        if self.met_at is not None or self.used >= self.budget:
            raise _Budget  # solved, or the budget spent (a truncated batch is not told)
        return np.array(costs)


def run_cma(f: Objective, rng: np.random.Generator) -> None:
    import cma

    dim = f.sim.fates.dim
    while True:
        es = cma.CMAEvolutionStrategy(rng.random(dim), 0.3, {"bounds": [0, 1], "seed": int(rng.integers(1, 2**31 - 1)),
                                                             "verbose": -9})
        while not es.stop():
            xs = es.ask()
            es.tell(xs, list(f(np.array(xs))))


def run_ps(f: Objective, rng: np.random.Generator) -> None:
    dim = f.sim.fates.dim
    nominal = rng.random(dim)
    best = float(f(nominal[None])[0])
    while True:
        cand = np.clip(nominal + PS_SIGMA * rng.standard_normal((PS_SAMPLES, dim)), 0.0, 1.0)
        c = f(cand)
        i = int(np.argmin(c))
        if c[i] < best:
            best, nominal = float(c[i]), cand[i]


def run_cem(f: Objective, rng: np.random.Generator) -> None:
    dim = f.sim.fates.dim
    mean, sigma = rng.random(dim), np.full(dim, CEM_SIGMA0)
    while True:
        cand = np.clip(mean + sigma * rng.standard_normal((CEM_SAMPLES, dim)), 0.0, 1.0)
        c = f(cand)
        elite = cand[np.argsort(c)[:CEM_ELITE]]
        mean, sigma = elite.mean(axis=0), np.maximum(elite.std(axis=0), CEM_SIGMA_MIN)


GENERIC: dict[str, Callable[[Objective, np.random.Generator], None]] = {"pycma": run_cma, "PS": run_ps, "CEM": run_cem}


def part_versus(scenes: list[str], seeds: list[int], budget: int, jobs: int,
                methods: tuple[str, ...] = ("nbst", *GENERIC)) -> None:
    print(f"## versus: the same scenes, cost and budget ({budget} rollouts), seeds {seeds}; solved and median rollouts "
          f"to meet (unsolved counted as the budget)")
    for name in scenes:
        fates, model = load_fates(name)
        line = []
        t0 = time.perf_counter()
        counts: dict[str, list[int]] = {}
        if "nbst" in methods:
            counts["nbst"] = []
            for s in seeds:
                res = _solve(name, s, budget, jobs)
                counts["nbst"].append(res.rollouts if res.met else -1)  # met: every fate at h, h/2 and h/4
                print(f"  {name} nbst seed {s}: {counts['nbst'][-1]}", flush=True)
        rungs = []
        for k in (2, 4):
            mk = copy.copy(model)
            mk.opt.timestep = model.opt.timestep / k
            rungs.append(SceneSim(fates, mk))
        with quiet_mujoco_warnings(), SceneSim(fates, model, jobs=jobs) as sim:
            for meth, fn in GENERIC.items():
                if meth not in methods:
                    continue
                counts[meth] = []
                for s in seeds:
                    f = Objective(sim, budget, tuple(rungs))
                    try:
                        fn(f, np.random.default_rng(s))
                    except _Budget:
                        pass
                    counts[meth].append(f.met_at if f.met_at is not None else -1)
                    print(f"  {name} {meth} seed {s}: {counts[meth][-1]}", flush=True)
        for meth, c in counts.items():
            solved = sum(1 for a in c if a > 0)
            med = _median([a if a > 0 else budget for a in c])
            line.append(f"{meth} {solved}/{len(seeds)} med {med:g}")
        print(f"{name:12s} " + " | ".join(line) + f"  [{time.perf_counter() - t0:.0f} s]")
        print(f"{'':12s} per seed: " + "; ".join(f"{m} {c}" for m, c in counts.items()) + " (-1: not met)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0], allow_abbrev=False)
    ap.add_argument("--part", choices=("rate", "builtins", "versus", "all"), default="all")
    ap.add_argument("--scenes", default=None, help="comma-separated built-ins (default: every one)")
    ap.add_argument("--seeds", default=None, help="e.g. 1-5 or 1,3 (default 1-5; --quick 1-3)")
    ap.add_argument("--budget", type=int, default=None, help="rollouts per search (default 2000; --quick 1000)")
    ap.add_argument("--jobs", type=int, default=2, help="threads for the searches (default 2)")
    ap.add_argument("--rate-rollouts", type=int, default=None, help="rollouts timed per rate row (default 400)")
    ap.add_argument("--quick", action="store_true", help="seeds 1-3, budget 1000, 200 rollouts timed")
    ap.add_argument("--methods", default=None,
                    help=f"comma-separated, of versus: nbst,{','.join(GENERIC)} (default: every one)")
    a = ap.parse_args()
    scenes = a.scenes.split(",") if a.scenes else example_names()
    seeds = seeds_of(a.seeds or ("1-3" if a.quick else "1-5"))
    budget = a.budget or (1000 if a.quick else 2000)
    n = a.rate_rollouts or (200 if a.quick else 400)
    print(f"bench_scene: scenes {scenes}, seeds {seeds}, budget {budget}, jobs {a.jobs}")
    if a.part in ("rate", "all"):
        part_rate(scenes, n)
    if a.part in ("builtins", "all"):
        part_builtins(scenes, seeds, budget, a.jobs)
    if a.part in ("versus", "all"):
        part_versus(scenes, seeds, budget, a.jobs, tuple(a.methods.split(",")) if a.methods else ("nbst", *GENERIC))


if __name__ == "__main__":
    main()
