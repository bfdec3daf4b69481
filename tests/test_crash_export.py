"""A crash's ``nbst mjcf`` export carries its recorded controls, and docs/crash.md's loop plays it.

docs/crash.md, "Play the export in MuJoCo", shows the plain MuJoCo loop; these tests run that very
block (its ``python -m nbst.cli mjcf`` call in-process) on a crash of a built-in script and find
the final state equal, bit for bit, to nbst's own replay of the crash file (``crashfile.replay``:
the same model, the same initial state, the same controls at every step, the same ``mj_step``,
so no tolerance is needed and any difference is a bug).
"""
import json
import re
import subprocess
from pathlib import Path

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")

from nbst.cli.main import main  # noqa: E402
from nbst.models.crash import crashfile, export, run, script, space  # noqa: E402

DOC = Path(__file__).resolve().parents[1] / "docs" / "crash.md"


def _doc_loop() -> str:
    text = DOC.read_text(encoding="utf-8")
    section = text.split("## Play the export in MuJoCo\n", 1)[1].split("\n## ", 1)[0]
    return re.search(r"```python\n(.*?)```", section, re.S).group(1)


def _crash_file(folder: Path, s, seed: int) -> Path:
    """A crash file (``nbst crash solve``'s content) of one rollout of ``s`` with intents drawn by ``seed``."""
    sp = space.space_of(s)
    R = run.CrashRunner(s, jobs=1, batch=1)
    intents = sp.intents(np.random.default_rng(seed).random((1, sp.dim)))
    res = R.run(intents)
    d = crashfile.crash_dict(s, R.xml, R.model, intents[0],
                             res.qpos0[0], res.qvel0[0], res.controls[0], res.final_qpos[0], res.outcomes[0],
                             seed=seed, period_steps=R.period)
    f = folder / "tbone.json"
    f.write_text(json.dumps(d))
    return f


def _play_the_doc_loop(folder: Path, monkeypatch) -> dict:
    """Run docs/crash.md's block in ``folder``; its ``python -m nbst.cli ...`` runs in-process."""
    def cli(argv, check=False, **kw):
        assert argv[1:3] == ["-m", "nbst.cli"], argv
        rc = main(argv[3:])
        assert rc == 0 or not check
        return subprocess.CompletedProcess(argv, rc)

    monkeypatch.chdir(folder)
    monkeypatch.setattr(subprocess, "run", cli)
    ns: dict = {}
    exec(compile(_doc_loop(), str(DOC), "exec"), ns)  # noqa: S102: the doc's own block
    return ns


def _nbst_replay(f: Path) -> np.ndarray:
    d, s, model = crashfile.load(f)
    return crashfile.replay(d, s, model)[0]


@pytest.mark.slow  # 2-5 s (3,000 steps three times); the next test runs the same loop in the fast tier
def test_the_docs_loop_plays_a_built_in_crash_as_nbst_replays_it(tmp_path, monkeypatch):
    f = _crash_file(tmp_path, script.load_script("t-bone"), seed=1)
    ns = _play_the_doc_loop(tmp_path, monkeypatch)  # it asserts final_qpos itself
    assert ns["d"].time > 0 and int(ns["nstep"]) == json.loads(f.read_text())["nstep"]
    assert np.array_equal(ns["d"].qpos, _nbst_replay(f))  # bit for bit: the same mj_step on the same inputs
    assert not np.array_equal(ns["d"].qpos, ns["m"].key("start").qpos)  # it moved (3000 steps of 2 ms)


SHORT = {
    "kind": "nbst-crash-script", "name": "short",
    "road": {"layout": "intersection", "width": 7, "length": 80},
    "duration": 1.005,  # 502 steps of 2 ms: the last 10-step row of controls holds for 2
    "vehicles": [
        {"name": "A", "type": "sedan", "start": {"x": -22, "y": -1.75, "heading": 0}, "speed": [45, 55],
         "driver": {"aim": {"x": [0, 4], "y": -1.75}, "arrive": [0.8, 1.0]}},
        {"name": "B", "type": "suv", "start": {"x": 1.75, "y": -22, "heading": 90}, "speed": [45, 55],
         "driver": {"aim": {"x": 1.75, "y": [-2, 2]}, "arrive": [0.8, 1.0]}},
    ],
}


def test_a_last_row_that_holds_for_fewer_steps_plays_exactly(tmp_path, monkeypatch):
    s = script.script_from_dict(json.loads(json.dumps(SHORT)), source="short")
    f = _crash_file(tmp_path, s, seed=2)
    d = json.loads(f.read_text())
    assert d["nstep"] % d["controls"]["period_steps"] != 0  # the case crash_nstep is there for
    ns = _play_the_doc_loop(tmp_path, monkeypatch)
    assert np.array_equal(ns["d"].qpos, _nbst_replay(f))
    m = ns["m"]
    assert int(m.numeric("crash_nstep").data[0]) == d["nstep"]
    assert np.array_equal(m.key("start").ctrl, d["controls"]["rows"][0])
    assert np.array_equal(m.numeric("crash_controls").data, np.ravel(d["controls"]["rows"]))  # exact


def test_the_export_refuses_controls_that_do_not_cover_the_steps(tmp_path):
    f = _crash_file(tmp_path, script.script_from_dict(json.loads(json.dumps(SHORT)), source="short"), seed=3)
    d = json.loads(f.read_text())
    d["controls"]["rows"] = d["controls"]["rows"][:-1]
    with pytest.raises(crashfile.CrashFileError, match="do not cover nstep"):
        export.export_xml(d)
