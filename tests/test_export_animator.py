"""What an animator taking motion out of every world met (docs/export.md; issue 46's "motion out"):
each case a test that failed before its fix."""
from __future__ import annotations

import json

import numpy as np
import pytest

from nbst.cli.main import main
from nbst.export.gltf import Body, BodyMotion, turn_note
from nbst.export.worlds import file_motion
from tests.test_export_gltf import files  # noqa: F401  (each world's file, as there)


def _spin(step_deg: float, keys: int = 5) -> BodyMotion:
    """One body turning ``step_deg`` about z between keyframes, and a still floor."""
    a = np.radians(step_deg) * np.arange(keys) / 2
    quat = np.zeros((keys, 2, 4))
    quat[:, 0, 0] = 1.0
    quat[:, 1, 0], quat[:, 1, 3] = np.cos(a), np.sin(a)
    return BodyMotion([Body("floor", moves=False), Body("wheel")], np.arange(keys) / 24.0, np.zeros((keys, 2, 3)),
                      quat)


def test_a_spin_near_half_a_turn_between_keyframes_is_noted_with_the_fps_that_plays_it():
    """At 24 fps a wheel at 180 deg a keyframe plays either way, and past it backwards; nothing said before."""
    note = turn_note(_spin(170.0), 24.0)
    assert note.startswith("wheel turns 170 deg or more") and "--fps 91 or more" in note
    assert turn_note(_spin(30.0), 24.0) == ""


def test_a_spin_the_keyframes_alias_is_noted_from_the_whole_recording():
    """A wheel at a full turn (360 deg) between keyframes looks still in them; at 350 deg it looks
    like 10 deg back. The recording's fastest turn (every step) is what the note reads (an animator
    saw a foul-line ball's 4,289 deg/s noted only as pin6's 154 deg at 12 fps)."""
    from dataclasses import replace

    import mujoco

    from nbst.export.mjbodies import qpos_motion

    aliased = _spin(350.0)   # between keyframes it reads as a 10 deg turn
    assert turn_note(aliased, 24.0) == ""
    rate = np.array([0.0, 350.0 * 24.0])
    note = turn_note(replace(aliased, turn_rate=rate), 24.0)
    assert note.startswith("wheel turns 350 deg or more") and "--fps 187 or more" in note
    # from recorded states: a free body spun at 10 turns a second, recorded every 1 ms, keyed at 10 fps
    m = mujoco.MjModel.from_xml_string('<mujoco><worldbody><body name="wheel"><freejoint/>'
                                       '<geom type="cylinder" size="0.3 0.1"/></body></worldbody></mujoco>')
    t = np.arange(1001) * 1e-3
    a = 2 * np.pi * 10 * t
    q = np.zeros((len(t), 7))
    q[:, 3], q[:, 6] = np.cos(a / 2), np.sin(a / 2)
    motion = qpos_motion(m, q, t, 10.0)
    assert motion.turn_rate is not None and motion.turn_rate[1] == pytest.approx(3600.0, rel=1e-3)
    assert turn_note(motion, 10.0).startswith("wheel turns 360 deg or more")


def test_a_crashs_vehicles_are_nodes_by_the_names_its_file_gives_them(files):  # noqa: F811
    d = json.loads(files["crash"].read_text())
    names = [b.name for b in file_motion(files["crash"], fps=10)[1].bodies]
    for v in d["vehicles"]:
        assert v["name"] in names and f"{v['name']}_wheel_fl" in names
        assert v["body"] not in names and not any(n.startswith(v["body"] + "_") for n in names)


def test_a_throws_phases_file_is_told_it_holds_no_motion(tmp_path, capsys):
    """`bowl throw -o` writes the ball's phases; export read it as a 2D solution ("names no problem")."""
    ph = tmp_path / "bt.json"
    assert main(["bowl", "throw", "--board", "10", "--at", "arrows", "--mph", "17", "--rpm", "300", "-o", str(ph)]) == 0
    capsys.readouterr()
    assert main(["export", str(ph), "--gltf", str(tmp_path / "x.glb")]) == 2
    err = capsys.readouterr().err
    assert "the ball's phases from `nbst bowl throw -o`, no motion" in err and "bowl frame" in err
    assert main(["render", str(ph), "-o", str(tmp_path / "x.mp4")]) == 2
    err = capsys.readouterr().err
    assert "holds a throw's phases" in err and "is a problem" not in err
    assert not list(tmp_path.glob("x.*"))


def test_render_takes_a_2d_solution_alone_as_export_does(files, tmp_path, capsys):  # noqa: F811
    """`nbst render sol.json -o x.png` said "sol.json is a problem: give its SOLUTION"."""
    out = tmp_path / "x.png"
    assert main(["render", str(files["disks"]), "-o", str(out), "--still", "0", "--size", "64x48"]) == 0
    assert out.stat().st_size > 0


def test_a_solution_naming_a_problem_not_here_says_so_and_names_the_flag(tmp_path, capsys):
    sol = tmp_path / "p-sol.json"
    sol.write_text(json.dumps({"problem": "planted-n200-k0-s1", "velocities": [[0.0, 0.0]]}))
    assert main(["export", str(sol), "--gltf", str(tmp_path / "x.glb")]) == 2
    err = capsys.readouterr().err
    assert f"{sol}: problem: names 'planted-n200-k0-s1'" in err and "--problem FILE" in err


@pytest.mark.slow
def test_bowl_replay_refuses_a_video_path_before_it_replays(files, tmp_path, capsys):  # noqa: F811
    """`bowl replay throw.json --video FOLDER.mp4` printed the replay's pins, then refused."""
    (tmp_path / "v.mp4").mkdir()
    assert main(["bowl", "replay", str(files["lane"]), "--video", str(tmp_path / "v.mp4")]) == 2
    out = capsys.readouterr()
    assert "is a folder" in out.err and "pins down" not in out.out


def test_realtime_videos_line_up_with_the_gltfs_keyframes(files, tmp_path, capsys):  # noqa: F811
    """A crash video slows 4x at its impacts, `--clean` too: a clean plate did not line up with the glTF."""
    import imageio.v3 as iio

    from nbst.render.crash.video import load

    duration = load(files["crash"])[3].duration
    counts = {}
    for flags in ((), ("--realtime",)):
        out = tmp_path / f"c{len(flags)}.mp4"
        assert main(["render", str(files["crash"]), "-o", str(out), "--clean", "--size", "64x48", "--fps", "10",
                     "--hold", "0", "-q", *flags]) == 0
        counts[flags] = sum(1 for _ in iio.imiter(out))
    glb = tmp_path / "c.glb"
    assert main(["export", str(files["crash"]), "--gltf", str(glb), "--fps", "10", "-q"]) == 0
    keys = len(file_motion(files["crash"], fps=10)[1].times)
    assert counts[("--realtime",)] == keys == int(np.floor(duration * 10 + 1e-9)) + 1  # one frame per keyframe
    assert counts[()] > keys  # slowed at the impacts
