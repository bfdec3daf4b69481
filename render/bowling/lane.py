"""A throw from the foul line in 3D (``nbst bowl throw --video/--still``): the full 60 ft lane
with its marks, a ball whose grip and track turn with it, numbered pins and a readout.

The throw is recorded, and the lane and ball laid out, by :mod:`nbst.render.bowling.throw`;
this module draws them.

* **Cameras**: ``behind`` (from behind the bowler, following the ball until it is
  :data:`FOLLOW_STOP_FT` ft down, pins numbered above their heads once they are large enough
  to read) and ``overhead`` (orthographic, true scale, the lane from :data:`OVERHEAD_FROM_FT`
  ft to the pit, with the ball's track on the lane, distance ticks and a pin diagram with the
  standing pins lit); ``both`` sets them side by side.
* **Readout**: the throw (hand, mph, rpm, rotation, tilt, boards at the foul line and arrows,
  launch angle), the oil and ball, the phases (skid, breakpoint, roll, at the pins), the pins
  down now (the final result at the end), and, when given, the pins asked for and the
  probability.

Compute apart from I/O: :class:`LaneRenderer` returns frames; :func:`render_throw` is the thin
writer the CLI calls (``nbst.cli.bowl.lane`` checks the flags and prints what was written).

Length: the full-lane video's cameras, oil shading and overlay (labels placed clear of the readout,
:meth:`LaneRenderer._place`) share one frame loop; past the house's 500.
"""
from __future__ import annotations

import math

import numpy as np

from nbst.errors import InputError
from nbst.models.bowling import lane, pin, pinfall, scene
from nbst.models.bowling.lane import names
from nbst.render.bowling.deck import BACKGROUND, PIN_WHITE, _pose, pin_solid
from nbst.render.bowling.throw import (BEHIND_AHEAD, BEHIND_BACK, BEHIND_FOV, BEHIND_HEIGHT, FOLLOW_STOP_FT, LEGEND,
                                       OVERHEAD_FROM_FT, OVERHEAD_SHARE, TRAIL_HALF_WIDTH, TRAIL_HALF_WIDTH_OVERHEAD,
                                       TRAIL_RGB, Throw, ball_texture, lane_marks, lane_solids, ortho_panel,
                                       still_time, throw_times)
from nbst.render.core import geoms as cg
from nbst.render.core import style
from nbst.render.core.camera import look_at, perspective
from nbst.render.core.gl import FrameRenderer, FrameTarget
from nbst.render.core.shaders import SHADE, SOLID_FS, SOLID_VS
from nbst.render.core.shapes import Text, text_cell
from nbst.render.core.solids import ribbon  # shared with the crash video
from nbst.render.core.video import render_output

