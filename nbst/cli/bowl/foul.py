"""``nbst bowl solve --foul-line/--robust`` and ``nbst bowl atlas --foul-line``: deliveries from the
foul line in a bowler's units (models/bowling/lane/atlas.py, robust.py, throwfile.py, folder.py).

:mod:`nbst.cli.bowl` owns the parsers of ``solve`` and ``atlas``; it adds the flags below to them and
hands a run over here when ``--foul-line`` or ``--robust`` is given. The 5 m deliveries are
:mod:`nbst.cli.bowl.deck`'s.

Exit codes as ``bowl solve``/``bowl atlas``: 0 done, 1 the request was not found within the
budget (the nearest throw is written), 2 bad input, 130 interrupted (the best throw so far,
or the atlas so far, is written).
"""
from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

from nbst.cli.args import Bounded
from nbst.cli.bowl.args import asked_text, bowler_flag, bowlers, err
from nbst.seeds import resolve_seed
from nbst import progress
from nbst.outputs import OutputError, prepare_output, signals_deferred, sigterm_as_interrupt, write_text_atomic
from nbst.parallel import default_jobs
from nbst.domain import plain

__all__ = ["SAMPLES", "ROBUST", "ROBUST_DEFAULT", "SOLVE_SAMPLES", "ATLAS_SAMPLES", "SOLVE_5M_ONLY",
           "ATLAS_5M_ONLY", "add_solve_flags", "add_atlas_flags", "shipped_elites", "cmd_solve", "robust_starts",
           "lane_scene", "cmd_atlas"]

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
                        f"paired noisy throws (models/bowling/lane/robust.py), FRAMES noisy frames (default "
                        f"{ROBUST_DEFAULT}), from the delivery found (and, for a strike, from the strike line and "
                        "the pocket map's best cell too); the pick is the latest that keeps its outcome at h = 1, "
                        "0.5 and 0.25 ms, if one does: the summary line and the file's ladder say which timesteps "
                        "the written throw keeps")
    g.add_argument("--require-robust", action="store_true",
                   help="exit 1 (the throw is still written) unless the written throw keeps its outcome at every "
                        "timestep of the ladder (h = 1, 0.5 and 0.25 ms)")
    g.add_argument("--samples", type=SAMPLES, default=SOLVE_SAMPLES, metavar="N",
                   help=f"noisy throws of the probability estimate (default {SOLVE_SAMPLES})")
    bowler_flag(g, "(with --foul-line) measure the probability and climb it")


def add_atlas_flags(a) -> None:
    g = a.add_argument_group("from the foul line")
    g.add_argument("--foul-line", action="store_true",
                   help="an atlas of bowlers' deliveries from the foul line (house oil, the default ball): "
                        "--max-rollouts settled frames of the MAP-Elites search over board, angle, mph, rpm, "
                        "rotation, tilt and hand, then the other hand's throw for each subset whose mirror image "
                        "is missing, then each subset's throw run --samples times under the release noise "
                        "(its probability), at h = 0.5 and 0.25 ms, and 2 s longer. Writes DIR/foul_atlas.json "
                        "(one throw per subset), DIR/summary.md, DIR/checks.json and DIR/archive.json (the "
                        "search, to resume). --from ATLAS.json starts from an atlas file: one of this lane scene "
                        "as it is; one of another scene (the file's \"scene\") by throwing each of its deliveries "
                        "once here, archived by what it knocks down here")
    g.add_argument("--samples", type=SAMPLES, default=ATLAS_SAMPLES, metavar="N",
                   help=f"--foul-line: noisy throws per subset's probability (default {ATLAS_SAMPLES})")
    g.add_argument("--bowler", default=None, choices=bowlers(),
                   help="--foul-line: each subset's probability under this bowler profile's correlated release "
                        "noise (its strike ball's: docs/bowling.md, \"Bowler profiles\") instead of the default "
                        "noise; the atlas file records the profile and the noise (the search is the same)")


def _refuse(args, flags, what: str, how: str) -> str | None:
    """The first 5 m-only flag of ``flags`` that ``args`` sets, as one line, or None."""
    for dest, flag in flags:
        if getattr(args, dest, None):
            return f"{flag} is for the 5 m {what}; it does not apply with {how}"
    return None


