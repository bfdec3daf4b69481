"""Issue 12, inputs: parser limits, the accepted domain (``nbst.domain``), user text,
strict JSON out. Every bad input is a ProblemError (one line, exit 2), never another
exception; everything inside the domain loads and simulates to finite positions."""
import copy
import json
import math
import os

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from nbst import domain as D
from nbst import load_problem
from nbst.cli import main
from nbst.constants import GA_MAX_DISKS, MAX_EVENTS
from nbst.problem import ProblemError, box_crossings, display_name, parse_json, problem_from_dict
from nbst.sim import simulate
from nbst.solution import dumps_strict, make_solution, save_solution, solution_from_dict

from test_problem import GOOD  # noqa: E402 - the same valid two-disk problem


def _strict(text: str):
    """json.loads that refuses NaN / Infinity (what a strict parser does)."""
    def no(c):
        raise ValueError(f"non-standard JSON constant {c}")
    return json.loads(text, parse_constant=no)


def _write(tmp_path, obj, name="p.json"):
    f = tmp_path / name
    f.write_text(obj if isinstance(obj, str) else json.dumps(obj), encoding="utf-8")
    return f


def _refused(tmp_path, obj, capsys=None, *, solution=False):
    """Load obj as a problem (or as an over5 solution) through the CLI: exit 2, one line, no traceback."""
    f = _write(tmp_path, obj)
    argv = ["simulate", "over5", str(f)] if solution else ["simulate", str(f), str(_write(
        tmp_path, {"velocities": [[1.0, 0.0], [0.0, 0.0]]}, "s.json"))]
    rc = main(argv)
    err = capsys.readouterr().err
    assert rc == 2
    assert err.startswith("nbst: error: ") and err.count("\n") == 1, err
    assert "Traceback" not in err
    return err


# --------------------------------------------------------------------------- parser limits

@pytest.mark.parametrize("text, why", [
    ("[" * 100_000 + "]" * 100_000, "nested too deeply"),      # RecursionError in json
    ("[" * (D.MAX_JSON_DEPTH + 1) + "]" * (D.MAX_JSON_DEPTH + 1), "levels deep"),  # parses, but too deep
    ('{"box": [1' + "0" * 400 + ', 8]}', "401 digits"),         # OverflowError in float()
    ('{"box": [1' + "0" * 5000 + ', 8]}', "5001 digits"),       # Python's digit limit (ValueError)
    ('{"box": [-1' + "0" * 500 + ', 8]}', "501 digits"),
])
def test_parser_limits_are_one_line_errors(tmp_path, capsys, text, why):
    with pytest.raises(ProblemError, match=why):
        parse_json(text, "x.json")
    for solution in (False, True):
        assert why in _refused(tmp_path, text, capsys, solution=solution)


def test_big_integers_within_the_digit_limit(tmp_path, capsys):
    # 309..400 digits parse, then cannot become a float: a field error, not OverflowError
    d = copy.deepcopy(GOOD)
    d["t_final"] = 10 ** 350
    with pytest.raises(ProblemError, match="too large") as ei:
        problem_from_dict(d)
    assert ei.value.field == "t_final"
    # integers that are exact floats are fine
    d["t_final"] = 2
    assert problem_from_dict(d).t_final == 2.0


def test_file_size_limit(tmp_path, monkeypatch):
    monkeypatch.setattr(D, "MAX_JSON_BYTES", 100)
    f = _write(tmp_path, GOOD)
    with pytest.raises(ProblemError, match="at most 100 bytes"):
        load_problem(f)


