"""``nbst generate``: problems with a known exact solution, planted (random) or a formation
(disks that end forming a text or an image)."""
from __future__ import annotations

import sys
import time
from typing import Any

from nbst import domain as D
from nbst.cli.args import SEED, Bounded, with_limits
from nbst.cli.flags import add_quiet, add_seed
from nbst.domain import MAX_DISKS
from nbst.outputs import prepare_output, write_json_atomic
from nbst.seeds import resolve_seed
from nbst.solution import make_solution

__all__ = ["DISKS", "FORMATION_DISKS", "NONCUE", "RADIUS", "BOX", "T_FINAL", "TARGET_RADIUS", "PLANTED_TARGET_RADIUS",
           "FORMATION_DISKS_DEFAULT", "LONG_STAGE_S", "ANNOUNCE_SIMULATION_FROM", "COMMANDS", "register",
           "cmd_generate"]

DISKS = Bounded("disk count", 1, MAX_DISKS, integer=True)
#: --disks of a formation (nbst.formation.MAX_FORMATION_DISKS: the swap passes check every pair).
FORMATION_DISKS = Bounded("disk count", 1, 20_000, integer=True)
NONCUE = Bounded("noncueable count", 0, MAX_DISKS - 1, integer=True)
RADIUS = Bounded("radius", 0.0, D.BOX_MAX / 2, lo_open=True)
BOX = Bounded("box side", D.BOX_MIN, D.BOX_MAX)
T_FINAL = Bounded("t_final", D.T_FINAL_MIN, D.T_FINAL_MAX, unit="s")
TARGET_RADIUS = Bounded("target radius", 0.0, 2 * D.BOX_MAX, lo_open=True)
#: Defaults that differ by mode (None on the parser, so that a flag of the other mode is caught).
PLANTED_TARGET_RADIUS = 75.0
FORMATION_DISKS_DEFAULT = 1000
#: A stage that runs longer than this (seconds) shows progress on stderr (unless -q), its clock
#: from the stage's start: a line within 2 s of it.
LONG_STAGE_S = 1.0
#: Planted problems from this many disks on announce the exact simulation before it starts
#: (it is one compiled call: it cannot report while it runs).
ANNOUNCE_SIMULATION_FROM = 1000


#: The top-level commands this module registers, with their help lines: ``nbst --help`` lists
#: them without building their arguments (nbst.cli.main builds only the command asked for).
COMMANDS = {
    "generate": "make a problem with a known exact solution: planted, or a formation (text/image)",
}


def register(sub) -> None:
    p = sub.add_parser("generate", help=COMMANDS["generate"],
        description="Make a problem whose exact solution is known. --planted N: random starts and cue velocities "
                    "(each noncueable disk is struck by a cueable one), simulated exactly; the targets are where "
                    "the disks end, and the file carries the planted velocities under \"planted\". "
                    "--targets-from SRC: disks start on a grid (or at random) and end forming the dark pixels "
                    "of an image or the glyphs of a text; starts and targets are spaced >= 2 sqrt(2) r (1 + 0.1) "
                    "and assigned by pairwise swaps, so the straight shots (target - start) / t_final never "
                    "touch (docs/generate.md). --solution also writes the known velocities as a solution file.",
        epilog="SRC: a value ending in .png .jpg .jpeg .gif .bmp .tif .tiff .webp is an image file (it must "
               "exist; dark = luminance below 0.5, transparent = white); anything else is the text to write "
               "(matplotlib, DejaVu Sans Bold, offscreen).")
    mode = p.add_mutually_exclusive_group(required=True)
    mode.add_argument("--planted", type=DISKS, metavar="N", help=with_limits("a planted problem of N disks", DISKS))
    mode.add_argument("--targets-from", metavar="SRC",
                      help="a formation: the disks end forming the image file SRC or the text SRC (see below)")
    p.add_argument("--noncue", type=NONCUE, default=None, metavar="K",
                   help=with_limits("--planted: how many disks are noncueable (default 0; fewer than N)", NONCUE))
    p.add_argument("--disks", type=FORMATION_DISKS, default=None, metavar="N",
                   help=with_limits(f"--targets-from: number of disks (default {FORMATION_DISKS_DEFAULT})",
                                    FORMATION_DISKS))
    p.add_argument("--start", choices=("grid", "random"), default=None,
                   help="--targets-from: where the disks start: a square grid over the box (default), or random "
                        "cells of a coarser grid, jittered (from --seed)")
    p.add_argument("--radius", type=RADIUS, default=15.0, metavar="r",
                   help=with_limits("disk radius (default 15; the disks must fit the box)", RADIUS))
    p.add_argument("--box", type=BOX, nargs=2, default=None, metavar=("W", "H"),
                   help=with_limits("box size. Default for --planted: 800 800 up to 63 disks; above that each "
                                    "side is 800*sqrt(N/60) (fixed density: that of 60 disks of radius 15 in "
                                    "800 x 800). Default for --targets-from: sized to fit the picture at the "
                                    "least spacing, with that spacing as a border. A given --box always wins",
                                    BOX))
    p.add_argument("--t-final", type=T_FINAL, default=5.0, help=with_limits("duration in seconds (default 5)", T_FINAL))
    p.add_argument("--target-radius", type=TARGET_RADIUS, default=None, metavar="R",
                   help=with_limits(f"target neighbourhood radius R (default: {PLANTED_TARGET_RADIUS:g} planted; "
                                    "half the least spacing for a formation, so no two targets' neighbourhoods "
                                    "overlap; at most the box diagonal)", TARGET_RADIUS))
    add_seed(p, type=SEED, resumable=False, what=f"random seed [{SEED.limits}]")
    p.add_argument("--name", default=None,
                   help="problem name (default planted-nN-kK-sSEED, text-WORDS or image-FILESTEM)")
    p.add_argument("-o", "--output", required=True, help="problem JSON file to write")
    p.add_argument("--solution", default=None, help="also write the known velocities as a solution file")
    add_quiet(p, "no progress and no summary")
    p.set_defaults(func=cmd_generate)


