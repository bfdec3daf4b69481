"""The robust pick's stages (models/crash/robust.py): the race among crashes that meet the script,
on common copies, and the gathering of such crashes by short searches."""
import json

import numpy as np
import pytest

from nbst.models.crash import robust, run, script, slack, space
from nbst.models.mjsearch.probability import normal_draws


class _Windows:
    """Members are numbers; a noisy copy is the number plus a standard normal draw (copy i the same
    draw for every member: common random numbers); it meets the 'script' inside [-1, 1]."""

    def __init__(self):
        self.ran = 0

    def noisy(self, x, m, seed):
        return list(float(x) + normal_draws(seed, m, 1)[:, 0])

    def run(self, copies):
        self.ran += len(copies)
        return list(copies)

    def judge(self, r):
        return abs(r) <= 1.0, -abs(r), "in" if abs(r) <= 1.0 else "out"


def test_the_race_ranks_the_member_met_most_often_first_within_its_budget():
    """Members at 3, 2.5, 0.2 (P = 0.58 of meeting [-1, 1] under unit noise), 1.5 and 2: the one at
    0.2 wins on paired copies; the race runs no more than its budget."""
    P = _Windows()
    members = [3.0, 2.5, 0.2, 1.5, 2.0]
    order, rows, used = robust._race(P, members, budget=200, seed=3)
    assert order[0] == 2 and used == P.ran <= 200
    assert [r[0] for r in rows] == list(range(5)) and rows[2][2] >= rows[0][2]  # the winner ran the most copies
    assert rows[2][1] > rows[0][1]  # the winner met more of its copies than the member at 3 did
    assert robust._race(P, members, budget=200, seed=3) == (order, rows, used)  # the same seed, the same race


def test_a_race_of_one_runs_nothing():
    P = _Windows()
    assert robust._race(P, [0.0], budget=100, seed=1) == ([0], [[0, 0, 0]], 0) and P.ran == 0


#: A short two-car crossing (tests/test_crash_run.py's): A eastbound meets B northbound.
SHORT = {
    "kind": "nbst-crash-script", "name": "short",
    "road": {"layout": "intersection", "width": 7, "length": 80},
    "duration": 2.5,
    "vehicles": [
        {"name": "A", "type": "sedan", "start": {"x": -22, "y": -1.75, "heading": 0}, "speed": [45, 55],
         "driver": {"aim": {"x": [0, 4], "y": -1.75}, "arrive": [1.5, 1.8], "after_impact": ["brake", "coast"]},
         "fate": {"hits": ["B"]}},
        {"name": "B", "type": "suv", "start": {"x": 1.75, "y": -22, "heading": 90}, "speed": [45, 55],
         "driver": {"aim": {"x": 1.75, "y": [-2, 2]}, "arrive": [1.5, 1.8]}, "fate": {"hits": ["A"]}},
    ],
}


@pytest.fixture
def short_problem():
    """(space, the middle of its ranges as intents, the robust problem about them) of the short
    crossing, its runner closed after the test."""
    s = script.script_from_dict(json.loads(json.dumps(SHORT)), source="short")
    S = space.space_of(s)
    R = run.CrashRunner(s, jobs=1)
    try:
        start = S.intents(np.full((1, S.dim), 0.5))[0]
        yield S, start, robust.RobustCrashProblem(S, R, R.xml, ref=start)
    finally:
        R.close()


@pytest.mark.slow
def test_gathering_finds_other_crashes_that_meet_the_script_at_every_timestep(short_problem):
    """A short search from a derived seed brings crashes other than the start, each meeting the
    script at 2, 1 and 0.5 ms, within the rollouts it was given."""
    S, start, P = short_problem
    members, used, runs = robust._gather(P, start, 4 * run.BATCH, seed=2, ladder=True)
    assert runs == 1 and 0 < used <= 4 * run.BATCH and len(members) >= 2 and members[0][1] == "start"
    for cand, origin in members[1:]:
        assert origin != "start" and not np.allclose(np.nan_to_num(cand), np.nan_to_num(start))
        rows, holds, _ = P.ladder(cand)
        assert holds and rows[0][2]  # met at 2 ms and kept at 1 and 0.5 ms


def _tbone_outcome(heading_deg=140.0, rest=(5.0, 10.0), moving=False, impact_kmh=52.5, dv_kmh=25.0):
    """A t-bone outcome built by hand: A (the sedan) hit B (the SUV) at ``impact_kmh``; B's
    delta-v ``dv_kmh``, at rest (unless ``moving``) at ``rest`` facing ``heading_deg``, upright."""
    from nbst.models.crash.outcome import Outcome, VehicleOutcome

    def vo(name, hits, speed, dv, pos, hd):
        return VehicleOutcome(name=name, hits=hits, impact_speed=speed / 3.6, impact_heading=0.0,
                              impact_pos=(1.0, -1.75), delta_v=dv / 3.6, rest=(pos[0], pos[1], np.radians(hd)),
                              quarter_turns=0, roll=0.0, attitude="upright", spin=0.0, curb=np.nan,
                              barrier=np.nan, moving=moving and name == "B", end_speed=2.0 if moving else 0.0)

    return Outcome(vehicles=[vo("A", [(1, 3.0)], impact_kmh, 30.0, (8.0, -1.0), 10.0),
                             vo("B", [(0, 3.0)], 50.0, dv_kmh, rest, heading_deg)],
                   contacts=[(0, 1, 3.0, 3.1, np.zeros(3), np.zeros(3))])


