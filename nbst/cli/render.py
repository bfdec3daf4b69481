"""``nbst render`` (video or still) and ``nbst plot`` (the paper's figures).

Registration is light: moderngl, imageio, matplotlib and the simulator load
inside the command functions. Length: one command's flags and its dispatch to every kind of
file (2D, crash, 5 m throw, scene); split, a flag's kinds would be read in two places.
"""
from __future__ import annotations

import argparse
import sys

from pathlib import Path

import numpy as np

from nbst.cli.args import Bounded, Size, exact_motion, with_limits
from nbst.domain import plain
from nbst.errors import InputError, RenderError
from nbst.outputs import atomic_path, prepare_output, sigterm_as_interrupt
from nbst.problem import builtin_names, load_problem
from nbst.progress import Bar, command_start, count_text, progress_bar, seconds_text
from nbst.render.bowling.deck import (DISK_ONLY_FLAGS, FPS_MAX, bowling_kind, is_throw_file, load_motion, motion_times,
                                      render_motion)
from nbst.render.core import style
from nbst.render.core.gl import create_context
from nbst.render.core.times import MAX_FRAMES, frame_count, frame_times
from nbst.render.core.video import render_video, write_png
from nbst.render.crash.video import crash_kind
from nbst.render import figures
from nbst.render.motion2d import SampledMotion
from nbst.render.scene2d import Renderer2D, auto_labels
from nbst.render.scene3d import Renderer3D
from nbst.solution import load_solution, named_problem

__all__ = ["CAMERAS", "COMMANDS", "OUTPUT_SUFFIXES", "TAKES", "check_render_args", "cmd_plot_problem",
           "cmd_plot_trajectories", "cmd_render", "cmd_render_throw", "make_renderer", "mujoco_positions", "parse_size", "register"]

FPS = Bounded("fps", 0.0, 240.0, lo_open=True)
SPEED = Bounded("speed", 0.0, 1e6, lo_open=True)
HOLD = Bounded("hold", 0.0, 60.0, unit="s")
STILL = Bounded("still time", 0.0, 1e6, unit="s")
MAX_FRAMES_FLAG = Bounded("max frames", 1, 10_000_000, integer=True)
DPI = Bounded("dpi", 10, 1200, integer=True)
SIZE = Size()

#: The top-level commands this module registers, with their help lines: ``nbst --help`` lists
#: them without building their arguments (nbst.cli.main builds only the command asked for).
COMMANDS = {
    "render": "render a solution's motion to MP4, GIF or a PNG still (headless OpenGL)",
    "plot": "draw the paper's figures (problem; trajectories) with matplotlib",
}


