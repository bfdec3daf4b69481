"""``nbst bowl throw``, ``frame``, ``spares`` and ``pocket``: the lane half, deliveries from the foul
line in a bowler's units (models/bowling/lane/), and the replay of a foul-line throw file.

The delivery flags (hand, board at the foul line or the arrows, launch angle, mph, rpm, axis
rotation and tilt) and the ball flags (weight, RG, differential, coverstock) are one vocabulary
for every subcommand (:mod:`nbst.cli.bowl.args`). The work is the library's: the ball's phases
(:mod:`nbst.models.bowling.lane.phases`), frames (:mod:`.frame`), noise, spares and the pocket
map (:mod:`.spares`), throw files (:mod:`.throwfile`).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from nbst.cli.args import Bounded, print_json
from nbst.cli.bowl.args import (ball_flags, ball_of, bowler_of, check_picture_args, delivery_flags,
                                delivery_of, err, mc_flags, oil_flag, picture_flags, pin_list, pins_text, size_of,
                                stance_target, wants_picture)
from nbst.cli.bowl.series import path_plot_flag, write_path_plot
from nbst.parallel import default_jobs
from nbst.progress import progress_bar
from nbst.outputs import write_text_atomic, prepare_output, signals_deferred, OutputError
from nbst.errors import MujocoError
from nbst.solution import dumps_strict

__all__ = ["register", "register_throw", "register_frame", "write_throw", "the_delivery", "cmd_throw",
           "line_lines", "throw_lines", "cmd_frame", "frame_lines", "replay_throw", "write_pictures",
           "picture_from_args"]


def register(bowl) -> None:
    """The lane half's subcommands ``throw`` and ``frame`` on ``nbst bowl``'s subparsers (``spares``,
    ``pocket`` and ``advise``: :mod:`nbst.cli.bowl.advise`)."""
    register_throw(bowl)
    register_frame(bowl)


def register_throw(bowl) -> None:
    """``nbst bowl throw``: one delivery from the foul line, its phases (models/bowling/lane/phases.py)."""
    t = bowl.add_parser("throw", help="one delivery from the foul line down the full lane: skid, breakpoint, roll, "
                                      "entry angle",
                        description="Run one delivery in a bowler's units down the full 60 ft lane in MuJoCo "
                                    "(the ball alone, h = 1 ms, until it reaches the head pin's line) and print its "
                                    "phases: skid length, breakpoint (distance and board), roll point, entry angle, "
                                    "board and speed at the pins. Boards as bowlers number them (board 1 at the "
                                    "edge on the bowling hand's side). Conventions: docs/bowling.md.",
                        epilog="Example: nbst bowl throw --hand right --board 10 --at arrows --angle 1.5 --mph 17 "
                               "--rpm 300 --rotation 45 --tilt 15 --oil house")
    delivery_flags(t)
    oil_flag(t)
    ball_flags(t)
    t.add_argument("-o", "--output", default=None, metavar="THROW.json",
                   help="also write the phases as JSON, with the line (stance, target, breakpoint, entry), the hit's "
                        "name and the --bowler (a gutter ball: its delivery and where it left the lane)")
    t.add_argument("--json", action="store_true", help="print the phases as one JSON object")
    path_plot_flag(t)
    picture_flags(t, "the throw's frame on all ten pins (as bowl frame runs it)")
    t.set_defaults(func=cmd_throw)


def register_frame(bowl) -> None:
    """``nbst bowl frame``, ``spares`` and ``pocket``: frames from the foul line (models/bowling/frame.py)."""
    f = bowl.add_parser("frame", help="one delivery from the foul line into the pins: the settled USBC pinfall",
                        description="Throw one delivery (as bowl throw) down the full lane into the pins and run "
                                    "MuJoCo until every pin rests (or until the pinsetter's sweep, 2.6 s after the "
                                    "ball reaches the head pin), then count pinfall as USBC does: knocked down, off "
                                    "the deck, in the gutter, or leaning on the kickback (dead wood). Options: the timestep ladder, a longer "
                                    "run, and the probability of the outcome under release noise (docs/bowling.md).",
                        epilog="Example: nbst bowl frame --board 10 --at arrows --angle 1.5 --timesteps --probability 40")
    delivery_flags(f)
    ball_flags(f)
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
    f.add_argument("--angle-sigma", type=Bounded("angle-sigma", 0, 5, unit="deg"), default=None, metavar="DEG",
                   help="the launch angle's sigma before --noise-scale (default 0.15, or the --bowler's; an "
                        "assumption: docs/bowling.md)")
    f.add_argument("-o", "--output", default=None, metavar="THROW.json",
                   help="also write the throw file: delivery, ball, oil, pins standing, the settled outcome, and the "
                        "--probability estimate and --timesteps ladder when given; bowl replay runs it again")
    mc_flags(f, None, "estimate")   # its throws are --probability N's (a --samples here was never read)
    f.set_defaults(func=cmd_frame)


def _bar(args, total: int, desc: str):
    return progress_bar(total=total, desc=desc, unit="frame", disable=args.quiet, file=sys.stderr)


def write_throw(path, r, oil: str, ball, *, ladder=None, estimate=None, extra=None) -> None:
    """Write THROW.json (models/bowling/throwfile.py) for frame ``r`` thrown with ``ball``, atomically;
    ``extra``: the keys beside the schema's (line, names, bowler, note)."""
    from nbst.models.bowling.lane import throwfile

    d = throwfile.throw_dict(r, oil=oil, ball=ball, ladder=ladder, estimate=estimate)
    write_text_atomic(Path(path), throwfile.dumps({**d, **(extra or {})}))


