"""The physics cross-validation of a scene solution: its fates judged under MuJoCo's other settings.

A solution found at one setting of MuJoCo (the scene's integrator, constraint solver, friction cone
and timestep h) is rolled out again from the same controls (the same initial state) under each of:

* the integrators ``Euler``, ``implicitfast`` and ``RK4`` (group ``integrator``);
* the constraint solvers ``Newton``, ``CG`` and ``PGS`` (group ``solver``);
* the friction cones ``pyramidal`` and ``elliptic`` (group ``cone``);
* the timestep ladder h, h/2 and h/4 (group ``timestep``; the same duration, so 2x and 4x the steps);

each setting changing that one option of the scene's ``<option>`` and keeping the others as the
scene sets them. A row judges every fate again with the room's own rollout and judge
(``nbst.scene.rollout.SceneSim.rollout``): met or not, with the graded cost. The first row is the
scene's own setting, which is the solution's replay (``nbst scene replay`` judges the same). A row
is met when every fate is met and MuJoCo did not warn (a diverging state).

**Noise**: ``samples`` copies of the controls, each coordinate plus sigma times a standard normal
draw (the fates' ``"noise"``, or the defaults of docs/scene.md), clipped into the ranges: the draws
of ``nbst scene solve --samples`` (``nbst.scene.search.noisy_probability``, the same seed gives the
same draws), at the scene's setting. It gives P(every fate met) with its 95 % Wilson interval.

:func:`validate_solution` returns a :class:`SceneValidation`; its :meth:`~SceneValidation.to_dict`
is the report's JSON; ``nbst.render.scene_report`` draws its pages and pictures.
"""
from __future__ import annotations

import copy
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from nbst.models.mjsearch.probability import Probability, normal_draws, perturb
from nbst.scene.fates import Fates
from nbst.scene.rollout import SceneRollout, SceneSim, quiet_mujoco_warnings
from nbst.scene.scenefile import check_against_model, load_fates
from nbst.scene.solution import SceneSolutionError, _floats, read_solution
from nbst.seeds import resolve_seed

__all__ = ["VALIDATION_FORMAT", "VALIDATION_VERSION", "DEFAULT_VALIDATE_SAMPLES", "GROUPS", "INTEGRATORS",
           "SOLVERS", "CONES", "DIVISORS", "PATH_POINTS", "SettingRow", "SceneValidation", "validate_solution"]

VALIDATION_FORMAT = "nbst-scene-validation"
VALIDATION_VERSION = 1
#: Noisy rollouts of the noise row, when none is asked (``nbst scene validate --samples``).
DEFAULT_VALIDATE_SAMPLES = 100
#: The settings' groups, in the report's order.
GROUPS = ("integrator", "solver", "cone", "timestep")
#: MuJoCo's names (``mjtIntegrator``, ``mjtSolver``, ``mjtCone``) for each setting's.
INTEGRATORS = {"Euler": "mjINT_EULER", "implicitfast": "mjINT_IMPLICITFAST", "RK4": "mjINT_RK4"}
SOLVERS = {"Newton": "mjSOL_NEWTON", "CG": "mjSOL_CG", "PGS": "mjSOL_PGS"}
CONES = {"pyramidal": "mjCONE_PYRAMIDAL", "elliptic": "mjCONE_ELLIPTIC"}
#: The timestep ladder: h / k for each k.
DIVISORS = (1, 2, 4)
#: At most this many points of each body's path are kept for the pictures.
PATH_POINTS = 1500

_NAMES = {"integrator": {"mjINT_EULER": "Euler", "mjINT_RK4": "RK4", "mjINT_IMPLICIT": "implicit",
                         "mjINT_IMPLICITFAST": "implicitfast"},
          "solver": {"mjSOL_NEWTON": "Newton", "mjSOL_CG": "CG", "mjSOL_PGS": "PGS"},
          "cone": {"mjCONE_PYRAMIDAL": "pyramidal", "mjCONE_ELLIPTIC": "elliptic"}}


