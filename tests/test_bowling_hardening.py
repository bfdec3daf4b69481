"""Shot and atlas files are hostile input too (the shot-file gate, models/bowling/deckfile.py):
regular files only, nbst's core JSON reader, finite and bounded states, shapes checked against
the scene, the scene inside the file's own folder; MuJoCo's warnings are our errors; the render
and plot commands check their flags on shot files. Every refusal is one line and exit 2."""
from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import pytest

mujoco = pytest.importorskip("mujoco")

from nbst.models.bowling.deck import throwfile as deckfile
from nbst.models.bowling import deck, pinfall
from nbst.models.mjsearch import runner as mjrunner
from nbst.errors import MujocoError

ROOT = Path(__file__).resolve().parents[1]
SHIPPED = ROOT / "models" / "bowling" / "deck"


@pytest.fixture(scope="module")
def good(tmp_path_factory):
    """A folder with one real shot (the atlas's 7-10 split leave) beside its scene."""
    folder = tmp_path_factory.mktemp("shots")
    atlas = json.loads((SHIPPED / "atlas.json").read_text())
    d = next(s for s in atlas["shots"] if s["down"] == [1, 2, 3, 4, 5, 6, 8, 9])
    shutil.copyfile(SHIPPED / "scene.xml", folder / "scene.xml")
    (folder / "shot.json").write_text(json.dumps(d))
    return folder, d


def _main(argv, capsys):
    from nbst.cli import main

    try:
        rc = main([str(a) for a in argv])
    except SystemExit as e:  # a flag refused by its argparse type (its domain) at parse time
        rc = e.code
    err = capsys.readouterr().err.strip().splitlines()
    return rc, [line for line in err if not line.startswith("nbst: note:")]


def _write(folder: Path, name: str, d) -> Path:
    p = folder / name
    p.write_text(d if isinstance(d, str) else json.dumps(d))
    return p


def _refused(argv, capsys, *needles):
    rc, err = _main(argv, capsys)
    assert rc == 2 and len(err) == 1, err
    assert "Traceback" not in err[0]
    for n in needles:
        assert n in err[0], err[0]
    return err[0]


# --- the gate: reading --------------------------------------------------------------------------

def test_the_good_shot_replays_exactly(good, capsys):
    folder, d = good
    rc, _ = _main(["bowl", "replay", folder / "shot.json"], capsys)
    assert rc == 0


@pytest.mark.parametrize("text, needle", [
    ("[" * 5000 + "]" * 5000, "nested"),
    ('{"kind": "nbst-bowling-shot", "x": ' + "9" * 5000 + "}", "5000 digits"),
    ("{not json", "not valid JSON"),
])
def test_malformed_json_is_one_line(good, tmp_path, capsys, text, needle):
    p = _write(tmp_path, "bad.json", text)
    _refused(["bowl", "replay", p], capsys, str(p), needle)


def test_non_utf8_is_one_line(tmp_path, capsys):
    p = tmp_path / "bin.json"
    p.write_bytes(b'{"kind": "nbst-bowling-shot", "\xff": 1}')
    _refused(["bowl", "replay", p], capsys, "UTF-8")


@pytest.mark.parametrize("field, value, needle", [
    ("qpos0", float("nan"), "finite"),
    ("qvel0", 1e300, "outside"),
    ("qvel0", True, "must be a number"),
    ("qpos0", "x", "must be a number"),
])
def test_bad_numbers_in_the_state_are_refused(good, capsys, field, value, needle):
    folder, d = good
    v = list(d[field])
    v[3] = value
    p = _write(folder, "bad-state.json", {**d, field: v})
    msg = _refused(["bowl", "replay", p], capsys, f"{field}[3]", needle)
    assert "DIFFERENT" not in msg
    assert not Path("MUJOCO_LOG.TXT").exists()


def test_wrong_lengths_are_refused_against_the_scene(good, capsys):
    folder, d = good
    p = _write(folder, "short.json", {**d, "qpos0": d["qpos0"][:3]})
    _refused(["bowl", "replay", p], capsys, "qpos0", "nq 77")
    _refused(["render", p, "-o", folder / "x.png", "--still", "0"], capsys, "qpos0", "nq 77")


def test_fifo_and_directory_are_refused_without_opening(good, tmp_path, capsys):
    folder, d = good
    fifo = tmp_path / "pipe.json"
    os.mkfifo(fifo)
    _refused(["bowl", "replay", fifo], capsys, "not a regular file")   # would block forever if opened
    os.mkfifo(folder / "pipe.xml")
    try:
        p = _write(folder, "fifo-scene.json", {**d, "scene": "pipe.xml"})
        _refused(["bowl", "replay", p], capsys, "scene", "not a regular file")
        _refused(["render", p, "-o", folder / "x.png", "--still", "0"], capsys, "not a regular file")
    finally:
        os.unlink(folder / "pipe.xml")
    (tmp_path / "dir.json").mkdir()
    _refused(["bowl", "replay", tmp_path / "dir.json"], capsys, "directory")


