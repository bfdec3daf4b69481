"""A crash in 3D (``nbst render CRASH.json``): the road, the vehicles, their marks and the readout.

The motion is the crash file's own replay (:mod:`nbst.render.crash.motion`); everything drawn
comes from the file (:mod:`nbst.render.crash.scene`): the road and the vehicles are the
scene's own geoms (their MJCF sizes, poses and colours), placed each frame by
``mj_kinematics`` from the recorded ``qpos``, so the wheels spin and steer as their joints do.

* **Cameras**: ``overhead`` (orthographic, true scale, north up, over every path, target and
  impact, with a scale bar; the wheels drawn through the bodies so that their steering shows)
  and ``behind``, a chase camera behind the followed vehicle, :data:`CHASE_SIDE` degrees off
  its axis so the wheels' faces show, turning with its heading smoothed over
  :data:`CHASE_TAU` s (a spinning car does not whirl the camera), that keeps its partner (the
  vehicle it first hits) in view too: it looks at a point between them and backs off (and up)
  as far as both need (:func:`chase_framing`); ``both``: the overhead view on the left half
  of the frame, full height, the chase view and the readout on the right.
* **At each impact** of a vehicle pair, from its time on: each vehicle's velocity arrow (just
  before the contact) and its PDOF arrow (the principal direction of force, from its velocity
  change over the contact, :func:`nbst.render.crash.motion.impact_vectors`), labelled in the
  overhead view with its clock direction.
* **On the road**: lane markings, the script's rest regions and heading arrows, each
  vehicle's trail, skid marks and scrapes, and an impact ring at each first contact point
  from the moment of contact, labelled with the pair and the time (drawn over the vehicles in
  the overhead view, as a crash diagram marks its points of impact).
* **Readout** (:mod:`nbst.render.crash.readout`) in a column on the right; slow motion around
  each impact (:func:`nbst.render.core.times.frame_times`). ``clean``: no text at all (no
  readout, titles, names or labels, no scale bar), the views filling the frame.

Compute apart from I/O: :class:`CrashRenderer` returns frames; :func:`render_crash` is the thin
writer the CLI calls; :func:`crash_kind` sniffs a file's kind.

Length: the crash video's two views (overhead and chase, with the chase's framing), the impact
arrows and the frame loop share the recorded motion and one GL context.
"""
from __future__ import annotations

import math
from typing import Any

import numpy as np

from nbst.errors import InputError
from nbst.files import sniff_kind
from nbst.render.core import style
from nbst.render.core.camera import look_at, perspective
from nbst.render.core.gl import FrameRenderer, FrameTarget
from nbst.render.core.shaders import SOLID_FS, SOLID_VS
from nbst.render.core.shapes import Rect, Text, text_cell
from nbst.render.core.textfit import CUT
from nbst.render.core.times import frame_times
from nbst.render.core.video import render_output
from nbst.render.crash import readout as ro
from nbst.render.crash import scene as cs
from nbst.render.crash.motion import SLOW, record, slow_windows, slowed
from nbst.render.scene2d import keep_apart

__all__ = ["BOTH_OVERHEAD_SHARE", "CAMERAS", "CHASE_FLOOR", "CHASE_LADDER", "CHASE_MIN_SHARE", "CHASE_NDC", "IMPACT_TEXT", "LIGHT",
           "MARK_FS", "MARK_VS", "PANEL", "SCALE_BARS", "SKY", "SNIFF_BYTES", "CrashRenderer", "chase_framing",
           "chase_yaw", "crash_kind", "load", "partner_of", "render_crash", "top_view"]

CAMERAS = ("overhead", "behind", "both")
#: Share of the frame's width the readout column takes, and the most it takes where its text
#: at MIN_READOUT_PX needs more (small frames).
COLUMN_SHARE, COLUMN_MAX = 0.36, 0.62
#: Camera "both": the overhead view takes this share of the frame's width, full height (so at least
#: half the frame); the chase view at least CHASE_MIN_SHARE of the height of the column on its
#: right, the readout the rest (its text smaller where it needs more rows; past the smallest
#: text, the chase view gives it rows down to CHASE_FLOOR of the height).
BOTH_OVERHEAD_SHARE, CHASE_MIN_SHARE, CHASE_FLOOR = 0.5, 0.45, 0.3
#: Chase camera: this far behind the vehicle (m), this high, looking at a point this far ahead
#: of it, from this many degrees off its axis (its left), field of view (deg); the heading it
#: follows is smoothed with this time constant (s).
CHASE_BACK, CHASE_HEIGHT, CHASE_AHEAD, CHASE_SIDE, CHASE_FOV, CHASE_TAU = 14.0, 5.5, 6.0, 15.0, 45.0, 0.6
#: Keeping the partner in view: the camera's distances to try, as multiples of CHASE_BACK (its
#: height grows with it), the look point's share of the way from the followed vehicle to its
#: partner, and how far out (normalised device coordinates) a vehicle's box may project.
CHASE_LADDER = (1.0, 1.25, 1.6, 2.0, 2.5, 3.2, 4.0, 5.0, 6.5, 8.0, 10.0, 13.0)
CHASE_BLEND = (0.0, 0.5)
CHASE_NDC = 0.9
#: A vehicle's box for framing: this half length and half width (m) about its CoM, up to its height.
CHASE_BOX = (2.6, 1.1)
#: Overhead view: the impacts, rest poses and regions and the paths within this distance (m) of
#: them, with this margin (m), at least this wide (m).
OVERHEAD_LEAD, OVERHEAD_MARGIN, OVERHEAD_MIN = 12.0, 4.0, 24.0
#: Scale bar lengths (m) to choose from: the longest under a quarter of the panel's width.
SCALE_BARS = (1, 2, 5, 10, 20, 50, 100, 200)
SKY = (0.60, 0.68, 0.78)
PANEL = (0.09, 0.10, 0.12)
OK_RGB, NO_RGB = (0.35, 0.85, 0.40), (0.95, 0.32, 0.26)
IMPACT_TEXT = (1.0, 0.70, 0.30)
LIGHT = (0.3, 0.4, 1.0)

