"""``nbst bowl solve --foul-line/--robust`` and ``nbst bowl atlas --foul-line``: deliveries from the
foul line in a bowler's units (models/bowling/lane/atlas.py, robust.py, throwfile.py, folder.py).

``bowl.py`` owns the parsers of ``solve`` and ``atlas``; it adds the flags below to them and
hands a run over here when ``--foul-line`` or ``--robust`` is given. The 5 m deliveries are
``bowl_deck.py``'s.

Exit codes as ``bowl solve``/``bowl atlas``: 0 done, 1 the request was not found within the
budget (the nearest throw is written), 2 bad input, 130 interrupted (the best throw so far,
or the atlas so far, is written).
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

from nbst.cli.args import Bounded
from nbst.cli.bowl_args import err

#: Frames of the fresh probability estimate (``--samples``) and of ``--robust``'s search.
SAMPLES = Bounded("samples", 1, 100_000, integer=True)
ROBUST = Bounded("robust", 1, 1_000_000, integer=True)
ROBUST_DEFAULT = 600
SOLVE_SAMPLES = 40
ATLAS_SAMPLES = 24
#: The flags of the 5 m search and atlas that a foul-line run refuses (they mean nothing there).
SOLVE_5M_ONLY = (("cluster", "--cluster"), ("no_robustness", "--no-robustness"))
ATLAS_5M_ONLY = (("cluster", "--cluster"), ("robustness_only", "--robustness-only"), ("no_robustness", "--no-robustness"))


def add_solve_flags(s) -> None:
    g = s.add_argument_group("from the foul line (a bowler's delivery: board, angle, mph, rpm, rotation, tilt)")
    g.add_argument("--foul-line", action="store_true",
                   help="find a bowler's delivery from the foul line (house oil, the default ball), not a 5 m "
                        "one: the shipped foul-line atlas's throw when it holds the request, else children of "
                        "its nearest subsets (--max-rollouts frames); the throw file carries the probability of the "
                        "outcome under the release noise (--samples throws) and the timestep ladder")
    g.add_argument("--robust", type=ROBUST, nargs="?", const=ROBUST_DEFAULT, default=None, metavar="FRAMES",
                   help="(implies --foul-line) then maximise that probability: a local search over the release on "
                        f"paired noisy throws (models/bowling/robust.py), FRAMES noisy frames (default "
                        f"{ROBUST_DEFAULT}), from the throw found (and, for a strike, from the strike line and "
                        "the pocket map's best cell too); the pick keeps its outcome at h = 1, 0.5 and 0.25 ms")
    g.add_argument("--samples", type=SAMPLES, default=SOLVE_SAMPLES, metavar="N",
                   help=f"noisy throws of the probability estimate (default {SOLVE_SAMPLES})")


def add_atlas_flags(a) -> None:
    g = a.add_argument_group("from the foul line")
    g.add_argument("--foul-line", action="store_true",
                   help="an atlas of bowlers' deliveries from the foul line (house oil, the default ball): "
                        "--max-rollouts settled frames of the MAP-Elites search over board, angle, mph, rpm, "
                        "rotation, tilt and hand, then the other hand's throw for each subset whose mirror image "
                        "is missing, then each subset's throw run --samples times under the release noise "
                        "(its probability), at h = 0.5 and 0.25 ms, and 2 s longer. Writes DIR/foul_atlas.json "
                        "(one throw per subset), DIR/summary.md, DIR/checks.json and DIR/archive.json (the "
                        "search, to resume)")
    g.add_argument("--samples", type=SAMPLES, default=ATLAS_SAMPLES, metavar="N",
                   help=f"--foul-line: noisy throws per subset's probability (default {ATLAS_SAMPLES})")


def _refuse(args, flags, what: str, how: str) -> str | None:
    """The first 5 m-only flag of ``flags`` that ``args`` sets, as one line, or None."""
    for dest, flag in flags:
        if getattr(args, dest, None):
            return f"{flag} is for the 5 m {what}; it does not apply with {how}"
    return None


def shipped_elites() -> dict:
    """{mask: (6,) point} of the shipped foul-line atlas, read through the throw-file gate;
    {} with a one-line warning when it cannot be read."""
    from nbst.models.bowling import lane, pinfall
    from nbst.models.bowling.lane import atlas as foul_atlas, throwfile

    try:
        a = throwfile.load_atlas(foul_atlas.SHIPPED)
    except (throwfile.ThrowFileError, OSError) as e:
        from nbst.domain import plain

        print(f"nbst bowl solve: warning: the shipped foul-line atlas is not used: {plain(str(e))}", file=sys.stderr)
        return {}
    return {pinfall.mask_from_pins(t["outcome"]["down"]): foul_atlas.point_of(lane.Delivery(**t["delivery"]))
            for t in a["throws"] if t["standing"] == throwfile.FULL_RACK and t["outcome"]["down"]}


def _delivery_text(d) -> str:
    return (f"board {d.foul_board():.1f} at the foul line, {d.angle:+.2f} deg, {d.mph:.1f} mph, {d.rpm:.0f} rpm, "
            f"rotation {d.rotation:.0f} deg, tilt {d.tilt:.0f} deg ({d.hand}-handed)")


def cmd_solve(args) -> int:
    import numpy as np

    from nbst.outputs import OutputError, prepare_output, signals_deferred, sigterm_as_interrupt, write_text_atomic
    from nbst.parallel import default_jobs
    from nbst.progress import progress_bar

    from nbst.models.bowling import pinfall, subsets
    from nbst.models.bowling.lane import atlas as foul_atlas, frame, noise, robust, throwfile

    bad = _refuse(args, SOLVE_5M_ONLY, "deliveries", "--foul-line/--robust")
    if bad is None and args.distance != "hamming":
        bad = "--distance is for the 5 m deliveries; it does not apply with --foul-line/--robust"
    if bad:
        return err("solve", bad)
    target = args.down if args.down is not None else args.leave
    want = pinfall.pins_of(target)
    try:
        prepare_output(args.output)
    except OutputError as e:
        return err("solve", str(e))
    seed = args.seed if args.seed is not None else int(np.random.SeedSequence().entropy % (2**31))
    jobs = args.jobs or default_jobs()
    elites = {} if args.no_atlas else shipped_elites()
    t0 = time.perf_counter()
    asked = (f"leave {','.join(str(n) for n in range(1, 11) if n not in want) or 'none'}" if args.leave is not None
             else f"down {','.join(map(str, want))}")
    bar = progress_bar(total=args.max_rollouts, desc=f"bowl {asked}", unit="frame",
                       disable=args.quiet or target in elites, file=sys.stderr)
    state = {"point": None, "est": None, "ladder": None, "stage": "search", "frames": 0, "from_atlas": target in elites}
    arch = dict(elites)
    interrupted = False

    def on_batch(frames, dist):
        bar.update(frames - bar.n)
        bar.set_postfix_str(f"nearest {dist} pin{'s' if dist != 1 else ''} off", refresh=False)

    R = frame.FrameRunner(foul_atlas.OIL, jobs=jobs)
    try:
        with sigterm_as_interrupt():
            try:
                point, arch, frames = foul_atlas.seek(R, elites, target, budget=args.max_rollouts, seed=seed,
                                                      on_batch=on_batch)
                state["frames"] = frames
                bar.close()
                if point is None:
                    state["stage"] = "not found"
                else:
                    state["point"] = point
                    d = foul_atlas.delivery_of(point)
                    if args.robust is not None:
                        state["stage"] = "robust"
                        rb = progress_bar(total=args.robust + args.samples, desc="robust", unit="frame",
                                          disable=args.quiet, file=sys.stderr)
                        res = robust.maximise(robust_starts(d, want), want=want, runner=R, budget=args.robust,
                                              seed=seed, n=args.samples, on_done=lambda: rb.update(1))
                        rb.close()
                        state["robust"] = res
                        if R.one(res.delivery).down == want:
                            state["point"] = foul_atlas.point_of(res.delivery)
                            state["est"] = res.estimate
                            state["ladder"] = [{"timestep": h, "leave": lv} for h, lv, _ in res.ladder]
                        else:  # the most probable throw seen misses without noise: keep the one that gives it
                            state["kept_start"] = True
                    if args.robust is None or state.get("kept_start"):
                        state["stage"] = "probability"
                        pb = progress_bar(total=args.samples, desc="probability", unit="frame", disable=args.quiet,
                                          file=sys.stderr)
                        est, _ = noise.probability(d, args.samples, seed, runner=R, want=want,
                                                   on_done=lambda: pb.update(1))
                        pb.close()
                        state["est"] = est
                        state["ladder"] = frame.ladder(d)
            except KeyboardInterrupt as e:
                interrupted = True
                if isinstance(e, robust.Interrupted):
                    state["point"] = foul_atlas.point_of(e.best)
        if state["point"] is None:  # not found (or interrupted before): the nearest subset's throw
            masks = np.array(sorted(arch), dtype=np.int64)
            if not len(masks):
                print("nbst bowl solve: no throw reached the pins within the budget; nothing written", file=sys.stderr)
                return 130 if interrupted else 1
            near = int(masks[int(np.argmin(subsets.hamming(target, masks)))])
            state["point"] = arch[near]
        d = foul_atlas.delivery_of(state["point"])
        r = R.one(d)
        with signals_deferred(reraise=False) as late:
            write_text_atomic(Path(args.output), throwfile.dumps(throwfile.throw_dict(
                r, oil=foul_atlas.OIL, requested=want, estimate=state["est"], want=want, ladder=state["ladder"])))
    except (OutputError, ValueError) as e:
        return err("solve", str(e))
    finally:
        bar.close()
        R.close()
    got = ",".join(map(str, r.down)) or "none"
    line = (f"pins down {got}, leave {','.join(map(str, r.leave)) or 'none'}; from the foul line: {_delivery_text(d)}")
    if state["est"] is not None:
        e = state["est"]
        line += f"; probability {e.text()} under the release noise, seed {seed}"
    if state["ladder"]:
        lv = [x.leave if hasattr(x, "leave") else x["leave"] for x in state["ladder"]]
        line += "; the same at h = 1, 0.5, 0.25 ms" if all(v == r.leave for v in lv) else "; CHANGES with the timestep"
    line += f"; {time.perf_counter() - t0:.1f} s; wrote {args.output}"
    if interrupted or late:
        print(f"nbst bowl solve: interrupted; best so far written: {line}", file=sys.stderr)
        return 130
    if state["stage"] == "not found":
        print(f"nbst bowl solve: not found within {args.max_rollouts} frames; nearest written: {line}", file=sys.stderr)
        return 1
    if r.down != want:
        print(f"nbst bowl solve: the most probable throw found misses without noise: {line}", file=sys.stderr)
        return 1
    if state.get("kept_start"):
        print("nbst bowl solve: --robust found no throw more probable that also gives the outcome without noise; "
              "the throw found first is written", file=sys.stderr)
    if not args.quiet:
        how = " (the shipped foul-line atlas's throw)" if state["from_atlas"] else f" after {state['frames']} frames"
        rb = state.get("robust")
        if rb is not None:
            moved = "the start kept" if rb.delivery == rb.start or state.get("kept_start") else "a new release"
            how += (f", then --robust ({rb.frames} frames; on its {rb.screen.n} common noisy throws the start "
                    f"gave it {rb.start_screen.k} times, the pick {rb.screen.k}: {moved})")
        print(f"nbst bowl solve: found{how}: {line}", file=sys.stderr)
    return 0


def robust_starts(found, want) -> list:
    """The starts of ``--robust``: the throw found (the atlas's or the search's), and for a strike
    (all ten down) also the strike line and the pocket map's best cell (``spares.STRIKE``,
    ``spares.POCKET_CELL``), which strike about 40 % under the default noise where a strike
    found in the atlas may be a knife edge. ``robust.maximise`` climbs from the best of them on
    its common noisy throws."""
    from nbst.models.bowling.lane import spares

    return [found] + ([spares.STRIKE, spares.POCKET_CELL] if len(want) == 10 else [])


def cmd_atlas(args) -> int:
    """``bowl atlas --foul-line``: the search, the mirror step and each subset's measures of
    :class:`nbst.models.bowling.lane.folder.FoulAtlasRun`, with progress and Ctrl-C handling."""
    from nbst.outputs import OutputError, prepare_output, sigterm_as_interrupt
    from nbst.parallel import default_jobs
    from nbst.progress import progress_bar

    from nbst.models.bowling import files
    from nbst.models.bowling.lane.folder import FoulAtlasRun

    bad = _refuse(args, ATLAS_5M_ONLY, "atlas", "--foul-line")
    if bad:
        return err("atlas", bad)
    if args.method != "elites":
        return err("atlas", "--method: the foul-line atlas uses elites only")
    try:
        out = prepare_output(args.out, directory=True, option="--out-dir")
        run = FoulAtlasRun(out, seed=args.seed if args.seed is not None else 1, jobs=args.jobs or default_jobs(),
                           from_atlas=args.from_atlas)
    except (OutputError, ValueError, OSError, files.BowlingFileError) as e:
        return err("atlas", str(e))
    interrupted = False
    bar = progress_bar(total=args.max_rollouts, desc="foul-line atlas", unit="frame", disable=args.quiet,
                       file=sys.stderr)

    def on_batch(frames, found) -> None:
        bar.update(frames - bar.n)
        bar.set_postfix_str(f"{found} subsets", refresh=False)

    try:
        with sigterm_as_interrupt():
            try:
                run.grow(args.max_rollouts, on_batch=on_batch)
                bar.close()
                run.mirror()
                pb = progress_bar(total=len(run.todo()) * (args.samples + 4), desc="probabilities", unit="frame",
                                  disable=args.quiet, file=sys.stderr)

                def more(k) -> None:
                    pb.total += k * (args.samples + 4)

                run.measure(args.samples, on_done=lambda: pb.update(1), on_more=more)
                pb.close()
            except KeyboardInterrupt:
                interrupted = True
        run.write_all()
    except (OutputError, ValueError) as e:
        return err("atlas", str(e))
    finally:
        bar.close()
        run.close()
    msg = (f"{len(run.done)} subsets with their probability ({len(run.archive.elite)} found in "
           f"{run.archive.rollouts} frames); wrote {run.atl}, {run.summ}")
    if interrupted:
        print(f"nbst bowl atlas: interrupted; what ran is written: {msg}", file=sys.stderr)
        return 130
    if not args.quiet:
        print(f"nbst bowl atlas: {msg}", file=sys.stderr)
    return 0
