"""Exported scenes at full precision: a scene written by ``scene_xml`` (``nbst mjcf``) and loaded
with ``mujoco.MjModel.from_xml_path`` is the model compiled in memory, bit for bit."""
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))
from conftest import make_problem  # noqa: E402

mujoco = pytest.importorskip("mujoco")

from nbst import load_problem  # noqa: E402
from nbst.models.scene import build_model, build_spec, scene_xml  # noqa: E402

#: Model fields that must survive the file exactly: the keyframe, the disks' starts and bodies,
#: every contact parameter, the step, the targets.
FIELDS = ("key_qvel", "key_qpos", "key_time", "body_pos", "body_mass", "body_inertia", "geom_size", "geom_pos",
          "geom_solref", "geom_solimp", "geom_friction", "geom_margin", "geom_gap", "geom_rgba", "site_pos",
          "jnt_axis")


def _hard_case():
    """Starts, masses, radii and velocities that need all 17 significant digits."""
    rng = np.random.default_rng(11)
    starts = [[100 + 1 / 3, 200 + 0.1 + 0.2], [400 + rng.random(), 300 + rng.random()], [650.123456789012345, 450.0]]
    p = make_problem(starts, [10 + 1 / 7, 12.345678901234567, 9.87654321], box=(800.0, 600.0), t_final=3.0,
                     masses=[1 / 3, 2.718281828459045, 1.0], cueable=[True, True, False],
                     targets=[[700 + 1 / 9, 100.0], [123.456789, 543.21], [50.5, 50.25]])
    v = np.array([[1 / 3, 0.1 + 0.2], [rng.normal() * 100, rng.normal() * 100], [0.0, 0.0]])
    return p, v


def _load(tmp_path, xml):
    path = tmp_path / "scene.xml"
    path.write_text(xml)
    return mujoco.MjModel.from_xml_path(str(path))


@pytest.mark.parametrize("timestep,unit", [(0.00025, 1e-3), (1 / 3000, 1e-3), (0.001, 0.01 / 3)])
def test_written_scene_is_the_in_memory_model_bit_for_bit(tmp_path, timestep, unit):
    p, v = _hard_case()
    mem = build_model(p, v, timestep=timestep, unit=unit)
    disk = _load(tmp_path, scene_xml(p, v, timestep=timestep, unit=unit))
    assert disk.opt.timestep == mem.opt.timestep == timestep
    for f in FIELDS:
        assert np.array_equal(getattr(disk, f), getattr(mem, f)), f
    # a cylinder site uses 2 of its 3 sizes: MuJoCo's writer omits the unused third (0 in memory)
    # and its reader fills in the default, so only the used two are compared
    assert np.array_equal(disk.site_size[:, :2], mem.site_size[:, :2])
    # back in problem units: qvel / unit is the solution's velocity and body_pos / unit the start to
    # within 1 ulp (x * u / u is not always x in floating point; measured: exact for most entries)
    qvel = disk.key_qvel[0].reshape(-1, 2) / unit
    assert np.all(np.abs(qvel - v) <= np.spacing(np.abs(v)))
    bodies = [mujoco.mj_name2id(disk, mujoco.mjtObj.mjOBJ_BODY, f"disk{i}") for i in range(p.n)]
    starts = disk.body_pos[bodies, :2] / unit
    assert np.all(np.abs(starts - p.start) <= np.spacing(np.abs(p.start)))


def test_six_digits_would_not_do(tmp_path):
    # the reason for the rewrite: MuJoCo's own writer moves the keyframe by ~1e-6 relative
    p, v = _hard_case()
    spec = build_spec(p, v)
    mem = spec.compile()
    raw = _load(tmp_path, spec.to_xml())
    assert not np.array_equal(raw.key_qvel, mem.key_qvel)
    assert np.abs(raw.key_qvel - mem.key_qvel).max() > 1e-12


def test_rewrite_changes_numbers_only(tmp_path):
    # same elements, same attributes, same order; only numeric values differ, and each by at most
    # the 6-digit rounding of MuJoCo's writer
    p, v = _hard_case()
    spec = build_spec(p, v)
    spec.compile()
    a = ET.fromstring(spec.to_xml())
    b = ET.fromstring(scene_xml(p, v))
    ea, eb = list(a.iter()), list(b.iter())
    assert [e.tag for e in ea] == [e.tag for e in eb]
    changed = 0
    for x, y in zip(ea, eb):
        assert list(x.attrib) == list(y.attrib)
        for k in x.attrib:
            if x.attrib[k] != y.attrib[k]:
                changed += 1
                old = np.array(x.attrib[k].split(), float)
                new = np.array(y.attrib[k].split(), float)
                assert old.shape == new.shape
                assert np.all(np.abs(old - new) <= 5e-6 * np.abs(new) + 1e-300), (x.tag, k)
    assert changed > 0


def test_gallery_scenes_are_full_precision():
    # the stored gallery scene of over5 loads as the model built from its problem and solution
    root = Path(__file__).resolve().parents[1] / "models" / "scenes" / "over5"
    if not (root / "scene.xml").exists():
        pytest.skip("no gallery in this checkout")
    from nbst.solution import load_solution
    p = load_problem(str(root / "problem.json"))
    v = load_solution(str(root / "solution.json"), p).velocities
    disk = mujoco.MjModel.from_xml_path(str(root / "scene.xml"))
    mem = build_model(p, v)
    for f in ("key_qvel", "body_pos", "body_mass", "geom_size", "geom_solref", "site_pos"):
        assert np.array_equal(getattr(disk, f), getattr(mem, f)), f
