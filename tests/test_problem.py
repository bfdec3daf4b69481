"""The problem model refuses bad input with one error naming file, field and reason."""
import copy
import json
import os
from pathlib import Path

import numpy as np
import pytest

from nbst import ProblemError, builtin_names, load_problem, load_solution
from nbst.problem import problem_from_dict
from nbst.solution import make_solution, save_solution

SHARED = Path(__file__).resolve().parents[1].parent / "shared" / "problems"
GOOD = {
    "name": "two",
    "box": [100.0, 80.0],
    "t_final": 2.0,
    "target_radius": 10.0,
    "disks": [
        {"start": [20.0, 20.0], "target": [80.0, 60.0], "radius": 5.0},
        {"start": [50.0, 40.0], "target": [30.0, 30.0], "radius": 5.0, "cueable": False, "mass": 2.0},
    ],
}


def write(tmp_path, obj, name="p.json"):
    f = tmp_path / name
    f.write_text(obj if isinstance(obj, str) else json.dumps(obj))
    return f


def bad(tmp_path, mutate):
    d = copy.deepcopy(GOOD)
    mutate(d)
    return load_problem(write(tmp_path, d))


def expect(tmp_path, mutate, field, reason):
    with pytest.raises(ProblemError) as ei:
        bad(tmp_path, mutate)
    e = ei.value
    assert e.field == field
    assert reason in e.reason
    assert str(tmp_path / "p.json") in str(e)  # names the file
    assert "\n" not in str(e)


def test_builtins_ship_unchanged_and_load():
    assert builtin_names() == ["diamond-s14", "diamond-s14-tiny", "over5"]
    import nbst.problems
    here = Path(nbst.problems.__file__).parent
    for name in builtin_names():
        if SHARED.is_dir():
            assert (here / f"{name}.json").read_bytes() == (SHARED / f"{name}.json").read_bytes()
        p = load_problem(name)
        assert p.name == name and p.box == (800.0, 800.0) and p.t_final == 5.0 and p.target_radius == 75.0
    p = load_problem("over5")
    assert p.n == 5 and p.cueable.tolist() == [True, True, False, False, False]
    assert np.all(p.mass == 1.0)


def test_load_by_path_and_defaults(tmp_path):
    p = load_problem(write(tmp_path, GOOD))
    assert p.n == 2 and p.cueable.tolist() == [True, False] and p.mass.tolist() == [1.0, 2.0]
    assert p.to_dict()["disks"][1]["mass"] == 2.0
    assert problem_from_dict(p.to_dict()).start.tolist() == p.start.tolist()
    with pytest.raises(ValueError):
        p.start[0, 0] = 1.0  # read-only


def test_unreadable_file(tmp_path):
    with pytest.raises(ProblemError, match="no such file"):
        load_problem(tmp_path / "missing.json")
    with pytest.raises(ProblemError, match="is a directory"):
        load_problem(tmp_path)
    f = write(tmp_path, GOOD)
    if os.geteuid() != 0:  # root reads anything
        f.chmod(0)
        with pytest.raises(ProblemError, match="permission denied"):
            load_problem(f)
    (tmp_path / "bin.json").write_bytes(b"\xff\xfe\x00")
    with pytest.raises(ProblemError, match="not a text file"):
        load_problem(tmp_path / "bin.json")


def test_not_json(tmp_path):
    with pytest.raises(ProblemError, match=r"not valid JSON: .* line 1 column"):
        load_problem(write(tmp_path, "{box: [1, 2]"))
    with pytest.raises(ProblemError, match="must be a JSON object"):
        load_problem(write(tmp_path, "[1, 2]"))


def test_wrong_types(tmp_path):
    expect(tmp_path, lambda d: d.update(t_final="5"), "t_final", "must be a number")
    expect(tmp_path, lambda d: d.update(box=[100.0]), "box", "list of 2 numbers")
    expect(tmp_path, lambda d: d["disks"][1].update(radius=True), "disks[1].radius", "must be a number")
    expect(tmp_path, lambda d: d["disks"][0].update(cueable="yes"), "disks[0].cueable", "true or false")
    expect(tmp_path, lambda d: d["disks"][1].update(start=[1, "a"]), "disks[1].start[1]", "must be a number")
    expect(tmp_path, lambda d: d.update(disks={"a": 1}), "disks", "must be a list")
    expect(tmp_path, lambda d: d["disks"].__setitem__(0, 3), "disks[0]", "must be a JSON object")
    expect(tmp_path, lambda d: d.update(name=7), "name", "must be a string")