def the_delivery(args, oil, ball):
    """(the delivery, the --bowler's noise or None) of a throwing command's flags: the --bowler's
    strike ball (or the defaults) with the flags given over it, aimed along the ball's real path
    (--at arrows: its board at the arrows; --stance/--target: the launch angle through the target)."""
    from nbst.models.bowling import lane
    from nbst.models.bowling.lane import advise

    bd, bnz = bowler_of(args)
    d = bd if bd is not None else delivery_of(args)
    st = stance_target(args)
    if st is not None:
        return advise.aim_target(d, st[1], oil, ball), bnz
    return lane.aim_at_arrows(d, oil, ball), bnz


def cmd_throw(args) -> int:
    from nbst.models.bowling import lane
    from nbst.models.bowling.lane import advise

    for option, path in (("-o", args.output), ("--video", getattr(args, "video", None)),
                         ("--still", getattr(args, "still", None)), ("--path-plot", args.path_plot)):
        if path:  # before the throw: a link, a FIFO or a folder is refused in one line
            prepare_output(path, option=option)
    bad = check_picture_args(args) if wants_picture(args) else None
    if bad:
        return err("throw", bad)
    ball = ball_of(args)
    d, _ = the_delivery(args, args.oil, ball)
    try:
        r = lane.throw(d, args.oil, ball)
    except lane.GutterBall as g:   # a result, not bad input: said as one, nothing written (no phases)
        return gutter_throw(args, d, g)
    if wants_picture(args):
        bad = picture_from_args(args, d, ball)
        if bad:
            return err("throw", bad)
    doc = r.to_dict()
    bad = write_path_plot(args.path_plot, [r], oil=args.oil) if args.path_plot else None
    if bad:
        return err("throw", bad)
    doc.update(bowler=args.bowler, line=advise.line_of(r), note=advise.SAMPLE_NOTE)
    if args.output:
        write_text_atomic(Path(args.output), dumps_strict(doc, indent=1) + "\n")
    if args.json:
        print_json(doc)
        return 0
    for line in throw_lines(r, bowler=args.bowler, oil=args.oil):
        print(line)
    return 0


def gutter_throw(args, d, g) -> int:
    """``bowl throw`` of a ball that leaves the lane before the pins: the delivery and where it
    left, as a result (exit 0). -o writes that as JSON; a still, video or path plot is not drawn
    (there are no phases), and stderr says so."""
    from dataclasses import asdict

    doc = {"delivery": asdict(d), "oil": str(args.oil), "gutter": {"side": g.side, "ft": round(g.ft, 2)},
           "bowler": args.bowler}
    if args.output:
        write_text_atomic(Path(args.output), dumps_strict(doc, indent=1) + "\n")
    if wants_picture(args) or args.path_plot:
        print("nbst bowl throw: a gutter ball has no phases: no still, video or path plot drawn", file=sys.stderr)
    if args.json:
        print_json(doc)
        return 0
    dd = doc["delivery"]
    print(f"delivery     {dd['hand']}-handed, {dd['mph']:g} mph, {dd['rpm']:g} rpm, board {dd['board']:g} at the "
          f"{'foul line' if dd['at'] == 'foul' else dd['at']}, angle {dd['angle']:.2f} deg; oil {args.oil}" + (f"; bowler {args.bowler}" if args.bowler else ""))
    print(f"gutter ball  it left the lane into the {g.side} gutter {g.ft:.1f} ft past the foul line: no breakpoint "
          "and no pinfall (USBC 6b.1; bowl frame counts it)")
    return 0


