"""The pin carry fit (issue 34): pocket carry, flush-hit 10s and 4s, 3-10, 10 and 7 conversion against
the pins' parameters, each figure on the same noisy throws.

    python benchmarks/bench_carry_fit.py [--part sweep|fit|heldout|all] [--n 400] [--spares 100]
                                         [--seed 1] [--jobs 2] [--cache DIR]

**Pin-deck starts.** The pins' parameters do not touch the ball before it reaches them, so each
noisy throw's lane phase runs once (``frame.deck_start``: the state where the ball crosses the
deck front, h = 1 ms, fresh house shot) and every setting replays only the pin deck from there
(``frame.run_frame(start=...)`` on a copy of the frame model with the setting's pins): the same
balls meet every setting (common random numbers), and a setting costs the pin action alone.
The throws: ``--n`` first balls of the ``pro`` profile (its strike ball and release noise, seed
``--seed``), and ``--spares`` throws each at the 3-10, the 10 and the 7 with the straight spare
ball cross-lane through the leave's aim point (``spares.straight_at``: the spare tool's line for
these leaves; the 3-10's aim is the mean of the two pins), under the pro's noise (seed + 1).

**Figures** per setting: carry (strikes / pocket hits: ball on boards 16.5-18.5 at the head pin's
line, entering at 4-6 deg); flush hits (boards 17-18 at 4-6 deg) that leave the 10 or the 4
standing alone; the pro's strike %; 3-10, 10 and 7 conversion; frames counted at the sweep
before they settled (caps).

**Parts.** ``fit``: a grid over the pin's centre of gravity and the pin-deck friction, on the pocket
hits only (the fit sees carry alone: PBA's 74 %); ``spares``: the spare throws at each noise scale of
``--spare-scales`` (the pro's spare noise is fitted to PBA's 3-10, 10 and 7); ``heldout``: every first
ball (the strike rate, which no fit saw), the flush hits' solid 10s and 4s, the spares at the pro's
spare noise, and with ``--timestep`` the pocket hits' pin deck again at that step; ``sweep``: each
parameter moved on its own from ``--setting`` (default: the scene's fitted pins), the sensitivity
table. Results go to ``--cache`` (default ``~/.cache/nbst/carry_fit``) as they come: a rerun skips
what is there (resumable; delete the folder to start again).
"""
from __future__ import annotations

import argparse
import copy
import importlib.util
import json
import os
import pickle
import time
from pathlib import Path

import numpy as np

from nbst.models.bowling import lane, pin, pinfall, scene
from nbst.models.bowling.lane import frame, noise, profiles, spares
from nbst.models.mjsearch.pool import WorkerPool

POCKET = (16.5, 18.5)
FLUSH = (17.0, 18.0)
ENTRY = (4.0, 6.0)
SPARE_LEAVES = {"3-10": (3, 10), "10": (10,), "7": (7,)}
#: The lane half's pins (``scene.LANE_PINS``): ball-pin / pin-pin friction and damping ratio, pin-deck
#: friction, pin mass (kg) and centre of gravity (in above the base; None: the uniform solid's), the pins'
#: scatter about their spots (mm: the sigma of each pin's x and y offset, normal, drawn per throw from its
#: index, the same in every setting; :func:`scatter`; the scene has none), and the kickbacks' contact
#: damping ratio (the side walls beside the deck; the scene's static surfaces are critically damped, 1: a
#: pin does not bounce back).
_P = scene.LANE_PINS
DEFAULTS = dict(bp_mu=_P.mu_ball_pin, pp_mu=_P.mu_pin_pin, bp_zeta=_P.zeta_ball_pin, pp_zeta=_P.zeta_pin_pin,
                deck_mu=_P.mu_deck, pin_mass=_P.mass, pin_com_in=_P.com_in, spot_mm=0.0,
                kick_zeta=scene.SOLREF_STATIC[1])
#: One parameter at a time, to its range (USBC's limits for the pin; assumed ranges for the rest).
SWEEP = [
    {}, {"pin_com_in": pin.COM_LIMITS_IN[0] + 0.1}, {"pin_com_in": None},
    {"pin_mass": pin.MASS_LIMITS[0]}, {"pin_mass": pin.MASS_LIMITS[1]},
    {"deck_mu": 0.1}, {"deck_mu": 0.3}, {"pp_mu": 0.06}, {"pp_mu": 0.2}, {"bp_mu": 0.06}, {"bp_mu": 0.2},
    {"pp_zeta": 0.3}, {"bp_zeta": 0.3},
]


