"""``nbst scene examples|check|solve|replay|validate|export`` (docs/scene.md): bring your own MuJoCo scene.

* this package registers the subcommands (light: the arguments only; their defaults are the
  library's, ``nbst.scene.search.DEFAULT_MAX_ROLLOUTS``);
* :mod:`.commands` runs them.

Exit codes, as ``nbst crash``: 0 done (solve: every fate met; replay: the file reproduced bit for
bit), 1 a check failed (solve: not met within the budget, the nearest solution written; replay:
the replay differs; validate --strict: a setting misses a fate), 2 bad input (one line naming the file and the field; nothing written), 130
interrupted (solve: the best solution so far written).
"""
from __future__ import annotations

import sys

from nbst.cli.args import JOBS, SEED, Bounded, with_limits
from nbst.cli.flags import add_out_dir, add_quiet, add_seed
from nbst.cli.scene.commands import (cmd_check, cmd_examples, cmd_export, cmd_pick, cmd_replay, cmd_solve,
                                     cmd_validate)

__all__ = ["COMMANDS", "register", "ROLLOUTS", "SAMPLES", "ANSWERS", "ROBUST"]

#: --max-rollouts' domain.
ROLLOUTS = Bounded("max-rollouts", 1, 10_000_000, integer=True)
#: --answers' domain.
ANSWERS = Bounded("answers", 1, 100, integer=True)
#: --samples' domain.
SAMPLES = Bounded("samples", 1, 100_000, integer=True)
#: --robust's domain (noisy rollouts).
ROBUST = Bounded("robust", 12, 1_000_000, integer=True)

#: The top-level commands this module registers, with their help lines: ``nbst --help`` lists
#: them without building their arguments (nbst.cli.main builds only the command asked for).
COMMANDS = {
    "scene": "bring your own MuJoCo scene: say what must happen to its bodies, solve it, replay it",
}

_FATES_HELP = "a fates file (JSON, \"format\": \"nbst-fates\") or a built-in example's name (see `nbst scene examples`)"


