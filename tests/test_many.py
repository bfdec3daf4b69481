"""The many-body search (nbst.search.many) and its two-disk contact solutions (nbst.search.aim)."""
from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from nbst.errors import SolveError
from nbst.problem import load_problem, problem_from_dict
from nbst.search import run_search, solve
from nbst.search.aim import pair_contact
from nbst.search.local import conflicts, subproblem
from nbst.search.many import ManyParams, run_many
from nbst.search.variants import SolveRequest
from nbst.sim import simulate


def _two(v, box=(200.0, 200.0), r=(5.0, 5.0), m=(1.0, 1.0), starts=((50.0, 100.0), (100.0, 104.0)), t=2.0):
    """Two disks sent with velocities v; the targets are where the exact simulator takes them."""
    d = {"name": "two", "box": list(box), "t_final": t, "target_radius": 5.0,
         "disks": [{"start": list(starts[k]), "target": list(starts[k]), "radius": r[k], "mass": m[k]} for k in (0, 1)]}
    tr = simulate(problem_from_dict(d), np.array(v, float))
    for k in (0, 1):
        d["disks"][k]["target"] = tr.final_positions[k].tolist()
    return problem_from_dict(d), tr


@pytest.mark.parametrize("v,m,r", [([[30.0, 1.0], [-5.0, 0.0]], (1.0, 1.0), (5.0, 5.0)),
                                   ([[25.0, 8.0], [-10.0, 3.0]], (1.0, 3.0), (5.0, 8.0)),
                                   ([[40.0, -2.0], [0.0, 0.0]], (2.0, 1.0), (6.0, 4.0))])
def test_pair_contact_finds_the_motion_that_made_the_targets(v, m, r):
    """A motion with one contact: pair_contact recovers its velocities (1e-9 relative), and every
    solution it returns lands both disks on their targets in the exact simulator (1e-9 of the box)."""
    p, tr = _two(v, r=r, m=m)
    assert tr.n_disk_disk == 1 and tr.n_wall == 0
    out = np.empty((8, 5))
    ka = p.kernel_arrays()
    k = pair_contact(ka.start[0], ka.start[1], ka.target[0], ka.target[1], ka.mass[0], ka.mass[1], ka.radius[0],
                     ka.radius[1], ka.W, ka.H, ka.t_final, 400, out)
    assert k >= 1
    got = [out[q, :4].reshape(2, 2) for q in range(k)]
    assert min(np.abs(g - np.array(v)).max() for g in got) <= 1e-9 * np.abs(v).max()
    for g in got:
        t2 = simulate(p, g)
        assert t2.n_disk_disk == 1
        assert np.abs(t2.final_positions - p.target).max() <= 1e-9 * 200.0


def test_pair_contact_far_apart_meets_on_the_way():
    """Two disks far apart that never meet on straight shots can still meet once and land: every
    motion pair_contact gives for them has one contact and lands both (1e-9 of the box)."""
    p, tr = _two([[5.0, 0.0], [0.0, 5.0]], starts=((20.0, 20.0), (180.0, 180.0)))
    assert tr.n_disk_disk == 0
    ka = p.kernel_arrays()
    out = np.empty((8, 5))
    k = pair_contact(ka.start[0], ka.start[1], ka.target[0], ka.target[1], 1.0, 1.0, 5.0, 5.0, ka.W, ka.H,
                     ka.t_final, 400, out)
    assert k >= 1
    for q in range(k):
        t2 = simulate(p, out[q, :4].reshape(2, 2))
        assert t2.n_disk_disk == 1 and np.abs(t2.final_positions - p.target).max() <= 1e-9 * 200.0


def test_a_window_subproblem_moves_the_same():
    """Velocities mean the same in a window of the box (translation invariance) while no disk
    reaches the window's sides: the same final positions, shifted, to round-off."""
    p = load_problem("diamond-s14")
    idx = np.array([0, 1, 2])
    whole = subproblem(p, idx, "w")
    win = subproblem(p, idx, "w", margin=200.0)
    v = whole.straight_velocities()
    fa = simulate(whole, v).final_positions
    fb = simulate(win, v).final_positions
    shift = whole.start[0] - win.start[0]
    assert win.box[0] <= p.box[0] and np.all(shift >= 0)
    np.testing.assert_allclose(fb + shift, fa, rtol=0, atol=1e-9 * max(p.box))


