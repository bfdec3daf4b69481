"""Planted crashes: scripts whose answer is known, for the benchmarks and the tests.

A **planted script** runs hidden driver intents, drawn uniformly within a template's ranges, and
writes what happened as the fates (whom each hit and in what order, where it came to rest and
facing where, its attitude), with the tolerances asked: a search must find intents that do the
same, and one is known to exist (by default one that also holds at 1 and 0.5 ms, as the
search's acceptance asks: :func:`holds_on_ladder`; and, ``min_p`` given, one that its own
drivers, re-driven with the driver noise, meet that often: :func:`hidden_probability`). A **planted case** does the same for reconstruction, and keeps
the hidden truth (each vehicle's impact speed and heading) for the comparison.

A **planted reconstruction** (:func:`planted_reconstruction`, the templates of
:data:`RECON_TEMPLATES`: a 90 degree crossing, a 30 degree oblique, an offset head-on, a
same-lane rear-end) also hides the road friction, the loads and the contact's stiffness and
damping, drawn in the ranges the case states: the reconstruction's coverage benchmark.

Templates (:data:`TEMPLATES`): ``crossing2`` (a sedan and an SUV meeting at an intersection,
after-impact braking known: the reconstruction's planted crashes), ``intersection3`` (three
vehicles at an intersection: the search's planted scripts).

Compute only.
"""
from __future__ import annotations

import copy
import math
from typing import Any

import numpy as np

from nbst.errors import SolveError
from nbst.models.crash import robust
from nbst.models.crash import script as script_mod
from nbst.models.crash.run import CrashRunner
from nbst.models.crash.search import LADDER_CHECK_TIMESTEPS
from nbst.models.crash.space import space_of

__all__ = ["TEMPLATES", "holds_on_ladder", "COPIES", "COPIES_SEED", "hidden_probability", "planted_script",
           "FUNNEL_STEPS", "funnel", "planted_case", "RECON_TEMPLATES",
           "PLANT_REST", "PLANT_HEADING", "PLANT_IMPACT", "planted_reconstruction"]

_ROAD = {"layout": "intersection", "width": 7, "length": 120, "curb": 0.15}
TEMPLATES = {
    "crossing2": {
        "kind": "nbst-crash-script", "road": _ROAD, "duration": 6.0,
        "vehicles": [
            {"name": "A", "type": "sedan", "start": {"x": -45, "y": -1.75, "heading": 0}, "speed": [30, 80],
             "driver": {"aim": {"x": [-3, 6], "y": [-3, 0]}, "arrive": [2.2, 4.0], "after_impact": "brake"}},
            {"name": "B", "type": "suv", "start": {"x": 1.75, "y": -45, "heading": 90}, "speed": [30, 80],
             "driver": {"aim": {"x": [0, 3], "y": [-3, 6]}, "arrive": [2.2, 4.0], "after_impact": "brake"}}]},
    "intersection3": {
        "kind": "nbst-crash-script", "road": _ROAD, "duration": 6.0,
        "vehicles": [
            {"name": "A", "type": "sedan", "start": {"x": -45, "y": -1.75, "heading": 0}, "speed": [40, 70],
             "driver": {"aim": {"x": [-5, 10], "y": [-4, 1]}, "arrive": [2.5, 4.0], "after_impact": ["brake", "coast"],
                        "after_steer": [-20, 20]}},
            {"name": "B", "type": "suv", "start": {"x": 1.75, "y": -45, "heading": 90}, "speed": [30, 60],
             "driver": {"aim": {"x": [-2, 5], "y": [-5, 10]}, "arrive": [2.5, 4.0], "after_impact": ["brake", "coast"],
                        "after_steer": [-20, 20]}},
            {"name": "C", "type": "van", "start": {"x": -1.75, "y": 25, "heading": -90}, "speed": [0, 30],
             "driver": {"brake_at": [0.5, 3.0], "after_impact": ["brake", "coast"]}}]},
}


def _hidden(template: dict, rng: np.random.Generator, need_contacts: int, tries: int = 64):
    """(script of the template, hidden unit point, its outcome) of every drawn rollout with at least
    ``need_contacts`` vehicle contacts, in the order drawn (``tries`` batches at most)."""
    s = script_mod.script_from_dict(copy.deepcopy(template), source="<planted template>")
    S = space_of(s)
    R = CrashRunner(s)
    try:
        for _ in range(tries):
            U = rng.random((16, S.dim))
            res = R.run(S.intents(U))
            for u, o in zip(U, res.outcomes):
                if len(o.contacts) >= need_contacts and all(v.rest == v.rest for v in o.vehicles):
                    yield s, u, o
    finally:
        R.close()