def register(sub) -> None:
    from nbst.scene.robust import DEFAULT_ROBUST_BUDGET, DEFAULT_ROBUST_SAMPLES
    from nbst.scene.search import DEFAULT_MAX_ROLLOUTS

    p = sub.add_parser("scene", help=COMMANDS["scene"],
                       description="Your own MJCF scene (docs/scene.md): a fates file names the scene, the free "
                                   "bodies whose initial velocities (and offsets) the search may choose, and what "
                                   "must happen to each body (where it rests, where it is at a time, which regions "
                                   "it passes, which axis ends up, what it hits in what order, what it never hits, "
                                   "that it ends at rest or never moves). Units: metres, seconds, radians (degrees "
                                   "where named).")
    sc = p.add_subparsers(dest="scene_command", metavar="SUBCOMMAND", parser_class=type(p))
    p.set_defaults(func=lambda args: (p.print_help(sys.stderr), 2)[1])

    e = sc.add_parser("examples", help="list the built-in example scenes",
                      description="List the built-in example scenes (nbst/scene/examples/): name and what must "
                                  "happen.")
    e.add_argument("--json", action="store_true", help="print one JSON object per example")
    e.set_defaults(func=cmd_examples)

    c = sc.add_parser("check", help="validate a fates file and its scene (exit 0, or 2 with one line naming the "
                                    "file and field)",
                      description="Read FATES and its scene through the input gate (the fates' fields, the scene's "
                                  "files under its folder, MuJoCo's compilation, the names) and print what it asks.")
    c.add_argument("fates", metavar="FATES", help=_FATES_HELP)
    c.add_argument("--scene", default=None, metavar="SCENE.xml", help="use this MJCF instead of the fates' \"scene\"")
    c.set_defaults(func=cmd_check)

    v = sc.add_parser("solve", help="search initial velocities that make the fates happen",
                      description="Search the controlled bodies' initial velocities (and offsets; within the fates' "
                                  "ranges) for a motion that meets every fate: the paper's signature search (one bit "
                                  "per body whose fates hold, crossover of whole per-body blocks, creep, directed "
                                  "and uniform randomize, elitism). Writes the solution file (SOL.json: the initial "
                                  "state, the controls, every fate's verdict, the seed, the versions) that `nbst "
                                  "scene replay` reads. Ctrl-C writes the best solution so far (exit 130). The same "
                                  "--seed gives the same solution for any --jobs.",
                      epilog="Example: nbst scene solve snake-eyes -o dice.json --seed 1. Exit 0: met (and, unless "
                             "--no-ladder, at h/2 and h/4 too); 1: not met within --max-rollouts (the nearest solution is written); 2: bad input; 130: "
                             "interrupted.")
    v.add_argument("fates", metavar="FATES", help=_FATES_HELP)
    v.add_argument("-o", "--output", required=True, metavar="SOL.json", help="where to write the solution")
    v.add_argument("--scene", default=None, metavar="SCENE.xml", help="use this MJCF instead of the fates' \"scene\"")
    add_seed(v, type=SEED, resumable=False, what=f"random seed [{SEED.limits}]")
    v.add_argument("--max-rollouts", type=ROLLOUTS, default=DEFAULT_MAX_ROLLOUTS, metavar="N",
                   help=with_limits(f"rollout budget of the search (default {DEFAULT_MAX_ROLLOUTS}); the finer steps' "
                                   "rollouts of the last batch's motions met at h may pass it, by 2 each at most",
                                   ROLLOUTS))
    g = v.add_mutually_exclusive_group()
    g.add_argument("--jobs", type=JOBS, default=None, metavar="K",
                   help=with_limits("threads running the rollouts (default: all cores); any K gives the same "
                                    "solution", JOBS))
    g.add_argument("--cluster", default=None, metavar="ADDRESS",
                   help="run the rollouts on the workers of this Dask scheduler (tcp://host:8786) instead; the same "
                        "solution as --jobs for the same seed (the scene's files at the same path on the workers)")
    v.add_argument("--robust", type=ROBUST, nargs="?", const=DEFAULT_ROBUST_BUDGET, default=None, metavar="BUDGET",
                   help=with_limits("after a search that meets every fate, maximise the probability that they are "
                                    "met under the fates' noise (the rollout room's robust maximiser: common random "
                                    f"numbers, successive halving; BUDGET noisy rollouts, default "
                                    f"{DEFAULT_ROBUST_BUDGET}, and 3 more for each pick's ladder) and write the pick, "
                                    "the latest that keeps every fate at h, h/2 and h/4, with its probability measured "
                                    "afresh", ROBUST))
    v.add_argument("--samples", type=SAMPLES, default=None, metavar="N",
                   help=with_limits("also estimate how often the solution written meets every fate under the "
                                    "fates' noise (\"noise\", or the defaults of docs/scene.md) from N noisy "
                                    "rollouts, with its 95 %% Wilson interval (default: none; "
                                    f"{DEFAULT_ROBUST_SAMPLES} with --robust)", SAMPLES))
    v.add_argument("--no-ladder", action="store_true",
                   help="accept a motion that meets every fate at the scene's step only (by default the search goes "
                        "on until one also meets them at h/2 and h/4, the same initial state rolled out at the "
                        "finer steps, those rollouts counted in --max-rollouts; the file records that ladder)")
    v.add_argument("--answers", type=ANSWERS, default=1, metavar="K",
                   help=with_limits("go on after every fate is met until K solutions meet them, each with a "
                                    "contact sequence of its own (which body touches what, in what order): the "
                                    "animator's choice, after Chenney & Forsyth; written under \"answers\", with "
                                    "their probabilities when --samples is given (default 1)", ANSWERS))
    add_quiet(v, "no progress bar and no summary line")
    v.set_defaults(func=cmd_solve)

    r = sc.add_parser("replay", help="replay a solution with a plain mj_step loop and check it bit for bit",
                      description="Replay SOL.json from its initial state with the plain mj_step loop of "
                                  "docs/scene.md, compare the final state with the file's bit for bit, and judge "
                                  "the fates again. Exit 0: reproduced (and, with --ladder, met at h/2 and h/4 too); 1: it differs "
                                  "(or the ladder does not hold).")
    r.add_argument("solution", metavar="SOL.json", help="a solution file written by `nbst scene solve`")
    r.add_argument("--json", action="store_true", help="print the result as JSON")
    r.add_argument("--ladder", action="store_true",
                   help="also roll the same initial state out at h/2 and h/4 and say whether every fate is still "
                        "met (exit 1 if not)")
    r.set_defaults(func=cmd_replay)

    from nbst.scene.validate import DEFAULT_VALIDATE_SAMPLES

    w = sc.add_parser("validate", help="the physics cross-validation report: the solution's fates under MuJoCo's "
                                       "integrators, solvers, cones, the timestep ladder and noise",
                      description="Roll SOL.json's controls out again under MuJoCo's integrators (Euler, "
                                  "implicitfast, RK4), constraint solvers (Newton, CG, PGS), friction cones "
                                  "(pyramidal, elliptic) and the timestep ladder (h, h/2, h/4), one option of the "
                                  "scene's <option> changed at a time, and judge every fate again (met or not, with "
                                  "its graded cost); and estimate P(every fate met) under the fates' noise from "
                                  "--samples noisy rollouts, with its 95 % Wilson interval. Prints a line per "
                                  "setting; --out-dir DIR writes index.html (a table per setting group, each fated "
                                  "body's path from above under each setting over the fates' regions and the fixed geoms), its PNGs "
                                  "and report.json (the same table).",
                      epilog="Exit status: 0, or 1 with --strict when a setting misses a fate (the noise row "
                             "apart: it is a probability); 2 on bad input. Example: nbst scene validate dice.json "
                             "--out-dir dice-report")
    w.add_argument("solution", metavar="SOL.json", help="a solution file written by `nbst scene solve`")
    add_out_dir(w, dest="out_dir", help="write the report: DIR/index.html, its PNGs and DIR/report.json")
    w.add_argument("--samples", type=SAMPLES, default=DEFAULT_VALIDATE_SAMPLES, metavar="N",
                   help=with_limits(f"noisy rollouts of the noise row (default {DEFAULT_VALIDATE_SAMPLES})", SAMPLES))
    w.add_argument("--seed", type=SEED, default=None,
                   help=f"the noise draws' seed [{SEED.limits}] (default: the solution's seed, the draws of "
                        "`nbst scene solve --samples`)")
    w.add_argument("--jobs", type=JOBS, default=None, metavar="K",
                   help=with_limits("threads running the noisy rollouts (default: all cores); any K gives the same "
                                    "report", JOBS))
    w.add_argument("--strict", action="store_true", help="exit 1 if any setting misses a fate")
    w.add_argument("--json", action="store_true", help="print report.json's content instead of the summary")
    add_quiet(w, "no summary (the report files and the exit code still tell)")
    w.set_defaults(func=cmd_validate)

    k = sc.add_parser("pick", help="write one of a solution's --answers as a solution file of its own",
                      description="Write answer N of SOL.json (solved with --answers K; 0 is the first, the "
                                  "solution's own) as a solution file of its own: its controls and states, rolled "
                                  "out again bit for bit, its fates judged anew, its ladder climbed again (when the "
                                  "solution had one) and its probability. replay, validate, export, render and "
                                  "`nbst export --gltf` take it as any solution. Exit 0, or 1 if it misses a fate.")
    k.add_argument("solution", metavar="SOL.json", help="a solution file written by `nbst scene solve --answers K`")
    k.add_argument("answer", type=int, metavar="N", help="the answer's index in the file's \"answers\" (0..K-1)")
    k.add_argument("-o", "--output", required=True, metavar="OUT.json", help="the solution file to write")
    k.set_defaults(func=cmd_pick)

    x = sc.add_parser("export", help="write the scene with a keyframe holding the solution's initial state",
                      description="Write the solution's MJCF (its own text, comments and numbers as written) with "
                                  "one more keyframe, `nbst`, holding the initial state at full precision (and the "
                                  "fates' timestep on <option>, when they set one). Loaded in `python -m "
                                  "mujoco.viewer` and reset to that key, it plays the same motion: before the file "
                                  "is kept it is compiled, reset to the key and stepped, and must end in the "
                                  "solution's final state bit for bit.")
    x.add_argument("solution", metavar="SOL.json", help="a solution file written by `nbst scene solve`")
    x.add_argument("-o", "--output", required=True, metavar="OUT.xml",
                   help="the MJCF to write (in the scene's folder when the scene reads meshes, textures or includes)")
    x.set_defaults(func=cmd_export)
