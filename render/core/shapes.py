"""Anti-aliased 2D primitives for moderngl: instanced quads shaded by signed
distance (circles with rim, rings, capsules, a rectangle) and monospace text
from a glyph atlas.

All coordinates are *image pixels*: x right, y down, (0, 0) the top-left corner
of the frame, pixel (c, r) covering [c, c+1) x [r, r+1). The vertex shaders map
image row 0 to GL's bottom row, so ``Framebuffer.read_into`` returns the top row
first with no flip. Colours are premultiplied in the shaders; blending is
``ONE, ONE_MINUS_SRC_ALPHA`` unless said otherwise.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from nbst.render.core.textfit import fit_lines

__all__ = ["ATLAS_COLS", "CAPSULE_DTYPE", "CAPSULE_FS", "CAPSULE_FS_IO", "CAPSULE_VS", "CAPSULE_VS_IO",
           "CIRCLE_DTYPE", "CIRCLE_FS", "CIRCLE_VS", "EXTRA_CHARS", "RECT_FS", "RECT_VS", "TEXT_DTYPE", "TEXT_FS",
           "TEXT_VS", "Capsules", "Circles", "GlyphRuns", "Rect", "Text", "digit_height", "glyph_atlas",
           "glyph_index", "text_cell"]

_NDC = """
uniform vec2 u_view;  // frame size in px
vec4 to_ndc(vec2 img) { return vec4(img / u_view * 2.0 - 1.0, 0.0, 1.0); }
"""

_QUAD = np.array([[-1, -1], [1, -1], [-1, 1], [1, 1]], dtype="f4")  # triangle strip

CIRCLE_VS = "#version 330\n" + _NDC + """
in vec2 in_corner;
in vec2 in_center;   // px
in float in_radius;  // px, outer edge
in float in_stroke;  // px, rim width inside the outer edge
in vec4 in_fill;     // straight alpha
in vec4 in_rim;
out vec2 v_off;
flat out float v_radius;
flat out float v_stroke;
flat out vec4 v_fill;
flat out vec4 v_rim;
void main() {
    float ext = in_radius + 1.5;
    v_off = in_corner * ext;
    v_radius = in_radius; v_stroke = in_stroke; v_fill = in_fill; v_rim = in_rim;
    gl_Position = to_ndc(in_center + v_off);
}
"""

CIRCLE_FS = """#version 330
in vec2 v_off;
flat in float v_radius;
flat in float v_stroke;
flat in vec4 v_fill;
flat in vec4 v_rim;
out vec4 f_color;
void main() {
    float d = length(v_off) - v_radius;          // signed distance to the outer edge, px
    float a_out = clamp(0.5 - d, 0.0, 1.0);      // coverage of the whole disk
    float a_in = clamp(0.5 - (d + v_stroke), 0.0, 1.0);  // coverage of the fill inside the rim
    vec4 rim = vec4(v_rim.rgb * v_rim.a, v_rim.a);
    vec4 fill = vec4(v_fill.rgb * v_fill.a, v_fill.a);
    f_color = mix(rim, fill, a_in) * a_out;
    if (f_color.a <= 0.0) discard;
}
"""

#: The capsule (a segment p0 -> p1 with round ends, its alpha running from one end to the other):
#: the one copy of its GLSL, shared by the 2D trails here and the 3D trails on the felt
#: (``nbst.render.scene3d``). ``CAPSULE_VS_IO`` declares the per-instance inputs and what the
#: fragment shader gets; ``capsule_corner`` places a corner of the quad that covers the capsule
#: (``ext``: how far it reaches beyond the segment); ``segment_distance`` (fragment side) is the
#: distance from p to the segment and, in ``h``, where along it (0 at p0, 1 at p1) the nearest point is.
CAPSULE_VS_IO = """
in vec2 in_corner;
in vec2 in_p0;
in vec2 in_p1;
in vec2 in_alpha;   // alpha at p0, at p1
in float in_half;   // half width
in vec3 in_color;
out vec2 v_pos;
flat out vec2 v_p0;
flat out vec2 v_p1;
flat out vec2 v_alpha;
flat out float v_half;
flat out vec3 v_color;
vec2 capsule_corner(vec2 corner, vec2 p0, vec2 p1, float ext) {
    vec2 d = p1 - p0;
    float len = length(d);
    vec2 u = len > 1e-6 ? d / len : vec2(1.0, 0.0);
    vec2 n = vec2(-u.y, u.x);
    return 0.5 * (p0 + p1) + u * corner.x * (0.5 * len + ext) + n * corner.y * ext;
}
void capsule_out() {
    v_p0 = in_p0; v_p1 = in_p1; v_alpha = in_alpha; v_half = in_half; v_color = in_color;
}
"""
CAPSULE_FS_IO = """
in vec2 v_pos;
flat in vec2 v_p0;
flat in vec2 v_p1;
flat in vec2 v_alpha;
flat in float v_half;
flat in vec3 v_color;
out vec4 f_color;
float segment_distance(vec2 p, vec2 p0, vec2 p1, out float h) {
    vec2 pa = p - p0, ba = p1 - p0;
    float bb = dot(ba, ba);
    h = bb > 1e-12 ? clamp(dot(pa, ba) / bb, 0.0, 1.0) : 0.0;
    return length(pa - ba * h);
}
"""

CAPSULE_VS = "#version 330\n" + _NDC + CAPSULE_VS_IO + """
void main() {
    v_pos = capsule_corner(in_corner, in_p0, in_p1, in_half + 1.5);  // px: half a pixel of anti-aliasing
    capsule_out();
    gl_Position = to_ndc(v_pos);
}
"""

# Trails are drawn with MAX blending over a uniform dark floor: overlapping
# segments of one path (joints, self-crossings) take the max, never the sum,
# so a trail has no dark or bright seams.
CAPSULE_FS = "#version 330\nuniform vec3 u_floor;" + CAPSULE_FS_IO + """
void main() {
    float h;
    float d = segment_distance(v_pos, v_p0, v_p1, h) - v_half;
    float a = mix(v_alpha.x, v_alpha.y, h) * clamp(0.5 - d, 0.0, 1.0);
    if (a <= 0.0) discard;
    f_color = vec4(mix(u_floor, v_color, a), 1.0);
}
"""

RECT_VS = "#version 330\n" + _NDC + """
uniform vec4 u_rect;   // x0, y0, x1, y1 (px) of the outer edge
in vec2 in_corner;
out vec2 v_pos;
void main() {
    vec2 c = 0.5 * (u_rect.xy + u_rect.zw), h = 0.5 * (u_rect.zw - u_rect.xy) + 1.5;
    v_pos = c + in_corner * h;
    gl_Position = to_ndc(v_pos);
}
"""

RECT_FS = """#version 330
uniform vec4 u_rect;
uniform float u_stroke;
uniform vec4 u_fill;
uniform vec4 u_rim;
in vec2 v_pos;
out vec4 f_color;
void main() {
    vec2 c = 0.5 * (u_rect.xy + u_rect.zw), h = 0.5 * (u_rect.zw - u_rect.xy);
    vec2 q = abs(v_pos - c) - h;
    float d = length(max(q, 0.0)) + min(max(q.x, q.y), 0.0);
    float a_out = clamp(0.5 - d, 0.0, 1.0);
    float a_in = clamp(0.5 - (d + u_stroke), 0.0, 1.0);
    vec4 rim = vec4(u_rim.rgb * u_rim.a, u_rim.a);
    vec4 fill = vec4(u_fill.rgb * u_fill.a, u_fill.a);
    f_color = mix(rim, fill, a_in) * a_out;
}
"""

TEXT_VS = "#version 330\n" + _NDC + """
uniform vec2 u_cell;    // glyph cell, px
uniform vec2 u_atlas;   // atlas size, px
uniform float u_cols;   // cells per atlas row
in vec2 in_corner;
in vec2 in_pos;         // top-left of the cell, px
in float in_glyph;
out vec2 v_uv;
void main() {
    vec2 c = 0.5 * (in_corner + 1.0);  // 0..1, y down
    float col = mod(in_glyph, u_cols), row = floor(in_glyph / u_cols);
    v_uv = (vec2(col, row) + c) * u_cell / u_atlas;
    gl_Position = to_ndc(in_pos + c * u_cell);
}
"""

TEXT_FS = """#version 330
uniform sampler2D u_tex;
uniform vec3 u_color;
in vec2 v_uv;
out vec4 f_color;
void main() {
    float a = texture(u_tex, v_uv).r;
    if (a <= 0.0) discard;
    f_color = vec4(u_color * a, a);
}
"""

CIRCLE_DTYPE = np.dtype([("center", "f4", 2), ("radius", "f4"), ("stroke", "f4"), ("fill", "f4", 4),
                         ("rim", "f4", 4)])
CAPSULE_DTYPE = np.dtype([("p0", "f4", 2), ("p1", "f4", 2), ("alpha", "f4", 2), ("half", "f4"),
                          ("color", "f4", 3)])
TEXT_DTYPE = np.dtype([("pos", "f4", 2), ("glyph", "f4")])


class _Instanced:
    """A program drawing one quad per instance from a growable instance buffer."""

    def __init__(self, ctx, vs, fs, dtype, fmt, attrs, capacity=64):
        self.ctx = ctx
        self.prog = ctx.program(vertex_shader=vs, fragment_shader=fs)
        self.dtype = dtype
        self.fmt, self.attrs = fmt, attrs
        self.quad = ctx.buffer(_QUAD.tobytes())
        self.capacity = 0
        self.inst = None
        self.vao = None
        self._grow(capacity)

    def _grow(self, n):
        if n <= self.capacity:
            return
        self.capacity = max(n, 2 * self.capacity)
        if self.inst is not None:
            self.vao.release()
            self.inst.release()
        self.inst = self.ctx.buffer(reserve=self.capacity * self.dtype.itemsize, dynamic=True)
        self.vao = self.ctx.vertex_array(self.prog, [(self.quad, "2f", "in_corner"),
                                                     (self.inst, self.fmt + "/i", *self.attrs)])

    def set_view(self, size):
        self.prog["u_view"].value = tuple(float(x) for x in size)

    def draw(self, data: np.ndarray) -> None:
        n = len(data)
        if n == 0:
            return
        self._grow(n)
        self.inst.write(np.ascontiguousarray(data, self.dtype).tobytes())
        import moderngl
        self.vao.render(moderngl.TRIANGLE_STRIP, vertices=4, instances=n)

    def release(self):
        for o in (self.vao, self.inst, self.quad, self.prog):
            o.release()


class Circles(_Instanced):
    def __init__(self, ctx):
        super().__init__(ctx, CIRCLE_VS, CIRCLE_FS, CIRCLE_DTYPE, "2f 1f 1f 4f 4f",
                         ("in_center", "in_radius", "in_stroke", "in_fill", "in_rim"))


class Capsules(_Instanced):
    def __init__(self, ctx):
        super().__init__(ctx, CAPSULE_VS, CAPSULE_FS, CAPSULE_DTYPE, "2f 2f 2f 1f 3f",
                         ("in_p0", "in_p1", "in_alpha", "in_half", "in_color"), capacity=1024)


class Rect:
    def __init__(self, ctx):
        self.ctx = ctx
        self.prog = ctx.program(vertex_shader=RECT_VS, fragment_shader=RECT_FS)
        self.quad = ctx.buffer(_QUAD.tobytes())
        self.vao = ctx.vertex_array(self.prog, [(self.quad, "2f", "in_corner")])

    def draw(self, size, rect, *, fill, rim, stroke):
        import moderngl
        p = self.prog
        p["u_view"].value = tuple(float(x) for x in size)
        p["u_rect"].value = tuple(float(x) for x in rect)
        p["u_stroke"].value = float(stroke)
        p["u_fill"].value = tuple(fill) if len(fill) == 4 else (*fill, 1.0)
        p["u_rim"].value = tuple(rim) if len(rim) == 4 else (*rim, 1.0)
        self.vao.render(moderngl.TRIANGLE_STRIP)

    def release(self):
        for o in (self.vao, self.quad, self.prog):
            o.release()


# --------------------------------------------------------------------------- text

FIRST_CHAR, LAST_CHAR = 32, 126  # printable ASCII
#: Beyond ASCII, the few signs the readouts write (a crash's delta-V, degrees, tolerances, a fate's
#: check mark and cross); DejaVu Sans Mono has each. Their glyphs follow ASCII's in the atlas.
EXTRA_CHARS = "\u00b0\u00b1\u00d7\u00b7\u0394\u2713\u2717\u2192"   # ° ± × · Δ ✓ ✗ →
#: ... and Latin-1's letters (a user's body named "würfel" or "pièce" lost its "ü" and "è").
EXTRA_CHARS += "".join(chr(k) for k in range(0xC0, 0x100) if chr(k) not in EXTRA_CHARS)
ATLAS_COLS = 16


def _font(px: int):
    import os

    import matplotlib
    from PIL import ImageFont

    path = os.path.join(matplotlib.get_data_path(), "fonts", "ttf", "DejaVuSansMono.ttf")
    return ImageFont.truetype(path, max(6, int(px)))


def text_cell(px: int) -> tuple[int, int]:
    """The glyph cell (cw, ch) in px of text at ``px`` pixels (as :class:`Text` lays it out),
    without a GL context: for fitting text before any is drawn."""
    font = _font(px)
    ascent, descent = font.getmetrics()
    return int(np.ceil(font.getlength("M"))), ascent + descent


def digit_height(px: int) -> int:
    """Height in px of the digits' ink at ``px`` pixels (about 0.73 px; "0" is 9 px tall at 12)."""
    from PIL import Image, ImageDraw

    font = _font(px)
    cw, ch = text_cell(px)
    img = Image.new("L", (2 * cw, ch), 0)
    ImageDraw.Draw(img).text((0, 0), "0", font=font, fill=255)
    rows = np.nonzero(np.asarray(img).max(axis=1) > 127)[0]
    return int(rows.max() - rows.min() + 1) if rows.size else 0


