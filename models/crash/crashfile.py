"""Crash files: what ``nbst crash solve`` writes, ``nbst crash replay`` checks and ``nbst render`` films.

A crash file (JSON, ``kind`` :data:`KIND`) holds everything a renderer or a plain MuJoCo user
needs, nothing to look up elsewhere:

* ``script``: the crash script as given (its fates are also in ``vehicles[i].fate``);
* ``scene_xml``: the MJCF text the rollout ran on (road, vehicles, sensors; every number
  exact), ``timestep`` (s), ``duration`` (s), ``nstep``;
* ``vehicles``: per vehicle its name, type and figures, its body, free joint, actuators (in
  control order), wheel bodies and tyre geoms, colour, the driver's intent (user units) and
  the fate asked (user units: rest region, heading and its tolerance, hits, ...), and for a
  crushing type ``crush``: the residual crush per zone and the EES (:func:`.crush.crush_record`);
* ``intents``: the drivers' intents, exact (SI; ``columns`` the intent names, one row per
  vehicle, null = off): what ``nbst crash probability`` perturbs;
* ``qpos0``, ``qvel0``: the initial state (JSON floats by ``repr``: exact);
* ``controls``: the realised controls, steps x actuators run-length coded: ``actuators``
  (names, the model's order), ``period_steps`` and ``rows``: row k holds for steps
  ``[k * period_steps, (k + 1) * period_steps)`` (the last row to ``nstep``);
* ``outcome``: solved, the signature (one character per vehicle), the order check, the cost,
  ``contacts`` (pairs in the order they first touched: times, the first contact point, the
  impulse and each vehicle's delta-V) and per vehicle what happened
  (:meth:`.outcome.VehicleOutcome.to_dict`);
* ``final_qpos``: the state after ``nstep`` steps, which a replay must reproduce bit for bit;
* ``probability``: P(fates) under driver noise, measured by every ``nbst crash solve`` (null
  when skipped, ``--samples 0``; absent in files written before it was measured by default):
  ``k`` of ``n`` noisy re-drives met the script, ``p``, the 95 % Wilson interval ``lo``-``hi``,
  the noise's ``seed``, ``noise_kind`` (retake or population; absent: retake), the standard
  deviations ``noise`` (SI; ``noise_relative`` names the columns given as a share of the
  intent) and the ``outcomes`` seen (label: count);
* ``seed``, ``search``, and when measured ``ladder`` (and ``robust``).

Replay (:func:`replay`): a fresh ``MjData``, ``qpos0``/``qvel0`` set, then for each row
``data.ctrl[:] = row; mj_step`` for its steps (docs/crash.md has the recipe as plain MuJoCo);
the outcome is read again with the same sensors and compared.

Input gate: :func:`load` reads through nbst's core JSON reader, checks every field it uses,
refuses a scene that reads other files, and checks the shapes against the scene; one
:class:`CrashFileError` line naming the file and the field.

Compute apart from I/O: :func:`crash_dict` builds the dict; the CLI writes it.
"""
from __future__ import annotations

import math
import re

import numpy as np

from nbst.errors import InputError
from nbst.models.crash import crush as crush_mod
from nbst.models.crash import driver as drv
from nbst.models.crash import outcome as out_mod
from nbst.models.crash import scene as scene_mod
from nbst.models.crash import vehicle as veh
from nbst.models.crash.script import AFTER_IMPACT, Script, ScriptError, script_from_dict
from nbst.problem import ProblemError, read_json

__all__ = ["KIND", "SCHEMA_VERSION", "QPOS_MAX", "QVEL_MAX", "CTRL_MAX", "MAX_XML_CHARS", "CrashFileError",
           "intents_dict", "fate_dict", "outcome_dict", "crash_dict", "load", "intents_array",
           "controls_array", "replay"]

KIND = "nbst-crash"
SCHEMA_VERSION = 1
#: A scene may not read other files (meshes, textures, includes): it is one self-contained XML.
_READS_FILES = re.compile(r"\bfile\s*=|<\s*include\b|\b(?:mesh|texture|asset)dir\s*=", re.IGNORECASE)
#: Bounds on a crash state: positions within 10 km, speeds under 1 km/s (MuJoCo overflows long before 1e300).
QPOS_MAX, QVEL_MAX, CTRL_MAX = 1e4, 1e3, 1e5
MAX_XML_CHARS = 4_000_000


class CrashFileError(InputError):
    """A crash file nbst refuses: one line naming the file and the field."""