def _fates(template: str, seed: int, s, o, radius: float, heading_tol: float) -> dict:
    """The template with the outcome ``o`` written as its fates."""
    d: dict[str, Any] = copy.deepcopy(TEMPLATES[template])
    names = s.names()
    d["name"] = f"planted-{template}-{seed}"
    for v, vo in zip(d["vehicles"], o.vehicles):
        v["fate"] = {"hits": [names[j] for j, _ in vo.hits],
                     "rest": {"x": round(vo.rest[0], 3), "y": round(vo.rest[1], 3), "radius": radius},
                     "heading": {"deg": round(math.degrees(vo.rest[2]), 2), "tol": heading_tol},
                     "attitude": vo.attitude}
    d["order"] = [[names[i], names[j]] for i, j in o.sequence]
    return d


def holds_on_ladder(d: dict, u: np.ndarray, timesteps=LADDER_CHECK_TIMESTEPS) -> bool:
    """Whether the intents of unit point ``u`` meet script ``d`` with the same contact sequence at
    every one of ``timesteps`` too (the search's acceptance: :func:`.search.ladder_check`)."""
    s = script_mod.script_from_dict(copy.deepcopy(d), source="<planted>")
    want = tuple(tuple(s.names().index(n) for n in pair) for pair in d["order"])
    intents = space_of(s).intents(u[None])
    for h in timesteps:
        R = CrashRunner(s, timestep=h, batch=1)
        try:
            o = R.run(intents).outcomes[0]
        finally:
            R.close()
        if not (o.solved and o.sequence == want):
            return False
    return True


#: Noisy re-drives (and their seed) of a hidden answer for :func:`hidden_probability`.
COPIES, COPIES_SEED = 32, 0


def hidden_probability(d: dict, u: np.ndarray, copies: int = COPIES, seed: int = COPIES_SEED, jobs: int = 1):
    """How often the hidden intents of unit point ``u``, re-driven ``copies`` times with the driver
    noise (:data:`.robust.NOISE`, common random numbers of ``seed``), meet script ``d`` at its own
    step: a :class:`.robust.CrashEstimate` (k of n, the Wilson interval, the outcomes seen). A
    crash whose fates its own drivers meet only by luck is a chaotic outcome (docs/results/crash.md)."""
    s = script_mod.script_from_dict(copy.deepcopy(d), source="<planted>")
    R = CrashRunner(s, jobs=jobs)
    try:
        return robust.probability(R, space_of(s).intents(u[None])[0], copies, seed)
    finally:
        R.close()


def _plant(seed: int, template: str, radius: float, heading_tol: float, need_contacts: int, ladder=None,
           min_p: float | None = None, tries: int = 64):
    rng = np.random.default_rng([int(seed), 32])
    for s, u, o in _hidden(TEMPLATES[template], rng, need_contacts, tries):
        d = _fates(template, seed, s, o, radius, heading_tol)
        if ladder is not None and not holds_on_ladder(d, u, ladder):
            continue
        if min_p is None or hidden_probability(d, u).p >= min_p:  # after the ladder: 32 rollouts, not 2
            return d, u, o
    raise SolveError(f"planted crash (seed {seed}, template {template!r}): none with {need_contacts} contacts "
                     f"in the {tries} tries allowed")


def planted_script(seed: int, *, template: str = "intersection3", radius: float = 2.0, heading_tol: float = 20.0,
                   need_contacts: int = 2, ladder=LADDER_CHECK_TIMESTEPS,
                   min_p: float | None = None) -> tuple[dict, np.ndarray]:
    """(script dict, hidden unit point): the template with the fates of hidden random intents
    that make at least ``need_contacts`` vehicle contacts (2: a chain worth the name, not one
    collision and a bystander) and, ``ladder`` not None, that keep meeting those fates with the
    same contact sequence at each of its timesteps (s): the search counts a script as solved
    only so (:data:`.search.LADDER_CHECK_TIMESTEPS`), and a planted script promises an answer
    that counts.
    ``ladder=None`` plants the first draw with enough contacts, whatever the ladder says (at
    seeds 100-109 half of those answers lose their own script at 1 or 0.5 ms: docs/crash.md).
    ``min_p`` not None plants only a hidden answer that :func:`hidden_probability` (32 noisy
    re-drives) finds met at least that often: a crash its drivers could stage again, not a lucky
    draw (most draws are; at 0.25, 4 of 80 draws measured qualify: docs/results/crash.md)."""
    d, u, _ = _plant(seed, template, radius, heading_tol, need_contacts, ladder, min_p,
                     tries=64 if min_p is None else 512)
    if min_p is not None:
        d["name"] += f"-p{min_p:g}"
    return d, u


