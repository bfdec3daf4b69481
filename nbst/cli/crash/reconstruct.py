"""``nbst crash reconstruct CASE -o REC.json``: the evidence back to each vehicle's impact speed,
delta-V and PDOF as 90 % intervals (Optimisation Monte Carlo: docs/crash.md), with the
quantities the evidence does not pin said to be not identifiable.

Registered by :mod:`nbst.cli.crash` (:func:`add_parser`); light at import: the crash room and
mujoco are imported inside :func:`cmd_reconstruct`.

Exit codes: 0 draws that meet the evidence were found (the intervals are theirs); 1 none within
the budget (the intervals are the prior's, said so, and the nearest crash is written); 2 bad
input; 130 interrupted (what ran is written).
"""
from __future__ import annotations

import json
import math
import sys

from nbst.cli.args import JOBS, SEED, Bounded, print_json, with_limits
from nbst.cli.flags import add_quiet, add_seed
from nbst.outputs import prepare_output, sigterm_as_interrupt, write_text_atomic
from nbst.parallel import default_jobs
from nbst.progress import progress_bar
from nbst.seeds import resolve_seed

__all__ = ["ROLLOUTS", "DRAWS", "add_parser", "cmd_reconstruct", "summary_lines"]

ROLLOUTS = Bounded("max-rollouts", 1, 10_000_000, integer=True)
DRAWS = Bounded("draws", 1, 100_000, integer=True)


def add_parser(cr) -> None:
    """Add ``reconstruct`` to the ``nbst crash`` subcommands ``cr`` (the defaults are the library's).

    Args:
        cr: the ``nbst crash`` subparsers.

    Returns:
        None.
    """
    from nbst.models.crash.reconstruct import DRAWS as N, MAX_ROLLOUTS

    c = cr.add_parser("reconstruct", help="from the evidence back to each vehicle's impact speed, delta-V and PDOF, "
                                          "as 90 %% intervals",
                      description="Read CASE (a crash script whose fates are the evidence: whom each vehicle hit, "
                                  "its rest position and heading, its centre of mass at the impact; or an "
                                  "nbst-crash-case, which adds the unknowns' ranges and skid marks, event data "
                                  "recorder speeds and residual crush: docs/formats.md). Each draw takes the road "
                                  "friction, the loads and the contact's stiffness and damping from their ranges "
                                  "and an error of the evidence within its tolerances, and fits the drivers' "
                                  "intents to it (Optimisation Monte Carlo); a draw whose fit meets every piece of "
                                  "evidence within its tolerance is accepted. Prints each vehicle's impact speed, "
                                  "delta-V (km/h) and PDOF (o'clock) as 90 % intervals over the accepted draws, each "
                                  "spread over its local set (the intents and unknowns near it that still meet "
                                  "the evidence, linearised), "
                                  "and says which the evidence cannot tell (not identifiable: the interval is "
                                  "reported at least as wide as the prior's). Writes the accepted draw nearest "
                                  "the evidence as a crash file (replay and render it as any) with the intervals "
                                  "in its `reconstruction`.",
                      epilog="Exit 0: draws that meet the evidence found; 1: none within the budget (the "
                             "intervals are the prior's); 2: bad input; 130: interrupted.")
    c.add_argument("case", metavar="CASE", help="a case file (nbst-crash-case or nbst-crash-script JSON) or a "
                                                "built-in name")
    c.add_argument("-o", "--output", required=True, metavar="REC.json", help="where to write the reconstruction")
    add_seed(c, type=SEED, resumable=False, what=f"random seed [{SEED.limits}]")
    c.add_argument("--max-rollouts", type=ROLLOUTS, default=MAX_ROLLOUTS, metavar="N",
                   help=with_limits(f"rollout budget, pilot fit and draws together (default {MAX_ROLLOUTS})",
                                    ROLLOUTS))
    c.add_argument("--draws", type=DRAWS, default=N, metavar="N",
                   help=with_limits(f"Monte Carlo draws, each fitted once (default {N})", DRAWS))
    c.add_argument("--jobs", type=JOBS, default=None, metavar="K",
                   help=with_limits("threads running the rollouts (default: all cores); any K gives the same draws",
                                    JOBS))
    c.add_argument("--json", action="store_true", help="print the reconstruction as one JSON object")
    add_quiet(c, "no progress bar and no summary")
    c.set_defaults(func=cmd_reconstruct)


def _iv(x: dict | None, unit: str, k: int = 0) -> str:
    if not x:
        return "none"
    med = x.get("median")
    mid = "" if med is None or (isinstance(med, float) and math.isnan(med)) else f" (median {med:.{k}f})"
    return f"{x['lo']:.{k}f}-{x['hi']:.{k}f} {unit}{mid}"


