"""The judge (nbst.scene.judge) on synthetic trajectories: each fate met or not, its graded cost as
an exact geometric fact (within 1e-12 m or rad), the signature one bit per body with fates."""
import math

import numpy as np
import pytest

from nbst.scene.fates import AT_REST_SPEED, AT_REST_SPIN, STILL_DISTANCE, Fate, Fates, Region
from nbst.scene.judge import Recording, judge, judge_body, rotate, signature_text

TOL = 1e-12
T = np.linspace(0.0, 1.0, 11)
Q0 = np.array([1.0, 0, 0, 0])
Z = np.zeros(3)


def line(a, b):
    """(11, 3) a straight path from a to b."""
    return np.asarray(a, float) + np.outer(T, np.asarray(b, float) - np.asarray(a, float))


def one(fate, path, quat=Q0, lin=Z, ang=Z, touches=None):
    return judge_body(fate, T, path, quat, lin, ang, touches or {})


def test_rest_in_a_ball_and_a_box():
    ball = Region(center=(1.0, 0.0, 0.0), radius=0.1)
    v = one(Fate("b", rest_in=ball), line([0, 0, 0], [1.05, 0, 0]))
    assert v.met and v.cost == 0.0
    v = one(Fate("b", rest_in=ball), line([0, 0, 0], [1.5, 0, 0]))
    assert not v.met and abs(v.cost - 0.4) < TOL
    box = Region(lo=(0.0, 0.0, 0.0), hi=(1.0, 1.0, 1.0))
    v = one(Fate("b", rest_in=box), line([5, 5, 5], [2, 3, 0.5]))  # 1 m out in x, 2 m in y
    assert not v.met and abs(v.cost - math.sqrt(5)) < TOL


def test_at_takes_the_recorded_time_nearest_t():
    r = Region(center=(0.5, 0.0, 0.0), radius=0.01)
    path = line([0, 0, 0], [1, 0, 0])
    assert one(Fate("b", at=((0.5, r),)), path).met
    v = one(Fate("b", at=((0.52, r), (0.7, r))), path)  # nearest 0.5: inside; at 0.7: 0.19 m out
    assert not v.met and abs(v.cost - 0.19) < TOL


def test_through_counts_regions_in_order_only():
    a, b = Region(center=(0.2, 0.0, 0.0), radius=0.05), Region(center=(0.8, 0.0, 0.0), radius=0.05)
    forward, backward = line([0, 0, 0], [1, 0, 0]), line([1, 0, 0], [0, 0, 0])
    assert one(Fate("b", through=(a, b)), forward).met
    v = one(Fate("b", through=(a, b)), backward)  # b first, then a: a passed at 0.8 s (x = 0.2), b never after: 0.6 - 0.05 m
    assert not v.met and v.fates[0].happened == "passed 1 of 2 in order" and abs(v.cost - 0.55) < 1e-9


def test_up_is_the_body_axis_turned_by_the_final_orientation():
    half = math.radians(30) / 2  # 30 deg about x
    q = np.array([math.cos(half), math.sin(half), 0, 0])
    assert np.allclose(rotate(q, np.array([0, 0, 1.0])), [0, -0.5, math.sqrt(3) / 2], atol=TOL)
    f = Fate("b", up=((0.0, 0.0, 1.0), 31.0))
    assert one(f, line(Z, Z), quat=q).met
    v = one(Fate("b", up=((0.0, 0.0, 1.0), 20.0)), line(Z, Z), quat=q)
    assert not v.met and abs(v.cost - math.radians(10)) < 1e-9
    v = one(Fate("b", up=((0.0, 1.0, 0.0), 20.0)), line(Z, Z), quat=q)  # y turned to (0, .87, .5): 60 deg off
    assert not v.met and abs(v.cost - math.radians(40)) < 1e-9


def test_hits_in_order_never_hits_and_their_counts():
    f = Fate("b", hits=("p", "q", "r"))
    assert one(f, line(Z, Z), touches={"p": 0.1, "q": 0.2, "r": 0.3}).met
    v = one(f, line(Z, Z), touches={"p": 0.3, "q": 0.2})  # r missing, p-q out of order
    assert not v.met and v.cost == 2.0
    v = one(Fate("b", never_hits=("p", "q")), line(Z, Z), touches={"q": 0.5})
    assert not v.met and v.cost == 1.0
    assert one(Fate("b", never_hits=("p",)), line(Z, Z), touches={"q": 0.5}).met


def test_at_rest_and_still_at_their_stated_thresholds():
    f = Fate("b", at_rest=True)
    assert one(f, line(Z, Z), lin=np.array([AT_REST_SPEED, 0, 0]), ang=np.array([0, 0, AT_REST_SPIN])).met
    v = one(f, line(Z, Z), lin=np.array([AT_REST_SPEED + 0.5, 0, 0]), ang=np.array([0, 0, AT_REST_SPIN + 1.0]))
    assert not v.met and abs(v.cost - 0.6) < TOL
    assert one(Fate("b", still=True), line(Z, [STILL_DISTANCE, 0, 0])).met
    v = one(Fate("b", still=True), line(Z, [0, 0.03, 0]))
    assert not v.met and abs(v.cost - 0.02) < TOL


