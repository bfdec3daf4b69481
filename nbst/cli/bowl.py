"""Subcommands ``nbst bowl solve``, ``nbst bowl replay``, ``nbst bowl atlas`` and ``nbst bowl throw``;
``nbst bowl frame``, ``spares`` and ``pocket`` (frames from the foul line, at the end of the file).

Registration is light: mujoco and cma are imported inside the commands.

Exit codes: 0 done (solve: the requested pins exactly; replay: the file's pins; atlas:
finished), 1 a check failed (solve: the request was not found within the budget and
the nearest shot was written; replay: the pins down differ from the file's ``down``),
2 bad input, 130 interrupted (solve: the best shot so far is written; atlas: the shots
found so far, the summary and atlas.json are written).

Length: ~950 lines, past the house's ~500: the three search subcommands share the launcher, the
shot writer and the atlas reader; split by subcommand, each would import the others (``throw``,
~95 lines, shares the error line and the command group; frame/spares/pocket, ~280 lines, share
the pin-list parser, the error line and the delivery conventions of ``throw``).
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from nbst.cli import bowl_foul
from nbst.cli.args import JOBS, SEED, Bounded, with_limits
from nbst.cli.flags import add_out_dir, add_seed
from nbst.parallel import default_jobs


def _pin_list(text: str, flag: str) -> int:
    """Pin numbers "1,2,4,7" -> 10-bit mask (bit n-1 = pin n)."""
    try:
        pins = [int(p) for p in text.strip().replace(" ", "").split(",") if p]
    except ValueError:
        raise argparse.ArgumentTypeError(f"{flag}: pins must be numbers 1..10 separated by commas (e.g. 1,2,4,7), "
                                         f"got {text!r}") from None
    bad = [p for p in pins if not 1 <= p <= 10]
    if bad or not pins:
        raise argparse.ArgumentTypeError(f"{flag}: pins must be numbers 1..10 (at least one), got {text!r}")
    return sum(1 << (p - 1) for p in set(pins))


def _pins(text: str) -> int:
    """``--down``: pin numbers "1,2,4,7" (or "strike"/"all") -> 10-bit mask of the pins down."""
    from nbst.models.bowling.geometry import ALL_DOWN

    if text.strip().lower() in ("strike", "all"):
        return ALL_DOWN
    return _pin_list(text, "--down")


def _leave(text: str) -> int:
    """``--leave``: the pins left standing, as bowlers name a leave ("7,10" is the 7-10 split;
    "none" is a strike) -> 10-bit mask of the pins DOWN (every other pin)."""
    from nbst.models.bowling.geometry import ALL_DOWN

    if text.strip().lower() in ("none", "strike"):
        return ALL_DOWN
    down = ALL_DOWN & ~_pin_list(text, "--leave")
    if not down:
        raise argparse.ArgumentTypeError("--leave: all ten pins standing is a gutter ball (any throw into the "
                                         "gutter); name at most 9 pins")
    return down


#: How many launches ``search.robustness`` spends (2 axes; per axis 4 at the largest change and,
#: when that fails, 10 bisection rounds of 4): stated in --help, measured in each shot's file.
#: Launch budgets, capped at 1e7: 500x `bowl atlas`'s default budget; past it a typo (an
#: extra zero or ten) is likelier than a plan.
SOLVE_ROLLOUTS = Bounded("max-rollouts", 1, 10_000_000, integer=True)
ATLAS_ROLLOUTS = Bounded("max-rollouts", 0, 10_000_000, integer=True)
PER_SUBSET = Bounded("per-subset", 1, 10_000_000, integer=True)

ROBUSTNESS_ROLLOUTS = (2 * 4, 2 * (4 + 10 * 4))


def register(sub) -> None:
    p = sub.add_parser("bowl", help="10-pin bowling in MuJoCo: find a throw that knocks down given pins",
                       description="Ten-pin bowling, synthesized on MuJoCo rollouts (docs/bowling.md): a USBC "
                                   "lane with oil, pins and a 15 lb ball; a throw is lateral position, speed, "
                                   "angle and spin, clamped to what a bowler can throw.")
    bowl = p.add_subparsers(dest="bowl_command", metavar="SUBCOMMAND", parser_class=type(p))
    p.set_defaults(func=lambda args: (p.print_help(sys.stderr), 2)[1])

    s = bowl.add_parser("solve", help="search for a throw that knocks down exactly the given pins",
                        description="Search the launch space (uniform exploration, then CMA-ES restarts from "
                                    "the throws whose pins-down sets are nearest the request) with mujoco.rollout "
                                    "on --jobs threads, and write the shot: JSON plus the scene XML beside it "
                                    "(replayable with plain mujoco). Ctrl-C writes the best shot so far (exit 130). "
                                    "The same --seed gives the same shot, for any --jobs.",
                        epilog="Example: nbst bowl solve --leave 7,10 -o split.json --seed 1   (the 7-10 split; "
                               "the shipped atlas holds it). Exit 0: found; 1: not found within --max-rollouts (the nearest shot is written "
                               "and its pins named); 2: bad input; 130: interrupted.")
    want = s.add_mutually_exclusive_group(required=True)
    want.add_argument("--down", type=_pins, metavar="PINS",
                      help="pins to knock down, e.g. 1,2,4,7 (USBC numbers: 1 in front, 7 back left, 10 back "
                           "right); 'strike' = all ten")
    want.add_argument("--leave", type=_leave, metavar="PINS",
                      help="pins to leave standing, as bowlers name a leave: --leave 7,10 is the 7-10 split "
                           "(every other pin down); 'none' = a strike")
    s.add_argument("-o", "--output", required=True, metavar="SHOT.json", help="where to write the shot")
    add_seed(s, type=SEED, resumable=False)
    s.add_argument("--max-rollouts", type=SOLVE_ROLLOUTS, default=3000, metavar="N",
                   help=with_limits("launch budget (default 3000)", SOLVE_ROLLOUTS))
    _runner_args(s, "the same shot as --jobs for the same seed")
    s.add_argument("--distance", choices=("hamming", "geometry"), default="hamming",
                   help="distance between subsets that ranks restart points: hamming (pins that differ; "
                        "default) or geometry (an extra pin down next to a wanted one counts 1/2)")
    s.add_argument("--no-robustness", action="store_true",
                   help="skip the robustness probes after the search (%d to %d more launches: on each of 2 axes, "
                        "4 at the largest change, then 10 bisection rounds of 4 if that fails; the shot file "
                        "records how many ran)" % ROBUSTNESS_ROLLOUTS)
    s.add_argument("--no-atlas", action="store_true",
                   help="search from scratch; by default the search starts from the shipped atlas's shots "
                        "(models/bowling/atlas.json, one throw for each of 328 subsets): a request it holds "
                        "is confirmed with one launch, others restart from its nearest subsets")
    s.add_argument("-q", "--quiet", action="store_true", help="no progress bar and no summary line")
    bowl_foul.add_solve_flags(s)
    s.set_defaults(func=cmd_solve)

    r = bowl.add_parser("replay", help="replay a shot or throw file and check its pins down",
                        description="Replay FILE and print the pins down; exit 1 if they differ from the file's. "
                                    "A 5 m shot file (bowl solve) replays from its scene XML with plain MuJoCo "
                                    "(fresh MjData, qpos0 and qvel0 set, mj_step for duration) against its `down`; "
                                    "a throw file (bowl frame -o) replays its delivery from the foul line, on its "
                                    "oil, ball and pins standing at its timestep, against its outcome's `down`.")
    r.add_argument("shot", metavar="FILE", help="a shot file (SHOT.json) or a throw file (THROW.json)")
    r.add_argument("--json", action="store_true", help="print one JSON object: down, expected, match")
    _picture_flags(r, "the throw file's frame, its readout with the pins asked for, the pins down and the file's "
                      "probability (throw files only: `nbst render SHOT.json` films a 5 m shot)")
    r.set_defaults(func=cmd_replay)

    a = bowl.add_parser("atlas", help="try for every one of the 1,023 non-empty subsets; one shot per subset found",
                        description="Search for all 1,023 non-empty subsets, keeping an archive keyed by subset. "
                                    "--method elites (default, MAP-Elites style): after 256 uniform throws, "
                                    "each batch of 16 holds 2 uniform throws and 14 children of archived "
                                    "throws (parents of rare subsets, of sizes with few subsets found, and "
                                    "whose children found new subsets are drawn more often), moved by a "
                                    "Gaussian step of 0.4 mm, 4 mm or 42 mm sideways (and alike on the other "
                                    "axes). --method targeted: a shared uniform exploration (a quarter of the "
                                    "budget), then targeted solves (--per-subset launches each) for the missing "
                                    "subsets nearest the archive. --method uniform: random throws. Writes "
                                    "DIR/subset-<pins>.json for every subset found (all naming one DIR/scene.xml), "
                                    "each with its robustness (16 more launches; see docs/bowling.md), "
                                    "DIR/summary.md (+ .csv, + .png: every subset found as a triangle) and "
                                    "DIR/atlas.json. Rerunning resumes: the shots already in DIR are the archive.")
    add_out_dir(a, dest="out", required=True, old=("--out",), help="output folder")
    a.add_argument("--max-rollouts", type=ATLAS_ROLLOUTS, default=20000, metavar="N",
                   help=with_limits("search launch budget of this run (default 20000; robustness probes not "
                                    "counted)", ATLAS_ROLLOUTS))
    a.add_argument("--method", choices=("elites", "targeted", "uniform"), default="elites",
                   help="how to spend the budget (default elites)")
    a.add_argument("--per-subset", type=PER_SUBSET, default=200, metavar="N",
                   help=with_limits("--method targeted: launch budget of each targeted solve (default 200)",
                                    PER_SUBSET))
    a.add_argument("--from", dest="from_atlas", metavar="ATLAS.json", default=None,
                   help="start from the shots of this atlas file (e.g. models/bowling/atlas.json): they are "
                        "written into DIR first (those not there yet), then the search resumes from them")
    a.add_argument("--robustness-only", action="store_true",
                   help="no search: add the robustness to every shot in DIR that lacks it, then the summary")
    a.add_argument("--no-robustness", action="store_true", help="write new shots without the robustness probes")
    add_seed(a, type=SEED, resumable=True)
    _runner_args(a, "the same shots as --jobs for the same seed and folder")
    a.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    bowl_foul.add_atlas_flags(a)
    a.set_defaults(func=cmd_atlas)

    register_throw(bowl)
    register_frame(bowl)


def register_throw(bowl) -> None:
    """``nbst bowl throw``: one delivery from the foul line, its phases (models/bowling/lane.py)."""
    t = bowl.add_parser("throw", help="one delivery from the foul line down the full lane: skid, breakpoint, roll, "
                                      "entry angle",
                        description="Run one delivery in a bowler's units down the full 60 ft lane in MuJoCo "
                                    "(the ball alone, h = 1 ms, until it reaches the head pin's line) and print its "
                                    "phases: skid length, breakpoint (distance and board), roll point, entry angle, "
                                    "board and speed at the pins. Boards as bowlers number them (board 1 at the "
                                    "edge on the bowling hand's side). Conventions: docs/bowling.md.",
                        epilog="Example: nbst bowl throw --hand right --board 10 --at arrows --angle 1.5 --mph 17 "
                               "--rpm 300 --rotation 45 --tilt 15 --oil house")
    _delivery_flags(t)
    t.add_argument("--oil", default="house", metavar="PATTERN",
                   help="oil pattern by name: house (40 ft crown), sport (42 ft, flat), short (34 ft), uniform "
                        "(test: full oil to the deck); default house")
    _ball_flags(t)
    t.add_argument("-o", "--output", default=None, metavar="THROW.json", help="also write the phases as JSON")
    t.add_argument("--json", action="store_true", help="print the phases as one JSON object")
    _picture_flags(t, "the throw's frame on all ten pins (as bowl frame runs it)")
    t.set_defaults(func=cmd_throw)


def _picture_flags(p, what: str) -> None:
    """--video, --still, --still-time, --size, --fps: the picture of a frame from the foul line."""
    p.add_argument("--video", default=None, metavar="OUT.mp4",
                   help=f"also film {what} (.mp4 or .gif; 3D, behind the bowler and overhead, from the release until "
                        "the pins settle, slow motion at impact; the pins down drawn at the end are the frame's "
                        "outcome; render/bowling_lane.py)")
    p.add_argument("--still", default=None, metavar="OUT.png",
                   help="also draw one frame as PNG (by default just before the ball meets the pins)")
    p.add_argument("--still-time", type=Bounded("still-time", 0, 30, unit="s"), default=None, metavar="S",
                   help="the --still's moment, seconds after the release")
    p.add_argument("--size", default=None, metavar="WxH", help="frame size of --video/--still (default 1280x720)")
    p.add_argument("--fps", type=Bounded("fps", 1, 240), default=None, help="--video's frames per second (default 60)")


def _runner_args(parser, same: str) -> None:
    """--jobs K | --cluster ADDRESS: where the rollouts run (see :func:`launcher`)."""
    g = parser.add_mutually_exclusive_group()
    g.add_argument("--jobs", type=JOBS, default=None, metavar="K",
                   help=with_limits("threads running rollouts (default: all cores)", JOBS))
    g.add_argument("--cluster", default=None, metavar="ADDRESS",
                   help=f"run the rollouts on the workers of this Dask scheduler (tcp://host:8786) instead; {same}")


_err = bowl_foul.err  # one error line, shared by every bowl subcommand


def launcher(args, jobs: int):
    """The rollout runner of a subcommand: K threads here, or a Dask cluster's workers
    (``--cluster``; ValueError, one line, when the scheduler cannot be reached)."""
    from nbst.models.bowling import shot

    if getattr(args, "cluster", None):
        from nbst.models.bowling.cluster import ClusterLauncher

        return ClusterLauncher(args.cluster)
    return shot.Launcher(jobs=jobs)


def write_shot(path, model, launch, mask: int, *, shared_scene: str | None = None, **kw) -> None:
    """Write SHOT.json and its scene XML (``<stem>.scene.xml``, with keyframe ``shot``) beside
    it, atomically; with ``shared_scene`` the file names that scene (written by the caller)."""
    from nbst.outputs import write_text_atomic

    from nbst.models.bowling import shotfile

    path = Path(path)
    scene_name = shared_scene or f"{path.stem}.scene.xml"
    d = shotfile.shot_dict(model, launch, scene_name=scene_name, down_mask=mask, **kw)
    if shared_scene is None:
        write_text_atomic(path.parent / scene_name, shotfile.scene_with_shot(d["qpos0"], d["qvel0"]))
    write_text_atomic(path, shotfile.dumps(d))


def atlas_json(folder, *, seed=None) -> Path:
    """Gather an atlas folder's shot files into FOLDER/atlas.json: one file a MuJoCo user
    replays without nbst, ``{"kind": "nbst-bowling-atlas", "scene": "scene.xml", "shots":
    [shot, ...]}``, each shot with the shot-file keys (``scene`` relative to the atlas file),
    sorted by subset size, then pins. Files that do not pass the shot-file checks are left out."""
    import json

    from nbst.outputs import write_text_atomic

    from nbst.models.bowling import shotfile

    folder = Path(folder)
    shots = []
    for f in sorted(folder.glob("subset-*.json")):
        try:
            shots.append(shotfile.load(f))
        except shotfile.ShotFileError:
            continue
    shots.sort(key=lambda d: (len(d["down"]), d["down"]))
    atlas = {"kind": shotfile.ATLAS_KIND, "schema_version": 1, "scene": "scene.xml", "seed": seed,
             "subsets": len(shots), "shots": shots}
    path = folder / "atlas.json"
    write_text_atomic(path, json.dumps(atlas, indent=1) + "\n")  # floats by repr: exact
    return path


def shipped_archive() -> dict:
    """The shipped atlas (models/bowling/atlas.json) as a search archive: mask -> (4,) launch,
    read through the shot-file gate; {} (with a one-line warning) if it cannot be read."""
    import numpy as np

    from nbst.models.bowling import shot, shotfile

    try:
        a, _, _ = shotfile.load_atlas(shotfile.SHIPPED_ATLAS)
        return {shot.mask_from_pins(d["down"]): np.array([float(d["launch"][k]) for k in shot.KEYS])
                for d in a["shots"] if "launch" in d}
    except shotfile.ShotFileError as e:
        from nbst.domain import plain

        print(f"nbst bowl solve: warning: the shipped atlas is not used: {plain(e)}", file=sys.stderr)
        return {}


def cmd_solve(args) -> int:
    import numpy as np

    from nbst.outputs import prepare_output, signals_deferred, sigterm_as_interrupt
    from nbst.progress import progress_bar

    from nbst.models.bowling import search, shot

    if args.foul_line or args.robust is not None:
        return bowl_foul.cmd_solve(args)
    target = args.down if args.down is not None else args.leave
    prepare_output(args.output)
    seed = args.seed if args.seed is not None else int(np.random.SeedSequence().entropy % (2**31))
    jobs = args.jobs or default_jobs()
    want = shot.pins_of(target)
    bar = []

    def progress(p) -> None:
        if args.quiet:
            return
        if not bar:
            bar.append(progress_bar(total=args.max_rollouts, unit="rollout", file=sys.stderr, dynamic_ncols=True,
                                    desc=f"bowl {','.join(map(str, want))}", smoothing=0.1))
        bar[0].update(p.rollouts - bar[0].n)
        if p.rollouts:
            near = ",".join(map(str, shot.pins_of(p.best_mask))) or "none"
            bar[0].set_postfix_str(f"nearest {near} ({p.best_hamming} off), {p.subsets} subsets seen",
                                   refresh=False)

    archive = {} if args.no_atlas else shipped_archive()
    try:
        L = launcher(args, jobs)
    except ValueError as e:
        return _err("solve", f"--cluster: {e}")
    progress(search.Progress(0, 10, 0, 0))  # the bar starts with the clock
    try:
        with sigterm_as_interrupt():
            res = search.solve(target, seed=seed, max_rollouts=args.max_rollouts, launcher=L, callback=progress,
                               distance=args.distance, archive=archive or None)
        if bar:
            bar[0].close()
        rob = None
        if not args.no_robustness and res.stopped != "interrupted":
            try:
                with sigterm_as_interrupt():
                    rob = search.robustness(L, res.launch, res.mask)
            except KeyboardInterrupt:
                res.stopped = "interrupted"
        runner = {"cluster": args.cluster} if args.cluster else {"jobs": jobs}
        from_atlas = bool(archive) and res.mask == target and target in archive and res.rollouts == 1
        meta = {"seed": seed, "rollouts": res.rollouts, "restarts": res.restarts, **runner,
                "max_rollouts": args.max_rollouts, "stopped": res.stopped, "wall_time_s": round(res.wall_time, 3),
                "subsets_seen": len(res.archive), "algorithm": "explore + CMA-ES restarts from nearest subsets",
                "distance": args.distance,
                "start": f"shipped atlas ({len(archive)} subsets)" if archive else "scratch",
                "from_atlas": from_atlas}
        if args.leave is not None:
            meta["leave"] = [n for n in range(1, 11) if not target >> (n - 1) & 1]
        with signals_deferred(reraise=False) as late:
            write_shot(args.output, L.model, res.launch, res.mask, requested=target, robustness=rob, search=meta)
    finally:
        if bar:
            bar[0].close()
        L.close()
    got = ",".join(map(str, shot.pins_of(res.mask))) or "none"
    how = " (the shipped atlas's throw, confirmed)" if from_atlas else ""
    line = (f"pins down {got} ({res.hamming} off the request) after {res.rollouts} "
            f"launch{'es' if res.rollouts != 1 else ''}{how} in "
            f"{res.wall_time:.1f} s, seed {seed}; wrote {args.output}")
    if res.stopped == "interrupted" or late:
        print(f"nbst bowl solve: interrupted; best so far written: {line}", file=sys.stderr)
        return 130
    if res.hamming:
        print(f"nbst bowl solve: not found within {args.max_rollouts} launches; nearest written: {line}",
              file=sys.stderr)
        return 1
    if not args.quiet:
        r = (f"; keeps the outcome within +/-{rob['lateral_m'] * 1000:.3g} mm sideways, "
             f"+/-{rob['speed_m_s'] * 1000:.3g} mm/s speed") if rob else ""
        print(f"nbst bowl solve: found: {line}{r}", file=sys.stderr)
    return 0


def cmd_replay(args) -> int:
    from nbst.models.bowling import shotfile, throwfile

    try:
        doc = shotfile.read_doc(args.shot)
        if throwfile.is_throw(doc):
            return _replay_throw(args)
        if isinstance(doc, dict) and "kind" not in doc and "format" in doc:
            return _err("replay", f"{args.shot}: format: not an nbst bowling shot or throw (a shot's kind is "
                                  f"{shotfile.KIND!r}, a throw's format {throwfile.FORMAT!r})")
        from nbst.render.bowling_lane import wants_picture

        if wants_picture(args):
            shot = isinstance(doc, dict) and doc.get("kind") == shotfile.KIND
            return _err("replay", f"{args.shot}: {'a 5 m shot file' if shot else 'not a throw file'}: --video/--still "
                                  "film throw files (bowl frame -o); a 5 m shot is filmed by "
                                  "`nbst render SHOT.json -o OUT.mp4` (or --still T -o OUT.png)")
        d, down = shotfile.replay_file(args.shot)
    except shotfile.ShotFileError as e:
        return _err("replay", str(e))
    want = sorted(d["down"])
    ok = down == want
    if args.json:
        from nbst.cli.args import print_json

        print_json({"shot": str(args.shot), "down": down, "expected": want, "match": ok})
    else:
        print(f"pins down  {','.join(map(str, down)) or 'none'}")
        print(f"expected   {','.join(map(str, want)) or 'none'}  ({'match' if ok else 'DIFFERENT'})")
    return 0 if ok else 1


def _replay_throw(args) -> int:
    """``bowl replay THROW.json``: the frame again from the foul line; exit 1 if its pins down differ.
    With --video/--still, the frame is recorded as it runs (one run) and filmed with the file's readout."""
    from nbst.models.bowling import throwfile
    from nbst.render import bowling_lane

    picture = bowling_lane.wants_picture(args)
    if not picture:
        d, r, ok = throwfile.replay_file(args.shot)
    else:
        from nbst.models.bowling import frame, lane, shot

        bad = bowling_lane.check_picture_args(args)
        if bad:
            return _err("replay", bad)
        d = throwfile.load(args.shot)
        try:   # the replay of throwfile.replay, recorded: its model, oil, ball, pins standing and timestep
            th = bowling_lane.record_throw(lane.Delivery(**d["delivery"]), d["oil"], lane.Ball(**d["ball"]),
                                           standing=d["standing"], timestep=float(d["outcome"]["timestep"]))
        except (lane.LaneError, frame.FrameError, shot.MujocoError) as e:
            return _err("replay", f"{args.shot}: delivery: {e}")
        r = th.frame
        ok = r.down == sorted(d["outcome"]["down"])
    want = sorted(d["outcome"]["down"])
    if args.json:
        from nbst.cli.args import print_json

        print_json({"throw": str(args.shot), "down": r.down, "expected": want, "leave": r.leave,
                    "expected_leave": sorted(d["outcome"]["leave"]), "match": ok})
    else:
        print(f"pins down  {','.join(map(str, r.down)) or 'none'}  (leave {_pins_text(r.leave)})")
        print(f"expected   {','.join(map(str, want)) or 'none'}  ({'match' if ok else 'DIFFERENT'})")
    if picture:
        bad = bowling_lane.write_pictures(args, th, prog="nbst bowl replay", **bowling_lane.throw_file_readout(d))
        if bad:
            return _err("replay", bad)
    return 0 if ok else 1


