"""Subcommands ``nbst mjcf``, ``nbst validate`` and ``nbst gallery`` (MuJoCo).

Registration is light: mujoco and matplotlib are imported inside the commands.
"""
from __future__ import annotations

import sys
import time

from nbst.cli.args import MAX_TRIALS, SEED, Bounded, with_limits
from nbst.cli.flags import add_out_dir, add_quiet, add_seed
from nbst.errors import NbstError
from nbst.outputs import prepare_output, write_text_atomic
from nbst.problem import load_problem
from nbst.progress import Bar
from nbst.solution import load_solution


__all__ = ["TIMESTEP", "UNIT", "TOL", "MAX_STEPS", "MJCF_PROGRESS_MIN_N", "COMMANDS", "register", "cmd_mjcf",
           "cmd_validate", "PROGRESS_MIN_WORK", "cmd_gallery"]

#: The flags' domains (each --help states its range). The time step: above 0.01 s contacts are too
#: soft; below 1e-7 s a t_final of 1 s is already 10 million steps. The unit: on over5 (radius 10),
#: MuJoCo refuses the scene at 1e-6 m per unit (bodies too light, one line) and stops with a
#: FatalError (a traceback) at 1e300; 1e-5 to 1e4 run (measured with `nbst validate --unit`).
TIMESTEP = Bounded("timestep", 1e-7, 0.01, unit="s")
UNIT = Bounded("unit", 1e-6, 1e3, unit="m per unit")
TOL = Bounded("tol", 0.0, 1e12, lo_open=True, unit="units")
MAX_STEPS = Bounded("max steps", 1, 100_000_000, integer=True)


def _add_scene_options(p) -> None:
    p.add_argument("--timestep", type=TIMESTEP, default=0.00025, metavar="H",
                   help=with_limits("MuJoCo timestep in seconds (default 0.00025; contact stiffness is 2/H^2)",
                                    TIMESTEP))
    p.add_argument("--unit", type=UNIT, default=1e-3, metavar="M",
                   help=with_limits("metres per problem unit (default 0.001: 1 unit = 1 mm)", UNIT))


#: Disks from which ``nbst mjcf`` shows progress: MjSpec's building grows faster than N (measured
#: 1.2 s at 3,000 disks, 24 s at 10,000: ``benchmarks/bench_mujoco_scale.py --mjcf``); 1,000 take 0.1 s.
MJCF_PROGRESS_MIN_N = 2000


#: The top-level commands this module registers, with their help lines: ``nbst --help`` lists
#: them without building their arguments (nbst.cli.main builds only the command asked for).
COMMANDS = {
    "mjcf": "write the MuJoCo scene (MJCF XML) of a problem and solution",
    "validate": "run a solution in MuJoCo and compare it with the exact simulator",
    "gallery": "regenerate the MuJoCo scene gallery (models/scenes/NAME/)",
}


