"""``nbst experiment``: cost curves (the paper's Figures 5/6), the ablation (Figures 7/8) and
comparisons over problem sets, with runs in parallel locally or on a Dask cluster.

Every finished run is kept as ``DIR/runs/<problem>/<entry>/t<trials>-s<seed>.json``; running
the same command again reuses them (only missing runs are run), so a crashed or
interrupted sweep resumes where it stopped, and commands share runs (the ablation's A runs
are the curves' A runs when seeds and budgets agree).
"""
from __future__ import annotations

import sys
from pathlib import Path

from nbst.cli.args import JOBS, MAX_TRIALS, RUNS_MAX, TARGET_COST, Bounded, cluster_client, with_limits
from nbst.cli.flags import add_jobs, add_out_dir, add_quiet, add_seed, old_spelling
from nbst.outputs import prepare_output
from nbst.problem import ProblemError, display_name, load_problem

__all__ = ["RUNS", "FIRST_SEED", "COMMANDS", "register", "cmd_curves", "ABLATION_COLUMNS", "cmd_ablation",
           "COMPARE_COLUMNS", "cmd_compare"]


def _entry_help() -> str:
    """The entries, from the registries: the signature search's variants and the other solvers."""
    from nbst.search.variants import VARIANTS
    from nbst.solvers import SOLVERS

    solvers = [e for e in SOLVERS.entries() if not e.value.variants]
    return ("comma-separated entries: the signature search's variants (" + VARIANTS.help_text() + "; 'signature' "
            "means nbst) and the other solvers (" + "; ".join(f"{e.name}: {e.help}" for e in solvers) + ")")


def _all_entries() -> str:
    from nbst.experiments.runs import entries

    return ",".join(entries())


RUNS = Bounded("runs", 1, RUNS_MAX, integer=True)
FIRST_SEED = Bounded("seed", 0, 2**62, integer=True)  # seed + k stays a valid seed (< 2^63)


def _common(p, *, runs: int, trials: int, entries: str) -> None:
    p.add_argument("--runs", type=RUNS, default=runs, metavar="R",
                   help=with_limits(f"runs per entry (and problem); run k uses seed SEED+k (default {runs})", RUNS))
    p.add_argument("--max-trials", dest="trials", type=MAX_TRIALS, default=trials, metavar="N",
                   help=with_limits(f"trial budget of each run (one trial = one simulation; default {trials})",
                                    MAX_TRIALS))
    old_spelling(p, "--trials", "--max-trials", dest="trials", type=MAX_TRIALS)
    p.add_argument("--algorithms", default=entries, metavar="LIST", help=f"{_entry_help()} (default {entries})")
    add_seed(p, type=FIRST_SEED, resumable=True, what=f"first seed; run k uses SEED+k [{FIRST_SEED.limits}]")
    add_out_dir(p, dest="out", default="nbst-experiments", old=("--out",),
                help="output folder: tables, figures and runs/ (default ./nbst-experiments)")
    add_jobs(p, dest="workers", type=JOBS, old=("--workers",),
             help=with_limits("local worker processes (default: all cores; 1 = in this process)", JOBS))
    p.add_argument("--cluster", default=None, metavar="ADDRESS",
                   help="run on a Dask distributed scheduler (e.g. tcp://head:8786) instead of local processes; "
                        "nbst must be installed on its workers")
    add_quiet(p, "no progress bar")
    p.add_argument("--json", action="store_true", help="print the summary rows as JSON instead of a table")


#: The top-level commands this module registers, with their help lines: ``nbst --help`` lists
#: them without building their arguments (nbst.cli.main builds only the command asked for).
COMMANDS = {
    "experiment": "curves, ablation and comparisons of the search and baselines",
}


