"""The contacts of a scene's bodies as MuJoCo will make them, read from the model before any
rollout (``nbst scene check`` prints what they say; ``nbst scene solve`` warns of the first):

* :func:`short_contacts`: a contact that lasts fewer than :data:`MIN_CONTACT_STEPS` steps
  (:func:`contact_time`: MuJoCo's solref as a spring and dashpot, its time to zero force) is not
  resolved by the step: the bounce changes with where in a step it begins, and the ladder (h/2,
  h/4) seldom agrees with h;
* :func:`ignored_friction`: torsional or rolling friction that the pair's condim ignores;
* :func:`endless_rolls`: a round body that must end at rest, with a contact that applies no rolling
  friction (it may roll for ever);
* :func:`deep_rests`: a body that would rest deeper in the floor than :data:`SINK_SHARE` of its
  smallest half-size (:func:`resting_depth`: the soft contact's equilibrium), as a millimetre scene
  in MuJoCo's default contact does.

Each pair's parameters follow MuJoCo's ``mj_contactParam``: an explicit ``<pair>``'s own, else the
higher priority's, else the solmix-weighted mean (the least of each entry for a direct solref).
Compute only; mujoco is imported inside the functions.
"""
from __future__ import annotations

import math
from typing import Any

import numpy as np

from nbst.scene.fates import Fates
from nbst.scene.scenefile import _collides

__all__ = ["MIN_CONTACT_STEPS", "SINK_SHARE", "contact_time", "short_contacts", "ignored_friction", "endless_rolls",
           "resting_depth", "deep_rests"]


#: A contact that rebounds in fewer steps than this is noted by ``nbst scene check`` (:func:`short_contacts`).
MIN_CONTACT_STEPS = 4.0


def _pair_sol(model: Any, g1: int, g2: int, pairs: dict[tuple[int, int], int]) -> tuple[tuple[float, float], np.ndarray]:
    """The solref and solimp MuJoCo gives a contact of geoms ``g1`` and ``g2`` (mj_contactParam: the
    model's override when enabled; an explicit ``<pair>``'s own; else the higher priority's; else the
    solmix-weighted mean, of a solref only where both are standard (positive), the least of each entry
    otherwise)."""
    import mujoco

    if model.opt.enableflags & mujoco.mjtEnableBit.mjENBL_OVERRIDE:
        return (float(model.opt.o_solref[0]), float(model.opt.o_solref[1])), np.asarray(model.opt.o_solimp, float)
    k = pairs.get((g1, g2), pairs.get((g2, g1)))
    if k is not None:
        return (float(model.pair_solref[k, 0]), float(model.pair_solref[k, 1])), np.asarray(model.pair_solimp[k], float)
    p1, p2 = int(model.geom_priority[g1]), int(model.geom_priority[g2])
    if p1 != p2:
        g = g1 if p1 > p2 else g2
        return (float(model.geom_solref[g, 0]), float(model.geom_solref[g, 1])), np.asarray(model.geom_solimp[g], float)
    m1, m2, tiny = float(model.geom_solmix[g1]), float(model.geom_solmix[g2]), mujoco.mjMINVAL
    mix = (m1 / (m1 + m2) if m1 >= tiny and m2 >= tiny else 0.5 if m1 < tiny and m2 < tiny
           else 0.0 if m1 < tiny else 1.0)
    r1, r2 = np.asarray(model.geom_solref[g1], float), np.asarray(model.geom_solref[g2], float)
    ref = mix * r1 + (1 - mix) * r2 if r1[0] > 0 and r2[0] > 0 else np.minimum(r1, r2)
    imp = mix * np.asarray(model.geom_solimp[g1], float) + (1 - mix) * np.asarray(model.geom_solimp[g2], float)
    return (float(ref[0]), float(ref[1])), imp


def _touching(fates: Fates, model: Any):
    """Each pair of geoms that may touch (MuJoCo's collision filter), a controlled or fated body's
    first, for each such body in turn: ``(body, g1, g2, the other's name, pairs)`` (a geom's own
    name, else its body's; ``pairs``: the model's ``<pair>`` geoms, to their index)."""
    import mujoco

    pairs = {(int(a), int(b)): k for k, (a, b) in enumerate(zip(model.pair_geom1, model.pair_geom2))}
    excluded, pairset = set(model.exclude_signature.tolist()), set(pairs)
    for name in dict.fromkeys([c.body for c in fates.controls] + [f.body for f in fates.fates]):
        b = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name)
        mine = [g for g in range(model.ngeom) if int(model.geom_bodyid[g]) == b]
        for g1 in mine:
            for g2 in range(model.ngeom):
                if g2 not in mine and _collides(model, g1, g2, pairset, excluded):
                    other = model.geom(g2).name or model.body(int(model.geom_bodyid[g2])).name or f"geom {g2}"
                    yield name, g1, g2, other, pairs


