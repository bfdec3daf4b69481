"""The ball alone on a lane that it wears (issue 34, issue 48): ``n`` identical throws
(:func:`identical_throws`), and a profile's strike balls under its noise over games
(:func:`strike_wear`): the film under the track, the board and angle at the pins, the track's
width and the oil carried down, with the oil's account. The experiments behind the transition's
figures (benchmarks/bench_transition.py); the same wear as :class:`.transition.Run`'s.

Compute only.
"""
from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from nbst.models.bowling import lane
from nbst.models.bowling.lane import noise, phases
from nbst.models.bowling.lane.oil import CELL_AREA, OilField, OilLaw, pattern
from nbst.models.bowling.lane.transition import film_along, lay_band, lineup

__all__ = ["strike_wear", "identical_throws"]


def strike_wear(profile: str, games: int = 3, seed: int = 1, oil="house", *, per_game: int = 12,
                law: OilLaw = lane.LAW) -> dict:
    """``games`` x ``per_game`` strike balls of ``profile`` (its line and noise, right-handed), the ball
    alone, on one lane of ``oil`` that they wear: the lane after each game (map, ml on it, ml past the
    pattern's end) and the oil's account (``initial`` = ``removed`` (taken by the covers: absorbed or
    wiped off before the next ball) + ``carried`` (on the lane past the pattern's end) + ``remaining``
    (on the lane up to it)). Quick (the ball alone, ~0.03 s a ball): the tests' and figures' transition."""
    b = lineup(profile, 1, 0.0, oil=oil)[0]
    pat = pattern(oil)
    field = OilField.fresh(pat)
    rng = np.random.default_rng([int(seed), 0])
    rows = b.noise.mix(rng.standard_normal((games * per_game, len(noise.KEYS))))
    lo = [noise.CLIP[k][0] for k in noise.KEYS]
    hi = [noise.CLIP[k][1] for k in noise.KEYS]
    out: dict[str, Any] = {"before": pat.grid(), "games": [], "initial": field.total_ml(), "removed": 0.0, "balls": 0}
    for g in range(games):
        for k in range(per_game):
            x = noise.perturb([getattr(b.strike, q) for q in noise.KEYS], [getattr(b.noise, q) for q in noise.KEYS],
                              rows[g * per_game + k][None], lo, hi)[0]
            fields: dict[str, Any] = {q: float(v) for q, v in zip(noise.KEYS, x)}
            d = replace(b.strike, **fields)
            h0 = field.h.copy()
            try:
                r = phases.throw(d, pat, law=law, field=field)
            except lane.LaneError:  # a gutter ball: what it took is still taken
                out["removed"] += float(h0.sum() - field.h.sum()) * CELL_AREA
                continue
            lay_band(field.h, h0, r.path["ft"], r.path["y"], law.band_in)
            out["removed"] += r.path["oil"]["taken"]
            out["balls"] += 1
        out["games"].append({"game": g + 1, "map": field.h.copy(), "lane_ml": field.total_ml(),
                             "past_end_ml": field.ml_past(pat.length_ft)})
    out["carried"] = field.ml_past(pat.length_ft)
    out["remaining"] = field.total_ml() - out["carried"]
    return out


def identical_throws(delivery: lane.Delivery, n: int, oil="house", ball: lane.Ball | None = None, *,
                     law: OilLaw = lane.LAW, at_ft: float = 20.0) -> list[dict]:
    """``n`` identical throws of ``delivery``, the ball alone, on one lane that they wear: per throw
    the film (um) under its track at ``at_ft`` before it ran, its board and entry angle at the pins,
    and the oil (ml) past the pattern's end after it."""
    pat = pattern(oil)
    field = OilField.fresh(pat)
    out = []
    for _ in range(n):
        before = field.copy()
        r = phases.throw(delivery, pat, ball, law=law, field=field)
        lay_band(field.h, before.h, r.path["ft"], r.path["y"], law.band_in)
        out.append({"film_um": film_along(before, r.path["ft"], r.path["board"], delivery.hand, at_ft),
                    "board_at_pins": r.board_at_pins, "entry_angle_deg": r.entry_angle_deg,
                    "past_ml": field.ml_past(pat.length_ft), "lane_ml": field.total_ml(), "oil": r.path["oil"]})
    return out
