"""``nbst bowl spares``, ``pocket`` and ``advise``: what a coach asks of the lane half -- the best
line at each leave, the pocket map, and where to stand and look (models/bowling/lane/spares.py,
advise.py, names.py).

Every readout names the leave (:mod:`nbst.models.bowling.lane.names`) and says that one
throw's outcome is a sample and its probability the result.
"""
from __future__ import annotations

import sys

from nbst.cli.args import Bounded, print_json
from nbst.cli.bowl.args import bowler_flag, bowler_of, mc_flags, number, standing_pins
from nbst.errors import InputError
from nbst.cli.bowl.lane import _bar
from nbst.parallel import default_jobs
from nbst.outputs import atomic_path, prepare_output

__all__ = ["register", "register_advise", "cmd_advise", "noise_line", "spare_frames", "cmd_spares", "leaves_of", "spare_doc",
           "spare_line", "cmd_pocket"]


def register(bowl) -> None:
    """``spares``, ``pocket`` and ``advise`` on ``nbst bowl``'s subparsers (their defaults read from
    :mod:`nbst.models.bowling.lane.spares`)."""
    from nbst.models.bowling.lane import spares

    s = bowl.add_parser("spares", help="the throw converting a leave (any, or each common one) with the highest "
                                       "probability",
                        description="For each leave, the 3-6-9 system's line (the strike ball, feet moved 3/6/9 "
                                    "boards, same target arrow) and straight spare balls (cross-lane at 17 and 21 mph, "
                                    "from the middle and straight down the boards, at the leave's aim point and 1-2 "
                                    "boards either side) are "
                                    "screened on --screen noisy throws each; the best is polished by a robust "
                                    "search (--polish) and measured on --samples, beside the 3-6-9 line "
                                    "(docs/bowling.md).",
                        epilog="Example: nbst bowl spares --leaves 10,7 --samples 40")
    which = s.add_mutually_exclusive_group()
    which.add_argument("--leave", default=None, metavar="PINS",
                       help="one leave to shoot, its pins standing: --leave 3,10 (any pins 1..10 but all ten)")
    which.add_argument("--leaves", default=None, metavar="L1,L2",
                       help="leaves to shoot, '-' joining pins, ',' between leaves, any leave (default: "
                            f"{', '.join(spares.LEAVES)})")
    bowler_flag(s, "shoot", hand=True, delivery=False)
    hand_flag(s)
    s.add_argument("--screen", type=Bounded("screen", 1, 10_000, integer=True), default=spares.SCREEN, metavar="M",
                   help=f"noisy throws per candidate in the screening (default {spares.SCREEN})")
    s.add_argument("--polish", type=Bounded("polish", 0, 1_000_000, integer=True), default=None, metavar="N",
                   help="noisy frames per leave for polishing the pick with a robust search (an evolution "
                        "strategy on common noisy throws; skipped where the pick converted every screening "
                        f"throw or nothing converted); default {spares.POLISH_PER_SCREEN} x --screen "
                        f"({spares.POLISH_PER_SCREEN * spares.SCREEN}); 0: no polish")
    mc_flags(s, 60, "measured throw")
    s.set_defaults(func=cmd_spares)

    p = bowl.add_parser("pocket", help="pocket map: strike probability over board x entry angle (a PNG), and carry",
                        description="Aim a delivery at each (board at the head pin, entry angle) cell, run --samples "
                                    "noisy frames of it, and draw the strike probability as a heatmap beside the "
                                    "strike share of all frames by actual entry; carry = strikes / pocket hits "
                                    "(actual board 17-18). The published pocket (17.5, ~6 deg) is marked.",
                        epilog="Example: nbst bowl pocket -o pocket.png --samples 40")
    p.add_argument("-o", "--output", required=True, metavar="MAP.png", help="the heatmap (PNG)")
    p.add_argument("--boards", default="15.5:19.5:1", metavar="A:B:STEP", help="boards (default 15.5:19.5:1)")
    p.add_argument("--angles", default="2:7:1", metavar="A:B:STEP", help="entry angles, deg (default 2:7:1)")
    bowler_flag(p, "aim", hand=False)
    mc_flags(p, 40, "cell")
    p.set_defaults(func=cmd_pocket)
    register_advise(bowl)


