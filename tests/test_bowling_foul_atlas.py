"""The atlas from the foul line and `nbst bowl solve --foul-line/--robust` (issue 22):
models/bowling/foul_atlas.py, nbst/cli/bowl/foul.py."""
from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest

pytest.importorskip("mujoco")

from nbst.models.bowling.deck import atlas  # noqa: E402
from nbst.models.bowling import lane  # noqa: E402
from nbst.models.bowling.lane import atlas as foul_atlas, frame, noise, throwfile
from nbst.models.bowling import pinfall


@pytest.fixture(scope="module")
def runner():
    with frame.FrameRunner(foul_atlas.OIL, jobs=1) as R:
        yield R


def _point(share: float, hand: float = 0.0) -> np.ndarray:
    x = foul_atlas.LO + share * (foul_atlas.HI - foul_atlas.LO)
    x[-1] = hand
    return x


def test_the_throw_space_is_a_bowlers_and_round_trips():
    assert foul_atlas.KEYS == ("board", "angle", "mph", "rpm", "rotation", "tilt") and foul_atlas.DIM == 7
    for hand, name in ((0.0, "right"), (1.0, "left")):
        x = _point(0.37, hand)
        d = foul_atlas.delivery_of(x)
        assert d.at == "foul" and d.hand == name and d.check() is d
        assert np.allclose(foul_atlas.point_of(d), x, atol=1e-12)
        assert np.allclose(foul_atlas.from_unit(foul_atlas.to_unit(x)), x, atol=1e-12)
    assert np.all(foul_atlas.from_unit([-1.0] * 7) == foul_atlas.LO)  # clipped to the ranges
    assert set(foul_atlas.from_unit(np.linspace(0, 1, 11)[:, None] * np.ones(7))[:, -1]) == {0.0, 1.0}


def test_the_mirror_swaps_the_pins_across_the_middle_board():
    assert foul_atlas.mirror(pinfall.mask_from_pins([7])) == pinfall.mask_from_pins([10])
    assert foul_atlas.mirror(pinfall.mask_from_pins([1, 2, 4, 8])) == pinfall.mask_from_pins([1, 3, 6, 9])
    assert all(foul_atlas.mirror(foul_atlas.mirror(m)) == m for m in range(1, 1024))


def test_a_left_handers_mirrored_spare_converts_the_mirrored_pin(runner):
    """The lane is mirror-symmetric: the 10-pin spare ball thrown left-handed (the same boards
    counted from the left edge) converts the 7 pin, within the ladder's robustness."""
    from dataclasses import replace

    from nbst.models.bowling.lane import spares

    d = spares.straight_at(*spares.aim_point((10,)))
    assert runner.one(d, standing=[10]).converted
    assert runner.one(replace(d, hand="left"), standing=[7]).converted


def test_grow_is_reproducible_from_the_seed_on_one_and_two_processes(runner):
    a1 = foul_atlas.grow(runner, atlas.SubsetArchive(), budget=24, seed=5)
    with frame.FrameRunner(foul_atlas.OIL, jobs=2) as R2:
        a2 = foul_atlas.grow(R2, atlas.SubsetArchive(), budget=24, seed=5)
    assert a1.rollouts == a2.rollouts == 24
    assert sorted(a1.elite) == sorted(a2.elite) and a1.elite
    for m in a1.elite:
        assert np.array_equal(a1.elite[m], a2.elite[m])
    # every elite is a throw whose settled pins down are its subset (a frame depends on its delivery only)
    m = sorted(a1.elite)[0]
    assert runner.one(foul_atlas.delivery_of(a1.elite[m])).down == pinfall.pins_of(m)


def test_the_probability_counts_exactly_the_subset(runner):
    a = foul_atlas.grow(runner, atlas.SubsetArchive(), budget=16, seed=2)
    m = max(a.elite, key=lambda k: bin(k).count("1"))
    est = foul_atlas.probabilities(runner, {m: a.elite[m]}, n=4, seed=3)[m]
    frames = runner.map(noise.sample(foul_atlas.delivery_of(a.elite[m]), 4, 3))
    k = sum(r.down == pinfall.pins_of(m) for r in frames)
    assert (est.k, est.n) == (k, 4) and est.lo <= est.p <= est.hi


def test_the_mirror_step_throws_the_other_hand_once_per_unmirrored_subset(runner):
    a = foul_atlas.grow(runner, atlas.SubsetArchive(), budget=16, seed=6)
    todo = [m for m in a.elite if foul_atlas.mirror(m) not in a.elite]
    before, n0 = dict(a.elite), a.rollouts
    new = foul_atlas.mirror_step(runner, a)
    assert a.rollouts == n0 + len(todo)
    for m in new:
        assert m not in before
        assert foul_atlas.hand_of(a.elite[m]) in ("left", "right")
    assert foul_atlas.mirror_step(runner, atlas.SubsetArchive()) == []


