"""5 m throws in 3D (``nbst render THROW.json``): the lane, the pins and the ball, headless.

The motion is the throw's own replay (plain ``mj_step`` from the throw file's scene and
initial state, the pose of every body recorded at each 1 ms step); every solid drawn is one of
the scene's MJCF geoms as the render core builds it (:mod:`nbst.render.core.geoms`): the pins'
visual mesh (with the neck stripes), the ball, and the lane, gutters, walls, pit and floor in
their MJCF colours. Two
cameras: ``behind`` (behind the ball, following it down the lane until the pins) and
``overhead`` (above the pin deck); ``both`` draws them side by side. The video runs
in slow motion (:data:`SLOW`) from just before the first ball-pin contact.

Compute apart from I/O: :func:`record` returns the motion, :class:`BowlingRenderer`
returns frames; :func:`render_file` is the thin writer (``nbst render``'s handler is
``nbst.cli.render.cmd_render_throw``). The shading is the core's (:mod:`nbst.render.core.shaders`).

Length: ~525 lines, past the house's ~500: recording, the two cameras and the readout of
one throw share the scene's meshes and the throw's timing, and read best together.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from nbst.errors import InputError
from nbst.files import sniff_kind
from nbst.render.core import style
from nbst.render.core import geoms as cg
from nbst.render.core.camera import look_at, perspective
from nbst.render.core.gl import FrameRenderer, FrameTarget
from nbst.render.core.shaders import SOLID_FS, SOLID_VS
from nbst.render.core.shapes import Text, text_cell
from nbst.render.core.times import frame_times
from nbst.render.core.video import render_output

__all__ = ["BACKGROUND", "BALL_RGB", "DISK_ONLY_FLAGS", "FPS_MAX", "IMPACT_WINDOW", "PIN_LABEL_BACK", "PIN_RED",
           "PIN_WHITE", "SLOW", "SNIFF_BYTES", "STRIPES_IN", "BowlingRenderer", "Motion", "ball_solid", "bowling_kind",
           "split_at_height",
           "is_throw_file", "load_motion", "motion_times", "pin_colour", "pin_solid", "record", "render_file",
           "render_motion", "slow_window", "static_solids"]

#: Slow motion around impact: this many times slower from IMPACT_WINDOW[0] s before
#: the first ball-pin contact to IMPACT_WINDOW[1] s after it.
SLOW = 4.0
IMPACT_WINDOW = (0.08, 0.7)
#: Pin colours: white maple with the red neck stripes (heights in inches).
PIN_WHITE = (0.96, 0.95, 0.92)
PIN_RED = (0.80, 0.10, 0.12)
STRIPES_IN = ((9.2, 9.6), (10.3, 10.7))
BALL_RGB = (0.30, 0.62, 0.96)
BACKGROUND = (0.10, 0.11, 0.13)
#: Overhead view: each pin's number is written on the deck this far (m) in front of its spot,
#: clear of the standing pin (belly radius 0.061 m) and of the spot in front (0.264 m).
PIN_LABEL_BACK = 0.11

@dataclass(frozen=True)
class Motion:
    """A replayed 5 m throw: times (S,), ball (S, 7) and pins (S, 10, 7) poses (pos, quat wxyz)."""

    times: np.ndarray
    ball: np.ndarray
    pins: np.ndarray
    impact: float          # time of the first ball-pin contact (s), or nan
    down: list
    down_masks: np.ndarray | None = None   # (S,) pins down (10-bit mask) at each step, by the throw's rule
    model: object = None                   # the compiled MjModel replayed: its geoms are what is drawn


def record(throw: dict, model) -> Motion:
    """Replay ``throw`` (a loaded 5 m throw file) in ``model`` and record every step's poses.
    A non-finite state is refused before stepping and MuJoCo's warnings raise
    :class:`~nbst.errors.MujocoError` (nothing goes to ``MUJOCO_LOG.TXT``)."""
    import mujoco

    from nbst.errors import MujocoError
    from nbst.models.bowling import pinfall
    from nbst.models.mjsearch.runner import check_state, data_warnings, mujoco_warnings_raise

    check_state(throw["qpos0"], throw["qvel0"])
    d = mujoco.MjData(model)
    d.qpos[:] = throw["qpos0"]
    d.qvel[:] = throw["qvel0"]
    n = int(round(float(throw["duration"]) / model.opt.timestep))
    adr = pinfall.pin_addresses(model)
    ba = int(model.joint("ball_free").qposadr[0])
    ball_geom = model.geom("ball").id
    pin_bodies = {model.body(name).id for name in throw["pins"]}
    q = np.empty((n + 1, model.nq))
    q[0] = d.qpos
    impact = math.nan
    with mujoco_warnings_raise():
        for k in range(n):
            mujoco.mj_step(model, d)
            q[k + 1] = d.qpos
            if math.isnan(impact):
                for c in d.contact[:d.ncon]:
                    if ball_geom in (c.geom1, c.geom2) and {int(model.geom_bodyid[c.geom1]),
                                                            int(model.geom_bodyid[c.geom2])} & pin_bodies:
                        impact = float(d.time)
                        break
    bad = data_warnings(d)
    if bad or not np.isfinite(q).all():
        raise MujocoError(f"MuJoCo warned: {', '.join(bad) or 'non-finite state'} during the replay")
    masks = pinfall.mask_of(pinfall.pins_down(model, q))
    return Motion(times=np.arange(n + 1) * model.opt.timestep, ball=q[:, ba:ba + 7],
                  pins=q[:, adr[:, None] + np.arange(7)], impact=impact, down=pinfall.pins_of(int(masks[-1])),
                  down_masks=masks, model=model)


def slow_window(motion: Motion) -> tuple[float, float]:
    """(start, end) simulated seconds of the slow motion around the first ball-pin contact."""
    T = float(motion.times[-1])
    if math.isnan(motion.impact):
        return 0.0, 0.0
    return max(0.0, motion.impact - IMPACT_WINDOW[0]), min(T, motion.impact + IMPACT_WINDOW[1])


def motion_times(motion: Motion, fps: float, *, hold: float = 1.0, realtime: bool = False) -> np.ndarray:
    """Simulated time of each video frame (:func:`nbst.render.core.times.frame_times`): real time,
    slowed SLOW x in :func:`slow_window` (not with ``realtime``: each frame 1/fps of the motion, as
    ``nbst export --gltf`` keys it), the last frame at the motion's end, then ``hold`` s."""
    a, b = slow_window(motion)
    return frame_times(float(motion.times[-1]), fps, windows=[(a, b)] if b > a and not realtime else [], slow=SLOW,
                       hold=hold)