def hand_flag(p) -> None:
    """--hand of ``spares`` and ``advise --leave``: a left-hander's lines, worked out on the mirror-image
    lane (the oil pattern must be mirror-symmetric)."""
    p.add_argument("--hand", choices=("right", "left"), default="right",
                   help="the bowling hand (default right); left: the leave in a left-hander's pins (the 7 its "
                        "corner pin), its lines worked out on the mirror-image lane and said in its boards, "
                        "counted from its own gutter (the oil pattern must be mirror-symmetric)")


def _mirror(args) -> bool:
    """Whether ``args`` asks a left-hander's lines; refused (one line) on a pattern that is not
    mirror-symmetric, where a left-hander's lane is not a right-hander's mirrored."""
    from nbst.models.bowling import lane

    if getattr(args, "hand", "right") != "left":
        return False
    if not lane.pattern(args.oil).symmetric():
        raise InputError(f"--hand left: the oil pattern {args.oil} is not mirror-symmetric, so a left-hander's "
                         f"lines are not a right-hander's mirrored; give a symmetric pattern")
    return True


def register_advise(bowl) -> None:
    """``advise`` on ``nbst bowl``'s subparsers."""
    from nbst.models.bowling.lane import spares

    a = bowl.add_parser("advise", help="where to stand and where to look: at a leave, or after a frame",
                        description="A coach's advice in a bowler's units. --leave PINS: the spare tool's best line "
                                    "at the leave (bowl spares, under the --bowler's release noise), said as the "
                                    "stance board and the target at the arrows (where the ball's real path crosses "
                                    "them), with the conversion probability and its 95 % Wilson interval. --after "
                                    "THROW.json (a frame's throw file, bowl frame -o): the hit and the leave named, "
                                    "and the move: after a strike ball, in the direction of the miss, feet 2 boards "
                                    "and eyes 1 per step (the 2-and-1 move; after a gutter ball, towards that "
                                    "gutter); after a spare ball, stay if it converted, else the feet kept and the "
                                    "eyes moved so that the ball passes the leave's aim point; the moved line thrown "
                                    "(the ball alone) to show where it now meets the pins or passes the aim "
                                    "(docs/bowling.md).",
                        epilog="Examples: nbst bowl advise --bowler league200 --leave 10 --samples 40; "
                               "nbst bowl frame --bowler pro -o f.json && nbst bowl advise --after f.json")
    what = a.add_mutually_exclusive_group(required=True)
    what.add_argument("--leave", default=None, metavar="PINS", help="the leave: pins standing, e.g. 10 or 3,10")
    what.add_argument("--after", default=None, metavar="THROW.json", help="a frame's throw file (bowl frame -o)")
    bowler_flag(a, "advise", hand=True, delivery=False)
    hand_flag(a)
    a.add_argument("--screen", type=Bounded("screen", 1, 10_000, integer=True), default=spares.SCREEN, metavar="M",
                   help=f"--leave: noisy throws per candidate line in the screening (default {spares.SCREEN})")
    a.add_argument("--polish", type=Bounded("polish", 0, 1_000_000, integer=True), default=0, metavar="N",
                   help="--leave: noisy frames polishing the pick (bowl spares --polish; default 0: none)")
    mc_flags(a, 60, "measured line")
    a.set_defaults(func=cmd_advise)


def cmd_advise(args) -> int:
    from nbst.models.bowling import lane
    from nbst.models.bowling.lane import advise, frame, noise, throwfile

    if args.after is not None:
        d = throwfile.load(args.after)
        throwfile.replayable(d, args.after)
        mv = advise.move_after(d, throwfile.oil_of(d), lane.Ball(**d["ball"]))
        doc = {"after": str(args.after), **mv.to_dict(), "note": _note()}
        if args.json:
            print_json(doc)
            return 0
        print(mv.text)
        if mv.check_text:
            print(f"check: {mv.check_text}")
        lv = d["outcome"]["leave"]
        if lv and len(lv) < 10:   # all ten standing (a gutter ball at a full rack): no spare to shoot
            print(f"spare: nbst bowl advise --leave {','.join(map(str, lv))}"
                  + (f" --bowler {args.bowler}" if args.bowler else ""))
        print(f"note: {_note()}")
        return 0
    args.leaves = None
    (leave,) = leaves_of(args)
    lane.pattern(args.oil)
    mirror = _mirror(args)
    if mirror:
        from nbst.models.bowling.lane import spares as _spares

        leave = _spares.mirrored(leave)   # the right-hander's mirror image, worked out on the mirrored lane
    strike, nz = bowler_of(args, spare=True)
    strike = _strike(strike)
    nz = noise.DEFAULT if nz is None else nz
    bar = _bar(args, spare_frames(leave, args.screen, args.samples, args.polish), "advise frames")
    try:
        with frame.FrameRunner(args.oil, jobs=args.jobs or default_jobs()) as R:
            adv = advise.advise_leave(leave, args.samples, args.seed, runner=R, noise=nz, strike=strike,
                                      screen=args.screen, polish=args.polish, on_done=lambda: bar.update(1),
                                      mirror=mirror)
    except KeyboardInterrupt:
        bar.close()
        print("nbst bowl advise: interrupted; no advice", file=sys.stderr)
        return 130
    except BaseException:   # an error (one line from nbst.cli.main) ends the bar first
        bar.close()
        raise
    bar.close()
    doc = {**adv.to_dict(), "hand": args.hand, "bowler": args.bowler, "noise": nz.to_dict(), "noise_of": noise_line(args.bowler, nz),
           "seed": args.seed, "note": _note()}
    if args.json:
        print_json(doc)
        return 0
    print(adv.text)
    if adv.count_text:
        print(adv.count_text)
    if adv.spare.get("ranked_note"):   # the measured throws ranked another line over the screening's pick
        print(f"pick: {adv.spare['ranked_note']}")
    print(noise_line(args.bowler, nz))
    print(f"note: {_note()}")
    return 0