def line_lines(ln: dict) -> list[str]:
    """The line (advise.line_of) as readout lines: stance and target, breakpoint, entry and the hit."""
    from nbst.models.bowling.lane.advise import arrow_text

    bp = ("none (the ball never moved out and came back)" if ln["breakpoint_ft"] is None
          else f"{ln['breakpoint_ft']:.1f} ft, board {ln['breakpoint_board']:.1f}")
    return [f"stance       board {ln['stance_board']:.1f} (the ball released on board {ln['foul_board']:.1f}, "
            f"{ln['separation_boards']:g} boards from the slide foot)",
            f"target       {arrow_text(ln['target_board'])} at the arrows, where the ball's path crosses 15 ft",
            f"breakpoint   {bp}",
            f"at the pins  board {ln['entry_board']:.1f}, entry angle {ln['entry_angle_deg']:.1f} deg"
            + (f": {ln['hit']}" if ln.get("hit") else "")]


def throw_lines(r, bowler: str | None = None, oil=None) -> list[str]:
    """The phases of a throw (lane.ThrowResult) as lines, in bowler's units; ``oil`` (the pattern
    thrown on) adds its computed length, volume and ratio."""
    from nbst.models.bowling import lane
    from nbst.models.bowling.lane import advise

    d = r.delivery

    def ft(v):
        return "none" if v is None else f"{v:.1f} ft"

    ln = advise.line_of(r)
    return [
        f"delivery     {d['hand']}-handed, {d['mph']:g} mph, {d['rpm']:g} rpm, rotation {d['rotation']:g} deg, "
        f"tilt {d['tilt']:g} deg, angle {d['angle']:.2f} deg; oil {r.oil}"
        + ("" if oil is None else f" ({lane.pattern(oil).summary()})") + (f"; bowler {bowler}" if bowler else ""),
        f"ball         {r.ball['weight_lb']:g} lb, RG {r.ball['rg']:g} in, diff {r.ball['diff']:g} in, "
        f"cover {r.ball['friction']:g}",
        *line_lines(ln),
        f"skid         {'none (no hook)' if r.skid_ft is None else ft(r.skid_ft) + ' (the hook starts)'}",
        f"roll         {ft(r.roll_ft)}",
        f"speed        {r.speed_pins_mph:.1f} mph at the pins (lost {r.speed_lost_mph:.1f} mph), {r.seconds_to_pins:.2f} s",
        f"note         the ball alone, no noise: {advise.SAMPLE_NOTE} (bowl frame --probability N)",
    ]


def cmd_frame(args) -> int:
    from nbst.models.bowling import lane
    from nbst.models.bowling.lane import frame, noise

    from nbst.models.bowling.lane import advise, names

    try:
        ball = ball_of(args)
        d, bnz = the_delivery(args, args.oil, ball)
        standing = None if args.leave is None else sorted(
            n for n in range(1, 11) if pin_list(args.leave, "--leave") >> (n - 1) & 1)
        if args.output:
            prepare_output(args.output)
        try:
            ball_line = advise.line_of(lane.throw(d, args.oil, ball))   # the ball alone: stance, target, breakpoint
        except lane.GutterBall:
            ball_line = None   # no line to the pins: the frame below counts it (no pinfall, USBC 6b.1)
    except argparse.ArgumentTypeError as e:  # --leave's pins (pin_list words it as argparse would)
        return err("frame", str(e))
    r = lad = est = None
    try:
        r = frame.run_frame(d, args.oil, ball, standing=standing)
        nm = names.names(r.in_play, r.leave, r.board_at_pins, r.entry_angle_deg, d.hand)
        extra = {"bowler": args.bowler, "line": ball_line, "names": nm, "note": advise.SAMPLE_NOTE}
        doc = {"frame": r.to_dict(), **extra}
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
            nz = bnz if bnz is not None else noise.Noise(board=D.board * k, angle=D.angle * k, mph=D.mph * k,
                                                         rpm=D.rpm * k, rotation=D.rotation * k, tilt=D.tilt * k)
            if args.angle_sigma is not None:
                from dataclasses import replace

                nz = replace(nz, angle=float(args.angle_sigma) * k)
            with frame.FrameRunner(args.oil, ball, jobs=args.jobs or default_jobs()) as R:
                est, _ = noise.probability(d, args.probability, args.seed, runner=R, standing=standing, noise=nz,
                                           on_done=lambda: bar.update(1))
            bar.close()
            doc["probability"] = est.to_dict()
    except KeyboardInterrupt:
        if args.output and r is not None:  # the frame is done: keep it (without what was cut short)
            with signals_deferred(reraise=False):
                write_throw(args.output, r, args.oil, ball, ladder=lad, extra=extra)
            print(f"nbst bowl frame: interrupted; wrote the frame without the unfinished parts to {args.output}",
                  file=sys.stderr)
            return 130
        print("nbst bowl frame: interrupted", file=sys.stderr)
        return 130
    if args.output:
        with signals_deferred(reraise=False) as late:
            write_throw(args.output, r, args.oil, ball, ladder=lad, estimate=est, extra=extra)
        if late:
            print(f"nbst bowl frame: interrupted; wrote {args.output}", file=sys.stderr)
            return 130
    if args.json:
        print_json(doc)
        return 0
    for line in frame_lines(doc):
        print(line)
    if args.output:
        print(f"throw file    {args.output} (nbst bowl replay {args.output})")
    return 0