def test_missing_fields(tmp_path):
    expect(tmp_path, lambda d: d.pop("box"), "box", "missing")
    expect(tmp_path, lambda d: d.pop("target_radius"), "target_radius", "missing")
    expect(tmp_path, lambda d: d["disks"][1].pop("radius"), "disks[1].radius", "missing")
    expect(tmp_path, lambda d: d["disks"][0].pop("target"), "disks[0].target", "missing")


def test_nan_and_inf(tmp_path):
    # Python's json reads NaN and Infinity literals; they must not get through
    text = json.dumps(GOOD).replace('"t_final": 2.0', '"t_final": NaN')
    with pytest.raises(ProblemError, match="must be finite") as ei:
        load_problem(write(tmp_path, text))
    assert ei.value.field == "t_final"
    text = json.dumps(GOOD).replace('"radius": 5.0, "cueable"', '"radius": Infinity, "cueable"')
    with pytest.raises(ProblemError, match="must be finite") as ei:
        load_problem(write(tmp_path, text))
    assert ei.value.field == "disks[1].radius"


def test_non_positive_sizes(tmp_path):
    expect(tmp_path, lambda d: d.update(box=[100.0, 0.0]), "box", "must be > 0")
    expect(tmp_path, lambda d: d.update(t_final=0), "t_final", "must be > 0")
    expect(tmp_path, lambda d: d.update(target_radius=-1), "target_radius", "must be > 0")
    expect(tmp_path, lambda d: d["disks"][0].update(radius=0), "disks[0].radius", "must be > 0")
    expect(tmp_path, lambda d: d["disks"][1].update(mass=-2), "disks[1].mass", "must be > 0")


def test_outside_the_walls(tmp_path):
    expect(tmp_path, lambda d: d["disks"][0].update(start=[3.0, 40.0]), "disks[0].start", "inside the walls")
    expect(tmp_path, lambda d: d["disks"][1].update(target=[50.0, 77.0]), "disks[1].target", "inside the walls")
    expect(tmp_path, lambda d: d["disks"][1].update(target=[-10.0, 40.0]), "disks[1].target", "inside the walls")


def test_overlapping_starts(tmp_path):
    expect(tmp_path, lambda d: d["disks"][1].update(start=[29.0, 20.0]), "disks[1].start", "overlaps disks[0]")
    # touching is allowed
    d = copy.deepcopy(GOOD)
    d["disks"][1]["start"] = [30.0, 20.0]
    assert load_problem(write(tmp_path, d)).n == 2


def test_no_cueable_disk(tmp_path):
    expect(tmp_path, lambda d: d["disks"][0].update(cueable=False), "disks", "no disk is cueable")
    expect(tmp_path, lambda d: d.update(disks=[]), "disks", "at least one disk")


def test_unknown_builtin_suggests_close_names():
    with pytest.raises(ProblemError, match=r"did you mean diamond-s14") as ei:
        load_problem("diamond-s41")
    assert "built-ins: diamond-s14, diamond-s14-tiny, over5" in str(ei.value)
    with pytest.raises(ProblemError, match="no such file"):
        load_problem("nothere/x.json")


# --------------------------------------------------------------------------- solutions

def test_solution_roundtrip_and_extra_keys(tmp_path):
    p = load_problem("over5")
    v = np.zeros((5, 2))
    v[0] = [10, -3.5]
    sol = make_solution(p, v, seed=3, cost=1.5)
    save_solution(tmp_path / "s.json", sol)
    back = load_solution(tmp_path / "s.json", p)
    assert np.array_equal(back.velocities, v)
    assert back.meta["seed"] == 3 and back.problem == "over5"
    assert json.loads((tmp_path / "s.json").read_text())["schema_version"] == 1
    old = os.umask(0o022)
    try:
        save_solution(tmp_path / "s2.json", sol)
    finally:
        os.umask(old)
    assert (tmp_path / "s2.json").stat().st_mode & 0o777 == 0o644  # not mkstemp's 0600
    assert not list(tmp_path.glob(".*.tmp"))