def register(sub) -> None:
    p = sub.add_parser("mjcf", help=COMMANDS["mjcf"],
                       description="Write PROBLEM (and the initial velocities of SOLUTION, as keyframe `initial`) "
                                   "as a MuJoCo MJCF scene built with mujoco.MjSpec: zero gravity, four walls, "
                                   "each disk a body with x/y slide joints and a frictionless elastic sphere, "
                                   "targets as non-colliding sites. Open it with `python -m mujoco.viewer "
                                   "--mjcf=scene.xml` and load keyframe `initial` to play the motion. "
                                   "Numbers are written at full double precision: the keyframe "
                                   "round-trips the solution bit for bit.")
    p.add_argument("problem", help="built-in name or path to a problem JSON file, or a crash file (nbst crash "
                                   "solve -o): its scene with keyframe `start` and its controls as custom numerics")
    p.add_argument("solution", nargs="?", help="solution JSON file (default: all disks at rest)")
    p.add_argument("-o", "--output", default="-", metavar="scene.xml", help="output file (default: stdout)")
    _add_scene_options(p)
    add_quiet(p, f"no progress line (shown from {MJCF_PROGRESS_MIN_N:,} disks) and no status line")
    p.set_defaults(func=cmd_mjcf)

    p = sub.add_parser("validate", help=COMMANDS["validate"],
                       description="Run SOLUTION in MuJoCo to t_final and compare with nbst's exact simulator: "
                                   "per-disk final position error, cost and signature under each, the collision "
                                   "sequences matched in order (time offsets), kinetic energy drift, and the first "
                                   "time any disk's two paths part by more than --tol units, with the event that "
                                   "caused it; the sensitivity of the motion and its predicted fixed-step error "
                                   "against the measured one. Prints a summary; --out-dir DIR writes report.json "
                                   "and a self-contained report.html with figures.",
                       epilog="Exit status: 0, or 1 with --strict when the signatures differ; 2 on bad input.")
    p.add_argument("problem", help="built-in name or path to a problem JSON file")
    p.add_argument("solution", help="solution JSON file")
    add_out_dir(p, dest="report", old=("--report",), help="write the report: DIR/report.html and DIR/report.json")
    _add_scene_options(p)
    p.add_argument("--tol", type=TOL, default=1.0, metavar="D",
                   help=with_limits("divergence tolerance in problem units (default 1)", TOL))
    p.add_argument("--strict", action="store_true", help="exit 1 if the signature under MuJoCo differs")
    add_quiet(p, "no summary and no status lines (the report files and the exit code still tell)")
    p.add_argument("--json", action="store_true", help="print report.json's content instead of the summary")
    p.add_argument("--max-steps", type=MAX_STEPS, default=None, metavar="N",
                   help=with_limits("refuse a run of more than N MuJoCo steps, t_final / H (default 1,000,000: "
                                    "every step's state is kept in memory); --convergence skips the step sizes "
                                    "that need more", MAX_STEPS))
    p.add_argument("--stepping", choices=("auto", "fixed", "aligned"), default="auto",
                   help="auto (default): fixed up to 63 disks, aligned above unless its estimated mj_step calls "
                        "pass 5x those of fixed steps (the report says which was used and why); fixed: MuJoCo's "
                        "fixed steps "
                        "of H, each impact resolved one step late; aligned: steps shortened to end at each touch "
                        "(found with MuJoCo's own collision detection) and each impact resolved by a micro-step of "
                        "matched stiffness: ~1e-12 units per impact before later collisions amplify it "
                        "(nbst.models.stepping; cost in the report: 3-8x the time of fixed steps at 10-1,000 disks)")
    p.add_argument("--sensitivity", choices=("auto", "on", "off"), default="auto",
                   help="the sensitivity analysis and its fixed-step prediction: auto (default) up to 300 disks "
                        "(it carries a dense Jacobian through every event: 21 s at 1,000 disks), on, off")
    p.add_argument("--convergence", action="store_true",
                   help="also run fixed steps of H, H/2, ... H/32 (scene rebuilt per step, stiffness 2/h^2) and "
                        "aligned stepping; report each one's max final error, signature and cost, and the fitted "
                        "order (log-log plot in report.html). H/32 takes 32x the steps of H")
    p.set_defaults(func=cmd_validate)

    p = sub.add_parser("gallery", help=COMMANDS["gallery"],
                       description="For each built-in problem (or the NAMEs given) write "
                                   "DIR/NAME/{problem.json, solution.json, scene.xml, preview.png}. The solution is "
                                   "the better of DIR/NAME/solution.json (if present) and a fresh `nbst.search."
                                   "solve` run (skipped with --no-search).")
    p.add_argument("names", nargs="*", metavar="NAME", help="built-in problems (default: all)")
    add_out_dir(p, dest="dir", old=("--dir",), help="gallery folder (default: models/scenes of nbst)")
    add_seed(p, type=SEED, resumable=True, what=f"search seed [{SEED.limits}]")
    p.add_argument("--max-trials", type=MAX_TRIALS, default=1_000_000, metavar="N",
                   help=with_limits("search budget per problem (default 1,000,000)", MAX_TRIALS))
    add_quiet(p, "no progress lines")
    p.add_argument("--no-search", action="store_true", help="only re-render scenes from the stored solutions")
    p.set_defaults(func=cmd_gallery)