def cmd_throw(args) -> int:
    from nbst.models.bowling import lane
    from nbst.outputs import prepare_output

    for option, path in (("-o", args.output), ("--video", getattr(args, "video", None)),
                         ("--still", getattr(args, "still", None))):
        if path:  # before the throw: a link, a FIFO or a folder is refused in one line
            prepare_output(path, option=option)
    try:
        ball = _ball(args)
        d = _delivery(args)
        lane.pattern(args.oil)
        r = lane.throw(d, args.oil, ball)
    except ValueError as e:
        return _err("throw", str(e))
    if args.video or args.still or args.still_time is not None or args.size or args.fps is not None:
        from nbst.render.bowling_lane import picture_from_args

        bad = picture_from_args(args, d, ball)
        if bad:
            return _err("throw", bad)
    doc = r.to_dict()
    if args.output:
        from nbst.outputs import OutputError, write_text_atomic
        from nbst.solution import dumps_strict

        try:
            write_text_atomic(Path(args.output), dumps_strict(doc, indent=1) + "\n")
        except OutputError as e:
            return _err("throw", str(e))
    if args.json:
        from nbst.cli.args import print_json

        print_json(doc)
        return 0
    for line in throw_lines(r):
        print(line)
    return 0


def throw_lines(r) -> list[str]:
    """The phases of a throw (lane.ThrowResult) as lines, in bowler's units."""
    d = r.delivery

    def ft(v):
        return "none" if v is None else f"{v:.1f} ft"

    bp = ("none (the ball never moved out)" if r.breakpoint_ft is None
          else f"{r.breakpoint_ft:.1f} ft, board {r.breakpoint_board:.1f}")
    return [
        f"delivery     {d['hand']}-handed, {d['mph']:g} mph, {d['rpm']:g} rpm, rotation {d['rotation']:g} deg, "
        f"tilt {d['tilt']:g} deg, angle {d['angle']:g} deg; oil {r.oil}",
        f"ball         {r.ball['weight_lb']:g} lb, RG {r.ball['rg']:g} in, diff {r.ball['diff']:g} in, "
        f"cover {r.ball['friction']:g}",
        f"boards       foul line {r.board_at_foul_line:.1f}, arrows {r.board_at_arrows:.1f}",
        f"skid         {'none (no hook)' if r.skid_ft is None else ft(r.skid_ft) + ' (the hook starts)'}",
        f"breakpoint   {bp}",
        f"roll         {ft(r.roll_ft)}",
        f"at the pins  board {r.board_at_pins:.1f}, entry angle {r.entry_angle_deg:.1f} deg, "
        f"{r.speed_pins_mph:.1f} mph (lost {r.speed_lost_mph:.1f} mph), {r.seconds_to_pins:.2f} s",
    ]