def glyph_atlas(px: int) -> tuple[np.ndarray, tuple[int, int]]:
    """Rasterize printable ASCII in DejaVu Sans Mono (shipped with matplotlib) at
    ``px`` pixels: returns the (rows*ch, 16*cw) uint8 coverage atlas and the cell
    (cw, ch). Made once per size with Pillow; no font dependency beyond matplotlib."""
    from PIL import Image, ImageDraw

    font = _font(px)
    ascent, descent = font.getmetrics()
    cw = int(np.ceil(font.getlength("M")))
    ch = ascent + descent
    chars = [chr(k) for k in range(FIRST_CHAR, LAST_CHAR + 1)] + list(EXTRA_CHARS)
    rows = (len(chars) + ATLAS_COLS - 1) // ATLAS_COLS
    img = Image.new("L", (ATLAS_COLS * cw, rows * ch), 0)
    draw = ImageDraw.Draw(img)
    for k, char in enumerate(chars):
        r, c = divmod(k, ATLAS_COLS)
        draw.text((c * cw, r * ch), char, font=font, fill=255)
    return np.asarray(img, dtype=np.uint8), (cw, ch)


def glyph_index(c: str) -> int | None:
    """The atlas cell of character ``c``; None for a space or a character the atlas lacks."""
    k = ord(c)
    if FIRST_CHAR < k <= LAST_CHAR:
        return k - FIRST_CHAR
    i = EXTRA_CHARS.find(c)
    return None if i < 0 else LAST_CHAR - FIRST_CHAR + 1 + i


