"""Event-aligned stepping: MuJoCo resolves every impact exactly, nbst only chooses the step lengths.

With a fixed step, MuJoCo resolves an impact one step late (docs/mujoco.md): each impact leaves
the bodies |dv| h off, and later collisions amplify that. ``step_aligned`` advances an elastic
scene with the same ``mj_step``, the same collision detection and the same contact model, but
lets no step cross an impact:

1. **trial step.** From the state at t0 take a step of length h (or up to ``t_end``). MuJoCo's
   own collision detection (``mj_collision`` with every collidable geom's margin raised to
   twice the distance any pair can close in one step) then lists, with signed distance and
   normal, every pair that could touch within the step, at t0 and at the trial end.
2. **locate the touch.** If a pair overlaps at the trial end, roll back to t0 and search the
   step length (regula falsi, Illinois variant, on the smallest signed distance
   ``data.contact.dist``; bisection as a fallback) until the step ends just past touch: the
   deepest new overlap eps is in (0, tol]. A pair that is apart at both ends but approaching
   at t0 and receding at the end may dip below zero in between (a graze inside a step, which
   fixed stepping misses): the distance of two convex geoms under a straight relative motion is
   convex in time, so tangent lines at the two ends bound it from below; the search cuts at the
   tangents' crossing until the bound is >= 0 (no touch) or an overlap is found (a touch).
3. **resolve it with a matched micro-step.** A contact with overlap eps and approach speed u
   (normal relative velocity at the contact point) gets one Euler step of length h_c with
   direct stiffness k = 2u / (eps h_c) (``solref = (-k, 0)``; at h_c = eps / u this is the
   scene's own law k = 2/h_c^2). The contact's reference acceleration k eps acts for h_c, so
   the normal velocity changes by exactly 2u: it reverses, as in an elastic impact, whatever
   h_c is. h_c = max(eps / u, 2u / ``MICRO_ACCEL``) keeps the acceleration far below MuJoCo's
   instability limit. Only that pair collides during the micro-step (``geom_contype`` /
   ``geom_conaffinity`` of all other geoms are 0 for it). The impact is then late by eps / u:
   each body ends |dv| eps / u off (2 eps for a wall bounce, ~1e-12 units at the default tol),
   and a pair's normal is that of the configuration eps / u after the touch.
4. **simultaneous and near-simultaneous contacts**: earliest touch first (t0 - eps / u); ties
   (within ``TIE_TIME``) in nbst.sim's fixed order (the lower body first, a world geom (wall)
   before a body, then the partner), as the exact simulator processes them. Contacts whose
   impulses do not couple (no shared moving body, or a translating body with perpendicular
   normals: a corner hit, two walls at one instant) share one micro-step, each with its own k
   (set on its own geom; MuJoCo mixes two direct solrefs by their minimum, so the shared geom
   gets ~0); coupled ones (a disk struck by two disks at once) go one micro-step at a time,
   which is nbst.sim's convention (resolving them together, as one LCP, ends 26 units off on
   a three-disk test). After each micro-step the contacts are detected again, so a contact the
   previous impact made separating is left alone and one it created (a disk pushed into its
   neighbour, a Newton's cradle) is resolved next; one that approaches slower than tol / h is a
   resting contact (its impulse is below resolution) and gets none.
5. **grazing** contacts (approach speed ~0) cannot loop: a contact is resolved only while it
   approaches, and each micro-step makes it separate. A micro-step longer than h (eps / u > h:
   u below eps / h) is capped at h with k = 2u / (eps h), which still reverses u.

Requirements on the scene (``nbst mjcf`` scenes satisfy them; :func:`check_model` refuses, in one
line naming each, a model that breaks one, before any step, so that no call returns an answer
it did not compute: a ball under gravity used to fall to z = -46 m and return normally):

* Euler integrator; no gravity, fluid (density, viscosity), actuator, spring, damper, friction
  loss or applied force (``data.qfrc_applied``, ``data.xfrc_applied``): Euler free flight is
  then exact and no force acts between impacts;
* no constraint but contacts: no equality, joint or tendon limit, and contacts and constraints
  enabled; no flex (soft body); no contact override or sleeping (``opt.enableflags``);
* each collidable geom (contype or conaffinity non-zero) frictionless (condim 1), margin =
  gap = 0, elastic: a direct undamped ``solref = (-k, 0)`` (the micro-step sets k) and
  ``solimp`` dmin = dmax = 0.9999, MuJoCo's most (a contact's impulse is then exact; measured on
  two disks with five wall bounces, tests/test_stepping.py's first case: 2.6e-10 units from the
  exact end, against 106 units and speeds 20 % low with the default solimp (0.9, 0.95), and
  219 units and speeds 43 % high with dmin 0.9999, dmax 0.95); convex (no height field or SDF:
  a graze is found by convexity);
* bodies that translate: every joint a slide joint, or a free joint of a body whose centre of
  mass is its frame's origin and whose collidable geoms are spheres centred there (their
  rotation then never shows: a frictionless contact exerts no torque on them);
* no explicit ``<pair>`` (only geom contype/conaffinity is masked).

Usage (a scene written by ``nbst mjcf``)::

    import mujoco
    from nbst.models.stepping import step_aligned
    model = mujoco.MjModel.from_xml_path("scene.xml")
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("initial").id)
    stats = step_aligned(model, data, 5.0)   # to t = 5 s; model.opt.timestep is the probe step
    print(data.qpos, stats)

Compute only: mujoco is imported on first call; the model's fields are restored on return.

Length: aligned stepping and the guard that lists every setting it cannot model sit together, so
the guard changes whenever the stepping's assumptions do.
"""
from __future__ import annotations

