"""The ``nbst crash`` subcommands themselves (registered by :mod:`nbst.cli.crash`): each takes the
parsed arguments and returns the exit code (0 done, 1 a check failed, 2 bad input, 130
interrupted; docs/crash.md).

Light at import: the crash room, mujoco and cma are imported inside the commands.
"""
from __future__ import annotations

import json
import math
import sys
from typing import Any

import numpy as np

from nbst.cli.args import print_json
from nbst.errors import InputError
from nbst.outputs import prepare_output, sigterm_as_interrupt, write_text_atomic
from nbst.parallel import default_jobs
from nbst.progress import command_start, count_text, progress_bar, seconds_text
from nbst.seeds import resolve_seed

__all__ = ["fate_phrases", "cmd_scripts", "cmd_check", "cmd_solve", "cmd_probability", "cmd_replay",
           "write_crash"]


def _runner(args, script, xml=None):
    from nbst.models.crash import run

    if getattr(args, "cluster", None):
        return run.CrashClusterRunner(script, args.cluster, xml=xml)
    return run.CrashRunner(script, jobs=args.jobs or default_jobs(), xml=xml)


def _load(name):
    from nbst.models.crash.script import load_script

    return load_script(name)


def cmd_scripts(args) -> int:
    from nbst.models.crash.script import builtin_names, load_script

    rows: list[dict[str, Any]] = []
    for name in builtin_names():
        s = load_script(name)
        rows.append({"name": name, "vehicles": [f"{v.name} ({v.vtype.name})" for v in s.vehicles],
                     "road": s.road.layout, "duration_s": s.duration, "description": s.description})
    if args.json:
        print_json(rows)
        return 0
    for r in rows:
        print(f"{r['name']:14s} {r['road']:12s} {', '.join(r['vehicles'])}")
        if r["description"]:
            print(f"{'':14s} {r['description'].splitlines()[0]}")
    return 0


def fate_phrases(script, i: int) -> dict:
    """{fate key (outcome.judge's): what vehicle ``i``'s script asks, in words}, every fate asked."""
    f, names = script.vehicles[i].fate, script.names()
    asks: dict = {}
    if f.hits is not None:
        asks["hits"] = "hits " + (", then ".join(names[j] for j in f.hits) or "nobody")
    if f.impact_speed is not None:
        asks["impact_speed"] = f"impact speed {f.impact_speed.lo * 3.6:g}-{f.impact_speed.hi * 3.6:g} km/h"
    if f.delta_v is not None:
        asks["delta_v"] = f"delta-V {f.delta_v.lo * 3.6:g}-{f.delta_v.hi * 3.6:g} km/h in its first impact"
    if f.impact_at is not None:
        asks["impact_at"] = f"at the impact within {f.impact_at[2]:g} m of ({f.impact_at[0]:g}, {f.impact_at[1]:g})"
    if f.rest is not None:
        asks["rest"] = f"comes to rest within {f.rest[2]:g} m of ({f.rest[0]:g}, {f.rest[1]:g})"
    if f.heading is not None:
        asks["heading"] = f"at rest facing {math.degrees(f.heading[0]):g} +- {math.degrees(f.heading[1]):g} deg"
    if f.quarter_turns is not None:
        lo, hi = f.quarter_turns
        asks["quarter_turns"] = f"{lo}{'' if lo == hi else f'-{hi}'} quarter turn{'' if hi == 1 else 's'} of roll"
    if f.attitude is not None:
        asks["attitude"] = f"ends {f.attitude}"
    if f.spin is not None:
        asks["spin"] = f"spins {math.degrees(f.spin[0]):g} +- {math.degrees(f.spin[1]):g} deg"
    for key in ("curb", "barrier"):
        want = getattr(f, key)
        if want is not None:
            asks[key] = f"{'strikes' if want else 'does not strike'} a {key}"
    return asks


def cmd_check(args) -> int:
    s = _load(args.script)
    print(f"{s.name}: {s.road.layout} road, {s.road.width:g} m wide, friction {s.road.friction:g}"
          + (f", curbs {s.road.curb:g} m" if s.road.curb else "") + f"; {s.duration:g} s at {s.timestep * 1e3:g} ms")
    names = s.names()
    for i, v in enumerate(s.vehicles):
        asks = list(fate_phrases(s, i).values())
        speed = f"{v.speed.lo * 3.6:g}" + ("" if v.speed.hi == v.speed.lo else f"-{v.speed.hi * 3.6:g}")
        print(f"  {v.name}: {v.vtype.label} at ({v.x:g}, {v.y:g}) facing {math.degrees(v.heading):g} deg, "
              f"{speed} km/h; " + ("; ".join(asks) or "no fate asked"))
    if s.order is not None:
        print("  order: " + ", then ".join(f"{names[a]}-{names[b]}" for a, b in s.order))
    return 0


