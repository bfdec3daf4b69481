"""``nbst solve``: run nbst's search (or the paper's, or one of its variants) and write a solution file."""
from __future__ import annotations

import sys
from dataclasses import dataclass
from typing import TYPE_CHECKING

from nbst import progress
from nbst.cli.args import JOBS, MAX_TRIALS, SEED, TARGET_COST, TRIALS_MAX, Bounded, cluster_client, with_limits
from nbst.cli.flags import add_seed
from nbst.constants import many_body
from nbst.outputs import prepare_output, signals_deferred, write_json_atomic
from nbst.problem import ProblemError, load_problem
from nbst.progress import count_text, seconds_text, since_start
from nbst.seeds import resolve_seed
from nbst.warmup import COLD_COMPILE_SECONDS

if TYPE_CHECKING:
    from nbst.search.variants import SolveRequest

__all__ = ["PATIENCE", "COMMANDS", "register", "cmd_solve"]

PATIENCE = Bounded("patience", 0, TRIALS_MAX, integer=True)


def _variant_help() -> str:
    from nbst.search.variants import DEFAULT_VARIANT, VARIANTS

    return f"the signature search's variant (default {DEFAULT_VARIANT}): " + VARIANTS.help_text()


def _algorithm_help() -> str:
    from nbst.solvers import SIGNATURE, SOLVERS

    return (f"the solver (default {SIGNATURE}; --variant picks the signature search's variant; the baselines: "
            "docs/experiments.md): " + SOLVERS.help_text())


#: The top-level commands this module registers, with their help lines: ``nbst --help`` lists
#: them without building their arguments (nbst.cli.main builds only the command asked for).
COMMANDS = {
    "solve": "find initial velocities that bring every disk to its target",
}