def register(sub) -> None:
    p = sub.add_parser("experiment", help=COMMANDS["experiment"],
                       description="Run many independent searches and summarize them: best-so-far cost curves "
                                   "(the paper's Figures 5/6), the ablation of variants A-H plus nbst and the "
                                   "baselines (Figures 7/8), and success rates over problem sets. Finished runs "
                                   "are kept under DIR/runs and reused: rerun a command to resume it.",
                       epilog="Details and measured results: docs/experiments.md, docs/results/disks.md.")
    s = p.add_subparsers(dest="action", metavar="ACTION")
    c = s.add_parser("curves", help="best-so-far cost against trials (PNG, SVG, CSV)",
                     description="Best cost so far against trials for R runs of each entry (the paper's "
                                 "Figures 5 and 6: six runs of its search, entry A). Writes "
                                 "DIR/curves-PROBLEM.{csv,png,svg}.")
    c.add_argument("problem", help="built-in name or path to a problem JSON file")
    _common(c, runs=6, trials=200_000, entries="A")
    c.set_defaults(func=cmd_curves)
    a = s.add_parser("ablation", help="mean / best / worst final cost per variant and baseline",
                     description="Final cost (average, best and worst of R runs) of variants A-H, nbst's "
                                 "default search and each baseline (the paper's Figures 7 and 8: five runs of "
                                 "400,000 trials). Writes DIR/ablation-PROBLEM.{csv,md,png,svg}.")
    a.add_argument("problem", help="built-in name or path to a problem JSON file")
    _common(a, runs=5, trials=400_000, entries=_all_entries())
    a.set_defaults(func=cmd_ablation)
    m = s.add_parser("compare", help="success rate and trials to solve over a set of problems",
                     description="Success rate and trials to solve per entry over PROBLEMS (files, built-in "
                                 "names, or folders of *.json such as planted instances from `nbst generate`). "
                                 "A run is solved at its first trial with every disk within R (or, with "
                                 "--target-cost C, its first with cost <= C; runs then stop there). Writes "
                                 "DIR/compare-NAME.{csv,md} and DIR/compare-NAME-runs.csv.")
    m.add_argument("problems", nargs="+", help="problems: built-in names, JSON files or folders of them")
    _common(m, runs=1, trials=100_000, entries="nbst,A,cma,de,ga,random")
    m.add_argument("--target-cost", type=TARGET_COST, default=None, metavar="C",
                   help=with_limits("solved = cost <= C, and each run stops there (default: solved = order N, full "
                                    "budget)", TARGET_COST))
    m.add_argument("--name", default="compare", help="name of the output files (default compare)")
    m.set_defaults(func=cmd_compare)
    p.set_defaults(func=lambda args: _no_action(p))


def _no_action(p) -> int:
    p.print_help(sys.stderr)
    return 2


def _run(args, specs, desc: str):
    from nbst.experiments.runs import run_specs

    prepare_output(args.out, directory=True, option="--out-dir")
    client = cluster_client(args)
    try:
        # a signal (main's interrupt_once): workers stopped, finished runs kept, exit 130 as on Ctrl-C
        return run_specs(specs, args.out, workers=args.workers, cluster=client, progress=not args.quiet, desc=desc)
    finally:
        if client is not None:
            client.close()


def _emit(args, rows, table: str, files) -> None:
    if args.json:
        from nbst.cli.args import print_json

        print_json(rows)
    else:
        sys.stdout.write(table)
    if not args.quiet:
        print("nbst experiment: wrote " + ", ".join(str(f) for f in files), file=sys.stderr)


def cmd_curves(args) -> int:
    from nbst.experiments import plots as P
    from nbst.experiments.runs import _safe, curves_rows, make_specs, parse_entries

    problem = load_problem(args.problem)
    entries = parse_entries(args.algorithms)
    specs = make_specs([problem], entries, runs=args.runs, trials=args.trials, seed=args.seed)
    results = _run(args, specs, f"curves {problem.name}")
    rows = curves_rows(results)
    stem = Path(args.out) / f"curves-{_safe(problem.name)}"
    P.write_csv(stem.with_suffix(".csv"), rows, ["problem", "entry", "run", "seed", "trial", "best_cost", "order"])
    fig = P.plot_curves(rows, title=f"{display_name(problem.name)}: best cost so far, {args.runs} runs x {args.trials:,} trials")
    files = [stem.with_suffix(".csv"), *P.save_figure(fig, stem)]
    final = [{"entry": r["key"]["entry"], "seed": r["seed"], "cost": r["cost"], "order": r["order"],
              "trials": r["trials"], "first_full_order_trial": r.get("first_full_order_trial")} for r in results]
    table = P.markdown_table(final, [("entry", "entry"), ("seed", "seed"), ("cost", "final cost"),
                                     ("order", "order"), ("first_full_order_trial", "first trial with order N")])
    _emit(args, final, table, files)
    return 0