import math
import time as _time
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from nbst.errors import InputError, MujocoError

__all__ = ["TOL_REL", "TIE_TIME", "MAX_SEARCH", "MICRO_ACCEL", "SHARED_K", "MAX_MICRO_PER_GEOM", "ELASTIC_IMP",
           "SceneNotSupported", "AlignedStats", "unsupported", "check_model", "step_aligned"]

#: Default overlap tolerance, relative to ``model.stat.extent``: the touch is located so that the
#: deepest new overlap is at most this (1e-15 x 0.8 m = 8e-16 m, a few ulps of a coordinate; the
#: micro-step stays exact at any overlap MuJoCo reports, k eps h_c = 2u). An impact then errs by
#: ~2 x overlap in position and, for a pair, by its normal turned by (overlap / u) w_t / s:
#: measured on 16 planted 5-disk motions (amplification 5e3-3e12 s), 1e-15 left 2-10x less error
#: than 1e-14 with the same search cost (docs/mujoco.md, "Aligned stepping").
TOL_REL = 1e-15
#: Two touches this close in time (s) are simultaneous and go in nbst.sim's fixed order: the
#: time of a touch is known to ~(distance round-off) / speed ~ 1e-15 s.
TIE_TIME = 1e-12
#: Search steps per located touch (regula falsi / bisection) and per graze check: the bracket
#: halves at worst, so 200 reach any float64 resolution.
MAX_SEARCH = 200
#: Acceleration (scene units / s^2) of a micro-step's impact: its length is at least 2u / this.
#: MuJoCo resets a simulation whose acceleration exceeds 1e10 (mjMAXVAL); 1e8 stays far below
#: it and keeps micro-steps short (2 ns at 0.1 m/s). The length does not change the result
#: (k eps h_c = 2u whatever h_c), only how far the pair separates within it.
MICRO_ACCEL = 1e9
#: Stiffness of a geom shared by contacts resolved in one micro-step: MuJoCo mixes two direct
#: solrefs by their minimum (measured, 4.0.0), so the partner geom's k acts.
SHARED_K = 1e-300
#: Micro-steps in one instant, per collidable geom, before the run is declared a jam
#: (disks pinned between walls bounce without end; nbst.constants.STALL_EVENTS_PER_DISK).
MAX_MICRO_PER_GEOM = 1000
#: ``solimp`` dmin and dmax a collidable geom needs: MuJoCo's largest impedance (mjMAXIMP), at
#: which a micro-step's impulse reverses the normal velocity exactly (module docstring).
ELASTIC_IMP = 0.9999
#: Collidable geoms named in a refusal before "and N more".
_NAMES_SHOWN = 3


