"""One writer for every output file: every command that writes, pointed at a symbolic link, a FIFO,
a device or a folder, refuses in one line (exit 2) and leaves what is there, and what a link points
to, as it was (issue 35: ``plot -o link.png`` wrote the PNG into the link's target).

To cover a new command that writes, add a row to :data:`WRITERS`.
"""
from __future__ import annotations

import json
import os
import stat

import pytest

from nbst.cli import main

#: Every command that writes a file: (id, arguments, output). In the arguments ``{out}`` is the
#: output file's path and ``{dir}`` the first folder of ``output`` (a command's ``--out-dir``);
#: ``{sol}`` is a solution of over5 and ``{crash}`` a crash file (one rollout of the t-bone script).
#: ``output`` is the output's path in the scratch folder. The commands run with small budgets: they
#: must refuse before or instead of writing, whatever the work.
WRITERS = [
    ("plot-problem", ["plot", "problem", "over5", "-o", "{out}"], "fig.png"),
    ("plot-trajectories", ["plot", "trajectories", "over5", "{sol}", "-o", "{out}"], "fig.svg"),
    ("render-mp4", ["render", "over5", "{sol}", "-o", "{out}", "--size", "64x64", "--fps", "4"], "v.mp4"),
    ("render-gif", ["render", "over5", "{sol}", "-o", "{out}", "--size", "64x64", "--fps", "4"], "v.gif"),
    ("render-still", ["render", "over5", "{sol}", "--still", "0", "-o", "{out}"], "f.png"),
    ("validate", ["validate", "over5", "{sol}", "--out-dir", "{dir}", "--timestep", "0.002"], "rep/report.html"),
    ("mjcf", ["mjcf", "over5", "{sol}", "-o", "{out}"], "scene.xml"),
    ("generate", ["generate", "--planted", "3", "--seed", "1", "-o", "{out}"], "p.json"),
    ("generate-solution", ["generate", "--planted", "3", "--seed", "1", "-o", "p.json", "--solution", "{out}"],
     "s.json"),
    ("generate-formation", ["generate", "--targets-from", "hi", "--disks", "20", "--seed", "1", "-o", "{out}"],
     "f.json"),
    ("solve", ["solve", "over5", "-o", "{out}", "--max-trials", "50", "--jobs", "1", "--seed", "1"], "sol.json"),
    ("experiment", ["experiment", "curves", "over5", "--runs", "1", "--max-trials", "50", "--jobs", "1",
                    "--out-dir", "{dir}"], "exp/curves-over5.csv"),
    ("gallery", ["gallery", "diamond-s14-tiny", "--no-search", "--out-dir", "{dir}"],
     "gal/diamond-s14-tiny/scene.xml"),
    ("bowl-solve", ["bowl", "solve", "--leave", "7,10", "-o", "{out}", "--seed", "1"], "shot.json"),
    ("bowl-throw-still", ["bowl", "throw", "--board", "10", "--at", "arrows", "--still", "{out}"], "t.png"),
    ("bowl-pocket", ["bowl", "pocket", "--samples", "1", "--boards", "17.5:17.5:1", "--angles", "6:6:1", "-o", "{out}"],
     "pocket.png"),
    ("bowl-throw-json", ["bowl", "throw", "--board", "10", "--at", "arrows", "-o", "{out}"], "t.json"),
    ("bowl-throw-video", ["bowl", "throw", "--board", "10", "--at", "arrows", "--video", "{out}", "--size", "64x64",
                          "--fps", "4"], "t.mp4"),
    ("bowl-frame", ["bowl", "frame", "--board", "10", "--at", "arrows", "-o", "{out}"], "frame.json"),
    ("crash-solve", ["crash", "solve", "t-bone", "-o", "{out}", "--max-rollouts", "8", "--jobs", "1", "--seed", "1"],
     "crash.json"),
    ("crash-reconstruct", ["crash", "reconstruct", "crossing-case", "-o", "{out}", "--max-rollouts", "8", "--jobs",
                           "1", "--seed", "1"], "rec.json"),
    ("crash-probability", ["crash", "probability", "{crash}", "--samples", "2", "--jobs", "1", "-o", "{out}"],
     "prob.json"),
    ("render-crash-mp4", ["render", "{crash}", "-o", "{out}", "--size", "64x64", "--fps", "4"], "crash.mp4"),
    ("render-crash-gif", ["render", "{crash}", "-o", "{out}", "--size", "64x64", "--fps", "4"], "crash.gif"),
    ("render-crash-still", ["render", "{crash}", "--still", "0", "-o", "{out}"], "crash.png"),
    ("crash-report", ["crash", "report", "{crash}", "-o", "{out}"], "report.html"),
]
#: What may be at the output path, and the word the refusal must use for it.
KINDS = {"link-to-file": "symbolic link", "dangling-link": "symbolic link", "fifo": "FIFO", "folder": "folder"}
OLD = b"the user's own file, not nbst's\n"


