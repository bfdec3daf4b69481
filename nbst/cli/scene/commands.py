"""The ``nbst scene`` subcommands themselves (registered by :mod:`nbst.cli.scene`): each takes the
parsed arguments and returns the exit code (0 done, 1 a check failed, 2 bad input, 130
interrupted; docs/scene.md).

Light at import: nbst.scene's modules (and mujoco) are imported inside the commands.
"""
from __future__ import annotations

import math
import sys
from pathlib import Path

from nbst.cli.args import print_json
from nbst.outputs import prepare_output, sigterm_as_interrupt, write_json_atomic
from nbst.parallel import default_jobs
from nbst.progress import command_start, count_text, progress_bar, seconds_text
from nbst.seeds import resolve_seed

__all__ = ["cmd_examples", "cmd_check", "cmd_solve", "cmd_replay", "cmd_validate", "cmd_export", "asks_text"]


def asks_text(fate) -> str:
    """What one body's fates ask, in words."""
    out = []

    def region(r) -> str:
        if r.center is not None:
            return f"within {r.radius:g} m of ({', '.join(f'{a:g}' for a in r.center)})"
        return (f"in the box ({', '.join(f'{a:g}' for a in r.lo)})-({', '.join(f'{a:g}' for a in r.hi)})")

    if fate.rest_in is not None:
        out.append("rests " + region(fate.rest_in))
    for t, r in fate.at:
        out.append(f"at {t:g} s {region(r)}")
    if fate.through:
        out.append(f"passes {len(fate.through)} region(s) in order")
    if fate.up is not None:
        axis, d = fate.up
        out.append(f"ends with its axis ({', '.join(f'{a:.3g}' for a in axis)}) within {d:g} deg of up")
    if fate.hits:
        out.append("hits " + ", then ".join(fate.hits))
    if fate.never_hits:
        out.append("never hits " + ", ".join(fate.never_hits))
    if fate.at_rest:
        out.append("ends at rest")
    if fate.still:
        out.append("never moves")
    return "; ".join(out)


def cmd_examples(args) -> int:
    from nbst.scene.builtin import example_description, example_names, example_path

    rows = [{"name": n, "description": example_description(n), "fates": str(example_path(n))}
            for n in example_names()]
    if args.json:
        print_json(rows)
        return 0
    for r in rows:
        print(f"{r['name']:14s} {r['description']}")
    print(f"\nthe fates files and their scenes (copy the folder to change one): {Path(rows[0]['fates']).parent}")
    return 0