def shot_name(mask: int) -> str:
    from nbst.models.bowling import shot

    return "subset-" + "_".join(map(str, shot.pins_of(mask))) + ".json"


def unpack_atlas(atlas_path, folder) -> int:
    """Write the shots of an atlas file as FOLDER/subset-<pins>.json (those not there yet)
    and its scene as FOLDER/scene.xml (when absent), every write atomic; returns how many
    shots were written. Everything is checked before anything is written: the atlas through
    the shot-file gate (its scene inside its own folder, parsed by MuJoCo, every shot's shapes
    fitting it), and its scene must be this version's (the search continues in it)."""
    from nbst.outputs import write_text_atomic

    from nbst.models.bowling import scene as scenemod
    from nbst.models.bowling import shot, shotfile

    folder = Path(folder)
    a, _, text = shotfile.load_atlas(atlas_path)
    if text != scenemod.scene_xml():
        raise shotfile.ShotFileError(f"{atlas_path}: scene: {a['scene']!r} is not this version's bowling scene; "
                                     f"its shots would not replay beside the ones found here")
    if not (folder / "scene.xml").exists():
        write_text_atomic(folder / "scene.xml", text, option="--out-dir")
    n = 0
    for d in a["shots"]:
        f = folder / shot_name(shot.mask_from_pins(d["down"]))
        if not f.exists():
            write_text_atomic(f, shotfile.dumps({**d, "scene": "scene.xml"}), option="--out-dir")
            n += 1
    return n


