"""Bowling shots in 3D (``nbst render SHOT.json``): the lane, the pins and the ball, headless.

The motion is the shot's own replay (plain ``mj_step`` from the shot file's scene and
initial state, the pose of every body recorded at each 1 ms step); the pin mesh is the
same trimesh solid the scene is built from (:mod:`nbst.models.bowling.pin`). Two
cameras: ``behind`` (behind the ball, following it down the lane until the pins) and
``overhead`` (above the pin deck); ``both`` draws them side by side. The video runs
in slow motion (:data:`SLOW`) from just before the first ball-pin contact.

Compute apart from I/O: :func:`record` returns the motion, :class:`BowlingRenderer`
returns frames; :func:`render_shot` is the thin writer the CLI calls.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from nbst.render import style
from nbst.render.gl import FrameRenderer, FrameTarget, create_context
from nbst.render.scene3d import look_at, perspective

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

VS = """#version 330
uniform mat4 u_vp;
uniform mat4 u_model;
in vec3 in_pos;
in vec3 in_normal;
in vec3 in_color;
out vec3 v_normal;
out vec3 v_world;
out vec3 v_color;
void main() {
    vec4 w = u_model * vec4(in_pos, 1.0);
    v_world = w.xyz;
    v_normal = mat3(u_model) * in_normal;
    v_color = in_color;
    gl_Position = u_vp * w;
}
"""
FS = """#version 330
uniform vec3 u_light;
uniform vec3 u_eye;
in vec3 v_normal;
in vec3 v_world;
in vec3 v_color;
out vec4 f_color;
void main() {
    vec3 n = normalize(v_normal);
    vec3 v = normalize(u_eye - v_world);
    if (dot(n, v) < 0.0) n = -n;
    float diff = max(dot(n, u_light), 0.0);
    vec3 h = normalize(u_light + v);
    float spec = pow(max(dot(n, h), 0.0), 40.0) * 0.3;
    f_color = vec4(v_color * (0.35 + 0.65 * diff) + vec3(spec), 1.0);
}
"""


@dataclass(frozen=True)
class Motion:
    """A replayed shot: times (S,), ball (S, 7) and pins (S, 10, 7) poses (pos, quat wxyz)."""

    times: np.ndarray
    ball: np.ndarray
    pins: np.ndarray
    impact: float          # time of the first ball-pin contact (s), or nan
    down: list


def record(shot: dict, model) -> Motion:
    """Replay ``shot`` (a loaded shot file) in ``model`` and record every step's poses."""
    import mujoco

    from nbst.models.bowling import shot as shotmod

    d = mujoco.MjData(model)
    d.qpos[:] = shot["qpos0"]
    d.qvel[:] = shot["qvel0"]
    n = int(round(float(shot["duration"]) / model.opt.timestep))
    adr = shotmod.pin_addresses(model)
    ba = int(model.joint("ball_free").qposadr[0])
    ball_geom = model.geom("ball").id
    pin_bodies = {model.body(name).id for name in shot["pins"]}
    q = np.empty((n + 1, model.nq))
    q[0] = d.qpos
    impact = math.nan
    for k in range(n):
        mujoco.mj_step(model, d)
        q[k + 1] = d.qpos
        if math.isnan(impact):
            for c in d.contact[:d.ncon]:
                if ball_geom in (c.geom1, c.geom2) and {int(model.geom_bodyid[c.geom1]),
                                                        int(model.geom_bodyid[c.geom2])} & pin_bodies:
                    impact = float(d.time)
                    break
    down = shotmod.pins_of(int(shotmod.mask_of(shotmod.pins_down(model, q[-1][None]))[0]))
    return Motion(times=np.arange(n + 1) * model.opt.timestep, ball=q[:, ba:ba + 7],
                  pins=q[:, adr[:, None] + np.arange(7)], impact=impact, down=down)


def frame_times(motion: Motion, fps: float, *, hold: float = 1.0) -> np.ndarray:
    """Simulated time of each video frame: real time, slowed SLOW x around the impact, then a hold."""
    T = float(motion.times[-1])
    a, b = (0.0, 0.0) if math.isnan(motion.impact) else (max(0.0, motion.impact - IMPACT_WINDOW[0]),
                                                          min(T, motion.impact + IMPACT_WINDOW[1]))
    out, t = [], 0.0
    while t <= T:
        out.append(t)
        t += (1.0 / SLOW if a <= t < b else 1.0) / fps
    out.extend([T] * int(round(hold * fps)))
    return np.array(out)


