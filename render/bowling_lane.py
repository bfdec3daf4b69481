"""A throw from the foul line in 3D (``nbst bowl throw --video/--still``): the full 60 ft lane
with its marks, a ball whose grip and track turn with it, numbered pins and a readout.

* **Motion** (:func:`record_throw`): the frame of :mod:`nbst.models.bowling.frame` itself:
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
* **Cameras**: ``behind`` (from behind the bowler, following the ball until it is
  :data:`FOLLOW_STOP_FT` ft down, pins numbered above their heads once they are large enough
  to read) and ``overhead`` (orthographic, true scale, the lane from :data:`OVERHEAD_FROM_FT`
  ft to the pit, with the ball's track on the lane, distance ticks and a pin diagram with the
  standing pins lit); ``both`` sets them side by side.
* **Readout**: the throw (hand, mph, rpm, rotation, tilt, boards at the foul line and arrows,
  launch angle), the oil and ball, the phases (skid, breakpoint, roll, at the pins), the pins
  down now (the final result at the end), and, when given, the pins asked for and the
  probability.

Compute apart from I/O: :func:`record_throw` returns the motion, :class:`LaneRenderer` returns
frames; :func:`render_throw` is the thin writer the CLI calls.

Length: ~800 lines, past the house's ~500: the lane's marks, the ball's texture, the two
cameras and the overlays all place things by the same conventions (boards by hand, feet past
the foul line, the panels' pixel mapping), and the tests check the pixels against exactly
these functions; a third of the lines are constants and shaders, each with why.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from nbst.render import style
from nbst.render.bowling import BACKGROUND, BALL_RGB, FS, PIN_RED, PIN_WHITE, STRIPES_IN, VS, Motion, _flat, _pose
from nbst.render.bowling import frame_times as _shot_frame_times
from nbst.render.gl import FrameRenderer, FrameTarget, create_context
from nbst.render.scene3d import look_at, perspective
from nbst.render.solids import box as _box, flat_poly as _flat_poly, ribbon as _ribbon  # shared with the crash video

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

BALL_VS = """#version 330
uniform mat4 u_vp;
uniform mat4 u_model;
in vec3 in_pos;
out vec3 v_local;
out vec3 v_normal;
out vec3 v_world;
void main() {
    vec4 w = u_model * vec4(in_pos, 1.0);
    v_world = w.xyz;
    v_local = in_pos;
    v_normal = mat3(u_model) * normalize(in_pos);
    gl_Position = u_vp * w;
}
"""
BALL_FS = """#version 330
uniform vec3 u_light;
uniform vec3 u_eye;
uniform sampler2D u_tex;
in vec3 v_local;
in vec3 v_normal;
in vec3 v_world;
out vec4 f_color;
const float PI = 3.14159265358979;
void main() {
    vec3 d = normalize(v_local);
    vec2 uv = vec2(atan(d.y, d.x) / (2.0 * PI) + 0.5, acos(clamp(d.z, -1.0, 1.0)) / PI);
    vec3 c = texture(u_tex, uv).rgb;
    vec3 n = normalize(v_normal);
    vec3 v = normalize(u_eye - v_world);
    float diff = max(dot(n, u_light), 0.0);
    vec3 h = normalize(u_light + v);
    float spec = pow(max(dot(n, h), 0.0), 40.0) * 0.3;
    f_color = vec4(c * (0.35 + 0.65 * diff) + vec3(spec), 1.0);
}
"""


@dataclass(frozen=True)
class Throw:
    """A recorded throw: the motion (``render.bowling.Motion``: ball and pin poses each step, the
    ball's orientation relative to its release), its phases (``lane.ThrowResult``, None for a ball
    that never reaches the pins), the settled frame it is (``frame.FrameResult``: its pins down
    are the last step's), the pins in play, and what made it."""

    motion: Motion
    result: object
    delivery: object
    oil: str
    ball: object
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


def record_throw(delivery, oil: str = "house", ball=None, *, standing=None, timestep: float | None = None,
                 model=None) -> Throw:
    """Record the frame of ``delivery`` (``lane.Delivery``) with ``ball`` on ``oil`` at the pins in
    ``standing`` (default all ten) exactly as :func:`nbst.models.bowling.frame.run_frame` runs it
    (its model, initial state, steps and stop rule, through its ``record`` hook): every step's
    poses, and the frame's result. Raises ``lane.LaneError``/``frame.FrameError`` (one line) for
    bad input; MuJoCo's warnings raise ``shot.MujocoError``."""
    from nbst.models.bowling import frame, lane, scene
    from nbst.models.bowling import shot as shotmod

    delivery = delivery.check()
    ball = (ball or lane.Ball()).check()
    try:
        result = lane.throw(delivery, oil, ball)
    except lane.LaneError as e:
        if "gutter" not in str(e) and "did not reach" not in str(e):
            raise
        result = None  # the picture still shows it; the readout says so
    m = model if model is not None else frame.frame_model(
        oil, ball, timestep=frame.TIMESTEP if timestep is None else timestep)
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
    padr = shotmod.pin_addresses(m)
    # the frame's ball body starts turned (its inertia axes placed for the delivery); drawn
    # relative to its release orientation, its body frame is the world frame at release, as the
    # texture (grip holes from the release's PAP) is laid out
    bq = q[:, ba:ba + 7].copy()
    bq[:, 3:7] = _qmul_rows(bq[:, 3:7], _qconj(q[0, ba + 3:ba + 7]))
    play = np.array([n in fr.in_play for n in scene.PIN_NUMBERS])
    masks = shotmod.mask_of(shotmod.pins_down(m, q) & play)   # now down: tilted or off the deck
    masks[-1] = shotmod.mask_from_pins(fr.down)                 # the end: the frame's USBC outcome
    motion = Motion(times=np.arange(len(q)) * h, ball=bq, pins=q[:, padr[:, None] + np.arange(7)],
                    impact=impact[0], down=list(fr.down), down_masks=masks)
    return Throw(motion=motion, result=result, delivery=delivery, oil=oil, ball=ball, timestep=h, frame=fr,
                 in_play=tuple(fr.in_play))


def frame_times(throw: Throw, fps: float, *, hold: float = 1.0) -> np.ndarray:
    """Simulated time of each video frame: real time from the release, slowed around the first
    ball-pin contact as ``nbst render SHOT.json`` is (render.bowling.frame_times), then a hold."""
    return _shot_frame_times(throw.motion, fps, hold=hold)


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
    from nbst.models.bowling import lane, scene

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
    from nbst.models.bowling import lane, scene

    from nbst.models.bowling.lane import _quat_to_mat

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
    marks = [(lane.pin_axis(throw.delivery), PIN_DOT_IN / 2 / R_in, PIN_DOT_RGB, None)]
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


def lane_solids(oil: str, hand: str = "right") -> np.ndarray:
    """(V, 9) triangles of the lane's solids: approach, the pattern's cells shaded by oil, the
    back end, deck, gutters, pit and kickbacks."""
    from nbst.models.bowling import lane, scene

    hw, gw = scene.LANE_WIDTH / 2, scene.GUTTER_WIDTH
    x_end = scene.PIT_EDGE_X + scene.PIT_LENGTH
    parts = [_box(lane.FOUL_LINE_X - APPROACH_DRAWN, lane.FOUL_LINE_X, -hw - gw - 0.3, hw + gw + 0.3, -0.05, 0.0,
                  APPROACH_RGB)]
    pat = lane.pattern(oil)
    x0 = lane.FOUL_LINE_X
    for to_ft, bands in pat.segments:
        x1 = float(lane.ft_to_x(to_ft))
        for lo, hi, u in bands:
            ya, yb = sorted((float(lane.board_to_y(lo - 0.5, hand)), float(lane.board_to_y(hi + 0.5, hand))))
            parts.append(_box(x0, x1, ya, yb, -0.05, 0.0, tuple(c * (1 - OIL_SHADE * u) for c in LANE_RGB)))
        x0 = x1
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
    from nbst.models.bowling import lane, scene

    out = []
    for j in range(lane.N_BOARDS + 1):
        y = -scene.LANE_WIDTH / 2 + j * lane.BOARD_WIDTH
        out.append((y, min(j, lane.N_BOARDS - j) % 5 == 0))
    return out


def lane_marks(hand: str = "right") -> np.ndarray:
    """(V, 9) flat triangles of the marks on the lane: board lines, the foul line, the guide
    dots and the arrows (each pointing down the lane, centred 15 ft past the foul line)."""
    from nbst.models.bowling import lane, scene

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


class LaneRenderer(FrameRenderer):
    """Frames of a recorded throw: ``render(t)`` -> (H, W, 3) uint8; ``camera``: behind | overhead | both.
    ``asked`` (pins the shot was meant to knock down), ``probability`` (of the outcome, 0..1) and
    ``probability_note`` (e.g. its sample size and interval) add readout lines when given;
    ``expected`` (the pins down a throw file records) adds a line only when the recorded frame
    ends differently; ``no_request`` says on the ``asked`` line that a file asked for nothing."""

    def __init__(self, ctx, throw: Throw, *, size=style.DEFAULT_SIZE, camera: str = "both", asked=None,
                 probability: float | None = None, probability_note: str | None = None,
                 overhead_from_ft: float = OVERHEAD_FROM_FT, expected=None, no_request: bool = False):
        import moderngl
        import trimesh

        from nbst.models.bowling import lane, pin, scene
        from nbst.render.shapes import Text, text_cell

        if camera not in ("behind", "overhead", "both"):
            raise ValueError(f"camera must be behind, overhead or both, got {camera!r}")
        self.ctx, self.throw, self.motion, self.camera = ctx, throw, throw.motion, camera
        self.size = tuple(size)
        self.asked = None if asked is None else sorted(int(p) for p in asked)
        self.expected = None if expected is None else sorted(int(p) for p in expected)
        self.no_request = bool(no_request)
        self.in_play = tuple(throw.in_play)
        self.probability, self.probability_note = probability, probability_note
        self.hand = throw.delivery.hand
        self._mgl = moderngl
        w, h = self.size
        if camera == "both":
            ow = int(round(w * OVERHEAD_SHARE))
            self.panels = {"behind": (0, 0, w - ow, h), "overhead": (w - ow, 0, ow, h)}
        else:
            self.panels = {camera: (0, 0, w, h)}
        px = max(style.MIN_READOUT_PX, int(round(style.TEXT_FRAC * min(self.size))))
        text_w = self.panels.get("behind", self.panels.get("overhead"))[2]
        chars = max(len(s) for s in self.readout(float(self.motion.times[-1])))
        while px > style.MIN_READOUT_PX and chars * text_cell(px)[0] > text_w - 16:
            px -= 1
        self.text = Text(ctx, px)
        self.small = Text(ctx, max(style.MIN_LABEL_PX, int(round(0.022 * min(self.size)))))
        self.target = FrameTarget(ctx, self.size, samples=style.MSAA_SAMPLES, depth=True)
        self.prog = ctx.program(vertex_shader=VS, fragment_shader=FS)
        self.ball_prog = ctx.program(vertex_shader=BALL_VS, fragment_shader=BALL_FS)
        L = np.array([0.3, 0.4, 1.0])
        for p in (self.prog, self.ball_prog):
            p["u_light"].value = tuple(L / np.linalg.norm(L))
        self._bufs = []

        def vao(arr, prog=None, fmt="3f 3f 3f", names=("in_pos", "in_normal", "in_color")):
            buf = ctx.buffer(np.ascontiguousarray(arr, dtype="f4").tobytes())
            v = ctx.vertex_array(prog or self.prog, [(buf, fmt, *names)])
            self._bufs.append((v, buf))
            return v

        g = pin.geometry()
        pm = trimesh.Trimesh(g.visual_vertices.astype(float), g.visual_faces, process=False)

        def pin_color(p):
            hh = p[2] / scene.INCH
            return PIN_RED if any(lo <= hh <= hi for lo, hi in STRIPES_IN) else PIN_WHITE

        self.pin_vao = vao(_flat(pm, pin_color))
        sphere = trimesh.creation.icosphere(subdivisions=4, radius=scene.BALL_RADIUS)
        self.ball_vao = vao(sphere.vertices[sphere.faces.reshape(-1)], self.ball_prog, "3f", ("in_pos",))
        tex = ball_texture(throw)
        self.ball_tex = ctx.texture((tex.shape[1], tex.shape[0]), 3, np.ascontiguousarray(tex).tobytes(), alignment=1)
        self.ball_tex.filter = (moderngl.LINEAR, moderngl.LINEAR)
        self.ball_tex.repeat_x, self.ball_tex.repeat_y = True, False
        self.solid_vao = vao(lane_solids(throw.oil, self.hand))
        self.marks_vao = vao(lane_marks(self.hand))
        # the ball's track on the lane: a ribbon, one pair of vertices every 10 ms, drawn up to t
        m = self.motion
        stride = max(1, int(round(0.01 / throw.timestep)))
        idx = np.arange(0, len(m.times), stride)
        on = idx[(m.ball[idx, 0] < scene.PIT_EDGE_X) & (m.ball[idx, 2] > -0.02)]
        self._trail_idx = on
        self.trail_vao = self.trail_wide_vao = None
        if len(on) > 1:
            self.trail_vao = vao(_ribbon(m.ball[on, :2], TRAIL_HALF_WIDTH, TRAIL_RGB))
            self.trail_wide_vao = vao(_ribbon(m.ball[on, :2], TRAIL_HALF_WIDTH_OVERHEAD, TRAIL_RGB))
        self.x_end = scene.PIT_EDGE_X + scene.PIT_LENGTH
        self.overhead_x = (float(lane.ft_to_x(overhead_from_ft)) - 0.3, self.x_end)
        self.pin_height = pin.HEIGHT_IN * scene.INCH

    # ---------------------------------------------------------------- cameras

    def step_at(self, t: float) -> int:
        m = self.motion
        return int(np.clip(round(t / self.throw.timestep), 0, len(m.times) - 1))

    def views(self, t: float):
        """[(viewport, view-projection, eye, camera)] for the frame at time t. Pixels: column =
        vx + (ndc_x + 1) / 2 * vw, row = (ndc_y + 1) / 2 * H (row 0 at the top)."""
        from nbst.models.bowling import lane, scene

        w, h = self.size
        k = self.step_at(t)
        out = []
        for cam, vp in self.panels.items():
            if cam == "behind":
                bx = min(float(self.motion.ball[k, 0]), float(lane.ft_to_x(FOLLOW_STOP_FT)))
                eye = np.array([bx - BEHIND_BACK, 0.0, BEHIND_HEIGHT])
                tgt = np.array([bx + BEHIND_AHEAD, 0.0, 0.0])
                proj = perspective(BEHIND_FOV, vp[2] / h, 0.3, 40.0)
                flip = np.diag([1.0, -1.0, 1.0, 1.0])
                out.append((vp, flip @ proj @ look_at(eye, tgt, np.array([0.0, 0.0, 1.0])), eye, cam))
            else:
                half = scene.LANE_WIDTH / 2 + scene.GUTTER_WIDTH + 0.05
                ch = self.text.cell[1]
                vpm, _ = ortho_panel(self.overhead_x, half, vp, h, margin_top=1.8 * ch, margin_bottom=0.5 * ch,
                                     col_centre=vp[0] + 0.42 * vp[2])
                out.append((vp, vpm, np.array([0.0, 0.0, 50.0]), cam))
        return out

    @staticmethod
    def to_pixel(vp, vpm, p, frame_h: int):
        """(column, row, in front of the camera) of the world point ``p`` in the panel ``vp``."""
        c = vpm @ np.r_[np.asarray(p, float), 1.0]
        return vp[0] + (c[0] / c[3] + 1) / 2 * vp[2], (c[1] / c[3] + 1) / 2 * frame_h, c[3] > 0

    # ---------------------------------------------------------------- readout

    def readout(self, t: float) -> list[str]:
        """The text of the frame at ``t``: the throw, the oil and ball, the phases, the ball now,
        the pins down (at the end: the result), and the pins asked for and the probability when
        given."""
        from nbst.models.bowling import lane
        from nbst.models.bowling import shot as shotmod

        th, d, r = self.throw, self.throw.delivery, self.throw.result
        b = th.ball

        def pins(ns) -> str:
            return ",".join(map(str, ns)) or "none"

        lines = [f"throw   {d.hand}-handed, {d.mph:.1f} mph, {d.rpm:.0f} rpm",
                 f"axis    rotation {d.rotation:.0f} deg, tilt {d.tilt:.0f} deg",
                 f"line    board {d.foul_board():.1f} at the foul line, {d.angle:+.1f} deg out",
                 f"oil     {th.oil} ({lane.pattern(th.oil).length_ft:.0f} ft); ball {b.weight_lb:g} lb, "
                 f"RG {b.rg:.2f}, diff {b.diff:.3f}"]
        if r is None:
            lines.append("phases  none: the ball does not reach the pins on the lane")
        else:
            lines.append(f"arrows  board {r.board_at_arrows:.1f}; skid "
                         + ("none" if r.skid_ft is None else f"{r.skid_ft:.1f} ft"))
            lines.append("break   " + ("none (never moved out)" if r.breakpoint_ft is None
                                       else f"{r.breakpoint_ft:.1f} ft, board {r.breakpoint_board:.1f}")
                         + ("" if r.roll_ft is None else f"; roll {r.roll_ft:.1f} ft"))
            lines.append(f"pins    board {r.board_at_pins:.1f}, entry {r.entry_angle_deg:.1f} deg, "
                         f"{r.speed_pins_mph:.1f} mph")
        m = self.motion
        k = self.step_at(t)
        play = list(self.in_play)
        full = len(play) == 10

        def leave_of(down) -> str:
            leave = [n for n in play if n not in down]
            return f" (leave {pins(leave)})" if leave else (" (a strike)" if full else " (the spare)")

        if not full:
            lines.append(f"rack    {pins(play)} standing before the throw")
        if self.asked is not None:
            lines.append(f"asked   down {pins(self.asked)}{leave_of(self.asked)}")
        elif self.no_request:
            lines.append("asked   nothing recorded (the file's requested is null)")
        if m.down_masks is not None:
            now = shotmod.pins_of(int(m.down_masks[k]))
            if k == len(m.times) - 1:
                tail = "" if self.asked is None else (" = asked" if now == self.asked else ", not asked")
                lines.append(f"result  down {pins(now)}{leave_of(now)}{tail}")
                if self.expected is not None and now != self.expected:
                    lines.append(f"file    down {pins(self.expected)}: this run differs")
            else:
                lines.append(f"now     down {pins(now)}")
        if self.probability is not None:
            note = f" ({self.probability_note})" if self.probability_note else ""
            lines.append(f"chance  {100 * self.probability:.0f}%{note}")
        x, y = m.ball[k, 0], m.ball[k, 1]
        a, b = max(k - 1, 0), min(k + 1, len(m.times) - 1)
        v = float(np.hypot(*(m.ball[b, :2] - m.ball[a, :2]))) / max((b - a) * self.throw.timestep, 1e-12)
        where = (f"{float(lane.x_to_ft(x)):4.1f} ft, board {float(lane.y_to_board(y, d.hand)):4.1f}"
                 if x < 0.0 and abs(y) < 0.6 else "past the head pin")
        lines.append(f"t {t:4.2f} s  ball {where}, {v / lane.MPH:4.1f} mph")
        return lines

    def _overlay(self, t: float, views) -> None:
        from nbst.models.bowling import lane
        from nbst.models.bowling import shot as shotmod

        size = self.size
        H = size[1]
        cw, ch = self.text.cell
        scw, sch = self.small.cell
        titles = {"behind": "behind the bowler: the full lane, 60 ft to the head pin",
                  "overhead": f"overhead from {lane.x_to_ft(self.overhead_x[0] + 0.3):.0f} ft"}
        k = self.step_at(t)
        down = (shotmod.pins_of(int(self.motion.down_masks[k])) if self.motion.down_masks is not None else [])
        for vp, vpm, _, cam in views:
            title = titles[cam]
            if len(title) * cw > vp[2] - 8:
                title = title.split(":")[0]
            self.text.draw_halo(size, self.text.layout([title], vp[0] + (vp[2] - cw * len(title)) / 2, 0.3 * ch),
                                style.TEXT, style.TEXT_HALO)
            if cam == "behind":
                self._behind_labels(vp, vpm, k, down)
            else:
                self._overhead_labels(vp, vpm, down)
        vp = self.panels.get("behind", next(iter(self.panels.values())))
        y0 = 1.5 * ch if "behind" in self.panels else H - (len(self.readout(t)) + 0.5) * ch
        self.text.draw_halo(size, self.text.layout(self.readout(t), vp[0] + 0.6 * cw, y0), style.TEXT,
                            style.TEXT_HALO)

    def pin_label_points(self, k: int) -> np.ndarray:
        """(10, 3) world points just above each pin's head at step k (where the behind view writes
        its number)."""
        out = []
        for p in self.motion.pins[k]:
            out.append(_pose(p)[:3, :3] @ np.array([0.0, 0.0, self.pin_height + 0.05]) + p[:3])
        return np.array(out)

    def _behind_labels(self, vp, vpm, k, down) -> None:
        """The standing pins' numbers above their heads, once neighbouring pins are far enough
        apart on screen for a number to fit between them."""
        from nbst.models.bowling import scene

        if not len(self.motion.pins):
            return
        H = self.size[1]
        scw, sch = self.small.cell
        a = self.to_pixel(vp, vpm, [0.0, 0.0, 0.0], H)
        b = self.to_pixel(vp, vpm, [0.0, scene.PIN_SPACING, 0.0], H)
        if abs(a[0] - b[0]) < 3.5 * scw:
            return
        parts, boxes = [], []
        for n, p in zip(scene.PIN_NUMBERS, self.pin_label_points(k)):   # front rows first: they keep theirs
            if n in down or n not in self.in_play:
                continue
            col, row, front = self.to_pixel(vp, vpm, p, H)
            label = str(n)
            x0, y0 = col - scw * len(label) / 2, row - sch
            box = (x0 - scw / 2, y0, x0 + scw * (len(label) + 0.5), y0 + sch)
            if not front or x0 < vp[0] or box[2] > vp[0] + vp[2]:
                continue
            if any(box[0] < b[2] and b[0] < box[2] and box[1] < b[3] and b[1] < box[3] for b in boxes):
                continue   # a label nearer the camera is there (rows overlap when seen from low behind)
            boxes.append(box)
            parts.append(self.small.layout([label], x0, y0))
        if parts:
            self.small.draw_halo(self.size, np.concatenate(parts), style.LABEL, PIN_WHITE)

    def pin_diagram(self, vp) -> list[tuple[int, float, float]]:
        """[(pin, column, row)] of the pin diagram's numbers (top-left of each label) in the
        overhead panel: the deck as a bowler sees it (7 8 9 10 at the back, the 1 in front)."""
        from nbst.models.bowling import scene

        scw, sch = self.small.cell
        gap = 2.2 * scw
        right = vp[0] + vp[2] - 0.8 * scw - 2 * scw
        spots = scene.pin_spots()
        out = []
        for n, (x, y) in zip(scene.PIN_NUMBERS, spots):
            col = right - (y / scene.PIN_SPACING + 1.5) * gap
            row = 1.5 * self.text.cell[1] + (4.4 - round(x / (scene.PIN_SPACING * math.sqrt(3) / 2))) * 1.5 * sch
            out.append((n, col - scw * len(str(n)) / 2, row))
        return out

    def _overhead_labels(self, vp, vpm, down) -> None:
        """Distance ticks beside the lane (every 10 ft, the arrows and the foul line when in
        view) and the pin diagram (standing pins lit, pins down dim)."""
        from nbst.models.bowling import lane, scene

        H = self.size[1]
        scw, sch = self.small.cell
        y_edge = scene.LANE_WIDTH / 2 + scene.GUTTER_WIDTH
        ticks = [(f"{ft:.0f} ft", ft) for ft in range(0, 61, 10)] + [("arrows", lane.ARROWS_FT)]
        parts = []
        for label, ft in ticks:
            x = float(lane.ft_to_x(ft))
            if not self.overhead_x[0] <= x <= self.overhead_x[1]:
                continue
            col, row, _ = self.to_pixel(vp, vpm, [x, y_edge, 0.0], H)
            parts.append(self.small.layout([label], col - scw * (len(label) + 0.6), row - sch / 2))
        if parts:
            self.small.draw_halo(self.size, np.concatenate(parts), style.TEXT_DIM, style.TEXT_HALO)
        diag = self.pin_diagram(vp)
        head = "pins"
        c0 = min(c for _, c, _ in diag)
        self.small.draw_halo(self.size, self.small.layout([head], c0, 1.5 * self.text.cell[1]), style.TEXT_DIM,
                             style.TEXT_HALO)
        for standing, colour in ((True, style.TEXT), (False, (0.35, 0.37, 0.42))):
            parts = [self.small.layout([str(n)], c, r) for n, c, r in diag
                     if (n not in down and n in self.in_play) == standing]
            if parts:
                self.small.draw_halo(self.size, np.concatenate(parts), colour, style.TEXT_HALO)
        # a key under the diagram, where it fits beside the lane
        right_of_lane = self.to_pixel(vp, vpm, [0.0, -y_edge, 0.0], H)[0] + scw
        key = [(line, rgb) for line, rgb in LEGEND]
        width = max(len(line) for line, _ in key) * scw
        if right_of_lane + width <= vp[0] + vp[2]:
            row = max(r for _, _, r in diag) + 2.5 * sch
            for i, (line, rgb) in enumerate(key):
                self.small.draw_halo(self.size, self.small.layout([line], right_of_lane, row + i * sch), rgb,
                                     style.TEXT_HALO)

    # ---------------------------------------------------------------- drawing

    def draw(self, t: float) -> None:
        ctx, mgl = self.ctx, self._mgl
        fbo = self.target.draw_fbo
        fbo.use()
        fbo.clear(*BACKGROUND, 1.0, depth=1.0)
        views = self.views(t)
        k = self.step_at(t)
        n_trail = int(np.searchsorted(self._trail_idx, k, side="right"))
        ident = np.eye(4, dtype="f4").tobytes()
        for vp, vpm, eye, cam in views:
            ctx.viewport = vp
            vpb = vpm.T.astype("f4").tobytes()
            for p in (self.prog, self.ball_prog):
                p["u_vp"].write(vpb)
                p["u_eye"].value = tuple(float(e) for e in eye)
            self.prog["u_model"].write(ident)
            ctx.enable(mgl.DEPTH_TEST)
            self.solid_vao.render(mgl.TRIANGLES)
            ctx.disable(mgl.DEPTH_TEST)   # the marks and the track lie on the lane: drawn over it, under the bodies
            self.marks_vao.render(mgl.TRIANGLES)
            if self.trail_vao is not None and n_trail > 1:
                trail = self.trail_wide_vao if cam == "overhead" else self.trail_vao
                trail.render(mgl.TRIANGLE_STRIP, vertices=2 * n_trail)
            ctx.enable(mgl.DEPTH_TEST)
            for n, p in zip(range(1, 11), self.motion.pins[k]):
                if n not in self.in_play:     # parked behind the approach, out of the frame: not drawn
                    continue
                self.prog["u_model"].write(_pose(p).T.astype("f4").tobytes())
                self.pin_vao.render(mgl.TRIANGLES)
            self.ball_prog["u_model"].write(_pose(self.motion.ball[k]).T.astype("f4").tobytes())
            self.ball_tex.use(0)
            self.ball_prog["u_tex"].value = 0
            self.ball_vao.render(mgl.TRIANGLES)
        ctx.viewport = (0, 0, *self.size)
        ctx.disable(mgl.DEPTH_TEST)
        ctx.enable(mgl.BLEND)
        ctx.blend_func = mgl.ONE, mgl.ONE_MINUS_SRC_ALPHA  # the text shader's premultiplied alpha
        self._overlay(t, views)
        ctx.disable(mgl.BLEND)

    def release(self) -> None:
        for v, b in self._bufs:
            v.release()
            b.release()
        self.ball_tex.release()
        self.prog.release()
        self.ball_prog.release()
        self.text.release()
        self.small.release()
        self.target.release()


#: The still's default moment: this long before the ball's first contact with a pin (the ball
#: near the deck, every pin standing and numbered, the track behind it), or the end of the throw.
STILL_BEFORE_IMPACT = 0.12


def still_time(throw: Throw) -> float:
    m = throw.motion
    if math.isnan(m.impact):
        return float(m.times[-1])
    return max(0.0, m.impact - STILL_BEFORE_IMPACT)


def render_throw(throw: Throw, output, *, still: float | None = None, camera: str = "both", size=None,
                 fps=None, hold: float = 1.0, asked=None, probability=None, probability_note=None,
                 expected=None, no_request: bool = False, progress=None) -> int:
    """Render a recorded throw to ``output``: a .png at time ``still`` (seconds from the release;
    a negative value: :func:`still_time`), else a .mp4/.gif video at ``fps``. Returns the frames."""
    from nbst.render.video import render_video, write_png

    size = tuple(size or style.DEFAULT_SIZE)
    ctx = create_context()
    try:
        r = LaneRenderer(ctx, throw, size=size, camera=camera, asked=asked, probability=probability,
                         probability_note=probability_note, expected=expected, no_request=no_request)
        try:
            if still is not None:
                t = still_time(throw) if still < 0 else float(np.clip(still, 0.0, throw.motion.times[-1]))
                write_png(output, r.render(t))
                return 1
            fps = float(fps or style.DEFAULT_FPS)
            return render_video(r, frame_times(throw, fps, hold=hold), output, fps=fps, progress=progress)
        finally:
            r.release()
    finally:
        ctx.release()


def check_picture_args(args) -> str | None:
    """The first problem with ``nbst bowl throw``'s picture flags (--video, --still, --still-time,
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


def write_pictures(args, th: Throw, *, prog: str = "nbst bowl throw", **readout) -> str | None:
    """Write ``args.still`` and/or ``args.video`` (flags checked by :func:`check_picture_args`) of
    the recorded throw ``th``; ``readout``: LaneRenderer's asked, probability, probability_note,
    expected, no_request. A progress line on stderr for the video and one line per file written. Returns a
    one-line error, or None."""
    import sys

    from nbst.outputs import OutputError, prepare_output
    from nbst.render.gl import RenderError

    size = tuple(int(v) for v in str(args.size).lower().split("x")) if getattr(args, "size", None) else None
    st = getattr(args, "still_time", None)
    if st is not None and st > th.motion.times[-1]:
        return f"--still-time {st:g}: the throw lasts {th.motion.times[-1]:.2f} s"
    try:
        if getattr(args, "still", None):
            prepare_output(args.still, option="--still")
            render_throw(th, args.still, still=-1.0 if st is None else float(st), size=size, **readout)
            print(f"{prog}: wrote {args.still}", file=sys.stderr)
        if getattr(args, "video", None):
            prepare_output(args.video, option="--video")
            fps = float(getattr(args, "fps", None) or style.DEFAULT_FPS)
            from nbst.progress import progress_bar

            bar = progress_bar(total=len(frame_times(th, fps)), unit="frame", file=sys.stderr, desc="render")
            try:
                n = render_throw(th, args.video, size=size, fps=fps, progress=bar, **readout)
            finally:
                bar.close()
            print(f"{prog}: wrote {args.video} ({n} frames)", file=sys.stderr)
    except (OutputError, RenderError) as e:
        return str(e)
    return None


def picture_from_args(args, delivery, ball) -> str | None:
    """``nbst bowl throw --video/--still``: record the throw's frame on all ten pins (as ``bowl
    frame`` runs it) and write the video and/or the still. Returns a one-line error, or None."""
    from nbst.models.bowling import frame, lane
    from nbst.models.bowling import shot as shotmod

    bad = check_picture_args(args)
    if bad:
        return bad
    try:
        th = record_throw(delivery, args.oil, ball)
    except (lane.LaneError, frame.FrameError, shotmod.MujocoError) as e:
        return str(e)
    return write_pictures(args, th)


def throw_file_readout(d: dict) -> dict:
    """LaneRenderer's readout arguments for a checked throw file ``d`` (``throwfile.load``): the pins
    asked for (``requested``), the file's outcome, and its probability with n and 95 % CI."""
    out = {"expected": sorted(d["outcome"]["down"])}
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
