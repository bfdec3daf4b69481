"""A scene solution in 3D (``nbst render SOL.json``): any MJCF drawn with moderngl.

* **The scene**: every geom MuJoCo's viewer shows by default (groups 0-2, alpha above 0) as its
  type's solid (:mod:`nbst.render.core.geoms`: plane, sphere, capsule, ellipsoid, cylinder, box,
  mesh) in its material's or its own colour, posed each frame from the replay
  (:mod:`nbst.render.scene.motion`); lit by the model's first light (else :data:`LIGHT`) with the
  3D worlds' shading (``nbst.render.core.shaders.SHADE``) and shadows from a shadow map of that
  light; planes carry a faint checker so the floor reads.
* **The fates**: each region (``rest_in``, ``at``, ``through``, the hoops numbered in order) as a
  translucent solid with its outline in its body's mark colour; an ``up`` axis as an arrow on the
  body; each first touch after the start (an impact; each pair once) that the fates name (all,
  where none do) as a yellow ball from its time on, each labelled with the body and what it
  touched (``cube-block2 0.24 s``); a body marked in a colour that nothing else in the frame
  carries (the palette's, no region or arrow: a ``still`` block) is tagged with its name in it.
* **The readout** (:mod:`nbst.render.scene.readout`), top left: asked vs happened (the brief one
  where the whole one would cover more than :data:`READOUT_WIDE` of the frame's width), and what
  nbst does not draw (a flex). ``clean`` draws no text at all.
* **Cameras**: a model camera by name, else one that frames the fated and controlled bodies and
  their regions from the front and above, tracking the bodies as they move (a box over where they
  are within a fraction of a second, smoothed: :mod:`nbst.render.scene.framing`).

Compute apart from I/O: :class:`SceneRenderer` returns frames; :func:`render_scene` is the thin
writer the CLI calls; :func:`is_scene_solution` sniffs a file.
"""
from __future__ import annotations

import math
import os
from typing import Any

import numpy as np

from nbst.errors import InputError
from nbst.files import sniff_kind
from nbst.render.core import style
from nbst.render.core.camera import look_at, orthographic, perspective
from nbst.render.core.gl import FrameRenderer, FrameTarget
from nbst.render.core.shapes import Rect, Text, text_cell
from nbst.render.core.times import frame_times
from nbst.render.core.video import render_output
from nbst.render.core import geoms as sg
from nbst.render.scene import readout as ro
from nbst.render.scene.readout import MARKS, legible, mark_colours
from nbst.render.scene.framing import (AZIMUTH, box_corners, clear_azimuth, default_camera, focus_points, on_track_grid,
                                      regions_of, track_grid, tracking_boxes)
from nbst.render.core.shaders import DEPTH_FS, DEPTH_VS, SCENE_FS, SCENE_VS
from nbst.render.scene.motion import SceneMotion, Touch, record
from nbst.scene.fates import Fates
from nbst.scene.solution import SOLUTION_FORMAT

__all__ = ["LIGHT", "MARKS", "READOUT_FRAC", "READOUT_WIDE", "SKY", "IMPACT", "SHADOW_PX", "SceneRenderer",
           "is_scene_solution", "render_scene", "camera_names"]

#: Towards the light when the model has none (world frame).
LIGHT = (0.35, -0.5, 1.0)
SKY = (0.78, 0.84, 0.90)
IMPACT = (1.0, 0.82, 0.15)
OK_RGB, NO_RGB = (0.35, 0.85, 0.40), (0.95, 0.32, 0.26)
PANEL_RGBA = (0.08, 0.09, 0.11, 0.72)
#: The readout's text height as a share of the frame's smaller side (smaller where it does not fit).
READOUT_FRAC = 0.02
#: The whole readout covers at most this share of the frame's width (its text shrinking to the least
#: legible size); past it, the brief one (at 320x180 the whole one hid the ball).
READOUT_WIDE = 0.6
#: The shadow map's side (px).
SHADOW_PX = 2048
#: Regions are drawn this opaque; their outlines this.
REGION_ALPHA, OUTLINE_ALPHA = 0.16, 0.9