# --- bowl atlas, in named steps ---------------------------------------------------------------

def _atlas_folder(args) -> Path:
    """Step 1: the output folder, with the --from atlas's shots in it and this version's
    scene.xml; ShotFileError (one line) when --from is refused or DIR holds another scene."""
    from nbst.outputs import prepare_output, write_text_atomic

    from nbst.models.bowling import scene as scenemod
    from nbst.models.bowling import shotfile

    out = prepare_output(args.out, directory=True, option="--out-dir")
    if args.from_atlas:
        try:
            unpack_atlas(args.from_atlas, out)
        except shotfile.ShotFileError as e:
            raise shotfile.ShotFileError(f"--from: {e}") from None
    xml = scenemod.scene_xml()
    here = out / "scene.xml"
    if not here.exists():
        write_text_atomic(here, xml, option="--out-dir")  # one scene for every shot (the same model)
    elif shotfile.read_scene_text(here, here) != xml:  # shots of another scene: new ones would not replay there
        raise shotfile.ShotFileError(f"{here} is not this version's scene; use a new --out-dir folder")
    return out


def _atlas_resume(out: Path) -> tuple[dict, dict]:
    """Step 2: the shots already in the folder: ({mask: file}, {mask: (4,) launch}); files
    that fail the shot-file checks are skipped (and found again if the search finds them)."""
    import numpy as np

    from nbst.models.bowling import shot, shotfile

    files, launches = {}, {}
    for f in out.glob("subset-*.json"):
        try:
            m = shot.mask_from_pins(int(p) for p in f.stem.split("-", 1)[1].split("_"))
        except ValueError:
            continue
        try:
            d = shotfile.load(f)
        except shotfile.ShotFileError:
            continue
        files[m] = f
        if "launch" in d:
            launches[m] = np.array([float(d["launch"][k]) for k in shot.KEYS])
    return files, launches


