"""step_aligned refuses, before any step and in one line naming it, a scene it does not model.

Aligned stepping is exact for elastic, frictionless impacts between bodies in free flight
(nbst.models.stepping, "Requirements"). A scene with gravity, friction, another integrator or
contact settings it does not model used to run to the end and return normally (a ball under
gravity fell to z = -46 m): now each such setting is named in one SceneNotSupported line and
the data is left as it was. The scenes nbst writes (``nbst mjcf``) pass, and so does a free
sphere, whose bounces between two walls this file checks against the exact answer.
"""
import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")

from nbst.errors import InputError  # noqa: E402
from nbst.models.scene import build_model, scene_xml  # noqa: E402
from nbst.models.stepping import SceneNotSupported, check_model, step_aligned, unsupported  # noqa: E402
from nbst.problem import load_problem  # noqa: E402


def _scene():
    p = load_problem("over5")
    return build_model(p, np.full((p.n, 2), 100.0) * np.asarray(p.cueable)[:, None])


def _refused(m, d, *words):
    """step_aligned refuses (m, d) with each of ``words`` in its one-line message and leaves d untouched."""
    q0, v0 = d.qpos.copy(), d.qvel.copy()
    with pytest.raises(SceneNotSupported) as e:
        step_aligned(m, d, 1.0)
    msg = str(e.value)
    assert "\n" not in msg and msg.startswith("step_aligned: ")
    for w in words:
        assert w in msg, (w, msg)
    assert d.time == 0.0 and np.array_equal(d.qpos, q0) and np.array_equal(d.qvel, v0)  # no step taken
    assert isinstance(e.value, InputError)
    return msg


def _disk_geom(m):
    return m.geom("disk0_collision").id


EDITS = {
    "gravity": lambda m: m.opt.gravity.__setitem__(slice(None), (0, 0, -9.81)),
    "integrator RK4": lambda m: setattr(m.opt, "integrator", int(mujoco.mjtIntegrator.mjINT_RK4)),
    "integrator IMPLICITFAST": lambda m: setattr(m.opt, "integrator", int(mujoco.mjtIntegrator.mjINT_IMPLICITFAST)),
    "friction: condim": lambda m: m.geom_condim.__setitem__(_disk_geom(m), 3),
    "margin or gap": lambda m: m.geom_margin.__setitem__(_disk_geom(m), 1e-3),
    "inelastic contacts": lambda m: m.geom_solref.__setitem__(_disk_geom(m), (0.02, 1.0)),
    "solimp": lambda m: m.geom_solimp.__setitem__(_disk_geom(m), (0.9, 0.95, 0.001, 0.5, 2)),
    "fluid forces": lambda m: setattr(m.opt, "density", 1.2),
    "contacts disabled": lambda m: setattr(m.opt, "disableflags", int(mujoco.mjtDisableBit.mjDSBL_CONTACT)),
    "contact override": lambda m: setattr(m.opt, "enableflags", int(mujoco.mjtEnableBit.mjENBL_OVERRIDE)),
    "joint damping": lambda m: m.dof_damping.__setitem__(0, 0.5),
    "joint stiffness": lambda m: m.jnt_stiffness.__setitem__(0, 10.0),
}


def test_the_scenes_nbst_writes_pass():
    m = _scene()
    assert unsupported(m, mujoco.MjData(m)) == []
    check_model(mujoco.MjModel.from_xml_string(scene_xml(load_problem("over5"))))  # the MJCF text too


@pytest.mark.parametrize("what", list(EDITS))
def test_each_unsupported_setting_is_refused_by_name(what):
    m = _scene()
    EDITS[what](m)
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    msg = _refused(m, d, what)
    if what in ("friction: condim", "margin or gap", "inelastic contacts", "solimp"):
        assert "'disk0_collision'" in msg  # the geom is named


def test_every_setting_is_named_in_one_line():
    m = _scene()
    for f in EDITS.values():
        f(m)
    d = mujoco.MjData(m)
    msg = _refused(m, d, *[w for w in EDITS if w != "integrator RK4"])
    assert msg.count("; ") >= len(EDITS) - 2  # one phrase each (the two integrators are one setting)


