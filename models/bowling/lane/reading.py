"""A bowler reading the lane as it is (issue 48): the line with the most strikes under its own
release noise, on the worn lane, among its feet moved in or out and re-aimed to the pocket
(:func:`read_line`), judged by the strike chance by board at the head pin's line
(:func:`strike_chance`). :class:`.transition.Run` calls it for a profile that ``reads_lane`` (off
for every shipped profile: tried for the pro, it does not gain; docs/results/bowling.md).

Compute only.
"""
from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from nbst.models.bowling import lane
from nbst.models.bowling.lane import noise, phases
from nbst.models.bowling.lane.noise import Noise
from nbst.models.bowling.lane.oil import OilField, OilLaw

__all__ = ["TARGET_BOARD", "STRIKE_BY_BOARD", "READ_FEET", "READ_BALLS", "READ_SHIFTS", "READ_MARGIN",
           "strike_chance", "read_line"]

#: The board a strike ball is aimed to cross the head pin's line on (the pocket's middle; the
#: mover's target too, :func:`.transition.move_for`).
TARGET_BOARD = 17.5
#: A reading bowler's (``reads_lane``) strike chance by board at the head pin's line: (board, share)
#: at the middle of each quarter board, on lane-4's pins (``scene.LANE_PINS``: the pins on the pin deck
#: at friction 0.1, the ball on it at 0.2): the pro's 80 first balls of fit seed 11 on the fresh house
#: shot (entering at 4.89 deg, sd 0.38), each carried onto every quarter board of 15-19.5, 1,440 pin
#: decks (``python benchmarks/bench_pocket_angle.py --by-board 15,19.5,0.25 --n 80 --seed 11``,
#: 2026-12-07; docs/results/bowling.md, "Lane-4 as shipped"); 0 outside.
STRIKE_BY_BOARD = ((15.125, 0.01), (15.375, 0.04), (15.625, 0.12), (15.875, 0.26), (16.125, 0.28),
                   (16.375, 0.08), (16.625, 0.14), (16.875, 0.51), (17.125, 0.76), (17.375, 0.99),
                   (17.625, 1.0), (17.875, 0.98), (18.125, 0.82), (18.375, 0.61), (18.625, 0.18),
                   (18.875, 0.01), (19.125, 0.0), (19.375, 0.01))
#: The lines a reading bowler tries (:func:`read_line`): its feet moved these boards (+: in) from
#: where they stand, each re-aimed on the lane as it is; READ_BALLS noisy balls a line (the same
#: draws for every line); the aim's fine-tuning at the pins (boards) tried on those balls.
READ_FEET = (-4.0, -2.0, 0.0, 2.0, 4.0)
READ_BALLS = 16
READ_SHIFTS = tuple(np.arange(-1.0, 1.001, 0.25).round(2))
#: A reading bowler leaves its feet where they are unless another line's expected strike chance beats
#: it by this much (0: the best line; 0.10 was tried, 2026-12-07: no gain).
READ_MARGIN = 0.0


def strike_chance(boards) -> np.ndarray:
    """The strike chance (:data:`STRIKE_BY_BOARD`, interpolated; 0 outside it and for None) of
    strike balls that crossed the head pin's line on ``boards``."""
    b = np.array([np.nan if v is None else float(v) for v in np.atleast_1d(np.asarray(boards, dtype=object))])
    x, y = np.array(STRIKE_BY_BOARD).T
    return np.where(np.isfinite(b), np.interp(np.nan_to_num(b, nan=0.0), x, y, left=0.0, right=0.0), 0.0)


