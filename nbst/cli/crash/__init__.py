"""``nbst crash scripts|check|solve|replay|probability|reconstruct`` (docs/crash.md): the crash's
command-line room.

* this package registers the subcommands (light: the arguments only; their defaults are the
  library's, ``nbst.models.crash.search.DEFAULT_MAX_ROLLOUTS`` and the like);
* :mod:`.commands` runs them (:mod:`.reconstruct` registers and runs ``reconstruct``);
  :mod:`.render` is ``nbst render CRASH.json`` (``nbst render``
  dispatches there on a crash file).

Registration is light: mujoco and cma are imported inside the commands.

Exit codes: 0 done (solve: the script met; replay: the file reproduced bit for bit), 1 a check
failed (solve: not met within the budget, the nearest crash written; replay: the replay
differs), 2 bad input, 130 interrupted (solve: the best crash so far written).
"""
from __future__ import annotations

import sys

from nbst.cli.args import JOBS, SEED, Bounded, with_limits
from nbst.cli.crash import reconstruct as reconstruct_cli
from nbst.cli.crash.commands import cmd_check, cmd_probability, cmd_replay, cmd_scripts, cmd_solve
from nbst.cli.crash.report import register_report
from nbst.cli.flags import add_quiet, add_seed

__all__ = ["COMMANDS", "register"]

ROLLOUTS = Bounded("max-rollouts", 1, 10_000_000, integer=True)
ROBUST = Bounded("robust", 12, 1_000_000, integer=True)
SAMPLES = Bounded("samples", 1, 100_000, integer=True)
SOLVE_SAMPLES_FLAG = Bounded("samples", 0, 100_000, integer=True)


#: The top-level commands this module registers, with their help lines: ``nbst --help`` lists
#: them without building their arguments (nbst.cli.main builds only the command asked for).
COMMANDS = {
    "crash": "a multi-vehicle crash on MuJoCo: script it, solve it, replay it, reconstruct one",
}