def summary_lines(out: dict) -> list[str]:
    """The reconstruction (its ``to_dict``) as the lines ``nbst crash reconstruct`` prints.

    Args:
        out: ``Reconstruction.to_dict()``.

    Returns:
        the lines, without newlines.
    """
    lines = []
    for v in out["vehicles"]:
        s, dv, p = v["impact_speed_kmh"], v["delta_v_kmh"], v["pdof_clock"]
        if s is None:
            lines.append(f"  {v['name']}: no interval")
            continue
        flag = lambda x: "" if not x or x.get("identifiable", True) else " NOT IDENTIFIABLE"  # noqa: E731
        lines.append(f"  {v['name']}: impact speed {_iv(s, 'km/h')}{flag(s)}, delta-V {_iv(dv, 'km/h')}{flag(dv)}, "
                     "PDOF " + _iv(p, "o'clock", 1))
    c = out.get("closing_speed_kmh")
    if c:
        lines.append(f"  closing speed {_iv(c, 'km/h')}{'' if c.get('identifiable', True) else ' NOT IDENTIFIABLE'}")
    u = out.get("unknowns") or {}
    if u:
        lines.append(f"  accepted draws' road friction {u['friction']['lo']:.2f}-{u['friction']['hi']:.2f}, load "
                     f"{u['load_kg']['lo']:.0f}-{u['load_kg']['hi']:.0f} kg, contact stiffness x "
                     f"{u['stiffness']['lo']:.2f}-{u['stiffness']['hi']:.2f}, damping x "
                     f"{u['damping']['lo']:.2f}-{u['damping']['hi']:.2f}")
    m = out.get("momentum_screen")
    if m:
        sp = ", ".join(f"{v['name']} {v['impact_speed_kmh']['lo']:.0f}-{v['impact_speed_kmh']['hi']:.0f} km/h"
                       for v in m["vehicles"])
        lines.append(f"  momentum screen (slides to rest, ranges drawn): {sp}"
                     + (" (approaches near parallel: the split is not pinned)" if m["degenerate"] else ""))
    for v in out.get("verdicts", []):
        lines.append(f"  {v}")
    return lines


def cmd_reconstruct(args) -> int:
    """Run ``nbst crash reconstruct`` (module docstring).

    Args:
        args: the parsed arguments.

    Returns:
        the exit code.
    """
    from nbst.models.crash import crashfile, evidence, reconstruct
    from nbst.models.crash.scene import model_from_xml
    from nbst.models.crash.space import space_of

    case = evidence.load_case(args.case)
    prepare_output(args.output)
    seed = resolve_seed(args.seed, what="--seed")
    runner = reconstruct.PhysRunner(case, jobs=args.jobs or default_jobs())
    bar = None if args.quiet else progress_bar(total=args.max_rollouts, unit="rollout", file=sys.stderr,
                                               desc=f"reconstruct {case.script.name}")

    def progress(p):
        if bar is not None:
            bar.update(p.rollouts - bar.n)
            bar.set_postfix_str(f"nearest {p.best:.2f} tolerances, {p.accepted} draws accepted", refresh=False)

    try:
        with sigterm_as_interrupt():
            rec = reconstruct.reconstruct(case, seed=seed, max_rollouts=args.max_rollouts, draws=args.draws,
                                          runner=runner, callback=progress)
    finally:
        if bar is not None:
            bar.update(max(0, (rec.rollouts if "rec" in locals() else bar.n) - bar.n))
            bar.close()
        runner.close()
    b, xml = reconstruct.best_trial(case, rec)
    assert b.controls is not None and b.qpos0 is not None and b.qvel0 is not None and b.final_qpos is not None
    model = model_from_xml(xml)
    S = space_of(case.script)
    d = crashfile.crash_dict(case.script, xml, model, S.intents(b.u[None])[0], b.qpos0, b.qvel0, b.controls,
                             b.final_qpos, b.outcome, seed=seed, period_steps=runner.period)
    out = rec.to_dict()
    d["reconstruction"] = out
    write_text_atomic(args.output, json.dumps(d, indent=1, allow_nan=False) + "\n")
    if args.json:
        print_json(out)
    elif not args.quiet:
        state = (f"{out['accepted']} of {out['draws']} draws meet the evidence" if rec.found else
                 "no draw meets the evidence within the budget: the intervals are the prior's")
        print(f"reconstruct {case.script.name} in {out['rollouts']} rollouts (pilot {out['pilot_rollouts']}), seed "
              f"{seed}: {state}; 90 % intervals; wrote {args.output}")
        for line in summary_lines(out):
            print(line)
    if rec.interrupted:
        return 130
    return 0 if rec.found else 1