class GlyphRuns:
    """Many one-line strings (disk numbers) laid out at once: each frame gives every
    string's top-left (x, y) and gets TEXT_DTYPE instances back, with no Python work per
    string (1,000 disk numbers cost one numpy gather, not 1,000 ``Text.layout`` calls).
    Positions are rounded to whole pixels as :meth:`Text.layout` rounds them."""

    def __init__(self, strings, cell):
        self.strings = list(strings)
        cw = cell[0]
        lens = np.array([len(s) for s in self.strings], np.int64)
        self.lengths = lens
        self.width = lens * cw  #: px width of each string
        chars = np.frombuffer("".join(self.strings).encode("ascii", "replace"), np.uint8).astype(np.int64)
        self.owner = np.repeat(np.arange(len(lens)), lens)
        starts = np.concatenate(([0], np.cumsum(lens)[:-1])) if len(lens) else np.zeros(0, np.int64)
        self.col = np.arange(len(chars)) - np.repeat(starts, lens)
        ok = (chars > FIRST_CHAR) & (chars <= LAST_CHAR)  # spaces and non-printables draw nothing
        self.owner, self.col, chars = self.owner[ok], self.col[ok], chars[ok]
        self.glyph = (chars - FIRST_CHAR).astype("f4")
        self.cw = float(cw)

    def layout(self, x, y, which=None) -> np.ndarray:
        """Instances of the strings (all, or those where the bool mask ``which`` holds) with
        string k's first cell's top-left at (x[k], y[k]) px."""
        x = np.asarray(x, float)
        y = np.asarray(y, float)
        sel = slice(None) if which is None else np.asarray(which, bool)[self.owner]
        owner, col = self.owner[sel], self.col[sel]
        data = np.empty(len(owner), TEXT_DTYPE)
        data["pos"][:, 0] = np.round(x[owner] + col * self.cw)
        data["pos"][:, 1] = np.round(y[owner])
        data["glyph"] = self.glyph[sel]
        return data