def _fail(src, field: str, why: str):
    raise CrashFileError(f"{src}: {field}: {why}" if field else f"{src}: {why}")


def intents_dict(script: Script, intents: np.ndarray) -> list[dict]:
    """Each driver's intent in user units (km/h, degrees, s, m); absent behaviours left out."""
    IX = drv.IX
    out = []
    for i, _ in enumerate(script.vehicles):
        row = intents[i]
        g = lambda k: float(row[IX[k]])  # noqa: E731
        d: dict[str, object] = {"speed_kmh": round(g("speed") * 3.6, 4)}
        if math.isfinite(g("aim_x")):
            d["aim"] = [round(g("aim_x"), 4), round(g("aim_y"), 4)]
        for k in ("arrive", "brake_at", "slide_at", "slide_power", "headway", "reaction"):
            if math.isfinite(g(k)):
                d[k] = round(g(k), 4)
        for k in ("slide_steer", "after_steer"):
            if math.isfinite(g(k)):
                d[k + "_deg"] = round(math.degrees(g(k)), 3)
        d["after_impact"] = AFTER_IMPACT[int(g("after"))]
        out.append(d)
    return out


def fate_dict(script: Script, i: int) -> dict:
    """Vehicle ``i``'s fate in user units (what the renderer draws and the readout asks)."""
    f, names = script.vehicles[i].fate, script.names()
    d: dict = {}
    if f.hits is not None:
        d["hits"] = [names[j] for j in f.hits]
    for k in ("impact_speed", "delta_v"):
        r = getattr(f, k)
        if r is not None:
            d[k + "_kmh"] = [r.lo * 3.6, r.hi * 3.6]
    if f.rest is not None:
        d["rest"] = {"x": f.rest[0], "y": f.rest[1], "radius": f.rest[2]}
    if f.impact_at is not None:
        d["impact_at"] = {"x": f.impact_at[0], "y": f.impact_at[1], "radius": f.impact_at[2]}
    if f.heading is not None:
        d["heading"] = {"deg": math.degrees(f.heading[0]), "tol": math.degrees(f.heading[1])}
    if f.quarter_turns is not None:
        d["quarter_turns"] = list(f.quarter_turns)
    if f.attitude is not None:
        d["attitude"] = f.attitude
    if f.spin is not None:
        d["spin"] = {"deg": math.degrees(f.spin[0]), "tol": math.degrees(f.spin[1])}
    for k in ("curb", "barrier"):
        if getattr(f, k) is not None:
            d.setdefault("strikes", {})[k] = getattr(f, k)
    return d


def outcome_dict(o: out_mod.Outcome, script: Script, mass) -> dict:
    names = script.names()
    contacts = []
    for i, j, t0, t1, pos, J in o.contacts:
        contacts.append({"a": names[i], "b": names[j], "t": round(t0, 4), "t_end": round(t1, 4),
                         "pos": [round(float(x), 4) for x in pos], "impulse_Ns": [round(float(x), 2) for x in J],
                         "delta_v_kmh": {names[i]: round(float(np.linalg.norm(J)) / mass[i] * 3.6, 2),
                                         names[j]: round(float(np.linalg.norm(J)) / mass[j] * 3.6, 2)}})
    return {"solved": o.solved, "signature": o.signature_text(script.n), "order_ok": o.order_ok,
            "cost": round(o.cost, 6), "contacts": contacts, "vehicles": [v.to_dict(names) for v in o.vehicles]}