MARK_VS = """#version 330
uniform mat4 u_vp;
in vec3 in_pos;
in vec4 in_color;
in float in_time;
out vec4 v_color;
out float v_time;
void main() {
    v_color = in_color;
    v_time = in_time;
    gl_Position = u_vp * vec4(in_pos, 1.0);
}
"""
#: A mark shows from its time on (the crash scene's rows): a ribbon whose vertices carry the times
#: they were laid grows between two samples as the frame's time passes.
MARK_FS = """#version 330
uniform float u_t;
in vec4 v_color;
in float v_time;
out vec4 f_color;
void main() {
    if (v_time > u_t) discard;
    f_color = vec4(v_color.rgb * v_color.a, v_color.a);
}
"""


def top_view(bounds, vp) -> tuple[np.ndarray, float]:
    """(4x4 view-projection, px per m) of a true-scale view from above of ``bounds`` (x0, y0, x1,
    y1) m in the viewport ``vp`` (x, top row, w, h) px: x east to the right, y north up, centred;
    image row 0 at the top (as FrameTarget); larger z nearer."""
    x0, y0, x1, y1 = bounds
    _, _, vw, vh = vp
    ppm = min(vw / (x1 - x0), vh / (y1 - y0))
    cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
    m = np.zeros((4, 4))
    m[0, 0], m[0, 3] = 2 * ppm / vw, -2 * ppm * cx / vw
    m[1, 1], m[1, 3] = -2 * ppm / vh, 2 * ppm * cy / vh
    m[2, 2], m[2, 3] = -0.1, 0.3
    m[3, 3] = 1.0
    return m, ppm


def chase_yaw(times: np.ndarray, yaw: np.ndarray, tau: float = CHASE_TAU) -> np.ndarray:
    """The chase camera's heading at each sample: the vehicle's unwrapped yaw through a causal
    first-order low-pass of time constant ``tau`` s (exact for the samples' spacing)."""
    out = np.empty_like(yaw)
    out[0] = yaw[0]
    a = 1.0 - np.exp(-np.diff(times) / tau)
    for k in range(1, len(yaw)):
        out[k] = out[k - 1] + a[k - 1] * (yaw[k] - out[k - 1])
    return out


def partner_of(motion, i: int) -> int | None:
    """The vehicle ``i`` first hits (its first vehicle pair impact), else the nearest other vehicle
    at the end, else None (it drives alone)."""
    for im in motion.impacts:
        if im.what == "vehicle" and im.b is not None and i in (im.a, im.b):
            return im.b if im.a == i else im.a
    n = motion.pos.shape[1]
    if n < 2:
        return None
    d = [np.inf if j == i else float(np.hypot(*(motion.pos[-1, j, :2] - motion.pos[-1, i, :2]))) for j in range(n)]
    return int(np.argmin(d))


def _chase_matrix(p, q, yaw, scale, blend, aspect):
    """(view-projection, eye) of the chase camera at ``scale`` x CHASE_BACK behind ``p`` (heading
    ``yaw``), looking at the point ``blend`` of the way from ``p``'s look point to ``q``."""
    back = yaw + math.pi - math.radians(CHASE_SIDE)
    eye = p + np.array([scale * CHASE_BACK * math.cos(back), scale * CHASE_BACK * math.sin(back),
                        scale * CHASE_HEIGHT])
    look = p + np.array([CHASE_AHEAD * math.cos(yaw), CHASE_AHEAD * math.sin(yaw), 0.6])
    tgt = look if q is None else (1 - blend) * look + blend * np.array([q[0], q[1], 0.6])
    flip = np.diag([1.0, -1.0, 1.0, 1.0])  # image row 0 at the top: no flip on readback
    far = 3000.0 * scale
    return flip @ perspective(CHASE_FOV, aspect, 0.5, far) @ look_at(eye, tgt, np.array([0.0, 0.0, 1.0])), eye


