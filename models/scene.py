"""MuJoCo scenes built with ``mujoco.MjSpec`` from a problem (and optionally its velocities).

Layout of a scene (problem units x ``unit`` metres; 1 unit = 1 mm by default):

* zero gravity, Euler integrator, timestep h (default 0.25 ms);
* a floor plane for looks (contype = conaffinity = 0: it touches nothing);
* four walls, boxes whose inner faces are the box edges x = 0, x = W, y = 0, y = H;
* disk i: body ``disk{i}`` at its start, slide joints ``disk{i}_x`` and
  ``disk{i}_y`` (so qpos = displacement from the start, qvel = velocity, m/s),
  a sphere collision geom of the disk's radius carrying the disk's mass, and a
  visual cylinder (a puck, contype = conaffinity = 0, no mass);
* target i: non-colliding sites ``target{i}`` (a flat disc of radius R and a
  small dot) at the target;
* keyframe ``initial``: qpos = 0 and qvel = the solution's velocities.

Contact model (see :data:`CONTACT`): frictionless (condim 1), margin = gap = 0,
``solref = (-k, 0)`` (direct stiffness k, zero damping) with k = 2 / h^2 and
``solimp = (0.9999, 0.9999, 0.001)``: with the Euler integrator one contact
step then reverses the normal velocity exactly (elastic bounce); k is computed
from h because a k off by 1% loses ~0.5% of the speed per bounce.

XML (``scene_xml``) keeps every number at full precision: MuJoCo's writer keeps 6
significant digits, so :func:`full_precision` rewrites the numbers from the spec's
own values; a model loaded from the text equals ``build_model``'s bit for bit.

Compute only: functions return a spec, a model or XML text; the CLI writes files.
"""
from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from nbst import palette
from nbst.errors import InputError
from nbst.problem import Problem, ProblemError

__all__ = ["DEFAULT_TIMESTEP", "DEFAULT_UNIT", "SOLIMP", "WALL_THICKNESS_RADII", "WALL_HEIGHT_RADII",
           "PUCK_HALF_HEIGHT_RADII", "PROGRESS_DISKS", "FLOOR_RGBA", "WALL_RGBA", "CUE_RGBA", "NONCUE_RGBA",
           "TARGET_RGBA", "TARGET_DOT_RGBA", "SceneOptions", "safe_name", "build_spec", "build_model", "scene_xml",
           "full_precision"]

#: Default MuJoCo timestep (s). 1 ms errs ~0.14 deg on oblique collisions and lets
#: a dense 14-disk scene drift ~12% in energy over 60 s; 0.25 ms: ~0.04 deg, <= 0.6%.
DEFAULT_TIMESTEP = 0.00025
#: Metres per problem unit: problems are "think millimetres", so scenes are physically sized.
DEFAULT_UNIT = 1e-3
#: Impedance of every contact: near 1 so the constraint is nearly hard; width small.
SOLIMP = (0.9999, 0.9999, 0.001, 0.5, 2.0)
#: Wall thickness and height, in disk radii of the largest disk (looks only).
WALL_THICKNESS_RADII = 1.0
WALL_HEIGHT_RADII = 1.5
#: Puck (visual cylinder) half-height, in disk radii.
PUCK_HALF_HEIGHT_RADII = 0.4
#: Disks between two calls of ``build_spec``'s progress callback.
PROGRESS_DISKS = 250
#: Characters allowed in the model name; everything else becomes '_' (XML safety).
_NAME_OK = re.compile(r"[^A-Za-z0-9_.-]")

#: Colours (RGBA). Disks in nbst's class colours (nbst.palette: cueable amber,
#: noncueable blue, as in the video, the figures and the report); targets in a
#: neutral green that belongs to no class.
FLOOR_RGBA = (0.93, 0.93, 0.90, 1.0)
WALL_RGBA = (0.35, 0.38, 0.45, 1.0)
CUE_RGBA = (*palette.CUEABLE, 1.0)
NONCUE_RGBA = (*palette.NONCUEABLE, 1.0)
TARGET_RGBA = (0.17, 0.63, 0.17, 0.25)
TARGET_DOT_RGBA = (0.17, 0.63, 0.17, 0.9)