def crash_dict(script: Script, xml: str, model, intents: np.ndarray, qpos0, qvel0, controls: np.ndarray,
               final_qpos, outcome: out_mod.Outcome, *, seed: int | None, search: dict | None = None,
               period_steps: int) -> dict:
    """The crash file's content (see the module docstring)."""
    import mujoco

    L = scene_mod.layout(model, script.n)
    vehicles = []
    for i, v in enumerate(script.vehicles):
        p = scene_mod.vehicle_prefix(i)
        vehicles.append({
            "name": v.name, **v.vtype.to_dict(), "body": p, "free_joint": f"{p}_free",
            "actuators": veh.control_names(p), "wheels": [f"{p}_wheel_{c}" for c in veh.CORNERS],
            "tyres": [f"{p}_tyre_{c}" for c in veh.CORNERS], "geoms": [f"{p}_lower", f"{p}_cabin"],
            "colour": list(scene_mod.COLOURS[i % len(scene_mod.COLOURS)]),
            "start": {"x": v.x, "y": v.y, "heading_deg": math.degrees(v.heading)},
            "intent": intents_dict(script, intents)[i], "fate": fate_dict(script, i)})
        if v.vtype.crush:  # residual crush per zone and the EES (crush.crush_record)
            vehicles[-1]["crush"] = crush_mod.crush_record(model, p, v.vtype, final_qpos)
    d = {
        "schema_version": SCHEMA_VERSION, "kind": KIND, "name": script.name, "script": script.raw,
        "scene_xml": xml, "timestep": float(model.opt.timestep), "duration": script.duration,
        "nstep": int(round(script.duration / model.opt.timestep)),
        "vehicles": vehicles,
        "intents": {"columns": list(drv.INTENT),
                    "rows": [[None if math.isnan(x) else float(x) for x in row] for row in intents]},
        "qpos0": [float(x) for x in qpos0], "qvel0": [float(x) for x in qvel0],
        "controls": {"actuators": [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_ACTUATOR, k) for k in range(model.nu)],
                     "period_steps": int(period_steps), "rows": [[float(x) for x in r] for r in controls]},
        "outcome": outcome_dict(outcome, script, L.mass),
        "final_qpos": [float(x) for x in final_qpos],
        "seed": seed, "mujoco": mujoco.__version__,
    }
    if search is not None:
        d["search"] = search
    return d


# --------------------------------------------------------------------------- reading

def _vector(d, key, src, bound, n=None) -> np.ndarray:
    v = d.get(key)
    if not isinstance(v, list):
        _fail(src, key, "must be a list of numbers")
    for i, x in enumerate(v):
        if isinstance(x, bool) or not isinstance(x, (int, float)) or not abs(x) <= bound:
            _fail(src, f"{key}[{i}]", f"must be a finite number within +-{bound:g}")
    if n is not None and len(v) != n:
        _fail(src, key, f"has {len(v)} numbers; the scene needs {n}")
    return np.array(v, dtype=float)


