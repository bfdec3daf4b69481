"""What every ``nbst bowl`` subcommand shares: pins on the command line, the error line, the
delivery and ball flags of a bowler, the runner and picture flags.

Light: only argparse and nbst's argument types at import; the bowling modules are imported
inside the functions that need them.
"""
from __future__ import annotations

import argparse
import re
import sys

from nbst.cli.args import JOBS, SEED, Bounded, with_limits
from nbst.errors import InputError
from nbst.domain import plain

__all__ = ["number", "size_of", "err", "STRIKE_WORDS", "pin_list", "standing_pins", "pins_down", "leave", "pins_text", "asked_text", "runner_args",
           "picture_flags", "oil_flag", "DELIVERY_KEYS", "BOARD_AT", "delivery_defaults", "bowlers", "bowlers_text", "bowler_flag",
           "delivery_flags", "arrows", "target_board", "ball_flags", "given", "delivery_of", "stance_target",
           "ball_of", "mc_flags", "check_picture_args", "wants_picture", "bowler_of"]

_INT = re.compile(r"[+-]?[0-9]+")
_FLOAT = re.compile(r"[+-]?([0-9]+(\.[0-9]*)?|\.[0-9]+)([eE][+-]?[0-9]+)?")
_SIZE = re.compile(r"([0-9]+)x([0-9]+)")


def number(text: str) -> float | None:
    """``text`` as a finite decimal number (blanks around it allowed), or None when it is not one."""
    t = str(text).strip()
    return float(t) if _FLOAT.fullmatch(t) else None


def size_of(text: str) -> tuple[int, int] | None:
    """``--size`` "WxH" as (width, height) in pixels, or None when it is not two whole numbers."""
    m = _SIZE.fullmatch(str(text).strip().lower().replace(" ", ""))
    return (int(m.group(1)), int(m.group(2))) if m else None


def err(cmd: str, msg: str) -> int:
    """One error line for ``nbst bowl CMD`` on stderr; the exit code 2 (every bowl subcommand)."""
    print(f"nbst bowl {cmd}: error: {plain(msg)}", file=sys.stderr)
    return 2


#: What a bowler writes for nothing standing: a strike to ``solve --leave`` (:func:`leave`), refused in
#: one line by the --leave of frame, advise and spares (:func:`pin_list`), which want pins to throw at.
STRIKE_WORDS = ("x", "none", "strike")


def pin_list(text: str, flag: str | None = None) -> int:
    """Pin numbers "1,2,4,7" -> 10-bit mask (bit n-1 = pin n): the one parser of every --leave
    (``bowl frame``, ``advise``, ``spares``, ``solve``). Pins are separated by commas and/or blanks
    ("4, 9", "3 10") or joined by dashes as bowlers write a leave ("4-7-10"). ``flag`` names the
    option in the message (argparse names it itself for a ``type=``: then leave it out, so it is
    said once)."""
    pre = f"{flag}: " if flag else ""
    t = text.strip()
    if t.lower() in STRIKE_WORDS and flag in ("--leave", "--leaves"):   # a coach's "x": the strike it is, alike
        raise argparse.ArgumentTypeError(f"{pre}{text.strip()!r} is a strike, nothing standing: name the pins "
                                         "standing, numbers 1..10 (e.g. 3,10)")
    dashed = "-" in t and all(_INT.fullmatch(p) for p in t.replace(" ", "").split("-"))   # "4-7-10"
    words = t.replace(" ", "").split("-") if dashed else [p for p in re.split(r"[,\s]+", t) if p]
    if not all(_INT.fullmatch(p) for p in words):
        raise argparse.ArgumentTypeError(f"{pre}pins must be numbers 1..10 separated by commas or spaces, or "
                                         f"joined by dashes (e.g. 1,2,4,7 or 3 10 or 4-7-10), got {text!r}")
    pins = [int(p) for p in words]
    bad = [p for p in pins if not 1 <= p <= 10]
    if bad or not pins:
        raise argparse.ArgumentTypeError(f"{pre}pins must be numbers 1..10, each once (at least one), got {text!r}")
    twice = sorted({p for p in pins if pins.count(p) > 1})
    if twice:   # a coach's "10,10" ran as the 10 alone; "10,7,10" as the 7-10
        raise argparse.ArgumentTypeError(f"{pre}pin {', '.join(map(str, twice))} named twice in {text!r}: "
                                         "name each pin once")
    return sum(1 << (p - 1) for p in pins)


