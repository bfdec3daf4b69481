"""``nbst export FILE --gltf OUT.glb``: any world's motion as glTF 2.0 node animation (docs/render.md).

Registration is light: the replays (MuJoCo, the simulator), trimesh and pygltflib load inside
the command function.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from nbst.cli.args import Bounded, with_limits
from nbst.errors import InputError
from nbst.export.worlds import DEFAULT_FPS, FPS_MAX
from nbst.outputs import prepare_output

__all__ = ["COMMANDS", "FPS", "register", "cmd_export"]

FPS = Bounded("fps", 0.0, FPS_MAX, lo_open=True)

#: The top-level commands this module registers, with their help lines.
COMMANDS = {
    "export": "write any world's motion (2D solution, bowling throw, crash, scene solution) as glTF 2.0 (.glb)",
}


def register(sub) -> None:
    p = sub.add_parser("export", help=COMMANDS["export"],
        description="Replay FILE with its own world's replay and write every body's motion as glTF 2.0 node\n"
                    "animation (translation and rotation, LINEAR, keyframes at --fps), with each body's\n"
                    "geometry and colours, for Blender or any glTF viewer. FILE is a 2D solution (`nbst\n"
                    "solve`; disks as pucks on the box's floor), a 5 m or foul-line bowling throw file (`nbst\n"
                    "bowl solve`, `nbst bowl frame -o`), a crash file (`nbst crash solve`) or a scene solution (`nbst\n"
                    "scene solve`).",
        epilog="examples:\n  nbst export sol.json --gltf out/over5.glb            # the problem named in sol.json\n"
               "  nbst export sol.json --problem my.json --gltf out.glb\n"
               "  nbst export tbone.json --gltf tbone.glb --fps 30       # a crash file\n"
               "  nbst export snake.json --gltf snake.glb                # a scene solution",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("file", metavar="FILE", help="a 2D solution, bowling throw, crash file or scene solution")
    p.add_argument("--gltf", "-o", dest="gltf", metavar="OUT.glb", required=True, help="the binary glTF file to write")
    p.add_argument("--problem", default=None, metavar="PROBLEM",
                   help="a 2D solution's problem (built-in name or file; default the one the solution names)")
    p.add_argument("--fps", type=FPS, default=DEFAULT_FPS,
                   help=with_limits(f"keyframes per second (default {DEFAULT_FPS:g}); MuJoCo worlds key the "
                                    f"recorded step nearest each keyframe time", FPS))
    p.add_argument("-q", "--quiet", action="store_true", help="no summary line")
    p.set_defaults(func=cmd_export)


def cmd_export(args) -> int:
    """Replay ``args.file`` and write ``args.gltf``; exit 0, or 2 after one line (nothing written)."""
    from nbst.export.gltf import empty_note, turn_note, write_glb
    from nbst.export.worlds import file_motion

    if Path(args.gltf).suffix.lower() != ".glb":
        raise InputError(f"--gltf {args.gltf}: must name a .glb file (binary glTF 2.0)")
    if not Path(args.file).exists():
        raise InputError(f"{args.file}: no such file")
    prepare_output(args.gltf, inputs=[p for p in (args.file, args.problem) if p is not None], option="--gltf")
    kind, motion = file_motion(args.file, problem=args.problem, fps=float(args.fps))
    if kind == "scene" and not args.quiet:
        from nbst.scene.solution import read_solution, scene_changed_at

        doc = read_solution(args.file)
        if scene_changed_at(doc):   # as render notes it: the motion is the scene's as it is now
            print(f"note: {Path(doc['scene']).name} changed since {Path(args.file).name} was solved: this writes the "
                  f"motion in the scene as it is now (nbst scene replay {args.file} says whether it is the solved one)",
                  file=sys.stderr)
    n = write_glb(args.gltf, motion, name=Path(args.file).stem)
    if not args.quiet:
        moving = sum(b.moves for b in motion.bodies)
        print(f"nbst export: wrote {args.gltf} ({kind}: {len(motion.bodies)} bodies, {moving} moving, "
              f"{len(motion.times)} keyframes over {motion.times[-1]:g} s, {n:,} bytes)", file=sys.stderr)
        for note in (empty_note(motion), turn_note(motion, float(args.fps))):
            if note:
                print(f"note: {note}", file=sys.stderr)
    return 0
