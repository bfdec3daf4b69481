"""``nbst generate``: planted problem instances with a known zero-cost solution."""
from __future__ import annotations

import sys

from nbst import domain as D
from nbst.cli.args import SEED, Bounded, with_limits
from nbst.domain import MAX_DISKS

DISKS = Bounded("disk count", 1, MAX_DISKS, integer=True)
NONCUE = Bounded("noncueable count", 0, MAX_DISKS - 1, integer=True)
RADIUS = Bounded("radius", 0.0, D.BOX_MAX / 2, lo_open=True)
BOX = Bounded("box side", D.BOX_MIN, D.BOX_MAX)
T_FINAL = Bounded("t_final", D.T_FINAL_MIN, D.T_FINAL_MAX, unit="s")
TARGET_RADIUS = Bounded("target radius", 0.0, 2 * D.BOX_MAX, lo_open=True)
from nbst.cli.flags import add_seed


def register(sub) -> None:
    p = sub.add_parser(
        "generate", help="make a planted problem (a zero-cost solution is known)",
        description="Make a random problem whose exact solution is known: random starts and cue velocities "
                    "(each noncueable disk is struck by a cueable one), simulated exactly; the targets are "
                    "where the disks end. The problem file carries the planted velocities under \"planted\"; "
                    "--solution also writes them as a solution file.")
    p.add_argument("--planted", type=DISKS, required=True, metavar="N", help=with_limits("number of disks", DISKS))
    p.add_argument("--noncue", type=NONCUE, default=0, metavar="K",
                   help=with_limits("how many disks are noncueable (default 0; fewer than N)", NONCUE))
    p.add_argument("--radius", type=RADIUS, default=15.0, metavar="r",
                   help=with_limits("disk radius (default 15; the disks must fit the box)", RADIUS))
    p.add_argument("--box", type=BOX, nargs=2, default=(800.0, 800.0), metavar=("W", "H"),
                   help=with_limits("box size (default 800 800)", BOX))
    p.add_argument("--t-final", type=T_FINAL, default=5.0, help=with_limits("duration in seconds (default 5)", T_FINAL))
    p.add_argument("--target-radius", type=TARGET_RADIUS, default=75.0, metavar="R",
                   help=with_limits("target neighbourhood radius R (default 75; at most the box diagonal)",
                                    TARGET_RADIUS))
    add_seed(p, type=SEED, resumable=False, what=f"random seed [{SEED.limits}]")
    p.add_argument("--name", default=None, help="problem name (default planted-nN-kK-sSEED)")
    p.add_argument("-o", "--output", required=True, help="problem JSON file to write")
    p.add_argument("--solution", default=None, help="also write the planted velocities as a solution file")
    p.set_defaults(func=cmd_generate)


def cmd_generate(args) -> int:
    import numpy as np

    from nbst.outputs import prepare_output, write_json_atomic
    from nbst.planted import planted
    from nbst.solution import make_solution

    prepare_output(args.output)
    if args.solution:
        prepare_output(args.solution, option="--solution", outputs=(args.output,))

    seed = args.seed if args.seed is not None else int(np.random.SeedSequence().entropy % 2**31)
    try:
        problem, v = planted(args.planted, noncue=args.noncue, radius=args.radius, seed=seed, box=tuple(args.box),
                             t_final=args.t_final, target_radius=args.target_radius, name=args.name)
    except ValueError as e:
        print(f"nbst generate: error: {e}", file=sys.stderr)
        return 2
    write_json_atomic(args.output, problem.raw)
    info = problem.raw["planted"]
    print(f"nbst generate: wrote {args.output}: {problem.n} disks ({int((~problem.cueable).sum())} noncueable, "
          f"{info['struck_noncueable']} of them struck), seed {seed}, planted motion with "
          f"{info['disk_disk_collisions']} disk-disk collisions and {info['wall_bounces']} wall bounces")
    if args.solution:
        write_json_atomic(args.solution, make_solution(problem, v, algorithm="planted", seed=seed, cost=0.0).to_dict(),
                          option="--solution")
        print(f"nbst generate: wrote {args.solution}: the planted velocities")
    return 0