def test_noisy_throws_harvest_new_subsets_with_themselves_as_elites(runner):
    a = foul_atlas.grow(runner, atlas.SubsetArchive(), budget=16, seed=2)
    m = max(a.elite, key=lambda k: bin(k).count("1"))
    b = atlas.SubsetArchive(rollouts=7)
    b.elite[m] = a.elite[m]
    _, throws, results = foul_atlas.probabilities(runner, {m: a.elite[m]}, n=6, seed=3, frames=True)
    new = foul_atlas.harvest(b, throws, results)
    seen = {pinfall.mask_from_pins(r.down) for r in results} - {0, m}
    assert set(new) <= seen and b.rollouts == 7  # the frames had run: no new frames counted
    for k in new:
        x = b.elite[k]
        assert np.all(x >= foul_atlas.LO) and np.all(x <= foul_atlas.HI)
        assert runner.one(foul_atlas.delivery_of(x)).down == pinfall.pins_of(k)


def test_seek_confirms_an_archived_answer_with_one_frame_and_searches_when_it_fails(runner):
    x = _point(0.5)
    m = foul_atlas.throw_masks(runner, [x])[0][0]
    point, arch, frames = foul_atlas.seek(runner, {m: x}, m, budget=100, seed=1)
    assert frames == 1 and np.array_equal(point, x) and set(arch) == {m}
    wrong = 1023 ^ m if m != 1023 else 1  # an archive of another scene: its answer is a start only
    point, arch, frames = foul_atlas.seek(runner, {wrong: x}, wrong, budget=1, seed=1)
    assert frames == 1 and point is None and wrong not in arch and (m == 0 or np.array_equal(arch[m], x))
    # an archive of this scene (trusted) answers with its throw, no frame run
    point, arch, frames = foul_atlas.seek(runner, {wrong: x}, wrong, budget=1, seed=1, trusted=True)
    assert frames == 0 and np.array_equal(point, x)


def test_seek_grows_the_archive_with_what_its_children_knock_down(runner):
    # the 7-10 split is out of reach of 16 frames; every subset seen on the way is archived truly
    point, arch, frames = foul_atlas.seek(runner, {}, pinfall.mask_from_pins([1, 2, 3, 4, 5, 6, 8, 9]), budget=16,
                                          seed=4)
    assert frames == 16
    for m, x in list(arch.items())[:2]:
        assert runner.one(foul_atlas.delivery_of(x)).down == pinfall.pins_of(m)


def test_the_archive_checkpoint_round_trips_and_refuses_hostile_content():
    a = atlas.SubsetArchive(rollouts=40)
    a.elite[3] = _point(0.25, 1.0)
    a.seen[3], a.found_at[3] = 2, 17
    doc = json.loads(json.dumps(foul_atlas.archive_doc(a, seed=9)))
    b = foul_atlas.archive_from_doc(doc, "archive.json")
    assert b.rollouts == 40 and np.array_equal(b.elite[3], a.elite[3]) and b.seen[3] == 2 and b.found_at[3] == 17
    bad = [("format", "x", "format"), ("rollouts", -1, "rollouts"), ("elites", {"0": list(a.elite[3])}, "elites.0"),
           ("elites", {"1024": list(a.elite[3])}, "elites.1024"), ("elites", {"3": [math.nan] * 7}, "elites.3"),
           ("elites", {"3": [99.0] * 7}, "elites.3"), ("elites", {"3": [1.0] * 6}, "elites.3"),
           ("keys", list(foul_atlas.KEYS), "keys"),
           ("seen", {"3": "many"}, "seen.3")]
    for key, value, field in bad:
        d = dict(doc, **{key: value})
        with pytest.raises(ValueError) as e:
            foul_atlas.archive_from_doc(d, "archive.json")
        msg = str(e.value)
        assert msg.startswith(f"archive.json: {field}:") and "\n" not in msg