def _pose(p7) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3] = cg.quat_mat(p7[3:7])
    m[:3, 3] = p7[:3]
    return m


def pin_colour(p) -> tuple:
    """A pin's colour at the body-frame point ``p``: white maple, red between STRIPES_IN (inches up)."""
    from nbst.models.bowling import scene

    h = p[2] / scene.INCH
    return PIN_RED if any(lo <= h <= hi for lo, hi in STRIPES_IN) else PIN_WHITE


def _visible_of(model, body: str) -> list[int]:
    b = model.body(body).id
    return [g for g in cg.visible_geoms(model) if int(model.geom_bodyid[g]) == b]


def split_at_height(rows: np.ndarray, z: float) -> np.ndarray:
    """Triangle rows (V, 6+: position, normal, ...) with every triangle that crosses the plane of
    height ``z`` cut there into three (the corners where its edges cross the plane interpolated,
    normals renormalised), so that a colour can change exactly at ``z``; the others unchanged."""
    tri = np.asarray(rows, float).reshape(-1, 3, rows.shape[1])
    side = tri[:, :, 2] > z
    cross = side.any(axis=1) & ~side.all(axis=1)
    out = [tri[~cross]]
    for t, sd in zip(tri[cross], side[cross]):
        # the lone corner (the one on its own side) first, the order of the other two kept
        k = int(np.flatnonzero(sd == (sd.sum() == 1))[0])
        a, b, c = t[k], t[(k + 1) % 3], t[(k + 2) % 3]

        def at(p, q):
            f = (z - p[2]) / (q[2] - p[2])
            v = p + f * (q - p)
            v[3:6] /= max(float(np.linalg.norm(v[3:6])), 1e-12)
            return v
        ab, ac = at(a, b), at(a, c)
        out.append(np.stack([np.stack([a, ab, ac]), np.stack([ab, b, c]), np.stack([ab, c, ac])]))
    return np.concatenate(out).reshape(-1, rows.shape[1])