__all__ = ["BALL_FS", "BALL_VS", "CAMERAS", "DECK_EYE", "DECK_FOV", "DECK_TARGET", "OIL_NAME_CHARS", "STANCE_SEP",
           "LaneRenderer", "oil_summary", "render_throw"]

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
""" + SHADE + """
void main() {
    vec3 d = normalize(v_local);
    vec2 uv = vec2(atan(d.y, d.x) / (2.0 * PI) + 0.5, acos(clamp(d.z, -1.0, 1.0)) / PI);
    f_color = vec4(shade(texture(u_tex, uv).rgb, v_normal, v_world, u_light, u_eye), 1.0);
}
"""


#: The most characters of an oil pattern's name on the readout (a pattern file may name it in 80).
OIL_NAME_CHARS = 24


def oil_summary(oil) -> str:
    """What a bowler reads of ``oil`` (a pattern, its registered name or its file): its name, its
    length and its volume, e.g. ``house (40 ft, 22 ml)``; the name cut to OIL_NAME_CHARS."""

    pat = lane.pattern(oil)
    name = pat.name if len(pat.name) <= OIL_NAME_CHARS else pat.name[:OIL_NAME_CHARS - 3] + "..."
    return f"{name} ({pat.length_ft:.0f} ft, {pat.volume_ml:.0f} ml)"


#: The cameras: behind the bowler (following the ball), overhead over the back of the lane, both
#: side by side, and the pin-deck close-up.
CAMERAS = ("behind", "overhead", "both", "deck")
#: The pin-deck camera (m; y towards the bowling hand's side, the pocket's): 1.5 m in front of the
#: head pin, 0.40 m up, looking at the middle of the rack at a pin's height, 42 deg of view.
DECK_EYE = (-1.5, -0.30, 0.40)
DECK_TARGET = (0.45, 0.0, 0.32)
DECK_FOV = 42.0
#: Boards from the slide foot to the ball at release (models/bowling/lane/advise.py's STANCE_SEP).
STANCE_SEP = 7.0


class LaneRenderer(FrameRenderer):
    """Frames of a recorded throw: ``render(t)`` -> (H, W, 3) uint8; ``camera``: behind | overhead | both |
    deck (the pin-deck close-up).
    ``asked`` (pins the throw was meant to knock down), ``probability`` (of the outcome, 0..1) and
    ``probability_note`` (e.g. its sample size and interval) add readout lines when given;
    ``expected`` (the pins down a throw file records) adds a line only when the recorded frame
    ends differently; ``no_request`` says on the ``asked`` line that a file asked for nothing; ``clean``
    draws no text (no readout, titles, pin numbers, ticks or key)."""

    def __init__(self, ctx, throw: Throw, *, size=style.DEFAULT_SIZE, camera: str = "both", asked=None,
                 probability: float | None = None, probability_note: str | None = None,
                 overhead_from_ft: float = OVERHEAD_FROM_FT, expected=None, no_request: bool = False,
                 clean: bool = False):
        import moderngl

        if camera not in CAMERAS:
            raise InputError(f"camera must be one of {', '.join(CAMERAS)}, got {camera!r}")
        self.ctx, self.throw, self.motion, self.camera = ctx, throw, throw.motion, camera
        self.size = tuple(size)
        self.asked = None if asked is None else sorted(int(p) for p in asked)
        self.expected = None if expected is None else sorted(int(p) for p in expected)
        self.no_request = bool(no_request)
        self.clean = bool(clean)
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
        text_w = next(iter(self.panels.values()))[2] if len(self.panels) == 1 else self.panels["behind"][2]
        chars = max(len(s) for s in self.readout(float(self.motion.times[-1])))
        while px > style.MIN_READOUT_PX and chars * text_cell(px)[0] > text_w - 16:
            px -= 1
        self.text = Text(ctx, px)
        self.small = Text(ctx, max(style.MIN_LABEL_PX, int(round(0.022 * min(self.size)))))
        self.target = FrameTarget(ctx, self.size, samples=style.MSAA_SAMPLES, depth=True)
        self.prog = ctx.program(vertex_shader=SOLID_VS, fragment_shader=SOLID_FS)
        self.ball_prog = ctx.program(vertex_shader=BALL_VS, fragment_shader=BALL_FS)
        L = np.array([0.3, 0.4, 1.0])
        for p in (self.prog, self.ball_prog):
            p["u_light"].value = tuple(L / np.linalg.norm(L))
        self._bufs: list = []

        def vao(arr, prog=None, fmt="3f 3f 3f", names=("in_pos", "in_normal", "in_color")):
            buf = ctx.buffer(np.ascontiguousarray(arr, dtype="f4").tobytes())
            v = ctx.vertex_array(prog or self.prog, [(buf, fmt, *names)])
            self._bufs.append((v, buf))
            return v

        # the pins and the ball: the frame model's own geoms (the core's triangles), the ball's
        # texture laid on in the shader
        model = self.motion.model
        if model is None:
            from nbst.models.bowling.lane import frame

            model = frame.frame_model(throw.ball, timestep=throw.timestep)
        self.pin_vao = vao(pin_solid(model))
        g = model.geom("ball").id
        self.ball_vao = vao(cg.sphere_rows(float(model.geom_size[g][0]), 4)[:, :3], self.ball_prog, "3f",
                            ("in_pos",))
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
            self.trail_vao = vao(ribbon(m.ball[on, :2], TRAIL_HALF_WIDTH, TRAIL_RGB))
            self.trail_wide_vao = vao(ribbon(m.ball[on, :2], TRAIL_HALF_WIDTH_OVERHEAD, TRAIL_RGB))
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

        w, h = self.size
        k = self.step_at(t)
        out = []
        for cam, vp in self.panels.items():
            if cam == "deck":   # the pin-deck close-up: fixed, low, in front of the pins, on the pocket's side
                s = lane.hand_sign(self.hand)
                eye = np.array([DECK_EYE[0], s * DECK_EYE[1], DECK_EYE[2]])
                tgt = np.array(DECK_TARGET)
                proj = perspective(DECK_FOV, vp[2] / h, 0.1, 20.0)
                flip = np.diag([1.0, -1.0, 1.0, 1.0])
                out.append((vp, flip @ proj @ look_at(eye, tgt, np.array([0.0, 0.0, 1.0])), eye, cam))
            elif cam == "behind":
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

    def readout(self, t: float) -> list[str]:  # type: ignore[override]  # the disks' readout counts insides
        """The text of the frame at ``t``: the throw, the oil and ball, the phases, the ball now,
        the pins down (at the end: the result), and the pins asked for and the probability when
        given."""

        th, d, r = self.throw, self.throw.delivery, self.throw.result
        b = th.ball

        def pins(ns) -> str:
            return ",".join(map(str, ns)) or "none"

        lines = [f"throw   {d.hand}-handed, {d.mph:.1f} mph, {d.rpm:.0f} rpm",
                 f"axis    rotation {d.rotation:.0f} deg, tilt {d.tilt:.0f} deg",
                 f"line    board {d.foul_board():.1f} at the foul line, {d.angle:+.1f} deg out "
                 f"(stance {d.foul_board() + STANCE_SEP:.1f})",
                 f"oil     {oil_summary(th.oil)}; ball {b.weight_lb:g} lb, RG {b.rg:.2f}, diff {b.diff:.3f}"]
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
            lines.append("asked   no pins named (a throw filmed as it fell)")
        if m.down_masks is not None:
            now = pinfall.pins_of(int(m.down_masks[k]))
            if k == len(m.times) - 1:
                tail = "" if self.asked is None else (" = asked" if now == self.asked else ", not asked")
                lines.append(f"result  down {pins(now)}{leave_of(now)}{tail}")
                if r is not None:

                    nm = names.names(play, [n for n in play if n not in now], r.board_at_pins, r.entry_angle_deg,
                                     d.hand)
                    lines.append(f"named   {names.text(nm)}")
                lines.append("note    one throw is a sample; its probability is the result")
                if self.expected is not None and now != self.expected:
                    lines.append(f"file    down {pins(self.expected)}: this run differs")
            else:
                lines.append(f"now     down {pins(now)}")
        if self.probability is not None:
            note = f" ({self.probability_note})" if self.probability_note else ""
            lines.append(f"chance  {100 * self.probability:.0f}%{note}")
        x, y = m.ball[k, 0], m.ball[k, 1]
        k0, k1 = max(k - 1, 0), min(k + 1, len(m.times) - 1)
        v = float(np.hypot(*(m.ball[k1, :2] - m.ball[k0, :2]))) / max((k1 - k0) * self.throw.timestep, 1e-12)
        where = (f"{float(lane.x_to_ft(x)):4.1f} ft, board {float(lane.y_to_board(y, d.hand)):4.1f}"
                 if x < 0.0 and abs(y) < 0.6 else "past the head pin")
        lines.append(f"t {t:4.2f} s  ball {where}, {v / lane.MPH:4.1f} mph")
        return lines

    def _overlay(self, t: float, views) -> None:
        """The titles, the labels and the readout: the readout laid out first, then each title and
        label only where it stays in its panel and the frame and clear of the readout's lines and the
        text placed before it (:meth:`_place`): at a small ``--size`` labels are left out, never drawn
        over other text."""

        size = self.size
        H = size[1]
        cw, ch = self.text.cell
        titles = {"behind": "behind the bowler: the full lane, 60 ft to the head pin",
                  "overhead": f"overhead from {lane.x_to_ft(self.overhead_x[0] + 0.3):.0f} ft",
                  "deck": "the pin deck, close up"}
        k = self.step_at(t)
        down = (pinfall.pins_of(int(self.motion.down_masks[k])) if self.motion.down_masks is not None else [])
        vp = self.panels.get("behind", next(iter(self.panels.values())))
        lines = self.readout(t)
        y0 = 1.5 * ch if ("behind" in self.panels or "deck" in self.panels) else max(1.5 * ch, H - (len(lines) + 0.5) * ch)
        lines = self.text.fit(lines, vp[2] - 1.2 * cw, H - y0)   # within its panel (a small --size)
        x0 = vp[0] + 0.6 * cw
        self._taken = [(x0 - 0.5 * cw, y0 + j * ch, x0 + (len(s.rstrip()) + 0.5) * cw, y0 + (j + 1) * ch)
                       for j, s in enumerate(lines) if s.strip()]
        for pvp, vpm, _, cam in views:
            title = titles[cam]
            if len(title) * cw > pvp[2] - 8:
                title = title.split(":")[0]
            for title in self.text.fit([title], pvp[2] - 8):   # never into the next panel's
                tx = pvp[0] + (pvp[2] - cw * len(title)) / 2
                self._taken.append((tx, 0.3 * ch, tx + cw * len(title), 1.3 * ch))
                self.text.draw_halo(size, self.text.layout([title], tx, 0.3 * ch), style.TEXT, style.TEXT_HALO)
        for pvp, vpm, _, cam in views:
            if cam in ("behind", "deck"):
                self._behind_labels(pvp, vpm, k, down)
            else:
                self._overhead_labels(pvp, vpm, down)
        self.text.draw_halo(size, self.text.layout(lines, x0, y0), style.TEXT, style.TEXT_HALO)

    def _place(self, vp, boxes) -> bool:
        """Whether labels in ``boxes`` [(x0, y0, x1, y1)] px all lie in the panel ``vp`` and the frame
        and clear of the readout's lines and the text placed before them (then they take their place)."""
        taken = self.__dict__.setdefault("_taken", [])
        for x0, y0, x1, y1 in boxes:
            if x0 < vp[0] or x1 > vp[0] + vp[2] or y0 < 0 or y1 > self.size[1]:
                return False
            if any(x0 < b[2] and b[0] < x1 and y0 < b[3] and b[1] < y1 for b in taken):
                return False
        taken.extend(boxes)
        return True

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

        if not len(self.motion.pins):
            return
        H = self.size[1]
        scw, sch = self.small.cell
        a = self.to_pixel(vp, vpm, [0.0, 0.0, 0.0], H)
        b = self.to_pixel(vp, vpm, [0.0, scene.PIN_SPACING, 0.0], H)
        if abs(a[0] - b[0]) < 3.5 * scw:
            return
        parts: list = []
        for n, p in zip(scene.PIN_NUMBERS, self.pin_label_points(k)):   # front rows first: they keep theirs
            if n in down or n not in self.in_play:
                continue
            col, row, front = self.to_pixel(vp, vpm, p, H)
            label = str(n)
            x0, y0 = col - scw * len(label) / 2, row - sch
            box = (x0 - scw / 2, y0, x0 + scw * (len(label) + 0.5), y0 + sch)
            # the readout, a title or a label nearer the camera is there (rows overlap seen from low behind)
            if front and self._place(vp, [box]):
                parts.append(self.small.layout([label], x0, y0))
        if parts:
            self.small.draw_halo(self.size, np.concatenate(parts), style.LABEL, PIN_WHITE)

    def pin_diagram(self, vp) -> list[tuple[int, float, float]]:
        """[(pin, column, row)] of the pin diagram's numbers (top-left of each label) in the
        overhead panel: the deck as a bowler sees it (7 8 9 10 at the back, the 1 in front)."""

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

        H = self.size[1]
        scw, sch = self.small.cell
        y_edge = scene.LANE_WIDTH / 2 + scene.GUTTER_WIDTH
        ticks = [(f"{ft:.0f} ft", ft) for ft in range(0, 61, 10)] + [("arrows", lane.ARROWS_FT)]
        diag = self.pin_diagram(vp)
        head = "pins"
        c0, r0 = min(c for _, c, _ in diag), 1.5 * self.text.cell[1]
        # the pin diagram whole or not at all (a small --size: under the readout, or past the frame)
        if self._place(vp, [(c0, r0, c0 + scw * len(head), r0 + sch)]
                       + [(c, r, c + scw * len(str(n)), r + sch) for n, c, r in diag]):
            self.small.draw_halo(self.size, self.small.layout([head], c0, r0), style.TEXT_DIM, style.TEXT_HALO)
            for standing, colour in ((True, style.TEXT), (False, (0.35, 0.37, 0.42))):
                parts = [self.small.layout([str(n)], c, r) for n, c, r in diag
                         if (n not in down and n in self.in_play) == standing]
                if parts:
                    self.small.draw_halo(self.size, np.concatenate(parts), colour, style.TEXT_HALO)
        parts = []
        for label, ft in ticks:
            x = float(lane.ft_to_x(ft))
            if not self.overhead_x[0] <= x <= self.overhead_x[1]:
                continue
            col, row, _ = self.to_pixel(vp, vpm, [x, y_edge, 0.0], H)
            x0, y0 = col - scw * (len(label) + 0.6), row - sch / 2
            if self._place(vp, [(x0, y0, x0 + scw * len(label), y0 + sch)]):
                parts.append(self.small.layout([label], x0, y0))
        if parts:
            self.small.draw_halo(self.size, np.concatenate(parts), style.TEXT_DIM, style.TEXT_HALO)
        # a key under the diagram, where it fits beside the lane
        x0 = self.to_pixel(vp, vpm, [0.0, -y_edge, 0.0], H)[0] + scw
        row = max(r for _, _, r in diag) + 2.5 * sch
        if self._place(vp, [(x0, row + i * sch, x0 + len(line) * scw, row + (i + 1) * sch)
                            for i, (line, _) in enumerate(LEGEND)]):
            for i, (line, rgb) in enumerate(LEGEND):
                self.small.draw_halo(self.size, self.small.layout([line], x0, row + i * sch), rgb, style.TEXT_HALO)

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
                assert trail is not None  # the two trails are made together
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
        if not self.clean:
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


