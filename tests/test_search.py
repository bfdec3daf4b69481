"""solve(), the variants and `nbst solve`: determinism, stopping, Ctrl-C, the file it writes."""
import dataclasses
import json
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from nbst import load_problem
from nbst.cli import main
from nbst.search import VARIANTS, SearchParams, run_search, solve, variant_params
from nbst.sim import simulate
from nbst.solution import load_solution

ROOT = Path(__file__).resolve().parents[1]
VOLATILE = {"wall_time", "trials_per_s"}


@pytest.fixture(scope="module")
def s14():
    return load_problem("diamond-s14")


def same(a, b):
    np.testing.assert_array_equal(a.velocities, b.velocities)
    assert {k: v for k, v in a.meta.items() if k not in VOLATILE} == \
        {k: v for k, v in b.meta.items() if k not in VOLATILE}


@pytest.mark.parametrize("variant", ["A", "nbst"])
def test_same_seed_same_solution_whatever_the_chunking(s14, variant):
    a = solve(s14, seed=11, max_trials=6000, patience=0, variant=variant)
    b = solve(s14, seed=11, max_trials=6000, patience=0, chunk=7, variant=variant)
    c = solve(s14, seed=11, max_trials=6000, patience=0, chunk=100_000, variant=variant)
    same(a, b)
    same(a, c)
    d = solve(s14, seed=12, max_trials=6000, patience=0, variant=variant)
    assert not np.array_equal(a.velocities, d.velocities)


def test_meta_is_complete_and_true(s14):
    sol = solve(s14, seed=1, max_trials=3000, variant="A")
    m = sol.meta
    for key in ("cost", "signature", "order", "trials", "seed", "variant", "params", "wall_time", "nbst_version",
                "history", "stopped", "init_trials", "first_full_order_trial"):
        assert key in m
    tr = simulate(s14, sol.velocities)
    assert tr.cost == m["cost"] and tr.signature_string == m["signature"] and tr.order == m["order"]
    assert m["trials"] == 3000 and m["stopped"] == "max_trials" and m["seed"] == 1
    hist = np.array(m["history"])
    assert hist[-1, 1] == m["cost"] and np.all(np.diff(hist[:, 1]) < 0) and np.all(np.diff(hist[:, 0]) > 0)
    assert m["params"] == dataclasses.asdict(SearchParams()) | {"op_weights": [0.25] * 4}


def test_tiny_problem_solved_quickly():
    # footnote 4: near-zero radius disks are solved in a few dozen generate-insert iterations
    sol = solve(load_problem("diamond-s14-tiny"), seed=3, max_trials=5000, target_cost=1e-6, variant="A")
    assert sol.meta["stopped"] == "target_cost" and sol.meta["cost"] < 1e-6
    assert sol.meta["trials"] - sol.meta["init_trials"] < 500


def test_noncueable_disks_never_move_and_patience_stops():
    p = load_problem("over5")
    sol = solve(p, seed=2, max_trials=200_000, patience=2000, variant="A")
    assert np.all(sol.velocities[~p.cueable] == 0.0)
    assert sol.meta["stopped"] == "patience"
    last_improvement = sol.meta["history"][-1][0]
    assert sol.meta["trials"] == last_improvement + 2000


def test_callback_can_stop_and_interrupt(s14):
    seen = []

    def cb(p):
        seen.append(p.trials)
        return len(seen) == 3

    sol = solve(s14, seed=4, max_trials=100_000, patience=0, chunk=500, callback=cb, variant="A")
    assert sol.meta["stopped"] == "callback" and sol.meta["trials"] == 1500 and seen == [500, 1000, 1500]

    def ctrl_c(p):
        if p.trials >= 1000:
            raise KeyboardInterrupt

    sol = solve(s14, seed=4, max_trials=100_000, patience=0, chunk=500, callback=ctrl_c, variant="A")
    assert sol.meta["stopped"] == "interrupted" and sol.meta["trials"] == 1000
    assert simulate(s14, sol.velocities).cost == sol.meta["cost"]