def _quat_mat(q) -> np.ndarray:
    w, x, y, z = np.asarray(q, float) / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def _pose(p7) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3] = _quat_mat(p7[3:7])
    m[:3, 3] = p7[:3]
    return m


def _flat(mesh, color_fn) -> np.ndarray:
    """(V, 9) float32 unshared triangles: position, smooth vertex normal, colour."""
    tris = mesh.faces.reshape(-1)
    pos = mesh.vertices[tris]
    nrm = mesh.vertex_normals[tris]
    col = np.array([color_fn(p) for p in pos])
    return np.concatenate([pos, nrm, col], axis=1).astype("f4")


class BowlingRenderer(FrameRenderer):
    """Frames of a recorded shot: ``render(t)`` -> (H, W, 3) uint8; ``camera``: behind | overhead | both."""

    def __init__(self, ctx, motion: Motion, *, size=style.DEFAULT_SIZE, camera: str = "both"):
        import moderngl
        import trimesh

        from nbst.models.bowling import pin, scene

        if camera not in ("behind", "overhead", "both"):
            raise ValueError(f"camera must be behind, overhead or both, got {camera!r}")
        self.ctx, self.motion, self.camera = ctx, motion, camera
        self.size = tuple(size)
        self.target = FrameTarget(ctx, self.size, samples=style.MSAA_SAMPLES, depth=True)
        self.prog = ctx.program(vertex_shader=VS, fragment_shader=FS)
        self._mgl = moderngl
        L = np.array([0.3, 0.4, 1.0])
        self.prog["u_light"].value = tuple(L / np.linalg.norm(L))

        def vao(arr):
            buf = ctx.buffer(np.ascontiguousarray(arr).tobytes())
            return ctx.vertex_array(self.prog, [(buf, "3f 3f 3f", "in_pos", "in_normal", "in_color")]), buf

        g = pin.geometry()
        pm = trimesh.Trimesh(g.visual_vertices.astype(float), g.visual_faces, process=False)
        inch = 0.0254

        def pin_color(p):
            h = p[2] / inch
            return PIN_RED if any(lo <= h <= hi for lo, hi in STRIPES_IN) else PIN_WHITE

        self.pin_vao = vao(_flat(pm, pin_color))
        self.ball_vao = vao(_flat(trimesh.creation.icosphere(subdivisions=3, radius=scene.BALL_RADIUS),
                                  lambda p: BALL_RGB))
        statics = []
        hw, gw = scene.LANE_WIDTH / 2, scene.GUTTER_WIDTH
        boxes = [  # (x0, x1, y0, y1, z0, z1, rgb)
            (scene.LANE_START_X, scene.OIL_END_X, -hw, hw, -0.05, 0.0, (0.80, 0.64, 0.42)),
            (scene.OIL_END_X, scene.DECK_FRONT_X, -hw, hw, -0.05, 0.0, (0.86, 0.70, 0.48)),
            (scene.DECK_FRONT_X, scene.PIT_EDGE_X, -hw, hw, -0.05, 0.0, (0.90, 0.78, 0.58)),
            (scene.LANE_START_X, scene.PIT_EDGE_X, hw, hw + gw, -0.06, -scene.GUTTER_DEPTH, (0.40, 0.40, 0.45)),
            (scene.LANE_START_X, scene.PIT_EDGE_X, -hw - gw, -hw, -0.06, -scene.GUTTER_DEPTH, (0.40, 0.40, 0.45)),
            (scene.PIT_EDGE_X, scene.PIT_EDGE_X + scene.PIT_LENGTH, -hw - gw, hw + gw, -scene.PIT_DEPTH - 0.02,
             -scene.PIT_DEPTH, (0.15, 0.15, 0.17)),
            (scene.DECK_FRONT_X, scene.PIT_EDGE_X + scene.PIT_LENGTH, hw + gw, hw + gw + 0.05, -scene.PIT_DEPTH, 0.5,
             (0.22, 0.24, 0.30)),
            (scene.DECK_FRONT_X, scene.PIT_EDGE_X + scene.PIT_LENGTH, -hw - gw - 0.05, -hw - gw, -scene.PIT_DEPTH, 0.5,
             (0.22, 0.24, 0.30)),
        ]
        for x0, x1, y0, y1, z0, z1, rgb in boxes:
            b = trimesh.creation.box(extents=[x1 - x0, y1 - y0, z1 - z0])
            b.apply_translation([(x0 + x1) / 2, (y0 + y1) / 2, (z0 + z1) / 2])
            tris = b.faces.reshape(-1)
            fn = np.repeat(b.face_normals, 3, axis=0)
            statics.append(np.concatenate([b.vertices[tris], fn, np.tile(rgb, (len(tris), 1))], axis=1))
        self.static_vao = vao(np.concatenate(statics).astype("f4"))

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
            out.append(((i * vw, 0, vw, h), flip @ proj @ look_at(eye, tgt, up), eye))
        return out, k

    def draw(self, t: float) -> None:
        ctx = self.ctx
        fbo = self.target.draw_fbo
        fbo.use()
        ctx.enable(self._mgl.DEPTH_TEST)
        fbo.clear(*BACKGROUND, 1.0, depth=1.0)
        views, k = self._views(t)
        for vp, vpm, eye in views:
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

    def release(self) -> None:
        for v, b in (self.pin_vao, self.ball_vao, self.static_vao):
            v.release()
            b.release()
        self.prog.release()
        self.target.release()


