"""``nbst solve``: run nbst's search (or the paper's, or one of its variants) and write a solution file."""
from __future__ import annotations

import sys

from nbst.cli.args import JOBS, MAX_TRIALS, SEED, TARGET_COST, TRIALS_MAX, Bounded, with_limits
from nbst.cli.flags import add_seed
from nbst.search.variants import DEFAULT_VARIANT
from nbst.warmup import COLD_COMPILE_SECONDS

PATIENCE = Bounded("patience", 0, TRIALS_MAX, integer=True)


def _variant_help() -> str:
    from nbst.search.variants import DEFAULT_VARIANT, VARIANTS

    return f"the signature search's variant (default {DEFAULT_VARIANT}): " + VARIANTS.help_text()


def _algorithm_help() -> str:
    from nbst.solvers import SIGNATURE, SOLVERS

    return (f"the solver (default {SIGNATURE}; --variant picks the signature search's variant; the baselines: "
            "docs/experiments.md): " + SOLVERS.help_text())


def register(sub) -> None:
    from nbst.search.variants import DEFAULT_MAX_TRIALS, DEFAULT_PATIENCE, DEFAULT_VARIANT, VARIANTS
    from nbst.solvers import SIGNATURE, SOLVERS

    p = sub.add_parser(
        "solve", help="find initial velocities that bring every disk to its target",
        description="Search for initial velocities that bring every disk of PROBLEM to its target at t_final "
                    "(nbst's search by default; the paper's signature-based evolutionary search with --variant A, "
                    "or one of its simplified variants B-H), "
                    "and write the best solution found to a JSON file. Ctrl-C stops the search and still writes "
                    "the best solution so far (exit 130). The same --seed gives the same solution, bit for bit.",
        epilog="By default a solve stops at the first of: --max-trials, --patience, or a cost at round-off level "
               "(every disk within 1e-9 of the box size of its target; --target-cost 0 turns that off). "
               "The first run on a new install also compiles the numba kernels (one time, about "
               f"{COLD_COMPILE_SECONDS} s; scripts/setup.sh does it ahead). "
               "Every choice the paper leaves open is listed in docs/search.md.")
    p.add_argument("problem", help="built-in name or path to a problem JSON file")
    p.add_argument("-o", "--output", required=True, metavar="SOLUTION.json", help="where to write the solution")
    add_seed(p, type=SEED, resumable=False, what=f"random seed [{SEED.limits}]")
    p.add_argument("--max-trials", type=MAX_TRIALS, default=DEFAULT_MAX_TRIALS, metavar="N",
                   help=with_limits(f"trial budget, initialization included (default {DEFAULT_MAX_TRIALS})",
                                    MAX_TRIALS))
    p.add_argument("--patience", type=PATIENCE, default=DEFAULT_PATIENCE, metavar="K",
                   help=with_limits(f"stop after K trials without improvement; 0 = never (default {DEFAULT_PATIENCE}). "
                                    "In nbst's "
                                    "portfolio (noncueable disks) an island restarts with the other configuration "
                                    "instead, while its budget lasts", PATIENCE))
    p.add_argument("--algorithm", type=SOLVERS.argtype("--algorithm"), default=SIGNATURE, metavar="NAME",
                   help=_algorithm_help())
    p.add_argument("--variant", type=VARIANTS.argtype("--variant"), default=DEFAULT_VARIANT, metavar="X",
                   help=_variant_help())
    p.add_argument("--target-cost", type=TARGET_COST, default=None, metavar="C",
                   help=with_limits("stop as soon as the best cost (sum of squared distances to the targets, units^2) "
                                    "is <= C (default: round-off level, N x (1e-9 x box size)^2; 0: only an exact "
                                    "zero stops)", TARGET_COST))
    p.add_argument("--robust", action="store_true",
                   help="search for a solution that also survives a fixed-step engine (MuJoCo, h = 0.25 ms): "
                        "every candidate is scored by its worst cost over its own run and 8 runs from start "
                        "positions shifted by ~half a step of travel (MuJoCo's per-impact error), a disk counting "
                        "as on target only if it is in all of them; the written solution is the most robust of the "
                        "best ones found "
                        "(fresh shifts, polished), which may cost more than a plain solve's "
                        "(signature search only; docs/search.md, \"Robust mode\")")
    p.add_argument("--jobs", type=JOBS, default=None, metavar="K",
                   help="independent searches (islands) on K cores, each from its own seed derived from --seed and "
                        "with 1/K of the trial budget, run in lockstep and all stopped at the first round in which "
                        "one reaches the target cost; the best island's solution is written. The same --seed and K "
                        "give the same solution. With noncueable disks the default search is a portfolio: the "
                        "islands alternate nbst (backward planner) and nbst-noplan, and --jobs 1 runs those two "
                        "islands taking turns in this process (docs/search.md). "
                        f"Default: every core; 1: a single search in this process [{JOBS.limits}]")
    p.add_argument("--cluster", default=None, metavar="ADDRESS",
                   help="run islands 1..K-1 as tasks on the workers of this Dask scheduler (tcp://host:8786; "
                        "start one with `dask scheduler` and `dask worker ADDRESS`); island 0 runs here. Same "
                        "rounds, so the same solution as on local cores for the same --seed and K. Default K "
                        "with --cluster: 1 + the workers' threads")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar and no summary line")
    p.set_defaults(func=cmd_solve)