@dataclass(frozen=True)
class SceneOptions:
    """What a scene is built with. timestep in s, unit in metres per problem unit."""

    timestep: float = DEFAULT_TIMESTEP
    unit: float = DEFAULT_UNIT

    def __post_init__(self):
        if not (np.isfinite(self.timestep) and self.timestep > 0):
            raise InputError(f"timestep must be a finite number > 0, got {self.timestep!r}")
        if not (np.isfinite(self.unit) and self.unit > 0):
            raise InputError(f"unit must be a finite number > 0, got {self.unit!r}")

    @property
    def stiffness(self) -> float:
        """k = 2 / h^2: one Euler step of the contact spring reverses the normal velocity."""
        return 2.0 / self.timestep**2


def safe_name(name: str) -> str:
    """A model name that is harmless anywhere in XML: [A-Za-z0-9_.-], at most 64 characters."""
    s = _NAME_OK.sub("_", str(name))[:64]
    return s or "nbst"


def build_spec(problem: Problem, velocities=None, *, timestep: float = DEFAULT_TIMESTEP,
               unit: float = DEFAULT_UNIT, progress=None):
    """An ``mujoco.MjSpec`` of the problem's scene.

    velocities : (N, 2) float, units/s, or None (keyframe ``initial`` then has zero qvel)
    progress   : None or progress(k): k more disks added (every :data:`PROGRESS_DISKS`). MjSpec's
                 add_body / add_geom / add_joint / add_site grow with the elements already there:
                 0.1 s for 1,000 disks, 24 s for 10,000 (``benchmarks/bench_mujoco_scale.py --mjcf``)
    """
    import mujoco

    opt = SceneOptions(timestep=float(timestep), unit=float(unit))
    n = problem.n
    v = np.zeros((n, 2)) if velocities is None else np.asarray(velocities, dtype=float)
    if v.shape != (n, 2):
        raise InputError(f"velocities must have shape ({n}, 2), got {v.shape}")
    u = opt.unit
    W, H = (float(problem.box[0]) * u, float(problem.box[1]) * u)
    rmax = float(problem.radius.max()) * u

    spec = mujoco.MjSpec()
    spec.modelname = safe_name(problem.name)
    spec.option.timestep = opt.timestep
    spec.option.gravity = [0.0, 0.0, 0.0]
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_EULER
    spec.visual.global_.offwidth = 1024
    spec.visual.global_.offheight = 1024
    spec.visual.map.znear = 0.001
    spec.stat.center = [W / 2, H / 2, 0.0]
    spec.stat.extent = max(W, H)

    solref = [-opt.stiffness, 0.0]
    wb = spec.worldbody
    wb.add_light(name="top", pos=[W / 2, H / 2, 2 * max(W, H)], dir=[0, 0, -1],
                 type=int(mujoco.mjtLightType.mjLIGHT_DIRECTIONAL), castshadow=0)
    wb.add_camera(name="top", pos=[W / 2, H / 2, 1.2 * max(W, H)], fovy=50.0)

    floor = wb.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, pos=[W / 2, H / 2, 0.0],
                        size=[W / 2 + 2 * rmax, H / 2 + 2 * rmax, 0.01 * max(W, H)], rgba=FLOOR_RGBA)
    floor.contype = floor.conaffinity = 0

    t = WALL_THICKNESS_RADII * rmax
    hz = WALL_HEIGHT_RADII * rmax
    walls = (  # name, centre, half-sizes: inner faces at x = 0, x = W, y = 0, y = H
        ("wall_left", [-t / 2, H / 2, hz], [t / 2, H / 2 + t, hz]),
        ("wall_right", [W + t / 2, H / 2, hz], [t / 2, H / 2 + t, hz]),
        ("wall_bottom", [W / 2, -t / 2, hz], [W / 2, t / 2, hz]),
        ("wall_top", [W / 2, H + t / 2, hz], [W / 2, t / 2, hz]),
    )
    for name, pos, size in walls:
        g = wb.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_BOX, pos=pos, size=size, rgba=WALL_RGBA)
        _contact(g, solref)

    for i in range(n):
        if progress is not None and i and i % PROGRESS_DISKS == 0:
            progress(PROGRESS_DISKS)
        r = float(problem.radius[i]) * u
        x0, y0 = (float(c) * u for c in problem.start[i])
        body = wb.add_body(name=f"disk{i}", pos=[x0, y0, r])
        body.add_joint(name=f"disk{i}_x", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[1, 0, 0])
        body.add_joint(name=f"disk{i}_y", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 1, 0])
        rgba = CUE_RGBA if problem.cueable[i] else NONCUE_RGBA
        sphere = body.add_geom(name=f"disk{i}_collision", type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[r, 0, 0],
                               mass=float(problem.mass[i]), rgba=[*rgba[:3], 0.3], group=3)
        _contact(sphere, solref)
        puck = body.add_geom(name=f"disk{i}_puck", type=mujoco.mjtGeom.mjGEOM_CYLINDER,
                             size=[r, PUCK_HALF_HEIGHT_RADII * r, 0], rgba=rgba, density=0.0, group=1)
        puck.contype = puck.conaffinity = 0
        tx, ty = (float(c) * u for c in problem.target[i])
        R = float(problem.target_radius) * u
        wb.add_site(name=f"target{i}", type=mujoco.mjtGeom.mjGEOM_CYLINDER, pos=[tx, ty, 0.0002],
                    size=[R, 0.0001, 0], rgba=TARGET_RGBA)
        wb.add_site(name=f"target{i}_dot", type=mujoco.mjtGeom.mjGEOM_CYLINDER, pos=[tx, ty, 0.0004],
                    size=[0.25 * r, 0.0001, 0], rgba=TARGET_DOT_RGBA)

    if progress is not None and n:
        progress(n - (n - 1) // PROGRESS_DISKS * PROGRESS_DISKS)
    key = spec.add_key()
    key.name = "initial"
    key.time = 0.0
    key.qpos = [0.0] * (2 * n)
    key.qvel = (v * u).reshape(-1).tolist()
    return spec


def _contact(geom, solref) -> None:
    """Frictionless, elastic, no margin (see the module docstring)."""
    geom.contype = geom.conaffinity = 1
    geom.condim = 1
    geom.friction = [0.0, 0.0, 0.0]
    geom.solref = solref
    geom.solimp = list(SOLIMP)
    geom.margin = 0.0
    geom.gap = 0.0


def build_model(problem: Problem, velocities=None, *, timestep: float = DEFAULT_TIMESTEP,
                unit: float = DEFAULT_UNIT):
    """The compiled ``mujoco.MjModel`` of :func:`build_spec`."""
    return _compile(build_spec(problem, velocities, timestep=timestep, unit=unit), problem, unit)


def _compile(spec, problem: Problem, unit: float):
    """``spec.compile()``; MuJoCo's refusal (e.g. bodies too small or too light in
    metres) becomes a one-line ProblemError that says which option to change."""
    try:
        return spec.compile()
    except ValueError as e:
        why = str(e).strip().splitlines()[0] if str(e).strip() else "compile failed"
        r_m = float(problem.radius.min()) * unit
        raise ProblemError(problem.source, "", f"MuJoCo cannot build the scene at --unit {unit:g} m per unit "
                                               f"(smallest disk radius {r_m:g} m, lightest mass "
                                               f"{float(problem.mass.min()):g}): {why}; a radius of ~0.01 m "
                                               f"needs --unit {0.01 / float(problem.radius.min()):.3g}") from None


def scene_xml(problem: Problem, velocities=None, *, timestep: float = DEFAULT_TIMESTEP,
              unit: float = DEFAULT_UNIT, progress=None) -> str:
    """MJCF text of the scene (what ``nbst mjcf`` writes), every number at full precision.

    A model loaded from this text has the same keyframe, disk starts, sizes, masses,
    contact parameters and timestep as ``build_model``, bit for bit (:func:`full_precision`).

    Args:
        problem: the problem whose box and disks make the scene.
        velocities: (N, 2) float, units/s (a solution's), or None: keyframe ``initial`` then has
            zero qvel.
        timestep: MuJoCo's timestep, seconds (default :data:`DEFAULT_TIMESTEP`).
        unit: metres per problem unit (default :data:`DEFAULT_UNIT`: problems are millimetres).
        progress: None or progress(k): k more disks added (see :func:`build_spec`).

    Returns:
        The MJCF XML text: load it with ``mujoco.MjModel.from_xml_string`` and reset to keyframe
        ``initial`` to play the motion.
    """
    spec = build_spec(problem, velocities, timestep=timestep, unit=unit, progress=progress)
    _compile(spec, problem, unit)
    return full_precision(spec.to_xml(), spec)


#: The numeric attributes ``full_precision`` rewrites, per element: everything the physics or
#: the keyframe reads, and the cosmetic geometry (all doubles in MjSpec; rgba is float32).
_EXACT_ATTRS = {
    "option": ("timestep", "gravity"),
    "statistic": ("extent", "center"),
    "body": ("pos",),
    "joint": ("axis",),
    "geom": ("pos", "size", "mass", "solref", "solimp", "friction", "margin", "gap", "rgba"),
    "site": ("pos", "size", "rgba"),
    "camera": ("pos", "fovy"),
    "light": ("pos", "dir"),
    "key": ("time", "qpos", "qvel"),
}
_TAG = re.compile(r'<([A-Za-z_]+)((?:\s+[A-Za-z_:]+="[^"]*")*)(\s*/?)>')
_ATTR = re.compile(r'([A-Za-z_:]+)="([^"]*)"')


def _exact(x, float32: bool) -> str:
    """Shortest text that reads back as exactly x (a double; or a float32 for float32 fields)."""
    t = str(np.float32(x)) if float32 else repr(float(x))
    return t[:-2] if t.endswith(".0") else t


def full_precision(xml: str, spec, *, exact_attrs: dict | None = None, spec_names: dict | None = None,
                   float32_attrs: tuple = ()) -> str:
    """``xml`` (``spec.to_xml()``, which keeps 6 significant digits) with the numbers of
    :data:`_EXACT_ATTRS` rewritten from ``spec``'s own values, shortest round-trip form.

    MuJoCo writes only the leading entries of a vector that differ from its defaults
    (e.g. ``solimp="0.9999 0.9999"``); the rewrite keeps the same entries. Text layout,
    element order and every other attribute stay as MuJoCo wrote them.

    exact_attrs   : {tag: attribute names} to rewrite (default :data:`_EXACT_ATTRS`)
    spec_names    : {attribute: spec field} where they differ (e.g. mesh ``vertex`` ->
                    ``uservert``)
    float32_attrs : attributes stored as float32 whatever the field's type says
    """
    exact_attrs = _EXACT_ATTRS if exact_attrs is None else exact_attrs
    spec_names = spec_names or {}
    lookup = {"body": spec.body, "joint": spec.joint, "geom": spec.geom, "site": spec.site, "mesh": spec.mesh,
              "camera": spec.camera, "light": spec.light, "key": spec.key}
    fixed = {"option": spec.option, "statistic": spec.stat}

    def element(m):
        tag, attrs, end = m.group(1), m.group(2), m.group(3)
        names = exact_attrs.get(tag)
        if not names:
            return m.group(0)
        if tag in fixed:
            obj = fixed[tag]
        else:
            name = dict(_ATTR.findall(attrs)).get("name")
            obj = lookup[tag](name) if name else None
        if obj is None:
            return m.group(0)

        def attr(a):
            key, text = a.group(1), a.group(2)
            if key not in names:
                return a.group(0)
            value = getattr(obj, spec_names.get(key, key))  # a float, a numpy array, or an MjDoubleVec
            float32 = getattr(value, "dtype", None) == np.float32 or key in float32_attrs
            if not isinstance(value, (np.ndarray, float, int)):
                value = list(value)
            vals = np.atleast_1d(np.asarray(value, dtype=float)).ravel()
            tokens = text.split()
            if len(tokens) > vals.size:
                raise AssertionError(f"MJCF {tag} {key}: {len(tokens)} numbers written, the spec has {vals.size}")
            return f'{key}="{" ".join(_exact(x, float32) for x in vals[:len(tokens)])}"'

        return f"<{tag}{_ATTR.sub(attr, attrs)}{end}>"

    return _TAG.sub(element, xml)