def contact_time(timeconst: float, dampratio: float, timestep: float, refsafe: bool = True) -> float:
    """How long a contact of this ``solref`` (standard: a time constant and a damping ratio, both
    > 0) pushes before the bodies part, s. MuJoCo makes of it a linear spring and dashpot of
    stiffness ``1 / (tau zeta)^2`` and damping ``2 / tau`` per unit mass at full impedance: a
    damping ratio ``zeta`` and a natural frequency ``w = 1 / (tau zeta)``, with ``tau`` at least two
    steps (MuJoCo's ``refsafe``). Such a contact ends when its force is zero, before the spring's
    half-period: at ``(pi - atan2(2 zeta sqrt(1 - zeta^2), 1 - 2 zeta^2)) / (w sqrt(1 - zeta^2))``
    (Schwager & Pöschel 2007, "Coefficient of restitution and linear-dashpot model revisited",
    Granular Matter 9: 465); critically damped, ``2 tau``; overdamped (``s = sqrt(zeta^2 - 1)``),
    ``ln((2 zeta^2 - 1 + 2 zeta s) / (2 zeta^2 - 1 - 2 zeta s)) / (2 w s)``."""
    tau = max(timeconst, 2.0 * timestep) if refsafe else timeconst
    z = float(dampratio)
    w = 1.0 / (tau * z)
    if z == 1.0:
        return 2.0 * tau
    if z > 1.0:
        s = math.sqrt(z * z - 1.0)
        return math.log((2.0 * z * z - 1.0 + 2.0 * z * s) / (2.0 * z * z - 1.0 - 2.0 * z * s)) / (2.0 * w * s)
    s = math.sqrt(1.0 - z * z)
    return (math.pi - math.atan2(2.0 * z * s, 1.0 - 2.0 * z * z)) / (w * s)


def short_contacts(fates: Fates, model: Any, *, steps: float = MIN_CONTACT_STEPS) -> list[tuple[str, str, float, float, float]]:
    """The contacts of a controlled or fated body that last fewer than ``steps`` steps
    (:func:`contact_time` of the solref MuJoCo gives the pair): such a bounce is not resolved by the
    step, so it changes with the step and with where in a step the contact begins (the ladder's h/2
    and h/4 then seldom agree with h). Each ``(body, other, seconds, timeconst, dampratio)``, the
    shortest per body and other (a geom's name, else its body's), shortest first; a direct
    (negative) solref is not judged. Compute only (``nbst scene check`` prints them)."""
    import mujoco

    h = float(model.opt.timestep)
    refsafe = not model.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_REFSAFE
    out: dict[tuple[str, str], tuple[float, float, float]] = {}
    done: set[frozenset[int]] = set()   # a pair of two such bodies' geoms, said once
    for name, g1, g2, other, pairs in _touching(fates, model):
        if frozenset((g1, g2)) in done:
            continue
        done.add(frozenset((g1, g2)))
        (tau, zeta), _ = _pair_sol(model, g1, g2, pairs)
        if tau <= 0 or zeta <= 0:
            continue
        t = contact_time(tau, zeta, h, refsafe)
        if t < steps * h and ((name, other) not in out or t < out[(name, other)][0]):
            out[(name, other)] = (t, tau, zeta)
    return sorted(((b, o, *v) for (b, o), v in out.items()), key=lambda r: (r[2], r[0], r[1]))


def _pair_condim_friction(model: Any, g1: int, g2: int, pairs: dict[tuple[int, int], int]) -> tuple[int, np.ndarray]:
    """The condim and the (sliding, torsional, rolling) friction MuJoCo gives a contact of ``g1`` and
    ``g2`` (mj_contactParam: a ``<pair>``'s own; else the higher priority's; else the larger of each)."""
    k = pairs.get((g1, g2), pairs.get((g2, g1)))
    if k is not None:
        f = model.pair_friction[k]
        return int(model.pair_dim[k]), np.array([f[0], f[2], f[3]], dtype=float)
    p1, p2 = int(model.geom_priority[g1]), int(model.geom_priority[g2])
    if p1 != p2:
        g = g1 if p1 > p2 else g2
        return int(model.geom_condim[g]), np.array(model.geom_friction[g], dtype=float)
    return (max(int(model.geom_condim[g1]), int(model.geom_condim[g2])),
            np.maximum(model.geom_friction[g1], model.geom_friction[g2]).astype(float))


#: MuJoCo's default geom friction (sliding, torsional, rolling): every geom carries it, ignored at the
#: default condim 3; a value other than these was written by someone who meant it.
_MJ_FRICTION = (1.0, 0.005, 0.0001)


def ignored_friction(fates: Fates, model: Any) -> list[tuple[str, str, str, float, int]]:
    """The contacts of a controlled or fated body whose torsional or rolling friction MuJoCo ignores:
    each ``(body, other, "rolling" | "torsional", value, condim)`` where the pair's condim is under 6
    (rolling) or 4 (torsional) while that friction is above 0 and not MuJoCo's default (every geom
    carries 0.005 and 0.0001, unused at the default condim 3: not noted) (a ball given rolling resistance in
    ``friction`` rolls on for ever at condim 3, the default: ``at_rest`` then can not be met), the
    first such other per body and kind. Compute only (``nbst scene check`` prints them)."""
    out: dict[tuple[str, str], tuple[str, float, int]] = {}
    for name, g1, g2, other, pairs in _touching(fates, model):
        condim, fr = _pair_condim_friction(model, g1, g2, pairs)
        for kind, value, need, default in (("torsional", fr[1], 4, _MJ_FRICTION[1]),
                                           ("rolling", fr[2], 6, _MJ_FRICTION[2])):
            if value > 0 and not math.isclose(value, default) and condim < need and (name, kind) not in out:
                out[(name, kind)] = (other, float(value), condim)
    return [(b, o, kind, v, c) for (b, kind), (o, v, c) in out.items()]