def pin_solid(model) -> np.ndarray:
    """(V, 9) a pin in its body's frame: the first pin's visible geoms (its visual mesh), its
    triangles cut at the stripes' edges (the mesh's rings of vertices are 0.6-0.9 in apart, wider
    than a stripe) and each coloured whole by its centre's height: the two red neck stripes."""
    from nbst.models.bowling import scene

    parts = [r for g in _visible_of(model, "pin1") if (r := cg.body_rows(model, g)) is not None]
    out = []
    for r in parts:
        for lo, hi in STRIPES_IN:
            r = split_at_height(split_at_height(r, lo * scene.INCH), hi * scene.INCH)
        col = np.repeat([pin_colour(c) for c in np.asarray(r, float)[:, :3].reshape(-1, 3, 3).mean(axis=1)], 3, axis=0)
        out.append(cg.coloured(r, col))
    return np.concatenate(out)


def ball_solid(model, rgb=BALL_RGB, level: int = 3) -> np.ndarray:
    """(V, 9) the ball geom in its body's frame (an icosphere of ``level`` subdivisions), one colour."""
    g = model.geom("ball").id
    rows = cg.body_rows(model, g) if int(model.geom_type[g]) != cg.SPHERE else cg.posed(
        cg.sphere_rows(float(model.geom_size[g][0]), level), cg.quat_mat(model.geom_quat[g]), model.geom_pos[g])
    if rows is None:
        raise InputError("the scene's ball geom is of a type not drawn (a height field)")
    return cg.coloured(rows, rgb)


def static_solids(model) -> np.ndarray:
    """(V, 9) the world body's visible geoms (lane, gutters, walls, pit, floor) in world
    coordinates and their MJCF colours."""
    parts = []
    # planes last: the lane hides most of the floor, and depth-tested fragments behind it are not shaded
    for g in sorted(cg.visible_geoms(model), key=lambda g: int(model.geom_type[g]) == cg.PLANE):
        if int(model.geom_bodyid[g]) == 0 and (r := cg.body_rows(model, g)) is not None:
            parts.append(cg.coloured(r, cg.geom_rgba(model, g)))
    return np.concatenate(parts)