def cmd_check(args) -> int:
    from nbst.scene.fates import STILL_DISTANCE
    from nbst.scene.contacts import (MIN_CONTACT_STEPS, contact_time, deep_rests, endless_rolls, ignored_friction,
                                     short_contacts)
    from nbst.scene.scenefile import idle_fates, load_fates, start_touches, unforced_still_moves

    f, model = load_fates(args.fates, scene=args.scene)
    steps = int(round(f.duration / model.opt.timestep))
    print(f"{args.fates}: scene {f.scene}" + (f", key {f.keyframe}" if f.keyframe else "")
          + f"; {f.duration:g} s at {model.opt.timestep * 1e3:g} ms ({steps:,} steps)")
    for c in f.controls:
        ranges = "; ".join(f"{part} " + ", ".join(f"[{a:g}, {b:g}]" for a, b in zip(r.lo, r.hi))
                           for part, r in c.parts())
        print(f"  controls {c.body}: {ranges}")
    for fa in f.fates:
        print(f"  fates {fa.body}: {asks_text(fa)}")
    hits = {fa.body: fa.hits for fa in f.fates}
    for body, key, name in start_touches(f, model):
        first = list(hits.get(body, ()))
        print(f"  note: {body} already touches {name} at the start" + (
            f" (the model's pose, before any control): its never_hits {name} can not be met; start it apart"
            if key == "never_hits" else f": its first touch of {name} is at 0 s" + (
                f", so its hits order ({', then '.join(first)}) can not be met; start it apart, or put {name} first"
                if name in first and first[0] != name else "")))
    for body, why in idle_fates(f, model):
        print(f"  note: {body} {why}")
    if model.nflex:
        print(f"  note: the scene has {model.nflex} flex{'es' if model.nflex > 1 else ''} (cloth, soft bodies): the "
              f"search and replay step {'them' if model.nflex > 1 else 'it'} as MuJoCo does, but render, the validate "
              f"report's plots and glTF draw geoms only, and fates name bodies and geoms, not a flex")
    for body, far in unforced_still_moves(f, model):
        print(f"  note: {body} moves {far:.3g} m by itself (the scene as written, no control, over the duration): "
              f"its still (at most {STILL_DISTANCE:g} m) is met only if a control holds it; start it at rest")
    for body, other, depth, half in deep_rests(f, model):
        print(f"  note: {body} would rest {depth * 1e3:.3g} mm deep in {other} ({100 * depth / half:.0f} % of its "
              f"smallest half-size, {half * 1e3:.3g} mm: MuJoCo's soft contact at rest under gravity); a shorter "
              f"time constant in solref, or solimp nearer 1, sinks it less")
    for body, other, kind, value, condim in ignored_friction(f, model):
        print(f"  note: {body}'s contact with {other} has {kind} friction {value:g} but condim {condim}: MuJoCo ignores "
              f"it (condim {6 if kind == 'rolling' else 4} applies it), so "
              + ("a rolling body is not slowed by it and may never come to rest" if kind == "rolling"
                 else "a spinning body is not slowed by it"))
    for body, other, condim in endless_rolls(f, model):
        print(f"  note: {body} must end at rest and can roll, but its contact with {other} applies no rolling "
              f"friction (condim {condim}{'' if condim < 6 else ', rolling friction 0'}): MuJoCo then slows a "
              f"rolling body not at all, so it may roll for ever; condim 6 with rolling friction (the third "
              f"friction) stops it")
    h = model.opt.timestep
    groups: dict[tuple[str, float, float, float], list[str]] = {}
    for body, other, t, tau, zeta in short_contacts(f, model):
        groups.setdefault((body, t, tau, zeta), []).append(other)
    for (body, t, tau, zeta), others in groups.items():
        named = ", ".join(others[:3]) + (f" and {len(others) - 3} more" if len(others) > 3 else "")
        held = f"; MuJoCo holds its time constant at 2 steps, {2 * h * 1e3:g} ms" if tau < 2 * h else ""
        print(f"  note: {body}'s contacts with {named} last {t * 1e3:.3g} ms (solref {tau:g} {zeta:g}{held}), "
              f"{t / h:.3g} steps of {h * 1e3:g} ms: a bounce resolved in under {MIN_CONTACT_STEPS:g} steps changes "
              f"with the step and with where in a step it begins, so h/2 and h/4 (the ladder) often disagree with h; "
              f"a step of at most {contact_time(tau, zeta, 0.0, refsafe=False) / MIN_CONTACT_STEPS * 1e3:.3g} ms gives it "
              f"{MIN_CONTACT_STEPS:g} (or a longer time constant, "
              f"or more damping)")
    return 0


def _by(fv) -> str:
    """How far a missed fate is, in its own unit (a region's metres, an axis's degrees), or "" for the
    counted ones (touches): a solve's summary says each, not only the cost that adds them up."""
    import math

    if fv.fate in ("rest_in", "at", "through", "still"):
        return f" by {fv.cost:.3g} m"
    if fv.fate == "up":
        return f" by {math.degrees(fv.cost):.3g} deg"
    return ""