def test_the_shipped_atlas_holds_each_subset_once_with_its_probability_on_this_scene():
    """The shipped atlas was grown on today's lane scene (docs/bowling.md says how many subsets; issue
    22's 302 were lane-1's): one throw per subset on a full rack, each with its probability under the
    atlas's noise (at least 20 noisy throws, a Wilson interval around it) and the timestep ladder."""
    a = throwfile.load_atlas(foul_atlas.SHIPPED)
    assert a["scene"] == lane.SCENE and noise.Noise(**a["noise"]) == noise.DEFAULT
    downs = [tuple(t["outcome"]["down"]) for t in a["throws"]]
    assert len(set(downs)) == len(downs) >= 150
    for t in a["throws"]:
        assert t["scene"] == lane.SCENE
        assert t["standing"] == throwfile.FULL_RACK and t["requested"]["down"] == t["outcome"]["down"]
        p = t["probability"]
        assert p["want"]["down"] == t["outcome"]["down"] and p["n"] >= 20 and 0 <= p["lo"] <= p["p"] <= p["hi"] <= 1
        assert [x["timestep"] for x in t["ladder"]] == list(frame.LADDER)
    assert any(t["probability"]["k"] > 0 for t in a["throws"])


def _held(a) -> list:
    """The shipped atlas's throws that keep their subset at every timestep of the ladder."""
    return [t for t in a["throws"] if all(x["kept"] for x in t["ladder"])]