def shipped_elites() -> tuple[dict, bool]:
    """({mask: (7,) point}, whether it was grown on this nbst's lane scene) of the shipped foul-line
    atlas, read through the throw-file gate; ({}, False) with a one-line warning when it cannot be
    read. An atlas of this scene holds answers; one of another scene, starts of searches."""
    from nbst.models.bowling.lane import atlas as foul_atlas, throwfile
    from nbst.models.bowling.lane.folder import atlas_points

    try:
        a = throwfile.load_atlas(foul_atlas.SHIPPED)
    except (throwfile.ThrowFileError, OSError) as e:
        print(f"nbst bowl solve: warning: the shipped foul-line atlas is not used: {plain(str(e))}", file=sys.stderr)
        return {}, False
    return atlas_points(a)


def _delivery_text(d) -> str:
    return (f"board {d.foul_board():.1f} at the foul line, {d.angle:+.2f} deg, {d.mph:.1f} mph, {d.rpm:.0f} rpm, "
            f"rotation {d.rotation:.0f} deg, tilt {d.tilt:.0f} deg ({d.hand}-handed)")


def cmd_solve(args) -> int:
    """``bowl solve --foul-line|--robust``: the search (the shipped atlas's delivery, else children of
    its nearest subsets), then --robust's climb or the probability, then the ladder; one progress
    bar over every frame, its clock the command's; the summary quotes the bar's count and seconds."""
    import numpy as np

    from nbst.models.bowling import lane, pinfall, subsets
    from nbst.models.bowling.lane import advise, atlas as foul_atlas, frame, names, noise, robust, throwfile
    from nbst.models.mjsearch.ladder import kept_text

    bad = _refuse(args, SOLVE_5M_ONLY, "deliveries", "--foul-line/--robust")
    strike, nz = None, noise.DEFAULT
    if args.bowler is not None:
        from nbst.models.bowling.lane import profiles

        strike = profiles.profile(args.bowler).strike
        nz = profiles.profile(args.bowler).noise
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
    seed = resolve_seed(args.seed, what="--seed")
    jobs = args.jobs or default_jobs()
    elites, answers = ({}, False) if args.no_atlas else shipped_elites()
    direct = answers and target in elites  # the atlas of this scene holds it: its throw, no search
    asked = asked_text(want, args.leave is not None)
    ladder_frames = len(frame.LADDER) * (robust.LADDER_TRIES if args.robust is not None else 1)
    after = (args.robust if args.robust is not None else 0) + args.samples + ladder_frames + 1
    # the budget unless this scene's atlas holds the request: an atlas grown on another lane scene holds
    # starts, and when its throw misses here the search runs (foul_atlas.seek)
    bar = progress.Bar(f"bowl solve {asked}", (0 if direct else args.max_rollouts) + after, unit="frame",
                       bound=True, start=progress.command_start(), quiet=args.quiet)
    state: dict[str, Any] = {"point": None, "est": None, "ladder": None, "stage": "search", "frames": 0,
                             "from_atlas": False}
    arch = dict(elites)
    interrupted = False

    def on_batch(frames, dist):
        bar.set(frames)
        bar.note(f"searching: nearest {dist} pin{'s' if dist != 1 else ''} off")

    R = frame.FrameRunner(foul_atlas.OIL, jobs=jobs)
    try:
        with sigterm_as_interrupt():
            try:
                point, arch, frames = foul_atlas.seek(R, elites, target, budget=args.max_rollouts, seed=seed,
                                                      on_batch=on_batch, trusted=answers)
                state["frames"] = frames
                state["from_atlas"] = point is not None and target in elites and frames <= 1
                if point is None:
                    state["stage"] = "not found"
                else:
                    state["point"] = point
                    d = foul_atlas.delivery_of(point)
                    if args.robust is not None:
                        state["stage"] = "robust"
                        bar.note("--robust: climbing the probability")
                        res = robust.maximise(robust_starts(d, want, strike), want=want, runner=R, budget=args.robust,
                                              seed=seed, n=args.samples, on_done=bar.update, noise=nz)
                        bar.set(frames + res.frames)  # the ladder's frames ran in this process
                        state["robust"] = res
                        if R.one(res.delivery).down == want:
                            state["point"] = foul_atlas.point_of(res.delivery)
                            state["est"] = res.estimate
                            state["ladder"] = [{"timestep": h, "leave": lv} for h, lv, _ in res.ladder]
                        else:  # the most probable delivery seen misses without noise: keep the one that gives it
                            state["kept_start"] = True
                    if args.robust is None or state.get("kept_start"):
                        state["stage"] = "probability"
                        bar.note("the probability under the release noise")
                        est, _ = noise.probability(d, args.samples, seed, runner=R, want=want, on_done=bar.update,
                                                   noise=nz)
                        state["est"] = est
                        bar.note("the timestep ladder")
                        state["ladder"] = frame.ladder(d)
                        bar.update(len(state["ladder"]))
            except KeyboardInterrupt as e:
                interrupted = True
                if isinstance(e, robust.Interrupted):
                    state["point"] = foul_atlas.point_of(e.best)
        if state["point"] is None:  # not found (or interrupted before): the nearest subset's delivery
            masks = np.array(sorted(arch), dtype=np.int64)
            if not len(masks):
                bar.close(note="nothing reached the pins")
                print("nbst bowl solve: no throw reached the pins within the budget; nothing written", file=sys.stderr)
                return 130 if interrupted else 1
            near = int(masks[int(np.argmin(subsets.hamming(target, masks)))])
            state["point"] = arch[near]
        d = foul_atlas.delivery_of(state["point"])
        r = R.one(d)
        bar.update()
        doc = throwfile.throw_dict(r, oil=foul_atlas.OIL, requested=want, estimate=state["est"], want=want,
                                   ladder=state["ladder"])
        try:
            ln = advise.line_of(lane.throw(d, foul_atlas.OIL))
        except lane.LaneError:   # a ball that leaves the lane has no line to the pins
            ln = None
        doc.update(bowler=args.bowler, line=ln,
                   names=names.names(r.in_play, r.leave, r.board_at_pins, r.entry_angle_deg, d.hand),
                   note=advise.SAMPLE_NOTE)
        with signals_deferred(reraise=False) as late:
            write_text_atomic(Path(args.output), throwfile.dumps(doc))
    except BaseException:   # an error (one line from nbst.cli.main) ends the bar first
        bar.close()
        raise
    finally:
        R.close()
    got = ",".join(map(str, r.down)) or "none"
    bar.close(note=asked_text(r.down, True) if args.leave is not None else f"pins down {got}")
    line = (f"pins down {got}, leave {','.join(map(str, r.leave)) or 'none'} ({names.text(doc['names'])}); "
            f"from the foul line: {_delivery_text(d)}")
    if state["est"] is not None:
        est = state["est"]
        line += (f"; probability {est.text()} under the release noise"
                 + (f" of bowler {args.bowler}" if args.bowler else "") + f", seed {seed}")
    steps, kept = throwfile.ladder_kept(doc)
    if steps:
        line += f"; {kept_text(steps, kept)}"
    line += (f"; {progress.count_text(bar.n)} frame{'s' if bar.n != 1 else ''} in {progress.seconds_text(bar.seconds)}"
             f"; wrote {args.output}")
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
        print("nbst bowl solve: --robust found no delivery more probable that also gives the outcome without noise; "
              "the delivery found first is written", file=sys.stderr)
    if args.require_robust and (not steps or len(kept) < len(steps)):
        why = "" if steps else " (no ladder was run)"
        print(f"nbst bowl solve: --require-robust: the written throw does not keep its outcome at every "
              f"timestep{why}: {line}", file=sys.stderr)
        return 1
    if not args.quiet:
        how = " (the shipped foul-line atlas's throw)" if state["from_atlas"] else f" after {state['frames']} frames"
        rb = state.get("robust")
        if rb is not None:
            moved = "the start kept" if rb.delivery == rb.start or state.get("kept_start") else "a new release"
            how += (f", then --robust ({rb.frames} frames; on its {rb.screen.n} common noisy throws the start "
                    f"gave it {rb.start_screen.k} times, the pick {rb.screen.k}: {moved})")
        print(f"nbst bowl solve: found{how}: {line}", file=sys.stderr)
    return 0


