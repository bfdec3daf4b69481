"""The 2D view: the box from above, disks, targets, lit target rings, trails, a
time readout and a legend (marks and colours: :mod:`nbst.palette`).
``Renderer2D.render(t)`` returns one frame, (H, W, 3) uint8.

Motions: anything with ``at(t) -> (N, 2)``. An exact :class:`nbst.sim.Trajectory`
gives exact positions at every frame and exact trail corners (its keyframes);
:class:`nbst.render.motion2d.SampledMotion` wraps positions known only at sample times (a
MuJoCo rollout); the trails are :mod:`nbst.render.motion2d`'s.

Length: past the house's ~500 on purpose: the 2D frame is one layout (box, readout,
legend, labels, targets) whose parts place themselves against each other, and the
many-disk rules (numbers only where legible, target rings around small disks) belong to
that layout.
"""
from __future__ import annotations

import numpy as np

from nbst import palette

from nbst.render.core import style
from nbst.render.core.gl import FrameRenderer, FrameTarget
from nbst.render.motion2d import trail_capsules
from nbst.render.core.shapes import CIRCLE_DTYPE, Capsules, Circles, Rect, Text, digit_height, text_cell

__all__ = ["Labels", "Layout", "Renderer2D", "auto_labels", "covered_by_own_disk", "draw_legend",
           "ghost_label_instances", "keep_apart", "labels_legible", "legend_entries", "marker_radii",
           "markers_outside", "overlaps", "target_label_boxes", "target_label_instances", "target_label_px"]


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
        self.wall = max(2.0, style.BOX_WALL_FRAC * short)  # 2 px at least: a 1-px wall blurs away in H.264
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


class Labels:
    """Disk indices (``--labels``), sized to the disks but never under MIN_LABEL_PX: dark
    digits centred on a disk where they fit inside it (LABEL_FIT), else beside the disk,
    upper left, in the disk's colour over a dark halo. ``on_disk`` says which is which."""

    def __init__(self, ctx, problem, rpx, colors=None):

        rpx = np.broadcast_to(np.asarray(rpx, float), (problem.n,))
        self.px = px = int(np.clip(np.median(rpx) * style.LABEL_FRAC, style.MIN_LABEL_PX, style.MAX_LABEL_PX))
        self.text = Text(ctx, px)
        self.runs = self.text.numbers(problem.n)
        #: px kept between two numbers: half a character, so two numbers side by side never read as one ("67")
        self.gap = 0.5 * self.text.cell[0]
        self.strings = self.runs.strings
        cw, ch = self.text.cell
        self.digit_px = digit_height(px)
        half_w = 0.5 * self.runs.width.astype(float)
        #: half-diagonal of each number's ink box (px): what a marker on the disk must clear
        self.half_diag = np.hypot(half_w, 0.5 * self.digit_px)
        self.on_disk = self.half_diag <= style.LABEL_FIT * rpx
        self.rpx = rpx
        self.colors = np.asarray(colors if colors is not None else style.disk_colors(problem.cueable), float)

    def instances(self, centers_px, which):
        """Text instances of the numbers of disks ``which`` (bool mask) at ``centers_px``:
        centred on the disk, or (beside) upper left of it."""
        x, y = self._origins(centers_px)
        return self.runs.layout(x, y, which)

    def _origins(self, centers_px):
        cw, ch = self.text.cell
        c = np.asarray(centers_px, float)
        w = self.runs.width
        d = 0.72 * self.rpx
        x = np.where(self.on_disk, c[:, 0] - 0.5 * w, c[:, 0] - d - w)
        y = np.where(self.on_disk, c[:, 1] - 0.5 * ch, c[:, 1] - d - 0.85 * ch)
        return x, y

    def _all_boxes(self, centers_px) -> np.ndarray:
        x, y = self._origins(centers_px)
        return np.stack([x, y, x + self.runs.width, y + self.text.cell[1]], axis=1)

    def drawn(self, centers_px, taken=None) -> np.ndarray:
        """Which numbers are drawn at ``centers_px``: each one written on its disk that covers no number
        drawn before it (disks do not overlap, but a number forced onto a disk narrower than it can
        reach the next one's), and each one beside its disk that covers no number drawn before it
        (lower disk numbers first): crowded disks never run their numbers together.
        ``taken``: boxes (M, 4) px (x0, y0, x1, y1) of other text (the readout) that no number
        covers, on its disk or beside it."""
        keep = self.on_disk.copy()
        boxes = self._all_boxes(centers_px)
        taken = np.asarray(taken if taken is not None else (), float).reshape(-1, 4)
        keep &= ~overlaps(boxes, taken)
        on = np.flatnonzero(keep)
        if on.size:   # a number wider than its disk (forced --labels on small disks) may reach the next one's
            keep[on] = keep_apart(boxes[on], taken=taken, gap=self.gap)
        beside = np.flatnonzero(~self.on_disk)
        if beside.size:
            keep[beside] = keep_apart(boxes[beside], taken=np.concatenate([boxes[keep], taken]), gap=self.gap)
        return keep

    def boxes(self, centers_px, drawn=None) -> np.ndarray:
        """(M, 4) px boxes (x0, y0, x1, y1) of the numbers drawn (for others to avoid)."""
        drawn = self.drawn(centers_px) if drawn is None else drawn
        return self._all_boxes(centers_px)[drawn]

    def draw(self, size, centers_px, drawn=None) -> None:
        drawn = self.drawn(centers_px) if drawn is None else drawn
        self.text.draw(size, self.instances(centers_px, self.on_disk & drawn), style.LABEL)
        beside = ~self.on_disk & drawn
        if beside.any():  # one draw per class colour
            for col in np.unique(self.colors[beside], axis=0):
                m = beside & (np.abs(self.colors - col).max(axis=1) < 1e-6)
                self.text.draw_halo(size, self.instances(centers_px, m), col, style.TEXT_HALO)

    def release(self) -> None:
        self.text.release()