def render_shot(path, output, *, still=None, camera: str = "both", size=None, fps=None, progress=None) -> int:
    """Render the shot file ``path`` to ``output`` (.mp4/.gif video, or .png at time ``still``).
    Returns the number of frames written."""
    import mujoco

    from nbst.models.bowling import shotfile

    from nbst.render.video import render_video, write_png

    shot = shotfile.load(path)
    from pathlib import Path

    model = mujoco.MjModel.from_xml_path(str(Path(path).parent / shot["scene"]))
    motion = record(shot, model)
    size = tuple(size or style.DEFAULT_SIZE)
    ctx = create_context()
    try:
        r = BowlingRenderer(ctx, motion, size=size, camera=camera)
        try:
            if still is not None:
                write_png(output, r.render(float(np.clip(still, 0.0, motion.times[-1]))))
                return 1
            fps = float(fps or style.DEFAULT_FPS)
            return render_video(r, frame_times(motion, fps), output, fps=fps, progress=progress)
        finally:
            r.release()
    finally:
        ctx.release()


def is_shot_file(path) -> bool:
    """True when ``path`` is a bowling shot file (JSON with kind ``nbst-bowling-shot``)."""
    import json
    from pathlib import Path

    from nbst.models.bowling.shotfile import KIND

    p = Path(str(path))
    if p.suffix.lower() != ".json" or not p.is_file():
        return False
    try:
        return json.loads(p.read_text()).get("kind") == KIND
    except (OSError, ValueError, AttributeError):
        return False


def cmd_render_shot(args) -> int:
    """``nbst render SHOT.json -o OUT [--still T] [--camera C] [--size WxH] [--fps F] [-q]``
    (the render CLI dispatches here when its first argument is a shot file)."""
    import sys

    from nbst.models.bowling.shotfile import ShotFileError
    from nbst.outputs import prepare_output

    from nbst.render.gl import RenderError

    out = str(args.output)
    still = getattr(args, "still", None)
    want = (".png",) if still is not None else (".mp4", ".gif")
    if not out.lower().endswith(want):
        print(f"nbst render: error: -o {out}: use a {' or '.join(want)} file"
              f"{' with --still' if still is not None else ' (or --still T for a .png)'}", file=sys.stderr)
        return 2
    size = getattr(args, "size", None)
    if isinstance(size, str):
        try:
            w, h = (int(v) for v in size.lower().split("x"))
            size = (w, h)
        except ValueError:
            print(f"nbst render: error: --size {size}: expected WxH, e.g. 1280x720", file=sys.stderr)
            return 2
    prepare_output(out, inputs=(args.problem,))
    bar = None
    if not getattr(args, "quiet", False) and still is None:
        from nbst.progress import progress_bar

        bar = progress_bar(unit="frame", file=sys.stderr, dynamic_ncols=True, desc="render")
    try:
        n = render_shot(args.problem, out, still=still, camera=getattr(args, "camera", None) or "both",
                        size=size, fps=getattr(args, "fps", None), progress=bar)
    except (ShotFileError, RenderError) as e:
        print(f"nbst render: error: {e}", file=sys.stderr)
        return 2
    finally:
        if bar is not None:
            bar.close()
    if not getattr(args, "quiet", False):
        print(f"nbst render: wrote {out} ({n} frame{'s' if n != 1 else ''})", file=sys.stderr)
    return 0
