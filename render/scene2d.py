"""The 2D view: the box from above, disks, targets, lit target rings, trails, a
time readout and a legend (marks and colours: :mod:`nbst.palette`).
``Renderer2D.render(t)`` returns one frame, (H, W, 3) uint8.

Motions: anything with ``at(t) -> (N, 2)``. An exact :class:`nbst.sim.Trajectory`
gives exact positions at every frame and exact trail corners (its keyframes);
:class:`SampledMotion` wraps positions known only at sample times (a MuJoCo
rollout) and interpolates linearly between them.
"""
from __future__ import annotations

import numpy as np

from nbst import palette

from nbst.render import style
from nbst.render.gl import FrameRenderer, FrameTarget
from nbst.render.shapes import CAPSULE_DTYPE, CIRCLE_DTYPE, Capsules, Circles, Rect, Text


class SampledMotion:
    """Positions known at sample times: times (T,) increasing, positions (T, N, 2).

    ``at(t)`` is exact at the sample times and linear in between.
    """

    def __init__(self, times, positions):
        self.times = np.asarray(times, float)
        self.positions = np.asarray(positions, float)
        if self.positions.ndim != 3 or self.positions.shape[0] != self.times.shape[0]:
            raise ValueError("positions must have shape (T, N, 2) matching times (T,)")

    def at(self, t):
        ts = np.asarray(t, float)
        k = np.clip(np.searchsorted(self.times, ts, side="right") - 1, 0, len(self.times) - 1)
        k1 = np.minimum(k + 1, len(self.times) - 1)
        span = self.times[k1] - self.times[k]
        w = np.where(span > 0, (ts - self.times[k]) / np.where(span > 0, span, 1.0), 0.0)
        w = np.clip(w, 0.0, 1.0)[..., None, None]
        return self.positions[k] * (1 - w) + self.positions[k1] * w


class Layout:
    """World (problem units, y up) to image pixels (x right, y down): the box fitted
    into the frame with a margin, centred.

    scale : px per unit; origin : image position of world (0, H).
    """

    def __init__(self, box, size, *, keep_left: float = 0.0):
        """keep_left: px at the left that the box must leave free (the time readout); the
        box stays centred if the centred box leaves them free, else it moves right (and
        shrinks if it must)."""
        W, H = float(box[0]), float(box[1])
        fw, fh = size
        short = min(fw, fh)
        self.margin = style.MARGIN_FRAC * short
        self.wall = max(1.5, style.BOX_WALL_FRAC * short)
        inner = self.margin + self.wall
        self.scale = min((fw - 2 * inner) / W, (fh - 2 * inner) / H)
        self.x0 = 0.5 * (fw - W * self.scale)
        if keep_left > 0 and self.x0 - self.wall < keep_left:
            self.scale = min((fw - keep_left - self.wall - inner) / W, (fh - 2 * inner) / H)
            # on a whole pixel, as the centred box (thin walls stay crisp through video encoding)
            self.x0 = float(round(keep_left + self.wall + 0.5 * (fw - keep_left - self.wall - inner - W * self.scale)))
        self.box = (W, H)
        self.size = (fw, fh)
        self.y0 = 0.5 * (fh - H * self.scale)

    def to_image(self, xy) -> np.ndarray:
        """(..., 2) world points -> (..., 2) image px (x, y down); pixel (c, r) covers [c, c+1) x [r, r+1)."""
        xy = np.asarray(xy, float)
        out = np.empty(xy.shape, float)
        out[..., 0] = self.x0 + xy[..., 0] * self.scale
        out[..., 1] = self.y0 + (self.box[1] - xy[..., 1]) * self.scale
        return out

    @property
    def box_rect(self) -> tuple[float, float, float, float]:
        """The box interior in image px: x0, y0, x1, y1."""
        W, H = self.box
        return (self.x0, self.y0, self.x0 + W * self.scale, self.y0 + H * self.scale)