@dataclass(frozen=True)
class SettingRow:
    """One setting's rollout of the solution's controls.

    Args:
        group: ``"scene"`` (the scene's own setting) or one of :data:`GROUPS`.
        setting: the setting's name in its group (``"RK4"``, ``"h/2"``; ``"as the scene"``).
        integrator, solver, cone: MuJoCo's options of this rollout, by name.
        timestep: seconds; nstep: steps.
        same_as_scene: every option is the scene's own (the row equals the first).
        rollout: the rollout: its final state and its judgement.
        paths: {body: (T, 3) float array}: the fated bodies' origins along the rollout (at most
            :data:`PATH_POINTS` points each, the first and the last kept), for the pictures.
    """

    group: str
    setting: str
    integrator: str
    solver: str
    cone: str
    timestep: float
    nstep: int
    same_as_scene: bool
    rollout: SceneRollout
    paths: dict[str, np.ndarray] = field(repr=False, compare=False)

    @property
    def met(self) -> bool:
        """Every fate met, and MuJoCo did not warn."""
        return bool(self.rollout.judgement.met and not self.rollout.warnings)

    def to_dict(self) -> dict:
        j = self.rollout.judgement.to_dict()
        return {"group": self.group, "setting": self.setting, "integrator": self.integrator, "solver": self.solver,
                "cone": self.cone, "timestep": self.timestep, "nstep": self.nstep,
                "same_as_scene": self.same_as_scene, "met": self.met, "signature": j["signature"],
                "cost": self.rollout.cost, "warnings": list(self.rollout.warnings), "bodies": j["bodies"]}


@dataclass(frozen=True)
class SceneValidation:
    """What :func:`validate_solution` found.

    Args:
        solution: the solution file's path, as given.
        fates: the checked fates.
        doc: the solution file's JSON object.
        rows: the scene's own setting first, then each group's settings in :data:`GROUPS`' order.
        probability: P(every fate met) under the fates' noise at the scene's setting.
        noise_seed: the noise draws' seed; samples: their number.
        noisy_ends: (samples, B, 3) float array: each noisy rollout's final position of the B
            fated bodies' origins; noisy_met: (samples,) bool array: each met every fate.
        mujoco: MuJoCo's version.
    """

    solution: str
    fates: Fates
    doc: dict
    rows: tuple[SettingRow, ...]
    probability: Probability
    noise_seed: int
    samples: int
    noisy_ends: np.ndarray = field(repr=False, compare=False)
    noisy_met: np.ndarray = field(repr=False, compare=False)
    mujoco: str = ""
    #: the footprints from above, (N, 2) polygons (m), of the geoms fixed to the world that bodies can
    #: touch (walls, a backboard, a bin, a height field; planes left out): drawn under the paths
    #: (:func:`static_footprints`)
    statics: tuple[np.ndarray, ...] = field(default=(), repr=False, compare=False)
    #: those of them a fate names (``hits``, ``never_hits``): kept inside the plots' axes
    aims: tuple[np.ndarray, ...] = field(default=(), repr=False, compare=False)

    @property
    def scene_row(self) -> SettingRow:
        """The scene's own setting (the replay)."""
        return self.rows[0]

    @property
    def all_met(self) -> bool:
        """Every setting's rollout meets every fate (the noise row apart)."""
        return all(r.met for r in self.rows)

    def group(self, name: str) -> list[SettingRow]:
        """The rows of one group."""
        return [r for r in self.rows if r.group == name]

    def to_dict(self) -> dict:
        """The report's JSON object (``report.json``)."""
        p = self.probability
        failed = [f"{r.group} {r.setting}" for r in self.rows if not r.met]
        return {"format": VALIDATION_FORMAT, "version": VALIDATION_VERSION, "solution": self.solution,
                "fates": self.doc.get("fates"), "scene": str(self.fates.scene), "duration": self.fates.duration,
                "timestep": float(self.doc["timestep"]), "mujoco": self.mujoco, "all_met": self.all_met,
                "failed": failed, "rows": [r.to_dict() for r in self.rows],
                "noise": {"samples": self.samples, "seed": self.noise_seed, "k": p.k, "n": p.n, "p": p.p,
                          "lo": p.lo, "hi": p.hi, "sigma": [float(a) for a in self.fates.noise()]}}


def _option_name(group: str, value: Any) -> str:
    return _NAMES[group].get(getattr(value, "name", ""), str(value))


