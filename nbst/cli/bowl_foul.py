"""``nbst bowl solve --foul-line/--robust`` and ``nbst bowl atlas --foul-line``: throws from the
foul line in a bowler's units (models/bowling/foul_atlas.py, robust.py, throwfile.py).

``bowl.py`` owns the parsers of ``solve`` and ``atlas``; it adds the flags below to them and
hands a run over here when ``--foul-line`` or ``--robust`` is given. The 5 m shots stay
``bowl.py``'s.

Exit codes as ``bowl solve``/``bowl atlas``: 0 done, 1 the request was not found within the
budget (the nearest throw is written), 2 bad input, 130 interrupted (the best throw so far,
or the atlas so far, is written).
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

from nbst.cli.args import Bounded

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
    g = s.add_argument_group("from the foul line (a bowler's throw: board, angle, mph, rpm, rotation, tilt)")
    g.add_argument("--foul-line", action="store_true",
                   help="find a bowler's throw from the foul line (house oil, the default ball), not a 5 m "
                        "launch: the shipped foul-line atlas's throw when it holds the request, else children of "
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
                   help="an atlas of bowlers' throws from the foul line (house oil, the default ball): "
                        "--max-rollouts settled frames of the MAP-Elites search over board, angle, mph, rpm, "
                        "rotation, tilt and hand, then the other hand's throw for each subset whose mirror image "
                        "is missing, then each subset's throw run --samples times under the release noise "
                        "(its probability), at h = 0.5 and 0.25 ms, and 2 s longer. Writes DIR/foul_atlas.json "
                        "(one throw per subset), DIR/summary.md, DIR/checks.json and DIR/archive.json (the "
                        "search, to resume)")
    g.add_argument("--samples", type=SAMPLES, default=ATLAS_SAMPLES, metavar="N",
                   help=f"--foul-line: noisy throws per subset's probability (default {ATLAS_SAMPLES})")


def err(cmd: str, msg: str) -> int:
    """One error line for ``nbst bowl CMD`` on stderr; the exit code 2 (every bowl subcommand)."""
    from nbst.domain import plain

    print(f"nbst bowl {cmd}: error: {plain(msg)}", file=sys.stderr)
    return 2



def _refuse(args, flags, what: str, how: str) -> str | None:
    """The first 5 m-only flag of ``flags`` that ``args`` sets, as one line, or None."""
    for dest, flag in flags:
        if getattr(args, dest, None):
            return f"{flag} is for the 5 m {what}; it does not apply with {how}"
    return None


def shipped_elites() -> dict:
    """{mask: (6,) point} of the shipped foul-line atlas, read through the throw-file gate;
    {} with a one-line warning when it cannot be read."""
    from nbst.models.bowling import foul_atlas, lane, shot, throwfile

    try:
        a = throwfile.load_atlas(foul_atlas.SHIPPED)
    except (throwfile.ThrowFileError, OSError) as e:
        from nbst.domain import plain

        print(f"nbst bowl solve: warning: the shipped foul-line atlas is not used: {plain(str(e))}", file=sys.stderr)
        return {}
    return {shot.mask_from_pins(t["outcome"]["down"]): foul_atlas.point_of(lane.Delivery(**t["delivery"]))
            for t in a["throws"] if t["standing"] == throwfile.FULL_RACK and t["outcome"]["down"]}


def _delivery_text(d) -> str:
    return (f"board {d.foul_board():.1f} at the foul line, {d.angle:+.2f} deg, {d.mph:.1f} mph, {d.rpm:.0f} rpm, "
            f"rotation {d.rotation:.0f} deg, tilt {d.tilt:.0f} deg ({d.hand}-handed)")


def cmd_solve(args) -> int:
    import numpy as np

    from nbst.outputs import OutputError, prepare_output, signals_deferred, sigterm_as_interrupt, write_text_atomic
    from nbst.parallel import default_jobs
    from nbst.progress import progress_bar

    from nbst.models.bowling import foul_atlas, frame, noise, robust, search, shot, throwfile

    bad = _refuse(args, SOLVE_5M_ONLY, "launches", "--foul-line/--robust")
    if bad is None and args.distance != "hamming":
        bad = "--distance is for the 5 m launches; it does not apply with --foul-line/--robust"
    if bad:
        return err("solve", bad)
    target = args.down if args.down is not None else args.leave
    want = shot.pins_of(target)
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
            near = int(masks[int(np.argmin(search.hamming(target, masks)))])
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
    from nbst.models.bowling import spares

    return [found] + ([spares.STRIKE, spares.POCKET_CELL] if len(want) == 10 else [])


#: Subsets whose probability, ladder and longer run are computed between two writes of the atlas.
CHUNK = 16


def atlas_summary(a: dict, extra: dict, archive) -> str:
    """DIR/summary.md of a foul-line atlas: subsets by size, probabilities, ladder and 2 s longer."""
    from nbst.models.bowling import atlas

    throws = a["throws"]
    ps = sorted((t["probability"]["p"] for t in throws if t["probability"]), reverse=True)
    lad = [t for t in throws if t["ladder"]]
    held = sum(all(x["leave"] == t["outcome"]["leave"] for x in t["ladder"]) for t in lad)
    longer = [v for v in extra.values() if "longer_leave" in v]
    same = sum(v["longer_same"] for v in longer)
    left = sum(t["delivery"]["hand"] == "left" for t in throws)
    lines = [f"# Foul-line atlas: {len(throws)} subsets", "",
             f"{archive.rollouts} settled frames searched (oil {a['oil']}, the default ball); "
             f"{len(throws) - left} right-handed throws, {left} left-handed.", "",
             "| pins down | subsets found | possible |", "|---|---|---|"]
    lines += [f"| {k} | {f} | {p} |" for k, f, p in atlas.size_table(
        [sum(1 << (n - 1) for n in t["outcome"]["down"]) for t in throws])]
    if ps:
        lines += ["", f"Probability of the subset under the release noise ({throws[0]['probability']['n']} throws "
                      f"each): median {100 * ps[len(ps) // 2]:.0f} %; at least 50 %: "
                      f"{sum(p >= 0.5 for p in ps)}; at least 90 %: {sum(p >= 0.9 for p in ps)}; "
                      f"none of the noisy throws: {sum(p == 0 for p in ps)}."]
    if lad:
        lines += [f"Timestep ladder (1, 0.5, 0.25 ms): {held} of {len(lad)} keep their subset."]
    if longer:
        lines += [f"2 s past the settle: {same} of {len(longer)} keep their subset."]
    got = sum(1 for v in extra.values() if v.get("harvested"))
    if got:
        lines += [f"{got} subsets were first knocked down by a noisy throw of another subset's probability "
                  "estimate (that throw is their elite)."]
    return "\n".join(lines) + "\n"


def cmd_atlas(args) -> int:
    import json

    from nbst.outputs import OutputError, prepare_output, signals_deferred, sigterm_as_interrupt, write_text_atomic
    from nbst.parallel import default_jobs
    from nbst.progress import progress_bar

    from nbst.models.bowling import atlas, foul_atlas, frame, lane, noise, shot, shotfile, throwfile

    bad = _refuse(args, ATLAS_5M_ONLY, "atlas", "--foul-line")
    if bad:
        return err("atlas", bad)
    if args.method != "elites":
        return err("atlas", "--method: the foul-line atlas uses elites only")
    try:
        out = prepare_output(args.out, directory=True, option="--out-dir")
    except OutputError as e:
        return err("atlas", str(e))
    ckpt, atl, summ = out / "archive.json", out / "foul_atlas.json", out / "summary.md"
    seed = args.seed if args.seed is not None else 1
    try:
        if ckpt.exists():
            archive = foul_atlas.archive_from_doc(shotfile.read_doc(ckpt), ckpt)
        elif args.from_atlas:
            old = throwfile.load_atlas(args.from_atlas)
            archive = atlas.Archive.from_launches({shot.mask_from_pins(t["outcome"]["down"]): foul_atlas.point_of(
                lane.Delivery(**t["delivery"])) for t in old["throws"] if t["outcome"]["down"]})
        else:
            archive = atlas.Archive()
        done = {}
        if atl.exists():
            for t in throwfile.load_atlas(atl)["throws"]:
                done[shot.mask_from_pins(t["outcome"]["down"])] = t
    except (ValueError, OSError, shotfile.ShotFileError) as e:
        return err("atlas", str(e))
    extra_path = out / "checks.json"
    extra = {}
    if extra_path.exists():
        try:
            raw = shotfile.read_doc(extra_path)
            extra = {int(k): v for k, v in raw.items() if str(k).isdigit() and isinstance(v, dict)}
        except (ValueError, shotfile.ShotFileError):
            extra = {}
    jobs = args.jobs or default_jobs()
    nz = noise.DEFAULT
    interrupted = False

    def write_all() -> None:
        throws = [done[m] for m in sorted(done)]
        a = throwfile.atlas_dict(throws, oil=foul_atlas.OIL, noise=nz)
        with signals_deferred(reraise=False):
            write_text_atomic(ckpt, json.dumps(foul_atlas.archive_doc(archive, seed)) + "\n", option="--out-dir")
            write_text_atomic(atl, throwfile.dumps(a), option="--out-dir")
            write_text_atomic(extra_path, json.dumps({str(k): v for k, v in sorted(extra.items())}, indent=1) + "\n",
                              option="--out-dir")
            write_text_atomic(summ, atlas_summary(a, extra, archive), option="--out-dir")

    R = frame.FrameRunner(foul_atlas.OIL, jobs=jobs)
    R05 = frame.FrameRunner(foul_atlas.OIL, jobs=jobs, timestep=frame.LADDER[1])
    R025 = frame.FrameRunner(foul_atlas.OIL, jobs=jobs, timestep=frame.LADDER[2])
    bar = progress_bar(total=args.max_rollouts, desc="foul-line atlas", unit="frame", disable=args.quiet,
                       file=sys.stderr)
    last = [time.monotonic()]

    def on_batch(a, new) -> None:
        bar.update(min(args.max_rollouts, a.rollouts - start) - bar.n)
        bar.set_postfix_str(f"{len(a.elite)} subsets", refresh=False)
        if time.monotonic() - last[0] > 30:  # a checkpoint every 30 s
            write_text_atomic(ckpt, json.dumps(foul_atlas.archive_doc(a, seed)) + "\n", option="--out-dir")
            last[0] = time.monotonic()

    start = archive.rollouts
    try:
        with sigterm_as_interrupt():
            try:
                foul_atlas.grow(R, archive, budget=args.max_rollouts, seed=seed, on_batch=on_batch)
                bar.close()
                foul_atlas.mirror_step(R, archive)  # the other hand's throw of each unmirrored subset
                todo = [m for m in sorted(archive.elite) if m not in done]
                pb = progress_bar(total=len(todo) * (args.samples + 4), desc="probabilities", unit="frame",
                                  disable=args.quiet, file=sys.stderr)
                skip: set = set()
                while True:
                    todo = [m for m in sorted(archive.elite) if m not in done and m not in skip]
                    if not todo:
                        break
                    part = todo[:CHUNK]
                    ds = [foul_atlas.delivery_of(archive.elite[m]) for m in part]
                    est, thr, res = foul_atlas.probabilities(R, {m: archive.elite[m] for m in part}, n=args.samples,
                                                             seed=seed, nz=nz, on_done=lambda: pb.update(1),
                                                             frames=True)
                    new = foul_atlas.harvest(archive, thr, res)  # subsets the noisy throws found
                    for m in new:
                        extra[m] = {"harvested": True}
                    if new:
                        pb.total += len(new) * (args.samples + 4)
                    r1 = R.map(ds)
                    r2, r4 = R05.map(ds), R025.map(ds)
                    rl = R.map(ds, extra_s=2.0)
                    pb.update(4 * len(part))
                    for j, m in enumerate(part):
                        if shot.mask_from_pins(r1[j].down) != m:  # cannot happen: a frame is deterministic
                            skip.add(m)
                            continue
                        done[m] = throwfile.throw_dict(r1[j], oil=foul_atlas.OIL, requested=shot.pins_of(m),
                                                       estimate=est[m], want=shot.pins_of(m),
                                                       ladder=[r1[j], r2[j], r4[j]])
                        extra[m] = {**extra.get(m, {}), "longer_leave": rl[j].leave,
                                    "longer_same": rl[j].leave == r1[j].leave}
                    write_all()
                pb.close()
            except KeyboardInterrupt:
                interrupted = True
        write_all()
    except (OutputError, ValueError) as e:
        return err("atlas", str(e))
    finally:
        bar.close()
        for r in (R, R05, R025):
            r.close()
    msg = (f"{len(done)} subsets with their probability ({len(archive.elite)} found in {archive.rollouts} frames); "
           f"wrote {atl}, {summ}")
    if interrupted:
        print(f"nbst bowl atlas: interrupted; what ran is written: {msg}", file=sys.stderr)
        return 130
    if not args.quiet:
        print(f"nbst bowl atlas: {msg}", file=sys.stderr)
    return 0
