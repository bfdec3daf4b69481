"""The bowling atlas (nbst.models.bowling.deck.atlas, .geometry): the shipped atlas's robustness,
the MAP-Elites emitter's reproducibility, and the geometric facts behind "which subsets seem
impossible"."""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from nbst.models.bowling import deck, geometry, pinfall

ROOT = Path(__file__).resolve().parents[1]
ATLAS = ROOT / "models" / "bowling" / "deck" / "atlas.json"


# --- geometry (pure numpy) -------------------------------------------------------------------

def test_geometry_numbers_are_the_scenes():
    pytest.importorskip("mujoco")
    from nbst.models.bowling import pin, scene
    
    np.testing.assert_allclose(geometry.pin_spots(), scene.pin_spots(), rtol=0, atol=1e-15)
    assert geometry.PIN_RADIUS == pytest.approx(pin.profile()[:, 0].max(), rel=1e-12)
    assert geometry.BALL_RADIUS == scene.BALL_RADIUS and geometry.LANE_WIDTH == scene.LANE_WIDTH
    assert geometry.GUTTER_WIDTH == scene.GUTTER_WIDTH
    assert geometry.Y_LANE == pytest.approx(deck.BOUNDS["y"][1])
    assert geometry.THETA_MAX >= deck.BOUNDS["angle"][1]


def test_the_ball_cannot_pass_between_neighbouring_pins():
    adj = geometry.neighbours()
    assert adj.sum() == 2 * 18                                    # the triangle's 18 edges
    for a, b in zip(*np.nonzero(np.triu(adj))):
        assert geometry.gap(a + 1, b + 1) < 2 * geometry.BALL_RADIUS   # 7.23 in < 8.5 in
    assert geometry.gap(2, 3) == pytest.approx(12 * 0.0254 - 4.766 * 0.0254)
    # but it fits between pins two spacings apart (e.g. the 7-10 split's 4 and 6 are 24 in apart)
    assert geometry.gap(4, 6) > 2 * geometry.BALL_RADIUS


def test_every_path_on_the_lane_touches_a_pin_and_a_back_row_pin():
    p = geometry.paths()
    inside, must = geometry.corridors(p)
    on_lane = np.abs(p[:, 0]) <= geometry.Y_LANE
    assert on_lane.sum() > 1000
    assert inside[on_lane].any(axis=1).all()                      # only a gutter ball misses every pin
    assert inside[on_lane][:, 6:].any(axis=1).all()               # and it reaches the back row (7-10)
    assert (must <= inside).all() and (must.any(axis=1) == inside.any(axis=1)).all()
    # columns 6 in apart, closer than ball + pin radius: no straight gap through a row
    assert geometry.PIN_SPACING / 2 < geometry.REACH


def test_classes_cover_every_subset_and_single_pins():
    cl = geometry.classify()
    assert len(cl) == 1023 and set(cl.values()) <= {"a", "corridor", "reach"}
    singles = {n: cl[1 << (n - 1)] for n in range(1, 11)}
    # only the corner pins fall alone (a ball in or at the edge of the gutter clips them)
    assert [n for n, c in singles.items() if c == "a"] == [7, 10]
    assert cl[1023] == "a"
    # a stricter rule classes fewer subsets as consistent, a weaker one more
    n = {t: sum(c == "a" for c in geometry.classify(touch=t).values()) for t in ("all", "front", "any")}
    assert n["all"] <= n["front"] <= n["any"]


# --- the shipped atlas ---------------------------------------------------------------------

def test_shipped_atlas_shots_carry_robustness():
    atlas = json.loads(ATLAS.read_text())
    for d in atlas["shots"]:
        r = d["robustness"]
        assert {"lateral_m", "speed_m_s", "lateral_m_rollouts", "speed_m_s_rollouts", "method"} <= set(r)
        assert 0 <= r["lateral_m"] <= 0.0512 and 0 <= r["speed_m_s"] <= 0.512
        assert 0 < r["lateral_m_rollouts"] <= 8 and 0 < r["speed_m_s_rollouts"] <= 8
        assert r["method"].startswith("ladder")


def test_shipped_atlas_has_no_subset_the_corridor_rule_excludes():
    """What the docs claim: no found subset breaks the corridor rule (the rule stands on the
    atlas's evidence); flying pins do happen (the reach rule is broken)."""
    
    found = [pinfall.mask_from_pins(d["down"]) for d in json.loads(ATLAS.read_text())["shots"]]
    r = geometry.compare(found)
    assert r["breakers"]["corridor"] == []
    assert r["breakers"]["reach"]


# --- the emitter ---------------------------------------------------------------------------

