"""The 3D view (``--view 3d``): pucks as cylinders on a table inside rails, seen
by a perspective camera, lit by one directional light; target rings lie on the
felt, lit in the puck's colour while it is inside; target markers (and, with
labels, their numbers) are drawn over everything, as in 2D, so no puck hides one.
With ``labels``, pucks carry their index and each target its disk's index, as in
the 2D view; a legend sits under the readout when there is room left of the table.

Meshes come from trimesh (cylinder, box, annulus) and are drawn instanced by one
Blinn-Phong program. ``Renderer3D.render(t)`` returns one frame, (H, W, 3) uint8,
antialiased by MSAA. World axes: x, y the problem's (units), z up, table top z = 0.
"""
from __future__ import annotations

import math

import numpy as np

from nbst.render.core import style
from nbst.render.core.camera import look_at, mesh_arrays, perspective
from nbst.render.core.gl import FrameRenderer, FrameTarget
from nbst.render.motion2d import trail_capsules
from nbst.render.scene2d import (Labels, covered_by_own_disk, draw_legend, ghost_label_instances, legend_entries,
                                 target_label_instances, target_label_px)
from nbst.render.core.shapes import CAPSULE_DTYPE, CAPSULE_FS_IO, CAPSULE_VS_IO, CIRCLE_DTYPE, Circles, Text, _Instanced

__all__ = ["INST_DTYPE", "MESH_FS", "MESH_VS", "TRAIL_FS", "TRAIL_VS", "TRAIL_Z", "Renderer3D"]

MESH_VS = """#version 330
uniform mat4 u_mvp;
in vec3 in_pos;
in vec3 in_normal;
in vec3 in_offset;
in vec3 in_scale;
in vec3 in_color;
out vec3 v_normal;
out vec3 v_world;
flat out vec3 v_color;
void main() {
    vec3 w = in_pos * in_scale + in_offset;
    v_world = w;
    v_normal = in_normal / in_scale;  // inverse-transpose of an axis-aligned scale
    v_color = in_color;
    gl_Position = u_mvp * vec4(w, 1.0);
}
"""

MESH_FS = """#version 330
uniform vec3 u_light;   // unit vector towards the light
uniform vec3 u_eye;
uniform float u_ambient;
in vec3 v_normal;
in vec3 v_world;
flat in vec3 v_color;
out vec4 f_color;
void main() {
    vec3 n = normalize(v_normal);
    vec3 v = normalize(u_eye - v_world);
    if (dot(n, v) < 0.0) n = -n;  // two-sided (culling is off: the projection flips winding)
    float diff = max(dot(n, u_light), 0.0);
    vec3 h = normalize(u_light + v);
    float spec = pow(max(dot(n, h), 0.0), 48.0) * 0.35;
    f_color = vec4(v_color * (u_ambient + (1.0 - u_ambient) * diff) + vec3(spec), 1.0);
}
"""

# Trails lie on the felt as capsules in world units, blended with MAX against the
# felt's own lit colour (computed here, per fragment, by the same lighting), so
# overlapping segments never add up into beads at the joints.
TRAIL_VS = "#version 330\nuniform mat4 u_mvp;\nuniform float u_z;" + CAPSULE_VS_IO + """
void main() {
    v_pos = capsule_corner(in_corner, in_p0, in_p1, in_half * 1.6 + 1.0);  // world units, with room for fwidth
    capsule_out();
    gl_Position = u_mvp * vec4(v_pos, u_z, 1.0);
}
"""

TRAIL_FS = """#version 330
uniform vec3 u_light;
uniform vec3 u_eye;
uniform float u_ambient;
uniform float u_z;
uniform vec3 u_felt;""" + CAPSULE_FS_IO + """
vec3 shade(vec3 c, vec3 w) {
    vec3 n = vec3(0.0, 0.0, 1.0), v = normalize(u_eye - w);
    float diff = max(dot(n, u_light), 0.0);
    float spec = pow(max(dot(n, normalize(u_light + v)), 0.0), 48.0) * 0.35;
    return c * (u_ambient + (1.0 - u_ambient) * diff) + vec3(spec);
}
void main() {
    float h;
    float d = segment_distance(v_pos, v_p0, v_p1, h) - v_half;  // world units
    float px = max(fwidth(d), 1e-6);                 // world units per pixel here
    float a = mix(v_alpha.x, v_alpha.y, h) * clamp(0.5 - d / px, 0.0, 1.0);
    if (a <= 0.0) discard;
    vec3 w = vec3(v_pos, u_z);
    f_color = vec4(mix(shade(u_felt, w), shade(v_color, w), a), 1.0);
}
"""