def _box_corners(pos, yaw, height) -> np.ndarray:
    """(8, 3) the corners of a vehicle's framing box (CHASE_BOX) at ``pos`` heading ``yaw``."""
    c, s = math.cos(yaw), math.sin(yaw)
    a, b = CHASE_BOX
    out = []
    for dx in (-a, a):
        for dy in (-b, b):
            for z in (0.0, height):
                out.append([pos[0] + c * dx - s * dy, pos[1] + s * dx + c * dy, z])
    return np.array(out)


def _contains(vpm, pts) -> bool:
    c = vpm @ np.c_[pts, np.ones(len(pts))].T
    if np.any(c[3] <= 0.5):
        return False
    ndc = c[:2] / c[3]
    return bool(np.all(np.abs(ndc) <= CHASE_NDC))


def chase_framing(motion, follow: int, partner: int | None, cam_yaw: np.ndarray, heights, aspect: float
                  ) -> tuple[np.ndarray, np.ndarray]:
    """(scale (S,), blend (S,)) of the chase camera at each sample: the nearest of CHASE_LADDER
    (then the look point's CHASE_BLEND towards the partner) at which both vehicles' boxes project
    inside CHASE_NDC of the view; the scale backs off at once and closes in smoothly
    (CHASE_TAU), never closer than the sample needs."""
    S = len(motion.times)
    need_s, need_b = np.ones(S), np.zeros(S)
    if partner is None:
        return need_s, need_b
    for k in range(S):
        p = motion.pos[k, follow].copy()
        p[2] = 0.0
        q = motion.pos[k, partner]
        pts = np.concatenate([_box_corners(p, float(motion.yaw[k, follow]), heights[follow]),
                              _box_corners(q, float(motion.yaw[k, partner]), heights[partner])])
        found = None
        for sc in CHASE_LADDER:
            for bl in CHASE_BLEND:
                if _contains(_chase_matrix(p, q, float(cam_yaw[k]), sc, bl, aspect)[0], pts):
                    found = (sc, bl)
                    break
            if found:
                break
        need_s[k], need_b[k] = found or (CHASE_LADDER[-1], CHASE_BLEND[-1])
    # back off at once, close in over CHASE_TAU; the look point likewise, never short of the need
    scale, blend = need_s.copy(), need_b.copy()
    a = 1.0 - np.exp(-np.diff(motion.times) / CHASE_TAU)
    for k in range(1, S):
        scale[k] = max(need_s[k], scale[k - 1] + a[k - 1] * (need_s[k] - scale[k - 1]))
        blend[k] = max(need_b[k], blend[k - 1] + a[k - 1] * (need_b[k] - blend[k - 1]))
    return scale, blend