class _AtlasRun:
    """Step 3: the search (or the robustness pass) over one folder, writing each new shot as it
    is found, with its robustness; ``probes`` counts the robustness launches."""

    def __init__(self, args, L, out: Path, files: dict, launches: dict):
        from nbst.models.bowling import atlas as atlasmod

        self.args, self.L, self.out, self.files, self.launches = args, L, out, files, launches
        self.arch = atlasmod.Archive.from_launches(launches)
        self.probes = 0
        self.bar = None

    def add_robustness(self, mask: int, f: Path) -> None:
        from nbst.outputs import write_text_atomic

        from nbst.models.bowling import search, shotfile

        d = shotfile.load(f)
        rob = search.robustness_ladder(self.L, self.launches[mask], mask)
        self.probes += rob["lateral_m_rollouts"] + rob["speed_m_s_rollouts"]
        d["robustness"] = rob
        write_text_atomic(f, shotfile.dumps(d), option="--out-dir")

    def on_new(self, masks) -> None:
        a = self.args
        for m in masks:
            f = self.out / shot_name(m)
            write_shot(f, self.L.model, self.arch.elite[m], m, shared_scene="scene.xml", requested=m,
                       search={"seed": a.seed, "method": a.method, "found_after": self.arch.found_at[m]})
            self.files[m], self.launches[m] = f, self.arch.elite[m]
            if not a.no_robustness:
                self.add_robustness(m, f)

    def progress(self, arch) -> None:
        if self.bar:
            self.bar.update(arch.rollouts - self.bar.n)
            self.bar.set_postfix_str(f"{len(arch)} subsets", refresh=False)

    def run(self) -> bool:
        """Search (or add robustness); True when interrupted (what ran is kept)."""
        from nbst.outputs import sigterm_as_interrupt
        from nbst.progress import progress_bar

        from nbst.models.bowling import atlas as atlasmod
        from nbst.models.bowling import shotfile

        a = self.args
        todo = []
        if a.robustness_only:
            for m in sorted(self.files):
                try:
                    if m in self.launches and "robustness" not in shotfile.load(self.files[m]):
                        todo.append(m)
                except shotfile.ShotFileError:
                    continue
        if not a.quiet:
            total = len(todo) if a.robustness_only else a.max_rollouts
            self.bar = progress_bar(total=total, unit="shot" if a.robustness_only else "rollout", file=sys.stderr,
                                    dynamic_ncols=True, desc="atlas")
        try:
            with sigterm_as_interrupt():
                if a.robustness_only:
                    for m in todo:
                        self.add_robustness(m, self.files[m])
                        if self.bar:
                            self.bar.update(1)
                elif a.max_rollouts:
                    atlasmod.run(self.L, self.arch, method=a.method, budget=a.max_rollouts, seed=a.seed,
                                 per_subset=a.per_subset, on_new=self.on_new, callback=self.progress)
        except KeyboardInterrupt:
            return True
        finally:
            if self.bar:
                self.bar.close()
        return False


def _atlas_summaries(out: Path, run: _AtlasRun, *, seconds: float, seed: int, method: str) -> int:
    """Step 4: summary.csv, summary.md, atlas.json and summary.png; returns the subsets held."""
    import csv
    import io

    from nbst.outputs import write_text_atomic

    from nbst.models.bowling import figure, geometry, shot

    have = {m: f.name for m, f in run.files.items()}
    buf = io.StringIO()
    w = csv.writer(buf)
    w.writerow(["mask", "pins", "size", "file"])
    for m in range(1, geometry.N_SUBSETS + 1):
        pins = shot.pins_of(m)
        w.writerow([m, "-".join(map(str, pins)), len(pins), have.get(m, "")])
    write_text_atomic(out / "summary.csv", buf.getvalue(), option="--out-dir")
    write_text_atomic(out / "summary.md", summary_md(have, launches=run.arch.rollouts, probes=run.probes,
                                                     seconds=seconds, seed=seed, method=method, archive=run.arch),
                      option="--out-dir")
    atlas_json(out, seed=seed)
    fig = figure.atlas_figure(have, title=f"{len(have)} of {geometry.N_SUBSETS:,} subsets "
                                          f"(red frame: needs a flying pin)")
    from nbst.outputs import atomic_path

    with atomic_path(out / "summary.png", option="--out-dir") as tmp:
        figure.save(fig, tmp)
    return len(have)


def cmd_atlas(args) -> int:
    if args.foul_line:
        return bowl_foul.cmd_atlas(args)
    from nbst.models.bowling import geometry, shotfile

    try:
        out = _atlas_folder(args)
    except shotfile.ShotFileError as e:
        return _err("atlas", str(e))
    try:
        L = launcher(args, args.jobs or default_jobs())
    except ValueError as e:
        return _err("atlas", f"--cluster: {e}")
    files, launches = _atlas_resume(out)
    t0 = time.perf_counter()
    run = _AtlasRun(args, L, out, files, launches)
    try:
        stopped = run.run()
    finally:
        L.close()
    n = _atlas_summaries(out, run, seconds=time.perf_counter() - t0, seed=args.seed, method=args.method)
    print(f"nbst bowl atlas: {n} of {geometry.N_SUBSETS} subsets have a shot in {out} ({run.arch.rollouts} search "
          f"launches and {run.probes} robustness launches this run{', interrupted' if stopped else ''})",
          file=sys.stderr)
    return 130 if stopped else 0