def test_the_signature_has_one_bit_per_body_with_fates():
    fates = Fates(source="mem", scene=None, keyframe=None, timestep=None, duration=1.0, controls=(),  # type: ignore[arg-type]
                  fates=(Fate("a", rest_in=Region(center=(1.0, 0.0, 0.0), radius=0.1)), Fate("b", still=True),
                         Fate("c", never_hits=("a",))))
    pos = np.stack([line(Z, [1, 0, 0]), line(Z, [0, 1, 0]), line(Z, Z)], axis=1)
    rec = Recording(times=T, pos=pos, quat=np.tile(Q0, (3, 1)), linvel=np.zeros((3, 3)), angvel=np.zeros((3, 3)),
                    touches=({}, {}, {"a": 0.4}))
    j = judge(fates, rec)
    assert j.signature == (True, False, False) and j.order == 1 and not j.met
    assert signature_text(j.signature) == "100" and abs(j.cost - (1 - STILL_DISTANCE + 1)) < TOL
    assert j.to_dict()["bodies"]["c"]["fates"]["never_hits"]["happened"] == "touched a"


@pytest.mark.parametrize("p, d", [((0.5, 0.5, 0.5), 0.0), ((1.0, 1.0, 1.0), 0.0), ((2.0, 0.5, 0.5), 1.0),
                                  ((-3.0, -4.0, 0.5), 5.0)])
def test_box_distance_is_exact(p, d):
    assert abs(float(Region(lo=(0.0, 0.0, 0.0), hi=(1.0, 1.0, 1.0)).distance(np.array(p))) - d) < TOL


def test_a_millimetre_scene_reads_in_its_own_digits():
    """A bead 2 cm away ending 0.4 mm outside its 7 mm box: what happened is readable at that scale
    (three decimals of a metre would say 0.000 m from the region and round the ends to whole mm)."""
    box = Region(lo=(0.0165, -0.0035, 0.0), hi=(0.0235, 0.0035, 0.005))
    v = one(Fate("bead", rest_in=box), line([0, 0, 0.0025], [0.0239, 0.0012, 0.0025]))
    assert not v.met and abs(v.cost - 0.0004) < TOL
    assert v.fates[0].happened == "ends at (0.0239, 0.0012, 0.0025) m, 0.0004 m from the region"
    v = one(Fate("pin", still=True), line(Z, [0.0019, 0, 0]))
    assert v.met and v.fates[0].happened == "moved at most 0.0019 m"


def test_a_never_hits_touch_at_the_start_says_so():
    """A body that starts resting on what it must never hit can not meet the fate whatever its velocity:
    the verdict says the touch was there at the start (a new user's bead on the table), not just 'touched'."""
    v = one(Fate("bead", never_hits=("table", "wall")), line(Z, Z), touches={"table": 0.0, "wall": 0.5})
    assert not v.met and v.cost == 2.0
    assert v.fates[0].happened == "touched table (already touching at the start), wall"


def test_a_hits_name_never_touched_costs_1_plus_its_nearness_and_a_touched_one_nothing():
    """``hits`` of a name never touched: 1 plus its least gap over its gap at the start (here 0.1 m
    of 0.5 m: 1.2; 0.4 of 0.5: 1.8), so a near miss is cheaper than a far one; with no nearness
    recorded (or none for that name, or a start already touching) it is 1, flat; a name touched
    adds nothing, whatever its nearness says."""
    fate = Fate("b", hits=("x", "y"))
    path = line(Z, Z)

    def cost(touches, near):
        return judge_body(fate, T, path, Q0, Z, Z, touches, near).cost

    assert abs(cost({"x": 0.1}, {"y": (0.1, 0.5)}) - 1.2) < TOL
    assert abs(cost({"x": 0.1}, {"y": (0.4, 0.5)}) - 1.8) < TOL
    assert abs(cost({"x": 0.1}, {"x": (0.3, 0.5)}) - 1.0) < TOL  # y has no nearness: flat
    assert abs(cost({"x": 0.1}, {"y": (0.0, 0.0)}) - 1.0) < TOL  # touching at the start: flat
    assert abs(cost({}, {"x": (0.1, 0.5), "y": (0.0, 0.5)}) - 2.2) < TOL
    assert cost({"x": 0.1, "y": 0.2}, {"x": (0.3, 0.5), "y": (0.3, 0.5)}) == 0.0
    assert abs(one(fate, path, touches={"x": 0.1}).cost - 1.0) < TOL  # nothing recorded: flat