def _seed(args) -> int:
    """The seed given, or one drawn (nbst.seeds: one range for every drawn seed), recorded in the file."""
    return resolve_seed(args.seed, what="--seed")


def write_crash(path, d: dict) -> None:
    write_text_atomic(path, json.dumps(d, indent=1, allow_nan=False) + "\n")


def cmd_solve(args) -> int:
    from nbst.models.crash import crashfile, search

    script = _load(args.script)
    if args.robust is not None and args.samples == 0:
        raise InputError("--samples 0 with --robust: the robust pick's probability is measured afresh, from at least "
                         "1 noisy re-drive")
    prepare_output(args.output)
    seed = _seed(args)
    runner = _runner(args, script)
    bar: list = []

    def progress(p) -> None:
        if args.quiet:
            return
        if not bar:
            bar.append(progress_bar(total=args.max_rollouts, unit="rollout", file=sys.stderr, bound=True,
                                    start=command_start(), desc=f"crash {script.name}"))
        bar[0].update(p.rollouts - bar[0].n)
        bar[0].set_postfix_str(f"best cost {p.best_cost:.3g}, signature {p.best_signature}, "
                               f"{p.sequences} contact sequences", refresh=False)

    progress(search.CrashProgress(0, float("inf"), "0" * script.n, False, 0))
    with sigterm_as_interrupt():
        res = search.solve(script, seed=seed, max_rollouts=args.max_rollouts, runner=runner, callback=progress,
                           ladder=not args.no_ladder)
    if bar:
        bar[0].close(n=res.rollouts)
    b = res.best
    S = search.space_of(script)
    intents = S.intents(b.u[None])[0]
    extra: dict = {}
    stopped = res.stopped
    if stopped != "interrupted":
        try:
            with sigterm_as_interrupt():
                b, intents, extra = _after_search(args, script, runner, S, b, intents, seed)
        except KeyboardInterrupt:
            stopped = "interrupted"
    assert b.controls is not None  # every trial a search returns was rolled out
    d = crashfile.crash_dict(script, runner.xml, runner.model, intents, b.qpos0, b.qvel0, b.controls,
                             b.final_qpos, b.outcome, seed=seed, period_steps=runner.period,
                             search={"rollouts": res.rollouts, "restarts": res.restarts, "stopped": stopped,
                                     "wall_time_s": round(res.wall_time, 2), "max_rollouts": args.max_rollouts,
                                     "contact_sequences": len(res.archive)})
    d.update(extra)
    write_crash(args.output, d)
    runner.close()
    # met: the script met at its step and, where the ladder was asked, at 1 and 0.5 ms too (exit 0)
    held = bool(d["ladder"]["holds"]) if "ladder" in d else True
    solved = b.outcome.solved and held
    if not args.quiet:
        met = ("met" if solved else "met at the script's step only" if b.outcome.solved
               else f"not met (cost {b.cost:.3g})")
        more = ""
        if "ladder" in d:
            more += "; ladder " + ("holds at 2, 1 and 0.5 ms" if d["ladder"]["holds"] else "does not hold")
        if d.get("probability"):
            more += "; " + _p_text(d["probability"])
        moving = [v.name for v in b.outcome.vehicles if v.moving]
        if moving:
            more += (f"; {', '.join(moving)} still moving at the end ({script.duration:g} s): the pose then, not a "
                     "rest position (a longer duration lets it stop)")
        took = seconds_text(bar[0].seconds if bar else res.wall_time)  # the bar's count and clock
        print(f"crash {script.name}: {met}, signature {b.outcome.signature_text(script.n)} after "
              f"{count_text(res.rollouts)} rollouts in {took}, seed {seed}{more}; wrote {args.output}", file=sys.stderr)
    if stopped == "interrupted":
        return 130
    return 0 if solved else 1


def _p_text(p: dict) -> str:
    """A crash file's probability in one phrase: P, k/n, the interval, the noise."""
    text = (f"P(fates) {100 * p['p']:.0f} % ({p['k']}/{p['n']} noisy re-drives, 95 % CI {100 * p['lo']:.0f}-"
            f"{100 * p['hi']:.0f} %, {p.get('noise_kind', 'retake')} noise)")
    return text + _lottery_text(p)


def _lottery_text(p: dict) -> str:
    """': a LOTTERY ...' for a probability under robust.LOTTERY_P (fewer than 1 take in 10), else ''."""
    return ": a LOTTERY, not a script (its drivers repeat it in under 1 take in 10; docs/crash.md)" if p.get(
        "lottery") else ""


