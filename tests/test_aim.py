"""Bank shots and strikes land exactly; planted instances have their zero-cost solution."""
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from conftest import make_problem
from nbst.search.aim import alloc_clearance, bank_shot, choose_bank, flights_conflict, path_conflicts, strike
from nbst.planted import planted
from nbst.search.ops import seed_state
from nbst.sim import simulate

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("kx, ky", [(0, 0), (1, 0), (0, -1), (2, 1), (-1, -2), (3, 0)])
def test_bank_shot_lands_exactly_when_the_path_is_clear(kx, ky):
    p = make_problem([(120, 300)], 20.0, targets=[(610, 95)])
    v = bank_shot(p, 0, kx, ky)
    tr = simulate(p, v[None])
    assert tr.n_wall == abs(kx) + abs(ky)
    # straight flight through mirror images: exact up to round-off of the folds
    np.testing.assert_allclose(tr.final_positions[0], p.target[0], atol=1e-9)


def test_choose_bank_avoids_a_blocker():
    # disk 1 sits still in the middle of every path with few bounces along the x axis
    p = make_problem([(100, 400), (400, 400)], 20.0, targets=[(700, 400), (400, 400)])
    V = np.zeros((2, 2))
    out = np.empty(2)
    c = choose_bank(0, np.ascontiguousarray(p.start), V, np.ascontiguousarray(p.radius),
                    np.ascontiguousarray(p.target), 800.0, 800.0, 5.0, 1, 3, alloc_clearance(2), seed_state(0), out)
    assert c == 0
    assert path_conflicts(0, out, np.ascontiguousarray(p.start), V, np.ascontiguousarray(p.radius),
                          800.0, 800.0, 5.0) == 0
    tr = simulate(p, np.array([out, [0.0, 0.0]]))
    assert tr.n_disk_disk == 0
    np.testing.assert_allclose(tr.final_positions, p.target, atol=1e-9)
    # the straight shot would have hit it
    assert path_conflicts(0, bank_shot(p, 0, 0, 0), np.ascontiguousarray(p.start), V,
                          np.ascontiguousarray(p.radius), 800.0, 800.0, 5.0) == 1


def test_flights_conflict_iff_the_simulator_sees_a_collision():
    # two disks alone in a box: their free flights conflict exactly when the exact
    # simulation has a disk-disk event
    rng = np.random.default_rng(4)
    both = 0
    for _ in range(400):
        r = rng.uniform(5, 30, 2)
        a = rng.uniform([r[0], r[0]], [300 - r[0], 200 - r[0]])
        b = rng.uniform([r[1], r[1]], [300 - r[1], 200 - r[1]])
        if np.hypot(*(a - b)) < r.sum() + 1e-6:
            continue
        v = rng.uniform(-300, 300, (2, 2))
        p = make_problem([a, b], r, box=(300, 200), t_final=2.0)
        hit = simulate(p, v).n_disk_disk > 0
        got = flights_conflict(a[0], a[1], v[0, 0], v[0, 1], r[0], b[0], b[1], v[1, 0], v[1, 1], r[1],
                               300.0, 200.0, 2.0)
        assert got == hit
        both += hit
    assert 40 < both < 360  # both outcomes well represented


@pytest.mark.parametrize("masses", [(1.0, 1.0), (2.5, 1.0), (1.0, 3.0)])
def test_strike_sends_a_lone_struck_disk_to_its_target(masses):
    p = make_problem([(150, 200), (300, 260)], 15.0, masses=masses, cueable=[True, False],
                     targets=[(150, 200), (620, 520)])
    v, t_hit = strike(p, 0, 1)
    V = np.array([v, [0.0, 0.0]])
    tr = simulate(p, V)
    assert tr.events[0]["kind"] == 0 and tr.events[0]["time"] == pytest.approx(t_hit, abs=1e-9)
    assert tr.n_disk_disk == 1
    np.testing.assert_allclose(tr.final_positions[1], p.target[1], atol=1e-6)


def test_strike_from_the_far_side_is_refused():
    p = make_problem([(500, 200), (300, 200)], 15.0, cueable=[True, False], targets=[(500, 200), (600, 200)])
    with pytest.raises(ValueError, match="far side"):
        strike(p, 0, 1)


def test_planted_instances_have_zero_cost_and_are_reproducible():
    for n, k in ((6, 0), (10, 3), (20, 5)):
        p, v = planted(n, noncue=k, seed=11)
        tr = simulate(p, v)
        # targets are the simulated ends, written as floats: cost 0 up to a wall clip's round-off
        assert tr.cost < 1e-18 and tr.order == n
        assert int((~p.cueable).sum()) == k and np.all(v[~p.cueable] == 0)
        p2, v2 = planted(n, noncue=k, seed=11)
        assert np.array_equal(v, v2) and np.array_equal(p.target, p2.target)
    p, _ = planted(10, noncue=4, seed=2)
    assert p.raw["planted"]["struck_noncueable"] >= 3  # the strikes mostly connect


def test_generate_cli(tmp_path):
    out, sol = tmp_path / "p.json", tmp_path / "s.json"
    r = subprocess.run([sys.executable, str(ROOT / "cli.py"), "generate", "--planted", "8", "--noncue", "2",
                        "--seed", "3", "-o", str(out), "--solution", str(sol)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    r = subprocess.run([sys.executable, str(ROOT / "cli.py"), "simulate", str(out), str(sol), "--json"],
                       capture_output=True, text=True)
    assert json.loads(r.stdout)["order"] == 8
    r = subprocess.run([sys.executable, str(ROOT / "cli.py"), "generate", "--planted", "4", "--noncue", "4",
                        "-o", str(out)], capture_output=True, text=True)
    assert r.returncode == 2 and "noncue" in r.stderr and "Traceback" not in r.stderr


def test_chain_strike_sends_the_second_struck_disk_to_its_target():
    from nbst.search.aim import chain_strike_velocity
    p = make_problem([(100, 150), (250, 220), (420, 300)], 12.0, masses=[1.0, 1.5, 0.8],
                     cueable=[True, False, False], targets=[(100, 150), (250, 220), (700, 560)])
    out = np.empty(2)
    t2 = chain_strike_velocity(p.start[0], 12.0, 1.0, p.start[1], 12.0, 1.5, p.start[2], 12.0, 0.8,
                               np.ascontiguousarray(p.target[2]), 5.0, out)
    assert 0 < t2 < 5
    tr = simulate(p, np.array([out, [0, 0], [0, 0]]))
    assert [(e["i"], e["j"]) for e in tr.events[:2]] == [(0, 1), (1, 2)]
    assert tr.events[1]["time"] == pytest.approx(t2, abs=1e-9)
    np.testing.assert_allclose(tr.final_positions[2], p.target[2], atol=1e-6)