#: The funnel probe's steps (unit cube): a Gaussian step of each continuous coordinate.
FUNNEL_STEPS = (0.002, 0.005, 0.01, 0.02, 0.04)


def funnel(d: dict, u: np.ndarray, steps=FUNNEL_STEPS, n: int = 32, seed: int = 0, jobs: int = 1) -> list[int]:
    """How many of ``n`` neighbours of the unit point ``u`` meet script ``d`` at its own step, for
    each Gaussian step of ``steps`` (unit cube; the continuous coordinates move, the after-impact
    choices stay; the points are clipped into the cube): the width of the met funnel around a
    planted script's hidden answer, which tells how hard the script is for a search (docs/results/crash.md)."""
    s = script_mod.script_from_dict(copy.deepcopy(d), source="<planted>")
    S = space_of(s)
    moves = np.array([isinstance(r, script_mod.Range) for _, _, r in S.coords], float)
    rng = np.random.default_rng([int(seed), 33])
    R = CrashRunner(s, jobs=jobs)
    try:
        out = []
        for step in steps:
            U = np.clip(u + step * moves * rng.standard_normal((n, S.dim)), 0.0, 1.0)
            out.append(sum(o.solved for o in R.run(S.intents(U)).outcomes))
        return out
    finally:
        R.close()


def planted_case(seed: int, *, template: str = "crossing2", radius: float = 1.0,
                 heading_tol: float = 10.0, impact_radius: float | None = 0.5) -> tuple[dict, list]:
    """(case dict, truth): a reconstruction case from a hidden crash of ``template`` (the fates:
    whom each hit, rest within ``radius`` m, heading within ``heading_tol`` deg; no speeds), and
    the truth per vehicle: {"impact_speed": m/s, "impact_heading": rad}."""
    d, _, o = _plant(seed, template, radius, heading_tol, 1)
    d["name"] = f"planted-case-{template}-{seed}"
    for v, vo in zip(d["vehicles"], o.vehicles):
        v["fate"].pop("attitude", None)
        if impact_radius is not None:
            v["fate"]["impact_at"] = {"x": round(vo.impact_pos[0], 3), "y": round(vo.impact_pos[1], 3),
                                      "radius": impact_radius}
    return d, [{"impact_speed": v.impact_speed, "impact_heading": v.impact_heading} for v in o.vehicles]


# --------------------------------------------------------------------------- reconstruction cases, unknowns hidden

_STRAIGHT = {"layout": "straight", "width": 7, "length": 200}
#: Two-car templates of the coverage benchmark (benchmarks/bench_crash_coverage.py) and the tests:
#: a 90 degree crossing, a 30 degree oblique on a wide plaza, an offset head-on and a same-lane rear-end.
RECON_TEMPLATES = {
    "crossing": {
        "kind": "nbst-crash-script", "road": {"layout": "intersection", "width": 7, "length": 120, "curb": 0.15},
        "duration": 5.5,
        "vehicles": [
            {"name": "A", "type": "sedan", "start": {"x": -45, "y": -1.75, "heading": 0}, "speed": [30, 80],
             "driver": {"aim": {"x": [-3, 6], "y": [-3, 0]}, "arrive": [2.2, 4.0], "after_impact": "brake"}},
            {"name": "B", "type": "suv", "start": {"x": 1.75, "y": -45, "heading": 90}, "speed": [30, 80],
             "driver": {"aim": {"x": [0, 3], "y": [-3, 6]}, "arrive": [2.2, 4.0], "after_impact": "brake"}}]},
    "oblique": {
        "kind": "nbst-crash-script", "road": {"layout": "straight", "width": 30, "length": 160}, "duration": 5.5,
        "vehicles": [
            {"name": "A", "type": "sedan", "start": {"x": -40, "y": 0, "heading": 0}, "speed": [40, 80],
             "driver": {"aim": {"x": [-2, 3], "y": [-1.5, 1.5]}, "arrive": [2.2, 3.2], "after_impact": "brake"}},
            {"name": "B", "type": "suv", "start": {"x": -22, "y": -12, "heading": 30}, "speed": [30, 60],
             "driver": {"aim": {"x": [-2, 3], "y": [-2, 2]}, "arrive": [2.2, 3.2], "after_impact": "brake"}}]},
    "head-on": {
        "kind": "nbst-crash-script", "road": _STRAIGHT, "duration": 4.5,
        "vehicles": [
            {"name": "A", "type": "sedan", "start": {"x": -30, "y": -1.75, "heading": 0}, "speed": [30, 70],
             "driver": {"aim": {"x": [10, 30], "y": [0.0, 2.5]}, "after_impact": "brake"}},
            {"name": "B", "type": "suv", "start": {"x": 30, "y": 1.75, "heading": 180}, "speed": [30, 70],
             "driver": {"after_impact": "brake"}}]},
    "rear-end": {
        "kind": "nbst-crash-script", "road": _STRAIGHT, "duration": 5.0,
        "vehicles": [
            {"name": "A", "type": "sedan", "start": {"x": 0, "y": -1.75, "heading": 0}, "speed": [30, 50],
             "driver": {"after_impact": "brake"}},
            {"name": "B", "type": "suv", "start": {"x": -12, "y": -1.75, "heading": 0}, "speed": [70, 90],
             "driver": {"after_impact": "brake"}}]},
}
#: The evidence's tolerances of a planted case: rest (m), heading at rest (deg), impact position (m).
PLANT_REST, PLANT_HEADING, PLANT_IMPACT = 1.5, 15.0, 1.0




