"""What a seventh new user, driving the scene search from Python, met (issue 46, docs/results/scene.md,
"Tried by a seventh new user"): each case a test that failed before its fix."""
import json

import pytest

from nbst.cli.scene import ANSWERS
from nbst.errors import InputError, SolveError
from nbst.scene import FatesError, solve
from nbst.scene.api import ANSWERS_MAX
from nbst.scene.scenefile import load_fates

BALL = """<mujoco model="ball">
  <worldbody>
    <geom name="floor" type="plane" size="3 3 0.1"/>
    <body name="ball" pos="0 0 0.05"><freejoint/><geom type="sphere" size="0.05"/></body>
  </worldbody>
</mujoco>
"""
FATES = """{"format": "nbst-fates", "version": 1, "scene": "ball.xml", "duration": 0.5,
 "controls": {"ball": {"linvel": [[0, 1], [0, LO], [0, 0]]}},
 "fates": {"ball": {"rest_in": {"center": [0.2, 0, 0.05], "radius": RADIUS}}}}
"""


@pytest.mark.parametrize("kw, word", [
    ({"ladder": "false"}, "ladder must be True or False"),  # read as truth, it kept the ladder on
    ({"ladder": None}, "ladder must be True or False"),     # read as falsehood, it turned it off
    ({"callback": 5}, "callback must be None or a function"),
    ({"cluster": 123}, "cluster must be None, a Dask scheduler's address"),
    ({"answers": ANSWERS_MAX + 1}, f"answers must be an integer >= 1 and <= {ANSWERS_MAX}"),
])
def test_solve_refuses_a_keyword_of_the_wrong_kind_as_a_solve_error(kw, word):
    with pytest.raises(SolveError, match=word):
        solve(None, "snake-eyes", seed=1, max_rollouts=10, **kw)


def test_the_cli_and_the_library_allow_the_same_answers():
    assert (ANSWERS.lo, ANSWERS.hi) == (1, ANSWERS_MAX)


def _write(tmp_path, lo="1", radius="0.1"):
    (tmp_path / "ball.xml").write_text(BALL)
    p = tmp_path / "f.json"
    p.write_text(FATES.replace("LO", lo).replace("RADIUS", radius))
    return p


@pytest.mark.parametrize("lo, radius, field, why", [
    ("NaN", "0.1", "controls.ball.linvel[1][1]", "NaN is not a finite number"),
    ("1", "-Infinity", "fates.ball.rest_in.radius", "-Infinity is not a finite number"),
    ("1", "1" * 20, "fates.ball.rest_in.radius", "more than 15 digits"),
])
def test_a_number_json_refuses_is_told_by_its_field(tmp_path, lo, radius, field, why):
    p = _write(tmp_path, lo, radius)
    with pytest.raises(FatesError, match=why) as e:
        load_fates(p)
    assert e.value.field == field


def test_a_key_given_twice_is_told_by_the_object_it_is_in(tmp_path):
    p = _write(tmp_path)
    p.write_text(p.read_text().replace('"radius": 0.1', '"radius": 0.1, "radius": 0.2'))
    with pytest.raises(FatesError, match="'radius' appears twice") as e:
        load_fates(p)
    assert e.value.field == "fates.ball.rest_in"


@pytest.mark.parametrize("make", [
    lambda d: d / "missing.json",
    lambda d: (d / "empty.json").write_text("") or d / "empty.json",
    lambda d: d,  # a folder
])
def test_a_fates_file_that_cannot_be_read_is_a_fates_error(tmp_path, make):
    with pytest.raises(FatesError) as e:
        load_fates(make(tmp_path))
    assert isinstance(e.value, InputError) and "\n" not in str(e.value)


def test_a_good_file_still_loads(tmp_path):
    p = _write(tmp_path)
    fates, model = load_fates(p)
    assert [f.body for f in fates.fates] == ["ball"] and model.nbody == 2
    assert json.loads(p.read_text())["duration"] == fates.duration == 0.5


#: two balls that must meet in mid-air, then each land in a box of its own (the seventh user's scene, smaller)
TWO = """<mujoco model="two">
  <option timestep="0.002"/>
  <worldbody>
    <geom name="floor" type="plane" size="3 3 0.1"/>
    <geom name="boxA" type="box" pos="-1 0.8 0.01" size="0.25 0.25 0.01"/>
    <geom name="boxB" type="box" pos="1 0.8 0.01" size="0.25 0.25 0.01"/>
    <body name="red" pos="-1.2 -0.5 0.5"><freejoint/><geom type="sphere" size="0.06" mass="0.2"/></body>
    <body name="blue" pos="1.2 -0.5 0.5"><freejoint/><geom type="sphere" size="0.06" mass="0.2"/></body>
  </worldbody>
</mujoco>
"""
TWO_FATES = {"format": "nbst-fates", "version": 1, "scene": "two.xml", "duration": 1.0,
             "controls": {"red": {"linvel": [[-1, 3], [-1, 3], [1, 5]]}, "blue": {"linvel": [[-3, 1], [-1, 3], [1, 5]]}},
             "fates": {"red": {"hits": ["blue", "boxA"], "rest_in": {"min": [-1.24, 0.56, 0], "max": [-0.76, 1.04, 0.2]}},
                       "blue": {"hits": ["red", "boxB"], "rest_in": {"min": [0.76, 0.56, 0], "max": [1.24, 1.04, 0.2]}}}}


def test_two_bodies_that_must_hit_each_other_are_aimed_at_one_point_at_one_time(tmp_path):
    """Uniform throws of the two balls touch in about 2 % (the seventh user: 58 of 3,000); the search's
    aimed pair must touch in most: its velocities meet the ballistic formula at one point and time."""
    import types

    import numpy as np

    from nbst.scene import search
    from nbst.scene.rollout import SceneSim

    (tmp_path / "two.xml").write_text(TWO)
    (tmp_path / "two.json").write_text(json.dumps(TWO_FATES))
    f, m = load_fates(tmp_path / "two.json")
    sim = SceneSim(f, m)
    sc = search._Scene(sim, 1, ())
    assert sc.meet == [1, 0]
    eng = types.SimpleNamespace(rng=np.random.default_rng(3), population=[])
    xs = []
    for k in range(16):
        u = np.random.default_rng(k).random(len(sc.lo))
        sc._aim_meet(eng.rng, u, 0, 1)
        xs.append(sc.x_full(u))

    def touches(rollouts):
        return sum("blue" in next(v.happened for v in r.judgement.bodies[0].fates if v.fate == "hits") for r in rollouts)

    # the pair is one block of the engine's: a creep or a redraw of one moves both
    assert sc.engine_blocks[0] is sc.engine_blocks[1] and sorted(sc.engine_blocks[0]) == list(range(6))
    touched = touches(sim.run(np.array(xs)))
    uniform = [sc.x_full(np.random.default_rng(100 + k).random(len(sc.lo))) for k in range(16)]
    by_chance = touches(sim.run(np.array(uniform)))
    assert touched >= 12 > by_chance + 8, (touched, by_chance)