def test_emitter_batches_depend_on_the_seed_and_archive_only():
    from nbst.models.bowling.deck import atlas

    a = atlas.SubsetArchive.from_elites({7: np.array([0.3, 7.0, 0.0, 0.0]), 1023: np.array([0.05, 8.0, 0.0, -10.0])})
    X1, p1 = atlas.emit(a, np.random.default_rng(5))
    X2, p2 = atlas.emit(a, np.random.default_rng(5))
    np.testing.assert_array_equal(X1, X2)
    np.testing.assert_array_equal(p1, p2)
    assert (p1[:atlas.UNIFORM_PER_BATCH] == -1).all() and set(p1[atlas.UNIFORM_PER_BATCH:]) <= {7, 1023}
    
    assert (X1 >= deck.LO).all() and (X1 <= deck.HI).all()
    w = atlas.parent_weights(a, [7, 1023])
    assert w.sum() == pytest.approx(1.0) and w[0] > w[1]          # size 1 (1/10 found) over the strike (1/1)


def test_emitter_run_is_reproducible_for_any_jobs():
    pytest.importorskip("mujoco")
    from nbst.models.bowling.deck import atlas

    runs = []
    for jobs in (1, 2):
        with deck.DeliveryRunner(jobs=jobs) as L:
            a = atlas.SubsetArchive.from_elites({1023: np.array([0.05, 8.0, 0.0, -10.0])})
            runs.append(atlas.run(L, a, method="elites", budget=32, seed=4))
    assert runs[0].rollouts == runs[1].rollouts == 32
    assert sorted(runs[0].elite) == sorted(runs[1].elite)
    for m in runs[0].elite:
        np.testing.assert_array_equal(runs[0].elite[m], runs[1].elite[m])
    assert runs[0].children == runs[1].children and sum(runs[0].children.values()) == 32 - 2 * 2


def test_size_table():
    from nbst.models.bowling.deck import atlas

    t = atlas.size_table([1, 2, 1023])
    assert t[0] == (1, 2, 10) and t[-1] == (10, 1, 1) and sum(p for _, _, p in t) == 1023
    assert math.comb(10, 5) == t[4][2]


def test_geometry_distance_ranks_neighbouring_extras_nearer():
    pytest.importorskip("mujoco")
    from nbst.models.bowling.deck import search

    want = pinfall.mask_from_pins([1, 2, 3])
    d = {tuple(p): float(search.geometry_distance(pinfall.mask_from_pins(p), want))
         for p in ([1, 2, 3], [], [1, 2, 3, 5], [1, 2, 3, 10], [1, 2], [1, 2, 3, 5, 8, 9])}
    assert d[(1, 2, 3)] == 0.0 and d[()] == 3.0 and d[(1, 2)] == 1.0
    assert d[(1, 2, 3, 5)] == 0.5 < d[(1, 2, 3, 10)] == 1.0           # 5 neighbours 2 and 3; 10 is far
    assert d[(1, 2, 3, 5, 8, 9)] == 2.5 < d[()]                        # the superset now ranks nearer than none
    for m in range(1024):                                              # 0 exactly at the request
        assert (search.geometry_distance(m, want) == 0) == (m == want)


def test_atlas_from_a_file_without_its_scene_is_one_clear_error(tmp_path, capsys):
    """--from names the missing scene file instead of a bare OS error; nothing is searched."""
    from nbst.cli import main

    src = Path(__file__).resolve().parents[1] / "models" / "bowling" / "deck" / "atlas.json"
    lonely = tmp_path / "a" / "atlas.json"
    lonely.parent.mkdir()
    lonely.write_bytes(src.read_bytes())  # without scene.xml beside it
    assert main(["bowl", "atlas", "--out-dir", str(tmp_path / "out"), "--from", str(lonely), "--max-rollouts", "16",
                 "-q"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("nbst bowl atlas: error: --from: ") and "scene.xml" in err and len(err.splitlines()) == 1
    assert "is missing" in err and "Errno" not in err  # the atlas's own words, not the OS error's
    assert not list((tmp_path / "out").glob("subset-*.json"))


def test_atlas_on_a_dask_cluster_writes_the_same_shots_as_one_thread(tmp_path):
    """--cluster sends the rollouts to Dask workers; batches and archive stay here, so the
    shots (initial states, pins down) are the same as with --jobs 1 for the same seed."""
    from dask.distributed import LocalCluster

    from nbst.cli import main

    base = ["bowl", "atlas", "--max-rollouts", "32", "--seed", "7", "--no-robustness", "-q"]
    assert main([*base, "--out-dir", str(tmp_path / "here"), "--jobs", "1"]) == 0
    from nbst.models.mjsearch import cluster as C

    C._WORKER_RUNNERS.clear()
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None) as cluster:
        assert main([*base, "--out-dir", str(tmp_path / "dask"), "--cluster", cluster.scheduler_address]) == 0
    assert C._WORKER_RUNNERS  # the rollouts ran on the workers (threads of this process here)
    here = {f.name: json.loads(f.read_text()) for f in (tmp_path / "here").glob("subset-*.json")}
    dask = {f.name: json.loads(f.read_text()) for f in (tmp_path / "dask").glob("subset-*.json")}
    assert here and here.keys() == dask.keys()
    for name, d in here.items():
        assert (d["qpos0"], d["qvel0"], d["down"]) == (dask[name]["qpos0"], dask[name]["qvel0"], dask[name]["down"])