def planted_reconstruction(template: str, seed: int, *, impact_at: bool = True,
                           friction: tuple = (0.7, 0.9)) -> tuple[dict, dict]:
    """(case dict, truth): a reconstruction case (``nbst-crash-case``) of one of
    :data:`RECON_TEMPLATES`: hidden intents, road friction (uniform in ``friction``, which the
    case states as its range but not the value), loads and contact factors (uniform in
    :mod:`.evidence`'s default ranges), simulated until a crash with one contact whose vehicles
    both come to rest; what happened written as the evidence (whom each hit, rest within
    :data:`PLANT_REST`, heading within :data:`PLANT_HEADING`, with ``impact_at`` the impact
    positions within :data:`PLANT_IMPACT`). The truth: per vehicle impact speed, delta-V (m/s)
    and PDOF (o'clock), the closing speed, the friction and the loads.

    Raises:
        SolveError: no such crash in 64 batches of draws."""
    from nbst.models.crash import evidence as ev_mod
    from nbst.models.crash import reconstruct as rc

    d: dict[str, Any] = copy.deepcopy(RECON_TEMPLATES[template])
    d["name"] = f"planted-{template}-{seed}"
    d["kind"] = ev_mod.CASE_KIND
    d["unknowns"] = {"friction": list(friction)}
    case = ev_mod.case_from_dict(d, source="<planted>")
    S = space_of(case.script)
    pc = rc.phys_coords(case)
    rng = np.random.default_rng([int(seed), 470])
    R = rc.PhysRunner(case)
    try:
        for _ in range(64):
            Z = rng.random((16, S.dim + len(pc)))
            phys = rc._phys_values(case, Z[:, S.dim:])
            rolls, track = R.run_phys(S.intents(Z[:, :S.dim]), phys)
            for k, o in enumerate(rolls.outcomes):
                if len(o.contacts) != 1 or any(v.moving or not v.hits for v in o.vehicles):
                    continue
                mass = R.L.mass + phys["load"][k]
                q = rc._quantities(case, o, track, k, mass)
                names = case.script.names()
                vehicles: list = d["vehicles"]
                for v, vo in zip(vehicles, o.vehicles):
                    v["fate"] = {"hits": [names[j] for j, _ in vo.hits],
                                 "rest": {"x": round(vo.rest[0], 3), "y": round(vo.rest[1], 3), "radius": PLANT_REST},
                                 "heading": {"deg": round(math.degrees(vo.rest[2]), 2), "tol": PLANT_HEADING}}
                    if impact_at:
                        v["fate"]["impact_at"] = {"x": round(vo.impact_pos[0], 3), "y": round(vo.impact_pos[1], 3),
                                                  "radius": PLANT_IMPACT}
                truth = {"vehicles": [{"impact_speed": float(q[3 * i]), "delta_v": float(q[3 * i + 1]),
                                       "pdof": float(q[3 * i + 2])} for i in range(case.n)],
                         "closing_speed": float(q[-1]), "friction": float(phys["friction"][k]),
                         "load": [float(x) for x in phys["load"][k]]}
                return d, truth
    finally:
        R.close()
    raise SolveError(f"planted reconstruction ({template!r}, seed {seed}): no single-contact crash with both "
                     "vehicles at rest in 64 batches")
