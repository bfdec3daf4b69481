"""``nbst bowl``: ten-pin bowling on MuJoCo, in two halves (docs/bowling.md).

The words: a **delivery** is what the bowler does, a **throw** is its result (the ball's run
and the pins down); a throw file records both.

* the deck half, deliveries 5 m before the pins (y, speed, angle, spin): ``bowl solve``,
  ``bowl atlas`` (:mod:`nbst.cli.bowl.deck`);
* the lane half, deliveries from the foul line in a bowler's units (hand, board, angle, mph,
  rpm, axis rotation and tilt): ``bowl throw``, ``frame`` (:mod:`nbst.cli.bowl.lane`), ``spares``,
  ``pocket``, ``advise`` (:mod:`nbst.cli.bowl.advise`), and ``bowl solve --foul-line|--robust``, ``bowl atlas
  --foul-line`` (:mod:`nbst.cli.bowl.foul`);
* ``bowl replay`` runs either half's throw file again (here).

Registration is light: mujoco and cma are imported inside the commands.

Exit codes: 0 done (solve: the requested pins exactly; replay: the file's pins; atlas:
finished), 1 a check failed (solve: the request was not found within the budget and the
nearest throw was written, or ``--require-robust`` and no timestep keeps it; replay: the pins
down differ from the file's), 2 bad input, 130 interrupted (solve: the best throw so far is
written; atlas: what ran is written).
"""
from __future__ import annotations

import sys

from nbst.cli.args import SEED, print_json, with_limits
from nbst.cli.bowl import advise as bowl_advise, deck as bowl_deck, foul as bowl_foul, lane as bowl_lane
from nbst.cli.bowl import series as bowl_series
from nbst.cli.bowl.args import err, leave, picture_flags, pins_down, runner_args, wants_picture
from nbst.cli.flags import add_out_dir, add_seed

__all__ = ["COMMANDS", "DESCRIPTION", "BOWLER_5M", "register", "cmd_solve", "cmd_atlas", "cmd_replay"]

DESCRIPTION = (
    "Ten-pin bowling, synthesized on MuJoCo rollouts (docs/bowling.md): a USBC lane with oil, pins and a "
    "ball. A delivery is what the bowler does, a throw its result. Two halves: from the foul line, a "
    "delivery in a bowler's units (hand, board at the foul line or the arrows, launch angle, mph, rpm, axis "
    "rotation and tilt; bowl throw, frame, spares, pocket, and solve/atlas --foul-line); and on the last 5 m "
    "before the pins, a delivery as the ball's lateral position, speed, angle and spin there (bowl solve, "
    "atlas), clamped to what a bowler can throw.")


#: The top-level commands this module registers, with their help lines: ``nbst --help`` lists
#: them without building their arguments (nbst.cli.main builds only the command asked for).
COMMANDS = {
    "bowl": "10-pin bowling in MuJoCo: find a delivery that knocks down given pins",
}