def _strike(strike):
    """The strike ball of the 3-6-9 line: the --bowler's, or without one the default release every
    command throws (:func:`.args.delivery_defaults`: league200's strike ball, docs/bowling.md), not
    issue 22's older line (:data:`.spares.STRIKE`)."""
    if strike is not None:
        return strike
    from nbst.models.bowling.lane import profiles

    return profiles.house_release()


def noise_line(bowler, nz) -> str:
    """Which release noise a spare command threw with: the --bowler's spare noise, or (no --bowler)
    the default release noise, its sigmas said."""
    sig = (f"board {nz.board:g}, angle {nz.angle:g} deg, {nz.mph:g} mph, {nz.rpm:g} rpm, rotation {nz.rotation:g} deg, "
           f"tilt {nz.tilt:g} deg")
    if bowler:
        return f"noise: bowler {bowler}'s spare-ball noise ({sig})"
    return f"noise: the default release noise, no --bowler ({sig}; --bowler P throws with a profile's)"


def spare_frames(leave: str, screen: int, samples: int, polish: int) -> int:
    """Frames :func:`.spares.best_spare` runs at ``leave`` at most (its candidates screened, three
    screened more and their ladders, the measures: the 3-6-9 line, the three, the lines for the
    count, a measured pick's ladder, the polish and its measures)."""
    from nbst.models.bowling.lane import spares

    return ((5 + spares.COUNT_LINES) * samples + spares.candidate_count(leave) * screen + 3 * 2 * screen + 13
            + (polish + 2 * samples) * (polish > 0))


def _grid(text: str, flag: str, lo: float, hi: float) -> list:
    import numpy as np

    parts = [number(v) for v in text.split(":")]
    if len(parts) != 3 or None in parts:
        raise InputError(f"{flag}: must be A:B:STEP (numbers), got {text!r}")
    a, b, st = (float(v) for v in parts if v is not None)
    if not (lo <= a <= b <= hi and st > 0 and (b - a) / st <= 40):
        raise InputError(f"{flag}: need {lo:g} <= A <= B <= {hi:g}, STEP > 0 and at most 41 values, got {text!r}")
    return [round(float(v), 6) for v in np.arange(a, b + st / 2, st)]