def cmd_solve(args) -> int:
    from nbst.scene.api import solve
    from nbst.scene.contacts import MIN_CONTACT_STEPS, short_contacts
    from nbst.scene.scenefile import check_scene_files, load_fates
    from nbst.scene.search import SceneProgress
    from nbst.scene.solution import solution_dict

    fates, model = load_fates(args.fates, scene=args.scene)  # bad input: exit 2 before anything is written
    prepare_output(args.output, inputs=[args.fates, *check_scene_files(fates.scene)])  # never the scene's files
    seed = resolve_seed(args.seed, what="--seed")
    short = short_contacts(fates, model) if not (args.quiet or args.no_ladder) else []
    if short:  # the ladder will be hard: said before the search, where a user can stop it
        body, other, t, _tau, _zeta = short[0]
        h = model.opt.timestep
        print(f"note: {count_text(len(short))} pair(s) of geoms touch for fewer than {MIN_CONTACT_STEPS:g} steps (the shortest, "
              f"{body} with {other}, {t / h:.3g} steps of {h * 1e3:g} ms): h/2 and h/4 will often disagree with h; "
              f"nbst scene check {args.fates} says more", file=sys.stderr)
    bar: list = []
    name = fates.source

    def progress(p: SceneProgress) -> None:
        if args.quiet:
            return
        if not bar:
            bar.append(progress_bar(total=args.max_rollouts, unit="rollout", file=sys.stderr, bound=True,
                                    start=command_start(), desc=f"scene {name}"))
        bar[0].update(p.rollouts - bar[0].n)
        if p.phase != "search":  # the search is over; the bar says what the wait is for
            bar[0].set_postfix_str(f"search done; {p.phase}", refresh=True)
            return
        cost = f"{p.best_cost:.3g}" if math.isfinite(p.best_cost) else "inf"
        seen = f"{p.signatures} signature{'' if p.signatures == 1 else 's'}"
        bar[0].set_postfix_str(f"best cost {cost}, signature {p.best_signature}, {seen}",
                               refresh=False)

    with sigterm_as_interrupt():
        res = solve(args.scene, fates, seed=seed, max_rollouts=args.max_rollouts, jobs=args.jobs or default_jobs(),
                    samples=args.samples or 0, answers=args.answers, ladder=not args.no_ladder, robust=args.robust,
                    cluster=args.cluster, callback=progress)
    if bar:
        bar[0].close(n=res.rollouts)
    write_json_atomic(args.output, solution_dict(res))
    if not args.quiet:
        b = res.best
        # res.met holds the ladder too where it was asked (exit 0 only then)
        unmet = ", ".join(f"{bv.body}'s {fv.fate}{_by(fv)}" for bv in b.judgement.bodies for fv in bv.fates
                          if not fv.met)
        met = ("met" if res.met else "met at the scene's step only" if b.judgement.met and not b.warnings
               else f"not met (cost {b.cost:.3g}; the best misses {unmet})" if unmet else f"not met (cost {b.cost:.3g})")
        took = seconds_text(bar[0].seconds if bar else res.wall_time)
        warn = f"; MuJoCo warned: {', '.join(b.warnings)}" if b.warnings else ""
        if res.probability is not None:
            warn += f"; P {res.probability.text()} under the fates' noise"
        if not args.no_ladder and b.judgement.met:  # (a motion that misses at h is not rolled out finer)
            warn += "; kept at h/2 and h/4" if res.ladder_held else "; not kept at h/2 and h/4"
        if res.robust is not None:
            warn += (f"; robust: {res.robust['start_screen'][0]} -> {res.robust['screen'][0]} of "
                     f"{res.robust['screen'][1]} noisy copies in {count_text(res.robust['rollouts'])} rollouts")
        if args.answers > 1:
            warn += f"; {len(res.answers)} of {args.answers} answers with contact sequences of their own"
        stop = ("interrupted; best so far written: " if res.stopped == "interrupted" else
                f"interrupted during the {res.interrupted} after the search (no probability): " if res.interrupted
                else "")
        print(f"scene {name}: {stop}{met}, signature {res.judgement.to_dict()['signature']} after "
              f"{count_text(res.rollouts)} rollouts in {took}, seed {seed}{warn}; wrote {args.output}",
              file=sys.stderr)
    if res.stopped == "interrupted" or res.interrupted:
        return 130
    return 0 if res.met else 1


def cmd_replay(args) -> int:
    from nbst.scene.solution import ladder_solution, read_solution, replay_solution

    doc = read_solution(args.solution)
    r = replay_solution(args.solution)
    d = r.judgement.to_dict()
    lad = ladder_solution(args.solution) if args.ladder else None
    ok = r.same and (lad is None or lad.holds)
    if args.json:
        out = {"identical": r.same, "scene_changed": r.scene_changed, "fates_changed": r.fates_changed,
               "met": d["met"], "signature": d["signature"],
               "bodies": d["bodies"]}
        if lad is not None:
            out["ladder"] = {"holds": lad.holds, "rungs": [{"timestep": h, "met": o, "signature":
                                                            res.judgement.to_dict()["signature"]}
                                                           for h, o, res in zip(lad.timesteps, lad.outcomes,
                                                                                lad.results)]}
        print_json(out)
        return 0 if ok else 1
    changed = "; the scene file changed since it was solved" if r.scene_changed else ""
    if r.fates_changed:
        changed += "; the fates file changed since it was solved (judged here by the file as it is now)"
    if lad is None and d["met"] and isinstance(doc.get("ladder"), dict) and doc["ladder"].get("holds") is False:
        changed += "; the file says it does not hold at h/2 and h/4 (--ladder rolls them out)"
    print(f"{args.solution}: {'reproduced bit for bit' if r.same else 'DIFFERS'} (plain mj_step loop); "
          f"{'met' if d['met'] else 'not met'} at h = {float(doc['timestep']) * 1e3:g} ms, signature "
          f"{d['signature']}{changed}")
    for b in r.judgement.bodies:
        for v in b.fates:
            print(f"  {b.body} {v.fate}: {'met' if v.met else 'NOT met'} ({v.happened})")
    if lad is not None:
        rungs = ", ".join(f"{h * 1e3:g} ms {'met' if o else 'NOT met'} ({res.judgement.to_dict()['signature']})"
                          for h, o, res in zip(lad.timesteps, lad.outcomes, lad.results))
        print(f"  ladder: {rungs}; {'holds' if lad.holds else 'does not hold'}")
    return 0 if ok else 1