def cmd_solve(args) -> int:
    from nbst.outputs import prepare_output, signals_deferred, write_json_atomic
    from nbst.problem import ProblemError, load_problem
    from nbst.solvers import SIGNATURE, SOLVERS

    problem = load_problem(args.problem)
    # before the search: a long solve must not end unable to write, nor overwrite its input
    prepare_output(args.output, inputs=(args.problem,))
    algorithm = getattr(args, "algorithm", SIGNATURE)
    robust = bool(getattr(args, "robust", False))
    takes_variants = SOLVERS[algorithm].variants
    for option, given in (("--variant", args.variant != DEFAULT_VARIANT), ("--robust", robust)):
        if given and not takes_variants:
            raise ProblemError("<arguments>", option, f"applies to --algorithm {SIGNATURE} only, not {algorithm}")
    label = (args.variant if takes_variants else algorithm) + (", robust" if robust else "")
    from nbst.search import roundoff_cost

    target_cost = roundoff_cost(problem) if args.target_cost is None else args.target_cost
    if not args.quiet:
        from nbst.warmup import announce, search_kernels

        announce(search_kernels())
    bar = []  # made at the first progress report: no rate or ETA while numba compiles
    done = [0]

    def progress(p) -> None:
        if args.quiet:
            return
        if not bar:
            from nbst.progress import progress_bar

            # the many-body search stops after rounds without a better motion, long before its
            # trial budget as a rule: no total (so no ETA over --max-trials); the postfix says
            # how near that stop is
            bar.append(progress_bar(total=None if p.stall is not None else args.max_trials, unit="trial",
                                    unit_scale=True, file=sys.stderr, dynamic_ncols=True,
                                    desc=f"solve {problem.name} ({label})", smoothing=0.1))
        bar[0].update(p.trials - done[0])
        done[0] = p.trials
        post = f"best cost {p.best_cost:.6g}, {p.best_order}/{problem.n} disks on target"
        if p.stall is not None:
            post += f", {p.stall[0]} of {p.stall[1]} rounds without a better motion"
        bar[0].set_postfix_str(post, refresh=False)

    from nbst.cli.args import cluster_client
    from nbst.parallel import default_jobs
    from nbst.solvers.islands import solve_islands

    client = cluster_client(args)  # None without --cluster; ProblemError (exit 2, one line) if unreachable
    if args.jobs is not None:
        jobs = args.jobs
    elif client is not None:
        jobs = 1 + sum(w.get("nthreads", 1) for w in client.scheduler_info().get("workers", {}).values())
    else:
        jobs = default_jobs()
    # Inside main's interrupt_once: the first Ctrl-C, SIGTERM or SIGHUP stops the search, which
    # returns its best so far; later ones cannot stop the write below (they are only noted).
    result, stopped_late = None, False
    try:
        # K islands on K cores, or (the many-body search past 63 disks) one search on K threads
        result = solve_islands(problem, jobs=jobs, algorithm=algorithm, seed=args.seed, max_trials=args.max_trials,
                               patience=args.patience, target_cost=target_cost,
                               variant=args.variant if takes_variants else None, robust=robust,
                               callback=progress, cluster=client)
    finally:
        try:
            if bar:
                bar[0].close()
            if client is not None:
                client.close()
        except KeyboardInterrupt:  # the first signal landed after the search: write its result all the same
            stopped_late = True
    if result is None:
        raise KeyboardInterrupt
    with signals_deferred(reraise=False) as late:  # a signal during the write waits for it
        write_json_atomic(args.output, result.to_dict())
    late = late or stopped_late
    return _summary(args, problem, result, target_cost, late)


def _summary(args, problem, r, target_cost: float, late: bool) -> int:
    """The summary line (and robust mode's line); the exit status."""
    from nbst.constants import many_body

    why = {"target_cost": ("cost at round-off level" if args.target_cost is None else f"cost <= {target_cost:g}"),
           "max_trials": "trial budget spent", "patience": f"no improvement in {args.patience} trials",
           "interrupted": "interrupted"}.get(r.stopped, str(r.stopped))
    if r.stopped == "patience" and r.many is not None:  # the many-body search: rounds, or --patience trials
        why = f"no better motion in {r.params['patience_rounds']} rounds (or in {args.patience} trials)"
    island = (f" (best of {len(r.islands)} islands: island {r.island}"
              + (f", {r.configuration}" if r.configuration is not None else "") + ")") if r.island is not None else ""
    shown = "in the file" if many_body(problem.n) else r.signature
    line = (f"cost {r.cost:.6g}, {r.order}/{problem.n} disks on target (signature {shown}) "
            f"after {r.trials} trials in {r.wall_time:.1f} s, seed {r.seed}"
            f"{island}; stopped: {why}; "
            f"wrote {args.output}")
    if r.stopped == "interrupted" or late:
        print(f"nbst solve: interrupted; best so far written: {line}", file=sys.stderr)
        return 130
    if not args.quiet:
        print(f"nbst solve: {line}", file=sys.stderr)
        rb = r.robust
        if rb:
            sc = rb["score"]
            print(f"nbst solve: robust: {sc['order']}/{problem.n} disks on target in every one of {rb['samples']} "
                  f"shifted runs; on-target disks within {sc['worst_distance']:.4g} units of their targets "
                  f"({rb['quantile']:.0%} quantile, R = {problem.target_radius:g}); chosen from {rb['candidates']} "
                  "candidates", file=sys.stderr)
    return 0