def register(sub) -> None:
    """``nbst bowl`` and its subcommands on the top-level subparsers ``sub``; the defaults they show
    are the library's (:mod:`nbst.models.bowling.deck.search`, :mod:`.atlas`), read here, when the
    parser is built."""
    from nbst.models.bowling.deck import atlas, search

    p = sub.add_parser("bowl", help=COMMANDS["bowl"],
                       description=DESCRIPTION)
    bowl = p.add_subparsers(dest="bowl_command", metavar="SUBCOMMAND", parser_class=type(p))
    p.set_defaults(func=lambda args: (p.print_help(sys.stderr), 2)[1])

    s = bowl.add_parser("solve", help="search for a delivery that knocks down exactly the given pins",
                        description="Search the 5 m delivery space (uniform exploration, then CMA-ES restarts from "
                                    "the throws whose pins-down sets are nearest the request) with mujoco.rollout "
                                    "on --jobs threads, and write the throw: JSON plus the scene XML beside it "
                                    "(replayable with plain mujoco). With --foul-line (or --robust), a bowler's "
                                    "delivery from the foul line instead. Ctrl-C writes the best throw so far "
                                    "(exit 130). The same --seed gives the same throw, for any --jobs.",
                        epilog="Example: nbst bowl solve --leave 7,10 -o split.json --seed 1   (the 7-10 split; "
                               "the shipped atlas holds it). Exit 0: found; 1: not found within --max-rollouts "
                               "(the nearest throw is written and its pins named), or --require-robust and no "
                               "timestep keeps the written throw; 2: bad input; 130: interrupted.")
    want = s.add_mutually_exclusive_group(required=True)
    want.add_argument("--down", type=pins_down, metavar="PINS",
                      help="pins to knock down, e.g. 1,2,4,7 (USBC numbers: 1 in front, 7 back left, 10 back "
                           "right); 'strike' = all ten")
    want.add_argument("--leave", type=leave, metavar="PINS",
                      help="pins to leave standing, as bowlers name a leave: --leave 7,10 is the 7-10 split "
                           "(every other pin down); 'none' = a strike")
    s.add_argument("-o", "--output", required=True, metavar="THROW.json", help="where to write the throw")
    add_seed(s, type=SEED, resumable=False)
    s.add_argument("--max-rollouts", type=bowl_deck.SOLVE_ROLLOUTS, default=search.DEFAULT_MAX_ROLLOUTS, metavar="N",
                   help=with_limits(f"rollout budget (default {search.DEFAULT_MAX_ROLLOUTS})", bowl_deck.SOLVE_ROLLOUTS))
    runner_args(s, "the same throw as --jobs for the same seed")
    s.add_argument("--distance", choices=("hamming", "geometry"), default="hamming",
                   help="distance between subsets that ranks restart points: hamming (pins that differ; "
                        "default) or geometry (an extra pin down next to a wanted one counts 1/2)")
    s.add_argument("--no-robustness", action="store_true",
                   help="skip the robustness probes after the search (%d to %d more rollouts: on each of 2 axes, "
                        "4 at the largest change, then 10 bisection rounds of 4 if that fails; the throw file "
                        "records how many ran)" % search.ROBUSTNESS_ROLLOUTS)
    s.add_argument("--no-atlas", action="store_true",
                   help="search from scratch; by default the search starts from the shipped atlas's throws "
                        "(models/bowling/deck/atlas.json, one for each of 328 subsets): a request it holds "
                        "is confirmed with one rollout, others restart from its nearest subsets")
    s.add_argument("-q", "--quiet", action="store_true", help="no progress bar and no summary line")
    bowl_foul.add_solve_flags(s)
    s.set_defaults(func=cmd_solve)

    r = bowl.add_parser("replay", help="replay a throw file (either half's) and check its pins down",
                        description="Replay FILE and print the pins down; exit 1 if they differ from the file's. "
                                    "A 5 m throw file (bowl solve) replays from its scene XML with plain MuJoCo "
                                    "(fresh MjData, qpos0 and qvel0 set, mj_step for duration) against its `down`; "
                                    "a foul-line throw file (bowl frame -o, bowl solve --foul-line) replays its "
                                    "delivery on its oil, ball and pins standing at its timestep, against its "
                                    "outcome's `down`.")
    r.add_argument("file", metavar="FILE", help="a throw file (THROW.json) of either half")
    r.add_argument("--json", action="store_true", help="print one JSON object: down, expected, match")
    picture_flags(r, "the foul-line throw's frame, its readout with the pins asked for, the pins down and the "
                     "file's probability (foul-line throw files only: `nbst render THROW.json` films a 5 m throw)")
    r.set_defaults(func=cmd_replay)

    a = bowl.add_parser("atlas", help="try for every one of the 1,023 non-empty subsets; one throw per subset found",
                        description="Search for all 1,023 non-empty subsets with 5 m deliveries, keeping an archive "
                                    "keyed by subset. --method elites (default, MAP-Elites style): after 256 uniform "
                                    "deliveries, each batch of 16 holds 2 uniform ones and 14 children of archived "
                                    "deliveries (parents of rare subsets, of sizes with few subsets found, and "
                                    "whose children found new subsets are drawn more often), moved by a "
                                    "Gaussian step of 0.4 mm, 4 mm or 42 mm sideways (and alike on the other "
                                    "axes). --method targeted: a shared uniform exploration (a quarter of the "
                                    "budget), then targeted solves (--per-subset rollouts each) for the missing "
                                    "subsets nearest the archive. --method uniform: random deliveries. Writes "
                                    "DIR/subset-<pins>.json for every subset found (all naming one DIR/scene.xml), "
                                    "each with its robustness (16 more rollouts; see docs/bowling.md), "
                                    "DIR/summary.md (+ .csv, + .png: every subset found as a triangle) and "
                                    "DIR/atlas.json. Rerunning resumes: the throws already in DIR are the archive. "
                                    "With --foul-line, an atlas of bowlers' deliveries from the foul line instead.")
    add_out_dir(a, dest="out", required=True, old=("--out",), help="output folder")
    a.add_argument("--max-rollouts", type=bowl_deck.ATLAS_ROLLOUTS, default=atlas.DEFAULT_BUDGET, metavar="N",
                   help=with_limits(f"search rollout budget of this run (default {atlas.DEFAULT_BUDGET}; robustness "
                                    "probes not counted)", bowl_deck.ATLAS_ROLLOUTS))
    a.add_argument("--method", choices=("elites", "targeted", "uniform"), default="elites",
                   help="how to spend the budget (default elites)")
    a.add_argument("--per-subset", type=bowl_deck.PER_SUBSET, default=atlas.PER_SUBSET, metavar="N",
                   help=with_limits(f"--method targeted: rollout budget of each targeted solve (default "
                                    f"{atlas.PER_SUBSET})", bowl_deck.PER_SUBSET))
    a.add_argument("--from", dest="from_atlas", metavar="ATLAS.json", default=None,
                   help="start from the throws of this atlas file (e.g. models/bowling/deck/atlas.json): they "
                        "are written into DIR first (those not there yet), then the search resumes from them")
    a.add_argument("--robustness-only", action="store_true",
                   help="no search: add the robustness to every throw in DIR that lacks it, then the summary")
    a.add_argument("--no-robustness", action="store_true", help="write new throws without the robustness probes")
    add_seed(a, type=SEED, resumable=True)
    runner_args(a, "the same throws as --jobs for the same seed and folder")
    a.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    bowl_foul.add_atlas_flags(a)
    a.set_defaults(func=cmd_atlas)

    bowl_lane.register(bowl)
    bowl_series.register(bowl)
    bowl_advise.register(bowl)