def _unit_cylinder() -> np.ndarray:
    """(V, 6) a cylinder of radius 1 along z from 0 to 1 (a tendon's segment, stretched by :func:`_stretch`)."""
    import trimesh

    from nbst.render.core.camera import mesh_arrays

    rows = mesh_arrays(trimesh.creation.cylinder(radius=1.0, height=1.0, sections=16)).astype(float)
    rows[:, 2] += 0.5
    return rows


def _stretch(a: np.ndarray, b: np.ndarray, width: float) -> np.ndarray:
    """The 3x3 taking the unit cylinder (radius 1, z from 0 to 1) to the segment a-b of radius ``width``
    (a tendon's segment; with a unit b - a and width 1, a rotation taking z to b - a: an up-arrow)."""
    z = b - a
    u = z / np.linalg.norm(z)
    x = np.cross(u, [1.0, 0.0, 0.0] if abs(u[0]) < 0.9 else [0.0, 1.0, 0.0])
    x /= np.linalg.norm(x)
    return np.column_stack([x * width, np.cross(u, x) * width, z])


def is_scene_solution(path: str | os.PathLike) -> bool:
    """Whether ``path`` is a regular .json file whose first bytes name the scene solution format
    (``nbst.files.sniff_kind``; the solution's reader checks it)."""
    return sniff_kind(path, (("scene", SOLUTION_FORMAT),)) == "scene"


def camera_names(model: Any) -> list[str]:
    """The model's cameras by name (unnamed ones as ``#k``)."""
    return [model.camera(c).name or f"#{c}" for c in range(int(model.ncam))]