class _Stages:
    """Progress for generate's stages: a bar (the house progress_bar) for a stage that runs past
    LONG_STAGE_S, a line before a long blocking stage and one after it if it ran long."""

    def __init__(self, quiet: bool, announce: bool = False):
        self.quiet, self.announce = quiet, announce
        self.stage: str | None = None
        self.t0 = time.monotonic()
        self.bar: Any = None
        self.seconds: dict[str, float] = {}  # stage -> seconds from its first call to the next stage's (or its done = 1)

    def _close(self):
        if self.bar is not None:
            self.bar.close()
        self.bar = None

    def __call__(self, stage: str, done: int, total: int) -> None:
        now = time.monotonic()
        if stage != self.stage:
            if self.stage is not None:
                self.seconds[self.stage] = now - self.t0
            self._close()
            self.t0 = now
            self.stage = stage
            if total == 1 and done == 0 and self.announce and not self.quiet:
                print(f"nbst generate: {stage} (one exact run; no progress until it ends)...", file=sys.stderr,
                      flush=True)
        if total == 1:  # a blocking stage: 0 before, 1 after
            if done == 1:
                self.seconds[stage] = now - self.t0
                if now - self.t0 >= LONG_STAGE_S and not self.quiet:
                    print(f"nbst generate: {stage}: done in {now - self.t0:.1f} s", file=sys.stderr, flush=True)
            return
        if self.quiet:
            return
        if self.bar is None and now - self.t0 >= LONG_STAGE_S:
            from nbst.progress import Bar

            self.bar = Bar(f"nbst generate: {stage}", total or None, unit="disk" if total else "sweep",
                           start=self.t0)
        if self.bar is not None:
            self.bar.set(done)

    def close(self):
        self._close()


def _refuse(msg: str) -> int:
    print(f"nbst generate: error: {msg}", file=sys.stderr)
    return 2


def cmd_generate(args) -> int:
    import numpy as np

    formation = args.targets_from is not None
    other = (("--noncue", args.noncue),) if formation else (("--disks", args.disks), ("--start", args.start))
    for flag, value in other:
        if value is not None:
            return _refuse(f"{flag} applies to {'--planted' if formation else '--targets-from'} only")
    inputs: tuple = ()
    if formation:
        from nbst.formation import is_image_source

        inputs = (args.targets_from,) if is_image_source(args.targets_from) else ()
    prepare_output(args.output, inputs=inputs)
    if args.solution:
        prepare_output(args.solution, option="--solution", inputs=inputs, outputs=(args.output,))

    seed = resolve_seed(args.seed, what="--seed")
    box = tuple(args.box) if args.box is not None else None
    if formation:
        from nbst.formation import FormationError
        from nbst.formation import formation as make_formation

        n = args.disks if args.disks is not None else FORMATION_DISKS_DEFAULT
        stages = _Stages(args.quiet)
        try:
            problem, v, info = make_formation(args.targets_from, n, radius=args.radius, start=args.start or "grid",
                                              seed=seed, t_final=args.t_final, target_radius=args.target_radius,
                                              box=box, name=args.name, progress=stages)
        except FormationError as e:
            return _refuse(str(e))
        finally:
            stages.close()
        f = problem.raw["formation"]
        what = f"the text {args.targets_from!r}" if f["source"] == "text" else f"the image {f['image']}"
        summary = (f"{problem.n} disks forming {what} in a {problem.width:.6g} x {problem.height:.6g} box "
                   f"({f['box']}), starts on a {'grid' if f['start'] == 'grid' else 'random jittered grid'}, seed "
                   f"{seed}; straight shots keep centres >= {f['spacing'] / np.sqrt(2):.4g} apart "
                   f"(2r = {2 * args.radius:g}); {info['passes']} swap passes, {info['swaps']:,} swaps in "
                   f"{info['assign_s']:.2g} s")
        algorithm = "formation"
    else:
        from nbst.planted import planted

        stages = _Stages(args.quiet, announce=args.planted >= ANNOUNCE_SIMULATION_FROM)
        try:  # an InputError (no cueable disk, the disks do not fit) reaches main's one line
            problem, v = planted(args.planted, noncue=args.noncue or 0, radius=args.radius, seed=seed, box=box,
                                 t_final=args.t_final,
                                 target_radius=args.target_radius if args.target_radius is not None
                                 else PLANTED_TARGET_RADIUS, name=args.name, progress=stages)
        finally:
            stages.close()
        info = problem.raw["planted"]
        summary = (f"{problem.n} disks ({int((~problem.cueable).sum())} noncueable, "
                   f"{info['struck_noncueable']} of them struck), seed {seed}, planted motion with "
                   f"{info['disk_disk_collisions']} disk-disk collisions and {info['wall_bounces']} wall bounces "
                   f"(placed in {stages.seconds.get('placing disks', 0.0):.2g} s, simulated exactly in "
                   f"{stages.seconds.get('simulating the planted motion', 0.0):.2g} s)")
        algorithm = "planted"
    write_json_atomic(args.output, problem.raw)
    if not args.quiet:
        print(f"nbst generate: wrote {args.output}: {summary}")
    if args.solution:
        write_json_atomic(args.solution, make_solution(problem, v, algorithm=algorithm, seed=seed, cost=0.0).to_dict(),
                          option="--solution")
        if not args.quiet:
            print(f"nbst generate: wrote {args.solution}: the {'straight' if formation else 'planted'} velocities")
    return 0
