"""The crash script's input gate: every refusal is one line naming the file and the field."""
import copy
import json
import math

import pytest

from nbst.models.crash import script as S


def base() -> dict:
    return {
        "kind": "nbst-crash-script", "name": "t",
        "road": {"layout": "intersection", "width": 7, "length": 120, "curb": 0.15},
        "duration": 4.0,
        "vehicles": [
            {"name": "A", "type": "sedan", "start": {"x": -40, "y": -1.75, "heading": 0}, "speed": [40, 60],
             "driver": {"aim": {"x": [0, 5], "y": -1.75}, "arrive": [2.5, 3.5]},
             "fate": {"hits": ["B"], "rest": {"x": 5, "y": 5, "radius": 2}}},
            {"name": "B", "type": "suv", "start": {"x": 1.75, "y": -40, "heading": 90}, "speed": 50,
             "fate": {"hits": ["A"]}},
        ],
    }


def refuse(d, field, words=()):
    with pytest.raises(S.ScriptError) as e:
        S.script_from_dict(d, source="x.json")
    msg = str(e.value)
    assert "\n" not in msg and msg.startswith("x.json: ")
    assert e.value.field == field, msg
    for w in words:
        assert w in msg, msg
    return msg


def test_a_good_script_reads_in_si_units():
    s = S.script_from_dict(base(), source="x.json")
    a, b = s.vehicles
    assert a.speed.lo == pytest.approx(40 / 3.6) and a.speed.hi == pytest.approx(60 / 3.6)
    assert b.speed.fixed and b.heading == pytest.approx(math.pi / 2)
    assert a.fate.hits == (1,) and a.fate.rest == (5.0, 5.0, 2.0)
    assert s.timestep == 0.002 and s.road.friction == S.SURFACES["dry"]


def test_every_builtin_script_loads():
    names = S.builtin_names()
    assert {"t-bone", "chain3", "rear-end4", "rollover", "stunt"} <= set(names)
    for n in names:
        s = S.load_script(n)
        assert s.n >= 1 and any(v.fate.asks() for v in s.vehicles)


@pytest.mark.parametrize("path, value, field, words", [
    (("road", "layout"), "roundabout", "road.layout", ["straight", "intersection", "curve"]),
    (("road", "friction"), 2.5, "road.friction", ["outside"]),
    (("road", "friction"), float("nan"), "road.friction", ["finite"]),
    (("road", "width"), True, "road.width", ["number"]),
    (("duration",), 1e300, "duration", ["outside"]),
    (("vehicles", 0, "speed"), [70, 40], "vehicles[0].speed", ["low end"]),
    (("vehicles", 0, "speed"), 400, "vehicles[0].speed", ["outside"]),
    (("vehicles", 0, "type"), "tank", "vehicles[0].type", ["sedan"]),
    (("vehicles", 1, "name"), "A", "vehicles[1].name", ["differ"]),
    (("vehicles", 0, "driver", "after_impact"), "pray", "vehicles[0].driver.after_impact", ["brake"]),
    (("vehicles", 0, "fate", "attitude"), "flying", "vehicles[0].fate.attitude", ["roof"]),
    (("vehicles", 0, "fate", "quarter_turns"), 2.5, "vehicles[0].fate.quarter_turns", ["whole"]),
])
def test_bad_values_are_refused_with_their_field(path, value, field, words):
    d = base()
    o = d
    for k in path[:-1]:
        o = o[k]
    o[path[-1]] = value
    refuse(d, field, words)


def test_unknown_keys_are_refused_with_a_hint():
    d = base()
    d["vehicles"][0]["fate"]["hit"] = ["B"]
    msg = refuse(d, "vehicles[0].fate.hit", ["unknown key", "hits"])
    assert "did you mean" in msg
    d = base()
    d["colour"] = "red"
    refuse(d, "colour", ["unknown key"])


def test_overlapping_starts_are_refused():
    d = base()
    d["vehicles"][1]["start"] = {"x": -38, "y": -1.75, "heading": 0}
    refuse(d, "vehicles[1].start", ["overlaps"])


def test_a_start_off_the_road_is_refused():
    d = base()
    d["vehicles"][0]["start"] = {"x": -40, "y": 3.0, "heading": 0}  # its left side 0.4 m past the carriageway's edge
    refuse(d, "vehicles[0].start", ["not on the road", "corner"])


def test_a_fate_outside_the_map_is_refused():
    d = base()
    d["vehicles"][0]["fate"]["rest"] = {"x": 500, "y": 0}
    refuse(d, "vehicles[0].fate.rest", ["outside the map"])