def summary_md(have: dict, *, launches: int, probes: int, seconds: float, seed: int, method: str,
               archive=None) -> str:
    """The atlas's summary table (markdown): found / possible by size, and the geometry classes."""
    from nbst.models.bowling import geometry

    found = sorted(have)
    lines = ["# Bowling atlas", "", f"{len(found)} of {geometry.N_SUBSETS} subsets found; this run: {launches} search launches "
             f"({method}) and {probes} robustness launches in {seconds:.0f} s (seed {seed}).", ""]
    if archive is not None and method.startswith("elites") and launches:
        (nu, hu), kids = archive.uniform, sum(archive.children.values())
        new = sum(1 for v in archive.found_at.values() if v >= 0)
        lines[-1:-1] = ["", f"New subsets this run: {new}; from its {nu} uniform launches: {hu}; from its "
                            f"{kids} children of elites: {sum(archive.hits.values())}."]
    return "\n".join(lines + geometry.summary_lines(found)) + "\n"


# --------------------------------------------------------------------------- frames from the foul line


def _delivery_flags(t) -> None:
    """The delivery flags of ``bowl throw`` and ``bowl frame``: one vocabulary, one help text."""
    t.add_argument("--hand", choices=("right", "left"), default="right", help="bowling hand (default right)")
    t.add_argument("--board", type=Bounded("board", 1, 39), default=10.0, metavar="B",
                   help="board where the ball is at --at (default 10; 1..39, fractions allowed)")
    t.add_argument("--at", choices=("foul", "arrows"), default="arrows",
                   help="where --board is: at the foul line or where the ball crosses the arrows, 15 ft out "
                        "(default arrows)")
    t.add_argument("--angle", type=Bounded("angle", -10, 10, unit="deg"), default=1.5, metavar="DEG",
                   help="launch angle from straight down the lane, + out towards board 1 (default 1.5)")
    t.add_argument("--mph", type=Bounded("mph", 5, 30, unit="mph"), default=17.0, help="release speed (default 17)")
    t.add_argument("--rpm", type=Bounded("rpm", 0, 800, unit="rpm"), default=300.0, help="rev rate (default 300)")
    t.add_argument("--rotation", type=Bounded("rotation", 0, 90, unit="deg"), default=45.0, metavar="DEG",
                   help="axis rotation: 0 end over end, 90 pure side spin (default 45)")
    t.add_argument("--tilt", type=Bounded("tilt", 0, 90, unit="deg"), default=15.0, metavar="DEG",
                   help="axis tilt: 0 a horizontal spin axis (default 15)")


def _ball_flags(t) -> None:
    """The ball flags of ``bowl throw`` and ``bowl frame`` (the ball maker's units; lane.Ball checks them)."""
    t.add_argument("--weight", type=float, default=15.0, metavar="LB", help="ball weight, lb (default 15; at most 16)")
    t.add_argument("--rg", type=float, default=2.50, metavar="IN", help="ball RG, in (default 2.50; USBC 2.46..2.80)")
    t.add_argument("--diff", type=float, default=0.040, metavar="IN",
                   help="RG differential, in (default 0.040; USBC at most 0.060)")
    t.add_argument("--cover", type=float, default=0.20, metavar="MU",
                   help="coverstock friction on the dry lane (default 0.20; USBC at most 0.32)")


def _delivery(args):
    """The delivery of the ``_delivery_flags``, checked (LaneError naming the field)."""
    from nbst.models.bowling import lane

    return lane.Delivery(hand=args.hand, board=args.board, at=args.at, angle=args.angle, mph=args.mph,
                         rpm=args.rpm, rotation=args.rotation, tilt=args.tilt).check()


def _ball(args):
    """The ball of the ``_ball_flags``, checked (LaneError naming the field outside USBC's limits)."""
    from nbst.models.bowling import lane

    return lane.Ball(weight_lb=args.weight, rg=args.rg, diff=args.diff, friction=args.cover).check()


def _mc_flags(t, samples: int, what: str) -> None:
    t.add_argument("--oil", default="house", metavar="PATTERN", help="oil pattern by name (default house)")
    t.add_argument("--seed", type=SEED, default=1, help="seed of the release noise (default 1: same command, "
                                                         "same numbers)")
    t.add_argument("--jobs", type=JOBS, default=None, metavar="K", help="processes running frames (default: all cores)")
    t.add_argument("--samples", type=Bounded("samples", 1, 100_000, integer=True), default=samples, metavar="N",
                   help=f"noisy throws per {what} (default {samples})")
    t.add_argument("--json", action="store_true", help="print the result as one JSON object")
    t.add_argument("-q", "--quiet", action="store_true", help="no progress")


def register_frame(bowl) -> None:
    """``nbst bowl frame``, ``spares`` and ``pocket``: frames from the foul line (models/bowling/frame.py)."""
    f = bowl.add_parser("frame", help="one delivery from the foul line into the pins: the settled USBC pinfall",
                        description="Throw one delivery (as bowl throw) down the full lane into the pins and run "
                                    "MuJoCo until every pin rests (or 6 s after the ball reaches the head pin), then "
                                    "count pinfall as USBC does: knocked down, off the deck, in the gutter, or "
                                    "leaning on the kickback (dead wood). Options: the timestep ladder, a longer "
                                    "run, and the probability of the outcome under release noise (docs/bowling.md).",
                        epilog="Example: nbst bowl frame --board 10 --at arrows --angle 1.5 --timesteps --probability 40")
    _delivery_flags(f)
    _ball_flags(f)
    f.add_argument("--leave", default=None, metavar="PINS",
                   help="pins standing before the throw, e.g. 10 or 2,4,5,8 (default: a full rack)")
    f.add_argument("--timesteps", action="store_true", help="also run it at h = 0.5 and 0.25 ms (the ladder)")
    f.add_argument("--longer", type=Bounded("longer", 0, 60, unit="s"), default=0.0, metavar="S",
                   help="also run it S seconds past the settle and say whether the outcome changed")
    f.add_argument("--probability", type=Bounded("probability", 1, 100_000, integer=True), default=None, metavar="N",
                   help="the probability of converting (strike, or the leave) over N noisy throws, with a 95%% "
                        "Wilson interval")
    f.add_argument("--noise-scale", type=Bounded("noise-scale", 0, 10), default=1.0, metavar="F",
                   help="multiply every release-noise sigma by F (default 1: 1/2 board, 0.15 deg, 0.3 mph, 15 rpm, "
                        "5 deg rotation)")
    f.add_argument("--angle-sigma", type=Bounded("angle-sigma", 0, 5, unit="deg"), default=0.15, metavar="DEG",
                   help="the launch angle's sigma before --noise-scale (default 0.15, an assumption: docs/bowling.md)")
    f.add_argument("-o", "--output", default=None, metavar="THROW.json",
                   help="also write the throw file: delivery, ball, oil, pins standing, the settled outcome, and the "
                        "--probability estimate and --timesteps ladder when given; bowl replay runs it again")
    _mc_flags(f, 40, "estimate")
    f.set_defaults(func=cmd_frame)

    s = bowl.add_parser("spares", help="the throw converting each common leave with the highest probability",
                        description="For each leave, the 3-6-9 system's line (the strike ball, feet moved 3/6/9 "
                                    "boards, same target arrow) and straight spare balls (cross-lane at 17 and 21 mph, "
                                    "from the middle and straight down the boards, at the leave's aim point and 1-2 "
                                    "boards either side) are "
                                    "screened on --screen noisy throws each; the best is polished by a robust "
                                    "search (--polish) and measured on --samples, beside the 3-6-9 line "
                                    "(docs/bowling.md).",
                        epilog="Example: nbst bowl spares --leaves 10,7 --samples 40")
    s.add_argument("--leaves", default=None, metavar="L1,L2",
                   help="leaves to shoot, '-' joining pins, ',' between leaves (default: 10, 7, 4, 6, 2-4-5-8, "
                        "3-6-10, 1-2-4, 1-3-6, 2-8, 3-9, 7-10)")
    s.add_argument("--screen", type=Bounded("screen", 1, 10_000, integer=True), default=12, metavar="M",
                   help="noisy throws per candidate in the screening (default 12)")
    s.add_argument("--polish", type=Bounded("polish", 0, 1_000_000, integer=True), default=None, metavar="N",
                   help="noisy frames per leave for polishing the pick with a robust search (an evolution "
                        "strategy on common noisy throws; skipped where the pick converted every screening "
                        "throw or nothing converted); default 40 x --screen (480); 0: no polish")
    _mc_flags(s, 60, "measured throw")
    s.set_defaults(func=cmd_spares)

    p = bowl.add_parser("pocket", help="pocket map: strike probability over board x entry angle (a PNG), and carry",
                        description="Aim a delivery at each (board at the head pin, entry angle) cell, run --samples "
                                    "noisy frames of it, and draw the strike probability as a heatmap beside the "
                                    "strike share of all frames by actual entry; carry = strikes / pocket hits "
                                    "(actual board 17-18). The published pocket (17.5, ~6 deg) is marked.",
                        epilog="Example: nbst bowl pocket -o pocket.png --samples 40")
    p.add_argument("-o", "--output", required=True, metavar="MAP.png", help="the heatmap (PNG)")
    p.add_argument("--boards", default="15.5:19.5:1", metavar="A:B:STEP", help="boards (default 15.5:19.5:1)")
    p.add_argument("--angles", default="2:7:1", metavar="A:B:STEP", help="entry angles, deg (default 2:7:1)")
    _mc_flags(p, 40, "cell")
    p.set_defaults(func=cmd_pocket)