def frame_lines(doc: dict) -> list[str]:
    from nbst.models.bowling.lane import advise, names

    r = doc["frame"]
    what = "strike" if len(r["in_play"]) == 10 and not r["leave"] else ("converted" if not r["leave"] else "")
    out = [f"pins in play  {pins_text(r['in_play'])}",
           f"down          {pins_text(r['down'])}" + (f"  ({what})" if what else ""),
           f"leave         {pins_text(r['leave'])}"]
    if doc.get("names"):
        out.append(f"named         {names.text(doc['names'])}")
    if doc.get("bowler"):
        out.append(f"bowler        {doc['bowler']}")
    if doc.get("line"):
        ln = doc["line"]
        out.append(f"line          stance board {ln['stance_board']:.1f}, target {advise.arrow_text(ln['target_board'])}"
                   + ("" if ln["breakpoint_ft"] is None else
                      f", breakpoint {ln['breakpoint_ft']:.1f} ft on board {ln['breakpoint_board']:.1f}"))
    if r["partition"]:
        out.append(f"dead wood     {pins_text(r['partition'])} leaning on the kickback (USBC 6a.4)")
    if r["ball_left_lane"]:
        out.append("gutter ball   the ball left the lane before the pins: no pinfall (USBC 6b.1)")
    if r["board_at_pins"] is not None:
        out.append(f"entry         board {r['board_at_pins']:.1f} at {r['entry_angle_deg']:.1f} deg (at the deck front, among the pins; "
                   "bowl throw gives the ball alone's at the head pin's line)")
    out.append(f"settled       {'at %.2f s' % r['settle_s'] if r['settled'] else 'no: counted at the sweep, %.2f s' % r['seconds']}"
               + (f" (the ball passed the pins in the gutter at {r['ball_at_pins_s']:.2f} s)" if r["ball_left_lane"]
                  else f" (ball at the head pin {r['ball_at_pins_s']:.2f} s)") if r["ball_at_pins_s"] is not None else
               f"settled       {'at %.2f s' % r['settle_s'] if r['settled'] else 'no: counted at the sweep'}")
    if "longer" in doc:
        g = doc["longer"]
        out.append(f"{g['extra_s']:g} s longer  leave {pins_text(g['leave'])}: {'same' if g['same'] else 'CHANGED'}")
    for x in doc.get("ladder", []):
        out.append(f"h = {1000 * x['timestep']:g} ms".ljust(14) + f"leave {pins_text(x['leave'])}"
                   + (f", settled at {x['settle_s']:.2f} s" if x["settle_s"] is not None else ", counted at the sweep"))
    if "probability" in doc:
        e = doc["probability"]
        top = ", ".join(f"{k or 'none'} {v}" for k, v in list(e["leaves"].items())[:5])
        done = "strikes" if len(r["in_play"]) == 10 else "converted"   # a full rack's every pin down is a strike
        out.append(f"probability   {100 * e['p']:.0f}% {done} ({e['k']}/{e['n']}; 95% CI {100 * e['lo']:.0f}-"
                   f"{100 * e['hi']:.0f}%), seed {e['seed']}; leaves: {top}")
        out.append(f"note          {advise.SAMPLE_NOTE}, as above")
    else:
        out.append(f"note          {advise.SAMPLE_NOTE}: run --probability N for it")
    return out


