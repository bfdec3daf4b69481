"""``nbst bowl solve`` and ``nbst bowl atlas``: the deck half, deliveries 5 m before the pins
(models/bowling/deck/). The parsers are :mod:`nbst.cli.bowl`'s; the work is the library's
(:mod:`nbst.models.bowling.deck.search`, :mod:`nbst.models.bowling.deck.folder`).

Progress: one bar per command, counting every rollout (the search's and the robustness
probes'), its clock the command's; a budget is a bound, so no ETA is shown for it; the summary
line quotes the bar's own count and seconds.
"""
from __future__ import annotations

import sys
from typing import Any

from nbst.cli.args import Bounded
from nbst.cli.bowl.args import asked_text, err
from nbst.seeds import resolve_seed
from nbst import progress
from nbst.outputs import prepare_output, signals_deferred, sigterm_as_interrupt
from nbst.parallel import default_jobs
from nbst.domain import plain

__all__ = ["SOLVE_ROLLOUTS", "ATLAS_ROLLOUTS", "PER_SUBSET", "runner_of", "cmd_solve", "cmd_atlas"]

#: Rollout budgets, capped at 1e7: 500x `bowl atlas`'s default budget; past it a typo (an
#: extra zero or ten) is likelier than a plan.
SOLVE_ROLLOUTS = Bounded("max-rollouts", 1, 10_000_000, integer=True)
ATLAS_ROLLOUTS = Bounded("max-rollouts", 0, 10_000_000, integer=True)
PER_SUBSET = Bounded("per-subset", 1, 10_000_000, integer=True)


def runner_of(args, jobs: int):
    """The rollout runner of a subcommand: K threads here, or a Dask cluster's workers
    (``--cluster``, through :func:`nbst.cluster.connect`: one line, within its timeout, when
    nothing answers there)."""
    from nbst.models.bowling import deck

    if getattr(args, "cluster", None):
        from nbst.models.bowling.deck.cluster import DeliveryClusterRunner

        return DeliveryClusterRunner(args.cluster)
    return deck.DeliveryRunner(jobs=jobs)