def register(sub) -> None:
    p = sub.add_parser("render", help=COMMANDS["render"],
        description="Render the motion of PROBLEM under the initial velocities in SOLUTION: disks\n"
                    "(amber cueable, blue noncueable), target markers, target rings of radius R that\n"
                    "light up while their disk is inside, a time readout. Positions are exact at every\n"
                    "frame (the event-driven simulator). The output's extension picks the format:\n"
                    ".mp4 (H.264, yuv420p, plays everywhere) or .gif; with --still T, a .png of the\n"
                    "frame at time T. Headless: OpenGL through EGL, no display or GPU needed.\n\nPROBLEM alone may "
                    "instead be a crash file (nbst crash solve), a bowling 5 m throw\nfile (nbst bowl solve) or a scene "
                    "solution (nbst scene solve: any MJCF, every geom in its\ncolours, the fates' regions and a readout "
                    "of asked and happened; docs/scene.md), each\ndrawn in 3D.",
        epilog="examples:\n  nbst render diamond-s14 sol.json -o out/diamond.mp4 --trails\n"
               "  nbst render tbone.json -o tbone.mp4 --follow A         # a crash file (nbst crash solve)\n"
               "  nbst render over5 sol.json -o out/over5.gif\n"
               "  nbst render diamond-s14 sol.json --still 0 -o out/start.png\n"
               "  nbst render diamond-s14 sol.json -o out/check.mp4 --source both   # MuJoCo replay as rings\n"
               "  nbst render sol.json -o dice.mp4                       # a scene solution (nbst scene solve)",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("problem", help="built-in name or path to a problem JSON file (or a crash file from `nbst crash "
                                   "solve`, rendered in 3D alone, docs/render.md; or a scene solution from `nbst "
                                   "scene solve`, alone, docs/scene.md)")
    p.add_argument("solution", nargs="?",
                   help="path to a solution JSON file (e.g. from `nbst solve`); omit it when PROBLEM is a bowling "
                        "5 m throw file from `nbst bowl solve` (rendered in 3D, docs/bowling.md)")
    p.add_argument("-o", "--output", metavar="PATH", help="output file (required): .mp4, .gif, or .png with --still")
    p.add_argument("--camera", default=None, metavar="CAMERA",
                   help="5 m bowling throws: behind the ball, overhead, or both side by side (default both); "
                        "crash files: overhead (default), behind the --follow vehicle, or both; scene "
                        "solutions: the name of one of the scene's own cameras (default: one that frames the "
                        "bodies)")
    p.add_argument("--clean", action="store_true",
                   help="no overlay text (no readout, legend, titles, names or labels): the picture alone, for "
                        "compositing; every kind of input")
    p.add_argument("--realtime", action="store_true",
                   help="crash and 5 m throw files: no slow motion at the impacts (each frame 1/fps of the motion, "
                        "as `nbst export --gltf` keys it: a clean plate that lines up with the glTF); the other "
                        "kinds' videos are real time already (--speed slows a 2D one)")
    p.add_argument("--follow", default=None, metavar="NAME",
                   help="crash files only: a chase camera behind vehicle NAME, beside the overhead view")
    p.add_argument("--fps", type=FPS, default=None,
                   help=with_limits(f"frames per second (default {style.DEFAULT_FPS}; {style.GIF_FPS} for .gif)", FPS))
    p.add_argument("--size", type=SIZE, default=None, metavar="WxH",
                   help="frame size in pixels (default %dx%d; %dx%d for .gif) [%s]" % (*style.DEFAULT_SIZE,
                                                                                   *style.GIF_SIZE, SIZE.limits))
    p.add_argument("--speed", type=SPEED, default=None,
                   help=with_limits("simulated seconds per second of video (default 1.0; 0.5 = slow motion)", SPEED))
    p.add_argument("--hold", type=HOLD, default=1.0, metavar="SECONDS",
                   help=with_limits("seconds of video holding the final frame (default 1.0)", HOLD))
    p.add_argument("--trails", action="store_true", help="draw each disk's recent path, fading with age")
    p.add_argument("--labels", action=argparse.BooleanOptionalAction, default=None,
                   help="write each disk's index on it, and beside each target the index of its disk (default: "
                        "on when every disk is at least %g px across in the frame, where a number stays legible; "
                        "off for smaller disks, e.g. 1,000 disks at 720p; --labels and --no-labels decide "
                        "instead)" % style.LABELS_MIN_DISK_PX)
    p.add_argument("--view", choices=["2d", "3d"], default=None,
                   help="2d: the box from above (default); 3d: pucks on a table, perspective camera, lighting")
    p.add_argument("--source", choices=["analytic", "mujoco", "both"], default=None,
                   help="positions from the exact simulator (default), from a MuJoCo replay, or both "
                        "(MuJoCo drawn as white rings over the exact disks, numbered with --labels; the readout "
                        "counts both)")
    p.add_argument("--still", type=STILL, default=None, metavar="T",
                   help="write only the frame at time T (seconds, in [0, t_final]; for a bowling throw in [0, its "
                        f"duration]) to a .png [{STILL.limits}]")
    p.add_argument("--max-frames", type=MAX_FRAMES_FLAG, default=None, metavar="N",
                   help=with_limits("refuse a video of more than N frames (default 108,000: 30 minutes at 60 fps)",
                                    MAX_FRAMES_FLAG))
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar or summary")
    p.set_defaults(func=cmd_render)

    p = sub.add_parser("plot", help=COMMANDS["plot"],
                       description="Figures in the manner of the paper: `plot problem` as its Figures 1-2 (disks "
                                   "at their starts, small circles at the targets, arrows start -> target, broken "
                                   "for noncueable disks); `plot trajectories` as its Figures 3-4 (each disk's path, "
                                   "wall bounces and disk-disk collisions marked). The marks mean what they mean in "
                                   "the video: amber cueable, blue noncueable; numbers are disk indices, on each disk "
                                   "at its start and beside its target; a legend below the box says the rest. The "
                                   "extension picks the format (.png, .pdf, .svg).")
    psub = p.add_subparsers(dest="what", metavar="WHAT", required=True)
    q = psub.add_parser("problem", help="starts, targets and arrows (the paper's Figures 1-2)",
                        description="Draw PROBLEM as the paper's Figures 1-2: each disk at its start (amber "
                                    "cueable, blue noncueable, numbered), a small circle at each target with the "
                                    "index of its disk beside it, the target neighbourhood of radius R, and an "
                                    "arrow from each start to its target (broken for noncueable disks). A legend "
                                    "below the box says what each mark means. The extension of -o picks the "
                                    "format: .png (raster, --dpi), .pdf or .svg (vector).")
    q.add_argument("problem", help="built-in name or path to a problem JSON file")
    q.add_argument("-o", "--output", required=True, metavar="PATH", help="output image (.png, .pdf, .svg)")
    q.add_argument("--dpi", type=DPI, default=150, help=with_limits("resolution of raster output (default 150)", DPI))
    q.add_argument("-q", "--quiet", action="store_true", help="no summary line")
    q.set_defaults(func=cmd_plot_problem)
    q = psub.add_parser("trajectories", help="the disks' paths with bounces and collisions (Figures 3-4)",
                        description="Simulate SOLUTION on PROBLEM exactly and draw it as the paper's Figures 3-4: "
                                    "each disk's path from its start to where it ends at t_final, marks where it "
                                    "bounces off a wall and where two disks collide, and the targets with their "
                                    "neighbourhoods of radius R, so a glance shows which disks end on target. "
                                    "Colours and numbers as in `plot problem` and the video; a legend below the "
                                    "box. The extension of -o picks the format: .png (--dpi), .pdf or .svg.")
    q.add_argument("problem", help="built-in name or path to a problem JSON file")
    q.add_argument("solution", help="path to a solution JSON file")
    q.add_argument("-o", "--output", required=True, metavar="PATH", help="output image (.png, .pdf, .svg)")
    q.add_argument("--dpi", type=DPI, default=150, help=with_limits("resolution of raster output (default 150)", DPI))
    q.add_argument("-q", "--quiet", action="store_true", help="no summary line")
    q.set_defaults(func=cmd_plot_trajectories)


def _err(cmd: str, msg: str) -> int:
    print(f"nbst {cmd}: error: {msg}", file=sys.stderr)
    return 2


def parse_size(s: str) -> tuple[int, int]:
    """'1280x720' -> (1280, 720); InputError (a ValueError) with a one-line reason otherwise."""
    parts = s.lower().replace("*", "x").split("x")
    if len(parts) != 2 or not all(x.strip().isdigit() for x in parts):
        raise InputError(f"--size {s!r}: expected WIDTHxHEIGHT in pixels, e.g. 1280x720")
    w, h = int(parts[0]), int(parts[1])
    if not (16 <= w <= 8192 and 16 <= h <= 8192):
        raise InputError(f"--size {s}: width and height must be 16..8192 pixels")
    return w, h


#: The files ``nbst render`` writes, by extension (the help lists them; anything else is refused).
OUTPUT_SUFFIXES = (".mp4", ".gif", ".png")
#: What ``nbst render`` takes, said when it is given something else.
TAKES = ("nbst render takes a problem (a built-in name or a problem .json) and its solution (or the solution "
         "alone: the problem it names), a crash file (`nbst crash solve`), a 5 m bowling throw file (`nbst bowl "
         "solve`), or a scene solution (`nbst scene solve`)")
#: The cameras of the crash and the 5 m throw videos (a scene solution's are its model's, by name).
CAMERAS = ("behind", "overhead", "both")


def check_render_args(args) -> int | None:
    """Exit status 2 (after one line) when the input file is missing or the output is not a file
    ``nbst render`` writes, else None; before any work, for every kind of input."""
    if not Path(args.problem).exists() and args.problem not in builtin_names():
        return _err("render", f"{args.problem}: no such file, and no built-in problem of that name; {TAKES}")
    if args.output is None:
        return _err("render", "-o PATH is required: the .mp4 or .gif to write (or a .png with --still T)")
    ext = Path(args.output).suffix.lower()
    if ext not in OUTPUT_SUFFIXES:
        return _err("render", f"-o {args.output}: unknown output format {ext or '(no extension)'!r}; "
                              f"use .mp4 or .gif, or .png with --still T")
    return None


def cmd_render(args) -> int:
    bad = check_render_args(args)
    if bad is not None:
        return bad
    from nbst.render.scene.video import is_scene_solution

    if is_scene_solution(args.problem):  # sniffs the first bytes only; the solution's reader checks it
        from nbst.cli.render_scene import cmd_render_scene

        return cmd_render_scene(args)
    if args.camera is not None and args.camera not in CAMERAS:
        return _err("render", f"--camera {args.camera}: use {', '.join(CAMERAS)} (a camera by name: scene "
                              f"solutions only)")
    ck = crash_kind(args.problem)  # sniffs the first bytes only; the crash file's gate reads it, capped
    if ck == "crash":
        from nbst.cli.crash.render import cmd_render_crash

        return cmd_render_crash(args)
    if ck == "script":
        return _err("render", f"{args.problem} is a crash script; solve it first (`nbst crash solve "
                              f"{args.problem} -o crash.json`), then render the crash file")
    if args.follow is not None:
        return _err("render", "--follow applies to crash files only (from `nbst crash solve`)")
    if is_throw_file(args.problem):  # sniffs the first bytes only; the throw loader reads it, capped
        return cmd_render_throw(args)  # disk-only flags (--trails, --view, ...) are an error there
    from nbst.files import sniff_kind
    from nbst.models.bowling.lane.throwfile import FORMAT as LANE_FORMAT

    if sniff_kind(args.problem, (("lane", LANE_FORMAT),)) == "lane":  # a foul-line throw: its own command films it
        return _err("render", f"{args.problem} is a foul-line throw file: film it with `nbst bowl replay "
                              f"{args.problem} --video OUT.mp4` (or --still OUT.png; --camera, --clean as here)")
    args.view, args.source = args.view or "2d", args.source or "analytic"
    args.speed = 1.0 if args.speed is None else args.speed
    if args.solution is None and (named := named_problem(args.problem)) is not None:
        args.problem, args.solution = named, args.problem  # a 2D solution alone: the problem it names, as export
    if args.solution is None:   # a fates file or an MJCF gets its own line: solve it first
        from nbst.cli.render_scene import unsolved_scene
        return _err("render", unsolved_scene(args.problem) or f"{args.problem} is a problem: give its SOLUTION; {TAKES}")
    if args.camera is not None:
        return _err("render", "--camera applies to 5 m bowling throw files only")

    out = Path(args.output)
    ext = out.suffix.lower()
    if args.still is not None:
        if ext != ".png":
            return _err("render", f"--still writes a PNG image; give -o with a .png name, not {out.name!r}")
        kind = "png"
    elif ext == ".png":
        return _err("render", f"{out.name}: a .png output needs --still T (the time of the frame)")
    else:
        kind = "gif" if ext == ".gif" else "mp4"
    size = (parse_size(args.size) if isinstance(args.size, str) else args.size) if args.size else \
        (style.GIF_SIZE if kind == "gif" else style.DEFAULT_SIZE)  # a bad text: InputError, main's one line
    if kind == "mp4" and (size[0] % 2 or size[1] % 2):
        return _err("render", f"--size {size[0]}x{size[1]}: H.264 (yuv420p) needs an even width and height")
    fps = args.fps if args.fps is not None else (style.GIF_FPS if kind == "gif" else style.DEFAULT_FPS)
    if not (0 < fps <= 240):
        return _err("render", f"--fps {fps:g}: must be in (0, 240]")
    if not (args.speed > 0 and args.speed < 1e6):
        return _err("render", f"--speed {args.speed:g}: must be > 0")
    if not (0 <= args.hold <= 60):
        return _err("render", f"--hold {args.hold:g}: must be in [0, 60] seconds")

    problem = load_problem(args.problem)
    sol = load_solution(args.solution, problem)
    tr = exact_motion(problem, args.solution, sol.velocities)  # one line, before any work, if it truncates
    if args.still is not None and not (0 <= args.still <= problem.t_final):
        return _err("render", f"--still {args.still:g}: must lie in [0, t_final = {problem.t_final:g}] seconds")
    # bounded work, before any: frames (and the MuJoCo replay's steps) grow with t_final
    if kind != "png":
        if args.max_frames is not None and args.max_frames < 1:
            return _err("render", f"--max-frames {args.max_frames}: must be >= 1")
        limit = args.max_frames or MAX_FRAMES
        n = frame_count(problem.t_final, fps, speed=args.speed, hold=args.hold)
        if n > limit:
            return _err("render", f"t_final = {problem.t_final:g} s at {fps:g} fps and --speed {args.speed:g} is "
                                  f"{n:,} frames, over the limit of {limit:,}; raise it with --max-frames N, or "
                                  f"shorten the video with a higher --speed (simulated seconds per second of "
                                  f"video) or a lower --fps")
    if args.source != "analytic":
        try:
            from nbst.models.mjrun import check_steps
            from nbst.models.scene import DEFAULT_TIMESTEP
        except ImportError:
            pass  # no MuJoCo replay in this install: mujoco_positions says so
        else:  # past the limit: InputError, main's one line
            check_steps(problem.t_final, DEFAULT_TIMESTEP, hint="the MuJoCo replay cannot cover it: use "
                        "--source analytic")
    prepare_output(out, inputs=(args.problem, args.solution))
    try:
        with sigterm_as_interrupt():  # kill: the partial video is removed as on Ctrl-C
            return _render(args, problem, tr, out, kind, size, fps)
    except RenderError as e:
        return _err("render", str(e))


def _render(args, problem, tr, out, kind, size, fps) -> int:


    if kind == "png":
        times = np.array([float(args.still)])
    else:
        times = frame_times(problem.t_final, fps, speed=args.speed, hold=args.hold)
    # the bar counts from the command's start: setting up GL (and the MuJoCo replay) shows in it
    bar = None if kind == "png" else Bar(f"nbst render: {out.name}", len(times), unit="frame", file=sys.stderr,
                                          quiet=args.quiet, start=command_start())
    try:
        motion, ghost = tr, None
        if args.source in ("mujoco", "both"):
            sample_t = np.unique(np.concatenate((times, frame_times(problem.t_final, 120.0))))
            if bar is not None:
                bar.note(f"replaying {problem.n} disks for {problem.t_final:g} s in MuJoCo")
            elif not args.quiet:
                print(f"nbst render: replaying {problem.n} disks for {problem.t_final:g} s in MuJoCo ...",
                      file=sys.stderr, flush=True)
            mj = SampledMotion(sample_t, mujoco_positions(problem, tr.initial_velocities, sample_t))
            motion, ghost = (mj, None) if args.source == "mujoco" else (tr, mj)
        if bar is not None:
            bar.note("")
        ctx = create_context()
        try:
            renderer = make_renderer(ctx, problem, motion, view=args.view, size=size, trails=args.trails,
                                     ghost=ghost, labels=args.labels,
                                     motion_name="MuJoCo" if args.source == "mujoco" else None,
                                     clean=bool(getattr(args, "clean", False)))
            if kind == "png":
                write_png(out, renderer.render(float(args.still)))
                if not args.quiet:
                    print(f"nbst render: wrote {out} ({size[0]}x{size[1]}, t = {args.still:g} s)"
                          f"{_labels_note(args, renderer)}", file=sys.stderr)
                return 0
            n = render_video(renderer, times, out, fps=fps, progress=bar)
        finally:
            ctx.release()
    except BaseException:
        if bar is not None:
            bar.close()
        raise
    assert bar is not None  # a video (a still returned above)
    bar.close(n=n)
    if not args.quiet:
        print(f"nbst render: wrote {out}: {count_text(n)} frames, {size[0]}x{size[1]}, {fps:g} fps, "
              f"{n / fps:.2f} s of video, in {seconds_text(bar.seconds)}{_labels_note(args, renderer)}",
              file=sys.stderr)
    return 0


def _labels_note(args, renderer) -> str:
    """Why the disks carry no numbers, when the size rule (not the user) left them off."""
    rpx = getattr(renderer, "rpx", None)
    if getattr(args, "clean", False) or args.labels is not None or getattr(renderer, "labels", None) is not None or rpx is None:
        return ""
    return (f"; no disk numbers: disks {2 * float(min(rpx)):.0f} px across, under the {style.LABELS_MIN_DISK_PX:g} "
            f"px they need (--labels writes them anyway)")


def make_renderer(ctx, problem, motion, *, view="2d", size=style.DEFAULT_SIZE, trails=False, ghost=None,
                  labels=False, motion_name=None, clean=False):
    """A 2D or 3D renderer with ``render(t, out=None) -> (H, W, 3) uint8`` and ``size``.
    labels: True, False, or None (only where legible: :func:`nbst.render.scene2d.labels_legible`).
    motion_name: what the disks show when it is not the exact motion ("MuJoCo" for --source mujoco).
    clean: no text at all (no readout, legend or numbers: ``labels`` is then off)."""
    if clean:
        labels = False
    if view == "3d":
        if labels is None:
            labels = auto_labels(problem, size)
        return Renderer3D(ctx, problem, motion, size=size, trails=trails, ghost=ghost, labels=labels,
                          motion_name=motion_name, clean=clean)
    return Renderer2D(ctx, problem, motion, size=size, trails=trails, ghost=ghost, labels=labels,
                      motion_name=motion_name, clean=clean)


def mujoco_positions(problem, velocities, times):
    """Disk centres (T, N, 2) from the MuJoCo replay, or a one-line RenderError."""
    try:
        from nbst.models import rollout
    except ImportError:
        raise RenderError("--source mujoco/both needs the MuJoCo replay (nbst.models.rollout), which this "
                          "install does not have yet; use --source analytic") from None
    return rollout(problem, velocities, times)


def _not_bowling(args) -> int | None:
    """Exit 2 with one line when PROBLEM is a bowling throw or atlas file (not a disk problem)."""

    kind = bowling_kind(args.problem)
    if kind:
        how = (f"draw it with `nbst render {args.problem} -o throw.mp4`" if kind == "throw" else
               f"`nbst bowl atlas --from {args.problem} --out-dir DIR` draws it as DIR/summary.png")
        return _err("plot", f"{args.problem}: this is a bowling {kind} file, not a disk problem; {how} "
                            f"(docs/bowling.md)")
    return None


def cmd_plot_problem(args) -> int:

    if (rc := _not_bowling(args)) is not None:
        return rc

    problem = load_problem(args.problem)
    fig = figures.plot_problem(problem)
    return _save(fig, args, figures.save_figure)


def cmd_plot_trajectories(args) -> int:

    if (rc := _not_bowling(args)) is not None:
        return rc

    problem = load_problem(args.problem)
    sol = load_solution(args.solution, problem)
    fig = figures.plot_trajectories(problem, exact_motion(problem, args.solution, sol.velocities))
    return _save(fig, args, figures.save_figure)


def _save(fig, args, save_figure) -> int:
    if not 10 <= args.dpi <= 1200:
        return _err("plot", f"--dpi {args.dpi}: must be in 10..1200")
    ext = Path(args.output).suffix.lower()
    if ext not in (".png", ".pdf", ".svg"):
        return _err("plot", f"{Path(args.output).name}: unknown figure format {ext or '(no extension)'!r}; "
                            "use .png, .pdf or .svg")
    prepare_output(args.output, inputs=(getattr(args, "problem", None), getattr(args, "solution", None)))
    with atomic_path(args.output) as tmp:  # a full disk leaves the previous figure, not a 0-byte one
        save_figure(fig, tmp, dpi=args.dpi)
    if not getattr(args, "quiet", False):
        kind = f"PNG, {args.dpi} dpi" if ext == ".png" else ext[1:].upper()
        print(f"nbst plot: wrote {args.output} ({kind})", file=sys.stderr)
    return 0


# --------------------------------------------------------------------------- bowling (H2's)


def _check_throw_flags(args, duration: float | None = None) -> str | None:
    """The first problem with ``nbst render THROW.json``'s flags (a 5 m throw file), as one line, or None."""

    given = [flag for attr, default, flag in DISK_ONLY_FLAGS
             if getattr(args, attr, default) not in (default, None, False)]
    if given:
        return (f"{', '.join(given)} draw{'s' if len(given) == 1 else ''} disk problems only; a 5 m throw file "
                f"takes -o, --still, --camera, --clean, --realtime, --size, --fps, --hold, --max-frames and -q")
    fps = getattr(args, "fps", None)
    if fps is not None and not (0 < fps <= FPS_MAX):
        return f"--fps {fps:g}: must be in (0, {FPS_MAX:g}] frames per second"
    still = getattr(args, "still", None)
    if still is not None and not (0 <= still <= (60.0 if duration is None else duration)):
        if duration is None:
            return f"--still {still:g}: must lie in [0, the throw's duration] seconds"
        return f"--still {still:g}: must lie in [0, {duration:g}] seconds (the throw's duration)"
    hold = getattr(args, "hold", None)
    if hold is not None and not (0 <= hold <= 60):
        return f"--hold {hold:g}: must be in [0, 60] seconds"
    mf = getattr(args, "max_frames", None)
    if mf is not None and mf < 1:
        return f"--max-frames {mf}: must be >= 1"
    return None


def cmd_render_throw(args) -> int:
    """``nbst render THROW.json -o OUT [--still T] [--camera C] [--clean] [--size WxH] [--fps F] [--hold S] [-q]``
    (``cmd_render`` dispatches here when its first argument is a 5 m throw file; the recording and
    the frames are :mod:`nbst.render.bowling.deck`'s)."""

    from nbst.models.bowling.deck import throwfile


    def err(msg) -> int:
        print(f"nbst render: error: {plain(msg)}", file=sys.stderr)
        return 2

    out = str(args.output)
    still = getattr(args, "still", None)
    want = (".png",) if still is not None else (".mp4", ".gif")
    if not out.lower().endswith(want):
        return err(f"-o {out}: use a {' or '.join(want)} file"
                   f"{' with --still' if still is not None else ' (or --still T for a .png)'}")
    bad = _check_throw_flags(args)  # before any work; --still is checked again against the throw's duration
    if bad:
        return err(bad)
    size = getattr(args, "size", None)
    if size:   # a text from a caller, else argparse's (W, H): refused here, before the throw is read
        w, h = parse_size(size) if isinstance(size, str) else size  # InputError, main's one line
        if out.lower().endswith(".mp4") and (w % 2 or h % 2):
            return err(f"--size {w}x{h}: H.264 (yuv420p) needs an even width and height")
        size = (w, h)
    try:
        throw, motion = load_motion(args.problem)
    except throwfile.ThrowFileError as e:
        return err(str(e))
    bad = _check_throw_flags(args, float(motion.times[-1]))
    if bad:
        return err(bad)
    fps = float(getattr(args, "fps", None) or style.DEFAULT_FPS)
    hold = getattr(args, "hold", None)
    realtime = bool(getattr(args, "realtime", False))
    times = motion_times(motion, fps, hold=1.0 if hold is None else float(hold), realtime=realtime)

    limit = getattr(args, "max_frames", None) or MAX_FRAMES
    if still is None and len(times) > limit:
        return err(f"{len(times):,} frames at --fps {fps:g}; at most {limit:,} (--max-frames)")
    prepare_output(out, inputs=(args.problem,))
    bar = None
    if not getattr(args, "quiet", False) and still is None:
        bar = progress_bar(total=len(times), unit="frame", file=sys.stderr, dynamic_ncols=True, desc="render")
    try:
        n = render_motion(throw, motion, out, still=still, camera=getattr(args, "camera", None) or "both",
                          size=size, times=times, fps=fps, progress=bar, clean=bool(getattr(args, "clean", False)),
                          realtime=realtime)
    except RenderError as e:
        return err(str(e))
    finally:
        if bar is not None:
            bar.close()
    if not getattr(args, "quiet", False):
        print(f"nbst render: wrote {out} ({n} frame{'s' if n != 1 else ''})", file=sys.stderr)
    return 0