class BowlingRenderer(FrameRenderer):
    """Frames of a recorded 5 m throw: ``render(t)`` -> (H, W, 3) uint8; ``camera``: behind | overhead | both;
    ``clean``: no text (no readout, titles or pin numbers); ``realtime``: no "slow motion" said in the readout."""

    def __init__(self, ctx, motion: Motion, *, size=style.DEFAULT_SIZE, camera: str = "both", throw: dict | None = None,
                 clean: bool = False, realtime: bool = False):
        import moderngl

        if camera not in ("behind", "overhead", "both"):
            raise InputError(f"camera must be behind, overhead or both, got {camera!r}")
        self.ctx, self.motion, self.camera = ctx, motion, camera
        self.realtime = realtime  # no slow motion: none said in the readout
        self.size = tuple(size)
        self.throw = throw or {}
        self.clean = bool(clean)
        n_cams = 2 if camera == "both" else 1
        panel_w = self.size[0] // n_cams
        px = max(style.MIN_READOUT_PX, int(round(style.TEXT_FRAC * min(self.size))))
        chars = max(len(line) for line in self.readout(float(motion.times[-1])))
        while px > style.MIN_READOUT_PX and chars * text_cell(px)[0] > panel_w - 16:
            px -= 1
        self.text = Text(ctx, px)
        self.pin_text = Text(ctx, max(style.MIN_LABEL_PX, int(round(0.024 * min(self.size)))))
        self.target = FrameTarget(ctx, self.size, samples=style.MSAA_SAMPLES, depth=True)
        self.prog = ctx.program(vertex_shader=SOLID_VS, fragment_shader=SOLID_FS)
        self._mgl = moderngl
        L = np.array([0.3, 0.4, 1.0])
        self.prog["u_light"].value = tuple(L / np.linalg.norm(L))

        def vao(arr):
            buf = ctx.buffer(np.ascontiguousarray(arr).tobytes())
            return ctx.vertex_array(self.prog, [(buf, "3f 3f 3f", "in_pos", "in_normal", "in_color")]), buf

        model = motion.model
        if model is None:
            raise InputError("the motion carries no model: record it with record(throw, model)")
        self.pin_vao = vao(pin_solid(model))
        self.ball_vao = vao(ball_solid(model))
        self.static_vao = vao(static_solids(model))

    def _views(self, t):
        """[(viewport, view-projection, eye)] for the frame at time t."""
        w, h = self.size
        cams = ["behind", "overhead"] if self.camera == "both" else [self.camera]
        vw = w // len(cams)
        k = int(np.clip(round(t / (self.motion.times[1] - self.motion.times[0])), 0, len(self.motion.times) - 1))
        bx = min(float(self.motion.ball[k, 0]), -1.2)
        out = []
        for i, cam in enumerate(cams):
            aspect = vw / h
            if cam == "behind":
                eye = np.array([bx - 1.6, 0.0, 0.55])
                tgt = np.array([bx + 2.0, 0.0, 0.05])
                proj = perspective(40.0, aspect, 0.05, 20.0)
            else:
                eye = np.array([0.35, 0.0, 2.6])
                tgt = np.array([0.35, 0.0, 0.0])
                proj = perspective(42.0, aspect, 0.1, 10.0)
            up = np.array([1.0, 0.0, 0.0]) if cam == "overhead" else np.array([0.0, 0.0, 1.0])
            flip = np.diag([1.0, -1.0, 1.0, 1.0])  # image row 0 at the top: no flip on readback
            out.append(((i * vw, 0, vw, h), flip @ proj @ look_at(eye, tgt, up), eye, cam))
        return out, k

    def readout(self, t: float) -> list[str]:  # type: ignore[override]  # the disks' readout counts insides
        """The text of the frame at ``t``: what was asked, the pins down now (at the end: the
        result, and whether it is what was asked), the throw, the time and the slow motion."""
        from nbst.models.bowling import deck, pinfall

        def pins(ns) -> str:
            return ",".join(map(str, ns)) or "none"

        sh = self.throw
        asked = sorted(sh.get("requested", sh.get("down", [])))
        leave = [n for n in range(1, 11) if n not in asked]
        what = f" (leave {pins(leave)})" if leave and asked else " (a strike)" if asked else ""
        lines = [f"asked   down {pins(asked)}{what}"]
        m = self.motion
        k = int(np.clip(round(t / (m.times[1] - m.times[0])), 0, len(m.times) - 1))
        if m.down_masks is not None:
            now = pinfall.pins_of(int(m.down_masks[k]))
            if k == len(m.times) - 1:
                lines.append(f"result  down {pins(now)} " + ("= asked" if now == asked else "(not what was asked)"))
            else:
                lines.append(f"now     down {pins(now)}")
        la = sh.get("launch")
        if isinstance(la, dict) and all(key in la for key in deck.KEYS):
            lines.append(f"delivery {la['speed']:.2f} m/s, spin {la['spin']:+.1f} rad/s")
            lines.append(f"         angle {la['angle']:+.2f} deg, from y = {la['y']:+.3f} m")
        a, b = slow_window(m)
        slow = f"   slow motion x{SLOW:g}" if a <= t < b and not self.realtime else ""
        lines.append(f"t = {t:4.2f} s{slow}")
        return lines

    def _overlay(self, t: float, views) -> None:
        """Panel titles, the pin numbers on the deck (overhead view) and the readout, in pixels."""
        from nbst.models.bowling import scene

        size = self.size
        cw, ch = self.text.cell
        titles = {"behind": "behind the ball", "overhead": "overhead: the pin deck (USBC pin numbers)"}
        for (vx, _, vw, _), _, _, cam in views:
            for title in self.text.fit([titles[cam]], vw - 8):   # never into the next panel's
                self.text.draw_halo(size, self.text.layout([title], vx + (vw - cw * len(title)) / 2, 0.4 * ch),
                                    style.TEXT, style.TEXT_HALO)
            if cam == "overhead":
                vpm = next(v[1] for v in views if v[3] == "overhead")
                pcw, pch = self.pin_text.cell
                parts = []
                for n, (x, y) in zip(scene.PIN_NUMBERS, scene.pin_spots()):
                    c = vpm @ np.array([x - PIN_LABEL_BACK, y, 0.0, 1.0])
                    col = vx + (c[0] / c[3] + 1) / 2 * vw
                    row = (c[1] / c[3] + 1) / 2 * size[1]
                    label = str(n)
                    parts.append(self.pin_text.layout([label], col - pcw * len(label) / 2, row - pch / 2))
                self.pin_text.draw_halo(size, np.concatenate(parts), style.LABEL, PIN_WHITE)
        x0 = views[0][0][0] + 0.6 * cw
        lines = self.text.fit(self.readout(t), views[0][0][2] - 1.2 * cw, size[1] - 1.8 * ch)  # within its panel
        self.text.draw_halo(size, self.text.layout(lines, x0, 1.8 * ch), style.TEXT, style.TEXT_HALO)

    def draw(self, t: float) -> None:
        ctx = self.ctx
        fbo = self.target.draw_fbo
        fbo.use()
        ctx.enable(self._mgl.DEPTH_TEST)
        fbo.clear(*BACKGROUND, 1.0, depth=1.0)
        views, k = self._views(t)
        for vp, vpm, eye, _ in views:
            ctx.viewport = vp
            self.prog["u_vp"].write(vpm.T.astype("f4").tobytes())
            self.prog["u_eye"].value = tuple(eye)
            self.prog["u_model"].write(np.eye(4, dtype="f4").tobytes())
            self.static_vao[0].render(self._mgl.TRIANGLES)
            self.prog["u_model"].write(_pose(self.motion.ball[k]).T.astype("f4").tobytes())
            self.ball_vao[0].render(self._mgl.TRIANGLES)
            for p in self.motion.pins[k]:
                self.prog["u_model"].write(_pose(p).T.astype("f4").tobytes())
                self.pin_vao[0].render(self._mgl.TRIANGLES)
        ctx.viewport = (0, 0, *self.size)
        ctx.disable(self._mgl.DEPTH_TEST)
        ctx.enable(self._mgl.BLEND)
        ctx.blend_func = self._mgl.ONE, self._mgl.ONE_MINUS_SRC_ALPHA  # the text shader's premultiplied alpha
        if not self.clean:
            self._overlay(t, views)
        ctx.disable(self._mgl.BLEND)

    def release(self) -> None:
        for v, b in (self.pin_vao, self.ball_vao, self.static_vao):
            v.release()
            b.release()
        self.prog.release()
        self.text.release()
        self.pin_text.release()
        self.target.release()