def cmd_validate(args) -> int:
    from pathlib import Path

    from nbst.outputs import write_bytes_atomic
    from nbst.render.scene_report import REPORT_FILES, scene_report_files
    from nbst.scene.solution import read_solution
    from nbst.scene.validate import validate_solution

    read_solution(args.solution)  # bad input: exit 2 before anything is written
    if args.out_dir:
        prepare_output(args.out_dir, directory=True, option="--out-dir", files=REPORT_FILES)
    val = validate_solution(args.solution, samples=args.samples, seed=args.seed, jobs=args.jobs or default_jobs())
    if args.out_dir:
        for name, data in scene_report_files(val).items():
            write_bytes_atomic(Path(args.out_dir) / name, data, option="--out-dir")
    if args.json:
        print_json(val.to_dict())
    elif not args.quiet:
        p = val.probability
        print(f"{args.solution}: {'every setting meets every fate' if val.all_met else 'NOT met under some settings'}"
              f" (MuJoCo {val.mujoco}, {val.fates.duration:g} s)")
        for r in val.rows:
            worst = "" if r.met else "; " + ", ".join(
                f"{b.body} {v.fate} ({v.happened})" for b in r.rollout.judgement.bodies for v in b.fates if not v.met)
            warn = f"; MuJoCo warned: {', '.join(r.rollout.warnings)}" if r.rollout.warnings else ""
            print(f"  {r.group:10s} {r.setting:13s} {r.timestep * 1e3:7g} ms  {'met' if r.met else 'NOT met':7s} "
                  f"cost {r.rollout.cost:.3g}{worst}{warn}"
                  + (" (the scene's)" if r.same_as_scene and r.group != "scene" else ""))
        print(f"  {'noise':10s} {p.n} samples  P(every fate) {p.p:.3g} [{p.lo:.3g}, {p.hi:.3g}] (95 % Wilson, seed "
              f"{val.noise_seed})")
        if args.out_dir:
            print(f"report     {args.out_dir}/index.html, {args.out_dir}/report.json")
    if args.strict and not val.all_met:
        failed = ", ".join(f"{r.group} {r.setting}" for r in val.rows if not r.met)
        print(f"nbst scene validate: --strict: the fates are not met under {failed}", file=sys.stderr)
        return 1
    return 0


def cmd_export(args) -> int:
    from nbst.scene.solution import export_scene, read_solution, solution_reads

    doc = read_solution(args.solution)
    prepare_output(args.output, inputs=solution_reads(args.solution, doc))  # never the files it replays from
    key = export_scene(args.solution, args.output)
    print(f"wrote {args.output}: {doc['scene']} with keyframe {key!r} (the solution's initial state); play it with "
          f"python -m mujoco.viewer --mjcf={args.output}, then load key {key!r}")
    return 0


def cmd_pick(args) -> int:
    from nbst.scene.solution import pick_answer, read_solution, solution_reads

    doc = read_solution(args.solution)
    prepare_output(args.output, inputs=solution_reads(args.solution, doc))
    out = pick_answer(args.solution, args.answer)
    write_json_atomic(args.output, out)
    seq = ", ".join("-".join(map(str, s)) if isinstance(s, list) else str(s) for s in out["picked"]["sequence"])
    p = out.get("probability")
    print(f"wrote {args.output}: answer {args.answer} of {args.solution} ({seq or 'no touches'}); "
          f"{'met' if out['met'] else 'NOT met'}" + (f", P(every fate) {p['p']:.3g}" if p else "")
          + f"; replay, validate, export and render take it as any solution")
    return 0 if out["met"] else 1