def standing_pins(text: str, flag: str = "--leave") -> list[int]:
    """The pins of a --leave (:func:`pin_list`), sorted; InputError (one line naming ``flag``)."""
    try:
        mask = pin_list(text, flag)
    except argparse.ArgumentTypeError as e:
        raise InputError(str(e)) from None
    return [n for n in range(1, 11) if mask >> (n - 1) & 1]


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

    if text.strip().lower() in STRIKE_WORDS:
        return ALL_DOWN
    down = ALL_DOWN & ~pin_list(text)
    if not down:
        raise argparse.ArgumentTypeError("all ten pins standing is a gutter ball (any delivery into the gutter); "
                                         "name at most 9 pins")
    return down


def pins_text(pins) -> str:
    """Pins as a leave is written ("3-6-10"), or "none"."""
    return "-".join(str(p) for p in pins) if pins else "none"


def asked_text(down: list[int], leave: bool) -> str:
    """What ``bowl solve`` was asked for, in the words it was asked in: "leave 7,10" for
    ``--leave`` (the pins left standing, not the pins knocked down), "down 1,2,4,7" for ``--down``.

    Args:
        down: the pins asked to be knocked down (the pins of the request's mask).
        leave: whether the request came as ``--leave``.
    """
    if leave:
        return f"leave {','.join(str(n) for n in range(1, 11) if n not in down) or 'none'}"
    return f"down {','.join(map(str, down))}"


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
                        "outcome; render/bowling/lane.py)")
    p.add_argument("--still", default=None, metavar="OUT.png",
                   help="also draw one frame as PNG (by default just before the ball meets the pins)")
    p.add_argument("--still-time", type=Bounded("still-time", 0, 30, unit="s"), default=None, metavar="S",
                   help="the --still's moment, seconds after the release")
    p.add_argument("--size", default=None, metavar="WxH", help="frame size of --video/--still (default 1280x720)")
    p.add_argument("--fps", type=Bounded("fps", 1, 240), default=None, help="--video's frames per second (default 60)")
    p.add_argument("--camera", choices=("both", "behind", "overhead", "deck"), default=None,
                   help="--video/--still's view: both (behind the bowler and overhead, side by side; default), "
                        "behind, overhead, or deck (the pin deck close up: the ball into the pins, the pins flying)")
    p.add_argument("--clean", action="store_true", help="--video/--still without overlay text (the picture alone)")


def oil_flag(t) -> None:
    """--oil: a pattern registered in :data:`nbst.models.bowling.lane.oil.PATTERNS` (its names and
    descriptions are the choices and the help), or a pattern file."""
    from nbst.models.bowling.lane.oil import DEFAULT_OIL, PATTERNS, argtype

    t.add_argument("--oil", default=DEFAULT_OIL, type=argtype("--oil"), metavar="PATTERN",
                   help=f"oil pattern (default {DEFAULT_OIL}): {PATTERNS.help_text()}; or a pattern file "
                        "(nbst-oil-pattern JSON: a lane machine's sheet of load and buff rows; docs/formats.md)")


#: The delivery flags (their defaults: :func:`delivery_defaults`).
DELIVERY_KEYS = ("hand", "board", "at", "angle", "mph", "rpm", "rotation", "tilt")
#: A release speed above this (mph) gets a note: no bowler's, and most likely km/h (30 km/h is 18.6 mph).
FAST_MPH = 24.0
#: Where a --board given without --at is: at the arrows.
BOARD_AT = "arrows"


def delivery_defaults() -> dict:
    """The delivery flags' defaults: the release of the library's house profile
    (:data:`nbst.models.bowling.lane.profiles.HOUSE_PROFILE`, a typical house bowler's strike
    ball), right-handed, its board at the foul line (a --bowler's release replaces them; a flag
    given beside it overrides it)."""
    from nbst.models.bowling.lane import profiles

    return profiles.house_release().to_dict()


def bowlers() -> tuple[str, ...]:
    """The bowler profiles' names (:data:`nbst.models.bowling.lane.profiles.PROFILES`), read when a
    parser is built (the profiles' module reads their data files)."""
    from nbst.models.bowling.lane.profiles import NAMES

    return NAMES