def _contacts():
    path = Path(__file__).resolve().parent / "bench_bowling_contacts.py"
    spec = importlib.util.spec_from_file_location("bench_bowling_contacts", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def key(prm: dict) -> str:
    """The setting's name: the parameters moved from the scene's (None: the uniform pin's centre)."""
    return ",".join(f"{k}={'uniform' if v is None else format(v, 'g')}" for k, v in sorted(prm.items())) or "fitted"


def pin_deck_model(base, prm: dict):
    """A copy of the frame model ``base`` with the pins' parameters of ``prm`` (keys of :data:`DEFAULTS`)."""
    import mujoco

    p = {**DEFAULTS, **{k: v for k, v in prm.items() if k != "h"}}
    m = _contacts().contact_model(base, bp_mu=p["bp_mu"], pp_mu=p["pp_mu"], bp_zeta=p["bp_zeta"], pp_zeta=p["pp_zeta"])
    for name in (lane.PIN_DECK_GEOM, lane.PIN_LANE_GEOM):  # the pins' surfaces (the ball's deck: scene.MU_DECK)
        m.geom_friction[m.geom(name).id, 0] = p["deck_mu"]
    for name in ("wall_left", "wall_right"):  # the kickbacks (the walls run the lane's length)
        m.geom_solref[m.geom(name).id, 1] = p["kick_zeta"]
    com, inertia = pin.mass_properties(p["pin_mass"], p["pin_com_in"])
    for n in scene.PIN_NUMBERS:
        b = m.body(f"pin{n}").id
        m.body_mass[b] = p["pin_mass"]
        m.body_ipos[b] = com
        m.body_inertia[b] = inertia
    d = mujoco.MjData(m)
    mujoco.mj_setConst(m, d)
    return m


_W: dict = {}


def _init(prm: dict) -> None:
    _W["m"] = pin_deck_model(frame.frame_model(timestep=float(prm.get("h", frame.TIMESTEP))),
                             {k: v for k, v in prm.items() if k != "h"})
    _W["spot"] = float({**DEFAULTS, **prm}["spot_mm"]) / 1000  # "h": the pin deck's timestep (s)


def scatter(model, start, spot_m: float, seed: int):
    """A copy of the deck start ``start`` with every pin moved off its spot, as a pinsetter might set
    it: each pin's x and y offsets drawn normal with sigma ``spot_m`` (m) from ``seed`` (pins 1..10
    in turn), the pin still upright at rest on the deck (its height and turn kept)."""
    out = copy.copy(start)
    out.qpos = start.qpos.copy()
    rng = np.random.default_rng(seed)
    for a in pinfall.pin_addresses(model):
        out.qpos[a:a + 2] += rng.normal(0.0, spot_m, 2)
    return out


def _replay(delivery, start, i: int) -> tuple:
    if _W["spot"] > 0:  # the pinsetter's spotting error: each pin off its spot, seeded by the throw
        start = scatter(_W["m"], start, _W["spot"], 10_000 + i)
    r = frame.run_frame(delivery, model=_W["m"], start=start)
    return tuple(r.leave), bool(r.cap_hit)


def capture(cache: Path, n: int, n_spares: int, seed: int, scale: float, spare_scales) -> dict:
    """The throws and their deck starts (cached): ``n`` pro first balls at noise ``scale`` x the shape
    (seed ``seed``), ``n_spares`` at each spare per scale of ``spare_scales`` (seed + 1)."""
    path = cache / f"starts_n{n}_x{scale:g}_s{n_spares}_seed{seed}.pkl"
    out = pickle.loads(path.read_bytes()) if path.exists() else {}
    t0 = time.time()
    m = frame.frame_model()
    if "strike" not in out:
        pro = profiles.profile("pro")
        nz = profiles.scaled(profiles.NOISE_SHAPE, scale)
        out["strike"] = [(dv, frame.deck_start(dv, model=m)) for dv in noise.sample(pro.strike, n, seed, nz)]
    for sc in spare_scales:
        for name, pins in SPARE_LEAVES.items():
            if f"{name}@{sc:g}" in out:
                continue
            line = spares.straight_at(*spares.aim_point(pins))
            nz = profiles.scaled(profiles.NOISE_SHAPE, sc)
            out[f"{name}@{sc:g}"] = [(dv, frame.deck_start(dv, model=m, standing=pins))
                                     for dv in noise.sample(line, n_spares, seed + 1, nz)]
            out[name + "_line"] = line.to_dict()
    print(f"deck starts ready ({time.time() - t0:.0f} s)", flush=True)
    cache.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp")
    tmp.write_bytes(pickle.dumps(out))
    os.replace(tmp, path)
    return out


def _classify(throws: dict) -> dict:
    starts = [st for _, st in throws["strike"]]
    board = np.array([np.nan if s.board is None else s.board for s in starts])
    angle = np.array([np.nan if s.angle is None else s.angle for s in starts])
    ent = (angle >= ENTRY[0]) & (angle <= ENTRY[1])
    return {"pocket": (board >= POCKET[0]) & (board <= POCKET[1]) & ent,
            "flush": (board >= FLUSH[0]) & (board <= FLUSH[1]) & ent}


def evaluate(throws: dict, prm: dict, jobs: int, spare_keys=(), everything: bool = False) -> dict:
    """Figures of setting ``prm``: the pocket hits (all first balls if ``everything``) and the spare
    throws under ``spare_keys`` ('3-10@1', ...)."""
    cls = _classify(throws)
    pick = [i for i in range(len(throws["strike"])) if everything or cls["pocket"][i]]
    calls = [(*throws["strike"][i], i) for i in pick]
    spans = {"strike": (0, len(calls))}
    for name in spare_keys:
        a = len(calls)
        calls += [(dv, st, 100_000 * (1 + len(spans)) + i) for i, (dv, st) in enumerate(throws[name])]
        spans[name] = (a, len(calls))
    with WorkerPool(jobs, _init, (prm,)) as pool:
        res = pool.map(_replay, calls)
    leaves = {i: lv for i, (lv, _) in zip(pick, res[slice(*spans["strike"])])}
    pocket = [i for i in pick if cls["pocket"][i]]
    flush = [i for i in pick if cls["flush"][i]]
    out = {"prm": prm, "pocket": len(pocket), "carried": sum(1 for i in pocket if not leaves[i]),
           "flush": len(flush), "flush_10": sum(1 for i in flush if leaves[i] == (10,)),
           "flush_4": sum(1 for i in flush if leaves[i] == (4,)), "caps": int(sum(c for _, c in res))}
    if everything:
        out["n"], out["strikes"] = len(pick), sum(1 for i in pick if not leaves[i])
        out["all_leaves"] = _top(leaves[i] for i in pick)
    for name in spare_keys:
        rr = res[slice(*spans[name])]
        out[name] = [int(sum(1 for lv, _ in rr if not lv)), len(rr)]
    out["pocket_leaves"] = _top(leaves[i] for i in pocket)
    return out


def _top(leaves, k: int = 6) -> dict:
    c: dict = {}
    for lv in leaves:
        if lv:
            c["-".join(map(str, lv))] = c.get("-".join(map(str, lv)), 0) + 1
    return dict(sorted(c.items(), key=lambda kv: -kv[1])[:k])


def row(r: dict, spare_keys=()) -> str:
    lo, hi = noise.wilson(r["carried"], r["pocket"])
    c = f"{r['carried']}/{r['pocket']} = **{100 * r['carried'] / r['pocket']:.0f} %** ({100 * lo:.0f}-{100 * hi:.0f} %)"
    sp = " | ".join(f"{r[k][0]}/{r[k][1]}" if k in r else "" for k in spare_keys)
    st = f"{r['strikes']}/{r['n']}" if "n" in r else ""
    top = ", ".join(f"{k} {v}" for k, v in r["pocket_leaves"].items())
    return (f"| {key(r['prm'])} | {c} | {r['flush_10']} + {r['flush_4']} of {r['flush']} | {st} | {sp}"
            f"{' | ' if spare_keys else ''}{r['caps']} | {top} |")


def header(spare_keys=()) -> str:
    cols = ["setting", "carry of pocket hits (95 % CI)", "flush hits: solid 10 + solid 4", "pro strikes",
            *spare_keys, "caps", "leaves of pocket hits"]
    return "| " + " | ".join(cols) + " |\n|" + "---|" * len(cols)


def run_settings(settings: list, throws: dict, cache: Path, tag: str, jobs: int, spare_keys=(),
                 everything: bool = False) -> list:
    """Evaluate each setting (resumable: results kept in ``cache``), print its row."""
    path = cache / f"results_{tag}.json"
    done = json.loads(path.read_text()) if path.exists() else {}
    out = []
    print(header(spare_keys), flush=True)
    for prm in settings:
        k = f"{key(prm)}|{','.join(spare_keys)}|{int(everything)}"
        if k not in done:
            t0 = time.time()
            done[k] = evaluate(throws, prm, jobs, spare_keys, everything)
            done[k]["s"] = round(time.time() - t0)
            tmp = path.with_suffix(".tmp")
            tmp.write_text(json.dumps(done, indent=1))
            os.replace(tmp, path)
        print(row(done[k], spare_keys) + f"  <!-- {done[k]['s']} s -->", flush=True)
        out.append(done[k])
    return out


def parse_setting(text: str) -> dict:
    out = {}
    for kv in filter(None, text.split(",")):
        k, v = kv.split("=")
        if k not in DEFAULTS and k != "h":
            raise SystemExit(f"--setting: no parameter {k!r}; parameters: {', '.join(DEFAULTS)}")
        out[k] = float(v)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0], allow_abbrev=False)
    ap.add_argument("--part", choices=("fit", "spares", "sweep", "heldout", "all"), default="all")
    ap.add_argument("--n", type=int, default=260, help="pro first balls (default 260: ~210 pocket hits)")
    ap.add_argument("--spares", type=int, default=100, help="throws at each spare (default 100)")
    ap.add_argument("--scale", type=float, default=profiles.PRO_SCALE,
                    help="the pro's strike-ball noise, x the assumed shape (default: the profile's)")
    ap.add_argument("--spare-scales", default="0.5,1,1.1,1.25,1.5", help="spare noise scales to measure (part spares)")
    ap.add_argument("--spare-scale", type=float, default=profiles.PRO_SPARE_SCALE,
                    help="the spare noise scale of parts sweep, heldout (default: the pro's)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--cache", type=Path, default=Path.home() / ".cache" / "nbst" / "carry_fit")
    ap.add_argument("--grid", default="5.796,5.87,5.9375;0.2,0.25,0.3",
                    help="fit grid 'com1,com2,..;mu1,mu2,..' (pin centre of gravity, in; pin-deck friction)")
    ap.add_argument("--setting", default="", help="parameters moved from the scene's, 'key=value,...'")
    ap.add_argument("--timestep", type=float, default=None,
                    help="part heldout: also replay the pocket hits' pin deck at this step (s; the lane phase stays 1 ms)")
    args = ap.parse_args()
    tag = f"n{args.n}_x{args.scale:g}_s{args.spares}_seed{args.seed}"
    scales = sorted({float(x) for x in args.spare_scales.split(",")} | {args.spare_scale})
    throws = capture(args.cache, args.n, args.spares, args.seed, args.scale, scales)
    base = parse_setting(args.setting)
    cls = _classify(throws)
    print(f"pro first balls: {args.n} at noise x{args.scale:g}: {int(cls['pocket'].sum())} pocket hits "
          f"({100 * cls['pocket'].mean():.1f} %), {int(cls['flush'].sum())} flush")
    for name in SPARE_LEAVES:
        ln = throws[name + "_line"]
        print(f"{name}: board {ln['board']:.2f} at the foul line, {ln['angle']:.3f} deg, {ln['mph']:g} mph, "
              f"{ln['rpm']:g} rpm")
    sk = tuple(f"{name}@{args.spare_scale:g}" for name in SPARE_LEAVES)
    if args.part in ("fit", "all"):
        a, b = args.grid.split(";")
        grid = [{**base, "pin_com_in": float(c), "deck_mu": float(mu)} for c in a.split(",") for mu in b.split(",")]
        print("\n## fit: pin centre of gravity x pin-deck friction, pocket hits only\n")
        run_settings(grid, throws, args.cache, tag, args.jobs)
    if args.part in ("spares", "all"):
        print("\n## spares: the spare noise scale\n")
        run_settings([base], throws, args.cache, tag, args.jobs,
                     tuple(f"{name}@{sc:g}" for sc in scales for name in SPARE_LEAVES))
    if args.part in ("heldout", "all"):
        print(f"\n## held out: every first ball, flush hits, spares at noise x{args.spare_scale:g}\n")
        run_settings([base], throws, args.cache, tag, args.jobs, sk, everything=True)
        if args.timestep:
            print(f"\n## the pocket hits' pin deck at h = {args.timestep * 1000:g} ms\n")
            run_settings([{**base, "h": args.timestep}], throws, args.cache, tag, args.jobs)
    if args.part in ("sweep", "all"):
        print(f"\n## sensitivity: one parameter at a time from the setting, spares at noise x{args.spare_scale:g}\n")
        run_settings([{**base, **s} for s in SWEEP], throws, args.cache, tag, args.jobs, sk)


if __name__ == "__main__":
    main()