class SceneNotSupported(InputError):
    """A model ``step_aligned`` cannot advance exactly (gravity, friction, another integrator,
    contact settings it does not model): one line naming every unsupported setting."""


def _names(model, obj, ids) -> str:
    import mujoco
    ids = [int(i) for i in ids]
    out = []
    for i in ids[:_NAMES_SHOWN]:
        name = mujoco.mj_id2name(model, obj, i)
        out.append(f"'{name}'" if name else f"#{i}")
    more = f" and {len(ids) - _NAMES_SHOWN} more" if len(ids) > _NAMES_SHOWN else ""
    return ", ".join(out) + more


def _vec(x) -> str:
    return "(" + ", ".join(f"{float(v):.6g}" for v in np.ravel(x)) + ")"


def unsupported(model, data=None) -> list[str]:
    """What in ``model`` (and ``data``'s applied forces) ``step_aligned`` does not model.

    Args:
        model: a ``mujoco.MjModel``.
        data: its ``mujoco.MjData``, or None: then applied forces are not checked.

    Returns:
        One phrase per unsupported setting, naming it and the geoms, joints or fields concerned
        (empty: the scene is one step_aligned advances exactly; module docstring, requirements).
    """
    import mujoco
    o = model.opt
    dis, ena = int(o.disableflags), int(o.enableflags)
    D, E, G, J = mujoco.mjtDisableBit, mujoco.mjtEnableBit, mujoco.mjtObj.mjOBJ_GEOM, mujoco.mjtObj.mjOBJ_JOINT
    off = lambda bit: bool(dis & int(bit))  # noqa: E731
    out = []
    if int(o.integrator) != int(mujoco.mjtIntegrator.mjINT_EULER):
        out.append(f"integrator {mujoco.mjtIntegrator(int(o.integrator)).name[len('mjINT_'):]} (it needs Euler, "
                   f"whose free flight is exact)")
    if not off(D.mjDSBL_GRAVITY) and np.any(o.gravity != 0):
        out.append(f"gravity {_vec(o.gravity)} m/s^2 (it needs none: bodies fly free between impacts)")
    if o.density != 0 or o.viscosity != 0:
        out.append(f"fluid forces (opt.density {o.density:g}, opt.viscosity {o.viscosity:g}; it needs none)")
    if off(D.mjDSBL_CONTACT) or off(D.mjDSBL_CONSTRAINT):
        out.append("contacts disabled (opt.disableflags: aligned stepping resolves impacts through them)")
    for bit, what in ((E.mjENBL_OVERRIDE, "contact override (it would replace the micro-step's solref)"),
                      (E.mjENBL_SLEEP, "sleeping bodies")):
        if ena & int(bit):
            out.append(f"{what} (opt.enableflags)")
    if model.npair:
        out.append(f"explicit contact pairs (<pair>, {model.npair}: only geom contype/conaffinity is masked)")
    if model.nu and not off(D.mjDSBL_ACTUATION):
        out.append(f"actuators ({model.nu}: it models no force between impacts)")
    if model.neq and not off(D.mjDSBL_EQUALITY):
        out.append(f"equality constraints ({model.neq})")
    if getattr(model, "nflex", 0):
        out.append(f"flexes ({model.nflex}: soft bodies)")
    lim = np.flatnonzero(model.jnt_limited) if not off(D.mjDSBL_LIMIT) else np.zeros(0, dtype=int)
    if len(lim):
        out.append(f"joint limits on {_names(model, J, lim)}")
    if model.ntendon and ((not off(D.mjDSBL_LIMIT) and np.any(model.tendon_limited))
                          or (not off(D.mjDSBL_SPRING) and np.any(model.tendon_stiffness != 0))
                          or (not off(D.mjDSBL_DAMPER) and np.any(model.tendon_damping != 0))
                          or (not off(D.mjDSBL_FRICTIONLOSS) and np.any(model.tendon_frictionloss != 0))):
        out.append("tendon limits, springs, dampers or friction loss")
    dof_j = model.dof_jntid
    for flag, vals, what in ((D.mjDSBL_SPRING, model.jnt_stiffness, "joint stiffness"),
                             (D.mjDSBL_DAMPER, model.dof_damping, "joint damping"),
                             (D.mjDSBL_FRICTIONLOSS, model.dof_frictionloss, "joint friction loss")):
        bad = np.flatnonzero(vals != 0)
        if len(bad) and not off(flag):
            js = bad if vals is model.jnt_stiffness else np.unique(dof_j[bad])
            out.append(f"{what} on {_names(model, J, js)}")
    # bodies that translate: slide joints, or a free joint of spheres centred at the centre of mass
    coll = np.flatnonzero((model.geom_contype | model.geom_conaffinity) != 0)
    free_t, slide_t = int(mujoco.mjtJoint.mjJNT_FREE), int(mujoco.mjtJoint.mjJNT_SLIDE)
    rot = [j for j in range(model.njnt) if int(model.jnt_type[j]) not in (free_t, slide_t)]
    if rot:
        out.append(f"hinge or ball joints {_names(model, J, rot)} (it models bodies that translate)")
    for j in range(model.njnt):
        if int(model.jnt_type[j]) != free_t:
            continue
        b = int(model.jnt_bodyid[j])
        sub = {b} | {k for k in range(model.nbody) if _ancestor(model, b, k)}
        gs = [g for g in coll if int(model.geom_bodyid[g]) in sub]
        ok = np.all(np.abs(model.body_ipos[b]) == 0) and all(
            int(model.geom_bodyid[g]) == b and int(model.geom_type[g]) == int(mujoco.mjtGeom.mjGEOM_SPHERE)
            and np.all(model.geom_pos[g] == 0) for g in gs)
        if not ok:
            out.append(f"free joint {_names(model, J, [j])} of a body that may turn what collides (it needs its "
                       f"centre of mass at its origin and only spheres centred there)")
    g = coll
    checks = (
        (model.geom_condim[g] != 1, "friction: condim other than 1 on geoms"),
        ((model.geom_margin[g] != 0) | (model.geom_gap[g] != 0), "contact margin or gap on geoms"),
        ((model.geom_solref[g, 0] >= 0) | (model.geom_solref[g, 1] != 0),
         "inelastic contacts: solref not direct and undamped (-k, 0) on geoms"),
        ((model.geom_solimp[g, 0] < ELASTIC_IMP) | (model.geom_solimp[g, 1] < ELASTIC_IMP),
         f"solimp dmin or dmax below {ELASTIC_IMP:g} (the impulse would not be elastic) on geoms"),
        (np.isin(model.geom_type[g], [int(mujoco.mjtGeom.mjGEOM_HFIELD), int(mujoco.mjtGeom.mjGEOM_SDF)]),
         "non-convex collision geoms (height field or SDF)"),
    )
    for mask, what in checks:
        if np.any(mask):
            out.append(f"{what} {_names(model, G, g[mask])}")
    if data is not None:
        for name in ("qfrc_applied", "xfrc_applied"):
            if np.any(getattr(data, name) != 0):
                out.append(f"applied forces (data.{name})")
    return out