def read_line(strike: lane.Delivery, nz: Noise, field: OilField, oil="house", ball: lane.Ball | None = None, *,
              law: OilLaw = lane.LAW, feet=None, balls: int | None = None, margin: float | None = None,
              seed=0) -> dict:
    """A bowler reading the lane as it is now: the line with the most strikes under its own release noise.

    Each candidate line stands ``feet`` boards in (+) or out from ``strike``'s foul-line board and is
    re-aimed (:func:`.phases.aim_angle`) to board 17.5 at the head pin on ``field``; ``balls`` noisy
    releases of it (``nz``; the same draws for every line: common random numbers) run the ball alone
    on copies of ``field``. A line's worth is its expected strike chance (:func:`strike_chance`) at
    the best fine-tuning of the aim (the balls' boards shifted by one of :data:`READ_SHIFTS`: a
    bowler's small target adjustment); the best line is taken when it beats staying (a move of 0) by
    ``margin``, and is aimed again at 17.5 plus its shift.

    Args:
        strike: the line the bowler stands on now (its hand, release and foul-line board).
        nz: the bowler's release noise.
        field: the lane's oil now (not worn: copies are thrown on).
        oil: the pattern (for the ball's phases).
        ball: the ball (None: the default ball).
        law: the film-to-friction law.
        feet: the candidate moves of the feet (boards, + in; None: :data:`READ_FEET`).
        balls: noisy balls a candidate (None: :data:`READ_BALLS`).
        margin: how much more expected strike chance a move must promise than staying (None:
            :data:`READ_MARGIN`).
        seed: the draws' seed (a sequence of ints is accepted, as numpy's).

    Returns:
        a dict: ``delivery`` (the chosen, aimed line), ``feet`` (its move), ``shift`` and per candidate
        ``lines`` (feet, angle, mean and sd of the boards at the pins, expected strike chance).

    Raises:
        LaneError: no candidate line can be aimed on ``field``.
    """
    feet = READ_FEET if feet is None else tuple(float(f) for f in feet)
    balls = READ_BALLS if balls is None else int(balls)
    rows = nz.mix(np.random.default_rng(seed).standard_normal((balls, len(noise.KEYS))))
    lo = [noise.CLIP[k][0] for k in noise.KEYS]
    hi = [noise.CLIP[k][1] for k in noise.KEYS]
    shifts = np.array(READ_SHIFTS)
    lines: list[dict] = []
    best: tuple[float, dict, lane.Delivery] | None = None
    stay: tuple[float, dict, lane.Delivery] | None = None
    for f in feet:
        base = replace(strike, board=strike.foul_board() + float(f), at="foul")
        try:
            d, _ = phases.aim_angle(base, TARGET_BOARD, oil, ball, law=law, field=field)
        except lane.LaneError:
            continue
        x = noise.perturb([getattr(d, k) for k in noise.KEYS], [getattr(nz, k) for k in noise.KEYS], rows, lo, hi)
        bs: list[float | None] = []
        for r in x:
            fields: dict[str, Any] = {k: float(v) for k, v in zip(noise.KEYS, r)}
            try:
                t = phases.throw(replace(d, **fields), oil, ball, law=law, field=field.copy())
                bs.append(t.board_at_pins)
            except lane.LaneError:
                bs.append(None)
        got = np.array([np.nan if v is None else v for v in bs], dtype=float)
        worth = [float(strike_chance([None if not np.isfinite(v) else v + s for v in got]).mean()) for s in shifts]
        k = int(np.argmax(worth))
        ok = got[np.isfinite(got)]
        rec = {"feet": float(f), "angle": d.angle, "mean": float(ok.mean()) if len(ok) else None,
               "sd": float(ok.std(ddof=1)) if len(ok) > 1 else None, "strike": worth[k], "shift": float(shifts[k])}
        lines.append(rec)
        if best is None or worth[k] > best[0] + 1e-12:
            best = (worth[k], rec, d)
        if f == 0.0:
            stay = (worth[k], rec, d)
    margin = READ_MARGIN if margin is None else float(margin)
    if best is not None and stay is not None and best[0] < stay[0] + margin:
        best = stay
    if best is None:
        raise lane.LaneError("read_line: no candidate line reaches the pocket on this lane")
    _, rec, d = best
    if rec["shift"]:
        try:
            d, _ = phases.aim_angle(d, TARGET_BOARD + rec["shift"], oil, ball, law=law, field=field)
        except lane.LaneError:
            pass
    return {"delivery": d, "feet": rec["feet"], "shift": rec["shift"], "lines": lines}
