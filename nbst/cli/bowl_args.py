"""What every ``nbst bowl`` subcommand shares: pins on the command line, the error line, the
delivery and ball flags of a bowler, the runner and picture flags.

Light: only argparse and nbst's argument types at import; the bowling modules are imported
inside the functions that need them.
"""
from __future__ import annotations

import argparse
import sys

from nbst.cli.args import JOBS, SEED, Bounded, with_limits


def err(cmd: str, msg: str) -> int:
    """One error line for ``nbst bowl CMD`` on stderr; the exit code 2 (every bowl subcommand)."""
    from nbst.domain import plain

    print(f"nbst bowl {cmd}: error: {plain(msg)}", file=sys.stderr)
    return 2


def pin_list(text: str, flag: str | None = None) -> int:
    """Pin numbers "1,2,4,7" -> 10-bit mask (bit n-1 = pin n). ``flag`` names the option in the
    message (argparse names it itself for a ``type=``: then leave it out, so it is said once)."""
    pre = f"{flag}: " if flag else ""
    try:
        pins = [int(p) for p in text.strip().replace(" ", "").split(",") if p]
    except ValueError:
        raise argparse.ArgumentTypeError(f"{pre}pins must be numbers 1..10 separated by commas (e.g. 1,2,4,7), "
                                         f"got {text!r}") from None
    bad = [p for p in pins if not 1 <= p <= 10]
    if bad or not pins:
        raise argparse.ArgumentTypeError(f"{pre}pins must be numbers 1..10 (at least one), got {text!r}")
    return sum(1 << (p - 1) for p in set(pins))


def pins_down(text: str) -> int:
    """``--down``: pin numbers "1,2,4,7" (or "strike"/"all") -> 10-bit mask of the pins down."""
    from nbst.models.bowling.geometry import ALL_DOWN

    if text.strip().lower() in ("strike", "all"):
        return ALL_DOWN
    return pin_list(text)


def leave(text: str) -> int:
    """``--leave``: the pins left standing, as bowlers name a leave ("7,10" is the 7-10 split;
    "none" is a strike) -> 10-bit mask of the pins DOWN (every other pin)."""
    from nbst.models.bowling.geometry import ALL_DOWN

    if text.strip().lower() in ("none", "strike"):
        return ALL_DOWN
    down = ALL_DOWN & ~pin_list(text)
    if not down:
        raise argparse.ArgumentTypeError("all ten pins standing is a gutter ball (any delivery into the gutter); "
                                         "name at most 9 pins")
    return down


def pins_text(pins) -> str:
    return "-".join(str(p) for p in pins) if pins else "none"


def runner_args(parser, same: str) -> None:
    """--jobs K | --cluster ADDRESS: where the rollouts run."""
    g = parser.add_mutually_exclusive_group()
    g.add_argument("--jobs", type=JOBS, default=None, metavar="K",
                   help=with_limits("threads running rollouts (default: all cores)", JOBS))
    g.add_argument("--cluster", default=None, metavar="ADDRESS",
                   help=f"run the rollouts on the workers of this Dask scheduler (tcp://host:8786) instead; {same}")


def picture_flags(p, what: str) -> None:
    """--video, --still, --still-time, --size, --fps: the picture of a frame from the foul line."""
    p.add_argument("--video", default=None, metavar="OUT.mp4",
                   help=f"also film {what} (.mp4 or .gif; 3D, behind the bowler and overhead, from the release until "
                        "the pins settle, slow motion at impact; the pins down drawn at the end are the frame's "
                        "outcome; render/bowling_lane.py)")
    p.add_argument("--still", default=None, metavar="OUT.png",
                   help="also draw one frame as PNG (by default just before the ball meets the pins)")
    p.add_argument("--still-time", type=Bounded("still-time", 0, 30, unit="s"), default=None, metavar="S",
                   help="the --still's moment, seconds after the release")
    p.add_argument("--size", default=None, metavar="WxH", help="frame size of --video/--still (default 1280x720)")
    p.add_argument("--fps", type=Bounded("fps", 1, 240), default=None, help="--video's frames per second (default 60)")


def oil_flag(t) -> None:
    """--oil: a pattern registered in :data:`nbst.models.bowling.lane.oil.PATTERNS` (its names and
    descriptions are the choices and the help), or a pattern file."""
    from nbst.models.bowling.lane.oil import PATTERNS, argtype

    t.add_argument("--oil", default="house", type=argtype("--oil"), metavar="PATTERN",
                   help=f"oil pattern (default house): {PATTERNS.help_text()}; or a pattern file "
                        "(nbst-oil-pattern JSON: forward/reverse passes with length, volume and units or loads per "
                        "board; docs/bowling.md)")


def delivery_flags(t) -> None:
    """The delivery flags of ``bowl throw`` and ``bowl frame``: one vocabulary, one help text."""
    t.add_argument("--hand", choices=("right", "left"), default="right", help="bowling hand (default right)")
    t.add_argument("--board", type=Bounded("board", 1, 39), default=10.0, metavar="B",
                   help="board where the ball is at --at (default 10; 1..39, fractions allowed)")
    t.add_argument("--at", choices=("foul", "arrows"), default="arrows",
                   help="where --board is: at the foul line, or where the ball crosses the arrows, 15 ft out, "
                        "along its real path (the board at the foul line is found by running the ball alone; "
                        "default arrows)")
    t.add_argument("--angle", type=Bounded("angle", -10, 10, unit="deg"), default=1.5, metavar="DEG",
                   help="launch angle from straight down the lane, + out towards board 1 (default 1.5)")
    t.add_argument("--mph", type=Bounded("mph", 5, 30, unit="mph"), default=17.0, help="release speed (default 17)")
    t.add_argument("--rpm", type=Bounded("rpm", 0, 800, unit="rpm"), default=300.0, help="rev rate (default 300)")
    t.add_argument("--rotation", type=Bounded("rotation", 0, 90, unit="deg"), default=45.0, metavar="DEG",
                   help="axis rotation: 0 end over end, 90 pure side spin (default 45)")
    t.add_argument("--tilt", type=Bounded("tilt", 0, 90, unit="deg"), default=15.0, metavar="DEG",
                   help="axis tilt: 0 a horizontal spin axis (default 15)")


