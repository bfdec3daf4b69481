"""Planted problems at scale (issue 21): grid-hashed placement that keeps every old problem
bit for bit, the default box at fixed density, and planted motions that reproduce their targets."""
from __future__ import annotations

import hashlib
import itertools
import math

import numpy as np
import pytest
from scipy.spatial import cKDTree

from nbst import evaluate
from nbst.cli.main import main
from nbst.planted import START_GAP, default_box, place_disks, place_tries, planted

#: Today's output, computed by the code before the grid hash (commit de82345, the O(N) check per
#: try): sha256 over the starts, the planted velocities (float64 bytes) and the cueable flags
#: (int8), i.e. everything drawn from the seed; then the sum of the targets and the planted
#: motion's event counts, which come from the exact simulator.
PINS = {
    (5, 0, 15.0, 1): ("0b306fb01aa5aa5ae3fb", (1675.6277857615137, 2150.1050154329273), 0),
    (12, 3, 15.0, 7): ("1f50f90bc952bb4ac2fb", (4237.840593495696, 5312.257755791396), 2),
    (30, 4, 12.0, 123): ("65c4654c3ee4c80a0c1f", (11290.290667317993, 12491.15629563989), 23),
    (60, 0, 15.0, 2): ("11fc1e3cf998bba99a03", (25825.7417676193, 22639.046806787403), 57),
}


def _draws_hash(p, v) -> str:
    m = hashlib.sha256()
    for a in (np.array([d["start"] for d in p.raw["disks"]]), np.asarray(v, float),
              np.array([d["cueable"] for d in p.raw["disks"]]).astype(np.int8)):
        m.update(np.ascontiguousarray(a).tobytes())
    return m.hexdigest()[:20]


@pytest.mark.parametrize("case", sorted(PINS))
def test_planted_problems_are_bit_identical_to_before_the_grid_hash(case):
    n, k, r, seed = case
    want, tsum, collisions = PINS[case]
    p, v = planted(n, noncue=k, radius=r, seed=seed)
    assert p.box == (800.0, 800.0)
    assert _draws_hash(p, v) == want
    # the targets are the exact simulator's: the same motion to round-off (1e-9 of the box per disk)
    assert np.allclose(p.target.sum(axis=0), tsum, rtol=0, atol=n * 800 * 1e-9)
    assert p.raw["planted"]["disk_disk_collisions"] == collisions


def _old_placement(n, r, box, seed, tries=20_000, gap=START_GAP):
    """The placement loop as it was (one rng.uniform pair per try, O(N) check): the reference."""
    rng = np.random.default_rng(seed)
    W, H = box
    starts = np.empty((n, 2))
    placed = 0
    for _ in range(tries):
        c = rng.uniform([r, r], [W - r, H - r])
        if placed == 0 or np.min(np.hypot(*(starts[:placed] - c).T)) >= 2 * r + gap:
            starts[placed] = c
            placed += 1
            if placed == n:
                break
    return starts[:placed], rng.random()  # and the next draw: the stream is left where it was


def test_grid_placement_keeps_the_old_draws_and_acceptances_in_crowded_boxes_too():
    # near the packing limit (hundreds to thousands of rejected tries), plus a case that ran out of tries
    crowded = [(63, 30.0, (800.0, 800.0)), (16, 30.0, (400.0, 260.0)), (33, 52.0, (800.0, 800.0)),
               (4, 52.0, (400.0, 260.0)), (1, 6.0, (800.0, 800.0)), (40, 6.0, (400.0, 260.0))]
    cases = [(n, r, seed, box) for (n, r, box), seed in itertools.product(crowded, range(4))]
    for n, r, seed, box in cases + [(20, 30.0, 0, (400.0, 260.0))]:
        old, old_next = _old_placement(n, r, box, seed)
        rng = np.random.default_rng(seed)
        new, placed = place_disks(rng, n, r, box)
        if old.shape[0] == n:  # it worked before: the same disks, and the stream continues the same
            assert placed == n and np.array_equal(new, old), (n, r, seed, box)
            assert rng.random() == old_next
        else:  # it failed before; the larger budget may place more, never differently
            assert np.array_equal(new[:old.shape[0]], old)


def test_default_box_keeps_800_up_to_the_old_cap_then_fixed_density():
    assert default_box(1) == default_box(63) == (800.0, 800.0)
    for n in (64, 1000, 10_000):
        W, H = default_box(n)
        assert W == H and math.isclose(n / (W * H), 60 / 800**2, rel_tol=1e-12)
    p, _ = planted(70, seed=1, box=(900.0, 700.0))  # a given box wins
    assert p.box == (900.0, 700.0)


def _min_centre_distance(x):
    d, _ = cKDTree(x).query(x, k=2)
    return float(d[:, 1].min())


@pytest.mark.parametrize("n", [2000, 10_000])
def test_large_n_places_without_overlap_within_its_budget(n):
    r = 15.0
    starts, placed = place_disks(np.random.default_rng(3), n, r, default_box(n))
    W, H = default_box(n)
    assert placed == n and place_tries(n) >= 200 * n
    assert _min_centre_distance(starts) >= 2 * r + START_GAP
    assert (starts >= r).all() and (starts[:, 0] <= W - r).all() and (starts[:, 1] <= H - r).all()


def _reproduces(n, seed):
    p, v = planted(n, seed=seed)
    assert p.n == n and p.box == default_box(n)
    assert _min_centre_distance(p.start) >= 2 * p.radius[0] + START_GAP
    final, cost, _ = evaluate(p, v[None])
    # the planted velocities bring every disk to its target (the exact run that made them), to 1e-9 of the box
    assert np.abs(final[0] - p.target).max() <= 1e-9 * max(p.box)
    # a real many-body motion, not free flight: ~1 collision per disk at the fixed density and speeds
    assert p.raw["planted"]["disk_disk_collisions"] > n // 2


def test_planted_300_reproduces_its_targets():
    _reproduces(300, seed=5)


@pytest.mark.slow
def test_planted_2000_reproduces_its_targets():
    _reproduces(2000, seed=1)


def test_cli_quiet_says_nothing_and_progress_shows_long_stages(tmp_path, capsys, monkeypatch):
    out = tmp_path / "p.json"
    assert main(["generate", "--planted", "80", "--seed", "1", "-o", str(out), "-q"]) == 0
    said = capsys.readouterr()
    assert said.out == "" and said.err == "" and out.is_file()
    import nbst.cli.generate as g

    monkeypatch.setattr(g, "LONG_STAGE_S", 0.0)
    monkeypatch.setattr(g, "ANNOUNCE_SIMULATION_FROM", 1)
    assert main(["generate", "--planted", "80", "--seed", "1", "-o", str(out)]) == 0
    err = capsys.readouterr().err.splitlines()
    assert any(ln.startswith("nbst generate: placing disks: 80/80") for ln in err), err
    assert any("simulating the planted motion" in ln for ln in err) and "\r" not in "".join(err)
    from nbst import load_problem

    p = load_problem(str(out))
    assert p.box == default_box(80) and p.n == 80
