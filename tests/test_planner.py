"""The backward planner: its closed-form chains land exactly, it recovers planted chains, and
every simulation of a search is counted as a trial (issue 15)."""
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from conftest import make_problem
from nbst import load_problem
from nbst.search.aim import chain_strike_velocity, strike_velocity
from nbst.search.planner import chain_aim, plan
from nbst.search import solve, variant_params
from nbst.constants import EVENT_DISK
from nbst.sim import simulate

ROOT = Path(__file__).resolve().parents[1]


def _aim(p, chain, imgs):
    L = len(chain) - 1
    v, t, pred = np.empty(2), np.empty(max(L, 1)), np.empty((L + 1, 2))
    w = chain_aim(np.ascontiguousarray(p.start), np.ascontiguousarray(p.radius), np.ascontiguousarray(p.mass),
                  np.ascontiguousarray(p.target), float(p.box[0]), float(p.box[1]), float(p.t_final),
                  np.array(chain, np.int64), L, np.array(imgs, np.int64).reshape(L + 1, 2), v, t, pred)
    return w, v, t[:L], pred


def _random_chain_problem(rng, L):
    """A cue and L noncueable disks at random (apart), random masses; targets anywhere."""
    while True:
        starts = rng.uniform(60, 740, (L + 1, 2))
        d = np.hypot(*(starts[:, None] - starts[None]).transpose(2, 0, 1)) + np.eye(L + 1) * 1e9
        if d.min() > 80:
            break
    return make_problem(starts, 12.0, masses=rng.uniform(0.5, 2.0, L + 1), cueable=[True] + [False] * L,
                        targets=rng.uniform(40, 760, (L + 1, 2)))