def cmd_solve(args) -> int:
    from nbst.models.bowling import pinfall
    from nbst.models.bowling.deck import folder, search

    target = args.down if args.down is not None else args.leave
    prepare_output(args.output)
    seed = resolve_seed(args.seed, what="--seed")
    jobs = args.jobs or default_jobs()
    want = pinfall.pins_of(target)
    archive: dict = {}
    if not args.no_atlas:
        archive, why = folder.shipped_archive()
        if why:
            print(f"nbst bowl solve: warning: the shipped atlas is not used: {plain(why)}", file=sys.stderr)
    L = runner_of(args, jobs)  # nbst.cluster.connect's InputError names --cluster and the address
    probes = 0 if args.no_robustness else search.ROBUSTNESS_ROLLOUTS[1]
    leave = args.leave is not None   # the bar names what was asked: the leave, or the pins down
    bar = progress.Bar(f"bowl solve {asked_text(want, leave)}", args.max_rollouts + probes, unit="rollout",
                       bound=True, start=progress.command_start(), quiet=args.quiet)

    def on_batch(p) -> None:
        bar.set(p.rollouts)
        near = asked_text(pinfall.pins_of(p.best_mask), leave)
        bar.note(f"nearest {near} ({p.best_hamming} off), {p.subsets} subsets seen")

    try:
        with sigterm_as_interrupt():
            res = search.solve(target, seed=seed, max_rollouts=args.max_rollouts, runner=L, callback=on_batch,
                               distance=args.distance, archive=archive or None)
        rob = None
        if not args.no_robustness and res.stopped != "interrupted":
            bar.note("robustness probes")
            try:
                with sigterm_as_interrupt():
                    rob = search.robustness(L, res.delivery, res.mask)
                bar.set(res.rollouts + rob["lateral_m_rollouts"] + rob["speed_m_s_rollouts"])
            except KeyboardInterrupt:
                res.stopped = "interrupted"
        where = {"cluster": args.cluster} if args.cluster else {"jobs": jobs}
        from_atlas = bool(archive) and res.mask == target and target in archive and res.rollouts == 1
        meta = {"seed": seed, "rollouts": res.rollouts, "restarts": res.restarts, **where,
                "max_rollouts": args.max_rollouts, "stopped": res.stopped, "wall_time_s": round(res.wall_time, 3),
                "subsets_seen": len(res.archive), "algorithm": "explore + CMA-ES restarts from nearest subsets",
                "distance": args.distance,
                "start": f"shipped atlas ({len(archive)} subsets)" if archive else "scratch",
                "from_atlas": from_atlas}
        if args.leave is not None:
            meta["leave"] = [n for n in range(1, 11) if not target >> (n - 1) & 1]
        with signals_deferred(reraise=False) as late:
            folder.write_throw(args.output, L.model, res.delivery, res.mask, requested=target, robustness=rob,
                               search=meta)
    except BaseException:
        bar.close()
        raise
    finally:
        L.close()
    got = ",".join(map(str, pinfall.pins_of(res.mask))) or "none"
    bar.close(note=asked_text(pinfall.pins_of(res.mask), True) if leave else f"pins down {got}")
    how = " (the shipped atlas's throw, confirmed)" if from_atlas else ""
    extra = f" ({res.rollouts} search, {bar.n - res.rollouts} robustness)" if bar.n != res.rollouts else ""
    line = (f"pins down {got} ({res.hamming} off the request) after {progress.count_text(bar.n)} "
            f"rollout{'s' if bar.n != 1 else ''}{extra}{how} in {progress.seconds_text(bar.seconds)}, seed {seed}; "
            f"wrote {args.output}")
    if res.stopped == "interrupted" or late:
        print(f"nbst bowl solve: interrupted; best so far written: {line}", file=sys.stderr)
        return 130
    if res.hamming:
        print(f"nbst bowl solve: not found within {args.max_rollouts} rollouts; nearest written: {line}",
              file=sys.stderr)
        return 1
    if not args.quiet:
        r = (f"; keeps the outcome within +/-{rob['lateral_m'] * 1000:.3g} mm sideways, "
             f"+/-{rob['speed_m_s'] * 1000:.3g} mm/s speed") if rob else ""
        print(f"nbst bowl solve: found: {line}{r}", file=sys.stderr)
    return 0


def cmd_atlas(args) -> int:
    from nbst.models.bowling import geometry
    from nbst.models.bowling.deck import folder, throwfile

    try:
        out = folder.prepare(args.out, args.from_atlas)
    except throwfile.ThrowFileError as e:
        return err("atlas", str(e))
    L = runner_of(args, args.jobs or default_jobs())  # nbst.cluster.connect's InputError names --cluster
    files, deliveries, skipped = folder.resume(out)
    for _, why in skipped:  # said, not silently dropped: the search finds the subset again if it can
        print(f"nbst bowl atlas: skipped {why} (the search finds its subset again if it can)", file=sys.stderr)
    bar: Any = None

    def on_progress(n, found) -> None:
        bar.set(n)
        bar.note(f"{found} subsets")

    run = folder.AtlasRun(L, out, files, deliveries, seed=args.seed, method=args.method,
                          robustness=not args.no_robustness, on_progress=on_progress)
    stopped = False
    try:
        todo = run.lacking_robustness() if args.robustness_only else None
        bar = progress.Bar("bowl atlas", len(todo) if todo is not None else args.max_rollouts,
                           unit="throw" if todo is not None else "rollout", bound=todo is None,
                           start=progress.command_start(), quiet=args.quiet)
        with sigterm_as_interrupt():
            if todo is not None:
                run.robustness_pass(todo)
            elif args.max_rollouts:
                run.search(args.max_rollouts, per_subset=args.per_subset)
    except KeyboardInterrupt:
        stopped = True
    finally:
        L.close()
        if bar is not None:
            bar.close(note=f"{len(run.arch)} subsets")
    n = folder.write_summaries(out, run, seconds=bar.seconds)
    print(f"nbst bowl atlas: {n} of {geometry.N_SUBSETS} subsets have a throw in {out} ({run.arch.rollouts} search "
          f"rollouts and {run.probes} robustness rollouts this run, {progress.seconds_text(bar.seconds)}"
          f"{', interrupted' if stopped else ''})", file=sys.stderr)
    return 130 if stopped else 0