def _grid(text: str, flag: str, lo: float, hi: float) -> list:
    import numpy as np

    try:
        a, b, st = (float(v) for v in text.split(":"))
    except ValueError:
        raise ValueError(f"{flag}: must be A:B:STEP (numbers), got {text!r}") from None
    if not (lo <= a <= b <= hi and st > 0 and (b - a) / st <= 40):
        raise ValueError(f"{flag}: need {lo:g} <= A <= B <= {hi:g}, STEP > 0 and at most 41 values, got {text!r}")
    return [round(float(v), 6) for v in np.arange(a, b + st / 2, st)]


def _bar(args, total: int, desc: str):
    from nbst.progress import progress_bar

    return progress_bar(total=total, desc=desc, unit="frame", disable=args.quiet, file=sys.stderr)


def write_throw(path, r, oil: str, ball, *, ladder=None, estimate=None) -> None:
    """Write THROW.json (models/bowling/throwfile.py) for frame ``r`` thrown with ``ball``, atomically."""
    from nbst.outputs import write_text_atomic

    from nbst.models.bowling import throwfile

    write_text_atomic(Path(path), throwfile.dumps(throwfile.throw_dict(r, oil=oil, ball=ball, ladder=ladder,
                                                                       estimate=estimate)))


def cmd_frame(args) -> int:
    from nbst.outputs import OutputError, prepare_output, signals_deferred

    from nbst.models.bowling import frame, lane, noise

    try:
        d = _delivery(args)
        ball = _ball(args)
        lane.pattern(args.oil)
        standing = None if args.leave is None else sorted(
            n for n in range(1, 11) if _pin_list(args.leave, "--leave") >> (n - 1) & 1)
        if args.output:
            prepare_output(args.output)
    except (ValueError, argparse.ArgumentTypeError, OutputError) as e:
        return _err("frame", str(e))
    r = lad = est = None
    try:
        r = frame.run_frame(d, args.oil, ball, standing=standing)
        doc = {"frame": r.to_dict()}
        if args.longer:
            r2 = frame.run_frame(d, args.oil, ball, standing=standing, extra_s=args.longer)
            doc["longer"] = {"extra_s": args.longer, "leave": r2.leave, "same": r2.leave == r.leave}
        if args.timesteps:
            lad = frame.ladder(d, args.oil, ball, standing=standing)
            doc["ladder"] = [{"timestep": x.timestep, "leave": x.leave, "settle_s": x.settle_s, "cap_hit": x.cap_hit}
                             for x in lad]
        if args.probability:
            bar = _bar(args, args.probability, "noisy throws")
            k = float(args.noise_scale)
            D = noise.DEFAULT
            nz = noise.Noise(board=D.board * k, angle=args.angle_sigma * k, mph=D.mph * k, rpm=D.rpm * k,
                             rotation=D.rotation * k, tilt=D.tilt * k)
            with frame.FrameRunner(args.oil, ball, jobs=args.jobs or default_jobs()) as R:
                est, _ = noise.probability(d, args.probability, args.seed, runner=R, standing=standing, noise=nz,
                                           on_done=lambda: bar.update(1))
            bar.close()
            doc["probability"] = est.to_dict()
    except KeyboardInterrupt:
        if args.output and r is not None:  # the frame is done: keep it (without what was cut short)
            try:
                with signals_deferred(reraise=False):
                    write_throw(args.output, r, args.oil, ball, ladder=lad)
            except (OutputError, ValueError) as e:
                return _err("frame", str(e))
            print(f"nbst bowl frame: interrupted; wrote the frame without the unfinished parts to {args.output}",
                  file=sys.stderr)
            return 130
        print("nbst bowl frame: interrupted", file=sys.stderr)
        return 130
    except ValueError as e:
        return _err("frame", str(e))
    if args.output:
        try:
            with signals_deferred(reraise=False) as late:
                write_throw(args.output, r, args.oil, ball, ladder=lad, estimate=est)
        except (OutputError, ValueError) as e:
            return _err("frame", str(e))
        if late:
            print(f"nbst bowl frame: interrupted; wrote {args.output}", file=sys.stderr)
            return 130
    if args.json:
        from nbst.cli.args import print_json

        print_json(doc)
        return 0
    for line in frame_lines(doc):
        print(line)
    if args.output:
        print(f"throw file    {args.output} (nbst bowl replay {args.output})")
    return 0


def _pins_text(pins) -> str:
    return "-".join(str(p) for p in pins) if pins else "none"