def bowlers_text() -> str:
    """Each profile's name, speed and rev rate, from the registry, for the help texts."""
    from nbst.models.bowling.lane.profiles import PROFILES

    return ", ".join(f"{e.name} {e.value.strike.mph:g} mph {e.value.strike.rpm:g} rpm" for e in PROFILES.entries())


def bowler_flag(t, what: str = "throw", *, hand: bool = True, delivery: bool | None = None) -> None:
    """--bowler P: a profile's release as the default release and its correlated noise (``hand``:
    the command has --hand; else its lines are a right-hander's, and the help says how a
    left-hander reads them; ``delivery``: it has the delivery flags, by default as ``hand``)."""
    delivery = hand if delivery is None else delivery
    mirror = ("--hand mirrors it" if hand else "right-handed: a left-hander's lane is its mirror image (boards "
              "counted from the left; the 7 for the 10, the 4-10 for the 6-7)")
    t.add_argument("--bowler", default=None, choices=bowlers(),
                   help=f"{what} as this bowler profile: its strike ball (release and line, aimed at board 17.5 on the "
                        "fresh house shot) is the default release and its correlated release noise gives the "
                        f"probabilities: {bowlers_text()} (docs/bowling.md); {mirror}"
                        + ("; a delivery flag given beside it overrides that part of the release" if delivery else
                           " (this command takes no delivery flags: the release is the profile's)")
                        + "; recorded in the output")


def delivery_flags(t, *, bowler: bool = True) -> None:
    """The delivery flags of ``bowl throw`` and ``bowl frame``: one vocabulary, one help text
    (defaults :func:`delivery_defaults`, filled by :func:`delivery_of`, so that a flag given
    beside --bowler is told from one left out)."""
    from nbst.models.bowling.lane.advise import STANCE_SEP
    from nbst.models.bowling.lane.profiles import HOUSE_PROFILE

    D = delivery_defaults()
    t.add_argument("--hand", choices=("right", "left"), default=None, help="bowling hand (default right)")
    t.add_argument("--board", type=Bounded("board", 1, 39), default=None, metavar="B",
                   help=f"board where the ball is at --at (1..39, fractions allowed; default: the {HOUSE_PROFILE} "
                        f"profile's line, a typical house bowler's, board {D['board']:g} at the foul line)")
    t.add_argument("--at", choices=("foul", "arrows"), default=None,
                   help="where --board is: at the foul line, or where the ball crosses the arrows, 15 ft out, "
                        "along its real path (the board at the foul line is found by running the ball alone; "
                        f"default {BOARD_AT} for a --board given)")
    t.add_argument("--angle", type=Bounded("angle", -10, 10, unit="deg"), default=None, metavar="DEG",
                   help=f"launch angle from straight down the lane, + out towards board 1 (default {D['angle']:g})")
    t.add_argument("--stance", type=Bounded("stance", 1, 39), default=None, metavar="B",
                   help="where the bowler stands: the board of the slide foot on the approach (walking straight; "
                        "1..39, the approach's boards numbered as the lane's); "
                        "the ball is released %g boards towards the hand (a medium frame's ball-to-foot "
                        "separation, docs/bowling.md); with --target instead of --board/--at/--angle" % STANCE_SEP)
    t.add_argument("--target", type=target_board, default=None, metavar="ARROW",
                   help="where the bowler looks: an arrow (1st-arrow .. 7th-arrow, boards 5..35; e.g. 2nd-arrow) or "
                        "a board at the arrows, 15 ft out; the launch angle is found so the ball's real path "
                        "crosses it (needs --stance)")
    t.add_argument("--mph", type=Bounded("mph", 5, 30, unit="mph"), default=None,
                   help=f"release speed (default {D['mph']:g})")
    t.add_argument("--rpm", type=Bounded("rpm", 0, 800, unit="rpm"), default=None, help=f"rev rate (default {D['rpm']:g})")
    t.add_argument("--rotation", type=Bounded("rotation", 0, 90, unit="deg"), default=None, metavar="DEG",
                   help=f"axis rotation: 0 end over end, 90 pure side spin (default {D['rotation']:g})")
    t.add_argument("--tilt", type=Bounded("tilt", 0, 90, unit="deg"), default=None, metavar="DEG",
                   help=f"axis tilt: 0 a horizontal spin axis (default {D['tilt']:g})")
    if bowler:
        bowler_flag(t)