class CrashRenderer(FrameRenderer):
    """Frames of a recorded crash: ``render(t)`` -> (H, W, 3) uint8.

    d, script, model: ``crashfile.load``'s; motion: ``nbst.render.crash.motion.record``'s; camera: overhead |
    behind | both; follow: the chased vehicle's index (behind and both); clean: no text (the views
    fill the frame); realtime: no slow motion at the impacts (no windows, none said in the titles)."""

    def __init__(self, ctx, d: dict, script, model, motion, *, size=style.DEFAULT_SIZE, camera: str = "overhead",
                 follow: int = 0, clean: bool = False, realtime: bool = False):
        import moderngl
        import mujoco

        from nbst.models.crash import crashfile

        if camera not in CAMERAS:
            raise InputError(f"camera must be one of {', '.join(CAMERAS)}, got {camera!r}")
        self.ctx, self.d, self.script, self.model, self.motion = ctx, d, script, model, motion
        self.camera, self.follow, self.clean = camera, int(follow), bool(clean)
        self.size = (int(size[0]), int(size[1]))
        self._mgl, self._mj = moderngl, mujoco
        self.data = mujoco.MjData(model)
        n = script.n
        self.names = script.names()
        self.colours = [tuple(float(c) for c in model.geom_rgba[model.geom(f"v{i}_lower").id][:3]) for i in range(n)]
        self.fates = [crashfile.fate_dict(script, i) for i in range(n)]
        self.labels = [v.vtype.label for v in script.vehicles]
        self.windows = [] if realtime else slow_windows([im.t for im in motion.impacts], motion.duration)
        w, h = self.size
        # the readout: text as large as TEXT_FRAC of the frame, in a column COLUMN_SHARE wide;
        # where its lines do not fit, the text shrinks (to MIN_READOUT_PX), then the column widens
        # (to COLUMN_MAX of the frame; past that the lines are cut at the frame's edge)
        chars, rows = ro.widest(motion, script, self.fates, self.labels, self.windows)
        px = max(style.MIN_READOUT_PX, int(round(style.TEXT_FRAC * min(self.size))))
        if camera == "both":
            # the overhead on the left (at least half the frame), the chase view over the readout on the right
            ow = int(math.ceil(BOTH_OVERHEAD_SHARE * w))
            rw = w - ow
            room = 0 if self.clean else int((1 - CHASE_MIN_SHARE) * h)
            while px > style.MIN_READOUT_PX and ((chars + 2) * text_cell(px)[0] > rw or
                                                 (rows + 1) * text_cell(px)[1] > room):
                px -= 1
            # rows that do not fit at the smallest text take the chase view's height, down to CHASE_FLOOR
            th = 0 if self.clean else min((rows + 1) * text_cell(px)[1], int((1 - CHASE_FLOOR) * h))
            self.panels = {"overhead": (0, 0, ow, h), "behind": (ow, 0, rw, h - th)}
            self.text_box = self.column = (ow, h - th, rw, th)
        else:
            cw_ = 0 if self.clean else int(round(COLUMN_SHARE * w))
            while not self.clean and px > style.MIN_READOUT_PX and ((chars + 2) * text_cell(px)[0] > cw_ or
                                                                    (rows + 1) * text_cell(px)[1] > h):
                px -= 1
            if not self.clean:   # the overhead view keeps at least BOTH_OVERHEAD_SHARE of the width
                most = COLUMN_MAX if camera == "behind" else 1 - BOTH_OVERHEAD_SHARE
                cw_ = int(min(max(cw_, (chars + 2) * text_cell(px)[0]), math.floor(most * w)))
            self.column = self.text_box = (w - cw_, 0, cw_, h)
            self.panels = {camera: (0, 0, w - cw_, h)}
        self.text = Text(ctx, px)
        self.small = Text(ctx, max(style.MIN_LABEL_PX, int(round(0.018 * min(self.size)))))
        self.target = FrameTarget(ctx, self.size, samples=style.MSAA_SAMPLES, depth=True)
        self.prog = ctx.program(vertex_shader=SOLID_VS, fragment_shader=SOLID_FS)
        L = np.asarray(LIGHT) / np.linalg.norm(LIGHT)
        self.prog["u_light"].value = tuple(L)
        self.mprog = ctx.program(vertex_shader=MARK_VS, fragment_shader=MARK_FS)
        self._objs: list = []
        self.data.qpos[:] = motion.qpos[0]    # the start: the statics, and the wheels the arches are over
        mujoco.mj_kinematics(model, self.data)
        ground, statics, rgb = cs.static_solids(model, self.data)
        self.ground_vao, self.static_vao = self._vao(ground), self._vao(statics)
        # the overhead view clears to the ground's lit colour instead of filling it (a flat surface
        # under LIGHT: ambient + diffuse; the highlight of the chase view's ground is left out)
        self.ground_rgb = tuple(float(c) * (0.35 + 0.65 * float(L[2])) for c in rgb)
        self.lines_vao = self._vao(np.concatenate([cs.lane_marks(script.road),
                                                   cs.target_marks(self.fates, self.colours)]), marks=True)
        self.trail_vao = self._vao(cs.motion_marks(motion, self.colours), marks=True)
        self.impact_vao = self._vao(np.concatenate([
            cs.impact_arrows(motion.impacts, lambda t, i: motion.pos[motion.index(t), i], self.colours),
            cs.impact_marks(motion.impacts)]), marks=True)
        # the vehicles' geoms, one buffer per shape (equal vehicles share theirs); the lower body
        # has an arch over each wheel, placed from the wheels' poses at the start
        self.geoms: list[tuple[int, bool, Any]] = []    # (geom id, is a tyre, vao)
        self.heights = []
        cache: dict = {}
        for i in range(n):
            for g in cs.vehicle_geoms(model, i):
                nm = model.geom(g).name
                arches = cs.vehicle_arches(model, self.data, i, g)
                key = (int(model.geom_type[g]), tuple(np.round(model.geom_size[g], 6)), tuple(model.geom_rgba[g]),
                       nm.endswith("_cabin"), "_tyre_" in nm, tuple(np.round(np.ravel(arches), 6)))
                if key not in cache:
                    solid = cs.geom_solid(model, g, arches)
                    cache[key] = None if solid is None else self._vao(solid)
                if cache[key] is not None:
                    self.geoms.append((g, "_tyre_" in nm, cache[key]))
            self.heights.append(script.vehicles[i].vtype.height)
        self.bounds = self._overhead_bounds()
        self.partner = partner_of(motion, self.follow)
        if "behind" in self.panels:
            self.cam_yaw = chase_yaw(motion.times, motion.yaw[:, self.follow])
            vp = self.panels["behind"]
            self.chase_scale, self.chase_blend = chase_framing(motion, self.follow, self.partner, self.cam_yaw,
                                                               self.heights, vp[2] / vp[3])

    def _vao(self, rows: np.ndarray, *, marks: bool = False):
        """A vertex array of solids (V, 9) or marks (V, 8); None for no rows."""
        if not len(rows):
            return None
        buf = self.ctx.buffer(np.ascontiguousarray(rows, dtype="f4").tobytes())
        if marks:
            vao = self.ctx.vertex_array(self.mprog, [(buf, "3f 4f 1f", "in_pos", "in_color", "in_time")])
        else:
            vao = self.ctx.vertex_array(self.prog, [(buf, "3f 3f 3f", "in_pos", "in_normal", "in_color")])
        self._objs += [vao, buf]
        return vao

    def _overhead_bounds(self) -> tuple[float, float, float, float]:
        """(x0, y0, x1, y1) m the overhead view shows: the crash's places (every impact, rest pose
        and rest region) and the paths within OVERHEAD_LEAD m of them, with OVERHEAD_MARGIN, at least
        OVERHEAD_MIN across, in the panel's aspect: a crash diagram the vehicles drive into (their
        names wait at the edge they come from)."""
        m = self.motion
        keys = [m.pos[-1, :, :2]]
        for f in self.fates:
            if "rest" in f:
                r = f["rest"]
                keys.append(np.array([[r["x"] - r["radius"], r["y"] - r["radius"]],
                                      [r["x"] + r["radius"], r["y"] + r["radius"]]]))
        keys += [np.array([im.pos[:2]]) for im in m.impacts if all(math.isfinite(c) for c in im.pos[:2])]
        places = np.concatenate(keys)
        path = m.pos[:, :, :2].reshape(-1, 2)
        near = np.hypot(*(path[:, None, :] - places[None]).transpose(2, 0, 1)).min(axis=1) <= OVERHEAD_LEAD
        p = np.concatenate([places, path[near]])
        lo, hi = p.min(axis=0) - OVERHEAD_MARGIN, p.max(axis=0) + OVERHEAD_MARGIN
        c, half = (lo + hi) / 2, np.maximum((hi - lo) / 2, OVERHEAD_MIN / 2)
        _, _, vw, vh = self.panels["overhead"] if "overhead" in self.panels else (0, 0, 1, 1)
        aspect = vw / vh
        half = np.maximum(half, [half[1] * aspect, half[0] / aspect])
        return c[0] - half[0], c[1] - half[1], c[0] + half[0], c[1] + half[1]

    # ---------------------------------------------------------------- cameras

    def views(self, t: float):
        """[(camera, viewport (x, top row, w, h) px, view-projection, eye)] of the frame at ``t``."""
        out = []
        k = self.motion.index(t)
        for cam, vp in self.panels.items():
            if cam == "overhead":
                vpm, _ = top_view(self.bounds, vp)
                out.append((cam, vp, vpm, np.array([0.0, 0.0, 100.0])))
                continue
            p = self.motion.pos[k, self.follow].copy()
            p[2] = 0.0
            q = None if self.partner is None else self.motion.pos[k, self.partner]
            vpm, eye = _chase_matrix(p, q, float(self.cam_yaw[k]), float(self.chase_scale[k]),
                                     float(self.chase_blend[k]), vp[2] / vp[3])
            out.append((cam, vp, vpm, eye))
        return out

    @staticmethod
    def to_pixel(vp, vpm, p) -> tuple[float, float, bool]:
        """(column, row, in front of the camera) of the world point ``p`` in the panel ``vp``."""
        c = vpm @ np.r_[np.asarray(p, float)[:3], 1.0]
        return vp[0] + (c[0] / c[3] + 1) / 2 * vp[2], vp[1] + (c[1] / c[3] + 1) / 2 * vp[3], c[3] > 0

    def readout(self, t: float) -> list[str]:  # type: ignore[override]  # the disks' readout counts insides
        return ro.readout(t, self.motion, self.script, self.fates, self.labels, self.windows)

    # ---------------------------------------------------------------- drawing

    def draw(self, t: float) -> None:
        mgl, ctx = self._mgl, self.ctx
        k = self.motion.index(t)
        self.data.qpos[:] = self.motion.qpos[k]
        self._mj.mj_kinematics(self.model, self.data)
        fbo = self.target.draw_fbo
        fbo.use()
        fbo.clear(*PANEL, 1.0, depth=1.0)
        views = self.views(t)
        for cam, vp, vpm, eye in views:
            ctx.viewport = vp
            fbo.clear(*(SKY if cam == "behind" else self.ground_rgb), 1.0, depth=1.0, viewport=vp)
            ctx.enable(mgl.DEPTH_TEST)
            ctx.disable(mgl.BLEND)
            self.prog["u_vp"].write(vpm.T.astype("f4").tobytes())
            self.prog["u_eye"].value = tuple(float(e) for e in eye)
            self.prog["u_model"].write(np.eye(4, dtype="f4").tobytes())
            for vao in (self.ground_vao if cam == "behind" else None, self.static_vao):
                if vao is not None:
                    vao.render(mgl.TRIANGLES)
            ctx.enable(mgl.BLEND)
            ctx.blend_func = mgl.ONE, mgl.ONE_MINUS_SRC_ALPHA
            self.mprog["u_vp"].write(vpm.T.astype("f4").tobytes())
            self.mprog["u_t"].value = float(t)
            fbo.depth_mask = False   # the marks lie on the road in the order drawn: each is hidden by
            for vao in (self.lines_vao, self.trail_vao, self.impact_vao if cam == "behind" else None):
                if vao is not None:  # what stands in front of it, and hides nothing
                    vao.render(mgl.TRIANGLES)
            fbo.depth_mask = True
            ctx.disable(mgl.BLEND)
            self._draw_vehicles(tyres_only=False)
            if cam == "overhead":
                ctx.disable(mgl.DEPTH_TEST)   # the wheels through the bodies; the impacts over all
                self._draw_vehicles(tyres_only=True)
                if self.impact_vao is not None:
                    ctx.enable(mgl.BLEND)
                    self.impact_vao.render(mgl.TRIANGLES)
        ctx.viewport = (0, 0, *self.size)
        ctx.disable(mgl.DEPTH_TEST)
        ctx.enable(mgl.BLEND)
        ctx.blend_func = mgl.ONE, mgl.ONE_MINUS_SRC_ALPHA  # the text shader's premultiplied alpha
        if not self.clean:
            self._overlay(t, k, views)
        ctx.disable(mgl.BLEND)

    def _draw_vehicles(self, *, tyres_only: bool) -> None:
        mgl = self._mgl
        m = np.eye(4, dtype="f4")
        for g, tyre, vao in self.geoms:
            if tyres_only and not tyre:
                continue
            m[:3, :3] = self.data.geom_xmat[g].reshape(3, 3)
            m[:3, 3] = self.data.geom_xpos[g]
            self.prog["u_model"].write(m.T.copy().tobytes())
            vao.render(mgl.TRIANGLES)

    def _overlay(self, t: float, k: int, views) -> None:
        """Panel titles, names by the vehicles and their targets, impact labels, the scale bar and
        the readout, in pixels."""
        size = self.size
        sm = self.small
        scw, sch = sm.cell
        for cam, vp, vpm, _ in views:
            title = ("overhead, true scale" if cam == "overhead" else f"chase: {self.names[self.follow]}")
            if cam == "behind" and slowed(t, self.windows):
                title += f"   slow motion \u00d7{ro.SLOW:g}"
            placed = []        # label boxes (x0, y0, x1, y1) px drawn in this panel, the title's first
            for title in sm.fit([title], vp[2] - 1.2 * scw):   # never into the next panel (a small --size)
                sm.draw_halo(size, sm.layout([title], vp[0] + 0.6 * scw, vp[1] + 0.3 * sch), style.TEXT,
                             style.TEXT_HALO)
                placed.append((vp[0] + 0.6 * scw, vp[1] + 0.3 * sch, vp[0] + 0.6 * scw + scw * len(title),
                               vp[1] + 1.3 * sch))
            for i, nm in enumerate(self.names):
                p = self.motion.pos[k, i].copy()
                p[2] += self.heights[i]
                col, row, front = self.to_pixel(vp, vpm, p)
                if cam == "overhead":   # above the vehicle; at the panel's edge while it is outside
                    col = float(np.clip(col, vp[0] + scw * (len(nm) / 2 + 0.5), vp[0] + vp[2] - scw * (len(nm) / 2 + 0.5)))
                    rows = [float(np.clip(r, vp[1] + 1.5 * sch, vp[1] + vp[3] - 1.2 * sch))
                            for r in (row - 1.6 * sch, row + 0.6 * sch)]   # above it, else below it
                elif not (front and self._inside(vp, col, row)):
                    continue
                else:
                    rows = [row - 0.5 * sch, row - 1.6 * sch]
                # clear of the title and the names and labels placed (two vehicles side by side at a touch)
                spot = next((b for b in (self._box(vp, nm, col - scw * len(nm) / 2, r) for r in rows)
                             if keep_apart([b], placed)[0]), None)
                if spot is None:
                    continue
                placed.append(self._label(vp, nm, spot[0], spot[1], self.colours[i]))
                if cam == "overhead" and "rest" in self.fates[i]:
                    f = self.fates[i]["rest"]
                    col, row, _ = self.to_pixel(vp, vpm, (f["x"], f["y"] + f["radius"], 0.0))
                    x, y = col - scw * len(nm) / 2, row - 1.1 * sch
                    if self._inside(vp, col, row) and keep_apart([(x, y, x + scw * len(nm), y + sch)], placed)[0]:
                        placed.append(self._label(vp, nm, x, y, self.colours[i]))

            for im in self.motion.impacts:
                if im.t > t or not all(math.isfinite(c) for c in im.pos[:2]):
                    continue
                label = (f"{self.names[im.a]}-{self.names[im.b]}" if im.b is not None else
                         f"{self.names[im.a]} {im.what}") + f" {im.t:.2f} s"
                col, row, front = self.to_pixel(vp, vpm, im.pos)
                if not (front and self._inside(vp, col, row)):
                    continue
                w = scw * len(label)
                spots = [(col + 0.8 * scw, row + 0.3 * sch), (col + 0.8 * scw, row - 1.3 * sch),
                         (col - 0.8 * scw - w, row + 0.3 * sch), (col - 0.8 * scw - w, row - 1.3 * sch),
                         (col - w / 2, row + 1.2 * sch), (col - w / 2, row - 2.2 * sch),
                         (col - w / 2, row + 2.2 * sch), (col - w / 2, row - 3.2 * sch)]
                boxes = [self._box(vp, label, x, y) for x, y in spots]   # where _label would draw each
                free = next((b for b in boxes if keep_apart([b], placed)[0]), None)
                if free is not None:   # no room (a small frame, labels crowded): the ring speaks alone
                    placed.append(self._label(vp, label, free[0], free[1], IMPACT_TEXT))
                if cam == "overhead":
                    self._pdof_labels(vp, vpm, im, placed)
            if cam == "overhead":
                self._scale_bar(vp, vpm)
        self._readout(t)

    def _pdof_labels(self, vp, vpm, im, placed: list) -> None:
        """Beside each PDOF arrow's tail (overhead): the vehicle's name and the clock direction."""
        scw, sch = self.small.cell
        col, row, _ = self.to_pixel(vp, vpm, im.pos)
        r = cs.IMPACT_RING[1] * top_view(self.bounds, vp)[1] + 2
        placed.append((col - r, row - r, col + r, row + r))   # the ring stays clear
        for i, h in im.pdof.items():
            dx, dy = im.dv[i]
            n = math.hypot(dx, dy)
            if n < 1e-6:
                continue
            x, y = self.motion.pos[self.motion.index(im.t), i, :2]
            tail = (x - (cs.PDOF_LENGTH + 0.8) * dx / n, y - (cs.PDOF_LENGTH + 0.8) * dy / n, 0.0)
            col, row, _ = self.to_pixel(vp, vpm, tail)
            if not self._inside(vp, col, row):
                continue
            label = f"{self.names[i]} PDOF {h} o'clock"
            w = scw * len(label)
            spots = [(col - w / 2, row - 0.5 * sch), (col - w / 2, row - 1.6 * sch), (col - w / 2, row + 0.6 * sch),
                     (col + 0.8 * scw, row - 0.5 * sch), (col - 0.8 * scw - w, row - 0.5 * sch)]
            spot = next(((a, b) for a, b in spots if vp[0] <= a and a + w <= vp[0] + vp[2]
                         and keep_apart([self._box(vp, label, a, b)], placed)[0]), None)
            if spot is not None:   # no room (a small frame): the arrow speaks alone
                placed.append(self._label(vp, label, spot[0], spot[1], cs.PDOF[:3]))

    def _box(self, vp, text: str, x: float, y: float) -> tuple:
        """The box (x0, y0, x1, y1) px of ``text`` in the small size with its top-left at (x, y), moved
        into the panel ``vp`` where it would cross its edge."""
        sm = self.small
        x = float(np.clip(x, vp[0], max(vp[0], vp[0] + vp[2] - sm.cell[0] * len(text))))
        y = float(np.clip(y, vp[1], max(vp[1], vp[1] + vp[3] - sm.cell[1])))
        return (x, y, x + sm.cell[0] * len(text), y + sm.cell[1])

    def _label(self, vp, text: str, x: float, y: float, colour) -> tuple:
        """Draw ``text`` in the small size at :meth:`_box`'s place; its box."""
        box = self._box(vp, text, x, y)
        self.small.draw_halo(self.size, self.small.layout([text], box[0], box[1]), colour, style.TEXT_HALO)
        return box

    @staticmethod
    def _inside(vp, col, row) -> bool:
        return vp[0] <= col < vp[0] + vp[2] and vp[1] <= row < vp[1] + vp[3]

    def _scale_bar(self, vp, vpm) -> None:

        _, ppm = top_view(self.bounds, vp)
        L = max((b for b in SCALE_BARS if b * ppm <= vp[2] / 4), default=SCALE_BARS[0])
        sm = self.small
        x0, y0 = vp[0] + 0.6 * sm.cell[0], vp[1] + vp[3] - 1.6 * sm.cell[1]
        if not hasattr(self, "_rect"):
            self._rect = Rect(self.ctx)
            self._objs.append(self._rect)
        self._rect.draw(self.size, (x0, y0, x0 + L * ppm, y0 + 4.0), fill=(*style.TEXT, 1.0), rim=(*style.TEXT_HALO, 1.0),
                        stroke=1.0)
        sm.draw_halo(self.size, sm.layout([f"{L} m"], x0 + L * ppm + 0.5 * sm.cell[0], y0 - 0.4 * sm.cell[1]),
                     style.TEXT, style.TEXT_HALO)

    def _readout(self, t: float) -> None:
        lines = self.readout(t)
        plain, oks, nos = ro.mark_masks(lines)
        owner = ro.colour_rows(lines, self.names)
        cw, ch = self.text.cell
        x0, y0 = self.text_box[0] + 0.7 * cw, self.text_box[1] + 0.5 * ch
        size = self.size
        # within its panel (a small --size): the marks cut where their line is
        fitted = self.text.fit(plain, self.text_box[2] - 1.4 * cw, self.text_box[3] - 0.5 * ch)
        cut = [None if a == b else len(a) - len(CUT) * a.endswith(CUT) for a, b in zip(fitted, plain)]
        keep = max(0, len(fitted) - (len(fitted) < len(plain)))   # lines kept whole (the last may be the marker)
        oks = [m[:cut[j]] if cut[j] is not None else m for j, m in enumerate(oks[:keep])]
        nos = [m[:cut[j]] if cut[j] is not None else m for j, m in enumerate(nos[:keep])]
        owner = [o if j < keep else -1 for j, o in enumerate(owner[:len(fitted)])]
        plain = fitted
        base = [s if owner[j] < 0 else "" for j, s in enumerate(plain)]
        self.text.draw(size, self.text.layout(base, x0, y0), style.TEXT)
        for j, s in enumerate(plain):
            if owner[j] >= 0:
                self.text.draw(size, self.text.layout([s], x0, y0 + j * ch), self.colours[owner[j]])
        self.text.draw(size, self.text.layout(oks, x0, y0), OK_RGB)
        self.text.draw(size, self.text.layout(nos, x0, y0), NO_RGB)

    def release(self) -> None:
        for o in self._objs:
            o.release()
        self.prog.release()
        self.mprog.release()
        self.text.release()
        self.small.release()
        self.target.release()