def _ancestor(model, a: int, b: int) -> bool:
    """Body ``a`` is a proper ancestor of body ``b``."""
    while b > 0:
        b = int(model.body_parentid[b])
        if b == a:
            return True
    return False


def check_model(model, data=None) -> None:
    """Refuse a model ``step_aligned`` cannot advance exactly, naming every unsupported setting.

    Args:
        model: a ``mujoco.MjModel``.
        data: its ``mujoco.MjData`` (its applied forces are checked), or None.

    Raises:
        SceneNotSupported: one line listing what the model has that aligned stepping does not
            model (:func:`unsupported`).
    """
    bad = unsupported(model, data)
    if bad:
        raise SceneNotSupported("step_aligned: the model has what aligned stepping does not model (elastic, "
                                "frictionless impacts between bodies in free flight): " + "; ".join(bad))


@dataclass
class AlignedStats:
    """Cost and work of one ``step_aligned`` call.

    steps       : accepted steps (full steps of h and steps shortened to end at a touch)
    trials      : mj_step calls spent on trial steps (accepted or rolled back), micro-steps apart
    bisections  : of the trials, the search steps that located touches
    graze_checks: of the trials, those spent on grazes inside a step
    impacts     : contacts resolved (one micro-step each, or one for a group of independent
                  contacts of one instant: a corner)
    simultaneous: impacts in the same instant as the previous one (TIE_TIME)
    capped      : micro-steps capped at h (grazing: approach speed below eps / h)
    max_overlap : deepest overlap resolved (m)
    wall_time   : seconds
    """

    steps: int = 0
    trials: int = 0
    bisections: int = 0
    graze_checks: int = 0
    impacts: int = 0
    simultaneous: int = 0
    capped: int = 0
    max_overlap: float = 0.0
    wall_time: float = 0.0

    def to_dict(self) -> dict:
        return asdict(self)


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise a x b of (k, 3) arrays, the same numbers as np.cross without its axis handling
    (~70 us a call: 3.9 s of a 41 s aligned run of 1,000 disks, profiled)."""
    out = np.empty_like(b)
    out[:, 0] = a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1]
    out[:, 1] = a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2]
    out[:, 2] = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    return out


class _Stepper:
    """The model's arrays that stepping changes, saved; state save/load; detection."""

    def __init__(self, model, data, h: float, tol: float):
        import mujoco
        self.mj = mujoco
        self.m, self.d = model, data
        self.h, self.tol = h, tol
        self.timestep0 = float(model.opt.timestep)
        self.solref0 = model.geom_solref.copy()
        self.margin0 = model.geom_margin.copy()
        self.contype0 = model.geom_contype.copy()
        self.conaff0 = model.geom_conaffinity.copy()
        self.collide = (self.contype0 | self.conaff0) != 0
        self.body = model.geom_bodyid.copy()
        self.root = model.body_rootid.copy()
        self.spec = mujoco.mjtState.mjSTATE_INTEGRATION
        self.state = np.empty(mujoco.mj_stateSize(model, self.spec))
        self.cache: Any = None  # (dt, margin, contacts) of the current state, from the last trial
        self.normal: dict = {}  # contact normal of each pair last detected
        # bodies that only translate (every joint from the world to them a slide joint)
        jt = model.jnt_type
        slide = int(mujoco.mjtJoint.mjJNT_SLIDE)
        self.translating = np.ones(model.nbody, dtype=bool)
        for b in range(1, model.nbody):
            js = range(model.body_jntadr[b], model.body_jntadr[b] + model.body_jntnum[b])
            own = all(int(jt[j]) == slide for j in js)
            parent = int(model.body_parentid[b])
            self.translating[b] = own and (parent == 0 or self.translating[parent])

    def restore_model(self) -> None:
        m = self.m
        m.opt.timestep = self.timestep0
        m.geom_solref[:] = self.solref0
        m.geom_margin[:] = self.margin0
        m.geom_contype[:] = self.contype0
        m.geom_conaffinity[:] = self.conaff0

    def save(self) -> np.ndarray:
        self.mj.mj_getState(self.m, self.d, self.state, self.spec)
        return self.state.copy()

    def load(self, s: np.ndarray) -> None:
        self.mj.mj_setState(self.m, self.d, s, self.spec)

    def step(self, dt: float) -> None:
        self.m.opt.timestep = dt
        self.mj.mj_step(self.m, self.d)

    def speed(self) -> float:
        """Largest speed of any point of a collidable geom (m/s), from ``data.cvel`` (needs
        mj_kinematics, mj_comPos, mj_comVel at the current state)."""
        m, d = self.m, self.d
        g = np.flatnonzero(self.collide)
        b = self.body[g]
        cv = d.cvel[b]
        r = d.geom_xpos[g] - d.subtree_com[self.root[b]]
        v = np.linalg.norm(cv[:, 3:] + _cross(cv[:, :3], r), axis=1) + \
            np.linalg.norm(cv[:, :3], axis=1) * m.geom_rbound[g]
        return float(v.max(initial=0.0))

    def detect(self, margin: float = 0.0) -> dict:
        """Contacts at the current state: {(g1, g2): (dist, ddist/dt)}; with ``margin`` > 0 every
        pair closer than it (MuJoCo's broad and narrow phase with raised geom margins)."""
        mj, m, d = self.mj, self.m, self.d
        mj.mj_kinematics(m, d)
        if margin > 0.0:
            m.geom_margin[self.collide] = margin
            mj.mj_collision(m, d)
            m.geom_margin[:] = self.margin0
        else:
            mj.mj_collision(m, d)
        n = d.ncon
        if n == 0:
            return {}
        mj.mj_comPos(m, d)
        mj.mj_comVel(m, d)
        con = d.contact
        geom = con.geom[:n]
        dist = con.dist[:n]
        nrm = con.frame[:n, :3]
        pos = con.pos[:n]
        rate = np.zeros(n)
        for side, sign in ((0, -1.0), (1, 1.0)):
            b = self.body[geom[:, side]]
            cv = d.cvel[b]
            v = cv[:, 3:] + _cross(cv[:, :3], pos - d.subtree_com[self.root[b]])
            rate += sign * np.einsum("ij,ij->i", nrm, v)
        out: dict = {}
        for k in range(n):
            g1, g2 = int(geom[k, 0]), int(geom[k, 1])
            key = (g1, g2) if g1 < g2 else (g2, g1)
            if key not in out or dist[k] < out[key][0]:
                out[key] = (float(dist[k]), float(rate[k]))
                self.normal[key] = nrm[k].copy()
        return out

    def independent(self, k1, k2) -> bool:
        """Two contacts one micro-step can resolve together: their impulses do not couple (they
        share no moving body, or the body they share only translates and their normals are
        perpendicular, J1 M^-1 J2^T = 0)."""
        b1 = {int(self.body[g]) for g in k1} - {0}
        b2 = {int(self.body[g]) for g in k2} - {0}
        shared = b1 & b2
        if not shared:
            return True
        if not all(self.translating[b] for b in shared):
            return False
        return abs(float(np.dot(self.normal[k1], self.normal[k2]))) < 1e-12

    def order_key(self, key) -> tuple:
        """nbst.sim's order of simultaneous events: the lower body first, a world geom (a wall)
        before a body partner, then the partner."""
        b1, b2 = int(self.body[key[0]]), int(self.body[key[1]])
        lo, hi = (b1, b2) if (b2 == 0 or (b1 != 0 and b1 < b2)) else (b2, b1)
        return (lo, 0 if hi == 0 else 1, hi, key)