def replay_throw(args) -> int:
    """``bowl replay THROW.json``: the frame again from the foul line; exit 1 if its pins down differ.
    With --video/--still, the frame is recorded as it runs (one run) and filmed with the file's readout."""
    from nbst.models.bowling.lane import throwfile
    from nbst.render.bowling import throw as bowling_throw

    picture = wants_picture(args)
    r: Any  # the replayed frame (a FrameResult), from the replay or from the recording
    if not picture:
        d, r, ok = throwfile.replay_file(args.file)
    else:
        from nbst.models.bowling import lane
        from nbst.models.bowling.lane import frame

        bad = check_picture_args(args)
        if bad:
            return err("replay", bad)
        for option, path in (("--video", args.video), ("--still", args.still)):
            if path:  # before the replay: a link, a FIFO or a folder is refused in one line
                prepare_output(path, option=option)
        d = throwfile.load(args.file)
        throwfile.replayable(d, args.file)  # another scene's throw: one line
        try:   # the replay of throwfile.replay, recorded: its model, oil, ball, pins standing and timestep
            th = bowling_throw.record_throw(lane.Delivery(**d["delivery"]), throwfile.oil_of(d),  # type: ignore[arg-type]
                                           lane.Ball(**d["ball"]),
                                           standing=d["standing"], timestep=float(d["outcome"]["timestep"]))
        except (lane.LaneError, frame.FrameError, MujocoError) as e:
            return err("replay", f"{args.file}: delivery: {e}")
        r = th.frame
        ok = r.down == sorted(d["outcome"]["down"])
    want = sorted(d["outcome"]["down"])
    if args.json:
        print_json({"throw": str(args.file), "down": r.down, "expected": want, "leave": r.leave,
                    "expected_leave": sorted(d["outcome"]["leave"]), "match": ok})
    else:
        from nbst.models.bowling.lane import advise, names

        nm = names.names(r.in_play, r.leave, r.board_at_pins, r.entry_angle_deg, d["delivery"]["hand"])
        print(f"pins down  {','.join(map(str, r.down)) or 'none'}  (leave {pins_text(r.leave)})")
        print(f"expected   {','.join(map(str, want)) or 'none'}  ({'match' if ok else 'DIFFERENT'})")
        print(f"named      {names.text(nm)}")
        print(f"note       {advise.SAMPLE_NOTE}")
    if picture:
        bad = write_pictures(args, th, prog="nbst bowl replay", **bowling_throw.throw_file_readout(d))
        if bad:
            return err("replay", bad)
    return 0 if ok else 1


def write_pictures(args, th, *, prog: str = "nbst bowl throw", **readout) -> str | None:
    """Write ``args.still`` and/or ``args.video`` (flags checked by :func:`check_picture_args`) of
    the recorded throw ``th``; ``readout``: LaneRenderer's asked, probability, probability_note,
    expected, no_request. A progress line on stderr for the video and one line per file written. Returns a
    one-line error, or None."""
    from nbst.render.core import style
    from nbst.render.bowling.lane import render_throw
    from nbst.render.bowling.throw import throw_times
    from nbst.render.core.gl import RenderError

    size = size_of(args.size) if getattr(args, "size", None) else None
    st = getattr(args, "still_time", None)
    camera = getattr(args, "camera", None) or "both"
    if st is not None and st > th.motion.times[-1]:
        return f"--still-time {st:g}: the throw lasts {th.motion.times[-1]:.2f} s"
    try:
        if getattr(args, "still", None):
            prepare_output(args.still, option="--still")
            render_throw(th, args.still, still=-1.0 if st is None else float(st), size=size, camera=camera,
                         clean=bool(getattr(args, "clean", False)), **readout)
            print(f"{prog}: wrote {args.still}", file=sys.stderr)
        if getattr(args, "video", None):
            prepare_output(args.video, option="--video")
            fps = float(getattr(args, "fps", None) or style.DEFAULT_FPS)

            bar = progress_bar(total=len(throw_times(th, fps)), unit="frame", file=sys.stderr, desc="render")
            try:
                n = render_throw(th, args.video, size=size, fps=fps, progress=bar, camera=camera,
                                 clean=bool(getattr(args, "clean", False)), **readout)
            finally:
                bar.close()
            print(f"{prog}: wrote {args.video} ({n} frames)", file=sys.stderr)
    except (OutputError, RenderError) as e:
        return str(e)
    return None


def picture_from_args(args, delivery, ball) -> str | None:
    """``nbst bowl throw --video/--still``: record the throw's frame on all ten pins (as ``bowl
    frame`` runs it) and write the video and/or the still. Returns a one-line error, or None."""
    from nbst.models.bowling import lane
    from nbst.models.bowling.lane import frame
    from nbst.render.bowling.throw import record_throw

    bad = check_picture_args(args)
    if bad:
        return bad
    try:
        th = record_throw(delivery, args.oil, ball)
    except (lane.LaneError, frame.FrameError, MujocoError) as e:
        return str(e)
    return write_pictures(args, th)