def render_throw(throw: Throw, output, *, still: float | None = None, camera: str = "both", size=None,
                 fps=None, hold: float = 1.0, asked=None, probability=None, probability_note=None,
                 expected=None, no_request: bool = False, progress=None, clean: bool = False) -> int:
    """Render a recorded throw to ``output``: a .png at time ``still``, else a .mp4/.gif video.

    Args:
        throw: the recorded throw from the foul line (``nbst.render.bowling.throw.record_throw``).
        output: the .mp4, .gif or .png to write.
        still: None for a video; seconds from the release: one frame then (clipped to the
            motion); a negative value: :func:`still_time`.
        camera: behind | overhead | both | deck (the pin deck close up).
        size: (width, height) pixels (default 1280 x 720).
        fps: frames per second (default 60).
        hold: seconds the last frame is held.
        asked: the pins the throw was meant to knock down (a readout line), or None.
        probability: the probability of the outcome, 0..1 (a readout line), or None.
        probability_note: its sample size and interval, or None.
        expected: the pins down a throw file records (a line only when the frame ends
            differently), or None.
        no_request: say on the ``asked`` line that the file asked for nothing.
        progress: None, or an object whose ``update(1)`` is called after each frame.
        clean: no overlay text (no readout, titles, pin numbers, ticks or key).

    Returns:
        The number of frames written (1 for a still).

    Raises:
        InputError: an unknown camera.
        RenderError: no GL context, an extension other than .mp4/.gif/.png, or the encoder failed (one line).
    """

    size = tuple(size or style.DEFAULT_SIZE)
    if still is not None:
        still = still_time(throw) if still < 0 else np.clip(still, 0.0, throw.motion.times[-1])
    return render_output(lambda ctx: LaneRenderer(ctx, throw, size=size, camera=camera, asked=asked,
                                                  probability=probability, probability_note=probability_note,
                                                  expected=expected, no_request=no_request, clean=clean),
                         output, still=still, times=lambda r, fps: throw_times(throw, fps, hold=hold),
                         fps=fps, progress=progress)