def cmd_spares(args) -> int:
    from nbst.models.bowling import lane
    from nbst.models.bowling.lane import frame, spares

    names = leaves_of(args)
    lane.pattern(args.oil)
    mirror = _mirror(args)
    strike, nz = bowler_of(args, spare=True)
    strike = _strike(strike)
    from nbst.models.bowling.lane import noise

    nz = noise.DEFAULT if nz is None else nz
    out = []
    # frames per leave: 17 candidates (19 on a multi-pin leave) screened, 3 x 2 more screens, the measures,
    # then at most the polish's budget and its measure (a skipped polish leaves the bar short of its total)
    polish = spares.POLISH_PER_SCREEN * args.screen if args.polish is None else args.polish
    total = sum(spare_frames(nm, args.screen, args.samples, polish) for nm in names)
    bar = _bar(args, total, "spare frames")
    try:
        with frame.FrameRunner(args.oil, jobs=args.jobs or default_jobs()) as R:
            for nm in names:
                res = spares.best_spare(spares.mirrored(nm) if mirror else nm, args.samples, args.seed, runner=R,
                                        screen=args.screen, on_done=lambda: bar.update(1), polish=polish, nz=nz,
                                        strike=strike, mirror=mirror)
                out.append(spare_doc(res, oil=args.oil, mirror=mirror))
                if not args.json:
                    bar.clear() if hasattr(bar, "clear") else None
                    print(spare_line(out[-1]), flush=True)
    except KeyboardInterrupt:
        bar.close()
        print(f"nbst bowl spares: interrupted after {len(out)} of {len(names)} leaves", file=sys.stderr)
        return 130
    bar.close()
    if args.json:
        print_json({"seed": args.seed, "samples": args.samples, "screen": args.screen, "polish": polish,
                    "bowler": args.bowler, "noise": nz.to_dict(), "note": _note(), "spares": out})
    else:
        print(noise_line(args.bowler, nz))
        print(f"note: {_note()}")
    return 0


def _note() -> str:
    from nbst.models.bowling.lane.advise import SAMPLE_NOTE

    return SAMPLE_NOTE


def leaves_of(args) -> list[str]:
    """The leaves of ``bowl spares`` and ``advise`` ('-' joined pins): --leave (one: its pins by the
    one parser of every --leave, :func:`.args.standing_pins`, as ``bowl frame`` reads them: commas
    and/or blanks, or dashes), --leaves (several, ',' between them, '-' joining a leave's pins), or
    the common ones; InputError (one line naming the flag) for a pin outside 1..10, an empty leave
    (a strike: nothing to shoot) or all ten standing (a first ball)."""
    from nbst.models.bowling.lane import spares

    if args.leave is not None:
        raw, flag = [args.leave], "--leave"
    elif args.leaves is not None:
        raw, flag = [x.strip() for x in args.leaves.split(",")], "--leaves"
    else:
        return list(spares.LEAVES)
    out = []
    for nm in raw:
        if not nm.strip():
            raise InputError(f"{flag}: an empty leave is a strike, nothing standing: name the pins standing, "
                             "numbers 1..10 (e.g. 3,10)")
        pins = standing_pins(nm, flag)
        if len(pins) == 10:
            raise InputError(f"{flag}: {nm.strip()!r} is all ten pins standing: a first ball, not a spare")
        key = "-".join(map(str, pins))
        if key not in out:   # "10,7-10,10": the 10 measured once
            out.append(key)
    return out


def spare_doc(res, oil=None, mirror: bool = False) -> dict:
    """A spare result (spares.SpareResult) as a dict, with its leave's names; with ``oil`` (the
    pattern thrown on), ``system_369_gutter`` says where the 3-6-9 line's noise-free ball leaves the
    lane when it does (a coach read its 0 % as a line that misses the pins)."""
    from nbst.models.bowling import lane
    from nbst.models.bowling.lane import names, spares

    d = spares.mirror_doc(res.to_dict()) if mirror else res.to_dict()   # a left-hander's pins and hand
    d["names"] = names.leave_names(range(1, 11), spares.leave_pins(d["leave"]))
    if oil is not None:
        try:
            lane.throw(lane.Delivery(**d["system_369"]), oil)
        except lane.GutterBall as g:
            d["system_369_gutter"] = {"side": g.side, "ft": round(g.ft, 2)}
        except lane.LaneError:
            pass
    return d


def _left(leave) -> str:
    return "converted" if not leave else "left: " + ",".join(map(str, leave))


def spare_line(r: dict) -> str:
    """One leave's row of ``bowl spares``: the pick (where no line converts, the line that took the most
    pins on the measured throws, as ``advise`` says it), the 3-6-9 line, the pick's ladder."""
    from nbst.models.bowling.lane.advise import pins_rate

    e, s, b, label = r["estimate"], r["system_369_estimate"], r["best"], r["best_label"]
    nm = f" ({', '.join(r['names'])})" if r.get("names") else ""
    pins, most = r.get("pins"), r.get("most_pins")
    if not r.get("converts", True) and most:   # ranked on the measured pins, the figure printed
        b, label, pins = most["delivery"], most["label"], most["pins"]
        e = pins_rate(pins, e)
    took = f", {pins['mean']:.2f} of {pins['of']} pins a throw" if pins else ""
    best = "best" if r.get("converts", True) else "no line converts; the most pins"
    return (f"{r['leave']:>8}{nm}  {best}: {label:<18} (board {b['board']:.1f}, {b['angle']:+.2f} deg, "
            f"{b['mph']:.1f} mph, {b['rpm']:.0f} rpm, rotation {b['rotation']:.0f})  {100 * e['p']:3.0f}% ({e['k']}/{e['n']}, CI "
            f"{100 * e['lo']:.0f}-{100 * e['hi']:.0f}%{took})   3-6-9 line (board {r['system_369']['board']:.1f}): "
            + _line_369(s, r.get("system_369_gutter"))
            + "   ladder 1/0.5/0.25 ms, +2 s" + (f" (the screening's pick, {r['best_label']})"
                                                if label != r["best_label"] else "")
            + ": " + " / ".join(_left(x[1]) for x in r["ladder"]))