def test_throws_that_hold_at_three_timesteps_replay_their_subset():
    """A throw whose subset holds at h = 1, 0.5 and 0.25 ms does not hang on one floating-point path:
    replayed (h = 1 ms, a fresh lane), it knocks down its subset; the most and the least pins of them."""
    a = throwfile.load_atlas(foul_atlas.SHIPPED)
    held = sorted(_held(a), key=lambda t: len(t["outcome"]["down"]))
    assert len(held) >= 5
    for t in (held[0], held[len(held) // 2], held[-1]):
        assert throwfile.replay(t).down == t["outcome"]["down"], t["delivery"]


def test_a_throw_of_an_earlier_scene_is_refused_in_one_line(tmp_path):
    """Throws of lane-1 (issue 22's soft friction), lane-2 (the pins before the carry fit) and lane-3 (the
    pin deck at 0.2) do not replay on today's scene: nbst says so in one line, naming what the scene was,
    rather than reporting a different outcome."""
    a = throwfile.load_atlas(foul_atlas.SHIPPED)
    t = {k: v for k, v in a["throws"][0].items() if k != "scene"}  # a file without a scene is lane-1's
    with pytest.raises(throwfile.ThrowFileError) as e:
        throwfile.replay(t)
    assert "lane-1" in str(e.value) and lane.SCENE in str(e.value) and "\n" not in str(e.value)
    f = tmp_path / "old.json"
    f.write_text(throwfile.dumps(t))
    p = _nbst("bowl", "replay", str(f))
    assert p.returncode == 2 and p.stderr.count("\n") == 1 and "lane-1" in p.stderr and "Traceback" not in p.stderr
    with pytest.raises(throwfile.ThrowFileError) as e:
        throwfile.replay({**t, "scene": "lane-2"})
    assert "lane-2" in str(e.value) and "carry fit" in str(e.value) and "\n" not in str(e.value)
    with pytest.raises(throwfile.ThrowFileError) as e:  # lane-3: the fitted pins on a pin deck at 0.2
        throwfile.replay({**t, "scene": "lane-3"})
    assert "lane-3" in str(e.value) and "pin deck at friction 0.2" in str(e.value) and "carry fit" not in str(e.value)


def _nbst(*argv):
    import subprocess
    import sys

    return subprocess.run([sys.executable, "-m", "nbst.cli", *argv], capture_output=True, text=True, timeout=600)


def test_cli_solve_from_the_foul_line_answers_from_the_atlas_with_a_probability(tmp_path):
    """A request the shipped atlas (of this scene) holds is answered with its throw, no search: the
    probability's frames, the ladder's and the written throw's alone; the file replays."""
    a = throwfile.load_atlas(foul_atlas.SHIPPED)
    t = _held(a)[0]
    down = ",".join(map(str, t["outcome"]["down"]))
    out = tmp_path / "throw.json"
    p = _nbst("bowl", "solve", "--foul-line", "--down", down, "-o", str(out), "--samples", "6", "--seed", "2",
              "--jobs", "1", "--max-rollouts", "48")
    assert p.returncode == 0, p.stderr
    assert "the shipped foul-line atlas's throw" in p.stderr
    assert f"; {6 + len(frame.LADDER) + 1} frames in" in p.stderr  # no search frame
    d = throwfile.load(out)
    assert d["scene"] == lane.SCENE and d["outcome"]["down"] == t["outcome"]["down"]
    assert d["delivery"] == t["delivery"]
    assert d["probability"]["n"] == 6 and d["probability"]["want"]["down"] == t["outcome"]["down"]
    assert [x["timestep"] for x in d["ladder"]] == list(frame.LADDER)
    assert throwfile.replay(d).down == d["outcome"]["down"]


def test_cli_refuses_5m_flags_with_the_foul_line_in_one_line(tmp_path):
    p = _nbst("bowl", "solve", "--foul-line", "--down", "1", "-o", str(tmp_path / "x.json"), "--no-robustness")
    assert p.returncode == 2 and p.stderr.count("\n") == 1 and "--no-robustness" in p.stderr
    assert "Traceback" not in p.stderr


def test_cli_atlas_refuses_a_hostile_checkpoint_in_one_line(tmp_path):
    (tmp_path / "archive.json").write_text(json.dumps({"format": foul_atlas.ARCHIVE_FORMAT, "version": 1,
                                                       "keys": [*foul_atlas.KEYS, "hand"], "rollouts": 3,
                                                       "elites": {"7": [1e308] * 7}}))
    p = _nbst("bowl", "atlas", "--foul-line", "--out-dir", str(tmp_path), "--max-rollouts", "0")
    assert p.returncode == 2 and p.stderr.count("\n") == 1 and "elites.7" in p.stderr
    assert "Traceback" not in p.stderr


def test_robust_strike_starts_include_throws_that_strike_without_noise(runner):
    """--robust for a strike also starts from the strike line and the pocket cell: each must
    strike without noise (a start that misses could never be the pick)."""
    from nbst.cli.bowl.foul import robust_starts
    from nbst.models.bowling.lane import spares

    found = foul_atlas.delivery_of(_point(0.5))
    ten = list(range(1, 11))
    starts = robust_starts(found, ten)
    assert starts[0] is found and len(starts) == 3
    for d in starts[1:]:
        r = runner.one(d)
        assert r.down == ten, (d, r.leave)  # counted when the pins settle or at the sweep
        # aimed at the pocket: the ball enters within a board of 17.5 (the published pocket)
        assert abs(r.board_at_pins - spares.POCKET_PEAK[0]) < 1.0
    assert robust_starts(found, [10]) == [found]  # any other outcome: the throw found alone


@pytest.mark.slow
def test_cli_atlas_from_another_scenes_atlas_throws_its_deliveries_again_with_a_bowlers_noise(tmp_path):
    """``bowl atlas --foul-line --from`` an atlas of another lane scene: each of its deliveries is
    thrown once on this scene and archived by what it knocks down here (not by the file's outcome);
    ``--bowler`` gives the probabilities the profile's noise, and the atlas records both; a resumed run
    does not throw them again."""
    from nbst.models.bowling.lane import profiles

    a = throwfile.load_atlas(foul_atlas.SHIPPED)
    old = {**a, "scene": "lane-2", "throws": [{**t, "scene": "lane-2"} for t in a["throws"][:2]]}
    src = tmp_path / "old.json"
    src.write_text(throwfile.dumps(old))
    out = tmp_path / "run"
    argv = ("bowl", "atlas", "--foul-line", "--out-dir", str(out), "--from", str(src), "--max-rollouts", "0",
            "--samples", "2", "--seed", "3", "--jobs", "1", "--bowler", "pro", "-q")
    p = _nbst(*argv)
    assert p.returncode == 0, p.stderr
    arch = foul_atlas.archive_from_doc(json.loads((out / "archive.json").read_text()), "archive.json")
    got = throwfile.load_atlas(out / "foul_atlas.json")
    assert got["scene"] == lane.SCENE and got["bowler"] == "pro"
    assert noise.Noise(**got["noise"]) == profiles.profile("pro").noise != noise.DEFAULT
    ds = [lane.Delivery(**t["delivery"]) for t in old["throws"]]
    with frame.FrameRunner(foul_atlas.OIL, jobs=1) as R:
        here = [pinfall.mask_from_pins(r.down) for r in R.map(ds)]
    first = {m: d for m, d in reversed(list(zip(here, ds))) if m}
    assert first  # keyed by what they knock down on this scene, the first throw of a subset its elite
    for m, d in first.items():
        assert np.array_equal(arch.elite[m], foul_atlas.point_of(d))
    for t in got["throws"]:
        assert t["probability"]["n"] == 2 and noise.Noise(**t["probability"]["noise"]) == profiles.profile("pro").noise
    n = arch.rollouts
    assert n >= 2
    p = _nbst(*argv)  # resumed: the checkpoint holds them; nothing is thrown again
    assert p.returncode == 0, p.stderr
    again = foul_atlas.archive_from_doc(json.loads((out / "archive.json").read_text()), "archive.json")
    assert again.rollouts == n