def register(sub) -> None:
    # the defaults are the library's; read here, when `nbst crash` is built, so that `nbst --help`
    # loads no crash module (their registries, the vehicle files) at all
    from nbst.models.crash.robust import DEFAULT_NOISE, DEFAULT_ROBUST_BUDGET, DEFAULT_SAMPLES, NOISE_KINDS, SOLVE_SAMPLES
    from nbst.models.crash.search import DEFAULT_MAX_ROLLOUTS

    p = sub.add_parser("crash", help=COMMANDS["crash"],
                       description="The paper's second challenge (docs/crash.md): several vehicles, each driven by "
                                   "a partially autonomous driver, crash as a script says (whom each hits and in what "
                                   "order, its impact speed or delta-V, where it ends up and facing where, how it "
                                   "rolls). Units: metres, km/h, degrees, seconds.")
    cr = p.add_subparsers(dest="crash_command", metavar="SUBCOMMAND", parser_class=type(p))
    p.set_defaults(func=lambda args: (p.print_help(sys.stderr), 2)[1])

    s = cr.add_parser("scripts", help="list the built-in crash scripts",
                      description="List the built-in crash scripts (models/crash/scripts/): name, vehicles, "
                                  "what the script asks.")
    s.add_argument("--json", action="store_true", help="print one JSON object per script")
    s.set_defaults(func=cmd_scripts)

    c = cr.add_parser("check", help="validate a crash script (exit 0, or 2 with one line naming the field)",
                      description="Read SCRIPT through the input gate and print what it asks: the road, each "
                                  "vehicle, its driver's ranges and its fate.")
    c.add_argument("script", metavar="SCRIPT", help="built-in name (see `nbst crash scripts`) or a JSON file")
    c.set_defaults(func=cmd_check)

    v = cr.add_parser("solve", help="search driver intents that make the crash happen as scripted",
                      description="Search each vehicle's driver intent (speed, aim point, arrival time, reactions, "
                                  "after-impact behaviour; within the script's ranges) for a crash that meets the "
                                  "script: the paper's signature search (one bit per vehicle whose fates hold, "
                                  "crossover of whole per-vehicle blocks), a MAP-Elites archive keyed by the contact "
                                  "sequence, CMA-ES restarts. Writes the crash file (CRASH.json: the scene, the "
                                  "initial state, the realised controls, the outcome) that `nbst crash replay` and "
                                  "`nbst render` read. Ctrl-C writes the best crash so far (exit 130). The same "
                                  "--seed gives the same crash for any --jobs.",
                      epilog="Example: nbst crash solve t-bone -o tbone.json --seed 1. Exit 0: met (and, unless "
                             "--no-ladder, met at 1 and 0.5 ms too); 1: not met within --max-rollouts (the nearest "
                             "crash is written); 2: bad input; 130: interrupted.")
    v.add_argument("script", metavar="SCRIPT", help="built-in name (see `nbst crash scripts`) or a JSON file")
    v.add_argument("-o", "--output", required=True, metavar="CRASH.json", help="where to write the crash")
    add_seed(v, type=SEED, resumable=False, what=f"random seed [{SEED.limits}]")
    v.add_argument("--max-rollouts", type=ROLLOUTS, default=DEFAULT_MAX_ROLLOUTS, metavar="N",
                   help=with_limits(f"rollout budget of the search (default {DEFAULT_MAX_ROLLOUTS})", ROLLOUTS))
    _runner_flags(v)
    v.add_argument("--robust", type=ROBUST, nargs="?", const=DEFAULT_ROBUST_BUDGET, default=None, metavar="BUDGET",
                   help=with_limits("after the search, look for the crash that meets the script most often under "
                                    "driver noise: short searches gather other crashes that meet it, they race on "
                                    "common noisy re-drives, the winner is climbed on their smoothed success (CMA-ES) "
                                    "and by the rollout room's robust maximiser (BUDGET noisy rollouts, default "
                                    f"{DEFAULT_ROBUST_BUDGET}); the "
                                    "pick written keeps its outcome at 2, 1 and 0.5 ms", ROBUST))
    v.add_argument("--samples", type=SOLVE_SAMPLES_FLAG, default=None, metavar="N",
                   help=with_limits("estimate the probability that the crash written meets the script under "
                                    "driver noise from N noisy re-drives, with its 95 %% Wilson interval, into the "
                                    f"file and the summary (default {SOLVE_SAMPLES}, {DEFAULT_SAMPLES} with --robust; "
                                    "0: none)", SOLVE_SAMPLES_FLAG))
    _noise_flag(v, DEFAULT_NOISE, NOISE_KINDS)
    v.add_argument("--no-ladder", action="store_true",
                   help="accept a crash that meets the script at the script's step only (by default the search "
                        "goes on until one also meets it at 1 and 0.5 ms, and the file records that ladder)")
    add_quiet(v, "no progress bar and no summary line")
    v.set_defaults(func=cmd_solve)

    reconstruct_cli.add_parser(cr)

    b = cr.add_parser("probability", help="the probability that a crash file's intents meet its script under "
                                          "driver noise",
                      description="Run N noisy copies of CRASH.json's driver intents (--noise retake: speed "
                                  "+-0.5 m/s, aim +-0.2 m, times +-0.1 s, steering +-1 deg; population: published "
                                  "spreads of real drivers; docs/crash.md) and print the share "
                                  "that meets the script with its 95 % Wilson interval, and the outcomes seen. "
                                  "The same --seed gives the same copies (common random numbers).")
    b.add_argument("crash", metavar="CRASH.json", help="a crash file (nbst crash solve -o)")
    b.add_argument("--samples", type=SAMPLES, default=DEFAULT_SAMPLES, metavar="N",
                   help=with_limits(f"noisy rollouts (default {DEFAULT_SAMPLES})", SAMPLES))
    b.add_argument("--seed", type=SEED, default=1, help=f"noise seed [{SEED.limits}] (default 1)")
    _noise_flag(b, DEFAULT_NOISE, NOISE_KINDS)
    b.add_argument("-o", "--output", default=None, metavar="OUT.json",
                   help="also write the crash file with this estimate in its `probability`")
    _runner_flags(b)
    b.add_argument("--json", action="store_true", help="print the estimate as one JSON object")
    add_quiet(b, "no progress bar")
    b.set_defaults(func=cmd_probability)

    r = cr.add_parser("replay", help="replay a crash file with plain mj_step and check it bit for bit",
                      description="Replay CRASH.json from its own scene, initial state and recorded controls with "
                                  "a plain mj_step loop (docs/crash.md has the same recipe in a few lines of "
                                  "MuJoCo), check that the final state equals the file's bit for bit and that the "
                                  "outcome read again is the file's, and print the outcome.",
                      epilog="Exit 0: reproduced; 1: it differs; 2: bad input.")
    r.add_argument("crash", metavar="CRASH.json", help="a crash file (nbst crash solve -o)")
    r.add_argument("--json", action="store_true", help="print one JSON object: identical, outcome")
    r.set_defaults(func=cmd_replay)
    register_report(cr)


def _noise_flag(p, default: str, kinds) -> None:
    p.add_argument("--noise", choices=tuple(kinds), default=default,
                   help=f"the driver noise (default {default}): retake, what a stunt crew repeats take to take; "
                        "population, what ordinary drivers vary (published reaction times, speeds, lane positions: "
                        "docs/crash.md)")


def _runner_flags(p) -> None:
    g = p.add_mutually_exclusive_group()
    g.add_argument("--jobs", type=JOBS, default=None, metavar="K",
                   help=with_limits("threads running the rollouts (default: all cores); any K gives the same crash",
                                    JOBS))
    g.add_argument("--cluster", default=None, metavar="ADDRESS",
                   help="run the rollouts on the workers of this Dask scheduler (tcp://host:8786) instead; the same "
                        "crash as --jobs for the same seed")