ABLATION_COLUMNS = [("entry", "entry"), ("runs", "runs"), ("mean", "mean"), ("best", "best"), ("worst", "worst"),
                    ("full_order", "runs reaching order N"), ("median_trials_per_s", "median trials/s")]


def cmd_ablation(args) -> int:
    from nbst.experiments import plots as P
    from nbst.experiments.runs import _safe, ablation_rows, make_specs, parse_entries

    problem = load_problem(args.problem)
    entries = parse_entries(args.algorithms)
    specs = make_specs([problem], entries, runs=args.runs, trials=args.trials, seed=args.seed)
    results = _run(args, specs, f"ablation {problem.name}")
    rows = ablation_rows(results, entries)
    stem = Path(args.out) / f"ablation-{_safe(problem.name)}"
    P.write_csv(stem.with_suffix(".csv"), rows, [k for k, _ in ABLATION_COLUMNS] + ["median_trials"])
    table = P.markdown_table(rows, ABLATION_COLUMNS)
    P.write_markdown(stem.with_suffix(".md"),
                     f"**{problem.name}**: final L2 cost of {args.runs} runs x {args.trials:,} trials "
                     f"(seeds {args.seed}..{args.seed + args.runs - 1})\n\n" + table)
    fig = P.plot_ablation(rows, title=f"{display_name(problem.name)}: final cost, {args.runs} runs x {args.trials:,} trials")
    files = [stem.with_suffix(".csv"), stem.with_suffix(".md"), *P.save_figure(fig, stem)]
    _emit(args, rows, table, files)
    return 0


COMPARE_COLUMNS = [("entry", "entry"), ("problems", "problems"), ("runs", "runs"), ("solved", "solved"),
                   ("success_rate", "success rate"), ("median_trials_to_solve", "median trials to solve"),
                   ("mean_trials_budget", "mean trials (failures = budget)"), ("median_cost", "median final cost"),
                   ("median_trials_per_s", "median trials/s")]


def _expand(problems: list[str]) -> list:
    out: list = []
    for p in problems:
        path = Path(p)
        if path.is_dir():
            files = sorted(path.glob("*.json"))
            if not files:
                raise ProblemError(p, "", "folder holds no *.json problem files")
            out.extend(load_problem(f) for f in files)
        else:
            out.append(load_problem(p))
    return out


def cmd_compare(args) -> int:
    from nbst.experiments import plots as P
    from nbst.experiments.runs import _safe, compare_detail_rows, compare_rows, make_specs, parse_entries

    problems = _expand(args.problems)
    entries = parse_entries(args.algorithms)
    specs = make_specs(problems, entries, runs=args.runs, trials=args.trials, seed=args.seed,
                       target_cost=args.target_cost)
    results = _run(args, specs, f"compare {len(problems)} problems")
    rows = compare_rows(results, entries, target_cost=args.target_cost)
    stem = Path(args.out) / f"compare-{_safe(args.name)}"
    P.write_csv(stem.with_suffix(".csv"), rows, [k for k, _ in COMPARE_COLUMNS] + ["mean_trials_to_solve"])
    runs_csv = stem.parent / f"{stem.name}-runs.csv"
    P.write_csv(runs_csv, compare_detail_rows(results, target_cost=args.target_cost),
                ["problem", "entry", "seed", "cost", "order", "n", "trials", "solved_at"])
    table = P.markdown_table(rows, COMPARE_COLUMNS)
    what = "cost <= %g" % args.target_cost if args.target_cost is not None else "every disk within R"
    P.write_markdown(stem.with_suffix(".md"),
                     f"{len(problems)} problems x {args.runs} runs x {args.trials:,} trials; solved = {what}\n\n"
                     + table)
    _emit(args, rows, table, [stem.with_suffix(".csv"), stem.with_suffix(".md"), runs_csv])
    return 0