def overlaps(boxes, taken, gap: float = 1.0) -> np.ndarray:
    """Which of ``boxes`` (M, 4) px (x0, y0, x1, y1) come within ``gap`` px of a box of ``taken`` (K, 4)."""
    b = np.asarray(boxes, float).reshape(-1, 1, 4)
    t = np.asarray(taken, float).reshape(1, -1, 4)
    return np.asarray(((b[..., 0] < t[..., 2] + gap) & (t[..., 0] < b[..., 2] + gap)
                       & (b[..., 1] < t[..., 3] + gap) & (t[..., 1] < b[..., 3] + gap)).any(axis=1), dtype=bool)


def keep_apart(boxes, taken=None, gap: float = 1.0) -> np.ndarray:
    """Which of ``boxes`` (M, 4) px (x0, y0, x1, y1) to draw so that no two drawn ones come within
    ``gap`` px of each other or of a box of ``taken``: greedy, in order (the first one wins). On a
    grid of cells as large as the largest box: each box looks at the few cells it covers."""
    boxes = np.asarray(boxes, float).reshape(-1, 4)
    keep = np.zeros(len(boxes), bool)
    if not len(boxes):
        return keep
    cell = float(max((boxes[:, 2] - boxes[:, 0]).max(), (boxes[:, 3] - boxes[:, 1]).max(), 1.0)) + gap
    grid: dict = {}

    def span(b):
        return [(i, j) for i in range(int((b[0] - gap) // cell), int((b[2] + gap) // cell) + 1)
                for j in range(int((b[1] - gap) // cell), int((b[3] + gap) // cell) + 1)]

    def add(b):
        for key in span(b):
            grid.setdefault(key, []).append(b)

    for b in np.asarray(taken if taken is not None else (), float).reshape(-1, 4):
        add(b)
    for k, b in enumerate(boxes):
        if not any(b[0] < o[2] + gap and o[0] < b[2] + gap and b[1] < o[3] + gap and o[1] < b[3] + gap
                   for key in span(b) for o in grid.get(key, ())):
            keep[k] = True
            add(b)
    return keep


def marker_radii(rpx) -> np.ndarray:
    """Target marker radii (px, outer edge) for disks of on-screen radii ``rpx``: inside the
    disk (MARKER_FRAC of it, at least MIN_MARKER_PX) where the marker and its halo stay within
    MARKER_INSIDE_MAX of the disk's radius, else a ring just outside the disk's rim (small
    disks: the marker would hide the disk resting on it; see :func:`markers_outside`)."""
    rpx = np.asarray(rpx, float)
    inner = np.maximum(style.MARKER_FRAC * rpx, style.MIN_MARKER_PX)
    outside = rpx + style.MARKER_OUTSIDE_GAP_PX + style.MARKER_OUTSIDE_PX
    return np.where(markers_outside(rpx), outside, inner)


def markers_outside(rpx) -> np.ndarray:
    """Which targets (of disks with on-screen radii ``rpx``) are marked by a thin ring outside
    their disk's rim, drawn under the disks, instead of a small circle over them."""
    rpx = np.asarray(rpx, float)
    inner = np.maximum(style.MARKER_FRAC * rpx, style.MIN_MARKER_PX)
    return inner + style.MARKER_HALO_PX > style.MARKER_INSIDE_MAX * rpx


def labels_legible(rpx) -> bool:
    """Whether disks of on-screen radii ``rpx`` (px) are numbered by default: every one at
    least LABELS_MIN_DISK_PX across (``nbst render`` without --labels or --no-labels)."""
    rpx = np.asarray(rpx, float)
    return bool(rpx.size) and 2.0 * float(rpx.min()) >= style.LABELS_MIN_DISK_PX


def auto_labels(problem, size) -> bool:
    """:func:`labels_legible` for ``problem`` in a frame of ``size`` with the box centred
    (the 2D renderer decides on its own layout, the 3D view by this)."""
    s = Layout(problem.box, size).scale
    return labels_legible(np.maximum(problem.radius * s, style.MIN_DISK_PX))


def target_label_px(size) -> int:
    """Text height of the target numbers for a frame of ``size``."""
    return int(np.clip(round(style.TARGET_LABEL_FRAC * min(size)), style.MIN_TARGET_LABEL_PX,
                       style.MAX_TARGET_LABEL_PX))


def target_label_instances(text, centers_px, marker_px, avoid=None, skip=None) -> np.ndarray:
    """Text instances of :func:`target_label_boxes`' numbers (the ones it draws)."""
    x, y, want = target_label_boxes(text, centers_px, marker_px, avoid, skip)
    return text.numbers(len(want)).layout(x, y, want)


def target_label_boxes(text, centers_px, marker_px, avoid=None, skip=None):
    """(x, y, drawn): where each target's number goes (top-left, px) and which are drawn. Each
    target is numbered with its disk's index, just above and
    right of its marker (centres (N, 2) px, marker radii (N,) px). ``avoid``: boxes
    (M, 4) px (x0, y0, x1, y1; the disks' numbers drawn): a number that would
    overlap one moves to the first free corner of its marker (upper left, lower right,
    lower left), or stays upper right if none is free, and is left out if it still covers
    one or another target's number. ``skip`` (N,) bool: targets left unnumbered (their own
    disk covers them and carries the same number)."""
    cw, ch = text.cell
    centers_px = np.asarray(centers_px, float)
    n = len(centers_px)
    marker_px = np.broadcast_to(np.asarray(marker_px, float), (n,))
    runs = text.numbers(n)
    w = runs.width.astype(float)
    d = 0.75 * marker_px + 1.0
    right, left = centers_px[:, 0] + d, centers_px[:, 0] - d - w
    up, down = centers_px[:, 1] - 0.75 * marker_px - 0.8 * ch, centers_px[:, 1] + 0.75 * marker_px - 0.2 * ch
    cands = [(right, up), (left, up), (right, down), (left, down)]
    x, y = right.copy(), up.copy()
    if avoid is not None and len(avoid):
        a = np.asarray(avoid, float)
        free = np.zeros(n, bool)
        for cx, cy in cands:
            hit = ((cx[:, None] < a[None, :, 2]) & (cx[:, None] + w[:, None] > a[None, :, 0])
                   & (cy[:, None] < a[None, :, 3]) & (cy[:, None] + ch > a[None, :, 1])).any(axis=1)
            take = ~free & ~hit
            x[take], y[take] = cx[take], cy[take]
            free |= take
    want = np.ones(n, bool) if skip is None else ~np.asarray(skip, bool)
    # a target's number never covers a disk's number nor another target's (crowded targets: the
    # lower disk numbers are written, the others left out rather than run together)
    idx = np.flatnonzero(want)
    want[idx] = keep_apart(np.stack([x, y, x + w, y + ch], axis=1)[idx], taken=avoid)
    return x, y, want


def covered_by_own_disk(problem, pos) -> np.ndarray:
    """Which targets their own disk covers at positions ``pos`` (N, 2): the disk's number
    then names the target, and the target's own number is left out (no "1313" pairs)."""
    return ((np.asarray(pos, float) - problem.target) ** 2).sum(axis=1) < problem.radius ** 2


def ghost_label_instances(text, centers_px, ring_px, avoid=None) -> np.ndarray:
    """Text instances numbering each ghost ring (``--source both --labels``) with its
    disk's index, just below and right of the ring (centres (N, 2) px, radii (N,) px);
    none that covers a box of ``avoid`` (M, 4) px (the readout)."""
    cw, ch = text.cell
    c = np.asarray(centers_px, float)
    ring_px = np.broadcast_to(np.asarray(ring_px, float), (len(c),))
    runs = text.numbers(len(c))
    x, y = c[:, 0] + 0.72 * ring_px + 1.0, c[:, 1] + 0.72 * ring_px - 0.2 * ch
    which = None if avoid is None else ~overlaps(np.stack([x, y, x + runs.width, y + ch], axis=1), avoid)
    return runs.layout(x, y, which)


def legend_entries(problem, *, ghost: bool, labels: bool, long: bool = True, ghost_name: str = "MuJoCo",
                   motion_name: str | None = None) -> list[tuple]:
    """The legend's lines as (words, swatch kind, colour): a filled disk per class
    present (naming the motion when rings show a second one), the hollow target mark
    (saying that its number names its disk when targets are numbered), the lit ring
    that the readout's "on target" counts, the ring of the second motion when one is
    drawn. ``long=False``: the short words, for narrow margins."""
    out: list[tuple[str, str, tuple[float, float, float] | None]] = []
    of = f" ({motion_name or 'exact'})" if (ghost or motion_name) and long else ""
    if problem.cueable.any():
        out.append((palette.LEGEND_CUEABLE + of, "disk", style.CUEABLE))
    if (~problem.cueable).any():
        out.append((palette.LEGEND_NONCUEABLE + of, "disk", style.NONCUEABLE))
    out.append((palette.LEGEND_TARGET if labels and long else "target", "target", None))
    lit = style.CUEABLE if problem.cueable.any() else style.NONCUEABLE
    out.append(("on target: within R" if long else "within R", "lit", lit))
    if ghost:
        out.append((f"{ghost_name} replay" + (" (ring)" if long else ""), "ghost", None))
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
        elif kind == "lit":
            d["radius"] = 0.45 * ch
            d["stroke"] = max(1.5, 0.5 * style.RING_LIT_PX)
            d["fill"] = (*col, style.RING_LIT_FILL_ALPHA)
            d["rim"] = (*col, style.RING_LIT_ALPHA)
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

    ctx     : a moderngl context (see :func:`nbst.render.core.gl.create_context`)
    motion  : the disks' motion, ``at(t) -> (N, 2)`` (a Trajectory, or SampledMotion)
    ghost   : optional second motion drawn as rings on top (MuJoCo replay)
    trails  : draw the last TRAIL_SECONDS of every path, fading with age
    labels  : write each disk's index on it (as in ``nbst simulate``'s table), beside
              each target the index of the disk it belongs to, and beside each ghost
              ring its disk's index; None: only where legible (:func:`labels_legible`:
              every disk at least LABELS_MIN_DISK_PX across), as ``nbst render``'s default
    motion_name, ghost_name : what the disks and the rings show, for the readout and
              the legend (default: "exact" and "MuJoCo" when both are drawn; no name
              for the disks alone)

    Layers, bottom to top: floor and dim target rings (static), trails, lit rings, disks,
    target markers (in a dark halo: a disk never hides one), ghost rings, numbers, readout.
    """

    def __init__(self, ctx, problem, motion, *, size=style.DEFAULT_SIZE, trails: bool = False, ghost=None,
                 labels: bool | None = False, title: str | None = None, motion_name: str | None = None,
                 ghost_name: str | None = None, clean: bool = False):
        import moderngl

        self.clean = bool(clean)   # no text: no readout, legend or numbers (``nbst render --clean``)
        self._show(ctx, problem, motion, ghost, trails=trails, motion_name=motion_name, ghost_name=ghost_name,
                   title=title)
        self.target = FrameTarget(ctx, size)
        self.size = self.target.size
        # the readout lives in the top-left corner, one fact a line, at the frame's text size when
        # it ends above the box (a wide box, e.g. a formation of text, leaves room above it) or
        # left of it; else smaller type where its longest line would reach the box, never under
        # MIN_READOUT_PX; the box makes room below that
        short = min(self.size)
        L = Layout(problem.box, self.size)
        chars = self.readout_width()
        free = L.box_rect[0] - L.wall - L.margin  # half a margin of padding on each side
        text_px = max(style.MIN_READOUT_PX, int(round(style.TEXT_FRAC * short)))
        cw, ch = text_cell(text_px)
        above = 0.5 * L.margin + self.readout_lines() * ch + 0.5 * L.margin <= L.box_rect[1] - L.wall
        if above and 0.5 * L.margin + chars * cw <= self.size[0]:
            free = float("inf")  # it ends above the box: its width is free
        while text_px > style.MIN_READOUT_PX and chars * text_cell(text_px)[0] > free:
            text_px -= 1
        # no room at MIN_READOUT_PX: the box moves right (and shrinks) for it, but keeps at least
        # MIN_BOX_SHARE of its size; on a frame too small for that (a 160x120 GIF) smaller type
        # is tried, down to 8 px, and at worst the readout overlaps the box's corner
        while chars * text_cell(text_px)[0] > free:
            L2 = Layout(problem.box, self.size, keep_left=chars * text_cell(text_px)[0] + L.margin)
            if L2.scale >= style.MIN_BOX_SHARE * L.scale:
                L = L2
                break
            if text_px <= 8:
                break
            text_px -= 1
        self.layout = L
        self.text = Text(ctx, text_px)
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
        if labels is None:
            labels = labels_legible(self.rpx)
        self.labels = Labels(ctx, problem, self.rpx, self.colors) if labels else None
        self.marker_px = marker_radii(self.rpx)
        if self.labels is not None and self.labels.on_disk.any():
            # a disk resting on its target: the marker rings its number instead of crossing it
            clear = float(self.labels.half_diag[self.labels.on_disk].max()) + style.MARKER_LABEL_GAP_PX
            self.marker_px = np.where(self.labels.on_disk, np.maximum(self.marker_px, clear), self.marker_px)
        # small circles over the disks, each in a dark halo (drawn every frame, above the disks);
        # around small disks, thin rings under them instead (static layer: markers_outside)
        self.marker_outside = markers_outside(self.rpx)
        over = ~self.marker_outside
        k = int(over.sum())
        self._markers = np.zeros(2 * k, CIRCLE_DTYPE)  # halo rings, then the markers
        self._markers["center"] = np.concatenate([self.target_px[over], self.target_px[over]])
        h = style.MARKER_HALO_PX
        self._markers["radius"][:k] = self.marker_px[over] + h
        self._markers["stroke"][:k] = style.MARKER_PX + 2 * h
        self._markers["rim"][:k] = style.MARKER_HALO
        self._markers["radius"][k:] = self.marker_px[over]
        self._markers["stroke"][k:] = style.MARKER_PX
        self._markers["rim"][k:] = style.MARKER
        self.legend_text = Text(ctx, max(style.MIN_LEGEND_PX, int(round(style.LEGEND_TEXT_FRAC * short))))
        self.target_text = Text(ctx, target_label_px(self.size)) if labels else None
        self.static = FrameTarget(ctx, self.size)
        self._draw_static()

    # ------------------------------------------------------------------ static layer

    def _readout_origin(self) -> tuple[float, float]:
        L = self.layout
        pad = L.margin * 0.5
        return (pad, pad)

    def _draw_static(self) -> None:
        """Background, box, dim target rings, the target rings of small disks and the legend:
        drawn once (other target markers and all numbers are drawn on every frame, above the
        disks)."""
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
        rings = np.zeros(p.n, CIRCLE_DTYPE)
        rings["center"] = self.target_px
        rings["radius"] = self.R_px
        rings["stroke"] = style.RING_DIM_PX
        rings["rim"] = style.RING_DIM
        self.circles.draw(rings)
        out = self.marker_outside
        if out.any():  # target rings around small disks: under the disks, never over them
            marks = np.zeros(int(out.sum()), CIRCLE_DTYPE)
            marks["center"] = self.target_px[out]
            marks["radius"] = self.marker_px[out]
            marks["stroke"] = style.MARKER_OUTSIDE_PX
            marks["rim"] = style.MARKER
            self.circles.draw(marks)
        self._draw_legend()

    def readout_box(self) -> tuple[float, float, float, float]:
        """The readout's box (x0, y0, x1, y1) px at its widest (its lines at t_final), made once."""
        if getattr(self, "_readout_box", None) is None:
            x, y = self._readout_origin()
            cw, ch = self.text.cell
            self._readout_box = (x, y, x + self.readout_width() * cw, y + self.readout_lines() * ch)
        return self._readout_box

    def readout_lines(self) -> int:
        """Lines of the readout (the legend starts below them)."""
        return len(self.readout(0.0, np.zeros(self.problem.n, bool),
                                np.zeros(self.problem.n, bool) if getattr(self, "ghost", None) is not None else None))

    def _draw_legend(self) -> None:
        """Legend under the readout, in the left margin, when the margin is wide enough; else
        below the box, or above it right of the readout (a wide box leaves no left margin)."""
        if self.clean:
            return
        L = self.layout
        x, y = self._readout_origin()
        pad = 0.5 * L.margin
        bx0, by0, bx1, by1 = L.box_rect
        places = [  # (x, y, max_w, max_h): left margin under the readout; below the box; above it
            (x, y + (self.readout_lines() + 0.6) * self.text.cell[1], bx0 - L.wall - pad - x, None),
            (bx0, by1 + L.wall + pad, self.size[0] - bx0 - pad, self.size[1] - (by1 + L.wall + pad) - pad),
            (x + (self.readout_width() + 2) * self.text.cell[0], y, None, by0 - L.wall - pad - y)]
        for px, py, max_w, max_h in places:
            max_w = self.size[0] - pad - px if max_w is None else max_w
            max_h = self.size[1] - pad - py if max_h is None else max_h
            self.legend_drawn = draw_legend(
                self.circles, self.legend_text, self.size, px, py, max_w, max_h,
                lambda long: legend_entries(self.problem, ghost=self.ghost is not None,
                                            labels=self.target_text is not None, long=long,
                                            ghost_name=self.ghost_name, motion_name=self.motion_name))
            if self.legend_drawn:
                return

    # ------------------------------------------------------------------ frames

    def to_pixels(self, xy) -> np.ndarray:
        """World points -> image px (x = column, y = row, fractional)."""
        return self.layout.to_image(xy)

    def inside(self, pos) -> np.ndarray:
        """Which disks at ``pos`` (N, 2) are within R of their targets (on target)."""
        p = self.problem
        return ((np.asarray(pos, float) - p.target) ** 2).sum(axis=1) <= p.target_radius ** 2

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
        inside = self.inside(pos)
        if inside.any():
            self.circles.draw(self._lit[inside])
        self._disks["center"] = self.layout.to_image(pos)
        self.circles.draw(self._disks)
        self.circles.draw(self._markers)  # above the disks: never hidden
        ghost_inside = None
        if self.ghost is not None:
            g = np.asarray(self.ghost.at(t), float)
            ghost_inside = self.inside(g)
            self._ghosts["center"] = self.layout.to_image(g)
            self.circles.draw(self._ghosts)
        if self.labels is not None and self.target_text is not None:  # set together
            # no number in the readout's box (a small frame's readout overlaps the box's corner)
            readout = np.zeros((0, 4)) if self.clean else np.array([self.readout_box()])
            drawn = self.labels.drawn(self._disks["center"], taken=readout)
            self.labels.draw(self.size, self._disks["center"], drawn)
            numbers = target_label_instances(self.target_text, self.target_px, self.marker_px,
                                             avoid=np.concatenate([self.labels.boxes(self._disks["center"], drawn),
                                                                   readout]),
                                             skip=covered_by_own_disk(p, pos))
            self.target_text.draw_halo(self.size, numbers, style.TARGET_LABEL, style.TEXT_HALO)
            if self.ghost is not None:
                self.target_text.draw_halo(self.size, ghost_label_instances(self.target_text, self._ghosts["center"],
                                                                            self.rpx, avoid=readout), style.GHOST_LABEL,
                                           style.TEXT_HALO)
        x, y = self._readout_origin()
        if not self.clean:
            self.text.draw(self.size, self.text.layout(self.readout(t, inside, ghost_inside), x, y), style.TEXT)

    def _trail_instances(self, t: float) -> np.ndarray:
        return trail_capsules(self.motion, t, self.trail_half, self.colors, to_view=self.layout.to_image,
                              min_step=1e-3)  # px

    def release(self) -> None:
        for o in (self.circles, self.capsules, self.rect, self.text, self.target, self.static, self.labels,
                  self.legend_text, self.target_text):
            if o is not None:
                o.release()