def _velocities(problem, solution, *, whole_motion: bool = False):
    """A solution file's velocities (None without one); with ``whole_motion``, refused in one
    line when nbst cannot simulate them to t_final (``nbst.cli.args.exact_motion``)."""
    if not solution:
        return None
    v = load_solution(solution, problem).velocities
    if whole_motion:
        from nbst.cli.args import exact_motion

        exact_motion(problem, solution, v)
    return v


def cmd_mjcf(args) -> int:
    from nbst.models.scene import scene_xml

    if _is_crash(args.problem):
        return _crash_mjcf(args)
    problem = load_problem(args.problem)
    v = _velocities(problem, args.solution)
    if args.output != "-":
        prepare_output(args.output, inputs=(args.problem, args.solution))
    bar = None
    if problem.n >= MJCF_PROGRESS_MIN_N and not args.quiet:
        bar = Bar("nbst mjcf: building the scene", problem.n, unit="disk", file=sys.stderr)
    try:
        xml = scene_xml(problem, v, timestep=args.timestep, unit=args.unit, progress=bar.update if bar else None)
    finally:
        if bar is not None:
            bar.close()
    if args.output == "-":
        sys.stdout.write(xml)
    else:
        write_text_atomic(args.output, xml)
        if not args.quiet:
            print(f"nbst mjcf: wrote {args.output} ({problem.n} disks; view: python -m mujoco.viewer "
                  f"--mjcf={args.output})", file=sys.stderr)
    return 0


def _is_crash(path) -> bool:
    """Whether PROBLEM names a crash file (nbst crash solve -o): a JSON file of kind nbst-crash."""
    import os
    import re

    try:
        if not (str(path).endswith(".json") and os.path.isfile(path)):
            return False
        with open(path, "rb") as f:
            head = f.read(4096).decode("utf-8", "replace")
    except OSError:
        return False
    return re.search(r'"kind"\s*:\s*"nbst-crash"', head) is not None


def _crash_mjcf(args) -> int:
    """``nbst mjcf CRASH.json``: the crash's scene with keyframe ``start`` and its recorded controls
    (``nbst.models.crash.export``: a plain mj_step loop plays it, docs/crash.md)."""
    from nbst.models.crash import crashfile, export

    if args.solution:
        raise crashfile.CrashFileError(f"{args.solution}: a crash file carries its own controls; give it alone")
    d, script, model = crashfile.load(args.problem)
    xml = export.export_xml(d)
    if args.output == "-":
        sys.stdout.write(xml)
        return 0

    prepare_output(args.output, inputs=(args.problem,))
    write_text_atomic(args.output, xml)
    if not args.quiet:
        print(f"nbst mjcf: wrote {args.output} ({script.n} vehicles, {d['nstep']} steps; keyframe `start`; "
              f"controls in custom numeric `crash_controls`, {d['controls']['period_steps']} steps a row; "
              f"play: docs/crash.md, \"Play the export in MuJoCo\")", file=sys.stderr)
    return 0