#: ``nbst render THROW.json`` flags: frames per second in (0, FPS_MAX] (as the 2D renderer), the
#: still's time within the throw (0 .. its duration), frames at most the renderer's MAX_FRAMES.
FPS_MAX = 240.0
#: Flags of ``nbst render`` that draw disk problems only (2D/3D disks); an error on a throw file.
DISK_ONLY_FLAGS = (("trails", False, "--trails"), ("labels", False, "--labels"), ("view", None, "--view"),
                   ("source", None, "--source"), ("speed", None, "--speed"))


def load_motion(path):
    """(throw dict, Motion) of the 5 m throw file ``path``, read through the throw-file gate (scene
    in its folder, parsed, shapes checked) and replayed; ThrowFileError (one line) otherwise."""
    from nbst.errors import MujocoError
    from nbst.models.bowling.deck import throwfile

    throw, model, _ = throwfile.load_with_scene(path)
    try:
        return throw, record(throw, model)
    except MujocoError as e:
        raise throwfile.ThrowFileError(f"{path}: qpos0/qvel0: {e}") from None


def render_motion(throw: dict, motion: Motion, output, *, still=None, camera: str = "both", size=None,
                  times=None, fps=None, progress=None, clean: bool = False, realtime: bool = False) -> int:
    """Render a recorded 5 m throw to ``output`` (.mp4/.gif video of ``times`` at ``fps``, or .png at
    time ``still``).

    Args:
        throw: the 5 m throw file's dict (:func:`load_motion`'s first value).
        motion: its replayed :class:`Motion` (:func:`load_motion`'s second value).
        output: the .mp4, .gif or .png to write.
        still: None for a video; seconds: one frame at that time (clipped to the motion).
        camera: behind | overhead | both.
        size: (width, height) pixels (default 1280 x 720).
        times: the frames' times (default :func:`motion_times` at ``fps``).
        fps: frames per second (default 60).
        progress: None, or an object whose ``update(1)`` is called after each frame.
        clean: no overlay text (no readout, titles or pin numbers).
        realtime: no slow motion at the impact (default ``times``), none said in the readout.

    Returns:
        The number of frames written (1 for a still).

    Raises:
        InputError: an unknown camera.
        RenderError: no GL context, an extension other than .mp4/.gif/.png, or the encoder failed (one line).
    """

    size = tuple(size or style.DEFAULT_SIZE)

    return render_output(lambda ctx: BowlingRenderer(ctx, motion, size=size, camera=camera, throw=throw, clean=clean,
                                                     realtime=realtime),
                         output, still=None if still is None else np.clip(still, 0.0, motion.times[-1]),
                         times=lambda r, fps: motion_times(motion, fps, realtime=realtime) if times is None else times,
                         fps=fps, progress=progress)