def test_solution_errors(tmp_path):
    p = load_problem("over5")
    f = write(tmp_path, {"velocities": [[0, 0]] * 4}, "s.json")
    with pytest.raises(ProblemError, match="has 4 entries but problem 'over5' has 5 disks") as ei:
        load_solution(f, p)
    assert ei.value.field == "velocities" and str(f) in str(ei.value)
    f = write(tmp_path, {"velocities": [[1, 0], [0, 0], [0, 2], [0, 0], [0, 0]]}, "s.json")
    with pytest.raises(ProblemError, match="noncueable") as ei:
        load_solution(f, p)
    assert ei.value.field == "velocities[2]"
    f = write(tmp_path, '{"velocities": [[1, 0], [NaN, 0], [0, 0], [0, 0], [0, 0]]}', "s.json")
    with pytest.raises(ProblemError, match="finite") as ei:
        load_solution(f, p)
    assert ei.value.field == "velocities[1][0]"
    f = write(tmp_path, {"problem": "diamond-s14", "velocities": [[0, 0]] * 5}, "s.json")
    with pytest.raises(ProblemError, match="is for problem 'diamond-s14'"):
        load_solution(f, p)
    f = write(tmp_path, {"cost": 0}, "s.json")
    with pytest.raises(ProblemError, match="missing") as ei:
        load_solution(f, p)
    assert ei.value.field == "velocities"


# --------------------------------------------------------------------------- many disks (issue 35)

def _grid_problem(n: int, *, full: bool = False, k: int = 317) -> dict:
    """n disks of radius 15 on a 40-unit grid, k a row, written as minimally as the format allows
    (or with mass and cueable): the shape of the largest problems the README promises."""
    disks = []
    for m in range(n):
        x, y = 20.0 + 40.0 * (m % k), 20.0 + 40.0 * (m // k)
        d = {"start": [x, y], "target": [x, y], "radius": 15}
        if full:
            d.update(mass=1.0, cueable=True)
        disks.append(d)
    return {"box": [40.0 * k + 40.0, 40.0 * (n // k + 2)], "t_final": 1, "target_radius": 10, "disks": disks}


@pytest.mark.parametrize("full", [False, pytest.param(True, marks=pytest.mark.slow)])
def test_the_promised_100000_disks_load(tmp_path, full):
    """README: problems of up to 100,000 disks load. The JSON value cap refused a minimal
    100,000-disk file (11 values a disk) before; now both forms are read."""
    from nbst.domain import MAX_DISKS

    f = tmp_path / "big.json"
    f.write_text(json.dumps(_grid_problem(MAX_DISKS, full=full), separators=(",", ":")))
    assert load_problem(f).n == MAX_DISKS


def test_an_overlap_in_a_90000_disk_problem_is_found_on_the_grid():
    """The last disk of 90,000 overlapping an early one: named (the old check compared every pair,
    O(N^2), and was still running after 60 s)."""
    d = _grid_problem(90_000)
    d["disks"][-1]["start"] = [d["disks"][5]["start"][0] + 1.0, d["disks"][5]["start"][1]]
    d["disks"][-1]["target"] = d["disks"][-1]["start"]
    with pytest.raises(ProblemError, match=r"overlaps disks\[5\]") as e:
        problem_from_dict(d)
    assert e.value.field == "disks[89999].start"
    many = _grid_problem(90_000)
    for disk in many["disks"]:  # every disk on one spot: the first dense cell says it at once
        disk["start"] = disk["target"] = [100.0, 100.0]
    with pytest.raises(ProblemError, match="overlaps"):
        problem_from_dict(many)


def test_the_grid_finds_the_pair_the_pairwise_check_finds():
    """first_overlap against the plain O(N^2) rule (the least i, then j), on random layouts of
    equal, similar and very different radii (several radius classes, big disks beside small)."""
    from nbst.overlap import first_overlap

    def pairwise(start, radius, tol=1e-9):
        for i in range(len(radius)):
            d2 = ((start[i + 1:] - start[i]) ** 2).sum(axis=1)
            bad = np.nonzero(d2 < ((radius[i + 1:] + radius[i]) * (1 - tol)) ** 2)[0]
            if bad.size:
                return i, i + 1 + int(bad[0])
        return None

    rng = np.random.default_rng(7)
    seen = set()
    for trial in range(300):
        n = int(rng.integers(2, 60))
        radius = [np.full(n, 10.0), rng.uniform(1, 30, n), np.exp(rng.uniform(0, 6, n))][trial % 3]
        start = rng.uniform(0, 500, (n, 2))
        got = first_overlap(start, radius)
        assert got == pairwise(start, radius), trial
        seen.add(got is None)
    assert seen == {True, False}  # both outcomes were tried
    touching = np.array([[0.0, 0.0], [20.0, 0.0]])
    assert first_overlap(touching, np.array([10.0, 10.0])) is None  # touching starts are allowed