class SceneRenderer(FrameRenderer):
    """Frames of a replayed scene solution: ``render(t)`` -> (H, W, 3) uint8.

    Args:
        ctx: the moderngl context.
        motion, fates, model: :func:`nbst.render.scene.motion.record`'s.
        size: (W, H) px.
        camera: a model camera's name, or None for the framing camera.
        clean: no text (no readout, no labels).
        title: the readout's first line.

    Raises:
        InputError: ``camera`` names no camera of the model (one line listing those it has).
    """

    def __init__(self, ctx: Any, motion: SceneMotion, fates: Fates, model: Any, *, size=style.DEFAULT_SIZE,
                 camera: str | None = None, clean: bool = False, title: str = ""):
        import moderngl
        import mujoco

        self.ctx, self.motion, self.fates, self.model = ctx, motion, fates, model
        self._mgl = moderngl
        self.size = (int(size[0]), int(size[1]))
        self.clean, self.title = bool(clean), title
        w, h = self.size
        names = camera_names(model)
        self.cam = -1
        if camera is not None:
            if camera not in names:
                have = ", ".join(names) if names else "none"
                raise InputError(f"camera {camera!r}: the scene has no camera of that name (its cameras: {have})")
            self.cam = names.index(camera)
        # the light: the model's first, else LIGHT (towards the light, world frame)
        d = mujoco.MjData(model)
        mujoco.mj_forward(model, d)
        L = -np.asarray(d.light_xdir[0], float) if model.nlight else np.asarray(LIGHT, float)
        if np.linalg.norm(L) < 1e-9:
            L = np.asarray(LIGHT, float)
        self.light = L / np.linalg.norm(L)
        # the framing (its points, the checker's size, the tracking boxes) on the frames of its own
        # clock, whatever the video's fps: a still at t is the video's frame at t
        self.grid = on_track_grid(motion)
        points = focus_points(self.grid, fates, model)
        self.lo, self.hi = points.min(axis=0), points.max(axis=0)
        span = float(np.linalg.norm(self.hi - self.lo))
        self.span = span
        # the planes' checker: 1, 2.5 or 5 x 10^k m, the nearest (in ratio) to a tenth of the framed extent
        want = max(span, 1e-3) / 10
        k = math.floor(math.log10(want))
        self.checker = min((m * 10.0 ** e for e in (k, k + 1) for m in (1.0, 2.5, 5.0)),
                           key=lambda c: abs(math.log(c / want)))
        # the geoms: one vertex array per distinct shape
        self.prog = ctx.program(vertex_shader=SCENE_VS, fragment_shader=SCENE_FS)
        self.dprog = ctx.program(vertex_shader=DEPTH_VS, fragment_shader=DEPTH_FS)
        self._objs: list[Any] = [self.prog, self.dprog]
        cache: dict = {}
        self.items: list[tuple[int, Any, Any, tuple[float, float, float, float], bool]] = []  # g, vao, depth vao, rgba, plane
        extent = max(3.0 * span, 1.0)
        for g in sg.visible_geoms(model):
            t = int(model.geom_type[g])
            key = (t, tuple(np.round(model.geom_size[g], 9)), int(model.geom_dataid[g]) if t in (sg.MESH, sg.HFIELD) else -1)
            if key not in cache:
                rows = sg.geom_rows(model, g, extent=extent)
                cache[key] = None if rows is None else self._vaos(rows)
            if cache[key] is not None:
                vao, dvao = cache[key]
                self.items.append((g, vao, dvao, sg.geom_rgba(model, g), t == sg.PLANE))
        # the spatial tendons' segments (a unit cylinder, scaled to each one's width and length)
        self.tendon_vao = self._vaos(_unit_cylinder())[0] if motion.tendon_segs is not None else None
        # the fates' marks
        self.marks: list[tuple[Any, Any, tuple[float, ...]]] = []   # (solid vao, outline vao, rgb)
        self.hoops: list[tuple[np.ndarray, str, tuple[float, ...]]] = []   # (centre, label, rgb)
        self.arrows: list[tuple[int, np.ndarray, Any, tuple[float, ...]]] = []  # (body, axis, vao, rgb)
        # the impacts: the first touches the fates name (ro.drawn_touches), each labelled; the bodies
        # whose mark colour nothing else in the frame carries, named beside them in it (ro.name_tags)
        self.impacts: list[Touch] = ro.drawn_touches(motion.touches, fates)
        one = len(fates.fates) == 1   # the regions' labels name the body when there are several
        self.mark_rgb = mark_colours(model, fates)
        self.tags = ro.name_tags(model, fates, self.mark_rgb)
        self.note = ro.not_drawn(model)   # what is not drawn (a flex): the readout's last line
        for i, f in enumerate(fates.fates):
            rgb = self.mark_rgb[i]
            for r in regions_of(f):
                vao, _ = self._vaos(sg.region_solid(r)[0])
                self.marks.append((vao, self._lines(sg.region_outline(r)), rgb))
            for k, r in enumerate(f.through):
                top = r.mid()   # the label over the region's top
                top[2] = top[2] + r.radius if r.center is not None else float(np.asarray(r.hi, float)[2])
                self.hoops.append((top, f"{k + 1}" if one else f"{f.body} {k + 1}", rgb))
            for t_at, r in f.at:
                self.hoops.append((r.mid(), f"t {t_at:g} s" if one else f"{f.body} t {t_at:g} s", rgb))
            if f.up is not None:
                b = int(mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, f.body))
                gs = [g for g in range(int(model.ngeom)) if int(model.geom_bodyid[g]) == b]
                reach = max((float(model.geom_rbound[g]) + float(np.linalg.norm(model.geom_pos[g])) for g in gs),
                            default=0.05)
                vao, _ = self._vaos(sg.arrow_solid(2.2 * reach, 0.05 * reach))
                self.arrows.append((b, np.asarray(f.up[0], float), vao, rgb))
        ids = {int(mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, f.body)) for f in fates.fates}
        rb = [float(model.geom_rbound[g]) for g in range(int(model.ngeom)) if int(model.geom_bodyid[g]) in ids]
        self.impact_vao, _ = self._vaos(sg.sphere_rows(0.3 * (min(rb) if rb else 0.02)))
        # the shadow map: an orthographic view from the light over the focus (and a margin)
        self.shadow_tex = ctx.depth_texture((SHADOW_PX, SHADOW_PX))
        self.shadow_tex.compare_func = "<="
        self.shadow_tex.filter = (moderngl.LINEAR, moderngl.LINEAR)
        self.shadow_tex.repeat_x = self.shadow_tex.repeat_y = False
        self.shadow_fbo = ctx.framebuffer(depth_attachment=self.shadow_tex)
        self._objs += [self.shadow_fbo, self.shadow_tex]
        R = 1.5 * span
        c = (self.lo + self.hi) / 2
        up = np.array([0.0, 1.0, 0.0]) if abs(self.light[2]) > 0.99 else np.array([0.0, 0.0, 1.0])
        self.light_vp = orthographic(-R, R, -R, R, 0.0, 8 * R) @ look_at(c + 4 * R * self.light, c, up)
        self.texel = 1.0 / SHADOW_PX
        self.offset = 2 * (2 * R / SHADOW_PX)
        # text: the readout in the frame's top left, as large as READOUT_FRAC of the frame where
        # its longest (final) lines fit; the framing camera frames the bodies beside or below it,
        # whichever leaves more room (also with ``clean``: the same view, with or without text)
        def fits(px: int, chars: int, rows_: int, wide: float) -> bool:
            return (chars + 2) * text_cell(px)[0] <= wide * w and (rows_ + 1) * text_cell(px)[1] <= 0.95 * h

        #: a frame where the whole readout at a legible size would cover more than READOUT_WIDE of its
        #: width gets the brief one (ro.readout)
        self.brief, self.brief_width = False, int(0.95 * w / text_cell(style.MIN_READOUT_PX)[0]) - 2
        for brief in (False, True):
            self.brief = brief
            chars, rows_ = ro.widest(title, fates, motion.judgement, motion.duration, brief=brief,
                                     width=self.brief_width if brief else None, note=self.note)
            px = max(style.MIN_READOUT_PX, int(round(READOUT_FRAC * min(self.size))))
            while px > style.MIN_READOUT_PX and not fits(px, chars, rows_, READOUT_WIDE):
                px -= 1
            if fits(px, chars, rows_, READOUT_WIDE):
                break
        cw, ch = text_cell(px)
        fw, fh = min((chars + 1.5) * cw / w, 0.6), min((rows_ + 1) * ch / h, 0.6)
        # the framing camera: beside the readout or below it, whichever shows the bodies larger
        # the framing camera tracks the bodies (nbst.render.scene.framing.tracking_boxes) from the side
        # that hides the fewest of them and their touches
        self.track = tracking_boxes(self.grid, fates, model) if self.cam < 0 else None
        self.azimuth = clear_azimuth(self.grid, fates, model, self.track) if self.track is not None else AZIMUTH
        best = None
        for free in ((-1 + 2 * fw, -1.0, 1.0, 1.0), (-1.0, -1 + 2 * fh, 1.0, 1.0)):
            eye, look, vpm = default_camera(points, w / h, free, self.azimuth)
            if best is None or abs(vpm[0, 0]) > abs(best[2][0, 0]):
                best = (eye, look, vpm)
                self.free = free
        assert best is not None
        self.eye, self.look, self.vpm = best
        self.text = self.small = None
        self.rect = None
        if not self.clean:
            self.text = Text(ctx, px)
            self.small = Text(ctx, max(style.MIN_LABEL_PX, int(round(0.019 * min(self.size)))))
            self.rect = Rect(ctx)
        self.target = FrameTarget(ctx, self.size, samples=style.MSAA_SAMPLES, depth=True)
        #: the boxes (x0, y0, x1, y1) px of the text drawn in the last frame
        self.overlay_boxes: list[tuple[float, float, float, float]] = []

    # ---------------------------------------------------------------- buffers

    def _vaos(self, rows: np.ndarray) -> tuple[Any, Any]:
        buf = self.ctx.buffer(np.ascontiguousarray(rows, dtype="f4").tobytes())
        vao = self.ctx.vertex_array(self.prog, [(buf, "3f 3f", "in_pos", "in_normal")])
        dvao = self.ctx.vertex_array(self.dprog, [(buf, "3f 12x", "in_pos")])
        self._objs += [vao, dvao, buf]
        return vao, dvao

    def _lines(self, pts: np.ndarray) -> Any:
        rows = np.concatenate([pts, np.tile([0.0, 0.0, 1.0], (len(pts), 1))], axis=1)
        vao, _ = self._vaos(rows)
        return vao

    # ---------------------------------------------------------------- cameras

    def view(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """(the view-projection (4, 4), the eye (3,)) of the frame at ``t``; image row 0 at the top."""
        w, h = self.size
        flip = np.diag([1.0, -1.0, 1.0, 1.0])
        if self.cam >= 0:
            k = self.motion.index(t)
            p, R = self.motion.cam_xpos[k, self.cam], self.motion.cam_xmat[k, self.cam]
            v = np.eye(4)
            v[:3, :3] = R.T
            v[:3, 3] = -R.T @ p
            fov = float(self.model.cam_fovy[self.cam])
            near = max(float(self.model.vis.map.znear) * float(self.model.stat.extent), 1e-3)
            return flip @ perspective(fov, w / h, near, 1e3 * near + 100.0 * self.span) @ v, p
        if self.track is not None:   # the boxes read between the grid's frames
            lo, hi = (np.array([np.interp(t, self.grid.times, b[:, i]) for i in range(3)]) for b in self.track)
            eye, _, vpm = default_camera(box_corners(lo, hi), w / h, self.free, self.azimuth)
            return vpm, eye
        return self.vpm, self.eye

    def to_pixel(self, vpm: np.ndarray, p: np.ndarray) -> tuple[float, float, bool]:
        """(column, row, in front of the camera) of the world point ``p``."""
        c = vpm @ np.r_[np.asarray(p, float)[:3], 1.0]
        w, h = self.size
        return (c[0] / c[3] + 1) / 2 * w, (c[1] / c[3] + 1) / 2 * h, bool(c[3] > 0)

    # ---------------------------------------------------------------- drawing

    @staticmethod
    def _pose(R: np.ndarray, p: np.ndarray) -> bytes:
        m = np.eye(4, dtype="f4")
        m[:3, :3], m[:3, 3] = R, p
        return m.T.copy().tobytes()

    def draw(self, t: float) -> None:
        mgl, ctx = self._mgl, self.ctx
        k = self.motion.index(t)
        gx, gm = self.motion.geom_xpos[k], self.motion.geom_xmat[k]
        bx, bm = self.motion.body_xpos[k], self.motion.body_xmat[k]
        t_now = float(self.motion.times[k])
        # the shadow map
        self.shadow_fbo.use()
        self.shadow_fbo.clear(depth=1.0)
        ctx.enable(mgl.DEPTH_TEST)
        ctx.disable(mgl.BLEND)
        self.dprog["u_light_vp"].write(self.light_vp.T.astype("f4").tobytes())
        for g, _, dvao, rgba, plane in self.items:
            if not plane and rgba[3] >= 1.0:
                self.dprog["u_model"].write(self._pose(gm[g], gx[g]))
                dvao.render(mgl.TRIANGLES)
        # the scene
        fbo = self.target.draw_fbo
        fbo.use()
        fbo.clear(*SKY, 1.0, depth=1.0)
        vpm, eye = self.view(t)
        P = self.prog
        P["u_vp"].write(vpm.T.astype("f4").tobytes())
        P["u_light_vp"].write(self.light_vp.T.astype("f4").tobytes())
        P["u_light"].value = tuple(float(c) for c in self.light)
        P["u_eye"].value = tuple(float(c) for c in eye)
        P["u_offset"].value = float(self.offset)
        P["u_texel"].value = float(self.texel)
        P["u_lit"].value = 1.0
        self.shadow_tex.use(0)
        P["u_shadow"].value = 0
        for g, vao, _, rgba, plane in self.items:
            if rgba[3] >= 1.0:
                self._solid(vao, gm[g], gx[g], rgba, checker=self.checker if plane else 0.0)
        if self.tendon_vao is not None:   # each segment between two wrap points, as MuJoCo's viewer
            for (a, b), (i, w) in zip(self.motion.tendon_segs[k], self.motion.tendon_slots):
                if np.isfinite(a[0]) and np.linalg.norm(b - a) > 0:
                    self._solid(self.tendon_vao, _stretch(a, b, w), a, tuple(self.model.tendon_rgba[i]))
        for b, axis, vao, rgb in self.arrows:   # an up-axis: along the body-frame axis
            z = bm[b] @ axis   # a unit vector: a rotation of the unit axis
            self._solid(vao, _stretch(np.zeros(3), z / np.linalg.norm(z), 1.0), bx[b], (*rgb, 1.0))
        for im in self.impacts:
            if im.t <= t_now:
                self._solid(self.impact_vao, np.eye(3), np.asarray(im.pos), (*IMPACT, 1.0))
        # the translucent: geoms, regions, then the outlines
        ctx.enable(mgl.BLEND)
        ctx.blend_func = mgl.ONE, mgl.ONE_MINUS_SRC_ALPHA
        fbo.depth_mask = False
        for g, vao, _, rgba, plane in self.items:
            if rgba[3] < 1.0:
                self._solid(vao, gm[g], gx[g], rgba, checker=self.checker if plane else 0.0)
        for vao, _, rgb in self.marks:
            self._solid(vao, np.eye(3), np.zeros(3), (*rgb, REGION_ALPHA))
        P["u_lit"].value = 0.0
        for _, lines, rgb in self.marks:
            self._solid(lines, np.eye(3), np.zeros(3), (*rgb, OUTLINE_ALPHA), mode=mgl.LINES)
        fbo.depth_mask = True
        ctx.disable(mgl.DEPTH_TEST)
        self.overlay_boxes = []
        if not self.clean:
            self._overlay(t, t_now, vpm)
        ctx.disable(mgl.BLEND)

    def _solid(self, vao: Any, R: np.ndarray, p: np.ndarray, rgba, *, checker: float = 0.0, mode: Any = None) -> None:
        P = self.prog
        P["u_model"].write(self._pose(R, p))
        P["u_color"].value = tuple(float(c) for c in rgba)
        P["u_checker"].value = float(checker)
        vao.render(self._mgl.TRIANGLES if mode is None else mode)

    def readout(self, t: float) -> list[str]:  # type: ignore[override]  # the disks' readout counts insides
        final = t >= self.motion.duration - 1e-9
        return ro.readout(self.title, t, self.fates, self.motion.judgement, final=final, brief=self.brief,
                          width=self.brief_width if self.brief else None, note=self.note)

    def _overlay(self, t: float, t_now: float, vpm: np.ndarray) -> None:
        """The labels (hoops in order, ``at`` regions, impacts, tags: each where it leaves the readout
        and the labels before it clear, else left out; each inside the frame, cut to it where wider)
        and the readout over its panel, cut to the frame (``Text.fit``)."""
        assert self.text is not None and self.small is not None and self.rect is not None
        size = self.size
        scw, sch = self.small.cell
        tx = self.text
        cw, ch = tx.cell
        x0, y0 = 0.6 * cw, 0.4 * ch
        # cut to the frame (a small --size): a line too long ends in "..", the last row kept counts the rest
        # (in no more than the widest line's width: the panel never grows for it)
        lines = self.readout(min(t, self.motion.duration))
        wide = min(size[0] - x0 - 0.6 * cw, max(len(s) for s in lines) * cw)
        lines = tx.fit(lines, wide, size[1] - y0 - 0.3 * ch)
        box = (0.0, 0.0, x0 + (max((len(s) for s in lines), default=0) + 0.6) * cw, y0 + (len(lines) + 0.3) * ch)
        placed = [box]
        labels = [(c, lab, rgb, False) for c, lab, rgb in self.hoops]
        labels += [(np.asarray(im.pos), ro.touch_label(im), IMPACT, True) for im in self.impacts if im.t <= t_now]
        k = self.motion.index(t)
        labels += [(self.motion.body_xpos[k, b], name, rgb, False) for b, name, rgb in self.tags]
        for centre, label, rgb, impact in labels:
            col, row, front = self.to_pixel(vpm, centre)
            if not (front and 0 <= col < size[0] and 0 <= row < size[1]):
                continue
            label = next(iter(self.small.fit([label], size[0] - 4)), "")   # a frame too narrow: cut
            if not label.strip():
                continue
            wl = scw * len(label)
            spots = ([(col + 0.8 * scw, row + 0.2 * sch), (col + 0.8 * scw, row - 1.2 * sch),
                      (col - 0.8 * scw - wl, row + 0.2 * sch), (col - 0.8 * scw - wl, row - 1.2 * sch),
                      (col - wl / 2, row + 1.2 * sch), (col - wl / 2, row - 2.2 * sch)] if impact else
                     [(col - wl / 2, row - 1.4 * sch), (col + 0.8 * scw, row - 0.5 * sch),
                      (col - 0.8 * scw - wl, row - 0.5 * sch)])
            # clear of the readout and every label (else a row or more further up or down; else left out:
            # a crowded small frame never writes one label over another), its halo inside the frame
            far = spots + [(x, y + j * sch) for j in (-1.2, 1.2, -2.4, 2.4, -3.6, 3.6) for x, y in spots[:3]]
            at = [(float(np.clip(x, 2, max(2, size[0] - wl - 2))), float(np.clip(y, 2, max(2, size[1] - sch - 2))))
                  for x, y in far]
            boxes = [(x - 1, y - 1, x + wl + 1, y + sch + 1) for x, y in at]
            bx = next((b for b in boxes if not any(b[0] < q[2] and q[0] < b[2] and b[1] < q[3] and q[1] < b[3]
                                                   for q in placed)), None)
            if bx is not None:
                self._label(label, bx[0] + 1, bx[1] + 1, rgb)
                placed.append(bx)
                self.overlay_boxes.append(bx)
        self.rect.draw(size, box, fill=PANEL_RGBA, rim=PANEL_RGBA, stroke=0.0)
        self.overlay_boxes.append(box)
        plain, oks, nos = ro.marks(lines)
        owner = ro.body_rows(lines, self.fates)
        tx.draw(size, tx.layout([" " * n + s[n:] for s, (_, n) in zip(plain, owner)], x0, y0), style.TEXT)
        for j, (i, n) in enumerate(owner):   # each body's name in its mark colour
            if i >= 0:
                tx.draw(size, tx.layout([plain[j][:n]], x0, y0 + j * ch), legible(self.mark_rgb[i]))
        tx.draw(size, tx.layout(oks, x0, y0), OK_RGB)
        tx.draw(size, tx.layout(nos, x0, y0), NO_RGB)

    def _label(self, text: str, x: float, y: float, colour) -> None:
        sm = self.small
        assert sm is not None
        sm.draw_halo(self.size, sm.layout([text], x, y), colour, style.TEXT_HALO)

    def release(self) -> None:
        for o in self._objs:
            o.release()
        for t in (self.text, self.small, self.rect):
            if t is not None:
                t.release()
        self.target.release()


def render_scene(path: str | os.PathLike, output: str | os.PathLike, *, still: float | None = None,
                 camera: str | None = None, clean: bool = False, size=None, fps: float | None = None,
                 speed: float = 1.0, hold: float = 1.0, progress=None) -> int:
    """Render a scene solution's motion to ``output`` (.mp4/.gif, or a .png at time ``still``).

    Args:
        path: the scene solution file (``nbst scene solve -o``).
        output: the .mp4, .gif or .png to write.
        still: None for a video; seconds: the one frame of a PNG (clipped to the motion).
        camera: a model camera's name; None: the camera that frames the bodies.
        clean: no overlay text.
        size, fps: (width, height) px and frames per second (default 1280 x 720, 60).
        speed: simulated seconds per second of video.
        hold: seconds of video holding the last frame.
        progress: None, or an object whose ``update(1)`` is called after each frame.

    Returns:
        The number of frames written (1 for a still).

    Raises:
        SceneSolutionError, FatesError: the solution, its fates or its scene is refused (one line).
        InputError: no camera of that name.
        RenderError: no GL context, an extension other than .mp4/.gif/.png, or the encoder failed.
    """
    from nbst.render.scene.motion import load_solution_scene

    doc, fates, model = load_solution_scene(path)
    if camera is not None and camera not in camera_names(model):
        have = ", ".join(camera_names(model)) or "none"
        raise InputError(f"camera {camera!r}: the scene has no camera of that name (its cameras: {have})")
    duration = int(doc["nstep"]) * float(doc["timestep"])
    fps_ = float(fps or style.DEFAULT_FPS)
    times = (np.array([min(max(float(still), 0.0), duration)]) if still is not None
             else frame_times(duration, fps_, speed=speed, hold=hold))
    # the framing camera's own frames recorded too (a still: the whole motion): it frames the same paths
    motion, fates, model = record(path, np.union1d(times, track_grid(duration)))
    size = tuple(size or style.DEFAULT_SIZE)
    title = fates.scene.name  # the MJCF's file name (its stem may be a body's name)
    return render_output(lambda ctx: SceneRenderer(ctx, motion, fates, model, size=size, camera=camera, clean=clean,
                                                   title=title),
                         output, still=None if still is None else float(times[0]),
                         times=lambda r, f: times, fps=fps_, progress=progress)
