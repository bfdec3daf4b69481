"""``nbst bowl series``: games bowled in order on one lane that every ball wears (lane transition,
models/bowling/lane/transition.py), with the drift figure and the path plot (render/bowling/path.py).

Also :func:`write_path_plot`, the Specto-style plot of one throw that ``bowl throw --path-plot``
writes. Light at import: the bowling modules are imported inside the command.
"""
from __future__ import annotations

import sys

from nbst.cli.args import SEED, Bounded, print_json
from nbst.cli.bowl.args import ball_flags, ball_of, bowlers, oil_flag
from nbst.cli.flags import add_seed
from nbst.errors import InputError
from nbst.seeds import resolve_seed
from nbst.outputs import prepare_output, signals_deferred, write_text_atomic, OutputError, dumps_strict
from nbst.progress import progress_bar

__all__ = ["GAMES", "LINEUP", "register", "cmd_series", "pictures", "series_lines", "png", "path_plot_flag",
           "write_path_plot"]

GAMES = Bounded("games", 1, 30, integer=True)
LINEUP = Bounded("lineup", 1, 8, integer=True)


def register(bowl) -> None:
    """``nbst bowl series`` on ``nbst bowl``'s subparsers."""
    s = bowl.add_parser(
        "series", help="games in order on one lane whose oil every ball wears: the drift of breakpoint, entry angle "
                       "and pocket hits (lane transition)",
        description="Bowl --games games with a bowler profile's strike ball and release noise on one lane: every ball "
                    "(strike and spare) is a frame from the foul line whose track takes oil from the lane and carries "
                    "some down past the pattern's end, and the next ball meets the lane as it left it. --lineup "
                    "bowlers alternate frames (--lefty-share of them left-handed: their side of the lane is fresh). "
                    "With --move auto each bowler makes the coach's '2 and 1' move (feet 2 boards, target 1 board, in "
                    "when the last 4 strike balls hit high on average by more than half a board, their standard "
                    "error and 2 standard errors of the bowler's own spread at the pins (its release noise on the "
                    "fresh lane: a coach's 'don't move until you repeat shots'), out when light; half steps, one step "
                    "per 2 boards); --move both bowls the same releases "
                    "twice, without and with moves. Prints, per game: pocket hits (boards 16.5-18.5), strikes, the "
                    "mean breakpoint, entry angle and board at the pins, and the scores; writes the series file "
                    "(every ball, the moves, the oil before and after). Ctrl-C writes the balls bowled so far "
                    "(exit 130). The same --seed gives the same series (docs/bowling.md).",
        epilog="Example: nbst bowl series --bowler pro --games 3 --move both -o series.json --figure drift.png "
               "--path-plot paths.png")
    from nbst.models.bowling.lane.profiles import DEFAULT_PROFILE

    s.add_argument("--bowler", default=DEFAULT_PROFILE, choices=bowlers(),
                   help=f"the bowler profile (default {DEFAULT_PROFILE}): its strike ball (aimed at board 17.5 on the fresh lane "
                        "with this ball) and correlated release noise")
    s.add_argument("--games", type=GAMES, default=3, metavar="N", help="games per bowler (default 3; 1..30)")
    s.add_argument("--move", choices=("none", "auto", "both"), default="none",
                   help="none: keep the line (default); auto: '2 and 1' moves after 4 strike balls high or light on "
                        "average (more than half a board from 17.5, their standard error, and 2 standard errors of "
                        "the bowler's own spread at the pins); both: the series twice, the same releases")
    s.add_argument("--lineup", type=LINEUP, default=1, metavar="N",
                   help="bowlers on the lane, alternating frames as in league play (default 1; 1..8)")
    s.add_argument("--lefty-share", type=Bounded("lefty-share", 0, 1), default=0.0, metavar="F",
                   help="share of the lineup that is left-handed (default 0; it must make a whole number of bowlers)")
    s.add_argument("--noise-scale", type=Bounded("noise-scale", 0, 10), default=1.0, metavar="F",
                   help="multiply the profile's release-noise sigmas by F (default 1)")
    oil_flag(s)
    ball_flags(s)
    add_seed(s, type=SEED, resumable=False, what="seed of the release noise")
    s.add_argument("-o", "--output", required=True, metavar="SERIES.json", help="where to write the series file")
    s.add_argument("--figure", type=png, default=None, metavar="DRIFT.png",
                   help="also draw the drift: board at the pins, breakpoint, entry angle and pocket hits against the "
                        "ball's number, and the oil before and after (PNG)")
    s.add_argument("--path-plot", type=png, default=None, metavar="PATHS.png",
                   help="also draw every strike ball's path over the lane's oil after the series (board against "
                        "distance, breakpoints marked; PNG)")
    s.add_argument("--json", action="store_true", help="print the summary as one JSON object")
    s.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    s.set_defaults(func=cmd_series)


