"""A crash for MuJoCo users: ``nbst mjcf CRASH.json -o crash.xml`` writes one MJCF file that plays it.

The file is the crash's own scene (``scene_xml``, every number exact) with what a plain
``mj_step`` loop needs to play the recorded motion, nothing to read from the crash file:

* keyframe ``start``: the initial state (``qpos0``, ``qvel0``) and the first row of controls;
* custom numerics (``model.numeric(NAME).data``, float64, every number exact):
  ``crash_controls`` the realised controls, one row of ``model.nu`` per period (row-major),
  ``crash_period_steps`` the steps each row holds, ``crash_nstep`` the steps in all (the last
  row holds for what is left);
* an XML comment above them that says the same.

The loop (docs/crash.md, "Play the export in MuJoCo"; tests/test_crash_export.py runs it and
finds the final state equal, bit for bit, to ``nbst crash replay``'s)::

    m = mujoco.MjModel.from_xml_path("crash.xml"); d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, m.key("start").id)
    rows = m.numeric("crash_controls").data.reshape(-1, m.nu)
    period, nstep = (int(m.numeric(k).data[0]) for k in ("crash_period_steps", "crash_nstep"))
    for k in range(nstep):
        d.ctrl[:] = rows[k // period]
        mujoco.mj_step(m, d)

MuJoCo's viewer alone (``python -m mujoco.viewer``, key ``start``) holds the first row of
controls throughout, so it does not play the crash: run the loop under
``mujoco.viewer.launch_passive`` to watch it.

Compute only: the CLI writes the text.
"""
from __future__ import annotations

from nbst.models.crash.crashfile import CrashFileError, controls_array

__all__ = ["KEY", "NUMERICS", "export_xml"]

#: The keyframe holding the initial state.
KEY = "start"
#: The custom numerics the file carries, in the order written.
NUMERICS = ("crash_nstep", "crash_period_steps", "crash_controls")


def _num(x: float) -> str:
    """Shortest text that reads back as the same float64 (MuJoCo parses numerics with strtod)."""
    t = repr(float(x))
    return t[:-2] if t.endswith(".0") else t


def export_xml(d: dict) -> str:
    """The crash's scene with its initial state and recorded controls, for a plain mj_step loop.

    Args:
        d: a checked crash dict (:func:`nbst.models.crash.crashfile.load`).

    Returns:
        The MJCF text: ``d["scene_xml"]`` with keyframe :data:`KEY` and the custom numerics
        :data:`NUMERICS` (module docstring), every number exact.

    Raises:
        CrashFileError: the scene text does not end with ``</mujoco>``, or the controls do not
            cover ``nstep`` steps.
    """
    xml = d["scene_xml"].rstrip()
    if not xml.endswith("</mujoco>"):
        raise CrashFileError("scene_xml: does not end with </mujoco>")
    rows = controls_array(d)
    period, nstep = int(d["controls"]["period_steps"]), int(d["nstep"])
    if not (period >= 1 and len(rows) == -(-nstep // period)):
        raise CrashFileError(f"controls: {len(rows)} rows of {period} steps do not cover nstep = {nstep}")
    custom = (
        "  <!-- nbst crash export: reset to key \"start\", then for k in range(crash_nstep): ctrl = row\n"
        "       k // crash_period_steps of crash_controls (nu numbers a row); mj_step. -->\n"
        "  <custom>\n"
        f'    <numeric name="crash_nstep" data="{nstep}"/>\n'
        f'    <numeric name="crash_period_steps" data="{period}"/>\n'
        f'    <numeric name="crash_controls" data="{" ".join(_num(x) for x in rows.ravel())}"/>\n'
        "  </custom>\n")
    key = (f'  <keyframe>\n    <key name="{KEY}" time="0" qpos="{" ".join(_num(x) for x in d["qpos0"])}" '
           f'qvel="{" ".join(_num(x) for x in d["qvel0"])}" ctrl="{" ".join(_num(x) for x in rows[0])}"/>\n'
           f'  </keyframe>\n')
    return xml[: -len("</mujoco>")] + custom + key + "</mujoco>\n"