# --------------------------------------------------------------------------- files

#: Bytes of a .json file read to tell a crash file from others: ``crash_dict`` writes ``kind``
#: second, so the sniff never reads a large file whole (the loader reads it, capped).
SNIFF_BYTES = 4096


def crash_kind(path) -> str | None:
    """"crash" (a crash file) or "script" (a crash script) when ``path`` names a regular .json
    file whose first SNIFF_BYTES name that kind, else None (``nbst.files.sniff_kind``)."""
    from nbst.models.crash.crashfile import KIND
    from nbst.models.crash.script import KIND as SCRIPT_KIND

    return sniff_kind(path, (("crash", KIND), ("script", SCRIPT_KIND)), max_bytes=SNIFF_BYTES)


def load(path):
    """(crash dict, Script, MjModel, CrashMotion) of the crash file ``path``: read through the crash
    file's gate (``crashfile.load``: one line naming the field) and replayed."""
    from nbst.models.crash import crashfile

    d, script, model = crashfile.load(path)
    return d, script, model, record(d, script, model)


def render_crash(d: dict, script, model, motion, output, *, still=None, camera: str = "overhead", follow: int = 0,
                 size=None, fps=None, hold: float = 1.0, times=None, progress=None, clean: bool = False,
                 realtime: bool = False) -> int:
    """Render a recorded crash to ``output`` (.mp4/.gif at ``fps``, slowed around each impact, or a
    .png at time ``still``).

    Args:
        d, script, model: the checked crash file, its script and its MuJoCo model, as
            ``nbst.models.crash.crashfile.load`` returns them.
        motion: the replayed motion (``nbst.render.crash.motion.record(d, script, model)``).
        output: the .mp4, .gif or .png to write.
        still: None for a video; seconds: one frame at that time (clipped to the motion).
        camera: overhead | behind | both.
        follow: the index of the vehicle the behind camera chases.
        size, fps: (width, height) pixels and frames per second (default 1280 x 720, 60).
        hold: seconds the last frame is held.
        times: the frames' times (default :func:`nbst.render.core.times.frame_times`: slowed at impacts).
        progress: None, or an object whose ``update(1)`` is called after each frame.
        clean: no overlay text (no readout, titles, names or labels): the views fill the frame.
        realtime: no slow motion at the impacts (default ``times``), none said in the titles.

    Returns:
        The number of frames written (1 for a still).

    Raises:
        InputError: an unknown camera.
        RenderError: no GL context, an extension other than .mp4/.gif/.png, or the encoder failed (one line).
    """

    size = tuple(size or style.DEFAULT_SIZE)
    return render_output(lambda ctx: CrashRenderer(ctx, d, script, model, motion, size=size, camera=camera,
                                                   follow=follow, clean=clean, realtime=realtime),
                         output, still=None if still is None else np.clip(still, 0.0, motion.duration),
                         times=lambda r, fps: (frame_times(motion.duration, fps, windows=r.windows, slow=SLOW, hold=hold)
                                               if times is None else times),
                         fps=fps, progress=progress)