def test_contradictory_hit_lists_are_refused():
    d = base()
    d["vehicles"][1]["fate"]["hits"] = []  # A says it hits B, B says it hits nobody
    refuse(d, "vehicles[1].fate.hits", ["mutual"])
    # three vehicles whose lists need a cycle of first contacts
    d = base()
    d["vehicles"].append({"name": "C", "type": "van", "start": {"x": -1.75, "y": 40, "heading": -90}, "speed": 30})
    d["vehicles"][0]["fate"] = {"hits": ["B", "C"]}
    d["vehicles"][1]["fate"] = {"hits": ["C", "A"]}
    d["vehicles"][2]["fate"] = {"hits": ["A", "B"]}
    refuse(d, "vehicles", ["contradict"])


def test_hits_must_agree_with_the_global_order():
    d = base()
    d["order"] = [["B", "A"]]
    S.script_from_dict(d, source="x.json")  # the same pair, either way round
    d["vehicles"].append({"name": "C", "type": "van", "start": {"x": -1.75, "y": 40, "heading": -90}, "speed": 30})
    d["order"] = [["A", "C"], ["A", "B"]]
    refuse(d, "vehicles[0].fate.hits", ["global order"])
    d["order"] = [["A", "A"]]
    refuse(d, "order[0]", ["itself"])


def test_impossible_fates_are_refused():
    d = base()
    d["road"]["curb"] = 0
    d["vehicles"][0]["fate"]["strikes"] = {"curb": True}
    refuse(d, "vehicles[0].fate.strikes.curb", ["no curbs"])
    d = base()
    d["vehicles"][0]["fate"].update({"quarter_turns": 1, "attitude": "roof"})
    refuse(d, "vehicles[0].fate.attitude", ["quarter turns"])
    d = base()
    d["vehicles"][0]["fate"] = {"delta_v": [10, 20]}
    refuse(d, "vehicles[0].fate.delta_v", ["whom it hits"])
    d = base()
    d["vehicles"][0]["fate"] = {"impact_at": {"x": 0, "y": -1.75}}
    refuse(d, "vehicles[0].fate.impact_at", ["whom it hits"])
    d = base()
    d["vehicles"][0]["fate"]["impact_at"] = {"x": 0, "y": -1.75, "radius": 0}
    refuse(d, "vehicles[0].fate.impact_at.radius", ["outside"])
    d = base()
    d["vehicles"][0]["fate"]["impact_at"] = {"x": 900, "y": -1.75}
    refuse(d, "vehicles[0].fate.impact_at", ["map"])
    d = base()
    d["vehicles"][0]["fate"]["impact_at"] = {"x": 0.5, "y": -1.75}
    assert S.script_from_dict(d).vehicles[0].fate.impact_at == (0.5, -1.75, 0.5)  # 0.5 m unless given


def test_the_file_gate_refuses_nan_huge_integers_and_other_kinds(tmp_path):
    f = tmp_path / "s.json"
    f.write_text(json.dumps(base()).replace('"duration": 4.0', '"duration": NaN'))
    with pytest.raises(S.ScriptError, match="duration: must be finite"):
        S.load_script(f)
    f.write_text(json.dumps(base()).replace('"duration": 4.0', '"duration": ' + "9" * 500))
    with pytest.raises(S.ScriptError, match="500 digits"):
        S.load_script(f)
    d = base()
    d["kind"] = "nbst-bowling-shot"
    f.write_text(json.dumps(d))
    with pytest.raises(S.ScriptError, match="kind"):
        S.load_script(f)
    with pytest.raises(S.ScriptError, match="no such file and no built-in"):
        S.load_script("t-bon")