# --------------------------------------------------------------------------- variants

EXPECTED_CHANGES = {
    "A": {},
    "B": {"senate": False},
    "C": {"op_weights": (1 / 3, 1 / 3, 1 / 3, 0.0)},
    "D": {"engineered": False},
    "E": {"signature_radius": 800.0, "init_population": 60, "sig_limit": 60},
    "F": {"cull": "worst"},
    "G": {"elitism": False},
    "H": {"op_weights": (1 / 3, 0.0, 1 / 3, 1 / 3), "p_directed_init": 0.0},
    "nbst": {"op_weights": (0.2, 0.1, 0.1, 0.2), "bank_weight": 0.3, "strike_weight": 0.1, "polish": True,
             "straight_start": True, "planner": True},
    "nbst-noplan": {"op_weights": (0.2, 0.1, 0.1, 0.2), "bank_weight": 0.3, "strike_weight": 0.1, "polish": True,
                    "straight_start": True},
}


@pytest.mark.parametrize("v", sorted(VARIANTS))
def test_each_variant_changes_what_it_should_and_nothing_else(v, s14):
    a = dataclasses.asdict(variant_params("A", s14))
    x = dataclasses.asdict(variant_params(v, s14))
    changed = {k: x[k] for k in a if a[k] != x[k] and k != "variant"}
    assert changed == EXPECTED_CHANGES[v]
    assert x["variant"] == v


def test_variants_behave(s14):
    runs = {v: solve(s14, seed=5, max_trials=8000, patience=0, variant=v).meta for v in "ACEH"}
    ops = {v: m["operators"] for v, m in runs.items()}
    assert ops["C"]["crossover"]["children"] == 0 and ops["A"]["crossover"]["children"] > 1000
    assert ops["H"]["directed"]["children"] == 0 and ops["H"]["uniform"]["children"] > 1000
    assert runs["E"]["init_trials"] >= 60 and runs["E"]["population_size"] == 60
    assert runs["E"]["params"]["signature_radius"] == 800.0 and runs["E"]["search_signature"] == "1" * 14
    e = runs["E"]
    sol_e = solve(s14, seed=5, max_trials=8000, patience=0, variant="E")
    assert simulate(s14, sol_e.velocities).signature_string == e["signature"]  # the problem's R in the file
    assert runs["A"]["population_size"] <= 200 and runs["A"]["cull_rounds"] > 0
    assert runs["A"]["fallback_deletions"] == 0


# --------------------------------------------------------------------------- the command

def test_cli_writes_a_file_that_simulate_accepts(tmp_path, capsys):
    out = tmp_path / "sol.json"
    assert main(["solve", "diamond-s14", "-o", str(out), "--seed", "7", "--max-trials", "4000", "--quiet",
                 "--variant", "A"]) == 0
    d = json.loads(out.read_text())
    assert d["seed"] == 7 and d["trials"] == 4000 and d["variant"] == "A" and d["problem"] == "diamond-s14"
    assert main(["simulate", "diamond-s14", str(out), "--json"]) == 0
    sim = json.loads(capsys.readouterr().out)
    assert sim["cost"] == d["cost"] and sim["signature"] == d["signature"]
    out2 = tmp_path / "sol2.json"
    assert main(["solve", "diamond-s14", "-o", str(out2), "--seed", "7", "--max-trials", "4000", "--quiet",
                 "--variant", "a"]) == 0
    assert json.loads(out2.read_text())["velocities"] == d["velocities"]
    out3 = tmp_path / "sol3.json"  # the default is nbst's search
    assert main(["solve", "diamond-s14", "-o", str(out3), "--seed", "7", "--max-trials", "4000", "--quiet"]) == 0
    assert json.loads(out3.read_text())["variant"] == "nbst"