def render_file(path, output, *, still=None, camera: str = "both", size=None, fps=None, progress=None,
                clean: bool = False) -> int:
    """Render the 5 m throw file ``path`` to ``output`` (.mp4/.gif video, or .png at time ``still``).

    Args:
        path: the throw file (``nbst bowl solve``).
        output, still, camera, size, fps, progress, clean: as :func:`render_motion`.

    Returns:
        The number of frames written (1 for a still).

    Raises:
        ThrowFileError: the file is not a 5 m throw file that replays (one line).
        RenderError: no GL context, or the video cannot be written.
    """
    throw, motion = load_motion(path)
    return render_motion(throw, motion, output, still=still, camera=camera, size=size, fps=fps, progress=progress,
                         clean=clean)


#: Bytes of a .json file read to tell a bowling file from a problem: nbst writes ``kind`` in
#: the first lines, so the sniff never reads a large file whole (the loaders read it, capped).
SNIFF_BYTES = 4096


def bowling_kind(path) -> str | None:
    """"throw" (a 5 m throw file) or "atlas" when ``path`` names a regular .json file whose first SNIFF_BYTES name
    an nbst bowling kind, else None. Reads at most SNIFF_BYTES (stat first: a FIFO or device
    is never opened), parses nothing."""
    from nbst.models.bowling.deck.throwfile import ATLAS_KIND, KIND

    # an atlas names its own kind before its throws' kind: the first found wins
    return sniff_kind(path, (("throw", KIND), ("atlas", ATLAS_KIND)), max_bytes=SNIFF_BYTES)


def is_throw_file(path) -> bool:
    """True when ``path`` looks like a 5 m throw file (:func:`bowling_kind`; the loader checks it)."""
    return bowling_kind(path) == "throw"