def test_the_falling_ball_of_the_issue_is_refused():
    # MuJoCo's defaults: gravity, condim 3, solref (0.02, 1), solimp (0.9, 0.95); no floor
    m = mujoco.MjModel.from_xml_string('<mujoco><worldbody><body name="ball" pos="0 0 1"><freejoint/>'
                                       '<geom name="ball" type="sphere" size="0.1"/></body></worldbody></mujoco>')
    _refused(m, mujoco.MjData(m), "gravity (0, 0, -9.81) m/s^2", "condim", "solref", "solimp", "'ball'")


ELASTIC = 'condim="1" solref="-1e6 0" solimp="0.9999 0.9999 0.001"'


def _xml(body: str, extra: str = "") -> str:
    return (f'<mujoco><option gravity="0 0 0" integrator="Euler" timestep="0.001"/>'
            f'<default><geom {ELASTIC}/></default><worldbody>'
            f'<geom name="left" type="box" pos="-1.1 0 0" size="0.1 1 1"/>'
            f'<geom name="right" type="box" pos="1.1 0 0" size="0.1 1 1"/>{body}</worldbody>{extra}</mujoco>')


BALL = '<body name="b" pos="0 0 0"><joint name="j" type="{}"{}/><geom name="g" type="{}" size="0.1 0.1 0.1" mass="1"/></body>'


@pytest.mark.parametrize("xml, words", [
    (_xml(BALL.format("hinge", ' axis="0 0 1"', "box")), ["hinge or ball joints 'j'"]),
    (_xml(BALL.format("ball", "", "box")), ["hinge or ball joints 'j'"]),
    (_xml(BALL.format("free", "", "box")), ["free joint 'j'"]),
    (_xml(BALL.format("slide", ' axis="1 0 0" range="-0.5 0.5" limited="true"', "sphere")), ["joint limits on 'j'"]),
    (_xml(BALL.format("slide", ' axis="1 0 0"', "sphere"), '<actuator><motor joint="j"/></actuator>'), ["actuators (1"]),
    (_xml(BALL.format("slide", ' axis="1 0 0"', "sphere") + '<body name="c" pos="0 0.5 0"><joint type="slide"/>'
          '<geom type="sphere" size="0.1"/></body>', '<equality><joint joint1="j"/></equality>'), ["equality constraints"]),
    (_xml(BALL.format("slide", ' axis="1 0 0"', "sphere"), '<contact><pair geom1="g" geom2="left"/></contact>'),
     ["explicit contact pairs"]),
])
def test_user_scenes_it_does_not_model_are_refused(xml, words):
    m = mujoco.MjModel.from_xml_string(xml)
    _refused(m, mujoco.MjData(m), *words)


def test_applied_forces_are_refused():
    m = mujoco.MjModel.from_xml_string(_xml(BALL.format("slide", ' axis="1 0 0"', "sphere")))
    d = mujoco.MjData(m)
    d.xfrc_applied[1, 0] = 1.0
    _refused(m, d, "data.xfrc_applied")


def test_a_spinning_free_sphere_between_two_walls_bounces_exactly():
    # a sphere of radius 0.1 from x = 0 at 2 m/s along x, spinning about all three axes; the walls'
    # faces at x = +-1, so it turns at x = +-0.9: the right wall at t = 0.45 s, the left at 1.35 s,
    # and at t = 2 s it is at x = 0.4 moving right (unfolded: a sawtooth of period 3.6 m). Fixed
    # steps of 1 ms err by up to |dv| h = 4 mm per bounce; aligned stepping by ~1e-12 m (asked: 1e-9).
    m = mujoco.MjModel.from_xml_string(_xml('<body name="b"><freejoint name="j"/>'
                                            '<geom name="g" type="sphere" size="0.1" mass="1"/></body>'))
    assert unsupported(m) == []
    d = mujoco.MjData(m)
    d.qvel[:] = (2.0, 0.0, 0.0, 3.0, -7.0, 5.0)
    stats = step_aligned(m, d, 2.0)
    s = (0.9 + 2.0 * 2.0) % 3.6  # unfold the bounces: a sawtooth of period 3.6 m over [-0.9, 0.9]
    x = s - 0.9 if s <= 1.8 else 2.7 - s
    assert stats.impacts == 2
    assert abs(d.qpos[0] - x) < 1e-9 and abs(d.qvel[0] - (2.0 if s <= 1.8 else -2.0)) < 1e-9
    assert np.abs(d.qpos[1:3]).max() < 1e-12 and np.allclose(d.qvel[3:], (3.0, -7.0, 5.0), rtol=0, atol=1e-12)