class Text:
    """Monospace text at integer pixel positions (nearest sampling: crisp, exact)."""

    def __init__(self, ctx, px: int):
        self.ctx = ctx
        atlas, self.cell = glyph_atlas(px)
        self._atlas = atlas
        self._halo: tuple[int, Any, _Instanced] | None = None  # the dilated atlas of draw_halo, made on first use
        h, w = atlas.shape
        self.tex = ctx.texture((w, h), 1, np.ascontiguousarray(atlas).tobytes(), alignment=1)
        import moderngl
        self.tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
        self.batch = _Instanced(ctx, TEXT_VS, TEXT_FS, TEXT_DTYPE, "2f 1f", ("in_pos", "in_glyph"), capacity=128)
        p = self.batch.prog
        p["u_cell"].value = tuple(float(x) for x in self.cell)
        p["u_atlas"].value = (float(w), float(h))
        p["u_cols"].value = float(ATLAS_COLS)

    def layout(self, lines, x: float, y: float) -> np.ndarray:
        """Instance data for ``lines`` (list of str) with the first cell's top-left at (x, y)."""
        cw, ch = self.cell
        out = []
        for li, s in enumerate(lines):
            for ci, c in enumerate(s):
                g = glyph_index(c)
                if g is None:
                    if c.isspace() or not c.isprintable():
                        continue
                    g = glyph_index("?")   # a script the font lacks (a body named 球): a mark, not a gap
                out.append(((round(x + ci * cw), round(y + li * ch)), g))
        data = np.zeros(len(out), TEXT_DTYPE)
        for i, (pos, g) in enumerate(out):
            data[i] = (pos, g)
        return data

    def draw(self, size, data: np.ndarray, color) -> None:
        self.batch.set_view(size)
        self.batch.prog["u_color"].value = tuple(float(c) for c in color[:3])
        self.tex.use(0)
        self.batch.prog["u_tex"].value = 0
        self.batch.draw(data)

    def draw_halo(self, size, data: np.ndarray, color, halo, *, px: int = 1) -> None:
        """Draw ``data`` in ``color`` over a halo: each glyph's ink grown by ``px`` in every
        direction (the union of the glyph shifted by up to ``px``), in ``halo``, so the text
        stays legible over disks, rings and trails. The grown glyphs come from a dilated copy
        of the atlas (cells ``px`` wider on each side), one quad a glyph: 1,000 disk numbers
        cost one halo quad each, not eight shifted copies."""
        if len(data) == 0:
            return
        if self._halo is None or self._halo[0] != px:
            self._make_halo(px)
        assert self._halo is not None
        _, tex, batch = self._halo
        d = data.copy()
        d["pos"] -= px
        batch.set_view(size)
        batch.prog["u_color"].value = tuple(float(c) for c in halo[:3])
        tex.use(0)
        batch.prog["u_tex"].value = 0
        batch.draw(d)
        self.draw(size, data, color)

    def _make_halo(self, px: int) -> None:
        """The atlas with every cell padded by ``px`` and its ink dilated by ``px`` (a square
        max filter, cell by cell: no ink bleeds in from a neighbouring cell)."""
        import moderngl

        if self._halo is not None:
            self._halo[1].release()
            self._halo[2].release()
        cw, ch = self.cell
        a = self._atlas
        rows, cols = a.shape[0] // ch, a.shape[1] // cw
        cells = a.reshape(rows, ch, cols, cw).transpose(0, 2, 1, 3)  # (rows, cols, ch, cw)
        pad = np.zeros((rows, cols, ch + 4 * px, cw + 4 * px), np.uint8)
        pad[:, :, 2 * px:2 * px + ch, 2 * px:2 * px + cw] = cells
        grown = np.zeros((rows, cols, ch + 2 * px, cw + 2 * px), np.uint8)
        for dy in range(-px, px + 1):
            for dx in range(-px, px + 1):
                np.maximum(grown, pad[:, :, px + dy:px + dy + ch + 2 * px, px + dx:px + dx + cw + 2 * px], out=grown)
        hc = (cw + 2 * px, ch + 2 * px)
        img = np.ascontiguousarray(grown.transpose(0, 2, 1, 3).reshape(rows * hc[1], cols * hc[0]))
        tex = self.ctx.texture((img.shape[1], img.shape[0]), 1, img.tobytes(), alignment=1)
        tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
        batch = _Instanced(self.ctx, TEXT_VS, TEXT_FS, TEXT_DTYPE, "2f 1f", ("in_pos", "in_glyph"), capacity=128)
        batch.prog["u_cell"].value = tuple(float(x) for x in hc)
        batch.prog["u_atlas"].value = (float(img.shape[1]), float(img.shape[0]))
        batch.prog["u_cols"].value = float(cols)
        self._halo = (px, tex, batch)

    def width(self, s: str) -> int:
        return len(s) * self.cell[0]

    def fit(self, lines: list[str], width: float, height: float | None = None) -> list[str]:
        """``lines`` cut to a box of ``width`` x ``height`` px in this text's cell (:func:`fit_lines`;
        ``height`` None: one row per line, cut in width only)."""
        cw, ch = self.cell
        rows = len(lines) if height is None else int(height // ch)
        return fit_lines(lines, int(width // cw), rows)

    def numbers(self, n: int) -> GlyphRuns:
        """The strings "0" .. str(n - 1) in this text's cell, made once per n (disk numbers)."""
        runs = getattr(self, "_numbers", None)
        if runs is None or len(runs.strings) != n:
            runs = self._numbers = GlyphRuns([str(i) for i in range(n)], self.cell)
        return runs

    def release(self):
        self.batch.release()
        self.tex.release()
        if self._halo is not None:
            self._halo[1].release()
            self._halo[2].release()