def _after_search(args, script, runner, S, best, intents, seed):
    """The robust maximiser (--robust), the ladder and the probability (--samples; by default
    :data:`.robust.SOLVE_SAMPLES` re-drives, 0: none) of the crash found: (the trial to write,
    its intents, the file's extra fields; ``probability`` None when not measured)."""
    from nbst.models.crash import robust
    from nbst.models.crash.search import Trial

    extra: dict = {"probability": None}
    noise = robust.check_noise(args.noise)
    if args.robust is not None and best.outcome.solved:
        n = args.samples if args.samples is not None else robust.DEFAULT_SAMPLES
        mx = robust.robust_pick(S, runner, intents, budget=args.robust, seed=seed, n=n, noise=noise,
                                ladder=not args.no_ladder)
        intents = mx.best
        r = runner.run(intents[None])
        best = Trial(u=S.unit_of(intents), outcome=r.outcomes[0], controls=r.controls[0], qpos0=r.qpos0[0],
                     qvel0=r.qvel0[0], final_qpos=r.final_qpos[0])
        extra["robust"] = {"budget": args.robust, "rollouts": mx.frames, "screen": [mx.screen.k, mx.screen.n],
                           "start_screen": [mx.start_screen.k, mx.start_screen.n], "screen_seed": mx.screen_seed,
                           "climb": mx.climb, "race": mx.race}
        extra["probability"] = mx.fresh.to_dict()
        if mx.ladder:
            extra["ladder"] = {"rows": mx.ladder, "holds": bool(mx.ladder_holds)}
        return best, intents, extra
    if not args.no_ladder:
        lad = robust.ladder(script, runner.xml, intents)
        extra["ladder"] = {"rows": robust.ladder_rows(lad), "holds": bool(lad.holds)}
    n = robust.SOLVE_SAMPLES if args.samples is None else args.samples
    if n:
        extra["probability"] = robust.probability(runner, np.asarray(intents), n, seed, noise=noise).to_dict()
    return best, intents, extra


def cmd_probability(args) -> int:
    from nbst.models.crash import crashfile, robust

    d, script, model = crashfile.load(args.crash)
    if args.output:
        prepare_output(args.output, inputs=(args.crash,))
    intents = crashfile.intents_array(d, script)
    runner = _runner(args, script, xml=d["scene_xml"])
    bar = None if args.quiet else progress_bar(total=args.samples, unit="rollout", file=sys.stderr,
                                               desc=f"probability {script.name}")
    est = robust.probability(runner, intents, args.samples, args.seed, noise=args.noise,
                             on_batch=None if bar is None else (lambda k: bar.update(k - bar.n)))
    if bar is not None:
        bar.close()
    runner.close()
    if args.output:
        d["probability"] = est.to_dict()
        write_crash(args.output, d)
    if args.json:
        print_json(est.to_dict())
    else:
        print(f"{args.crash}: P(script met) = {est.text()} under {args.noise} noise (docs/crash.md), seed {args.seed}"
              f"{_lottery_text(est.to_dict())}")
        for lab, k in est.outcomes.items():
            print(f"  {lab:12s} {k}")
    return 0


def cmd_replay(args) -> int:
    from nbst.models.crash import crashfile

    d, script, model = crashfile.load(args.crash)
    q, o = crashfile.replay(d, script, model)
    same_state = bool(np.array_equal(q, np.array(d["final_qpos"])))
    again = crashfile.outcome_dict(o, script, crashfile.scene_mod.layout(model, script.n).mass)
    same_outcome = again == d["outcome"]
    ok = same_state and same_outcome
    if args.json:
        print_json({"identical": ok, "final_state_identical": same_state, "outcome_identical": same_outcome,
                    "outcome": again})
    else:
        print(f"{args.crash}: {'reproduced bit for bit' if ok else 'DIFFERS'} "
              f"(final state {'identical' if same_state else 'differs'}, outcome "
              f"{'identical' if same_outcome else 'differs'}); {'met' if o.solved else 'not met'}, signature "
              f"{again['signature']}")
        for c in again["contacts"]:
            dv = ", ".join(f"{k} {v:.1f} km/h" for k, v in c["delta_v_kmh"].items())
            print(f"  t = {c['t']:.3f} s  {c['a']}-{c['b']}  delta-V {dv}")
        for v in again["vehicles"]:
            r = v["rest"]
            where = (f"still moving at the end ({d['duration']:g} s), at" if v["moving_at_end"] else "rests at")
            print(f"  {v['name']}: {where} ({r['x']:.2f}, {r['y']:.2f}) facing {r['heading_deg']:.1f} deg, "
                  f"{v['attitude']}, {v['quarter_turns']} quarter turns")
    return 0 if ok else 1