def load(path):
    """(crash dict, Script, MjModel) of a crash file, everything checked (see the module docstring)."""
    try:
        d = read_json(path)
    except ProblemError as e:
        raise CrashFileError(str(e)) from None
    src = str(path)
    if not isinstance(d, dict) or d.get("kind") != KIND:
        _fail(src, "kind", f"not an nbst crash file (kind must be {KIND!r}); a crash script is solved with "
                           f"`nbst crash solve`")
    for k in ("script", "scene_xml", "intents", "qpos0", "qvel0", "controls", "outcome", "final_qpos"):
        if k not in d:
            _fail(src, k, "missing")
    try:
        script = script_from_dict(d["script"], source=f"{src}: script")
    except ScriptError as e:
        raise CrashFileError(str(e)) from None
    xml = d["scene_xml"]
    if not isinstance(xml, str) or not xml or len(xml) > MAX_XML_CHARS:
        _fail(src, "scene_xml", f"must be the scene's MJCF text (at most {MAX_XML_CHARS:,} characters)")
    if _READS_FILES.search(xml):
        _fail(src, "scene_xml", "reads other files (file=, include or a *dir attribute); a crash scene is one "
                                "self-contained XML")
    try:
        model = scene_mod.model_from_xml(xml)
    except ValueError as e:
        _fail(src, "scene_xml", f"cannot load it as a MuJoCo scene ({str(e).strip().splitlines()[0]})")
    try:
        scene_mod.layout(model, script.n)
    except KeyError as e:
        _fail(src, "scene_xml", f"is not the scene of its script ({e.args[0] if e.args else 'a body is missing'})")
    if not (0 < model.opt.timestep <= 0.01):
        _fail(src, "scene_xml", f"timestep {model.opt.timestep:g} s is outside (0, 0.01]")
    _vector(d, "qpos0", src, QPOS_MAX, model.nq)
    _vector(d, "qvel0", src, QVEL_MAX, model.nv)
    _vector(d, "final_qpos", src, QPOS_MAX, model.nq)
    c = d["controls"]
    if not isinstance(c, dict) or not isinstance(c.get("rows"), list):
        _fail(src, "controls", "must be an object with rows (one list of controls per period)")
    ps = c.get("period_steps")
    if isinstance(ps, bool) or not isinstance(ps, int) or not 1 <= ps <= 10_000:
        _fail(src, "controls.period_steps", "must be a whole number of steps in [1, 10000]")
    nstep = int(round(script.duration / model.opt.timestep))
    if len(c["rows"]) != -(-nstep // ps):
        _fail(src, "controls.rows", f"{len(c['rows'])} rows; {script.duration:g} s at {model.opt.timestep:g} s in "
                                    f"periods of {ps} steps needs {-(-nstep // ps)}")
    for k, row in enumerate(c["rows"]):
        _vector({"r": row}, "r", f"{src}: controls.rows[{k}]", CTRL_MAX, model.nu)
    _probability(d.get("probability"), src)
    it = d["intents"]
    if not isinstance(it, dict) or it.get("columns") != list(drv.INTENT) or not isinstance(it.get("rows"), list) \
            or len(it["rows"]) != script.n:
        _fail(src, "intents", f"must hold columns {list(drv.INTENT)} and one row per vehicle")
    for k, row in enumerate(it["rows"]):
        if not isinstance(row, list) or len(row) != len(drv.INTENT) or not all(
                x is None or (isinstance(x, (int, float)) and not isinstance(x, bool) and abs(x) <= QPOS_MAX)
                for x in row):
            _fail(src, f"intents.rows[{k}]", f"must be {len(drv.INTENT)} finite numbers (or null: off)")
        a = row[drv.IX["after"]]
        if a is None or a not in (0, 1, 2):
            _fail(src, f"intents.rows[{k}]", "its after-impact code must be 0, 1 or 2")
    return d, script, model


def _probability(p, src) -> None:
    """A crash file's ``probability``: absent or null (not measured), else its fields checked."""
    if p is None:
        return
    if not isinstance(p, dict):
        _fail(src, "probability", "must be an object (k, n, p, lo, hi, ...) or null")
    for k in ("k", "n"):
        if isinstance(p.get(k), bool) or not isinstance(p.get(k), int):
            _fail(src, f"probability.{k}", "must be a whole number")
    if not 0 <= p["k"] <= p["n"] or p["n"] < 1:
        _fail(src, "probability", f"k = {p['k']} of n = {p['n']}: need 0 <= k <= n and n >= 1")
    for k in ("p", "lo", "hi"):
        x = p.get(k)
        if isinstance(x, bool) or not isinstance(x, (int, float)) or not 0.0 <= x <= 1.0:
            _fail(src, f"probability.{k}", "must be a number in [0, 1]")
    if not p["lo"] <= p["p"] <= p["hi"]:
        _fail(src, "probability", "p must lie in its interval [lo, hi]")
    kind = p.get("noise_kind", drv.NOISE_KIND_NAMES[0])
    if kind not in drv.NOISE_KIND_NAMES:
        _fail(src, "probability.noise_kind", f"must be one of {', '.join(drv.NOISE_KIND_NAMES)}")


def intents_array(d: dict, script: Script) -> np.ndarray:
    """(n, len(INTENT)) the drivers' intents of a checked crash dict (SI, exact; NaN = off)."""
    return np.array([[np.nan if x is None else x for x in row] for row in d["intents"]["rows"]], dtype=float)


def controls_array(d: dict) -> np.ndarray:
    """(periods, nu) of a checked crash dict."""
    return np.array(d["controls"]["rows"], dtype=float)


def replay(d: dict, script: Script, model, *, on_step=None):
    """Replay a checked crash dict with plain ``mj_step``: (final qpos, judged Outcome).
    ``on_step(k, data)``, when given, is called after step k (1 .. nstep) and only reads
    ``data`` (the renderer records the motion through it: the replay it films is this one)."""
    import mujoco

    L = scene_mod.layout(model, script.n)
    rows = controls_array(d)
    ps = int(d["controls"]["period_steps"])
    dt = float(model.opt.timestep)
    nstep = int(round(script.duration / dt))
    md = mujoco.MjData(model)
    md.qpos[:] = d["qpos0"]
    md.qvel[:] = d["qvel0"]
    rec = out_mod.Recorder(L, 1, dt)
    rec.begin(md.qpos[None])
    vi = L.qvel[:, None] + np.arange(2)
    pxy = L.qpos[:, None] + np.arange(2)
    for k in range(nstep):
        if k % ps == 0:
            md.ctrl[:] = rows[k // ps]
            if k:
                rec.period(md.qpos[None])
        vel, pos = md.qvel[vi][None], md.qpos[pxy][None]
        mujoco.mj_step(model, md)
        rec.step((k + 1) * dt, md.sensordata[None], vel, pos)
        if on_step is not None:
            on_step(k + 1, md)
    rec.finish(md.qpos[None], md.qvel[None])
    o = out_mod.outcomes(rec, script.names(), L.mass)[0]
    out_mod.judge(o, script, rec.min_dist[0])
    return md.qpos.copy(), o