# --- the gate: the scene path -----------------------------------------------------------------

@pytest.mark.parametrize("scene", ["/etc/passwd", "../scene.xml", "../../../../../../etc/hostname"])
def test_scene_outside_the_shot_folder_is_refused(good, capsys, scene):
    folder, d = good
    sub = folder / "sub"
    sub.mkdir(exist_ok=True)
    p = _write(sub, "escape.json", {**d, "scene": scene})
    _refused(["bowl", "replay", p], capsys, "scene", "outside the file's own folder")
    _refused(["render", p, "-o", folder / "x.png", "--still", "0"], capsys, "outside the file's own folder")


def test_a_link_out_of_the_folder_is_refused(good, tmp_path, capsys):
    folder, d = good
    (tmp_path / "in").mkdir()
    os.symlink(folder / "scene.xml", tmp_path / "in" / "scene.xml")
    p = _write(tmp_path / "in", "shot.json", d)
    _refused(["bowl", "replay", p], capsys, "outside the file's own folder")


def test_the_shipped_scene_may_be_named_from_anywhere(good, tmp_path, capsys):
    _, d = good
    p = _write(tmp_path, "shipped.json", {**d, "scene": str(deckfile.SHIPPED_SCENE)})
    rc, _ = _main(["bowl", "replay", p], capsys)
    assert rc == 0


@pytest.mark.parametrize("xml, needle", [
    ("<mujoco><worldbody><garbage", "cannot load"),
    ('<mujoco><include file="/etc/passwd"/></mujoco>', "reads other files"),
    ('<mujoco><worldbody><body><freejoint name="ball_free"/><geom size="1"/></body></worldbody></mujoco>',
     "not a bowling scene"),
])
def test_scenes_that_are_not_bowling_scenes_are_refused(good, tmp_path, capsys, xml, needle):
    _, d = good
    (tmp_path / "s.xml").write_text(xml)
    p = _write(tmp_path, "s.json", {**d, "scene": "s.xml"})
    _refused(["bowl", "replay", p], capsys, "scene", needle)
    _refused(["render", p, "-o", tmp_path / "x.png", "--still", "0"], capsys, needle)


# --- MuJoCo's warnings ------------------------------------------------------------------------

def test_mujoco_warnings_are_errors_and_leave_no_log(good, tmp_path, monkeypatch):
    """A bounded but violent state (every pin thrown at 1,000 m/s) makes MuJoCo warn or fail;
    nbst says so in one error and MuJoCo writes no MUJOCO_LOG.TXT into the current folder."""
    folder, d = good
    monkeypatch.chdir(tmp_path)
    model = mujoco.MjModel.from_xml_path(str(folder / "scene.xml"))
    qvel = [1000.0] * model.nv
    try:
        pins = deckfile.replay(model, d["qpos0"], qvel, 0.2)
    except MujocoError as e:
        assert str(e).startswith("MuJoCo warned")
    else:
        assert all(1 <= n <= 10 for n in pins)           # no warning: then the replay was a replay
    with pytest.raises(MujocoError, match="not finite"):
        deck.replay_final_qpos(model, [float("nan")] * model.nq, [0.0] * model.nv, 0.01)
    assert not (tmp_path / "MUJOCO_LOG.TXT").exists()


def test_warning_hook_turns_a_warning_into_an_error_and_is_restored():
    before = mujoco.get_mju_user_warning()
    with pytest.raises(MujocoError, match="MuJoCo warned: boom"):
        with mjrunner.mujoco_warnings_raise() as got:
            got.append("boom")
    assert mujoco.get_mju_user_warning() == before


# --- atlas --from -------------------------------------------------------------------------------

def test_atlas_from_never_copies_a_file_it_has_not_parsed(tmp_path, capsys):
    src = tmp_path / "src"
    src.mkdir()
    secret = tmp_path / "secret.txt"
    secret.write_text("not a scene\n")
    atlas = json.loads((SHIPPED / "atlas.json").read_text())
    atlas["shots"] = atlas["shots"][:3]
    for scene, needle in ((str(secret), "outside the file's own folder"), ("../secret.txt", "outside"),
                          ("notes.xml", "cannot load")):
        (src / "notes.xml").write_text("not a scene\n")
        a = _write(src, "atlas.json", {**atlas, "scene": scene})
        out = tmp_path / "out"
        _refused(["bowl", "atlas", "--out-dir", out, "--from", a, "--max-rollouts", "0", "-q"], capsys,
                 "--from", needle)
        assert not (out / "scene.xml").exists() and not list(out.glob("subset-*.json"))


def test_atlas_from_checks_every_shot_before_writing(tmp_path, capsys):
    src = tmp_path / "src"
    src.mkdir()
    shutil.copyfile(SHIPPED / "scene.xml", src / "scene.xml")
    atlas = json.loads((SHIPPED / "atlas.json").read_text())
    shots = atlas["shots"][:3]
    shots[2] = {**shots[2], "qvel0": shots[2]["qvel0"][:5]}
    a = _write(src, "atlas.json", {**atlas, "shots": shots})
    out = tmp_path / "out"
    _refused(["bowl", "atlas", "--out-dir", out, "--from", a, "--max-rollouts", "0", "-q"], capsys,
             "shots[2].qpos0/shots[2].qvel0")
    assert not list(out.glob("subset-*.json"))