@pytest.mark.parametrize("heading, rest, moving, want", [
    (140.0, (5.0, 10.0), False, 1.0),      # every fate in the middle of its tolerance: 1
    (155.0, (5.0, 10.0), False, 0.5),      # heading half-way to its edge (140 +- 30): 0.5
    (170.0, (5.0, 10.0), False, 0.0),      # at the heading's edge: 0
    (185.0, (5.0, 10.0), False, -0.5),     # beyond it by half its tolerance
    (140.0, (6.5, 10.0), False, 0.5),      # 1.5 m off the rest region's centre (radius 3)
    (140.0, (5.0, 10.0), True, -0.25),     # still moving: no rest, whatever the pose
])
def test_the_slack_is_the_worst_fate_in_half_widths_of_its_tolerance(heading, rest, moving, want):
    """The worst fate's slack: the impact speed (45-60 km/h) and delta-v (15-35) sit at their
    bands' middles, so B's heading or rest decides; it agrees with the judge's verdict (met
    exactly when the slack is >= 0)."""
    from nbst.models.crash.outcome import judge

    sc = script.load_script("t-bone")
    o = judge(_tbone_outcome(heading, rest, moving), sc)
    s = slack.slack(o, sc)
    assert s == pytest.approx(want, abs=1e-9)
    assert o.solved == (s >= 0.0)
    assert slack.soft(o, sc) == pytest.approx(1 / (1 + np.exp(-want / slack.SOFT_TEMP)), abs=1e-12)


def test_a_missed_contact_or_a_band_missed_is_a_negative_slack():
    from nbst.models.crash.outcome import judge

    sc = script.load_script("t-bone")
    o = _tbone_outcome(impact_kmh=67.5)  # 7.5 km/h above the 45-60 band: one half-width outside
    assert slack.slack(judge(o, sc), sc) == pytest.approx(-1.0, abs=1e-9)
    o = _tbone_outcome(impact_kmh=56.25)
    assert slack.slack(judge(o, sc), sc) == pytest.approx(0.5, abs=1e-9)
    o = _tbone_outcome()
    o.vehicles[1].hits = []
    assert slack.slack(judge(o, sc), sc) == -1.0


@pytest.mark.slow
def test_the_soft_climb_keeps_its_budget_and_the_ranges_and_repeats_from_its_seed(monkeypatch, short_problem):
    """A small soft climb on the short crossing (4 copies per candidate, 4 per generation, an
    8-copy confirming screen): it runs no more than its budget, its pick sits inside the script's
    ranges with a valid after-impact choice, meets its screen at least as often as the start,
    and the same seed gives the same pick."""
    monkeypatch.setattr(slack, "SOFT_COPIES", 4)
    monkeypatch.setattr(slack, "SOFT_POP", 4)
    monkeypatch.setattr(slack, "SOFT_CONFIRM", 8)
    S, start, P = short_problem
    pick, rec = slack.soft_climb(P, start, 2 * 16 + 3 * 8, seed=4)
    assert rec["generations"] == 2 and rec["rollouts"] <= 2 * 16 + 3 * 8
    assert (rec["climbed"], rec["soft_climbed"]) >= (rec["start"], rec["soft_start"])
    for i, f, r in S.coords:
        if hasattr(r, "lo"):
            assert r.lo <= pick[i, f] <= r.hi
        else:
            assert pick[i, f] in (0.0, 1.0)  # brake or coast, the script's choices
    again, rec2 = slack.soft_climb(P, start, 2 * 16 + 3 * 8, seed=4)
    assert np.array_equal(np.nan_to_num(again), np.nan_to_num(pick)) and rec2 == rec


class _Met:
    """An outcome as the probability counts it: met or not, one vehicle."""

    def __init__(self, met):
        self.solved, self.order_ok, self.vehicles = met, True, [None]

    def signature_text(self, n):
        return "1"


def test_a_crash_its_drivers_repeat_in_under_one_take_in_ten_is_marked_and_printed_a_lottery():
    """9 of 100 re-drives: a lottery (the file's probability.lottery, the summary says LOTTERY); 10 of
    100 is not; a file written before the mark (no key) is not called one."""
    from nbst.cli.crash.commands import _p_text

    rare = robust.estimate_of([_Met(k < 9) for k in range(100)], seed=1).to_dict()
    common = robust.estimate_of([_Met(k < 10) for k in range(100)], seed=1).to_dict()
    assert rare["lottery"] is True and common["lottery"] is False and robust.LOTTERY_P == 0.10
    assert "LOTTERY" in _p_text(rare) and "9/100" in _p_text(rare) and "LOTTERY" not in _p_text(common)
    assert "LOTTERY" not in _p_text({k: v for k, v in rare.items() if k != "lottery"})