def cmd_series(args) -> int:
    from nbst.models.bowling.lane import transition as T

    seed = resolve_seed(args.seed, what="--seed")
    outs = [(o, p) for o, p in (("-o", args.output), ("--figure", args.figure), ("--path-plot", args.path_plot))
            if p is not None]
    if len({str(p) for _, p in outs}) < len(outs):
        raise InputError("-o, --figure and --path-plot must name different files")
    for o, p in outs:
        prepare_output(p, option=o)
    ball = ball_of(args)
    bowlers = T.lineup(args.bowler, args.lineup, args.lefty_share, args.noise_scale, args.oil, ball)
    moves = ("none", "auto") if args.move == "both" else (args.move,)
    runs = [T.Run(bowlers, args.games, seed, m, args.oil, ball) for m in moves]
    bar = progress_bar(total=len(runs) * args.games * args.lineup * 10, desc="frames", unit="frame",
                       disable=args.quiet, file=sys.stderr)

    def write(interrupted: bool) -> dict:
        done = [r for r in runs if r.balls]
        doc = T.series_dict(done, profile=args.bowler, lineup_n=args.lineup, lefty_share=args.lefty_share,
                            interrupted=interrupted)

        write_text_atomic(args.output, dumps_strict(doc) + "\n")
        return doc

    try:
        for r in runs:
            r.play(on_frame=lambda: bar.update(1))
    except KeyboardInterrupt:
        bar.close()
        if not any(r.balls for r in runs):
            print("nbst bowl series: interrupted before the first ball; nothing written", file=sys.stderr)
            return 130
        with signals_deferred(reraise=False):
            doc = write(True)
        n = sum(len(r.balls) for r in runs)
        print(f"nbst bowl series: interrupted; wrote the {n} balls bowled so far to {args.output}", file=sys.stderr)
        return 130
    except BaseException:   # an error (one line from nbst.cli.main) ends the bar first
        bar.close()
        raise
    bar.close()
    with signals_deferred(reraise=False) as late:
        doc = write(False)
        pictures(doc, args.figure, args.path_plot)
    if args.json:
        print_json({"output": args.output, "seed": seed, "runs": [{"move": r["move"], "moves": r["moves"],
                    "scores": r["scores"], "summary": r["summary"]} for r in doc["runs"]]})
    else:
        for line in series_lines(doc):
            print(line)
        for o, p in (("series file", args.output), ("figure", args.figure), ("path plot", args.path_plot)):
            if p:
                print(f"{o:<12} {p}")
    return 130 if late else 0


def pictures(doc: dict, figure, path_plot) -> None:
    """Write the drift figure and the series' path plot of ``doc`` (a series file's content)."""
    from nbst.render.bowling import path as P

    if figure:
        P.save(P.transition_figure(doc), figure, option="--figure")
    if path_plot:
        run = doc["runs"][0]
        paths = [{**b["path"], "hand": b["hand"], "n": b["n"], "breakpoint_ft": b["breakpoint_ft"],
                  "breakpoint_board": b["breakpoint_board"]} for b in run["balls"] if b["path"] is not None]
        fig = P.path_figure(paths, film=run["oil"]["after"], dx_ft=run["oil"]["dx_ft"], length_ft=run["oil"]["length_ft"],
                            title=f"{doc['bowler']}: {len(paths)} strike balls in order (move {run['move']}) over the "
                                  f"lane's oil after them; width exaggerated; diamonds: breakpoints")
        P.save(fig, path_plot, option="--path-plot")