def robust_starts(found, want, strike=None) -> list:
    """The starts of ``--robust``: the throw found (the atlas's or the search's), and for a strike
    (all ten down) also the strike line and the pocket map's best cell (``spares.STRIKE``,
    ``spares.POCKET_CELL``), which strike about 40 % under the default noise where a strike
    found in the atlas may be a knife edge. ``robust.maximise`` climbs from the best of them on
    its common noisy throws."""
    from nbst.models.bowling.lane import spares

    extra = [spares.STRIKE, spares.POCKET_CELL] + ([] if strike is None else [strike.check()])
    return [found] + (extra if len(want) == 10 else [])


def lane_scene() -> str:
    from nbst.models.bowling import lane

    return lane.SCENE


def cmd_atlas(args) -> int:
    """``bowl atlas --foul-line``: the search, the mirror step and each subset's measures of
    :class:`nbst.models.bowling.lane.folder.FoulAtlasRun`, with progress and Ctrl-C handling."""
    from nbst.models.bowling import files
    from nbst.models.bowling.lane.folder import FoulAtlasRun

    bad = _refuse(args, ATLAS_5M_ONLY, "atlas", "--foul-line")
    if bad:
        return err("atlas", bad)
    if args.method != "elites":
        return err("atlas", "--method: the foul-line atlas uses elites only")
    nz = None
    if args.bowler is not None:
        from nbst.models.bowling.lane import profiles

        nz = profiles.profile(args.bowler).noise
    out = prepare_output(args.out, directory=True, option="--out-dir")
    try:
        run = FoulAtlasRun(out, seed=args.seed if args.seed is not None else 1, jobs=args.jobs or default_jobs(),
                           from_atlas=args.from_atlas, bowler=args.bowler, **({} if nz is None else {"nz": nz}))
    except (OSError, files.BowlingFileError) as e:   # a file in the folder or --from's: one line naming it
        return err("atlas", str(e))
    interrupted = False
    bar: Any = None
    pb: Any = None

    def on_batch(frames, found) -> None:
        bar.set(frames)
        bar.note(f"{found} subsets")

    try:
        with sigterm_as_interrupt():
            try:
                if run.starts:  # an atlas of another lane scene: its deliveries thrown again here first
                    rb = progress.Bar(f"bowl atlas --foul-line: --from's {len(run.starts)} throws on {lane_scene()}",
                                      len(run.starts), unit="frame", start=progress.command_start(), quiet=args.quiet)
                    try:
                        run.rethrow(on_done=rb.update)
                    finally:
                        rb.close(note=f"{len(run.archive.elite)} subsets")
                bar = progress.Bar("bowl atlas --foul-line: search", args.max_rollouts, unit="frame", bound=True,
                                   start=progress.command_start(), quiet=args.quiet)
                run.grow(args.max_rollouts, on_batch=on_batch)
                bar.close(note=f"{len(run.archive.elite)} subsets")
                run.mirror()
                pb = progress.Bar("bowl atlas --foul-line: probabilities", len(run.todo()) * (args.samples + 4),
                                  unit="frame", start=progress.command_start(), quiet=args.quiet)

                def more(k) -> None:
                    pb.total += k * (args.samples + 4)

                run.measure(args.samples, on_done=pb.update, on_more=more)
            except KeyboardInterrupt:
                interrupted = True
        run.write_all()
    finally:
        if bar is not None:
            bar.close()
        if pb is not None:
            pb.close(note=f"{len(run.done)} subsets measured")
        run.close()
    last = pb if pb is not None else bar
    took = f" in {progress.seconds_text(last.seconds)}" if last is not None else ""
    msg = (f"{len(run.done)} subsets with their probability ({len(run.archive.elite)} found in "
           f"{run.archive.rollouts} frames searched{f', {progress.count_text(pb.n)} frames measuring them' if pb else ''}"
           f"){took}; wrote {run.atl}, {run.summ}")
    if interrupted:
        print(f"nbst bowl atlas: interrupted; what ran is written: {msg}", file=sys.stderr)
        return 130
    if not args.quiet:
        print(f"nbst bowl atlas: {msg}", file=sys.stderr)
    return 0