def endless_rolls(fates: Fates, model: Any) -> list[tuple[str, str, int]]:
    """Bodies that must end ``at_rest`` and can roll (a sphere, capsule, cylinder or ellipsoid geom)
    while a contact they may make applies no rolling friction (condim under 6, or rolling friction
    0): MuJoCo then gives a rolling body no resistance at all, and it may roll for ever (an eighth
    new user's ball in a cup and stick on a floor: 0 of 11 runs met; with condim 6 and rolling
    friction, met). Each ``(body, the first such other, condim)``. Compute only."""
    import mujoco

    round_ = {int(mujoco.mjtGeom.mjGEOM_SPHERE), int(mujoco.mjtGeom.mjGEOM_CAPSULE),
              int(mujoco.mjtGeom.mjGEOM_CYLINDER), int(mujoco.mjtGeom.mjGEOM_ELLIPSOID)}
    resting = {f.body for f in fates.fates if f.at_rest}
    out: dict[str, tuple[str, int]] = {}
    for name, g1, g2, other, pairs in _touching(fates, model):
        if name not in resting or name in out or int(model.geom_type[g1]) not in round_:
            continue
        condim, fr = _pair_condim_friction(model, g1, g2, pairs)
        if condim < 6 or fr[2] <= 0:
            out[name] = (other, condim)
    return [(b, o, c) for b, (o, c) in out.items()]


#: A body that would rest deeper than this share of its smallest half-size is noted (:func:`deep_rests`).
SINK_SHARE = 0.1


def resting_depth(solref: tuple[float, float], solimp, gravity: float, timestep: float = 0.0) -> float:
    """How deep (m) a body rests in a contact of this standard ``solref`` and ``solimp`` under
    ``gravity`` (m/s^2): at rest MuJoCo's soft contact holds the penetration r where
    d(r) k r = (1 - d(r)) g, with k = d(r) / (dmax^2 tau^2 zeta^2) (``tau`` at least two steps,
    refsafe) and d(r) the impedance ``solimp`` gives at r (its midpoint and power), so
    r = (1 - d) g dmax^2 tau^2 zeta^2 / d^2, solved by bisection. 0 for a direct (negative) solref."""
    tau, zeta = max(float(solref[0]), 2.0 * timestep), float(solref[1])
    if solref[0] <= 0 or zeta <= 0 or gravity <= 0:
        return 0.0
    d0, dw, width, mid, power = (list(map(float, solimp)) + [0.5, 2.0])[:5]

    def d_of(r: float) -> float:
        x = min(r / width, 1.0) if width > 0 else 1.0
        if x >= 1.0 or power == 1.0:
            y = x
        elif x <= mid:
            y = x ** power / mid ** (power - 1)
        else:
            y = 1 - (1 - x) ** power / (1 - mid) ** (power - 1)
        return min(max(d0 + y * (dw - d0), 1e-4), 0.9999)

    lo, hi = 0.0, 10.0
    for _ in range(100):
        r = 0.5 * (lo + hi)
        d = d_of(r)
        if r < (1 - d) * gravity * dw * dw * tau * tau * zeta * zeta / (d * d):
            lo = r
        else:
            hi = r
    return 0.5 * (lo + hi)


def deep_rests(fates: Fates, model: Any, *, share: float = SINK_SHARE) -> list[tuple[str, str, float, float]]:
    """The controlled or fated bodies that would rest on a geom fixed to the world (a floor, a table)
    deeper than ``share`` of their smallest half-size (a sphere's radius, a box's least half side):
    each ``(body, other, depth, half)`` (m), the deepest per body (:func:`resting_depth` of the pair's
    solref and solimp; a small scene in MuJoCo's default contact sinks: 0.37 mm). Compute only."""
    import mujoco

    gravity = float(np.linalg.norm(model.opt.gravity))
    # refsafe holds a time constant at two steps (resting_depth's timestep; none when it is off)
    h = 0.0 if model.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_REFSAFE else float(model.opt.timestep)
    worst: dict[str, tuple[str, str, float, float]] = {}
    for name, g1, g2, other, pairs in _touching(fates, model):
        if int(model.body_weldid[int(model.geom_bodyid[g2])]) != 0:   # on what is fixed to the world
            continue
        size = np.asarray(model.geom_size[g1], float)
        half = float(size[size > 0].min()) if (size > 0).any() else float(model.geom_rbound[g1])
        depth = resting_depth(*_pair_sol(model, g1, g2, pairs), gravity, h)
        if depth > share * half and (name not in worst or depth / half > worst[name][2] / worst[name][3]):
            worst[name] = (name, other, depth, half)
    out = list(worst.values())
    return out