def ball_flags(t) -> None:
    """The ball flags of ``bowl throw`` and ``bowl frame`` (the ball maker's units; lane.Ball checks them)."""
    t.add_argument("--weight", type=float, default=15.0, metavar="LB", help="ball weight, lb (default 15; at most 16)")
    t.add_argument("--rg", type=float, default=2.50, metavar="IN", help="ball RG, in (default 2.50; USBC 2.46..2.80)")
    t.add_argument("--diff", type=float, default=0.040, metavar="IN",
                   help="RG differential, in (default 0.040; USBC at most 0.060)")
    t.add_argument("--cover", type=float, default=0.20, metavar="MU",
                   help="coverstock friction on the dry lane (default 0.20; USBC at most 0.32)")


def delivery_of(args):
    """The delivery of the :func:`delivery_flags`, checked (LaneError naming the field)."""
    from nbst.models.bowling import lane

    return lane.Delivery(hand=args.hand, board=args.board, at=args.at, angle=args.angle, mph=args.mph,
                         rpm=args.rpm, rotation=args.rotation, tilt=args.tilt).check()


def ball_of(args):
    """The ball of the :func:`ball_flags`, checked (LaneError naming the field outside USBC's limits)."""
    from nbst.models.bowling import lane

    return lane.Ball(weight_lb=args.weight, rg=args.rg, diff=args.diff, friction=args.cover).check()


def mc_flags(t, samples: int, what: str) -> None:
    """--oil, --seed, --jobs, --samples, --json, -q: the Monte Carlo subcommands' flags."""
    oil_flag(t)
    t.add_argument("--seed", type=SEED, default=1, help="seed of the release noise (default 1: same command, "
                                                         "same numbers)")
    t.add_argument("--jobs", type=JOBS, default=None, metavar="K", help="processes running frames (default: all cores)")
    t.add_argument("--samples", type=Bounded("samples", 1, 100_000, integer=True), default=samples, metavar="N",
                   help=f"noisy throws per {what} (default {samples})")
    t.add_argument("--json", action="store_true", help="print the result as one JSON object")
    t.add_argument("-q", "--quiet", action="store_true", help="no progress")


def check_picture_args(args) -> str | None:
    """The first problem with the picture flags (--video, --still, --still-time,
    --size, --fps), as one line, or None. Reads nothing, writes nothing."""
    video, still = getattr(args, "video", None), getattr(args, "still", None)
    if video is not None and not str(video).lower().endswith((".mp4", ".gif")):
        return f"--video {video}: use a .mp4 or .gif file"
    if still is not None and not str(still).lower().endswith(".png"):
        return f"--still {still}: use a .png file"
    if video is not None and still is not None and str(video) == str(still):
        return f"--video and --still name the same file {video}"
    for flag, attr in (("--still-time", "still_time"), ("--size", "size"), ("--fps", "fps")):
        if getattr(args, attr, None) is not None and video is None and still is None:
            return f"{flag}: needs --video or --still"
    if getattr(args, "fps", None) is not None and still is not None and video is None:
        return "--fps: sets --video's frame rate; a --still is one frame"
    size = getattr(args, "size", None)
    if size is not None:
        try:
            w, h = (int(v) for v in str(size).lower().split("x"))
        except ValueError:
            return f"--size {size}: expected WxH, e.g. 1280x720"
        if not (16 <= w <= 8192 and 16 <= h <= 8192):
            return f"--size {size}: width and height must be 16..8192 pixels"
        if video is not None and str(video).lower().endswith(".mp4") and (w % 2 or h % 2):
            return f"--size {size}: H.264 (yuv420p) needs an even width and height"
    return None


def wants_picture(args) -> bool:
    """Whether any picture flag (--video, --still, --still-time, --size, --fps) was given."""
    return any(getattr(args, a, None) is not None for a in ("video", "still", "still_time", "size", "fps"))


#: The bowler profiles (models/bowling/lane/profiles.py; a test checks the two lists agree).
BOWLERS = ("pro", "league200", "league150", "twohander")
#: The delivery flags' defaults: --bowler refuses a delivery flag moved from them.
_DELIVERY_DEFAULTS = {"board": 10.0, "at": "arrows", "angle": 1.5, "mph": 17.0, "rpm": 300.0, "rotation": 45.0,
                      "tilt": 15.0, "angle_sigma": 0.15}


def bowler_of(args):
    """(the delivery, the noise) of --bowler, or (None, None) without it; ValueError (one line) when a
    delivery flag is given with it."""
    if getattr(args, "bowler", None) is None:
        return None, None
    from nbst.models.bowling.lane import profiles

    moved = [k for k, v in _DELIVERY_DEFAULTS.items() if getattr(args, k) != v]
    if moved:
        raise ValueError(f"--bowler: sets the release and its noise; drop --{moved[0].replace('_', '-')}")
    p = profiles.profile(args.bowler)
    k = float(args.noise_scale)
    return p.delivery(args.hand), profiles.scaled(p.noise, k)