def trail_points(motion, t: float, seconds: float):
    """The path of every disk over [max(0, t - seconds), t]: points (M, N, 2), times (M,).

    For a Trajectory the points are its keyframes inside the window plus both
    ends, so the polyline is the exact path (straight between events). Otherwise,
    or when the window holds more than MAX_TRAIL_POINTS keyframes, uniform samples.
    """
    t0 = max(0.0, t - seconds)
    kt = getattr(motion, "times", None)
    kp = getattr(motion, "positions", None)
    if kt is not None and kp is not None and hasattr(motion, "velocities"):
        lo = int(np.searchsorted(kt, t0, side="right"))
        hi = int(np.searchsorted(kt, t, side="left"))
        if hi - lo <= style.MAX_TRAIL_POINTS:
            times = np.concatenate(([t0], kt[lo:hi], [t]))
            pts = np.concatenate((motion.at(t0)[None], kp[lo:hi], motion.at(t)[None]))
            return pts, times
    times = np.linspace(t0, t, min(style.MAX_TRAIL_POINTS, 64) + 1)
    return np.asarray(motion.at(times)), times


def trail_capsules(motion, t: float, half, colors, *, to_view=None, min_step: float) -> np.ndarray:
    """The trails at time ``t`` as capsule instances (CAPSULE_DTYPE): one per step of every
    disk's path over the last TRAIL_SECONDS (``trail_points``), mapped by ``to_view`` (default:
    world units kept), alpha fading with age; steps shorter than ``min_step`` (disks at rest)
    are left out. ``half`` and ``colors``: per-disk half width and colour."""
    pts, times = trail_points(motion, t, style.TRAIL_SECONDS)
    if to_view is not None:
        pts = to_view(pts)  # (M, N, 2)
    age = np.clip(1.0 - (t - times) / style.TRAIL_SECONDS, 0.0, 1.0) * style.TRAIL_ALPHA  # (M,)
    a, b = pts[:-1], pts[1:]
    m_idx, n_idx = np.nonzero(((b - a) ** 2).sum(axis=2) > min_step * min_step)
    data = np.empty(len(m_idx), CAPSULE_DTYPE)
    data["p0"] = a[m_idx, n_idx]
    data["p1"] = b[m_idx, n_idx]
    data["alpha"][:, 0] = age[m_idx]
    data["alpha"][:, 1] = age[m_idx + 1]
    data["half"] = half[n_idx]
    data["color"] = colors[n_idx]
    return data


class Labels:
    """Disk indices written on the disks (dark digits, centred), sized to the disks."""

    def __init__(self, ctx, problem, rpx):
        px = int(np.clip(np.median(rpx) * style.LABEL_FRAC, style.MIN_LABEL_PX, style.MAX_LABEL_PX))
        self.text = Text(ctx, px)
        self.strings = [str(i) for i in range(problem.n)]
        self.visible = np.asarray(rpx) >= style.MIN_LABEL_DISK_PX

    def draw(self, size, centers_px) -> None:
        cw, ch = self.text.cell
        parts = [self.text.layout([s], c[0] - 0.5 * cw * len(s), c[1] - 0.5 * ch)
                 for s, c, v in zip(self.strings, centers_px, self.visible) if v]
        if parts:
            self.text.draw(size, np.concatenate(parts), style.LABEL)

    def release(self) -> None:
        self.text.release()


def target_label_px(size) -> int:
    """Text height of the target numbers for a frame of ``size``."""
    return int(np.clip(round(style.TARGET_LABEL_FRAC * min(size)), style.MIN_TARGET_LABEL_PX,
                       style.MAX_TARGET_LABEL_PX))