#: Why ``--bowler`` is refused without ``--foul-line``: a 5 m throw is an exact initial state, with no
#: bowler's release or noise to take from a profile (it was ignored, silently, before).
BOWLER_5M = ("--bowler is a bowler's release and noise from the foul line; a 5 m throw is an exact "
             "initial state with neither: add --foul-line")


def cmd_solve(args) -> int:
    if args.foul_line or args.robust is not None:
        return bowl_foul.cmd_solve(args)
    if args.bowler is not None:
        return err("solve", BOWLER_5M)
    return bowl_deck.cmd_solve(args)


def cmd_atlas(args) -> int:
    if args.foul_line:
        return bowl_foul.cmd_atlas(args)
    if args.bowler is not None:
        return err("atlas", BOWLER_5M)
    return bowl_deck.cmd_atlas(args)


def cmd_replay(args) -> int:
    """``bowl replay FILE``: a foul-line throw file replays from the foul line
    (:func:`nbst.cli.bowl.lane.replay_throw`), a 5 m throw file from its scene with plain MuJoCo."""
    from nbst.models.bowling import files
    from nbst.models.bowling.deck import throwfile as deckfile
    from nbst.models.bowling.lane import throwfile as lanefile

    try:
        doc = files.read_doc(args.file)
        if lanefile.is_throw(doc):
            return bowl_lane.replay_throw(args)
        if isinstance(doc, dict) and "kind" not in doc and "format" in doc:
            return err("replay", f"{args.file}: format: not an nbst bowling throw file (a 5 m throw file's kind "
                                 f"is {deckfile.KIND!r}, a foul-line throw file's format {lanefile.FORMAT!r})")
        if wants_picture(args):
            deck = isinstance(doc, dict) and doc.get("kind") == deckfile.KIND
            return err("replay", f"{args.file}: {'a 5 m throw file' if deck else 'not a foul-line throw file'}: "
                                 "--video/--still film foul-line throw files (bowl frame -o); a 5 m throw is "
                                 "filmed by `nbst render THROW.json -o OUT.mp4` (or --still T -o OUT.png)")
        d, down = deckfile.replay_file(args.file)
    except files.BowlingFileError as e:
        return err("replay", str(e))
    want = sorted(d["down"])
    ok = down == want
    if args.json:
        print_json({"throw": str(args.file), "down": down, "expected": want, "match": ok})
    else:
        print(f"pins down  {','.join(map(str, down)) or 'none'}")
        print(f"expected   {','.join(map(str, want)) or 'none'}  ({'match' if ok else 'DIFFERENT'})")
    return 0 if ok else 1