def test_the_cli_check_refuses_in_one_line_with_exit_2(tmp_path, capsys):
    from nbst.cli.main import main

    d = copy.deepcopy(base())
    d["vehicles"][0]["speed"] = [40, "fast"]
    f = tmp_path / "s.json"
    f.write_text(json.dumps(d))
    assert main(["crash", "check", str(f)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "vehicles[0].speed[1]" in err and "Traceback" not in err
    assert main(["crash", "check", "t-bone"]) == 0


def test_every_script_file_is_registered_once():
    from importlib import resources

    files = sorted(p.name for p in resources.files("nbst.models.crash").joinpath("scripts").iterdir()
                   if p.name.endswith(".json"))
    assert sorted(S.SCRIPTS[n] for n in S.SCRIPTS.names()) == files


def test_crash_commands_refuse_bad_input_in_one_line(tmp_path, capsys):
    from nbst.cli.main import main

    f = tmp_path / "s.json"
    f.write_text(json.dumps(base()))
    for argv, words in ((["crash", "replay", str(f)], ["kind", "nbst crash solve"]),
                        (["crash", "probability", str(f)], ["kind"]),
                        (["crash", "solve", "no-such-script", "-o", str(tmp_path / "o.json")], ["no such file"]),
                        (["crash", "solve", str(f), "-o", str(tmp_path)], ["-o"]),
                        (["crash", "reconstruct", str(tmp_path / "x.json"), "-o", str(tmp_path / "r.json")],
                         ["no such file"]),
                        (["crash", "solve", str(f), "-o", str(tmp_path / "o.json"), "--max-rollouts", "0"],
                         ["max-rollouts"])):
        try:
            rc = main(argv)
        except SystemExit as e:  # argparse's usage errors exit 2 themselves
            rc = e.code
        assert rc == 2, argv
        err = capsys.readouterr().err.strip()
        assert err.count("\n") == 0 and "Traceback" not in err, err
        for w in words:
            assert w in err, (argv, err)


def test_every_vehicle_file_is_registered_once_and_read_exactly():
    """A vehicle type is one data file (models/crash/vehicles/) and one registry entry; the file's
    numbers are the type's, bit for bit (the scenes and replays depend on them)."""
    from importlib import resources

    from nbst.models.crash import vehicle as V

    folder = resources.files("nbst.models.crash").joinpath("vehicles")
    files = sorted(f.name for f in folder.iterdir() if f.name.endswith(".json"))
    assert files == sorted(f"{n}.json" for n in V.VEHICLE_TYPES)
    for name in V.VEHICLE_TYPES:
        d = json.loads(folder.joinpath(f"{name}.json").read_text(encoding="utf-8"))
        vt = V.VEHICLE_TYPES[name]
        assert vt.name == name and all(getattr(vt, k) == v for k, v in d.items() if k not in ("kind", "schema_version"))
    assert V.VEHICLE_TYPES["sedan"].mass == 1450.0 and V.VEHICLE_TYPES["suv"].power == 200e3


@pytest.mark.parametrize("edit, words", [
    ({"mass": "heavy"}, "mass: must be a finite number"),
    ({"wings": 2}, "wings: unknown field"),
    ({"label": 3}, "label: must be a string"),
    ({"kind": "nbst-crash-script"}, "kind 'nbst-crash-vehicle'"),
])
def test_a_bad_vehicle_file_is_refused_naming_the_field(edit, words):
    from nbst.errors import InputError
    from nbst.models.crash import vehicle as V

    d = {"kind": V.VEHICLE_KIND, "schema_version": 1, **{k: v for k, v in vars(V.VEHICLE_TYPES["van"]).items()}}
    assert V.vehicle_type_from_dict(d) == V.VEHICLE_TYPES["van"]
    with pytest.raises(InputError, match=words):
        V.vehicle_type_from_dict({**d, **edit}, source="van.json")
    del d["mass"]
    with pytest.raises(InputError, match="mass: missing"):
        V.vehicle_type_from_dict(d)


@pytest.mark.parametrize("kw, words", [({"seed": -1}, "seed must be an integer"),
                                       ({"seed": 1, "max_rollouts": 0}, "max_rollouts must be a whole number")])
def test_solve_refuses_a_bad_seed_or_budget_before_any_rollout(kw, words):
    from nbst.errors import InputError
    from nbst.models import crash

    with pytest.raises(InputError, match=words):
        crash.solve(S.load_script("t-bone"), **kw)


def test_the_cli_check_shows_every_fate_the_script_asks(capsys):
    """`nbst crash check` names each fate a vehicle is asked, exactly the fates the judge checks
    (outcome.judge's keys): nothing asked is left out (t-bone's impact speed and delta-V were)."""
    import numpy as np

    from nbst.cli.crash.commands import fate_phrases
    from nbst.cli.main import main
    from nbst.models.crash import outcome

    d = base()
    d["vehicles"][0]["fate"] = {
        "hits": ["B"], "impact_speed": [45, 60], "delta_v": [10, 30], "rest": {"x": 5, "y": 5, "radius": 2},
        "impact_at": {"x": 0, "y": -1.75, "radius": 1}, "heading": {"deg": 30, "tol": 20}, "quarter_turns": 0,
        "attitude": "upright", "spin": {"deg": 90, "tol": 30}, "strikes": {"curb": True, "barrier": False}}
    s = S.script_from_dict(d, source="x.json")
    nan = math.nan
    vo = [outcome.VehicleOutcome(name=n, hits=[], impact_speed=nan, impact_heading=nan, impact_pos=(nan, nan),
                                 delta_v=nan, rest=(0.0, 0.0, 0.0), quarter_turns=0, roll=0.0, attitude="upright",
                                 spin=0.0, curb=nan, barrier=nan, moving=False) for n in ("A", "B")]
    o = outcome.judge(outcome.Outcome(vehicles=vo, contacts=[]), s, np.zeros(1))
    for i in range(2):
        assert set(fate_phrases(s, i)) == set(o.vehicles[i].fates)
    assert main(["crash", "check", "t-bone"]) == 0
    out = capsys.readouterr().out
    assert "impact speed 45-60 km/h" in out and "delta-V 15-35 km/h" in out and "at rest facing 140" in out