def _paths(model: Any, sim: SceneSim, qpos0: np.ndarray, qvel0: np.ndarray) -> np.ndarray:
    """(T, B, 3): the fated bodies' origins along a plain mj_step loop from the state (the same
    steps as the rollout judged), at most PATH_POINTS points."""
    import mujoco

    d = mujoco.MjData(model)
    sim._reset(d)
    d.qpos[:] = qpos0
    d.qvel[:] = qvel0
    mujoco.mj_kinematics(model, d)
    n, ids = sim.nstep, sim.bodies
    stride = max(1, -(-n // (PATH_POINTS - 1)))
    out = [d.xpos[ids].copy()]
    done = 0
    while done < n:
        k = min(stride, n - done)
        mujoco.mj_step(model, d, nstep=k)
        done += k
        mujoco.mj_kinematics(model, d)
        out.append(d.xpos[ids].copy())
    return np.array(out)


def validate_solution(path: str, *, samples: int = DEFAULT_VALIDATE_SAMPLES, seed: int | None = None,
                      jobs: int = 1) -> SceneValidation:
    """Judge a solution's fates under MuJoCo's integrators, solvers, cones, timestep ladder and noise.

    Args:
        path: the solution file (``nbst scene solve -o``).
        samples: noisy rollouts of the noise row, >= 1.
        seed: the noise draws' seed; None: the solution's recorded seed (the draws of ``nbst scene
            solve --samples``).
        jobs: threads rolling the noisy copies out (any value gives the same report).

    Returns:
        the :class:`SceneValidation`: a :class:`SettingRow` per setting, the scene's own first;
        the noise row's probability.

    Raises:
        SceneSolutionError: the solution file is refused (or its controls do not fit the fates).
        FatesError: its fates file or scene is refused, or a rung's steps pass the cap.
        InputError: the seed is not an integer in range.
    """
    import mujoco

    if isinstance(samples, bool) or not isinstance(samples, int) or samples < 1:
        raise SceneSolutionError(f"{path}: samples must be an integer >= 1, got {samples!r}")
    doc = read_solution(path)
    fates, model = load_fates(doc.get("fates_file") or doc["fates"], scene=doc["scene"])
    h = float(doc["timestep"])
    model.opt.timestep = h
    x = _floats(doc, "x", fates.dim, str(path))
    # the file's state, under each setting (an edited scene would not give it again from x)
    state = (_floats(doc, "qpos0", int(model.nq), str(path)), _floats(doc, "qvel0", int(model.nv), str(path)))
    s = resolve_seed(doc.get("seed") if seed is None else seed, what="seed")
    base = {"integrator": model.opt.integrator, "solver": model.opt.solver, "cone": model.opt.cone, "timestep": h}
    wanted: list[tuple[str, str, dict]] = [("scene", "as the scene", {})]
    for name, enum in INTEGRATORS.items():
        wanted.append(("integrator", name, {"integrator": getattr(mujoco.mjtIntegrator, enum)}))
    for name, enum in SOLVERS.items():
        wanted.append(("solver", name, {"solver": getattr(mujoco.mjtSolver, enum)}))
    for name, enum in CONES.items():
        wanted.append(("cone", name, {"cone": getattr(mujoco.mjtCone, enum)}))
    for k in DIVISORS:
        wanted.append(("timestep", "h" if k == 1 else f"h/{k}", {"timestep": h / k}))
    done: dict[tuple, tuple[SceneRollout, dict[str, np.ndarray], int]] = {}
    rows = []
    with quiet_mujoco_warnings():
        for group, setting, change in wanted:
            opts = {**base, **change}
            key = (int(opts["integrator"]), int(opts["solver"]), int(opts["cone"]), float(opts["timestep"]))
            if key not in done:
                m = copy.copy(model)
                m.opt.integrator, m.opt.solver, m.opt.cone = opts["integrator"], opts["solver"], opts["cone"]
                m.opt.timestep = opts["timestep"]
                check_against_model(fates, m)  # the step cap, at this timestep
                with SceneSim(fates, m) as sim:
                    r = sim.rollout(x, state=state)
                    p = _paths(m, sim, r.qpos0, r.qvel0)
                    done[key] = (r, {f.body: p[:, i] for i, f in enumerate(fates.fates)}, sim.nstep)
            r, paths, nstep = done[key]
            rows.append(SettingRow(group=group, setting=setting,
                                   integrator=_option_name("integrator", mujoco.mjtIntegrator(key[0])),
                                   solver=_option_name("solver", mujoco.mjtSolver(key[1])),
                                   cone=_option_name("cone", mujoco.mjtCone(key[2])), timestep=key[3], nstep=nstep,
                                   same_as_scene=key == tuple(list(done)[0]), rollout=r, paths=paths))
        with SceneSim(fates, model, jobs=jobs) as sim:
            lo, hi = fates.bounds()
            xs = perturb(x, fates.noise(), normal_draws(s, samples, fates.dim), lo, hi)
            outs = sim.run(xs)  # nbst.scene.search.noisy_probability's draws and verdicts
            met = np.array([bool(o.judgement.met and not o.warnings) for o in outs])
            d = mujoco.MjData(model)
            ends = np.empty((samples, len(fates.fates), 3))
            for i, o in enumerate(outs):
                d.qpos[:] = o.qpos
                mujoco.mj_kinematics(model, d)
                ends[i] = d.xpos[sim.bodies]
        d = mujoco.MjData(model)
        with SceneSim(fates, model) as sim:
            sim._reset(d)  # the keyframe's mocap poses too
        mujoco.mj_kinematics(model, d)
        statics = static_footprints(model, d)
        named = {n for f in fates.fates for n in (*f.hits, *f.never_hits)}
        aims = static_footprints(model, d, names=named) if named else ()
    return SceneValidation(solution=str(path), fates=fates, doc=doc, rows=tuple(rows),
                           probability=Probability.of(int(met.sum()), samples), noise_seed=s, samples=samples,
                           noisy_ends=ends, noisy_met=met, mujoco=mujoco.__version__, statics=statics,
                           aims=aims)


def _hull(p: np.ndarray) -> np.ndarray:
    """The convex hull of 2D points (Andrew's monotone chain), counter-clockwise."""
    pts = sorted(set(map(tuple, np.round(p, 6))))   # to the micrometre: mesh vertices are float32
    if len(pts) < 3:
        return np.array(pts, dtype=float)

    def half(seq: list) -> list:
        out: list = []
        for q in seq:
            while len(out) >= 2 and ((out[-1][0] - out[-2][0]) * (q[1] - out[-2][1])
                                     - (out[-1][1] - out[-2][1]) * (q[0] - out[-2][0])) <= 0:
                out.pop()
            out.append(q)
        return out

    lower, upper = half(pts), half(pts[::-1])
    return np.array(lower[:-1] + upper[:-1], dtype=float)


def static_footprints(model: Any, data: Any, names: Any = None) -> tuple[np.ndarray, ...]:
    """The footprint from above of each geom fixed to the world (its body welded to the world, or a
    mocap body at its pose in ``data``) that collides with something (contype or conaffinity set),
    planes left out: a sphere's circle (24 sides), a mesh's hull, a height field's rectangle (its
    ``hfield_size`` radii x and y, from its base to its top, turned by its pose), else the hull of
    its bounding box's 8 corners (MuJoCo's ``geom_aabb``, turned by its pose), each an (N, 2) polygon
    in metres. ``names``: only the geoms of these names or of bodies of these names."""
    import mujoco

    out = []
    for g in range(int(model.ngeom)):
        if names is not None and model.geom(g).name not in names and model.body(
                int(model.geom_bodyid[g])).name not in names:
            continue
        t = int(model.geom_type[g])
        if t == mujoco.mjtGeom.mjGEOM_PLANE:
            continue
        if not (model.geom_contype[g] or model.geom_conaffinity[g]):
            continue
        b = int(model.geom_bodyid[g])
        if int(model.body_weldid[b]) != 0 and int(model.body_mocapid[b]) < 0:
            continue
        c, R = np.asarray(data.geom_xpos[g], float), np.asarray(data.geom_xmat[g], float).reshape(3, 3)
        if t == mujoco.mjtGeom.mjGEOM_SPHERE:
            a = np.linspace(0, 2 * np.pi, 24, endpoint=False)
            r = float(model.geom_size[g, 0])
            out.append(c[:2] + r * np.stack([np.cos(a), np.sin(a)], axis=1))
            continue
        if t == mujoco.mjtGeom.mjGEOM_MESH:   # its vertices, in the geom's frame once compiled
            m = int(model.geom_dataid[g])
            v0 = int(model.mesh_vertadr[m])
            corners = np.asarray(model.mesh_vert[v0:v0 + int(model.mesh_vertnum[m])], float)
        elif t == mujoco.mjtGeom.mjGEOM_HFIELD:   # x and y radii, top, base: the grid's box in the geom's frame
            rx, ry, top, base = (float(v) for v in model.hfield_size[int(model.geom_dataid[g])])
            corners = np.array([[sx * rx, sy * ry, z] for sx in (-1, 1) for sy in (-1, 1) for z in (-base, top)])
        else:
            box = np.asarray(model.geom_aabb[g], float)   # centre (3), half sizes (3), in the geom's frame
            corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1)
                                for sz in (-1, 1)]) * box[3:] + box[:3]
        out.append(_hull((c + corners @ R.T)[:, :2]))
    return tuple(out)