def test_cli_bad_values_exit_2(tmp_path):
    for args in (["--max-trials", "0"], ["--variant", "Z"], ["--patience", "-1"], ["--seed", "x"],
                 ["--target-cost", "-1"]):
        with pytest.raises(SystemExit) as e:
            main(["solve", "over5", "-o", str(tmp_path / "x.json"), *args])
        assert e.value.code == 2
    assert not (tmp_path / "x.json").exists()


def test_ctrl_c_writes_the_best_so_far(tmp_path):
    out = tmp_path / "int.json"
    proc = subprocess.Popen([sys.executable, str(ROOT / "cli.py"), "solve", "diamond-s14", "-o", str(out),
                             "--seed", "8", "--patience", "0", "--max-trials", "1000000000",
                             "--target-cost", "0"],
                            stderr=subprocess.PIPE, text=True,
                            # a shell runs background jobs with SIGINT ignored, and children inherit that:
                            # give the solver the default disposition, as a terminal's Ctrl-C finds it
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    buf = ""
    t0 = time.time()
    while "best" not in buf and time.time() - t0 < 60:  # the search is under way
        buf += proc.stderr.read(1)
    proc.send_signal(signal.SIGINT)
    err = buf + proc.communicate(timeout=60)[1]
    assert proc.returncode == 130, err
    assert "interrupted" in err.splitlines()[-1] and "Traceback" not in err
    d = json.loads(out.read_text())
    assert d["stopped"] == "interrupted" and 0 < d["trials"] < 1_000_000_000
    p = load_problem("diamond-s14")
    assert simulate(p, load_solution(out, p).velocities).cost == d["cost"]
    assert not list(tmp_path.glob(".*tmp"))  # no temporary file left behind


def test_recorded_candidates_are_what_the_loop_simulated(s14):
    from nbst import evaluate
    from nbst.search import run_search

    r = run_search(s14, seed=9, max_trials=1500, patience=0, record_every=1, variant="A")
    assert r.recorded.shape == (1500, 14, 2)
    _, cost, _ = evaluate(s14, r.recorded)
    for t, c, _ in r.result.meta["history"]:
        assert cost[t - 1] == c  # the improvement at trial t is the candidate simulated at trial t
    same(r.result, solve(s14, seed=9, max_trials=1500, patience=0, variant="A"))  # recording changes nothing
    assert len(r.costs) == r.result.meta["population_size"] and np.all(np.isfinite(r.costs))


# --------------------------------------------------------------------------- parameters and the velocity domain

@pytest.mark.parametrize("field, value", [("pop_limit", 1), ("planner_weight", -0.1), ("op_weights", (1.0, 0.0)),
                                          ("adapt_floor", 1.0 / 7), ("cull", "best"), ("polish_sims", 1),
                                          ("signature_radius", float("nan")), ("hard_limit", 100)])
def test_search_params_check_each_field_and_name_it(field, value):
    with pytest.raises(ValueError, match=rf"^SearchParams\.{field}: must be "):
        SearchParams(**{field: value})


def test_search_params_defaults_and_every_variant_pass_their_checks(s14):
    for v in VARIANTS:
        assert variant_params(v, s14).variant.lower() == v.lower()


def _narrow_channel(R=1e5):
    """Legal, and hostile to unbounded proposals: 1 unit of play across a 2001-unit channel,
    and a target radius so large that a creep (0.1 R / t_final per axis) crosses it 10,000
    times. The two disks cannot pass each other, so the straight shot fails."""
    from nbst.problem import problem_from_dict

    return problem_from_dict({"name": "channel", "box": [1e7, 2001], "t_final": 5.0, "target_radius": R,
                              "disks": [{"start": [2000, 1000.5], "target": [8e6, 1000.5], "radius": 1000},
                                        {"start": [9e6, 1000.5], "target": [1e6, 1000.2], "radius": 1000}]})


@pytest.mark.parametrize("variant", ["nbst", "A"])
def test_a_legal_problem_never_yields_a_refused_solution(variant):
    from nbst.domain import MAX_BOX_CROSSINGS
    from nbst.problem import box_crossings
    from nbst.solution import solution_from_dict

    p = _narrow_channel()
    sol = solve(p, seed=1, max_trials=4000, patience=0, variant=variant)
    assert box_crossings(p, sol.velocities).max() <= MAX_BOX_CROSSINGS
    if variant == "A":  # every candidate the loop simulated (creep alone proposes ~10,000 crossings here)
        rec = run_search(p, seed=1, max_trials=4000, patience=0, variant="A", record_every=1).recorded
        assert len(rec) == 4000 and max(box_crossings(p, v).max() for v in rec) <= MAX_BOX_CROSSINGS
    d = json.loads(json.dumps({"problem": p.name, "velocities": sol.velocities.tolist()}))
    solution_from_dict(d, p)  # the checker accepts it
    assert not simulate(p, sol.velocities).truncated


def test_limit_crossings_scales_onto_the_limit_and_leaves_the_domain_alone():
    from nbst.search.ops import SEARCH_MAX_CROSSINGS, limit_crossings
    from nbst.problem import box_crossings

    p = _narrow_channel()
    ka = p.kernel_arrays()
    cue = np.arange(2, dtype=np.int64)
    inside = np.array([[1.2e6, 0.3], [-3.0e5, -0.05]])
    v = inside.copy()
    assert limit_crossings(v, cue, ka.radius, ka.W, ka.H, ka.t_final) == 0
    np.testing.assert_array_equal(v, inside)
    fast = np.array([[1.0e6, 4000.0], [-2.0e5, 10.0]])  # disk 0: 20,000 crossings across the channel
    v = fast.copy()
    assert limit_crossings(v, cue, ka.radius, ka.W, ka.H, ka.t_final) == 1
    assert box_crossings(p, v)[0] == pytest.approx(SEARCH_MAX_CROSSINGS, rel=1e-12)
    assert v[0, 0] / v[0, 1] == pytest.approx(fast[0, 0] / fast[0, 1], rel=1e-12)  # direction kept
    np.testing.assert_array_equal(v[1], fast[1])
    # a disk that fills the channel (H = 2r) may not move across it at all
    tight = p.radius.copy()
    tight[0] = 1000.5
    v = fast.copy()
    limit_crossings(v, cue, tight, ka.W, ka.H, ka.t_final)
    assert v[0, 1] == 0.0 and v[0, 0] == fast[0, 0]


def test_where_the_crossing_bound_stops_the_event_cap_still_holds():
    """The crossing limit bounds the wall events of a disk that meets no other (constants.MAX_EVENTS):
    one collision in a 1e9 x 2001 box turns a run along the long axis into ~1e8 bounces
    across the short one. Such a run is truncated (cost inf), so the search never keeps it."""
    from nbst.constants import MAX_EVENTS
    from nbst.problem import box_crossings, problem_from_dict
    from nbst.sim import evaluate

    p = problem_from_dict({"name": "long", "box": [1e9, 2001], "t_final": 5.0, "target_radius": 75.0,
                           "disks": [{"start": [2000, 1000.2], "target": [5e8, 1000.5], "radius": 1000},
                                     {"start": [5e8, 1000.8], "target": [8e8, 1000.2], "radius": 1000}]})
    v = np.array([[999 * (1e9 - 2000) / 5, 0.0], [0.0, 0.0]])
    assert box_crossings(p, v).max() < 1000
    tr = simulate(p, v)
    assert tr.truncated and len(tr.events) == MAX_EVENTS and tr.n_disk_disk == 1
    assert np.isinf(evaluate(p, v[None])[1][0])
    # a lower cap keeps the test quick: the search's candidates here truncate at whatever cap
    params = dataclasses.replace(variant_params("A"), max_events=20_000)
    sol = solve(p, seed=1, max_trials=2000, patience=0, params=params)
    assert sol.meta["truncated_runs"] > 0 and not simulate(p, sol.velocities).truncated
