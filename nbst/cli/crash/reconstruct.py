"""``nbst crash reconstruct CASE -o REC.json``: the evidence back to each vehicle's impact speed,
delta-V and PDOF as 90 % intervals (approximate Bayesian computation: docs/crash.md).

Registered by :mod:`nbst.cli.crash` (:func:`add_parser`); light at import: the crash room and
mujoco are imported inside :func:`cmd_reconstruct`.

Exit codes: 0 draws that meet the evidence were found (the intervals are theirs); 1 none within
the budget (the intervals are those of the nearest draws, said so, and the nearest crash is
written); 2 bad input; 130 interrupted (what ran is written).
"""
from __future__ import annotations

import json
import sys

from nbst.cli.args import JOBS, SEED, Bounded, print_json, with_limits
from nbst.cli.flags import add_quiet, add_seed
from nbst.outputs import prepare_output, sigterm_as_interrupt, write_text_atomic
from nbst.parallel import default_jobs
from nbst.progress import progress_bar
from nbst.seeds import resolve_seed

__all__ = ["ROLLOUTS", "PARTICLES", "add_parser", "cmd_reconstruct", "summary_lines"]

ROLLOUTS = Bounded("max-rollouts", 16, 10_000_000, integer=True)
PARTICLES = Bounded("particles", 16, 100_000, integer=True)


def add_parser(cr) -> None:
    """Add ``reconstruct`` to the ``nbst crash`` subcommands ``cr`` (the defaults are the library's)."""
    from nbst.models.crash.reconstruct import MAX_ROLLOUTS, PARTICLES as N

    c = cr.add_parser("reconstruct", help="from the evidence back to each vehicle's impact speed, delta-V and PDOF, "
                                          "as 90 % intervals",
                      description="Read CASE (a crash script whose fates are the evidence: whom each vehicle hit, "
                                  "its rest position and heading, its centre of mass at the impact; or an "
                                  "nbst-crash-case, which adds the unknowns' ranges and skid marks, event data "
                                  "recorder speeds and residual crush: docs/formats.md) and draw the drivers' "
                                  "intents, the road friction, the loads and the contact's stiffness and damping "
                                  "within their ranges, keeping the draws whose crash meets every piece of "
                                  "evidence within its tolerance (ABC-SMC: approximate Bayesian computation by "
                                  "sequential Monte Carlo). Prints each vehicle's impact speed, delta-V (km/h) and "
                                  "PDOF (o'clock) as 90 %% intervals over those draws, and says which the "
                                  "evidence cannot tell (not identifiable: the interval stays wide). Writes the "
                                  "draw nearest the evidence as a crash file (replay and render it as any) with "
                                  "the intervals in its `reconstruction`.",
                      epilog="Exit 0: draws that meet the evidence found; 1: none within the budget (the "
                             "intervals are those of the nearest draws); 2: bad input; 130: interrupted.")
    c.add_argument("case", metavar="CASE", help="a case file (nbst-crash-case or nbst-crash-script JSON) or a "
                                                "built-in name")
    c.add_argument("-o", "--output", required=True, metavar="REC.json", help="where to write the reconstruction")
    add_seed(c, type=SEED, resumable=False, what=f"random seed [{SEED.limits}]")
    c.add_argument("--max-rollouts", type=ROLLOUTS, default=MAX_ROLLOUTS, metavar="N",
                   help=with_limits(f"rollout budget (default {MAX_ROLLOUTS}); the reconstruction ends sooner when "
                                    "its population meets the evidence", ROLLOUTS))
    c.add_argument("--particles", type=PARTICLES, default=N, metavar="N",
                   help=with_limits(f"draws in the population (default {N}; whole batches of 16)", PARTICLES))
    c.add_argument("--jobs", type=JOBS, default=None, metavar="K",
                   help=with_limits("threads running the rollouts (default: all cores); any K gives the same draws",
                                    JOBS))
    c.add_argument("--json", action="store_true", help="print the reconstruction as one JSON object")
    add_quiet(c, "no progress bar and no summary")
    c.set_defaults(func=cmd_reconstruct)


def _iv(x: dict | None, unit: str, k: int = 0) -> str:
    if not x:
        return "none"
    return f"{x['lo']:.{k}f}-{x['hi']:.{k}f} {unit} (median {x['median']:.{k}f})"


