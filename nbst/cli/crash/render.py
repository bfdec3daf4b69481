"""``nbst render CRASH.json -o crash.mp4`` (``nbst render``, :mod:`nbst.cli.render`, dispatches
here on a crash file).

A crash file from ``nbst crash solve`` is filmed from its own replay (docs/render.md, "A
crash"): ``--camera overhead`` (the default) a true-scale view from above; ``--follow NAME`` a
chase camera behind that vehicle beside the overhead view (``--camera behind``: the chase view
alone); ``--still T`` a PNG of the frame at T seconds; ``--clean`` no overlay text (the views
fill the frame). The video runs in real time, 4x slower around each impact, then holds the last
frame ``--hold`` seconds.

Exit codes: 0 written, 2 bad input (one line), 130 interrupted (no partial file is left).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from nbst.cli.args import Size
from nbst.domain import plain
from nbst.outputs import prepare_output, sigterm_as_interrupt
from nbst.progress import Bar, command_start, count_text, seconds_text

__all__ = ["DISK_ONLY_FLAGS", "FPS_MAX", "check_flags", "cmd_render_crash"]

#: Flags of ``nbst render`` that draw disk problems only; an error on a crash file.
DISK_ONLY_FLAGS = (("trails", False, "--trails"), ("labels", None, "--labels"), ("view", None, "--view"),
                   ("source", None, "--source"), ("speed", None, "--speed"))
FPS_MAX = 240.0


def _err(msg: str) -> int:
    print(f"nbst render: error: {plain(msg)}", file=sys.stderr)
    return 2


def check_flags(args) -> str | None:
    """The first problem with the flags of ``nbst render CRASH.json``, as one line, or None."""
    given = [flag for attr, default, flag in DISK_ONLY_FLAGS if getattr(args, attr, default) not in (default, None)]
    if given:
        return (f"{', '.join(given)} draw{'s' if len(given) == 1 else ''} disk problems only; a crash file takes "
                f"-o, --still, --camera, --follow, --clean, --size, --fps, --hold, --max-frames and -q")
    if getattr(args, "solution", None) is not None:
        return f"a crash file is rendered alone: drop {args.solution!r}"
    out = str(args.output)
    if args.still is not None and not out.lower().endswith(".png"):
        return f"-o {out}: --still writes a PNG image; give a .png name"
    if args.still is None and not out.lower().endswith((".mp4", ".m4v", ".mov", ".gif")):
        return f"-o {out}: use a .mp4 or .gif file (or --still T with a .png)"
    if args.fps is not None and not (0 < args.fps <= FPS_MAX):
        return f"--fps {args.fps:g}: must be in (0, {FPS_MAX:g}] frames per second"
    if not (0 <= args.hold <= 60):
        return f"--hold {args.hold:g}: must be in [0, 60] seconds"
    size = args.size
    if size is not None and out.lower().endswith((".mp4", ".m4v", ".mov")) and (size[0] % 2 or size[1] % 2):
        return f"--size {size[0]}x{size[1]}: H.264 (yuv420p) needs an even width and height"
    return None


def cmd_render_crash(args) -> int:
    """``nbst render CRASH.json -o OUT [--still T] [--camera C] [--follow NAME] [--clean] [--size WxH] [--fps F]
    [--hold S] [--max-frames N] [-q]``: every flag is checked against the file before the replay."""
    from nbst.models.crash import crashfile

    from nbst.render.core import style
    from nbst.render.crash.video import render_crash
    from nbst.render.core.times import MAX_FRAMES, frame_times
    from nbst.render.crash.motion import SLOW, impact_times, record, slow_windows

    if isinstance(args.size, str):
        try:
            args.size = Size()(args.size)
        except argparse.ArgumentTypeError as e:
            return _err(f"--size: {e}")
    bad = check_flags(args)
    if bad:
        return _err(bad)
    camera = args.camera or ("both" if args.follow is not None else "overhead")
    if args.follow is not None and camera == "overhead":
        return _err("--follow sets the chase camera, which --camera overhead does not draw; use --camera both or "
                    "behind")
    d, script, model = crashfile.load(args.problem)   # CrashFileError: one line naming the field
    names = script.names()
    if args.follow is not None and args.follow not in names:
        return _err(f"--follow {args.follow!r}: no vehicle of that name in {args.problem} ({', '.join(names)})")
    follow = names.index(args.follow) if args.follow is not None else 0
    if args.still is not None and not (0 <= args.still <= script.duration):
        return _err(f"--still {args.still:g}: must lie in [0, {script.duration:g}] seconds (the crash's duration)")
    out = Path(args.output)
    kind = "png" if args.still is not None else ("gif" if out.suffix.lower() == ".gif" else "mp4")
    size = tuple(args.size) if args.size else (style.GIF_SIZE if kind == "gif" else style.DEFAULT_SIZE)
    fps = float(args.fps) if args.fps is not None else float(style.GIF_FPS if kind == "gif" else style.DEFAULT_FPS)
    # the frames, from the file's impacts (the replay's, when it reproduces the file)
    realtime = bool(getattr(args, "realtime", False))
    times = frame_times(script.duration, fps, windows=[] if realtime else slow_windows(impact_times(d["outcome"]),
                                                                                       script.duration),
                        slow=SLOW, hold=args.hold)
    limit = args.max_frames or MAX_FRAMES
    if kind != "png" and len(times) > limit:
        return _err(f"{len(times):,} frames at --fps {fps:g}; at most {limit:,} (--max-frames)")
    prepare_output(out, inputs=(args.problem,))
    bar = None
    if kind != "png":  # the bar counts from the command's start: the replay shows in it
        bar = Bar(f"nbst render: {out.name}", len(times), unit="frame", file=sys.stderr, quiet=args.quiet,
                  start=command_start())
        bar.note(f"replaying {script.n} vehicles for {script.duration:g} s")
    try:
        motion = record(d, script, model)
        windows = [] if realtime else slow_windows([im.t for im in motion.impacts], motion.duration)
        if bar is not None:  # a video
            times = frame_times(motion.duration, fps, windows=windows, slow=SLOW, hold=args.hold)
            bar.total = len(times)
            bar.note("")
        with sigterm_as_interrupt():   # kill: the partial video is removed as on Ctrl-C
            n = render_crash(d, script, model, motion, out, still=args.still, camera=camera, follow=follow,
                             size=size, fps=fps, times=times, progress=bar, clean=bool(getattr(args, "clean", False)),
                             realtime=realtime)
    except BaseException:
        if bar is not None:
            bar.close()
        raise
    same = "the replay reproduces the file bit for bit" if motion.identical else f"WARNING: {motion.differs()}"
    if bar is not None:
        bar.close(n=n)
    if args.quiet:
        return 0
    if bar is None:  # a still
        print(f"nbst render: wrote {out} ({size[0]}x{size[1]}, t = {args.still:g} s); {same}", file=sys.stderr)
    else:
        k = len(motion.impacts)
        slow = f", {SLOW:g}x slow motion around {k} impact{'s' if k != 1 else ''}" if windows else ""
        print(f"nbst render: wrote {out}: {count_text(n)} frames, {size[0]}x{size[1]}, {fps:g} fps, {n / fps:.2f} s of "
              f"video{slow}, in {seconds_text(bar.seconds)}; {same}", file=sys.stderr)
    return 0