def series_lines(doc: dict) -> list[str]:
    """The summary of a series file's content, per run, game and hand, in a bowler's units."""
    out = [f"{doc['bowler']}, {doc['lineup']} bowler(s), {doc['games']} games on {doc['oil']}, seed {doc['seed']}; "
           f"pocket: boards {doc['pocket_boards'][0]:g}-{doc['pocket_boards'][1]:g} at the head pin"]
    for run in doc["runs"]:
        out.append(f"move {run['move']}" + (f": {len(run['moves'])} moves" if run["move"] != "none" else ""))
        out += _move_lines(run, doc)
        for s in run["summary"]:
            bp = "none" if s["breakpoint_ft"] is None else f"{s['breakpoint_ft']:.1f} ft, board {s['breakpoint_board']:.1f}"
            ent = "none" if s["entry_angle_deg"] is None else f"{s['entry_angle_deg']:.2f} deg"
            at = "none" if s["board_at_pins"] is None else f"{s['board_at_pins']:.2f}"
            out.append(f"  game {s['game']} {s['hand']:<5}  pocket {s['pocket_hits']:>2}/{s['strike_balls']:<2} "
                       f"({100 * s['pocket_rate']:3.0f}%, 95% CI {100 * s['pocket_lo']:.0f}-{100 * s['pocket_hi']:.0f}%)"
                       f"  strikes {s['strikes']:>2}  breakpoint {bp}  entry {ent}  at the pins board {at}")
        sc = "; ".join(f"bowler {k}: " + ", ".join(str(g[-1]) if g else "-" for g in v) for k, v in run["scores"].items())
        out.append(f"  scores  {sc}")
    return out


def _move_lines(run: dict, doc: dict | None = None) -> list[str]:
    """Each move of a run in a bowler's words: after which ball, where the bowler now stands and looks
    (the strike line's stance and target plus the move's feet and target, in the bowler's own
    boards). The target is where the ball's path crosses the arrows, as ``bowl throw`` and
    ``bowl advise`` give it: the strike line's, thrown alone on a fresh lane of the run's pattern,
    plus the move (a move shifts the line's board at the arrows; the skid is straight there), or,
    where the pattern cannot be read again by its name (a sheet of one's own), the straight line's."""
    from nbst.models.bowling import lane
    from nbst.models.bowling.lane import advise, transition

    base = {}
    oil = (doc or {}).get("oil", "house")
    ball = lane.Ball(**doc["ball"]) if doc and isinstance(doc.get("ball"), dict) else None
    for b in run.get("bowlers", []):
        d = lane.Delivery(**b["strike"])
        try:
            arrow = float(lane.throw(d, oil, ball).board_at_arrows)
        except lane.LaneError:   # a pattern not read again by its name (a sheet of one's own), a gutter ball
            arrow = transition.arrow_board(d)
        base[b["index"]] = (advise.stance_of(d.foul_board()), arrow)
    out = []
    for m in run.get("moves", []):
        if m["bowler"] not in base:
            continue
        stance, arrow = base[m["bowler"]]
        who = f"bowler {m['bowler']} " if len(base) > 1 else ""
        out.append(f"  after ball {m['after_ball']}: {who}stands on {stance + m['feet']:.1f} and looks at "
                   f"{advise.arrow_text(arrow + m['target'])} (in all, feet {m['feet']:+g}, target {m['target']:+g} "
                   f"boards; + is in)")
    return out


def png(text: str) -> str:
    """argparse type: a PNG file's name."""
    import argparse

    if not str(text).lower().endswith(".png"):
        raise argparse.ArgumentTypeError(f"{text}: use a .png file")
    return text


def path_plot_flag(p) -> None:
    """``--path-plot PATH.png`` of ``bowl throw``."""
    p.add_argument("--path-plot", type=png, default=None, metavar="PATH.png",
                   help="also draw the ball's path, Specto-style: board against distance over the oil, the width "
                        "exaggerated, the breakpoint marked (render/bowling/path.py)")


def write_path_plot(path, results, *, oil=None, option: str = "--path-plot", prog: str = "nbst bowl throw") -> str | None:
    """The path plot of ``results`` (:class:`.lane.ThrowResult`, the ball alone) over ``oil``'s fresh film;
    one line on stderr when written. Returns a one-line error, or None."""
    from nbst.models.bowling import lane
    from nbst.render.bowling import path as P

    pat = lane.pattern(oil) if oil is not None else None
    paths = [{"ft": r.path["ft"], "board": r.path["board"], "hand": r.delivery["hand"], "breakpoint_ft": r.breakpoint_ft,
              "breakpoint_board": r.breakpoint_board} for r in results]
    fig = P.path_figure(paths, film=None if pat is None else pat.grid(), dx_ft=lane.DX_FT,
                        length_ft=None if pat is None else pat.length_ft)
    try:
        P.save(fig, path, option=option)
    except OutputError as e:
        return str(e)
    print(f"{prog}: wrote {path}", file=sys.stderr)
    return None