def step_aligned(model, data, t_end: float, *, h: float | None = None, tol: float | None = None,
                 on_event=None, on_step=None, max_steps: int | None = None) -> AlignedStats:
    """Advance ``data`` to ``t_end`` (s) with every impact resolved exactly (module docstring).

    h         : probe step (s); default ``model.opt.timestep``. Free flight is exact at any h;
                h only bounds how far a step may go before contacts are checked
    tol       : largest overlap (m) at which a touch counts as located; default
                ``TOL_REL * model.stat.extent``
    on_event  : called as on_event(t_touch, geom1, geom2, approach_speed) after each impact
    on_step   : called as on_step(data) after every accepted step and micro-step
    max_steps : MujocoError past this many accepted steps + micro-steps (default: none)
    returns   : AlignedStats. The model's timestep, solref, margin, contype and conaffinity
                are restored on return, also on error.
    raises    : SceneNotSupported (before any step) for a model it does not model
                (:func:`check_model`: gravity, friction, another integrator, contact settings);
                InputError for a bad h or tol; MujocoError for a jam or past max_steps.
    """
    check_model(model, data)
    h = float(model.opt.timestep if h is None else h)
    if not (math.isfinite(h) and h > 0):
        raise InputError(f"h must be a finite number > 0, got {h!r}")
    tol = float(TOL_REL * max(float(model.stat.extent), 1e-300) if tol is None else tol)
    if not (math.isfinite(tol) and tol > 0):
        raise InputError(f"tol must be a finite number > 0, got {tol!r}")
    st = _Stepper(model, data, h, tol)
    stats = AlignedStats()
    t0_wall = _time.perf_counter()
    t_end = float(t_end)
    cap = max_steps if max_steps is not None else math.inf
    try:
        pending = True  # the start may overlap
        while True:
            if pending:
                _resolve(st, stats, on_event, on_step)
                st.cache = None
            t0 = float(data.time)
            left = t_end - t0
            if left <= 4 * math.ulp(max(abs(t_end), 1.0)):
                break
            if stats.steps + stats.impacts >= cap:
                raise MujocoError(f"aligned stepping: over max_steps = {max_steps} at t = {t0:g} s")
            pending = _advance(st, stats, min(h, left))
            stats.steps += 1
            if on_step is not None:
                on_step(data)
    finally:
        st.restore_model()
        stats.wall_time = _time.perf_counter() - t0_wall
    return stats