def target_label_instances(text, centers_px, marker_px) -> np.ndarray:
    """Text instances numbering each target with its disk's index, just above and
    right of its marker (centres (N, 2) px, marker radii (N,) px)."""
    cw, ch = text.cell
    centers_px = np.asarray(centers_px, float)
    marker_px = np.broadcast_to(np.asarray(marker_px, float), (len(centers_px),))
    parts = [text.layout([str(i)], c[0] + 0.75 * m + 1.0, c[1] - 0.75 * m - 0.8 * ch)
             for i, (c, m) in enumerate(zip(centers_px, marker_px))]
    return np.concatenate(parts) if parts else text.layout([], 0, 0)


def legend_entries(problem, *, ghost: bool, labels: bool, long: bool = True) -> list[tuple]:
    """The legend's lines as (words, swatch kind, colour): a filled disk per class
    present, the hollow target mark (saying that its number names its disk when
    targets are numbered), the MuJoCo ring when one is drawn. ``long=False``: the
    short words, for narrow margins."""
    out = []
    if problem.cueable.any():
        out.append((palette.LEGEND_CUEABLE, "disk", style.CUEABLE))
    if (~problem.cueable).any():
        out.append((palette.LEGEND_NONCUEABLE, "disk", style.NONCUEABLE))
    out.append((palette.LEGEND_TARGET if labels and long else "target", "target", None))
    if ghost:
        out.append(("MuJoCo" + (" (ring)" if long else ""), "ghost", None))
    return out


def draw_legend(circles, text, size, x: float, y: float, max_w: float, max_h: float, entries_for) -> bool:
    """Draw the legend with its top-left at (x, y) px if it fits in max_w x max_h px:
    ``entries_for(long)`` gives the lines (:func:`legend_entries`); the long words
    are tried first, then the short. Returns whether a legend was drawn."""
    cw, ch = text.cell
    pitch = style.LEGEND_PITCH * ch
    for long in (True, False):
        entries = entries_for(long)
        w = 1.6 * ch + max(len(e[0]) for e in entries) * cw
        if w <= max_w and len(entries) * pitch <= max_h:
            break
    else:
        return False
    dots = np.zeros(len(entries), CIRCLE_DTYPE)
    texts = []
    for k, (words, kind, col) in enumerate(entries):
        cy = y + k * pitch
        d = dots[k]
        d["center"] = (x + 0.6 * ch, cy + 0.5 * ch)
        if kind == "disk":
            d["radius"] = 0.45 * ch
            d["stroke"] = max(1.0, style.DISK_RIM_FRAC * 0.45 * ch)
            d["fill"] = (*col, 1.0)
            d["rim"] = (*(np.array(col) * style.DISK_RIM_SHADE), 1.0)
        elif kind == "target":
            d["radius"] = max(style.MIN_MARKER_PX, 0.22 * ch)
            d["stroke"] = 1.5
            d["rim"] = style.MARKER
        else:
            d["radius"] = 0.45 * ch
            d["stroke"] = style.GHOST_PX
            d["rim"] = style.GHOST
        texts.append(text.layout([words], x + 1.6 * ch, cy))
    circles.draw(dots)
    text.draw(size, np.concatenate(texts), style.TEXT_DIM)
    return True