def summary_lines(out: dict) -> list[str]:
    """The reconstruction (its ``to_dict``) as the lines ``nbst crash reconstruct`` prints."""
    lines = []
    for v in out["vehicles"]:
        s, dv, p = v["impact_speed_kmh"], v["delta_v_kmh"], v["pdof_clock"]
        if s is None:
            lines.append(f"  {v['name']}: no draw hit as the evidence says")
            continue
        weak = [nm for nm, x in (("impact speed", s), ("delta-V", dv)) if x and x.get("identifiable") is False]
        lines.append(f"  {v['name']}: impact speed {_iv(s, 'km/h')}, delta-V {_iv(dv, 'km/h')}, "
                     f"PDOF {_iv(p, 'o clock', 1)}")
        if weak:
            lines.append(f"    not identifiable from this evidence: {', '.join(weak)} (the interval is at least "
                         f"{100 * out['weak_threshold']:.0f} % of its prior's "
                         f"{s.get('prior_lo', float('nan')):.0f}-{s.get('prior_hi', float('nan')):.0f} km/h)")
    c = out.get("closing_speed_kmh")
    if c:
        lines.append(f"  closing speed {_iv(c, 'km/h')}")
    u = out["unknowns"]
    lines.append(f"  road friction {u['friction']['lo']:.2f}-{u['friction']['hi']:.2f}, contact stiffness x "
                 f"{u['stiffness']['lo']:.2f}-{u['stiffness']['hi']:.2f}, damping x "
                 f"{u['damping']['lo']:.2f}-{u['damping']['hi']:.2f} (90 % of the accepted draws)")
    return lines


def cmd_reconstruct(args) -> int:
    from nbst.models.crash import crashfile, evidence, reconstruct
    from nbst.models.crash.scene import model_from_xml
    from nbst.models.crash.space import space_of

    case = evidence.load_case(args.case)
    prepare_output(args.output)
    seed = resolve_seed(args.seed, what="--seed")
    runner = reconstruct.AbcRunner(case, jobs=args.jobs or default_jobs())
    bar = None if args.quiet else progress_bar(total=args.max_rollouts, unit="rollout", file=sys.stderr,
                                               desc=f"reconstruct {case.script.name}")

    def progress(p):
        if bar is not None:
            bar.update(p.rollouts - bar.n)
            bar.set_postfix_str(f"tolerance {p.epsilon:.3g}, {p.accepted} draws within the evidence", refresh=False)

    try:
        with sigterm_as_interrupt():
            rec = reconstruct.reconstruct(case, seed=seed, max_rollouts=args.max_rollouts, particles=args.particles,
                                          runner=runner, callback=progress)
    finally:
        if bar is not None:
            bar.close()
        runner.close()
    b, xml = reconstruct.best_trial(case, rec)
    model = model_from_xml(xml)
    S = space_of(case.script)
    d = crashfile.crash_dict(case.script, xml, model, S.intents(b.u[None])[0], b.qpos0, b.qvel0, b.controls,
                             b.final_qpos, b.outcome, seed=seed, period_steps=runner.period)
    out = rec.to_dict()
    d["reconstruction"] = out
    write_text_atomic(args.output, json.dumps(d, indent=1, allow_nan=False) + "\n")
    met = rec.found
    if args.json:
        print_json(out)
    elif not args.quiet:
        if met:
            state = f"{out['accepted']} of {out['particles']} draws meet the evidence"
            if out["accepted"] < reconstruct.MIN_ACCEPTED:
                state += (f" (fewer than {reconstruct.MIN_ACCEPTED}: rough intervals; a larger --max-rollouts lets "
                          "the population converge)")
        else:
            state = (f"no draw meets the evidence within the budget (tolerance reached {rec.epsilon:.2f}, 1: within "
                     "it): the intervals are those of the nearest draws")
        print(f"reconstruct {case.script.name}: {state}; {out['rollouts']} rollouts, {out['generations']} "
              f"generations, seed {seed}; 90 % intervals; wrote {args.output}")
        for line in summary_lines(out):
            print(line)
    if rec.interrupted:
        return 130
    return 0 if met else 1