def _advance(st: _Stepper, stats: AlignedStats, dt: float) -> bool:
    """One step of at most dt from the current state, ending just past the first touch if there
    is one (then True: an overlap to resolve)."""
    s0 = st.save()
    if st.cache is not None and st.cache[0] == dt:
        _, G, near0 = st.cache  # the last trial's end: this state, same velocities
    else:
        st.mj.mj_kinematics(st.m, st.d)
        st.mj.mj_comPos(st.m, st.d)
        st.mj.mj_comVel(st.m, st.d)
        G = 4.0 * st.speed() * dt + 2.0 * st.tol  # twice the most a pair can close in dt
        near0 = st.detect(G)
    # pairs already overlapping at t0 are separating (_resolve left them so): not new touches
    skip = {k for k, (dist, _) in near0.items() if dist < 0.0}
    first = [True]

    def trial(tau):
        if not first[0]:
            st.load(s0)
        first[0] = False
        st.step(tau)
        stats.trials += 1
        return st.detect(G)

    def gmin(near, keys=None):
        vals = [dist for k, (dist, _) in near.items() if k not in skip and (keys is None or k in keys)]
        return min(vals) if vals else G

    tol = st.tol
    near1 = trial(dt)
    g1 = gmin(near1)
    if g1 >= 0.0:
        graze = [k for k in set(near0) & set(near1) - skip if near0[k][1] < 0.0 < near1[k][1]]
        hit: tuple | None = None
        if graze:
            s1 = st.save()
            hit = _graze(st, stats, trial, near0, near1, dt, graze, skip)
            if hit is None:
                st.load(s1)
        if hit is None:
            st.cache = (dt, G, near1)
            return False
        b, gb, near_b = hit
    else:
        b, gb, near_b = dt, g1, near1
    st.cache = None
    if -tol <= gb < 0.0:  # data is at b: the last trial
        return True
    # regula falsi (Illinois) on f = gmin + tol/2 over [a, b], f(a) > 0 > f(b), gmin over the pairs
    # that overlap at b (a pair resting at distance ~0 must not flatten the function)
    cross = {k for k, (dist, _) in near_b.items() if dist < 0.0 and k not in skip}
    a, fa = 0.0, max(gmin(near0, cross), 0.0) + 0.5 * tol
    fb = gb + 0.5 * tol
    side = 0
    last = b
    for _ in range(MAX_SEARCH):
        tau = (a * fb - b * fa) / (fb - fa)
        if not (a < tau < b):
            tau = 0.5 * (a + b)
        g = gmin(trial(tau), cross)
        stats.bisections += 1
        last = tau
        if -tol <= g < 0.0:
            return True
        f = g + 0.5 * tol
        if f < 0.0:
            b, fb = tau, f
            if side == -1:
                fa *= 0.5
            side = -1
        else:
            a, fa = tau, f
            if side == 1:
                fb *= 0.5
            side = 1
        if b - a <= 4 * math.ulp(float(st.d.time) + 1.0):
            break
    if last != b:  # end at b: overlapping, deeper than tol (resolved all the same)
        trial(b)
    return True