_ORDINALS = ("1st", "2nd", "3rd", "4th", "5th", "6th", "7th")


def arrows() -> dict[str, float]:
    """The arrows by ordinal ("1st" .. "7th") and their boards, counted from the bowling hand's edge
    (the lane's :data:`nbst.models.bowling.lane.units.ARROW_BOARDS`)."""
    from nbst.models.bowling.lane.units import ARROW_BOARDS

    return {k: float(b) for k, b in zip(_ORDINALS, ARROW_BOARDS)}


def target_board(text: str) -> float:
    """``--target``: "2nd-arrow" (or "2nd arrow", "arrow2", "2nd") -> board 10; a number -> that board."""
    t = str(text).strip().lower().replace("_", "-").replace(" ", "-")
    for k, b in arrows().items():
        if t in (f"{k}-arrow", k, f"arrow{k[0]}", f"arrow-{k[0]}"):
            return b
    given = number(t)
    if given is None:
        raise argparse.ArgumentTypeError(f"expected an arrow (1st-arrow .. 7th-arrow) or a board 1..39, got {text!r}")
    if not (1.0 <= given <= 39.0):
        raise argparse.ArgumentTypeError(f"a board at the arrows must be 1..39, got {text!r}")
    return given


def ball_flags(t) -> None:
    """The ball flags of ``bowl throw`` and ``bowl frame`` (the ball maker's units; lane.Ball checks
    them): --ball names one of :data:`nbst.models.bowling.lane.ball.BALLS` (its fields the defaults
    of the others, which override them)."""
    from nbst.models.bowling.lane.ball import BALLS, DEFAULT_BALL

    b = BALLS[DEFAULT_BALL]
    t.add_argument("--ball", default=DEFAULT_BALL, choices=BALLS.names(),
                   help=f"the ball (default {DEFAULT_BALL}): {BALLS.help_text()}; --weight, --rg, --diff and --cover "
                        "given beside it override its fields")
    t.add_argument("--weight", type=float, default=None, metavar="LB",
                   help=f"ball weight, lb (default the ball's, {b.weight_lb:g}; at most 16)")
    t.add_argument("--rg", type=float, default=None, metavar="IN",
                   help=f"ball RG, in (default the ball's, {b.rg:.2f}; USBC 2.46..2.80)")
    t.add_argument("--diff", type=float, default=None, metavar="IN",
                   help=f"RG differential, in (default the ball's, {b.diff:.3f}; USBC at most 0.060)")
    t.add_argument("--cover", type=float, default=None, metavar="MU",
                   help=f"coverstock friction on the dry lane (default the ball's, {b.friction:.2f}; USBC at most 0.32)")


def given(args) -> dict:
    """The delivery flags given on the command line (not left at None), by name."""
    keys = (*DELIVERY_KEYS, "stance", "target")
    return {k: getattr(args, k) for k in keys if getattr(args, k, None) is not None}


def delivery_of(args, base=None):
    """The delivery of the :func:`delivery_flags`, checked (LaneError naming the field): ``base``
    (a --bowler's strike ball) or :func:`delivery_defaults`, with every flag given put over it. A
    --board given without --at is at the arrows (its default); --stance/--target give the board at
    the foul line and a target the caller aims through (:func:`stance_target`)."""
    from dataclasses import replace

    from nbst.models.bowling import lane

    g = given(args)
    if g.get("mph", 0) > FAST_MPH and not getattr(args, "quiet", False):   # km/h given for mph, most likely
        import sys

        print(f"note: --mph {g['mph']:g} is far faster than bowlers release (the pro profile's 18.6 mph is PBA League "
              f"2020's men's mean); if you meant km/h, {g['mph']:g} km/h is {g['mph'] / 1.609344:.1f} mph",
              file=sys.stderr)
    st = stance_target(args)
    d = lane.Delivery(**delivery_defaults()) if base is None else base
    over = {k: v for k, v in g.items() if k in DELIVERY_KEYS}
    if "board" in over and "at" not in over:
        over["at"] = BOARD_AT
    if st is not None:
        over.update(board=st[0], at="foul")
    return replace(d, **over).check()


