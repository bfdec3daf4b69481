"""``nbst generate``: planted problem instances with a known zero-cost solution."""
from __future__ import annotations

import sys

from nbst.cli.args import int_at_least
from nbst.cli.flags import add_seed


def register(sub) -> None:
    p = sub.add_parser(
        "generate", help="make a planted problem (a zero-cost solution is known)",
        description="Make a random problem whose exact solution is known: random starts and cue velocities "
                    "(each noncueable disk is struck by a cueable one), simulated exactly; the targets are "
                    "where the disks end. The problem file carries the planted velocities under \"planted\"; "
                    "--solution also writes them as a solution file.")
    p.add_argument("--planted", type=int, required=True, metavar="N", help="number of disks")
    p.add_argument("--noncue", type=int, default=0, metavar="K", help="how many disks are noncueable (default 0)")
    p.add_argument("--radius", type=float, default=15.0, metavar="r", help="disk radius (default 15)")
    p.add_argument("--box", type=float, nargs=2, default=(800.0, 800.0), metavar=("W", "H"),
                   help="box size (default 800 800)")
    p.add_argument("--t-final", type=float, default=5.0, help="duration in seconds (default 5)")
    p.add_argument("--target-radius", type=float, default=75.0, metavar="R",
                   help="target neighbourhood radius R (default 75)")
    add_seed(p, type=int_at_least(0, "seed"), resumable=False)
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
    for flag, value in (("--t-final", args.t_final), ("--target-radius", args.target_radius),
                        ("--box", min(args.box))):
        if not value > 0:
            print(f"nbst generate: error: {flag} must be > 0", file=sys.stderr)
            return 2
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