def test_atlas_from_the_shipped_atlas_unpacks_it(tmp_path, capsys):
    out = tmp_path / "out"
    rc, _ = _main(["bowl", "atlas", "--out-dir", out, "--from", SHIPPED / "atlas.json", "--max-rollouts", "0",
                   "--no-robustness", "-q"], capsys)
    assert rc == 0
    assert (out / "scene.xml").read_bytes() == (SHIPPED / "scene.xml").read_bytes()
    assert len(list(out.glob("subset-*.json"))) == json.loads((SHIPPED / "atlas.json").read_text())["subsets"]
    assert not list(out.glob(".*partial*"))


def test_load_atlas_checks_shapes_and_duplicates(tmp_path):
    shutil.copyfile(SHIPPED / "scene.xml", tmp_path / "scene.xml")
    atlas = json.loads((SHIPPED / "atlas.json").read_text())
    a = _write(tmp_path, "a.json", {**atlas, "shots": [atlas["shots"][0], atlas["shots"][0]]})
    with pytest.raises(deckfile.ThrowFileError, match=r"shots\[1\]\.down"):
        deckfile.load_atlas(a)
    a = _write(tmp_path, "a.json", {**atlas, "shots": [{**atlas["shots"][0], "duration": 1e9}]})
    with pytest.raises(deckfile.ThrowFileError, match=r"shots\[0\]\.duration"):
        deckfile.load_atlas(a)


# --- render and plot on shot files ------------------------------------------------------------

@pytest.mark.parametrize("flag, value, needle", [
    ("--fps", "nan", "--fps"), ("--fps", "1e9", "--fps"), ("--fps", "-5", "--fps"),
    ("--still", "nan", "--still"), ("--still", "1e9", "--still"), ("--still", "-5", "--still"),
])
def test_render_shot_flags_have_a_domain(good, tmp_path, capsys, flag, value, needle):
    folder, _ = good
    out = tmp_path / ("x.png" if flag == "--still" else "x.mp4")
    _refused(["render", folder / "shot.json", "-o", out, flag, value], capsys, needle, "must")
    assert not out.exists()


def test_render_shot_refuses_disk_only_flags(good, tmp_path, capsys):
    folder, _ = good
    _refused(["render", folder / "shot.json", "-o", tmp_path / "x.mp4", "--trails", "--view", "2d"], capsys,
             "--trails", "--view", "disk problems only")


def test_render_sniffs_json_without_reading_it_whole(tmp_path, capsys):
    deep = _write(tmp_path, "deep.json", "[" * 200000 + "]" * 200000)
    sol = _write(tmp_path, "sol.json", "{}")
    rc, err = _main(["render", deep, sol, "-o", tmp_path / "x.mp4"], capsys)
    assert rc == 2 and err and "Traceback" not in "\n".join(err)


def test_plot_problem_says_it_is_a_bowling_shot(good, tmp_path, capsys):
    folder, _ = good
    _refused(["plot", "problem", folder / "shot.json", "-o", tmp_path / "p.png"], capsys,
             "this is a bowling throw file")
    _refused(["plot", "problem", SHIPPED / "atlas.json", "-o", tmp_path / "p.png"], capsys,
             "this is a bowling atlas file")


# --- bowl solve --leave -----------------------------------------------------------------------

def test_leave_means_the_pins_left_standing():
    from nbst.cli.bowl import args as bowl_args

    assert bowl_args.leave("7,10") == pinfall.mask_from_pins([1, 2, 3, 4, 5, 6, 8, 9])
    assert bowl_args.leave("none") == 1023 and bowl_args.pins_down("strike") == 1023
    import argparse

    with pytest.raises(argparse.ArgumentTypeError, match="gutter ball"):
        bowl_args.leave("1,2,3,4,5,6,7,8,9,10")


def test_solve_leave_answers_from_the_shipped_atlas(tmp_path, capsys):
    out = tmp_path / "split.json"
    rc, err = _main(["bowl", "solve", "--leave", "7,10", "-o", out, "--seed", "1", "--jobs", "1",
                     "--no-robustness"], capsys)
    assert rc == 0 and "shipped atlas" in err[-1]
    d = json.loads(out.read_text())
    assert d["down"] == [1, 2, 3, 4, 5, 6, 8, 9] and d["search"]["leave"] == [7, 10]
    assert d["search"]["from_atlas"] is True and d["search"]["rollouts"] == 1
    atlas = json.loads((SHIPPED / "atlas.json").read_text())
    same = next(s for s in atlas["shots"] if s["down"] == d["down"])
    assert d["qpos0"] == same["qpos0"] and d["qvel0"] == same["qvel0"]   # the atlas's throw, bit for bit
    rc, _ = _main(["bowl", "replay", out], capsys)
    assert rc == 0