def frame_lines(doc: dict) -> list[str]:
    r = doc["frame"]
    what = "strike" if len(r["in_play"]) == 10 and not r["leave"] else ("converted" if not r["leave"] else "")
    out = [f"pins in play  {_pins_text(r['in_play'])}",
           f"down          {_pins_text(r['down'])}" + (f"  ({what})" if what else ""),
           f"leave         {_pins_text(r['leave'])}"]
    if r["partition"]:
        out.append(f"dead wood     {_pins_text(r['partition'])} leaning on the kickback (USBC 6a.4)")
    if r["ball_left_lane"]:
        out.append("gutter ball   the ball left the lane before the pins: no pinfall (USBC 6b.1)")
    if r["board_at_pins"] is not None:
        out.append(f"entry         board {r['board_at_pins']:.1f} at {r['entry_angle_deg']:.1f} deg")
    out.append(f"settled       {'at %.2f s' % r['settle_s'] if r['settled'] else 'no: the cap was hit at %.2f s' % r['seconds']}"
               f" (ball at the head pin {r['ball_at_pins_s']:.2f} s)" if r["ball_at_pins_s"] is not None else
               f"settled       {'at %.2f s' % r['settle_s'] if r['settled'] else 'no: capped'}")
    if "longer" in doc:
        g = doc["longer"]
        out.append(f"{g['extra_s']:g} s longer  leave {_pins_text(g['leave'])}: {'same' if g['same'] else 'CHANGED'}")
    for x in doc.get("ladder", []):
        out.append(f"h = {1000 * x['timestep']:g} ms".ljust(14) + f"leave {_pins_text(x['leave'])}"
                   + (f", settled at {x['settle_s']:.2f} s" if x["settle_s"] is not None else ", capped"))
    if "probability" in doc:
        e = doc["probability"]
        top = ", ".join(f"{k or 'none'} {v}" for k, v in list(e["leaves"].items())[:5])
        out.append(f"probability   {100 * e['p']:.0f}% converted ({e['k']}/{e['n']}; 95% CI {100 * e['lo']:.0f}-"
                   f"{100 * e['hi']:.0f}%), seed {e['seed']}; leaves: {top}")
    return out


def cmd_spares(args) -> int:
    from nbst.models.bowling import frame, lane, spares

    names = list(spares.LEAVES) if args.leaves is None else [x.strip() for x in args.leaves.split(",") if x.strip()]
    try:
        lane.pattern(args.oil)
        for nm in names:
            if nm not in spares.LEAVES:
                raise ValueError(f"--leaves: {nm!r} is not one of the common leaves ({', '.join(spares.LEAVES)})")
    except ValueError as e:
        return _err("spares", str(e))
    out = []
    # frames per leave: 17 candidates (19 on a multi-pin leave) screened, 3 x 2 more screens, 2 measures,
    # then at most the polish's budget and its measure (a skipped polish leaves the bar short of its total)
    polish = spares.POLISH_PER_SCREEN * args.screen if args.polish is None else args.polish
    total = sum(2 * args.samples + (23 + 2 * ("-" in nm)) * args.screen + (polish + args.samples) * (polish > 0)
                for nm in names)
    bar = _bar(args, total, "spare frames")
    try:
        with frame.FrameRunner(args.oil, jobs=args.jobs or default_jobs()) as R:
            for nm in names:
                res = spares.best_spare(nm, args.samples, args.seed, runner=R, screen=args.screen,
                                        on_done=lambda: bar.update(1), polish=polish)
                out.append(res.to_dict())
                if not args.json:
                    bar.clear() if hasattr(bar, "clear") else None
                    print(spare_line(out[-1]), flush=True)
    except KeyboardInterrupt:
        bar.close()
        print(f"nbst bowl spares: interrupted after {len(out)} of {len(names)} leaves", file=sys.stderr)
        return 130
    bar.close()
    if args.json:
        from nbst.cli.args import print_json

        print_json({"seed": args.seed, "samples": args.samples, "screen": args.screen, "polish": polish,
                    "spares": out})
    return 0


def spare_line(r: dict) -> str:
    e, s, b = r["estimate"], r["system_369_estimate"], r["best"]
    return (f"{r['leave']:>8}  best: {r['best_label']:<18} (board {b['board']:.1f}, {b['angle']:+.2f} deg, "
            f"{b['mph']:.1f} mph, {b['rpm']:.0f} rpm, rotation {b['rotation']:.0f})  {100 * e['p']:3.0f}% ({e['k']}/{e['n']}, CI "
            f"{100 * e['lo']:.0f}-{100 * e['hi']:.0f}%)   3-6-9 line (board {r['system_369']['board']:.1f}): "
            f"{100 * s['p']:.0f}% ({s['k']}/{s['n']}, CI {100 * s['lo']:.0f}-{100 * s['hi']:.0f}%)"
            + "   ladder 1/0.5/0.25 ms, +2 s: " + " / ".join(_pins_text(x[1]) for x in r["ladder"]))


def cmd_pocket(args) -> int:
    from nbst.models.bowling import frame, lane, spares

    try:
        boards = _grid(args.boards, "--boards", 1, 39)
        angles = _grid(args.angles, "--angles", 0, 10)
        lane.pattern(args.oil)
        if not args.output.lower().endswith(".png"):
            raise ValueError(f"{args.output}: -o must name a .png file")
    except ValueError as e:
        return _err("pocket", str(e))
    from nbst.outputs import atomic_path, prepare_output

    prepare_output(args.output)  # before the frames: a link, a FIFO or a folder is refused in one line
    bar = _bar(args, args.samples * len(boards) * len(angles), "pocket frames")
    try:
        with frame.FrameRunner(args.oil, jobs=args.jobs or default_jobs()) as R:
            pm = spares.pocket_map(boards, angles, args.samples, args.seed, runner=R, on_done=lambda: bar.update(1))
    except KeyboardInterrupt:
        bar.close()
        print("nbst bowl pocket: interrupted; nothing written", file=sys.stderr)
        return 130
    bar.close()
    fig = spares.pocket_figure(pm)
    with atomic_path(args.output) as tmp:  # the one writer: whole PNG or the previous file
        fig.savefig(tmp)
    b, a, p, k = pm.best()
    ks, ns = pm.carry()
    kc, nc = pm.carry(angles=(4.0, 6.0))
    from nbst.models.bowling.noise import wilson

    doc = {"best": {"board": b, "angle": a, "p": p, "k": k, "n": pm.n}, "carry": {"strikes": ks, "pocket_hits": ns},
           "carry_4_6_deg": {"strikes": kc, "pocket_hits": nc}, "map": pm.to_dict(), "output": args.output}
    if args.json:
        from nbst.cli.args import print_json

        doc["map"].pop("hits")
        print_json(doc)
        return 0
    lo, hi = wilson(k, pm.n)
    print(f"wrote {args.output}: {len(boards)} boards x {len(angles)} angles, {pm.n} noisy throws per cell, seed {pm.seed}")
    print(f"best cell  board {b:g} at {a:g} deg: strike {100 * p:.0f}% ({k}/{pm.n}; 95% CI {100 * lo:.0f}-{100 * hi:.0f}%)")
    for label, (kk, nn) in (("carry (actual board 17-18, any angle)", (ks, ns)), ("carry (17-18 at 4-6 deg)", (kc, nc))):
        if nn:
            l2, h2 = wilson(kk, nn)
            print(f"{label}: {100 * kk / nn:.0f}% ({kk}/{nn}; 95% CI {100 * l2:.0f}-{100 * h2:.0f}%)")
        else:
            print(f"{label}: no pocket hits")
    return 0