def register(sub) -> None:
    from nbst.search.variants import DEFAULT_MAX_TRIALS, DEFAULT_PATIENCE, DEFAULT_VARIANT, VARIANTS
    from nbst.solvers import SIGNATURE, SOLVERS

    p = sub.add_parser("solve", help=COMMANDS["solve"],
        description="Search for initial velocities that bring every disk of PROBLEM to its target at t_final "
                    "(nbst's search by default; the paper's signature-based evolutionary search with --variant A, "
                    "or one of its simplified variants B-H), "
                    "and write the best solution found to a JSON file. Ctrl-C (or SIGTERM, SIGHUP) at any moment after "
                    "the problem is read stops the search and still writes the best motion so far, the straight "
                    "start (every disk straight at its target) if the search has none yet (exit 130). The same "
                    "--seed gives the same solution, bit for bit.",
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


class _Progress:
    """``nbst solve``'s progress bar (``nbst.progress.Bar``): shown as soon as the problem is read, on
    the command's clock, fed by the search's reports, and closed on the written result, so its last
    line and the summary quote the same trials, seconds, cost and disks on target."""

    def __init__(self, args, problem, label: str, total: int | None) -> None:
        self.problem = problem
        # --max-trials is a budget the search may stop short of (patience, target): no ETA over it
        self.bar = progress.Bar(f"solve {problem.name} ({label})", total, unit="trial", bound=True,
                                start=progress.command_start(), quiet=args.quiet)
        self.bar.note("loading the simulator and the straight start")

    def report(self, p) -> None:
        """A search's report (``SearchProgress``): trials done, the best cost and order so far."""
        post = f"best cost {p.best_cost:.6g}, {p.best_order}/{self.problem.n} disks on target"
        if p.stall is not None:  # the many-body search: rounds without a better motion, not an ETA
            post += f", {p.stall[0]} of {p.stall[1]} rounds without a better motion"
        self.bar.note(post)
        self.bar.set(p.trials)

    def close(self, r) -> None:
        """The written result is the bar's last state (what the summary says)."""
        self.bar.close(n=r.trials, note=f"best cost {r.cost:.6g}, {r.order}/{self.problem.n} disks on target")

    @property
    def seconds(self) -> float:
        return self.bar.seconds


@dataclass(frozen=True)
class _Options:
    """A solve's options once checked (the seed drawn, so that even the straight start records it)."""

    algorithm: str
    request: SolveRequest  # seed (drawn), budget, patience, target cost, variant (None: a solver without), robust
    label: str


def _options(args, problem) -> _Options:
    """The checks before any work: the output path (a long solve must not end unable to write, nor
    overwrite its input) and the options that apply to the solver asked for."""
    from nbst.search.variants import DEFAULT_VARIANT, SolveRequest, roundoff_cost
    from nbst.solvers import SIGNATURE, SOLVERS

    prepare_output(args.output, inputs=(args.problem,))
    algorithm = getattr(args, "algorithm", SIGNATURE)
    robust = bool(getattr(args, "robust", False))
    takes_variants = SOLVERS[algorithm].variants
    for option, given in (("--variant", args.variant != DEFAULT_VARIANT), ("--robust", robust)):
        if given and not takes_variants:
            raise ProblemError("<arguments>", option, f"applies to --algorithm {SIGNATURE} only, not {algorithm}")
    label = (args.variant if takes_variants else algorithm) + (", robust" if robust else "")
    request = SolveRequest(seed=resolve_seed(args.seed, what="--seed"), max_trials=args.max_trials,
                           patience=args.patience, variant=args.variant if takes_variants else None, robust=robust,
                           target_cost=roundoff_cost(problem) if args.target_cost is None else args.target_cost)
    return _Options(algorithm=algorithm, request=request, label=label)


def _straight(args, problem, o: _Options):
    from nbst.search import straight_start

    return straight_start(problem, o.request)


def cmd_solve(args) -> int:
    problem = load_problem(args.problem)
    # Inside main's interrupt_once: the first Ctrl-C, SIGTERM or SIGHUP from here on stops the solve
    # and writes the best motion so far: the search's, or the straight start before it has one.
    o = result = fallback = client = bar = None
    interrupted = False
    try:
        try:
            with signals_deferred():  # a signal here waits for the checks, then stops the solve
                o = _options(args, problem)
            # before the bar: an unreachable --cluster address is one line (ProblemError, exit 2)
            client = cluster_client(args)
            # the bar, the heavy imports (numba, whose import a signal must not cut in half) and the
            # straight start: a signal here waits for them (about a second), then stops the solve
            with signals_deferred():
                # the many-body search stops after rounds without a better motion, long before its
                # trial budget as a rule: no total (so no ETA over --max-trials)
                bar = _Progress(args, problem, o.label,
                                None if many_body(problem.n) and o.request.variant is not None else args.max_trials)
                if not args.quiet:  # a cold numba cache: say so before the first kernel compiles
                    from nbst.warmup import announce, search_kernels

                    announce(search_kernels())
                from nbst.solvers.islands import run_islands

                fallback = _straight(args, problem, o)
            bar.report(_first_report(fallback))
            if args.jobs is not None:
                jobs = args.jobs
            elif client is not None:
                jobs = 1 + sum(w.get("nthreads", 1) for w in client.scheduler_info().get("workers", {}).values())
            else:
                from nbst.parallel import default_jobs

                jobs = default_jobs()
            # K islands on K cores, or (the many-body search past 63 disks) one search on K threads
            result = run_islands(problem, o.request, jobs=jobs, algorithm=o.algorithm, callback=bar.report,
                                 cluster=client)
        finally:
            if client is not None:
                client.close()
    except KeyboardInterrupt:  # before the search returned, or just after: what is there is written
        interrupted = True
    if o is None:  # stopped before the checks were done: nothing to write
        raise KeyboardInterrupt
    result, late = _write(args, problem, o, result, fallback, bar)

    seconds = bar.seconds if bar is not None else since_start()
    return _summary(args, problem, result, o.request.target_cost, interrupted or late, seconds)


def _write(args, problem, o: _Options, result, fallback, bar):
    """Write the result (the straight start if there is none yet), with signals held; returns
    (what was written, whether a signal came meanwhile)."""
    late = False
    for attempt in (1, 2):  # a first signal that lands between the search and this block: once more
        try:
            with signals_deferred(reraise=False) as got:  # a signal during the write waits for it
                if result is None:
                    result = (fallback or _straight(args, problem, o)).with_meta({"stopped": "interrupted"})
                if bar is not None:
                    bar.close(result)
                write_json_atomic(args.output, result.to_dict())
            return result, late or bool(got)
        except KeyboardInterrupt:
            late = True
    raise KeyboardInterrupt  # not reached: the second attempt holds every signal


def _first_report(r):
    """The straight start as the bar's first state (no trial yet)."""
    from nbst.search import SearchProgress

    return SearchProgress(trials=0, best_cost=r.cost, best_order=r.order, elapsed=0.0, population=0, phase="start")


def _summary(args, problem, r, target_cost: float | None, late: bool, seconds: float) -> int:
    """The summary line (and robust mode's line); the exit status. ``seconds``: the bar's, since the
    command began."""
    from nbst.search.api import ALGORITHM_STRAIGHT

    why = {"target_cost": ("cost at round-off level" if args.target_cost is None else f"cost <= {target_cost:g}"),
           "max_trials": "trial budget spent", "patience": f"no improvement in {args.patience} trials",
           "interrupted": "interrupted"}.get(r.stopped, str(r.stopped))
    if r.stopped == "patience" and r.many is not None:  # the many-body search: rounds, or --patience trials
        why = f"no better motion in {r.params['patience_rounds']} rounds (or in {args.patience} trials)"
    island = (f" (best of {len(r.islands)} islands: island {r.island}"
              + (f", {r.configuration}" if r.configuration is not None else "") + ")") if r.island is not None else ""
    shown = "in the file" if many_body(problem.n) else r.signature
    start = " (the straight start: no search result yet)" if r.algorithm == ALGORITHM_STRAIGHT else ""
    line = (f"cost {r.cost:.6g}, {r.order}/{problem.n} disks on target (signature {shown}){start} "
            f"after {count_text(r.trials)} trials in {seconds_text(seconds)}, seed {r.seed}"
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