def _graze(st, stats, trial, near0, near1, dt, keys, skip):
    """A touch inside the step of a pair apart at both ends: (tau, gmin) with gmin < 0, or None."""
    for key in sorted(keys):
        d0, r0 = near0[key]
        d1, r1 = near1[key]
        a, b = 0.0, dt
        for _ in range(MAX_SEARCH):
            if not (r0 < 0.0 < r1):
                break
            tx = (d1 - d0 - r1 * (b - a)) / (r0 - r1)  # tangents' crossing, from a
            lower = d0 + r0 * tx
            if lower >= 0.0 or tx <= 0.0 or tx >= b - a:
                break
            tau = a + tx
            near = trial(tau)
            stats.graze_checks += 1
            if key not in near:
                break
            d, r = near[key]
            if d < 0.0:
                vals = [x for k, (x, _) in near.items() if k not in skip]
                return tau, min(vals), near
            if r < 0.0:
                a, d0, r0 = tau, d, r
            else:
                b, d1, r1 = tau, d, r
    return None


def _resolve(st: _Stepper, stats: AlignedStats, on_event, on_step) -> None:
    """Micro-steps until no contact overlaps while approaching (module docstring, 3-5)."""
    m, d = st.m, st.d
    limit = MAX_MICRO_PER_GEOM * max(1, int(st.collide.sum()))
    u_rest = st.tol / st.h  # slower approach: resting contact, an impulse below resolution
    mj_badqacc = int(st.mj.mjtWarning.mjWARN_BADQACC)
    n_bad = d.warning[mj_badqacc].number
    last_t = None
    for _ in range(limit):
        near = st.detect()
        cands = [(eps_over_u, key, -dist, -rate) for key, (dist, rate) in near.items()
                 if dist < 0.0 and -rate > u_rest for eps_over_u in (dist / rate,)]
        if not cands:
            return
        lag = max(c[0] for c in cands)
        tied = sorted((c for c in cands if c[0] >= lag - TIE_TIME), key=lambda c: st.order_key(c[1]))
        group = _group(st, tied, near)
        hc = max(max(eps / u, 2.0 * u / MICRO_ACCEL) for _, _, eps, u in group)
        if hc > st.h:
            hc = st.h
            stats.capped += 1
        uses: dict = {}
        for _, key, _, _ in group:
            for g in key:
                uses[g] = uses.get(g, 0) + 1
        m.geom_contype[:] = 0
        m.geom_conaffinity[:] = 0
        for _, key, eps, u in group:
            k = 2.0 * u / (eps * hc)  # k eps hc = 2u: the normal velocity reverses
            for g in key:
                m.geom_contype[g] = 1
                m.geom_conaffinity[g] = 1
                # two direct solrefs mix by their minimum: a geom shared within the group gets
                # (almost) no stiffness, so each contact takes its own geom's k
                m.geom_solref[g] = (-k, 0.0) if uses[g] == 1 else (-SHARED_K, 0.0)
        try:
            st.step(hc)
            if d.warning[mj_badqacc].number > n_bad:
                raise MujocoError(f"aligned stepping: MuJoCo found the micro-step unstable at t = {float(d.time):g} s "
                                   f"(micro-step {hc:.3g} s)")
        finally:
            m.geom_contype[:] = st.contype0
            m.geom_conaffinity[:] = st.conaff0
            m.geom_solref[:] = st.solref0
        t_now = float(d.time) - hc
        for lag_c, key, eps, u in group:
            t_touch = t_now - lag_c
            stats.impacts += 1
            stats.max_overlap = max(stats.max_overlap, eps)
            if last_t is not None and abs(t_touch - last_t) <= TIE_TIME:
                stats.simultaneous += 1
            last_t = t_touch
            if on_event is not None:
                on_event(t_touch, key[0], key[1], u)
        if on_step is not None:
            on_step(d)
    raise MujocoError(f"aligned stepping: more than {limit} impacts at t = {float(d.time):g} s (a jam: bodies "
                       f"pinned between walls bounce without end)")


def _group(st: _Stepper, tied: list, near: dict) -> list:
    """The contacts of one instant that one micro-step may resolve together: the first (in
    nbst.sim's order) and every later one independent of all taken so far (no shared moving
    body, or one that only translates with perpendicular normals: a corner), each with a geom
    no other member uses (its stiffness goes there), and no other overlapping pair among them."""
    group = [tied[0]]
    for c in tied[1:]:
        if not all(st.independent(c[1], g[1]) for g in group):
            continue
        uses: dict = {}
        for _, key, _, _ in group + [c]:
            for g in key:
                uses[g] = uses.get(g, 0) + 1
        if not all(any(uses[g] == 1 for g in key) for _, key, _, _ in group + [c]):
            continue
        geoms = set(uses)
        keys = {x[1] for x in group} | {c[1]}
        if any(dist < 0.0 and k[0] in geoms and k[1] in geoms and k not in keys for k, (dist, _) in near.items()):
            continue
        group.append(c)
    return group
