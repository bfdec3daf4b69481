"""Core subcommands: ``nbst problems`` and ``nbst simulate``."""
from __future__ import annotations

import argparse
import sys
from typing import Any

from nbst.cli.args import exact_motion, print_json
from nbst.constants import many_body
from nbst.domain import plain
from nbst.problem import builtin_names, load_problem
from nbst.solution import load_solution


__all__ = ["COMMANDS", "register", "cmd_problems", "cmd_simulate"]

#: The top-level commands this module registers, with their help lines: ``nbst --help`` lists
#: them without building their arguments (nbst.cli.main builds only the command asked for).
COMMANDS = {
    "problems": "list the built-in problems, or show one",
    "simulate": "simulate a solution exactly and report where the disks end",
}


def register(sub) -> None:
    p = sub.add_parser("problems", help=COMMANDS["problems"],
                       description="List the built-in problems (name, disks, cueable, radius, box, t_final, R), "
                                   "or print one as JSON with `nbst problems NAME` (or `nbst problems show NAME`).")
    p.add_argument("words", nargs="*", metavar="[show] NAME",
                   help="print this problem's JSON (a built-in name or a path); `show` is optional")
    p.set_defaults(func=cmd_problems)

    p = sub.add_parser("simulate", help=COMMANDS["simulate"],
                       description="Simulate PROBLEM with the initial velocities in SOLUTION (a solution JSON "
                                   "file, e.g. from `nbst solve`) and report final positions, L2 cost, signature "
                                   "(1 = disk ends within R of its target), order and event counts. Cost, "
                                   "signature and order stored in the file are ignored and recomputed.",
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("problem", help="built-in name or path to a problem JSON file")
    p.add_argument("solution", help="path to a solution JSON file")
    p.add_argument("--json", action="store_true",
                   help="print one JSON object: final, cost, signature, order, events {disk_disk, wall}")
    p.set_defaults(func=cmd_simulate)


def cmd_problems(args) -> int:
    words = list(args.words)
    if words[:1] == ["show"]:
        words = words[1:]
        if not words:
            print("nbst problems show: error: give a problem NAME (see `nbst problems`)", file=sys.stderr)
            return 2
    if len(words) > 1:
        print(f"nbst problems: error: one problem at a time, got {len(words)}: {' '.join(words)}", file=sys.stderr)
        return 2
    if words:
        print_json(load_problem(words[0]).to_dict())
        return 0
    rows = [("name", "disks", "cueable", "radius", "box", "t_final", "R", "description")]
    for name in builtin_names():
        p = load_problem(name)
        radii = sorted(set(float(r) for r in p.radius))
        rows.append((name, str(p.n), str(int(p.cueable.sum())), "/".join(f"{r:g}" for r in radii),
                     f"{p.width:g}x{p.height:g}", f"{p.t_final:g}", f"{p.target_radius:g}",
                     _clip(plain(p.description), 60)))
    widths = [max(len(r[c]) for r in rows) for c in range(len(rows[0]) - 1)]
    for r in rows:
        print("  ".join(x.ljust(w) for x, w in zip(r, widths)) + "  " + r[-1])
    return 0


def _clip(s: str, n: int) -> str:
    return s if len(s) <= n else s[: n - 1] + "…"


def cmd_simulate(args) -> int:
    problem = load_problem(args.problem)
    sol = load_solution(args.solution, problem)
    tr = exact_motion(problem, args.solution, sol.velocities)
    if args.json:
        print_json({
            "problem": problem.name,
            "final": tr.final_positions.tolist(),
            "cost": tr.cost,
            "signature": tr.signature_string,
            "order": tr.order,
            "events": {"disk_disk": tr.n_disk_disk, "wall": tr.n_wall},
            "truncated": tr.truncated,
            "stalled": bool(tr.stalled),
            "t_end": tr.end_time,
        })
        return 0
    print(f"problem    {problem.name}  ({problem.n} disks, t_final = {problem.t_final:g} s)")
    print(f"cost       {tr.cost:.6g}  (sum of squared distances to targets)")
    import numpy as np

    many = many_body(problem.n)
    shown = f"({problem.n} characters: --json)" if many else tr.signature_string
    print(f"signature  {shown}  order {tr.order}/{problem.n}")
    print(f"events     {tr.n_disk_disk} disk-disk, {tr.n_wall} wall")
    d = ((tr.final_positions - problem.target) ** 2).sum(axis=1) ** 0.5
    rows: Any = range(problem.n)
    if many:  # the disks off target (at most 20), else the 5 farthest; --json has every disk
        off = np.flatnonzero(d > problem.target_radius)
        rows = (off[np.argsort(-d[off], kind="stable")] if off.size else np.argsort(-d, kind="stable"))[:20 if off.size
                                                                                                        else 5]
        print(f"disks      {problem.n - off.size} within R, {off.size} not; below: "
              + ("the farthest off target" if off.size else "the 5 farthest from their targets")
              + " (--json: every disk)")
    print(f"disk  final x     final y     target x    target y    distance  within R = {problem.target_radius:g}")
    for i in rows:
        fx, fy = tr.final_positions[i]
        tx, ty = problem.target[i]
        ok = "yes" if d[i] <= problem.target_radius else "no"
        print(f"{i:4d}  {fx:10.4f}  {fy:10.4f}  {tx:10.4f}  {ty:10.4f}  {d[i]:8.4f}  {ok}")
    return 0