def _grid(n, spacing=60.0, r=5.0, shift=(20.0, 0.0)):
    side = int(np.ceil(np.sqrt(n)))
    disks = [{"start": [40.0 + spacing * (k % side), 40.0 + spacing * (k // side)],
              "target": [40.0 + spacing * (k % side) + shift[0], 40.0 + spacing * (k // side) + shift[1]],
              "radius": r} for k in range(n)]
    return problem_from_dict({"name": f"grid-{n}", "box": [spacing * side + 80.0, spacing * side + 80.0],
                              "t_final": 2.0, "target_radius": 10.0, "disks": disks})


def test_collision_free_targets_are_exact_at_once():
    """A formation whose straight shots never meet (a shifted grid of 400 disks) is exact after
    the directed start: one simulation."""
    p = _grid(400)
    sol = solve(p, seed=1)
    assert sol.meta["algorithm"] == "nbst-many" and sol.meta["order"] == 400
    assert sol.meta["trials"] == 1 and sol.meta["stopped"] == "target_cost"
    assert len(sol.meta["signature"]) == 400 and set(sol.meta["signature"]) == {"1"}


def _crossing(n=100, seed=3):
    """n disks whose straight shots cross: targets are a random permutation of nearby starts."""
    rng = np.random.default_rng(seed)
    p = _grid(n, spacing=45.0, r=6.0, shift=(0.0, 0.0))
    d = json.loads(json.dumps(p.raw))
    perm = np.arange(n)
    for a in range(0, n - 1, 2):  # swap neighbours in pairs: their straight paths meet head on
        if rng.random() < 0.6:
            perm[a], perm[a + 1] = perm[a + 1], perm[a]
    for k in range(n):
        d["disks"][k]["target"] = p.start[perm[k]].tolist()
    d["name"] = f"swaps-{n}"
    return problem_from_dict(d)


def test_the_search_is_never_worse_than_its_start_and_reproducible():
    p = _crossing()
    start = simulate(p, p.straight_velocities())
    assert start.n_disk_disk > 10
    prm = ManyParams(patience_rounds=3)
    r1 = run_many(p, seed=7, max_trials=3000, patience=0, target_cost=1e-9, params=prm)
    r2 = run_many(p, seed=7, max_trials=3000, patience=0, target_cost=1e-9, params=prm)
    v1, v2 = r1.velocities, r2.velocities
    np.testing.assert_array_equal(v1, v2)
    end = simulate(p, v1)
    assert end.order >= start.order and end.cost <= start.cost
    assert r1.stats["by_pair"] + r1.stats["by_shot"] + r1.stats["by_chain"] > 0
    # every disk of every conflict left misses its target by more than the threshold
    for idx in conflicts(p, end, 1e-9 / p.n):
        assert np.any(np.sum((end.final_positions[idx] - p.target[idx]) ** 2, axis=1) > 1e-9 / p.n)


def test_the_signature_search_refuses_many_disks():
    from nbst.search import driver

    with pytest.raises(SolveError, match="at most 63 disks"):
        driver.run_search(_grid(64), SolveRequest(seed=1, max_trials=10))
    r = run_search(_grid(64), seed=1, max_trials=10)
    assert r.result.meta["order"] == 64


def test_nbst_solve_on_a_many_disk_file(tmp_path):
    prob = tmp_path / "grid.json"
    prob.write_text(json.dumps(_grid(150).raw))
    out = tmp_path / "sol.json"
    r = subprocess.run([sys.executable, "-m", "nbst.cli", "solve", str(prob), "-o", str(out), "--seed", "2"],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    assert "150/150 disks on target (signature in the file)" in r.stderr
    sol = json.loads(out.read_text())
    assert sol["order"] == 150 and len(sol["signature"]) == 150 and sol["algorithm"] == "nbst-many"


def test_progress_reports_the_best_motion_and_how_near_the_stop_is():
    """The many-body search's reports: the best motion so far never gets worse (fewer disks
    missing, then a lower cost: ``population`` is its disks missing), each report carries
    (rounds without a better motion, the rounds that stop it) within 0..patience_rounds, and
    the result is the last best reported."""
    from nbst.planted import planted

    p, _ = planted(100, seed=1)
    seen = []
    sol = solve(p, seed=1, max_trials=40_000, callback=lambda q: seen.append(q) and None, jobs=1)
    assert len(seen) > 3
    scores = [(q.population, q.best_cost) for q in seen]
    assert all(b <= a for a, b in zip(scores, scores[1:])), scores
    costs = [q.best_cost for q in seen]
    rounds = ManyParams().patience_rounds
    assert all(q.stall is not None and q.stall[1] == rounds and 0 <= q.stall[0] <= rounds for q in seen)
    assert sol.meta["cost"] <= costs[-1] * (1 + 1e-12)


def _grid_and_strike(aim=(900.0, 500.0)):
    """64 disks on a grid whose straight shots never meet, and apart from them a cue disk c
    (index 64) that strikes a resting disk b (index 65) towards ``aim``; every target is where
    the exact simulator takes its disk, so a strike that lands both exists."""
    from nbst.search.aim import strike

    g = _grid(64)
    d = {"name": "grid-and-strike", "box": [1000.0, 600.0], "t_final": 2.0, "target_radius": 10.0,
         "disks": [{"start": p.tolist(), "target": t.tolist(), "radius": 5.0} for p, t in zip(g.start, g.target)]}
    d["disks"].append({"start": [700.0, 100.0], "target": [700.0, 100.0], "radius": 5.0})
    d["disks"].append({"start": [800.0, 300.0], "target": [800.0, 300.0], "radius": 5.0, "cueable": False})
    p = problem_from_dict(d)
    v = p.straight_velocities()
    v[64] = strike(p, 64, 65, np.array(aim))[0]
    tr = simulate(p, v)
    for k in (64, 65):
        d["disks"][k]["target"] = tr.final_positions[k].tolist()
    return problem_from_dict(d), tr


def test_strikes_send_a_resting_disk_to_its_target():
    """``_strikes``' aimed candidates include exact strikes (the resting disk, alone with its
    striker, lands within 1e-6 of its target, by the closed-form strike), and each polished
    candidate lands the pair no worse (sum of squared misses) than the aim it started from."""
    from nbst.search.many import _strikes

    p, _ = _grid_and_strike()
    cands = _strikes(p, 65, strikers=3, keep=4, polish_sims=30)
    assert len(cands) == 8 and all(d.size == 1 and p.cueable[d[0]] for d, _ in cands)
    pair_miss = []
    for d, rows in cands:
        pair = subproblem(p, np.array([d[0], 65]), "pair")
        fin = simulate(pair, np.array([rows[0], [0.0, 0.0]])).final_positions
        pair_miss.append(np.sum((fin - pair.target) ** 2, axis=1))
    assert sum(m[1] <= 1e-12 for m in pair_miss[1::2]) >= 2
    for polished, aimed in zip(pair_miss[0::2], pair_miss[1::2]):
        assert polished.sum() <= aimed.sum() * (1 + 1e-12) + 1e-18


def test_a_resting_disk_that_must_move_is_struck():
    """Past 63 disks, with a resting disk whose target is elsewhere, the search counts the
    disks outside R first and strikes it: every disk ends on its target."""
    p, planted = _grid_and_strike()
    assert planted.n_disk_disk == 1
    start = simulate(p, p.straight_velocities())
    assert start.order < p.n
    run = run_many(p, seed=3, max_trials=2000, patience=0, target_cost=1e-12, params=ManyParams(patience_rounds=3))
    v = run.velocities
    end = simulate(p, v)
    assert run.stats["by_strike"] >= 1
    assert end.order == p.n
    np.testing.assert_allclose(end.final_positions, p.target, atol=1e-6)


def test_a_missing_disk_pairs_with_its_nearest_neighbours_first():
    """``_candidates`` tries two-disk contacts with the missing disks first, then the nearest
    others (not the lowest-numbered ones): a missing disk next to a landed one gets the contact
    that made the targets (pair_contact finds every one-contact motion)."""
    from nbst.search.many import _candidates

    g = _grid(64)
    d = {"name": "grid-and-pair", "box": [1000.0, 600.0], "t_final": 2.0, "target_radius": 10.0,
         "disks": [{"start": p.tolist(), "target": t.tolist(), "radius": 5.0} for p, t in zip(g.start, g.target)]}
    d["disks"] += [{"start": [650.0, 300.0], "target": [650.0, 300.0], "radius": 5.0},
                   {"start": [800.0, 304.0], "target": [800.0, 304.0], "radius": 5.0}]
    p = problem_from_dict(d)
    v = p.straight_velocities()
    v[64], v[65] = (80.0, 0.0), (-10.0, 0.0)
    tr = simulate(p, v)
    assert tr.n_disk_disk == 1
    for k in (64, 65):
        d["disks"][k]["target"] = tr.final_positions[k].tolist()
    p = problem_from_dict(d)
    err2 = np.zeros(p.n)
    err2[64] = 1.0  # only disk 64 misses: its partners are the nearest landed disks, 65 first
    cands = _candidates(p, 64, p.straight_velocities(), err2, 1e-12, 3, np.empty((8, 5)))
    pairs = [rows for disks, rows in cands if list(disks) == [64, 65]]
    assert any(np.allclose(rows, v[[64, 65]], atol=1e-6) for rows in pairs)