#: Height of the trails above the felt: over the dim rings and markers (tops at 0.6
#: and 1.0), under the lit rings (top 1.1) and the pucks.
TRAIL_Z = 1.05

INST_DTYPE = np.dtype([("offset", "f4", 3), ("scale", "f4", 3), ("color", "f4", 3)])


class Renderer3D(FrameRenderer):
    """Renders ``motion`` of ``problem`` in 3D at any time: (H, W, 3) uint8 frames.

    Same interface as :class:`nbst.render.scene2d.Renderer2D`; trails lie on the felt.
    """

    def __init__(self, ctx, problem, motion, *, size=style.DEFAULT_SIZE, trails: bool = False, ghost=None,
                 labels: bool = False, title: str | None = None, motion_name: str | None = None,
                 ghost_name: str | None = None, clean: bool = False):
        import moderngl
        import trimesh

        self.clean = bool(clean)   # no text: no readout, legend or numbers (``nbst render --clean``)
        self._show(ctx, problem, motion, ghost, trails=trails, motion_name=motion_name, ghost_name=ghost_name,
                   title=title)
        self._mgl = moderngl
        self.target = FrameTarget(ctx, size, samples=style.MSAA_SAMPLES, depth=True)
        self.size = self.target.size
        p = problem
        W, H = p.box
        short = min(W, H)
        self.rail_h = style.RAIL_HEIGHT_FRAC * short
        self.puck_h = style.PUCK_HEIGHT_FRAC * p.radius  # (N,)
        self.prog = ctx.program(vertex_shader=MESH_VS, fragment_shader=MESH_FS)
        self._setup_camera()
        self._vbos: list = []

        def mesh_vao(mesh, capacity):
            vbo = ctx.buffer(mesh_arrays(mesh).tobytes())
            inst = ctx.buffer(reserve=capacity * INST_DTYPE.itemsize, dynamic=True)
            vao = ctx.vertex_array(self.prog, [(vbo, "3f 3f", "in_pos", "in_normal"),
                                               (inst, "3f 3f 3f/i", "in_offset", "in_scale", "in_color")])
            self._vbos += [vao, vbo, inst]
            return vao, inst

        n = p.n
        self.cyl = mesh_vao(trimesh.creation.cylinder(radius=1.0, height=1.0, sections=48), 2 * n)
        self.cube = mesh_vao(trimesh.creation.box(extents=(1.0, 1.0, 1.0)), 8)
        R = p.target_radius
        ring_w = max(2.0, 0.02 * R)
        self.ring_dim = mesh_vao(trimesh.creation.annulus(r_min=R - ring_w, r_max=R, height=0.6, sections=96), n)
        self.ring_lit = mesh_vao(trimesh.creation.annulus(r_min=R - 2.5 * ring_w, r_max=R, height=1.0,
                                                          sections=96), n)
        self.marker = mesh_vao(trimesh.creation.annulus(r_min=0.55, r_max=1.0, height=1.0, sections=32), n)
        self.ghost_ring = mesh_vao(trimesh.creation.annulus(r_min=0.88, r_max=1.06, height=1.0, sections=48), n)

        self.colors = np.array(style.disk_colors(p.cueable), "f4")
        # static instances
        t = 0.04 * short  # table slab thickness
        rw = max(6.0, 0.02 * short)  # rail width
        cubes = np.zeros(5, INST_DTYPE)
        cubes[0] = ((W / 2, H / 2, -t / 2), (W + 2 * rw, H + 2 * rw, t), style.TABLE)
        rh = self.rail_h
        cubes[1] = ((-rw / 2, H / 2, rh / 2), (rw, H + 2 * rw, rh), style.RAIL)
        cubes[2] = ((W + rw / 2, H / 2, rh / 2), (rw, H + 2 * rw, rh), style.RAIL)
        cubes[3] = ((W / 2, -rw / 2, rh / 2), (W, rw, rh), style.RAIL)
        cubes[4] = ((W / 2, H + rw / 2, rh / 2), (W, rw, rh), style.RAIL)
        self._cubes = cubes
        felt = np.array(style.TABLE)
        self._rings = np.zeros(n, INST_DTYPE)
        self._rings["offset"][:, :2] = p.target
        self._rings["offset"][:, 2] = 0.3
        self._rings["scale"] = 1.0
        self._rings["color"] = felt + 0.30 * (np.array(style.RING_DIM[:3]) - felt)
        self._markers = np.zeros(n, INST_DTYPE)
        self._markers["offset"][:, :2] = p.target
        self._markers["offset"][:, 2] = 0.5
        mr = np.maximum(style.MARKER_FRAC * p.radius, 3.0)
        self._markers["scale"] = np.stack([mr, mr, np.ones(n)], axis=1)
        self._markers["color"] = style.MARKER[:3]
        self._lit = self._rings.copy()
        self._lit["offset"][:, 2] = 0.6
        self._lit["color"] = self.colors
        self._pucks = np.zeros(n, INST_DTYPE)
        self._pucks["scale"] = np.stack([p.radius, p.radius, self.puck_h], axis=1)
        self._pucks["color"] = self.colors
        self._ghosts = np.zeros(n, INST_DTYPE)
        self._ghosts["scale"] = np.stack([p.radius, p.radius, np.ones(n)], axis=1)
        self._ghosts["color"] = style.GHOST[:3]
        self.trail_prog = None
        if self.trails:
            self.trail = _Instanced(ctx, TRAIL_VS, TRAIL_FS, CAPSULE_DTYPE, "2f 2f 2f 1f 3f",
                                    ("in_p0", "in_p1", "in_alpha", "in_half", "in_color"), capacity=1024)
            self.trail_prog = tp = self.trail.prog
            tp["u_mvp"].write(self.mvp.T.astype("f4").tobytes())
            L = np.array(style.LIGHT_DIR, float)
            tp["u_light"].value = tuple(L / np.linalg.norm(L))
            tp["u_eye"].value = tuple(self.eye)
            tp["u_ambient"].value = style.AMBIENT
            tp["u_z"].value = TRAIL_Z
            tp["u_felt"].value = style.TABLE
            self.trail_half = np.maximum(0.5 * style.TRAIL_WIDTH_FRAC * p.radius, 1.0).astype("f4")
        self.static = FrameTarget(ctx, size, samples=style.MSAA_SAMPLES, depth=True)
        self._static_done = False
        self.labels = self.target_text = None
        self.rail_w = rw
        if labels:
            c = np.array([[W / 2, H / 2], [W / 2 + 1.0, H / 2]])
            px_per_unit = float(np.linalg.norm(np.diff(self.to_pixels(c, z=0.0), axis=0)))
            self.labels = Labels(ctx, p, p.radius * px_per_unit, self.colors)
            self.target_text = Text(ctx, target_label_px(self.size))
        self.text = Text(ctx, max(style.MIN_READOUT_PX, int(round(style.TEXT_FRAC * min(self.size)))))
        self.legend_text = Text(ctx, max(style.MIN_LEGEND_PX, int(round(style.LEGEND_TEXT_FRAC * min(self.size)))))
        self.circles = Circles(ctx)
        self.circles.set_view(self.size)
        # the target markers as an image-space overlay: a ring of the marker's projected radius
        # at the height of the pucks' top faces, so a puck resting on its target has its marker
        # concentric with its top (and its number); widened to ring that number, as in 2D
        self._target_centre_px = self.to_pixels(p.target, z=self.puck_h)
        edge = self.to_pixels(p.target + self._markers["scale"][:, :2] * (1.0, 0.0), z=self.puck_h)
        self._target_marker_px = np.maximum(np.linalg.norm(edge - self._target_centre_px, axis=1),
                                            style.MIN_MARKER_PX)
        if self.labels is not None and self.labels.on_disk.any():
            clear = float(self.labels.half_diag[self.labels.on_disk].max()) + style.MARKER_LABEL_GAP_PX
            self._target_marker_px = np.where(self.labels.on_disk, np.maximum(self._target_marker_px, clear),
                                              self._target_marker_px)
        h = style.MARKER_HALO_PX
        ov = np.zeros(2 * n, CIRCLE_DTYPE)
        ov["center"] = np.concatenate([self._target_centre_px, self._target_centre_px])
        ov["radius"][:n] = self._target_marker_px + h
        ov["stroke"][:n] = style.MARKER_PX + 2 * h
        ov["rim"][:n] = style.MARKER_HALO
        ov["radius"][n:] = self._target_marker_px
        ov["stroke"][n:] = style.MARKER_PX
        ov["rim"][n:] = style.MARKER
        self._marker_overlay = ov

    def _setup_camera(self) -> None:
        p = self.problem
        W, H = p.box
        fw, fh = self.size
        aspect = fw / fh
        el = math.radians(style.CAMERA_ELEVATION_DEG)
        centre = np.array([W / 2, H / 2 * 0.92, 0.0])
        # distance: fit the table's bounding sphere (with the rails) in the narrower field of view
        radius = 0.5 * math.hypot(W, H) * 1.02
        fov_y = math.radians(style.CAMERA_FOV_DEG)
        fov_x = 2 * math.atan(math.tan(fov_y / 2) * aspect)
        d = radius / math.sin(min(fov_x, fov_y) / 2) * 0.74
        self.eye = centre + d * np.array([0.0, -math.cos(el), math.sin(el)])
        view = look_at(self.eye, centre, np.array([0.0, 0.0, 1.0]))
        proj = perspective(style.CAMERA_FOV_DEG, aspect, d * 0.2, d * 3.0)
        flip = np.diag([1.0, -1.0, 1.0, 1.0])  # image row 0 (top) -> GL bottom row: read_into needs no flip
        self.mvp_unflipped = proj @ view
        self.mvp = flip @ self.mvp_unflipped
        self.prog["u_mvp"].write(self.mvp.T.astype("f4").tobytes())  # GL is column-major
        L = np.array(style.LIGHT_DIR, float)
        self.prog["u_light"].value = tuple(L / np.linalg.norm(L))
        self.prog["u_eye"].value = tuple(self.eye)
        self.prog["u_ambient"].value = style.AMBIENT

    def to_pixels(self, xy, z=None) -> np.ndarray:
        """World points (..., 2) on the pucks' top faces (or at height z) -> image px (column, row)."""
        xy = np.asarray(xy, float)
        if z is None:
            z = np.broadcast_to(self.puck_h, xy.shape[:-1]) if xy.shape[:-1] == self.puck_h.shape else 0.0
        pts = np.concatenate([xy, np.broadcast_to(np.asarray(z, float), xy.shape[:-1])[..., None],
                              np.ones(xy.shape[:-1] + (1,))], axis=-1)
        clip = pts @ self.mvp_unflipped.T
        ndc = clip[..., :3] / clip[..., 3:4]
        fw, fh = self.size
        return np.stack([(ndc[..., 0] + 1) / 2 * fw, (1 - ndc[..., 1]) / 2 * fh], axis=-1)

    def _draw(self, vao_inst, data) -> None:
        vao, inst = vao_inst
        if len(data):
            inst.write(np.ascontiguousarray(data).tobytes())
            vao.render(self._mgl.TRIANGLES, instances=len(data))

    def _draw_static(self) -> None:
        """Table, rails, dim rings and the legend: drawn once (the big table quad is
        most of the fill cost under MSAA), copied into each frame."""
        ctx, mgl = self.ctx, self._mgl
        fbo = self.static.draw_fbo
        fbo.use()
        ctx.viewport = (0, 0, *self.size)
        fbo.clear(*style.BACKGROUND, 1.0, depth=1.0)
        ctx.disable(mgl.BLEND | mgl.CULL_FACE)
        ctx.enable(mgl.DEPTH_TEST)
        self._draw(self.cube, self._cubes)
        self._draw(self.ring_dim, self._rings)  # (the target markers: an overlay on every frame, in draw)
        # overlays in image px, on the felt (pucks drawn later cover them): target numbers, legend
        ctx.disable(mgl.DEPTH_TEST)
        ctx.enable(mgl.BLEND)
        ctx.blend_func = mgl.ONE, mgl.ONE_MINUS_SRC_ALPHA
        ctx.blend_equation = mgl.FUNC_ADD
        self._draw_legend()
        ctx.disable(mgl.BLEND)
        self._static_done = True

    def _draw_legend(self) -> None:
        """Legend under the readout, left of the table, when there is room."""
        if self.clean:
            return
        p = self.problem
        W, H = p.box
        pad = style.MARGIN_FRAC * min(self.size) * 0.5
        zero = np.zeros(self.problem.n, bool)
        lines = len(self.readout(0.0, zero, zero if self.ghost is not None else None))
        x, y = pad, pad + (lines + 0.6) * self.text.cell[1]
        max_h = self.size[1] - pad - y
        # the table's left edge (outer side of the rail) in the image: a straight line from its far
        # corner to its near one; the legend must end left of it at the legend's lowest row
        rw = self.rail_w
        far, near = self.to_pixels(np.array([[-rw, H + rw], [-rw, -rw]]), z=self.rail_h)
        n_rows = 5
        y_low = y + n_rows * style.LEGEND_PITCH * self.legend_text.cell[1]
        s = np.clip((y_low - far[1]) / max(near[1] - far[1], 1e-9), 0.0, 1.0)
        edge_x = far[0] + s * (near[0] - far[0]) if y_low > far[1] else self.size[0]
        draw_legend(self.circles, self.legend_text, self.size, x, y, edge_x - pad - x, max_h,
                    lambda long: legend_entries(p, ghost=self.ghost is not None,
                                                labels=self.target_text is not None, long=long,
                                                ghost_name=self.ghost_name, motion_name=self.motion_name))

    def draw(self, t: float) -> None:
        """Draw the frame at time ``t`` into the frame target (no readback)."""
        ctx, mgl, p = self.ctx, self._mgl, self.problem
        t = float(min(max(t, 0.0), p.t_final))
        pos = np.asarray(self.motion.at(t), float)
        fbo = self.target.draw_fbo
        if not self._static_done:
            self._draw_static()
        # colour and depth of the static layer (the blit copies both), so the rails hide
        # pucks and trails behind them without being drawn again
        ctx.copy_framebuffer(fbo, self.static.draw_fbo)
        fbo.use()
        ctx.viewport = (0, 0, *self.size)
        ctx.disable(mgl.BLEND | mgl.CULL_FACE)
        ctx.enable(mgl.DEPTH_TEST)
        inside = ((pos - p.target) ** 2).sum(axis=1) <= p.target_radius ** 2
        self._draw(self.ring_lit, self._lit[inside])
        if self.trails and t > 0:
            # depth test on (the near rail hides trails), depth writes off: segments meet in one
            # plane, and a segment's anti-aliased fringe must not reject its neighbour there
            fbo.depth_mask = False
            fbo.use()
            ctx.enable(mgl.BLEND)
            ctx.blend_equation = mgl.MAX
            self.trail.draw(self._trail_instances(t))
            ctx.blend_equation = mgl.FUNC_ADD
            ctx.disable(mgl.BLEND)
            fbo.depth_mask = True
            fbo.use()
        self._pucks["offset"][:, :2] = pos
        self._pucks["offset"][:, 2] = self.puck_h / 2
        self._draw(self.cyl, self._pucks)
        ghost_inside = None
        if self.ghost is not None:
            g = np.asarray(self.ghost.at(t), float)
            ghost_inside = ((g - p.target) ** 2).sum(axis=1) <= p.target_radius ** 2
            self._ghosts["offset"][:, :2] = g
            self._ghosts["offset"][:, 2] = self.puck_h + 0.8
            self._draw(self.ghost_ring, self._ghosts)
        ctx.disable(mgl.DEPTH_TEST)
        ctx.enable(mgl.BLEND)
        ctx.blend_func = mgl.ONE, mgl.ONE_MINUS_SRC_ALPHA
        ctx.blend_equation = mgl.FUNC_ADD
        # target markers (and numbers) over everything, in a dark halo, as in 2D: a puck never hides one
        self.circles.draw(self._marker_overlay)
        pad = style.MARGIN_FRAC * min(self.size) * 0.5
        if self.labels is not None and self.target_text is not None:  # set together
            # no number in the readout's box (a small frame's readout lies over the table), as in 2D
            cw, ch = self.text.cell
            readout = (np.zeros((0, 4)) if self.clean else
                       np.array([[pad, pad, pad + self.readout_width() * cw,
                                  pad + len(self.readout(t, inside, ghost_inside)) * ch]]))
            tops = self.to_pixels(pos, z=self.puck_h)
            drawn = self.labels.drawn(tops, taken=readout)
            self.labels.draw(self.size, tops, drawn)
            numbers = target_label_instances(self.target_text, self._target_centre_px, self._target_marker_px,
                                             avoid=np.concatenate([self.labels.boxes(tops, drawn), readout]),
                                             skip=covered_by_own_disk(p, pos))
            self.target_text.draw_halo(self.size, numbers, style.TARGET_LABEL, style.TEXT_HALO)
            if self.ghost is not None:
                self.target_text.draw_halo(self.size, ghost_label_instances(
                    self.target_text, self.to_pixels(g, z=self.puck_h), self.labels.rpx, avoid=readout),
                    style.GHOST_LABEL, style.TEXT_HALO)
        if not self.clean:
            # in a halo: a small frame's readout lies over the table, its markers and pucks
            self.text.draw_halo(self.size, self.text.layout(self.readout(t, inside, ghost_inside), pad, pad), style.TEXT,
                                style.TEXT_HALO)

    def _trail_instances(self, t: float) -> np.ndarray:
        return trail_capsules(self.motion, t, self.trail_half, self.colors, min_step=np.sqrt(1e-9))  # world units

    def release(self) -> None:
        if self.trail_prog is not None:
            self.trail.release()
        for o in self._vbos:
            o.release()
        self.prog.release()
        self.text.release()
        self.legend_text.release()
        self.circles.release()
        if self.target_text is not None:
            self.target_text.release()
        self.target.release()
        self.static.release()
        if self.labels is not None:
            self.labels.release()