def _measure_load(path) -> tuple[float, int, str]:
    """Seconds, peak resident memory (MB) and the one-line error of load_problem(path) in a fresh process."""
    import subprocess
    import sys

    code = ("import resource, sys, time\nfrom nbst.problem import ProblemError, load_problem\nt = time.perf_counter()\n"
            "try:\n    load_problem(sys.argv[1]); msg = 'accepted'\nexcept ProblemError as e:\n    msg = str(e)\n"
            "hwm = [ln for ln in open('/proc/self/status') if ln.startswith('VmHWM')]\n"
            "mb = int(hwm[0].split()[1]) // 1024 if hwm else resource.getrusage(resource.RUSAGE_SELF).ru_maxrss // 1024\n"
            "print(time.perf_counter() - t, mb, msg)")
    out = subprocess.run([sys.executable, "-c", code, str(path)], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0 and "Traceback" not in out.stderr, out.stderr
    dt, mb, msg = out.stdout.split(" ", 2)
    return float(dt), int(mb), msg.strip()


@pytest.mark.parametrize("unit, count", [
    ("[],", 21_000_000),          # 63 MiB of empty lists: 3.2 GB once parsed, before the value cap
    ("1,", 31_000_000),           # 62 MB of small integers
    ('"abcdefghijklmnopqrstuvwxyz",', 990_000),   # just under the value cap: the heaviest accepted shape
])
def test_a_huge_file_of_any_shape_is_refused_fast_and_small(tmp_path, unit, count):
    f = tmp_path / "huge.json"
    f.write_text("[" + unit * count + "1]")
    _, mb, msg = _measure_load(f)
    assert "JSON values" in msg or "must be a JSON object" in msg, msg
    assert mb < 512, mb  # the bound, whatever the shape (its time: benchmarks/fuzz_inputs.py --huge)


def test_the_value_count_is_checked_before_parsing(monkeypatch):
    monkeypatch.setattr(D, "MAX_JSON_VALUES", 10)
    with pytest.raises(ProblemError, match="more than 10 JSON values"):
        parse_json("[" + "[]," * 10 + "1]", "x.json")
    assert parse_json("[" + "[]," * 4 + "1]", "x.json") == [[]] * 4 + [1]


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs named pipes")
def test_special_files_as_inputs_are_refused_by_stat(tmp_path, capsys):
    fifo = tmp_path / "pipe.json"
    os.mkfifo(fifo)  # opening it for reading would block forever
    sol = _write(tmp_path, {"velocities": [[0.0, 0.0]] * 5}, "s.json")
    for argv, what in ((["simulate", str(fifo), str(sol)], "named pipe"),
                       (["simulate", "over5", str(fifo)], "named pipe"),
                       (["simulate", str(tmp_path), str(sol)], "directory"),
                       (["simulate", "over5", "/dev/zero"], "character device")):
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert what in err and err.count("\n") == 1, err


def test_numeric_flags_have_domains_stated_in_help():
    """Every numeric flag of the core commands, solve, generate, experiment, render, plot and the
    MuJoCo commands is checked by a shared type whose range its --help states."""
    import argparse

    from nbst.cli.args import Bounded, Size
    from nbst.cli.main import build_parser

    def walk(parser, prefix=()):
        for a in parser._actions:
            if isinstance(a, argparse._SubParsersAction):
                for name, sp in a.choices.items():
                    yield from walk(sp, prefix + (name,))
            elif a.option_strings:
                yield prefix, a

    checked = 0
    for prefix, a in walk(build_parser()):
        if prefix and prefix[0] == "bowl":
            continue  # the bowling commands' flags: tests/test_bowling*.py
        assert a.type not in (int, float), f"nbst {' '.join(prefix)} {a.option_strings[0]}: bare {a.type.__name__}"
        if isinstance(a.type, (Bounded, Size)) and a.help != argparse.SUPPRESS:  # hidden old spellings aside
            assert a.type.limits in " ".join(a.help.split()), (prefix, a.option_strings, a.help)
            checked += 1
    assert checked >= 30


@pytest.mark.parametrize("argv", [
    ["solve", "over5", "-o", "x.json", "--seed", "nan"], ["solve", "over5", "-o", "x.json", "--seed", str(2**63)],
    ["solve", "over5", "-o", "x.json", "--max-trials", "9" * 5000], ["solve", "over5", "-o", "x.json", "--jobs", "100000"],
    ["solve", "over5", "-o", "x.json", "--target-cost", "inf"], ["generate", "--planted", "100001", "-o", "x.json"],
    ["generate", "--planted", "2", "--t-final", "nan", "-o", "x.json"], ["render", "over5", "s.json", "-o", "x.png",
                                                                          "--still", "nan"],
    ["render", "over5", "s.json", "-o", "x.mp4", "--fps", "1e9"], ["render", "over5", "s.json", "-o", "x.mp4",
                                                                    "--fps", "-5"],
    ["render", "over5", "s.json", "-o", "x.mp4", "--max-frames", "0"], ["plot", "problem", "over5", "-o", "x.png",
                                                                          "--dpi", "1e9"],
    ["validate", "over5", "s.json", "--unit", "1e300"], ["validate", "over5", "s.json", "--timestep", "nan"],
    ["experiment", "curves", "over5", "--runs", "0"],
])
def test_a_flag_outside_its_domain_is_one_line_exit_2(argv, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as e:
        main(argv)
    err = capsys.readouterr().err.strip()
    assert e.value.code == 2 and len(err.splitlines()) == 1 and "Traceback" not in err, err
    assert "must be" in err and "--help" in err, err
    assert not list(tmp_path.iterdir())  # refused before any work or file


def test_surrogates_and_bad_escapes(tmp_path, capsys):
    d = copy.deepcopy(GOOD)
    text = json.dumps(d).replace('"two"', '"a\\ud800b"')
    assert "surrogate" in _refused(tmp_path, text, capsys)


# --------------------------------------------------------------------------- the domain

def _set(path, value):
    def f(d):
        obj = d
        for k in path[:-1]:
            obj = obj[k]
        obj[path[-1]] = value
    return f


OUTSIDE = [  # (mutation, field, reason fragment): each just outside one limit
    (_set(["box"], [D.BOX_MAX * 1.001, 80.0]), "box[0]", "outside"),
    (_set(["box"], [100.0, D.BOX_MIN * 0.999]), "box[1]", "outside"),
    (_set(["t_final"], D.T_FINAL_MAX * 1.001), "t_final", "outside"),
    (_set(["t_final"], D.T_FINAL_MIN * 0.999), "t_final", "outside"),
    (_set(["t_final"], 0), "t_final", "> 0"),
    (_set(["target_radius"], math.hypot(100, 80) * 1.001), "target_radius", "diagonal"),
    (_set(["target_radius"], -1.0), "target_radius", "> 0"),
    (_set(["disks", 0, "radius"], 100.0 * D.RADIUS_MIN_FRACTION * 0.999), "disks[0].radius", "below"),
    (_set(["disks", 0, "radius"], 40.001), "disks[0].radius", "too large"),
    (_set(["disks", 0, "mass"], D.MASS_MAX * 1.001), "disks[0].mass", "outside"),
    (_set(["disks", 0, "mass"], 1e308), "disks[0].mass", "outside"),
    (_set(["disks", 0, "mass"], 2.0 * D.MAX_MASS_RATIO * 1.001), "disks[0].mass", "ratio"),
    (_set(["disks", 1, "mass"], 0.0), "disks[1].mass", "> 0"),
    (_set(["disks", 1, "start"], [20.0, 20.0]), "disks[1].start", "overlaps"),        # the same start
    (_set(["disks", 1, "start"], [29.9, 20.0]), "disks[1].start", "overlaps"),
    (_set(["disks", 0, "start"], [4.99, 20.0]), "disks[0].start", "inside the walls"),
    (_set(["name"], "x" * (D.MAX_NAME_CHARS + 1)), "name", "at most"),
    (_set(["name"], "a\x1b[31mred"), "name", "control character"),
    (_set(["name"], "nul\x00"), "name", "control character"),
    (_set(["name"], "two\nlines"), "name", "control character"),
    (_set(["name"], "abc\u202eevil"), "name", "control character"),                   # bidi override
    (_set(["description"], "bell\x07"), "description", "control character"),
    (_set(["description"], "y" * (D.MAX_DESCRIPTION_CHARS + 1)), "description", "at most"),
]


@pytest.mark.parametrize("mutate, field, reason", OUTSIDE)
def test_just_outside_the_domain(tmp_path, capsys, mutate, field, reason):
    d = copy.deepcopy(GOOD)
    mutate(d)
    with pytest.raises(ProblemError) as ei:
        problem_from_dict(d, source="p.json")
    assert ei.value.field == field and reason in ei.value.reason, str(ei.value)
    err = _refused(tmp_path, d, capsys)
    assert field in err


def test_edges_of_the_domain_load():
    d = copy.deepcopy(GOOD)
    d["disks"][0]["mass"] = 2.0 * D.MAX_MASS_RATIO  # disk 1 weighs 2
    d["target_radius"] = math.hypot(100, 80)
    d["description"] = "two\tlines\nare fine in a description"
    d["name"] = "x" * D.MAX_NAME_CHARS
    p = problem_from_dict(d)
    assert p.mass.max() / p.mass.min() == D.MAX_MASS_RATIO
    d["disks"][1]["start"] = [30.0, 20.0]  # touching disk 0 exactly: allowed
    problem_from_dict(d)


def test_same_start_of_tiny_disks_is_refused():
    # used to be accepted (radii squared underflow), then MJCF crashed
    d = copy.deepcopy(GOOD)
    for disk in d["disks"]:
        disk["radius"] = 1e-300
        disk["start"] = [50.0, 40.0]
    with pytest.raises(ProblemError, match="below"):
        problem_from_dict(d)


def test_velocity_limit_is_the_event_cap():
    p = problem_from_dict(GOOD)
    gap = 100.0 - 10.0
    vmax = D.MAX_BOX_CROSSINGS * gap / p.t_final
    assert GA_MAX_DISKS * D.MAX_BOX_CROSSINGS <= MAX_EVENTS // 2  # every disk at the limit fits the cap
    ok = solution_from_dict({"velocities": [[vmax * 0.999, 0.0], [0.0, 0.0]]}, p)
    assert box_crossings(p, ok.velocities)[0] <= D.MAX_BOX_CROSSINGS
    tr = simulate(p, ok.velocities)  # a disk alone at the limit: within the event cap
    assert not tr.truncated and np.isfinite(tr.final_positions).all()
    for v in ([vmax * 1.001, 0.0], [1e200, 0.0], [0.0, 1e308]):
        with pytest.raises(ProblemError, match="event cap") as ei:
            solution_from_dict({"velocities": [v, [0.0, 0.0]]}, p)
        assert ei.value.field == "velocities[0]"
    # a disk as wide as the box may not move along that axis
    d = copy.deepcopy(GOOD)
    d["disks"] = [{"start": [50.0, 40.0], "target": [50.0, 40.0], "radius": 40.0}]
    q = problem_from_dict(d)
    solution_from_dict({"velocities": [[1.0, 0.0]]}, q)
    with pytest.raises(ProblemError, match="event cap"):
        solution_from_dict({"velocities": [[0.0, 1.0]]}, q)


def test_validate_refuses_runs_too_long_for_mujoco(tmp_path, capsys):
    pytest.importorskip("mujoco")
    d = copy.deepcopy(GOOD)
    d["t_final"] = D.T_FINAL_MAX  # inside the domain, but 4e9 MuJoCo steps
    pf = _write(tmp_path, d)
    sf = _write(tmp_path, {"velocities": [[0.01, 0.0], [0.0, 0.0]]}, "s.json")
    assert main(["validate", str(pf), str(sf)]) == 2
    err = capsys.readouterr().err
    assert "timestep" in err and err.count("\n") == 1 and "Traceback" not in err


def test_mujoco_refusal_is_one_line(tmp_path, capsys):
    pytest.importorskip("mujoco")
    d = copy.deepcopy(GOOD)
    for disk, x in zip(d["disks"], (20.0, 50.0)):
        disk["radius"] = 0.001  # 1 um at the default unit: MuJoCo refuses such a light, small body
        disk["start"] = [x, 20.0]
    f = _write(tmp_path, d)
    assert main(["mjcf", str(f)]) == 2
    err = capsys.readouterr().err
    assert "--unit" in err and err.count("\n") == 1


# --------------------------------------------------------------------------- property tests

@st.composite
def problems(draw):
    """Problems inside the domain: log-uniform scales from the edges of every range."""
    W = 10 ** draw(st.floats(math.log10(D.BOX_MIN), math.log10(D.BOX_MAX)))
    H = W * 10 ** draw(st.floats(-2, 2))
    H = min(max(H, D.BOX_MIN), D.BOX_MAX)
    side = min(W, H)
    n = draw(st.integers(1, 4))
    # disks on a grid of n cells along the longer side: never overlapping
    frac = 10 ** draw(st.floats(math.log10(D.RADIUS_MIN_FRACTION * max(W, H) / side * 1.01), math.log10(0.5)))
    cells = n
    long_is_w = W >= H
    cell = (W if long_is_w else H) / cells
    r = min(frac * side, 0.5 * side, 0.5 * cell) * 0.999
    r = max(r, D.RADIUS_MIN_FRACTION * max(W, H) * 1.001)
    if 2 * r > min(cell, side):
        n, cell = 1, (W if long_is_w else H)
        r = min(r, 0.4999 * side)
    m0 = 10 ** draw(st.floats(-90, 90))
    disks = []
    for i in range(n):
        c = (i + 0.5) * cell
        start = [c, H / 2] if long_is_w else [W / 2, c]
        target = [draw(st.floats(r, W - r)), draw(st.floats(r, H - r))]
        mass = m0 * 10 ** draw(st.floats(0, math.log10(D.MAX_MASS_RATIO) - 1e-9))
        disks.append({"start": start, "target": target, "radius": r, "mass": mass})
    t_final = 10 ** draw(st.floats(math.log10(D.T_FINAL_MIN), math.log10(D.T_FINAL_MAX)))
    R = draw(st.floats(1e-6, 1.0)) * math.hypot(W, H)
    return {"name": "prop", "box": [W, H], "t_final": t_final, "target_radius": R, "disks": disks}


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(d=problems(), data=st.data())
def test_inside_the_domain_loads_and_simulates_inside_the_box(d, data):
    p = problem_from_dict(d)
    W, H = p.box
    gaps = np.stack([W - 2 * p.radius, H - 2 * p.radius], axis=1)
    # velocities up to ~100 box crossings per disk (the limit itself is tested above)
    k = np.array([[data.draw(st.floats(-100, 100)) for _ in range(2)] for _ in range(p.n)])
    v = k * gaps / p.t_final
    sol = solution_from_dict({"velocities": v.tolist()}, p)
    tr = simulate(p, sol.velocities)
    f = tr.final_positions
    assert np.isfinite(f).all()
    # a light disk squeezed by a heavy one (mass ratio up to 1e6) can outrun the event
    # cap in a narrow box: that run is flagged and scored inf, never silently wrong
    assert np.isfinite(tr.cost) != (tr.truncated or getattr(tr, "stalled", False))
    slack = 1e-9 * max(W, H)  # round-off of positions of order the box
    assert (f[:, 0] >= p.radius - slack).all() and (f[:, 0] <= W - p.radius + slack).all()
    assert (f[:, 1] >= p.radius - slack).all() and (f[:, 1] <= H - p.radius + slack).all()


_FIELDS = ["box0", "box1", "t_final", "R", "radius", "mass_hi", "mass_lo", "ratio", "vel"]


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(d=problems(), which=st.sampled_from(_FIELDS), eps=st.floats(1e-6, 1e3))
def test_just_outside_the_domain_is_a_problem_error(d, which, eps):
    """Push one value past its limit by a factor (1 + eps): ProblemError, nothing else."""
    up, down = 1 + eps, 1 / (1 + eps)
    W, H = d["box"]
    if which == "box0":
        d["box"][0] = D.BOX_MAX * up
    elif which == "box1":
        d["box"][1] = D.BOX_MIN * down
    elif which == "t_final":
        d["t_final"] = D.T_FINAL_MAX * up if eps > 1 else D.T_FINAL_MIN * down
    elif which == "R":
        d["target_radius"] = math.hypot(W, H) * up
    elif which == "radius":
        d["disks"][0]["radius"] = D.RADIUS_MIN_FRACTION * max(W, H) * down
    elif which == "mass_hi":
        d["disks"][0]["mass"] = D.MASS_MAX * up
    elif which == "mass_lo":
        d["disks"][0]["mass"] = D.MASS_MIN * down
    elif which == "ratio":
        d["disks"].append(copy.deepcopy(d["disks"][0]))
        d["disks"][-1]["mass"] = d["disks"][0]["mass"] * D.MAX_MASS_RATIO * up
        d["disks"][-1]["start"] = list(d["disks"][0]["start"])  # and overlapping: either error will do
    if which == "vel":
        p = problem_from_dict(d)
        gap = W - 2 * p.radius[0]
        with pytest.raises(ProblemError):
            solution_from_dict({"velocities": [[D.MAX_BOX_CROSSINGS * gap / p.t_final * up, 0.0]]
                                              + [[0.0, 0.0]] * (p.n - 1)}, p)
        return
    with pytest.raises(ProblemError):
        problem_from_dict(d)


# --------------------------------------------------------------------------- user text

def test_dollar_and_control_characters_in_names(tmp_path, capsys):
    d = copy.deepcopy(GOOD)
    d["name"] = "cost $x^2$ and a lone $"
    f = _write(tmp_path, d)
    out = tmp_path / "fig.png"
    assert main(["plot", "problem", str(f), "-o", str(out)]) == 0
    assert out.stat().st_size > 0
    assert display_name("a$b") == r"a\$b"
    assert display_name("esc\x1b") == "esc\\x1b"
    # a file stem with control characters is the default name: made printable, not refused
    g = tmp_path / "we\x1bird.json"
    d.pop("name")
    g.write_text(json.dumps(d))
    p = load_problem(g)
    assert "\x1b" not in p.name and p.name == "we\\x1bird"


def test_error_lines_never_carry_control_characters(tmp_path, capsys):
    assert main(["simulate", "over5", str(tmp_path / "x\x1b[2Jy\nz.json")]) == 2
    err = capsys.readouterr().err
    assert "\x1b" not in err and err.count("\n") == 1


def test_report_html_escapes_the_name(tmp_path):
    pytest.importorskip("mujoco")
    from nbst.render.report import report_html
    from nbst.models.validate import validate
    d = copy.deepcopy(GOOD)
    d["name"] = "<script>alert(1)</script> & $x$"
    d["description"] = "<b>bold</b>\nsecond line"
    d["t_final"] = 0.2
    p = problem_from_dict(d)
    page = report_html(validate(p, np.array([[10.0, 0.0], [0.0, 0.0]])))
    assert "<script>alert" not in page and "&lt;script&gt;" in page and "<b>bold" not in page


# --------------------------------------------------------------------------- strict JSON out

def test_simulate_json_is_strict(tmp_path, capsys):
    p = load_problem("over5")
    v = np.zeros((5, 2))
    v[0] = [-90.0, 30.0]
    f = tmp_path / "s.json"
    save_solution(f, make_solution(p, v, cost=math.nan, extra=[math.inf, -math.inf, np.float64("nan")]))
    saved = _strict(f.read_text())
    assert saved["cost"] is None and saved["extra"] == ["inf", "-inf", None]
    assert main(["simulate", "over5", str(f), "--json"]) == 0
    out = _strict(capsys.readouterr().out)
    assert len(out["final"]) == 5 and out["truncated"] is False
    assert main(["problems", "show", "over5"]) == 0
    _strict(capsys.readouterr().out)


def test_print_json_writes_non_finite_numbers_strictly(capsys):
    from nbst.cli.args import print_json
    print_json({"cost": math.inf, "x": [math.nan, -math.inf, np.float32(1.5)], "n": np.int64(3)})
    assert _strict(capsys.readouterr().out) == {"cost": "inf", "x": [None, "-inf", 1.5], "n": 3}
    assert _strict(dumps_strict({"a": np.array([np.nan, 1.0])})) == {"a": [None, 1.0]}


def test_validate_json_outputs_are_strict(tmp_path, capsys):
    pytest.importorskip("mujoco")
    d = copy.deepcopy(GOOD)
    d["t_final"] = 0.2
    pf = _write(tmp_path, d)
    sf = _write(tmp_path, {"velocities": [[10.0, 0.0], [0.0, 0.0]]}, "s.json")
    rep = tmp_path / "rep"
    assert main(["validate", str(pf), str(sf), "--json", "--report", str(rep)]) == 0
    _strict(capsys.readouterr().out)
    _strict((rep / "report.json").read_text())


@pytest.mark.parametrize("cmd", [["simulate"], ["validate"], ["render", "--still", "1", "-o", "x.png"],
                                 ["plot", "trajectories", "-o", "p.png"]])
def test_a_solution_that_cannot_be_simulated_to_the_end_is_refused_up_front(cmd, tmp_path, capsys, monkeypatch):
    """Every accepted solution simulates without truncation, or is refused in one line (exit 2):
    one collision in a 1e9 x 2001 box sends a disk bouncing across the narrow side past the cap."""
    monkeypatch.chdir(tmp_path)
    p = {"name": "long", "box": [1e9, 2001], "t_final": 5.0, "target_radius": 75.0,
         "disks": [{"start": [2000, 1000.2], "target": [5e8, 1000.5], "radius": 1000},
                   {"start": [5e8, 1000.8], "target": [8e8, 1000.2], "radius": 1000}]}
    (tmp_path / "long.json").write_text(json.dumps(p))
    (tmp_path / "sol.json").write_text(json.dumps({"velocities": [[999 * (1e9 - 2000) / 5, 0.0], [0.0, 0.0]]}))
    argv = cmd[:2] if cmd[0] == "plot" else cmd[:1]
    rc = main(argv + ["long.json", "sol.json"] + (cmd[2:] if cmd[0] == "plot" else cmd[1:]))
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1, err
    assert "sol.json: velocities: the motion stops at t =" in err[0] and "cannot simulate it to the end" in err[0]
    assert not list(tmp_path.glob("*.png"))