@pytest.fixture(scope="module")
def sol(tmp_path_factory):
    d = tmp_path_factory.mktemp("sol")
    v = [[0.0, 0.0]] * 5
    (d / "sol.json").write_text(json.dumps({"problem": "over5", "velocities": v}))
    return str(d / "sol.json")


@pytest.fixture(scope="module")
def crash(tmp_path_factory):
    """A crash file as ``nbst crash solve`` writes one: one seeded rollout of the built-in t-bone
    script (what it meets does not matter here; the commands must refuse before they replay it)."""
    pytest.importorskip("mujoco")
    import numpy as np

    from nbst.models.crash import crashfile, run, space
    from nbst.models.crash.script import load_script

    s = load_script("t-bone")
    sp = space.space_of(s)
    intents = sp.intents(np.random.default_rng(3).random((1, sp.dim)))
    R = run.CrashRunner(s, jobs=1, batch=1)
    res = R.run(intents)
    d = crashfile.crash_dict(s, R.xml, R.model, intents[0], res.qpos0[0], res.qvel0[0], res.controls[0],
                             res.final_qpos[0], res.outcomes[0], seed=3, period_steps=R.period)
    R.close()
    f = tmp_path_factory.mktemp("crash") / "t-bone.json"
    f.write_text(json.dumps(d, allow_nan=False))
    return str(f)


def _plant(path, kind: str, elsewhere):
    """Make ``path`` a ``kind``; returns what must stay untouched: {path: bytes or None (must not exist)}."""
    path.parent.mkdir(parents=True, exist_ok=True)
    if kind == "link-to-file":
        elsewhere.write_bytes(OLD)
        path.symlink_to(elsewhere)
        return {elsewhere: OLD}
    if kind == "dangling-link":
        path.symlink_to(elsewhere)
        return {elsewhere: None}
    if kind == "fifo":
        os.mkfifo(path)
        return {}
    path.mkdir()
    (path / "keep.txt").write_bytes(OLD)
    return {path / "keep.txt": OLD}


def _mode(path) -> int:
    return os.lstat(path).st_mode


@pytest.mark.parametrize("kind", list(KINDS))
@pytest.mark.parametrize("cmd,argv,output", WRITERS, ids=[w[0] for w in WRITERS])
def test_no_command_writes_through_a_link_or_into_a_special_file(cmd, argv, output, kind, tmp_path, sol, capsys,
                                                                 monkeypatch, request):
    monkeypatch.chdir(tmp_path)
    out = tmp_path / output
    elsewhere = tmp_path / "elsewhere" / "notes.conf"
    elsewhere.parent.mkdir()
    keep = _plant(out, kind, elsewhere)
    before = _mode(out)
    folder = str(tmp_path / output.split("/")[0])  # {dir}: the output's first folder
    crash = request.getfixturevalue("crash") if "{crash}" in argv else ""
    args = [a.replace("{out}", str(out)).replace("{sol}", sol).replace("{dir}", folder).replace("{crash}", crash)
            for a in argv]
    rc = main(args)
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2, (rc, err)
    assert err and "Traceback" not in "\n".join(err)
    assert KINDS[kind] in err[-1] and str(out.name) in err[-1], err[-1]
    assert _mode(out) == before  # still the link, FIFO or folder it was
    for p, content in keep.items():
        if content is None:
            assert not os.path.lexists(p), f"{p} was created through the dangling link"
        else:
            assert p.read_bytes() == content
    leftovers = [f.name for f in out.parent.iterdir() if ".partial-" in f.name]
    assert not leftovers


def test_a_device_is_refused_and_left_a_device(capsys):
    assert main(["generate", "--planted", "2", "--seed", "1", "-o", os.devnull]) == 2
    assert "character device" in capsys.readouterr().err
    assert stat.S_ISCHR(os.lstat(os.devnull).st_mode)


def test_a_folder_that_is_a_link_is_written_into(tmp_path, capsys):
    """A link on the way to the output (an output folder on another disk) is fine: the file is
    written in the folder it leads to, as a regular file."""
    real = tmp_path / "big-disk" / "out"
    real.mkdir(parents=True)
    (tmp_path / "out").symlink_to(real)
    assert main(["generate", "--planted", "2", "--seed", "1", "-o", str(tmp_path / "out" / "p.json"), "-q"]) == 0
    assert stat.S_ISREG(os.lstat(real / "p.json").st_mode)


def test_a_link_that_appears_during_the_write_is_replaced_not_followed(tmp_path):
    """The check runs before the work; a link made at the path while the work ran is replaced by
    the rename (the file it points to is never written)."""
    from nbst.outputs import atomic_path

    target = tmp_path / "victim.conf"
    target.write_bytes(OLD)
    out = tmp_path / "out.txt"
    with atomic_path(out) as tmp:
        open(tmp, "w").write("new")
        out.symlink_to(target)
    assert target.read_bytes() == OLD
    assert stat.S_ISREG(os.lstat(out).st_mode) and out.read_text() == "new"