def stance_target(args):
    """(board at the foul line, target board at the arrows) of --stance/--target, or None; InputError
    (one line) when only one is given, or beside --board/--at/--angle."""
    from nbst.models.bowling.lane.advise import STANCE_SEP

    s, t = getattr(args, "stance", None), getattr(args, "target", None)
    if s is None and t is None:
        return None
    if s is None or t is None:
        raise InputError("--stance and --target go together: where you stand and where you look")
    clash = [f for f in ("board", "at", "angle") if getattr(args, f, None) is not None]
    if clash:
        raise InputError(f"--{clash[0]}: --stance/--target set the line; drop --{clash[0]}")
    foul = float(s) - STANCE_SEP
    if not 1.0 <= foul <= 39.0:
        raise InputError(f"--stance {s:g}: the ball would be released on board {foul:g} ({STANCE_SEP:g} boards towards "
                         "the hand), off the lane (1..39)")
    return foul, float(t)


def ball_of(args):
    """The ball of the :func:`ball_flags`: --ball's, with every field flag given over it, checked
    (LaneError naming the field outside USBC's limits)."""
    from dataclasses import replace

    from nbst.models.bowling.lane.ball import BALLS, DEFAULT_BALL

    from nbst.models.bowling.lane import LaneError

    base = BALLS[getattr(args, "ball", None) or DEFAULT_BALL]
    flags = (("weight_lb", "weight"), ("rg", "rg"), ("diff", "diff"), ("friction", "cover"))
    over = {k: getattr(args, a) for k, a in flags if getattr(args, a, None) is not None}
    try:
        return replace(base, **over).check()
    except LaneError as e:   # the flag given, by its name on the command line (not the ball's field)
        text = str(e)
        for k, a in flags:
            if k in over and text.startswith(f"ball.{k}:"):
                raise InputError(f"--{a} {over[k]:g}:{text[len(f'ball.{k}:'):]}") from None
        raise


def mc_flags(t, samples: int | None, what: str) -> None:
    """--oil, --seed, --jobs, --samples, --json, -q: the Monte Carlo subcommands' flags (``samples``
    None: no --samples, the command counting its throws another way, as frame's --probability N)."""
    oil_flag(t)
    t.add_argument("--seed", type=SEED, default=1, help="seed of the release noise (default 1: same command, "
                                                         "same numbers)")
    t.add_argument("--jobs", type=JOBS, default=None, metavar="K", help="processes running frames (default: all cores)")
    if samples is not None:
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
    for flag, attr in (("--still-time", "still_time"), ("--size", "size"), ("--fps", "fps"), ("--camera", "camera")):
        if getattr(args, attr, None) is not None and video is None and still is None:
            return f"{flag}: needs --video or --still"
    if getattr(args, "fps", None) is not None and still is not None and video is None:
        return "--fps: sets --video's frame rate; a --still is one frame"
    size = getattr(args, "size", None)
    if size is not None:
        wh = size_of(size)
        if wh is None:
            return f"--size {size}: expected WxH, e.g. 1280x720"
        w, h = wh
        if not (16 <= w <= 8192 and 16 <= h <= 8192):
            return f"--size {size}: width and height must be 16..8192 pixels"
        if video is not None and str(video).lower().endswith(".mp4") and (w % 2 or h % 2):
            return f"--size {size}: H.264 (yuv420p) needs an even width and height"
    return None


def wants_picture(args) -> bool:
    """Whether any picture flag (--video, --still, --still-time, --size, --fps) was given."""
    return any(getattr(args, a, None) is not None for a in ("video", "still", "still_time", "size", "fps", "camera"))


def bowler_of(args, *, spare: bool = False):
    """(the delivery, the noise) of --bowler (with every delivery flag given put over its strike
    ball, :func:`delivery_of`; the noise of its strike ball, or of its spare throws with
    ``spare``, times --noise-scale where the command has one), or (None, None) without --bowler."""
    if getattr(args, "bowler", None) is None:
        return None, None
    from nbst.models.bowling.lane import profiles

    p = profiles.profile(args.bowler)
    hand = getattr(args, "hand", None) or "right"
    base = p.delivery(hand)
    d = delivery_of(args, base) if hasattr(args, "board") else base
    k = getattr(args, "noise_scale", None)
    return d, profiles.scaled(p.spare() if spare else p.noise, 1.0 if k is None else float(k))