class Renderer2D(FrameRenderer):
    """Renders ``motion`` of ``problem`` at any time to an (H, W, 3) uint8 frame.

    ctx     : a moderngl context (see :func:`nbst.render.gl.create_context`)
    motion  : the disks' motion, ``at(t) -> (N, 2)`` (a Trajectory, or SampledMotion)
    ghost   : optional second motion drawn as rings on top (MuJoCo replay)
    trails  : draw the last TRAIL_SECONDS of every path, fading with age
    labels  : write each disk's index on it (as in ``nbst simulate``'s table) and
              beside each target the index of the disk it belongs to
    """

    def __init__(self, ctx, problem, motion, *, size=style.DEFAULT_SIZE, trails: bool = False, ghost=None,
                 labels: bool = False, title: str | None = None):
        import moderngl

        self.ctx, self.problem, self.motion, self.ghost = ctx, problem, motion, ghost
        self.trails = bool(trails)
        self.target = FrameTarget(ctx, size)
        self.size = self.target.size
        self.title = problem.name if title is None else title
        text_px = max(8, int(round(style.TEXT_FRAC * min(self.size))))
        self.text = Text(ctx, text_px)
        self.layout = L = Layout(problem.box, self.size)
        # the readout lives in the left margin: smaller type where its longest line would reach the box
        free = L.box_rect[0] - L.wall - L.margin  # half a margin of padding on each side
        need = max(len(s) for s in self.readout(0.0, np.zeros(problem.n, bool))) * self.text.cell[0]
        if need > free and text_px > 8:
            self.text.release()
            self.text = Text(ctx, max(8, int(text_px * free / need)))
        self._mgl = moderngl
        self.circles = Circles(ctx)
        self.capsules = Capsules(ctx)
        self.rect = Rect(ctx)
        for prog in (self.circles, self.capsules):
            prog.set_view(self.size)
        self.capsules.prog["u_floor"].value = style.BOX_FLOOR

        n = problem.n
        s = L.scale
        self.colors = np.array(style.disk_colors(problem.cueable), "f4")
        self.rpx = np.maximum(problem.radius * s, style.MIN_DISK_PX).astype("f4")
        self.target_px = L.to_image(problem.target).astype("f4")
        self.R_px = float(problem.target_radius * s)
        # per-frame instance arrays, allocated once
        self._disks = np.zeros(n, CIRCLE_DTYPE)
        self._disks["radius"] = self.rpx
        self._disks["stroke"] = np.maximum(1.0, style.DISK_RIM_FRAC * self.rpx)
        self._disks["fill"][:, :3] = self.colors
        self._disks["fill"][:, 3] = 1.0
        self._disks["rim"][:, :3] = self.colors * style.DISK_RIM_SHADE
        self._disks["rim"][:, 3] = 1.0
        self._lit = np.zeros(n, CIRCLE_DTYPE)
        self._lit["center"] = self.target_px
        self._lit["radius"] = self.R_px
        self._lit["stroke"] = style.RING_LIT_PX
        self._lit["fill"][:, :3] = self.colors
        self._lit["fill"][:, 3] = style.RING_LIT_FILL_ALPHA
        self._lit["rim"][:, :3] = self.colors
        self._lit["rim"][:, 3] = style.RING_LIT_ALPHA
        self._ghosts = np.zeros(n, CIRCLE_DTYPE)
        self._ghosts["radius"] = self.rpx
        self._ghosts["stroke"] = style.GHOST_PX
        self._ghosts["rim"] = style.GHOST
        self.trail_half = np.maximum(style.MIN_TRAIL_PX, style.TRAIL_WIDTH_FRAC * self.rpx).astype("f4") * 0.5
        self.labels = Labels(ctx, problem, self.rpx) if labels else None
        self.marker_px = np.maximum(style.MARKER_FRAC * self.rpx, style.MIN_MARKER_PX)
        self.legend_text = Text(ctx, max(8, int(round(style.LEGEND_TEXT_FRAC * min(self.size)))))
        self.target_text = Text(ctx, target_label_px(self.size)) if labels else None
        self.static = FrameTarget(ctx, self.size)
        self._draw_static()

    # ------------------------------------------------------------------ static layer

    def _readout_origin(self) -> tuple[float, float]:
        L = self.layout
        pad = L.margin * 0.5
        return (pad, pad)

    def _draw_static(self) -> None:
        """Background, box, dim target rings, target markers (numbered with --labels)
        and the legend: drawn once."""
        ctx, mgl, L, p = self.ctx, self._mgl, self.layout, self.problem
        self.static.fbo.use()
        ctx.viewport = (0, 0, *self.size)
        self.static.fbo.clear(*style.BACKGROUND, 1.0)
        ctx.enable(mgl.BLEND)
        ctx.blend_func = mgl.ONE, mgl.ONE_MINUS_SRC_ALPHA
        ctx.blend_equation = mgl.FUNC_ADD
        x0, y0, x1, y1 = L.box_rect
        w = L.wall
        self.rect.draw(self.size, (x0 - w, y0 - w, x1 + w, y1 + w), fill=style.BOX_FLOOR, rim=style.BOX_WALL,
                       stroke=w)
        n = p.n
        rings = np.zeros(n, CIRCLE_DTYPE)
        rings["center"] = self.target_px
        rings["radius"] = self.R_px
        rings["stroke"] = style.RING_DIM_PX
        rings["rim"] = style.RING_DIM
        markers = np.zeros(n, CIRCLE_DTYPE)
        markers["center"] = self.target_px
        markers["radius"] = self.marker_px
        markers["stroke"] = 1.5
        markers["rim"] = style.MARKER
        self.circles.draw(rings)
        self.circles.draw(markers)
        if self.target_text is not None:
            self.target_text.draw(self.size, target_label_instances(self.target_text, self.target_px,
                                                                    self.marker_px), style.TARGET_LABEL)
        self._draw_legend()

    def _draw_legend(self) -> None:
        """Legend under the readout, in the left margin, when the margin is wide enough."""
        L = self.layout
        x, y = self._readout_origin()
        y += (len(self.readout(0.0, np.zeros(self.problem.n, bool))) + 0.6) * self.text.cell[1]  # below the readout
        max_w = L.box_rect[0] - L.wall - 0.5 * L.margin - x
        max_h = self.size[1] - 0.5 * L.margin - y
        self.legend_drawn = draw_legend(
            self.circles, self.legend_text, self.size, x, y, max_w, max_h,
            lambda long: legend_entries(self.problem, ghost=self.ghost is not None,
                                        labels=self.target_text is not None, long=long))

    # ------------------------------------------------------------------ frames

    def to_pixels(self, xy) -> np.ndarray:
        """World points -> image px (x = column, y = row, fractional)."""
        return self.layout.to_image(xy)

    def draw(self, t: float) -> None:
        """Draw the frame at time ``t`` into the frame target (no readback)."""
        ctx, mgl, p = self.ctx, self._mgl, self.problem
        t = float(min(max(t, 0.0), p.t_final))
        pos = np.asarray(self.motion.at(t), float)
        fbo = self.target.fbo
        ctx.copy_framebuffer(fbo, self.static.fbo)
        fbo.use()
        ctx.viewport = (0, 0, *self.size)
        ctx.enable(mgl.BLEND)
        if self.trails and t > 0:
            ctx.blend_equation = mgl.MAX
            self.capsules.draw(self._trail_instances(t))
        ctx.blend_func = mgl.ONE, mgl.ONE_MINUS_SRC_ALPHA
        ctx.blend_equation = mgl.FUNC_ADD
        inside = ((pos - p.target) ** 2).sum(axis=1) <= p.target_radius ** 2
        if inside.any():
            self.circles.draw(self._lit[inside])
        self._disks["center"] = self.layout.to_image(pos)
        self.circles.draw(self._disks)
        if self.ghost is not None:
            self._ghosts["center"] = self.layout.to_image(np.asarray(self.ghost.at(t), float))
            self.circles.draw(self._ghosts)
        if self.labels is not None:
            self.labels.draw(self.size, self._disks["center"])
        x, y = self._readout_origin()
        self.text.draw(self.size, self.text.layout(self.readout(t, inside), x, y), style.TEXT)

    def _trail_instances(self, t: float) -> np.ndarray:
        return trail_capsules(self.motion, t, self.trail_half, self.colors, to_view=self.layout.to_image,
                              min_step=1e-3)  # px

    def release(self) -> None:
        for o in (self.circles, self.capsules, self.rect, self.text, self.target, self.static, self.labels,
                  self.legend_text, self.target_text):
            if o is not None:
                o.release()