def _line_369(s: dict, g: dict | None) -> str:
    """The 3-6-9 line's column: its conversion, or, where its noise-free ball is a gutter ball, that
    said first and plainly (a 0 % row read as a line that reaches the pins and misses)."""
    rate = f"{100 * s['p']:.0f}% ({s['k']}/{s['n']}, CI {100 * s['lo']:.0f}-{100 * s['hi']:.0f}%)"
    if not g:
        return rate
    return (f"a gutter ball without noise: the {g['side']} gutter at {g['ft']:.1f} ft, no line to the pins (its "
            f"noisy throws converted {s['k']} of {s['n']})")


def cmd_pocket(args) -> int:
    from nbst.models.bowling import lane
    from nbst.models.bowling.lane import frame, spares

    boards = _grid(args.boards, "--boards", 1, 39)
    angles = _grid(args.angles, "--angles", 0, 10)
    lane.pattern(args.oil)
    if not args.output.lower().endswith(".png"):
        raise InputError(f"{args.output}: -o must name a .png file")
    strike, nz = bowler_of(args)
    from nbst.models.bowling.lane import noise

    nz = noise.DEFAULT if nz is None else nz
    base = spares.STRIKE if strike is None else strike

    prepare_output(args.output)  # before the frames: a link, a FIFO or a folder is refused in one line
    bar = _bar(args, args.samples * len(boards) * len(angles), "pocket frames")
    try:
        with frame.FrameRunner(args.oil, jobs=args.jobs or default_jobs()) as R:
            pm = spares.pocket_map(boards, angles, args.samples, args.seed, runner=R, on_done=lambda: bar.update(1),
                                   nz=nz, base=base)
    except KeyboardInterrupt:
        bar.close()
        print("nbst bowl pocket: interrupted; nothing written", file=sys.stderr)
        return 130
    bar.close()
    fig = spares.pocket_figure(pm)
    with atomic_path(args.output) as tmp:  # the one writer: whole PNG or the previous file
        fig.savefig(tmp)
    b, a, p, k = pm.best()
    ks, ns = pm.carry()
    kc, nc = pm.carry(angles=(4.0, 6.0))
    from nbst.models.bowling.lane.noise import wilson

    doc = {"best": {"board": b, "angle": a, "p": p, "k": k, "n": pm.n}, "carry": {"strikes": ks, "pocket_hits": ns},
           "carry_4_6_deg": {"strikes": kc, "pocket_hits": nc}, "map": pm.to_dict(), "output": args.output,
           "bowler": args.bowler, "note": _note()}
    if args.json:
        doc["map"].pop("hits")
        print_json(doc)
        return 0
    lo, hi = wilson(k, pm.n)
    print(f"wrote {args.output}: {len(boards)} boards x {len(angles)} angles, {pm.n} noisy throws per cell, seed {pm.seed}"
          + (f", bowler {args.bowler} (its release and noise)" if args.bowler else ""))
    print(f"best cell  board {b:g} at {a:g} deg: strike {100 * p:.0f}% ({k}/{pm.n}; 95% CI {100 * lo:.0f}-{100 * hi:.0f}%)")
    for label, (kk, nn) in (("carry (actual board 17-18, any angle)", (ks, ns)), ("carry (17-18 at 4-6 deg)", (kc, nc))):
        if nn:
            l2, h2 = wilson(kk, nn)
            print(f"{label}: {100 * kk / nn:.0f}% ({kk}/{nn}; 95% CI {100 * l2:.0f}-{100 * h2:.0f}%)")
        else:
            print(f"{label}: no pocket hits")
    print(f"note: {_note()}")
    return 0
