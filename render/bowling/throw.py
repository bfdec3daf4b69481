"""A throw from the foul line, recorded for the picture: its motion, the ball's texture and the
lane's solids and marks (what :class:`nbst.render.bowling.lane.LaneRenderer` draws).

* **Motion** (:func:`record_throw`): the frame of :mod:`nbst.models.bowling.lane.frame` itself:
  ``frame.run_frame`` with a recording hook, so the same compiled model (``frame.frame_model``),
  the same initial state (``frame.initial_qpos_qvel``: the ball body turned for its inertia
  axes, the pins not in play parked behind the approach), the same steps and the same stop
  rule (settled, or the cap), every body's pose recorded each step. The pins down drawn at the
  end are the frame's USBC outcome, the one a throw file records. Pins not in play (a spare's
  leave) are not drawn; the pin diagram shows them dim. The phases come from ``lane.throw``
  (the ball alone: the same motion up to the first contact).
* **Lane**: the approach, the foul line, the guide dots at :data:`DOTS_FT` ft, the arrows at
  15 ft (boards 5 ... 35), the board lines (every fifth board counted from either edge
  stronger), the oil pattern shaded faintly (darker where the pattern holds more relative oil),
  the gutters, the pin deck, the pit and the kickbacks.
* **Ball**: an equirectangular texture in the ball's body frame, sampled per fragment from the
  body-frame normal, so it turns with the orientation quaternion: the three grip holes (an
  assumed layout, :func:`grip_holes`), the pin (the low-RG axis, a white dot) and the track
  (where the ball touched the lane before the pins, a lighter band: its rings spread where the
  axis migrates).

Compute only: :func:`record_throw` returns the motion, the others arrays.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from nbst.models.bowling import lane, pinfall, scene
from nbst.models.bowling.lane import frame
from nbst.models.bowling.lane import quat_to_mat as _quat_to_mat
from nbst.render.bowling.deck import BALL_RGB, Motion, motion_times
from nbst.render.core.solids import box as _box, flat_poly as _flat_poly  # shared with the crash video

__all__ = ["APPROACH_DRAWN", "APPROACH_RGB", "BOARD_LINE", "BOARD_LINE_5", "DECK_RGB", "DOTS_FT", "DOT_BOARDS",
           "FINGER_GAP_IN", "FOLLOW_STOP_FT", "FOUL_RGB", "FOUL_WIDTH", "GRIP_FROM_PAP_IN", "GRIP_SPAN_IN",
           "GUTTER_RGB", "HOLE_RGB", "HOLE_RIM_RGB", "KICKBACK_RGB", "LANE_RGB", "LEGEND", "MARK_RGB", "OIL_CELL_FT",
           "OIL_FULL_UM", "OIL_SHADE", "OVERHEAD_FROM_FT", "OVERHEAD_SHARE", "PIN_DOT_IN", "PIN_DOT_RGB", "PIT_RGB",
           "STILL_BEFORE_IMPACT", "TEXTURE_SIZE", "TRACK_DILATE_PX", "TRACK_RGB", "TRACK_SUBSTEPS",
           "TRAIL_HALF_WIDTH", "TRAIL_HALF_WIDTH_OVERHEAD", "TRAIL_RGB", "Throw", "ball_texture", "board_lines",
           "grip_holes", "lane_marks", "lane_solids", "ortho_panel", "record_throw", "still_time",
           "throw_file_readout", "throw_times"]

#: Guide dots (ft past the foul line) on these boards, counted from either edge.
DOTS_FT = 7.0
DOT_BOARDS = (3, 5, 8, 11, 14)
#: The approach drawn behind the foul line (m).
APPROACH_DRAWN = 5.0
#: The behind camera follows the ball until it is this far down the lane, then holds.
FOLLOW_STOP_FT = 44.0
BEHIND_BACK, BEHIND_HEIGHT, BEHIND_AHEAD, BEHIND_FOV = 2.0, 0.75, 8.0, 40.0
#: The overhead camera shows the lane from this far past the foul line to the end of the pit
#: (the breakpoint of a house shot is around 35-45 ft), and takes this share of the frame's
#: width when both cameras are drawn.
OVERHEAD_FROM_FT = 30.0
OVERHEAD_SHARE = 0.32
#: Colours: the approach, the lane (its oil up to OIL_SHADE darker), the marks, the track.
APPROACH_RGB = (0.93, 0.84, 0.66)
LANE_RGB = (0.86, 0.72, 0.52)
OIL_SHADE = 0.10
DECK_RGB = (0.90, 0.78, 0.58)
GUTTER_RGB = (0.40, 0.40, 0.45)
PIT_RGB = (0.15, 0.15, 0.17)
KICKBACK_RGB = (0.22, 0.24, 0.30)
MARK_RGB = (0.12, 0.12, 0.16)
FOUL_RGB = (0.55, 0.08, 0.08)
#: The foul line's width (m): USBC allows 3/8 to 1 in; drawn at 1 in so it reads from behind.
FOUL_WIDTH = 0.0254
BOARD_LINE = ((0.70, 0.56, 0.38), 0.0015)   # colour, width (m)
BOARD_LINE_5 = ((0.48, 0.36, 0.22), 0.004)
TRAIL_RGB = (0.97, 0.62, 0.18)
#: The ball's track on the lane, half its width: in the behind view and (wider, to stay a
#: couple of pixels wide at the overhead's scale) in the overhead view (m).
TRAIL_HALF_WIDTH = 0.012
TRAIL_HALF_WIDTH_OVERHEAD = 0.03
#: The ball's texture (equirectangular, body frame): the grip holes, the track, the pin dot.
TEXTURE_SIZE = (1024, 512)
HOLE_RGB = (0.03, 0.03, 0.05)
HOLE_RIM_RGB = (0.85, 0.87, 0.92)
TRACK_RGB = (0.62, 0.80, 1.00)
PIN_DOT_RGB = (1.0, 1.0, 1.0)
#: Assumed grip layout (inches of arc on the ball's surface): the grip's centre this far from
#: the PAP towards the back of the ball at release; fingers and thumb on a line across the
#: line to the PAP, the span between them GRIP_SPAN; hole diameters.
GRIP_FROM_PAP_IN = 5.0
GRIP_SPAN_IN = 3.0
FINGER_GAP_IN = 0.45
FINGER_HOLE_IN, THUMB_HOLE_IN = 0.85, 1.0
#: The track: the contact point's path sampled TRACK_SUBSTEPS times a step, widened by TRACK_DILATE_PX texels.
TRACK_SUBSTEPS = 8
TRACK_DILATE_PX = 2
PIN_DOT_IN = 0.35

#: The overhead panel's key (line, colour), under the pin diagram where it fits.
LEGEND = (("ball's path", TRAIL_RGB), ("darker wood: oil", (0.60, 0.64, 0.70)),
          ("lit: pins standing", (0.60, 0.64, 0.70)), ("ticks: ft past", (0.60, 0.64, 0.70)),
          ("  the foul line", (0.60, 0.64, 0.70)))


@dataclass(frozen=True)
class Throw:
    """A recorded throw: the motion (``nbst.render.bowling.deck.Motion``: ball and pin poses each step, the
    ball's orientation relative to its release), its phases (``lane.ThrowResult``, None for a ball
    that never reaches the pins), the settled frame it is (``frame.FrameResult``: its pins down
    are the last step's), the pins in play, and what made it."""

    motion: Motion
    result: lane.ThrowResult | None
    delivery: lane.Delivery
    oil: object         # a pattern name, file or Pattern (lane.pattern reads any)
    ball: lane.Ball
    timestep: float
    frame: object = None
    in_play: tuple = tuple(range(1, 11))


def _qconj(q: np.ndarray) -> np.ndarray:
    return q * np.array([1.0, -1.0, -1.0, -1.0])


def _qmul_rows(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise Hamilton product of (S, 4) quaternions ``a`` with one quaternion ``b`` (wxyz)."""
    w1, x1, y1, z1 = a.T
    w2, x2, y2, z2 = b
    return np.stack([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                     w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2], axis=1)


def record_throw(delivery, oil: object = "house", ball=None, *, standing=None, timestep: float | None = None,
                 model=None) -> Throw:
    """Record the frame of ``delivery`` (``lane.Delivery``) with ``ball`` on ``oil`` at the pins in
    ``standing`` (default all ten) exactly as :func:`nbst.models.bowling.lane.frame.run_frame` runs it
    (its model, initial state, steps and stop rule, through its ``record`` hook): every step's
    poses, and the frame's result.

    Args:
        delivery: the release (``lane.Delivery``).
        oil: the oil pattern: a registered name, a pattern file or a ``lane.Pattern``.
        ball: the ball (``lane.Ball``; default the default ball).
        standing: the pins standing before the throw (default all ten).
        timestep: MuJoCo's timestep, s (default the frame's).
        model: a compiled frame model to reuse (default built for ``ball`` and ``timestep``).

    Returns:
        The :class:`Throw`: motion (S steps: ball (S, 7) and pins (S, 10, 7) poses), phases, frame.

    Raises:
        LaneError, FrameError: bad input (one line).
        MujocoError: MuJoCo warned (a non-finite or unstable state).
    """

    delivery = delivery.check()
    ball = (ball or lane.Ball()).check()
    try:
        result = lane.throw(delivery, oil, ball)
    except lane.LaneError as e:
        if "gutter" not in str(e) and "did not reach" not in str(e):
            raise
        result = None  # the picture still shows it; the readout says so
    m = model if model is not None else frame.frame_model(
        ball, timestep=frame.TIMESTEP if timestep is None else timestep)
    ball_geom = m.geom("ball").id
    pin_geoms = {g for g in range(m.ngeom) if m.body(int(m.geom_bodyid[g])).name.startswith("pin")}
    qs: list = []
    impact = [math.nan]

    def record(d) -> None:       # reads d only: the frame's physics is untouched
        qs.append(d.qpos.copy())
        if math.isnan(impact[0]):
            for c in d.contact[:d.ncon]:
                g1, g2 = int(c.geom1), int(c.geom2)
                if ball_geom in (g1, g2) and {g1, g2} & pin_geoms:
                    impact[0] = float(d.time)
                    break

    fr = frame.run_frame(delivery, oil, ball, standing=standing, model=m, record=record)
    q = np.array(qs)
    h = float(m.opt.timestep)
    ja = m.joint("ball_free")
    ba = int(ja.qposadr[0])
    padr = pinfall.pin_addresses(m)
    # the frame's ball body starts turned (its inertia axes placed for the delivery); drawn
    # relative to its release orientation, its body frame is the world frame at release, as the
    # texture (grip holes from the release's PAP) is laid out
    bq = q[:, ba:ba + 7].copy()
    bq[:, 3:7] = _qmul_rows(bq[:, 3:7], _qconj(q[0, ba + 3:ba + 7]))
    play = np.array([n in fr.in_play for n in scene.PIN_NUMBERS])
    masks = pinfall.mask_of(pinfall.pins_down(m, q) & play)   # now down: tilted or off the deck
    masks[-1] = pinfall.mask_from_pins(fr.down)                 # the end: the frame's USBC outcome
    motion = Motion(times=np.arange(len(q)) * h, ball=bq, pins=q[:, padr[:, None] + np.arange(7)],
                    impact=impact[0], down=list(fr.down), down_masks=masks, model=m)
    return Throw(motion=motion, result=result, delivery=delivery, oil=oil, ball=ball, timestep=h, frame=fr,
                 in_play=tuple(fr.in_play))


def throw_times(throw: Throw, fps: float, *, hold: float = 1.0) -> np.ndarray:
    """Simulated time of each video frame: real time from the release, slowed around the first
    ball-pin contact as ``nbst render THROW.json`` is (:func:`nbst.render.bowling.deck.motion_times`), then a hold."""
    return motion_times(throw.motion, fps, hold=hold)


# --------------------------------------------------------------------------- the ball's texture


def _exp(base: np.ndarray, direction: np.ndarray, arc: float) -> np.ndarray:
    """The unit vector ``arc`` radians from ``base`` along the tangent ``direction``."""
    t = direction - np.dot(direction, base) * base
    t /= np.linalg.norm(t)
    return math.cos(arc) * base + math.sin(arc) * t


def grip_holes(delivery) -> list[tuple[np.ndarray, float]]:
    """[(unit direction in the ball's body frame, angular radius)] of the two finger holes and the
    thumb hole: an assumed layout (module constants) placed from the release's PAP. The body frame
    is the world frame at release (the throw starts at the identity orientation)."""

    R_in = scene.BALL_RADIUS / scene.INCH
    t, _, pap = lane.spin_axes(delivery)
    g = _exp(pap, -t if abs(np.dot(t, pap)) < 0.999 else np.array([0.0, 0.0, 1.0]), GRIP_FROM_PAP_IN / R_in)
    to_pap = pap - np.dot(pap, g) * g
    to_pap /= np.linalg.norm(to_pap)
    across = np.cross(g, to_pap)
    fingers = _exp(g, across, GRIP_SPAN_IN / 2 / R_in)
    thumb = _exp(g, -across, GRIP_SPAN_IN / 2 / R_in)
    out = [(_exp(fingers, s * to_pap, FINGER_GAP_IN / R_in), FINGER_HOLE_IN / 2 / R_in) for s in (1, -1)]
    out.append((thumb, THUMB_HOLE_IN / 2 / R_in))
    return out


def _texel_dirs(size) -> np.ndarray:
    """(H, W, 3) unit directions of the texels' centres, as the fragment shader maps them."""
    w, h = size
    u = (np.arange(w) + 0.5) / w
    v = (np.arange(h) + 0.5) / h
    phi = (u - 0.5) * 2 * math.pi
    th = v * math.pi
    st = np.sin(th)[:, None]
    return np.stack([st * np.cos(phi)[None, :], st * np.sin(phi)[None, :], np.cos(th)[:, None] * np.ones((1, w))], -1)


def ball_texture(throw: Throw, size=TEXTURE_SIZE) -> np.ndarray:
    """(H, W, 3) uint8 equirectangular texture of the ball in its body frame: the track (the
    contact point's path in the body frame up to the first pin contact), the pin dot and the
    grip holes (each with a thin light rim)."""

    R_in = scene.BALL_RADIUS / scene.INCH
    dirs = _texel_dirs(size).reshape(-1, 3).astype(np.float32)
    img = np.tile(np.asarray(BALL_RGB, np.float32), (len(dirs), 1))
    m = throw.motion
    end = len(m.times) if math.isnan(m.impact) else int(m.impact / throw.timestep)
    on_lane = np.flatnonzero((m.ball[:end, 2] < scene.BALL_RADIUS + 0.003) & (m.ball[:end, 0] < scene.DECK_FRONT_X))
    if len(on_lane) > 1:
        rot = _quat_to_mat(m.ball[on_lane, 3:7])
        c = -rot[:, 2, :]                                  # R^T (0, 0, -1): the lowest point, body frame
        f = np.linspace(0.0, 1.0, TRACK_SUBSTEPS, endpoint=False)[None, :, None]
        c = (c[:-1, None, :] * (1 - f) + c[1:, None, :] * f).reshape(-1, 3)   # one sample per ~0.2 deg
        c /= np.linalg.norm(c, axis=1, keepdims=True)
        w, h = size
        u = ((np.arctan2(c[:, 1], c[:, 0]) / (2 * math.pi) + 0.5) * w).astype(int) % w
        v = np.clip((np.arccos(np.clip(c[:, 2], -1, 1)) / math.pi * h).astype(int), 0, h - 1)
        track = np.zeros((h, w), bool)
        track[v, u] = True
        for _ in range(TRACK_DILATE_PX):                   # widen the lines in texels (wrapping in u)
            grown = track.copy()
            grown[1:] |= track[:-1]
            grown[:-1] |= track[1:]
            grown |= np.roll(track, 1, axis=1) | np.roll(track, -1, axis=1)
            track = grown
        img[track.reshape(-1)] = TRACK_RGB
    marks: list[tuple[np.ndarray, float, tuple, tuple | None]] = [
        (lane.pin_axis(throw.delivery, throw.ball.pin_pap_in), PIN_DOT_IN / 2 / R_in, PIN_DOT_RGB, None)]
    marks += [(p, r, HOLE_RGB, HOLE_RIM_RGB) for p, r in grip_holes(throw.delivery)]
    for p, r, rgb, rim in marks:
        c = dirs @ p.astype(np.float32)
        if rim is not None:
            img[c >= math.cos(r + 0.06 / R_in * 2)] = rim
        img[c >= math.cos(r)] = rgb
    w, h = size
    return (np.clip(img, 0, 1) * 255 + 0.5).astype(np.uint8).reshape(h, w, 3)


# --------------------------------------------------------------------------- the lane


def _rect(x0, x1, y0, y1, rgb) -> np.ndarray:
    return _flat_poly([(x0, y0), (x1, y0), (x1, y1), (x0, y1)], rgb)


#: The oil is shaded over cells of one board by this many ft; a film of OIL_FULL_UM or more
#: is the full OIL_SHADE.
OIL_CELL_FT = 2.0
OIL_FULL_UM = 3.0


def lane_solids(oil, hand: str = "right") -> np.ndarray:
    """(V, 9) triangles of the lane's solids: approach, the lane shaded by the pattern's film
    (darker where there is more oil), deck, gutters, pit and kickbacks."""

    hw, gw = scene.LANE_WIDTH / 2, scene.GUTTER_WIDTH
    x_end = scene.PIT_EDGE_X + scene.PIT_LENGTH
    parts = [_box(lane.FOUL_LINE_X - APPROACH_DRAWN, lane.FOUL_LINE_X, -hw - gw - 0.3, hw + gw + 0.3, -0.05, 0.0,
                  APPROACH_RGB)]
    g = lane.pattern(oil).grid()  # (board, 0.25 ft) film, um; index 0: the right-hander's board 1
    per = int(round(OIL_CELL_FT / lane.DX_FT))
    x0 = lane.FOUL_LINE_X
    for j0 in range(0, g.shape[1], per):
        x1 = float(lane.ft_to_x(min(j0 + per, g.shape[1]) * lane.DX_FT))
        for i in range(lane.N_BOARDS):
            u = min(float(g[i, j0:j0 + per].mean()) / OIL_FULL_UM, 1.0)
            ya, yb = float(lane.board_to_y(i + 0.5)), float(lane.board_to_y(i + 1.5))
            parts.append(_rect(x0, x1, min(ya, yb), max(ya, yb), tuple(c * (1 - OIL_SHADE * u) for c in LANE_RGB)))
        x0 = x1
    parts.append(_box(lane.FOUL_LINE_X, x0, -hw, hw, -0.05, -0.0005, LANE_RGB))
    parts += [
        _box(x0, scene.DECK_FRONT_X, -hw, hw, -0.05, 0.0, LANE_RGB),
        _box(scene.DECK_FRONT_X, scene.PIT_EDGE_X, -hw, hw, -0.05, 0.0, DECK_RGB),
        _box(lane.FOUL_LINE_X, scene.PIT_EDGE_X, hw, hw + gw, -0.06, -scene.GUTTER_DEPTH, GUTTER_RGB),
        _box(lane.FOUL_LINE_X, scene.PIT_EDGE_X, -hw - gw, -hw, -0.06, -scene.GUTTER_DEPTH, GUTTER_RGB),
        _box(scene.PIT_EDGE_X, x_end, -hw - gw, hw + gw, -scene.PIT_DEPTH - 0.02, -scene.PIT_DEPTH, PIT_RGB),
        _box(scene.DECK_FRONT_X, x_end, hw + gw, hw + gw + 0.05, -scene.PIT_DEPTH, 0.5, KICKBACK_RGB),
        _box(scene.DECK_FRONT_X, x_end, -hw - gw - 0.05, -hw - gw, -scene.PIT_DEPTH, 0.5, KICKBACK_RGB),
    ]
    return np.concatenate(parts).astype("f4")


def board_lines() -> list[tuple[float, bool]]:
    """[(y of a board line, strong)] for the 40 lines at the boards' edges; a line a multiple of
    five boards from either edge of the lane is strong (board 5's and board 35's outer edges...)."""

    out = []
    for j in range(lane.N_BOARDS + 1):
        y = -scene.LANE_WIDTH / 2 + j * lane.BOARD_WIDTH
        out.append((y, min(j, lane.N_BOARDS - j) % 5 == 0))
    return out


def lane_marks(hand: str = "right") -> np.ndarray:
    """(V, 9) flat triangles of the marks on the lane: board lines, the foul line, the guide
    dots and the arrows (each pointing down the lane, centred 15 ft past the foul line)."""

    hw = scene.LANE_WIDTH / 2
    parts = []
    for y, strong in board_lines():
        rgb, w = BOARD_LINE_5 if strong else BOARD_LINE
        parts.append(_rect(lane.FOUL_LINE_X, scene.PIT_EDGE_X, y - w / 2, y + w / 2, rgb))
    parts.append(_rect(lane.FOUL_LINE_X - FOUL_WIDTH / 2, lane.FOUL_LINE_X + FOUL_WIDTH / 2, -hw - 0.02, hw + 0.02,
                       FOUL_RGB))
    xd = float(lane.ft_to_x(DOTS_FT))
    k = np.linspace(0, 2 * math.pi, 13)[:-1]
    r = lane.BOARD_WIDTH * 0.3
    for b in DOT_BOARDS + tuple(lane.N_BOARDS + 1 - b for b in DOT_BOARDS):
        y = float(lane.board_to_y(b, hand))
        parts.append(_flat_poly(np.stack([xd + r * np.cos(k), y + r * np.sin(k)], 1), MARK_RGB))
    xa = float(lane.ft_to_x(lane.ARROWS_FT))
    for b in lane.ARROW_BOARDS:
        y = float(lane.board_to_y(b, hand))
        half = lane.BOARD_WIDTH * 0.45
        parts.append(_flat_poly([(xa - 0.08, y - half), (xa + 0.08, y), (xa - 0.08, y + half)], MARK_RGB))
    return np.concatenate(parts).astype("f4")


def ortho_panel(x_range, y_half: float, vp, frame_h: int, *, margin_top: float, margin_bottom: float,
                col_centre: float) -> tuple[np.ndarray, float]:
    """(4x4 view-projection, px per m) of a true-scale view from above: the lane's x from
    ``x_range[0]`` (bottom) to ``x_range[1]`` (top), the bowler's left (+y) on the image's left,
    the lane's centre at pixel column ``col_centre``; image row 0 at the top (as FrameTarget)."""
    vx, _, vw, h = vp
    xa, xb = x_range
    ppm = min((h - margin_top - margin_bottom) / (xb - xa), 0.9 * vw / (2 * y_half))
    # pixel: col = col_centre - y * ppm; row = margin_top + (xb - x) * ppm; ndc = 2 * px / size - 1
    m = np.zeros((4, 4))
    m[0, 1] = -2 * ppm / vw
    m[0, 3] = 2 * (col_centre - vx) / vw - 1
    m[1, 0] = -2 * ppm / frame_h
    m[1, 3] = 2 * (margin_top + xb * ppm) / frame_h - 1
    m[2, 2], m[2, 3] = -0.5, 0.1   # larger z nearer (depth -1 near)
    m[3, 3] = 1.0
    return m, ppm


#: The still's default moment: this long before the ball's first contact with a pin (the ball
#: near the deck, every pin standing and numbered, the track behind it), or the end of the throw.
STILL_BEFORE_IMPACT = 0.12


def still_time(throw: Throw) -> float:
    m = throw.motion
    if math.isnan(m.impact):
        return float(m.times[-1])
    return max(0.0, m.impact - STILL_BEFORE_IMPACT)


def throw_file_readout(d: dict) -> dict:
    """LaneRenderer's readout arguments for a checked throw file ``d`` (``throwfile.load``): the pins
    asked for (``requested``), the file's outcome, and its probability with n and 95 % CI."""
    out: dict[str, object] = {"expected": sorted(d["outcome"]["down"])}
    if d.get("requested") is not None:
        out["asked"] = sorted(d["requested"]["down"])
    else:
        out["no_request"] = True
    e = d.get("probability")
    if e:
        want = sorted(e["want"]["down"])
        standing = sorted(d["standing"])
        what = (("a strike" if len(standing) == 10 else "the spare") if want == standing
                else "down " + ",".join(map(str, want)))
        out["probability"] = float(e["p"])
        out["probability_note"] = (f"{what}; {e['k']}/{e['n']}, 95% CI {100 * e['lo']:.0f}-{100 * e['hi']:.0f}%")
    return out
