"""``nbst render SOL.json``: a scene solution's motion (``nbst scene solve``) as a video or a still,
any MJCF drawn by :mod:`nbst.render.scene.video` (docs/scene.md, "Render").

``nbst.cli.render.cmd_render`` dispatches here when its first argument is a scene solution; the
flags are its own (``--camera`` takes the name of one of the scene's cameras, ``--clean`` leaves
the text out). Registration is not here: moderngl and MuJoCo load when the command runs.
"""
from __future__ import annotations

import sys
from pathlib import Path

from nbst.cli.args import Size
from nbst.errors import RenderError
from nbst.outputs import prepare_output, sigterm_as_interrupt
from nbst.progress import Bar, command_start, count_text
from nbst.render.core import style
from nbst.render.core.times import MAX_FRAMES, frame_count

__all__ = ["SCENE_REFUSED", "cmd_render_scene"]


def _err(msg: str) -> int:
    print(f"nbst render: error: {msg}", file=sys.stderr)
    return 2


#: Flags that draw disk problems only, refused for a scene solution: (attribute, default, flag).
SCENE_REFUSED = (("trails", False, "--trails"), ("labels", None, "--labels"), ("view", None, "--view"),
                 ("source", None, "--source"), ("follow", None, "--follow"))


def cmd_render_scene(args) -> int:
    """``nbst render SOL.json -o OUT [--still T] [--camera NAME] [--clean] [--size WxH] [--fps F]
    [--speed S] [--hold S] [--max-frames N] [-q]`` (``cmd_render`` dispatches here when its first
    argument is a scene solution; the frames are :mod:`nbst.render.scene.video`'s)."""
    from nbst.render.scene.motion import load_solution_scene
    from nbst.render.scene.readout import not_drawn
    from nbst.render.scene.video import camera_names, render_scene
    from nbst.scene.solution import scene_changed

    given = [flag for attr, default, flag in SCENE_REFUSED if getattr(args, attr, default) not in (default, None, False)]
    if given:
        return _err(f"{', '.join(given)} draw{'s' if len(given) == 1 else ''} disk problems or crashes "
                              f"only; a scene solution takes -o, --still, --camera, --clean, --size, --fps, --speed, "
                              f"--hold, --max-frames and -q")
    if args.solution is not None:
        return _err(f"{args.problem} is a scene solution: it names its own scene; give it alone")
    out = Path(args.output)
    ext = out.suffix.lower()
    if args.still is not None and ext != ".png":
        return _err(f"--still writes a PNG image; give -o with a .png name, not {out.name!r}")
    if args.still is None and ext == ".png":
        return _err(f"{out.name}: a .png output needs --still T (the time of the frame)")
    kind = "png" if ext == ".png" else ("gif" if ext == ".gif" else "mp4")
    size = (Size()(args.size) if isinstance(args.size, str) else tuple(args.size)) if args.size else \
        (style.GIF_SIZE if kind == "gif" else style.DEFAULT_SIZE)
    if kind == "mp4" and (size[0] % 2 or size[1] % 2):
        return _err(f"--size {size[0]}x{size[1]}: H.264 (yuv420p) needs an even width and height")
    fps = args.fps if args.fps is not None else (style.GIF_FPS if kind == "gif" else style.DEFAULT_FPS)
    speed = 1.0 if args.speed is None else float(args.speed)
    doc, fates, model = load_solution_scene(args.problem)  # one line if the file, its fates or scene is refused
    if not args.quiet and scene_changed(doc, fates):
        print(f"note: {fates.scene.name} changed since {Path(args.problem).name} was solved: this draws the motion in "
              f"the scene as it is now (nbst scene replay {args.problem} says whether it is the solved one)",
              file=sys.stderr)
    if not args.quiet and (missing := not_drawn(model)):
        print(f"note: not drawn: the scene's {missing}: nbst draws geoms (and spatial tendons) only",
              file=sys.stderr)
    if args.camera is not None and args.camera not in camera_names(model):
        have = ", ".join(camera_names(model)) or "none"
        return _err(f"--camera {args.camera}: the scene has no camera of that name (its cameras: {have})")
    duration = int(doc["nstep"]) * float(doc["timestep"])
    if args.still is not None and not (0 <= args.still <= duration):
        return _err(f"--still {args.still:g}: must lie in [0, {duration:g}] seconds (the motion's duration)")
    n = 1
    if kind != "png":
        limit = args.max_frames or MAX_FRAMES
        n = frame_count(duration, fps, speed=speed, hold=args.hold)
        if n > limit:
            return _err(f"{duration:g} s at {fps:g} fps and --speed {speed:g} is {n:,} frames, over the "
                                  f"limit of {limit:,}; raise it with --max-frames N, or use a higher --speed or a "
                                  f"lower --fps")
    prepare_output(out, inputs=(args.problem,))
    bar = None if kind == "png" else Bar(f"nbst render: {out.name}", n, unit="frame", file=sys.stderr,
                                          quiet=args.quiet, start=command_start())
    try:
        with sigterm_as_interrupt():  # kill: the partial video is removed as on Ctrl-C
            wrote = render_scene(args.problem, out, still=args.still, camera=args.camera, clean=args.clean,
                                 size=size, fps=fps, speed=speed, hold=args.hold, progress=bar)
    except RenderError as e:
        return _err(str(e))
    finally:
        if bar is not None:
            bar.close()
    if not args.quiet:
        what = f"t = {args.still:g} s" if kind == "png" else f"{count_text(wrote)} frames, {fps:g} fps"
        print(f"nbst render: wrote {out} ({size[0]}x{size[1]}, {what})", file=sys.stderr)
    return 0


def unsolved_scene(path: str) -> str | None:
    """What to say of ``nbst render`` given a fates file, an MJCF or a throw's phases (no motion yet), else None."""
    from nbst.files import sniff_kind

    kind = sniff_kind(path, (("fates", "nbst-fates"), ("phases", "board_at_foul_line")))
    if kind == "fates":
        return f"{path} is a fates file: solve it first (`nbst scene solve {path} -o sol.json`), then render the solution"
    if kind == "phases":
        return (f"{path} holds a throw's phases (`nbst bowl throw -o`), no motion: film the throw with `nbst bowl "
                f"throw ... --video OUT.mp4`, or `nbst bowl frame ... -o THROW.json` then `nbst bowl replay "
                f"THROW.json --video OUT.mp4`")
    if Path(path).suffix.lower() == ".xml":
        return (f"{path} is a MuJoCo scene: write a fates file for it and solve it (`nbst scene solve FATES.json -o "
                f"sol.json`, docs/scene.md), then render the solution")
    return None