@pytest.mark.parametrize("L", [1, 2, 3])
def test_chain_aim_lands_the_last_disk_exactly(L):
    """Where the simulated motion is the planned chain (and nothing else touches), the last disk
    ends on its target, the contact times are the simulator's and the others end where predicted."""
    rng = np.random.default_rng(L)
    checked = 0
    for _ in range(4000):
        p = _random_chain_problem(rng, L)
        imgs = [tuple(rng.integers(-1, 2, 2)) for _ in range(L)] + [tuple(rng.integers(-1, 2, 2))]
        w, v, t, pred = _aim(p, list(range(L + 1)), imgs)
        if w <= 0:
            continue
        V = np.zeros((L + 1, 2))
        V[0] = v
        tr = simulate(p, V)
        ev = tr.events[tr.events["kind"] == EVENT_DISK]
        if [(int(e["i"]), int(e["j"])) for e in ev] != [(k, k + 1) for k in range(L)]:
            continue  # another contact got in the way (the planner's simulation check is for this)
        # closed form vs event-driven simulation: round-off of a few folds and divisions
        np.testing.assert_allclose(tr.final_positions[L], p.target[L], atol=1e-7)
        np.testing.assert_allclose(ev["time"], t, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(tr.final_positions, pred, atol=1e-7)
        checked += 1
        if checked == 12:
            break
    assert checked >= 6


def test_chain_aim_agrees_with_the_aim_helpers():
    rng = np.random.default_rng(7)
    agreed = 0
    for _ in range(2000):
        p = _random_chain_problem(rng, 2)
        x = [np.ascontiguousarray(p.start[k]) for k in range(3)]
        T = np.ascontiguousarray(p.target[2])
        out = np.empty(2)
        t2 = chain_strike_velocity(x[0], 12.0, p.mass[0], x[1], 12.0, p.mass[1], x[2], 12.0, p.mass[2], T, 5.0, out)
        w, v, t, _ = _aim(p, [0, 1, 2], [(0, 0)] * 3)
        assert w < 0 or t2 > 0  # possible for the planner only where the helper's is (it also cuts glancing chains)
        if t2 > 0 and w > 0:
            np.testing.assert_allclose(v, out, rtol=1e-12)
            assert t[1] == pytest.approx(t2, rel=1e-12)
            agreed += 1
        T1 = np.ascontiguousarray(p.target[1])
        t1 = strike_velocity(x[0], 12.0, p.mass[0], x[1], 12.0, p.mass[1], T1, 5.0, out)
        w, v, t, _ = _aim(p, [0, 1], [(0, 0)] * 2)
        if t1 > 0 and w > 0:
            np.testing.assert_allclose(v, out, rtol=1e-12)
            assert t[0] == pytest.approx(t1, rel=1e-12)
    assert agreed >= 30


def _planted_chain(chain_imgs, seed):
    """A 4-disk problem (cues 0 and 3; 1 and 2 noncueable) whose zero is a chain 0 -> 1 (-> 2)
    aimed by chain_aim, plus a free cue; targets = where the motion ends."""
    rng = np.random.default_rng(seed)
    for _ in range(2000):
        starts = rng.uniform(60, 740, (4, 2))
        d = np.hypot(*(starts[:, None] - starts[None]).transpose(2, 0, 1)) + np.eye(4) * 1e9
        if d.min() < 90:
            continue
        L = len(chain_imgs) - 1
        p = make_problem(starts, 12.0, cueable=[True, False, False, True], targets=rng.uniform(40, 760, (4, 2)))
        w, v, _, _ = _aim(p, list(range(L + 1)), chain_imgs)
        if w <= 0:
            continue
        V = np.zeros((4, 2))
        V[0] = v
        V[3] = rng.uniform(-60, 60, 2)
        tr = simulate(p, V)
        if tr.n_disk_disk != L:
            continue
        final = np.clip(tr.final_positions, 12.0, 788.0)
        return make_problem(starts, 12.0, cueable=[True, False, False, True], targets=final), V
    raise AssertionError("no planted chain")


@pytest.mark.parametrize("imgs", [[(0, 0), (0, 0)], [(1, 0), (0, 1)], [(0, 0), (0, 0), (0, 0)],
                                  [(0, -1), (0, 0), (1, 0)]])
def test_planner_recovers_a_planted_chain(imgs):
    p, _ = _planted_chain(imgs, seed=len(imgs) * 10 + imgs[0][0] + 3 * imgs[-1][0])
    r = plan(p, budget=20_000)
    assert r.costs[0] < 1e-6  # exact up to round-off: the chain is rebuilt in closed form
    assert r.trials <= 20_000 and np.all(r.velocities[:, ~p.cueable] == 0.0)
    assert simulate(p, r.velocities[0]).cost == r.costs[0]


def test_planner_counts_every_simulation_and_respects_its_budget():
    p = load_problem("over5")
    r = plan(p, budget=700)
    s = r.stats
    assert r.trials == 1 + s["routes_simulated"] + s["combinations"] + s["sweep_simulations"] <= 700
    assert r.velocities.shape[1:] == (5, 2) and np.all(np.diff(r.costs) >= 0)


def test_search_charges_the_planner_and_every_polish_simulation():
    p = load_problem("over5")
    m = solve(p, seed=3, max_trials=20_000, patience=0).meta
    assert m["planner"]["trials"] > 0 and m["trials"] == 20_000 == m["simulations"]
    off = solve(p, seed=3, max_trials=20_000, patience=0, variant="nbst-noplan").meta
    assert "planner" not in off and off["trials"] == off["simulations"] == 20_000
    assert off["operators"]["plan"]["children"] == 0


def test_planner_only_with_noncueable_disks():
    m = solve(load_problem("diamond-s14-tiny"), seed=0, max_trials=1000, target_cost=1e-6).meta
    assert "planner" not in m and m["trials"] <= 30
    assert variant_params("nbst").planner and not variant_params("nbst-noplan").planner


_COUNT = r"""
import json, sys
import nbst.sim.kernel as S, nbst.search.loop as SL, nbst.search.polish as PO
calls = [0]
real = S.run
def counted(*a):
    calls[0] += 1
    return real(*a)
S.run = SL.run = PO.run = counted
from nbst import load_problem
from nbst.search import solve
m = solve(load_problem("over5"), seed=4, max_trials=int(sys.argv[1]), patience=0).meta
print(json.dumps({"calls": calls[0], "trials": m["trials"], "polish": m["polish"]["simulations"],
                  "planner": m["planner"]["trials"]}))
"""


def test_every_simulation_is_a_trial_counted_at_the_simulator():
    """Independent count: with numba off, every call of the simulator's kernel is counted (the
    planner's, the loop's, each polish's, its first included); the search's one extra call
    re-simulates the written best for ``meta`` (not a trial)."""
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    out = subprocess.run([sys.executable, "-c", _COUNT, "600"], env=env, cwd=ROOT, capture_output=True, text=True,
                         timeout=600)
    assert out.returncode == 0, out.stderr[-2000:]
    d = json.loads(out.stdout.strip().splitlines()[-1])
    assert d["planner"] > 0 and d["polish"] > 0
    assert d["calls"] == d["trials"] + 1 and d["trials"] == 600


def test_ablation_entry_without_the_planner():
    from nbst.experiments import runs as X

    assert X.parse_entries("nbst, NBST-noplan") == ("nbst", "nbst-noplan") and "nbst-noplan" in X.entries()
    spec = X.make_specs([load_problem("over5")], ["nbst-noplan"], runs=1, trials=3000)[0]
    r = X.run_one(spec)
    assert r["trials"] == 3000 and r["algorithm"] == "nbst-signature-search"


def test_search_with_the_planner_is_reproducible_from_the_seed():
    p = load_problem("over5")
    a = solve(p, seed=9, max_trials=12_000, patience=0)
    b = solve(p, seed=9, max_trials=12_000, patience=0, chunk=777)
    assert np.array_equal(a.velocities, b.velocities) and a.meta["history"] == b.meta["history"]
    assert a.meta["planner"] == b.meta["planner"]


def test_planted_plannable_instance_is_solved_by_the_planner_at_once():
    # nbst generate --planted 10 --noncue 2 --seed 4: each struck disk is hit once, from rest, by a
    # cue coming from its start; the planner rebuilds it exactly (without it: ~27,000 trials)
    from nbst.planted import planted

    p, _ = planted(10, noncue=2, seed=4)
    m = solve(p, seed=1, max_trials=20_000, target_cost=1e-6).meta
    assert m["cost"] < 1e-6 and m["trials"] < 2_000 and m["planner"]["best_cost"] < 1e-6