def cmd_validate(args) -> int:
    from nbst.models.mjrun import MAX_STEPS, check_steps
    from nbst.models.validate import validate

    problem = load_problem(args.problem)
    v = _velocities(problem, args.solution, whole_motion=True)
    max_steps = args.max_steps or MAX_STEPS
    check_steps(problem.t_final, args.timestep, max_steps)  # before any work: memory grows with the steps
    if args.report:
        prepare_output(args.report, directory=True, option="--out-dir", files=("report.json", "report.html"))
    progress = _progress(problem, args)
    # aligned stepping's jam, or a run past --max-steps: a MujocoError, main's one line
    val = validate(problem, v, timestep=args.timestep, unit=args.unit, tol=args.tol, max_steps=max_steps,
                   stepping=args.stepping, convergence=args.convergence,
                   sensitivity={"auto": None, "on": True, "off": False}[args.sensitivity], progress=progress)
    if args.report:
        from pathlib import Path

        from nbst.outputs import write_json_atomic, write_text_atomic

        from nbst.render.report import report_html
        out = Path(args.report)
        t0 = time.perf_counter()
        if progress is not None:
            print(f"nbst validate: writing the report ({problem.n} disks, {len(val.exact.events):,} exact events)",
                  file=sys.stderr, flush=True)
        write_json_atomic(out / "report.json", val.to_dict(), option="--out-dir")
        write_text_atomic(out / "report.html", report_html(val), option="--out-dir")
        if progress is not None:
            print(f"nbst validate: report written in {time.perf_counter() - t0:.1f} s", file=sys.stderr, flush=True)
    if args.json:
        from nbst.cli.args import print_json
        from nbst.solution import _json_safe
        print_json(_json_safe(val.to_dict()))
    elif not args.quiet:
        print(val.summary())
        if args.report:
            print(f"report     {args.report}/report.html, {args.report}/report.json")
    if args.strict and not val.signatures_agree:
        print(_strict_hint(problem, v, val, args), file=sys.stderr)
        return 1
    return 0


def _strict_hint(problem, v, val, args) -> str:
    """What --strict's failure means and what to do: the motion's amplification (how far a velocity
    error of 1 unit/s moves the final positions, ``nbst.sim.sensitivity``) and ``nbst solve --robust``."""
    sens = val.sensitivity or {}
    amp = sens.get("amplification")
    if amp is None and not sens.get("error"):
        import numpy as np

        try:
            from nbst.sim.sensitivity import analyze

            amp = analyze(problem, v).get("amplification")
        except (NbstError, np.linalg.LinAlgError):
            amp = None
    what = (f"its amplification is {amp:.4g} s (a velocity error of 1 unit/s moves a final position by up to "
            f"{amp:.4g} units), so a fixed-step engine's small per-impact errors can change where disks end"
            if amp is not None else "a fixed-step engine's small per-impact errors changed where disks end")
    return (f"nbst validate: --strict: the signature under MuJoCo differs from the exact one: {what}. "
            f"For a motion that survives it: nbst solve {args.problem} --robust -o SOLUTION.json")


#: Work (MuJoCo steps x bodies) above which validate shows progress on stderr: ~0.3 s of fixed
#: steps (60 disks over 8,000 steps, benchmarks/bench_mujoco_scale.py); the built-in problems
#: (14 disks, 20,000 steps) stay as quiet as they always were.
PROGRESS_MIN_WORK = 500_000


def _progress(problem, args):
    """validate's progress factory (``nbst.progress.progress_bar``, one bar per long stage), or None
    with -q or for a short run (below :data:`PROGRESS_MIN_WORK`; the convergence study always talks)."""
    from nbst.models.mjrun import steps_needed

    if args.quiet:
        return None
    work = steps_needed(problem.t_final, args.timestep) * (problem.n + 4)
    if work < PROGRESS_MIN_WORK and not args.convergence:
        return None

    def factory(desc, total, unit):
        return Bar(f"nbst validate: {desc}", total, unit=unit, file=sys.stderr)
    return factory


def cmd_gallery(args) -> int:
    from nbst.models.gallery import main as gallery_main
    argv = list(args.names) + ["--seed", str(args.seed), "--max-trials", str(args.max_trials)]
    if args.dir:
        from nbst.models.gallery import FILES
        from nbst.problem import builtin_names

        prepare_output(args.dir, directory=True, option="--out-dir",
                       files=[f"{name}/{f}" for name in (args.names or builtin_names()) for f in FILES])
        argv += ["--dir", args.dir]
    if args.no_search:
        argv.append("--no-search")
    if args.quiet:
        import contextlib
        import io

        with contextlib.redirect_stdout(io.StringIO()):
            return gallery_main(argv)
    return gallery_main(argv)
