"""The picture a formation forms: the dark pixels of an image or the glyphs of a text, and the
hexagonal lattice of targets laid over them (``nbst generate --targets-from SRC``; the rest of
a formation, the starts and the assignment, is ``nbst.formation``).

Bounded whatever the source: an image file is read through ``nbst.files.read_regular`` (its
size capped), refused from its header when it claims more than :data:`MAX_IMAGE_PIXELS`, and
its lattice never lays more than :data:`MAX_LATTICE_POINTS` candidates nor spaces targets less
than :data:`MIN_LATTICE_PX` apart (a 1 x 2,000,000 line is refused in a second, not searched for
a minute). A text is checked before matplotlib draws it: printable UTF-8, not a picture's file
name (an ``.svg`` is refused rather than drawn as the letters of its name).
"""
from __future__ import annotations

import math
import os
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from nbst.domain import bad_text
from nbst.errors import InputError
from nbst.files import FileRefused, read_regular
from nbst.problem import ProblemError

__all__ = ["IMAGE_EXTENSIONS", "MAX_IMAGE_BYTES", "MAX_IMAGE_PIXELS", "OTHER_PICTURE_EXTENSIONS", "MIN_LATTICE_PX",
           "MAX_LATTICE_POINTS", "MAX_TEXT_CHARS", "TEXT_PX", "TEXT_FONT", "DARK_BELOW", "FormationError",
           "is_image_source", "image_mask", "check_text", "text_mask", "lattice_size", "hex_lattice", "lattice_for"]

#: A SRC ending in one of these is an image file; anything else is text to write.
IMAGE_EXTENSIONS = (".png", ".jpg", ".jpeg", ".gif", ".bmp", ".tif", ".tiff", ".webp")
#: Largest image file read (bytes) and largest picture decoded (pixels): a 4K frame is
#: 8.3 Mpx; the cap keeps a decoded RGBA picture under ~160 MB, and a small file that
#: claims a huge size (a decompression bomb) is refused from its header, before decoding.
MAX_IMAGE_BYTES = 64 * 1024 * 1024
MAX_IMAGE_PIXELS = 40_000_000
#: Pictures nbst does not read (vector drawings, documents, other raster formats): named, they are
#: refused rather than drawn as the text of their own name.
OTHER_PICTURE_EXTENSIONS = (".svg", ".svgz", ".pdf", ".eps", ".ps", ".ai", ".ico", ".heic", ".heif", ".avif",
                            ".jxl", ".psd", ".xcf", ".raw", ".cr2", ".nef", ".dng", ".jp2", ".tga", ".pnm", ".ppm")
#: The target lattice's least spacing (pixels): finer, two targets share a pixel and the lattice no
#: longer follows the picture (it is too small for the disks asked for).
MIN_LATTICE_PX = 1.0
#: Most candidate points one target lattice lays over the picture (its work and memory: ~50 MB): a
#: picture too thin or too scattered for the disks asked for would need more (a 1 x 2,000,000 line).
MAX_LATTICE_POINTS = 2_000_000
#: Longest text (characters): it names the problem and is rendered as one picture.
MAX_TEXT_CHARS = 200
#: Text is drawn this many pixels high per line (DejaVu Sans Bold): fine enough that the
#: target lattice, a few pixels apart for thousands of disks, follows the glyphs.
TEXT_PX = 160
TEXT_FONT: dict[str, Any] = {"family": "DejaVu Sans", "weight": "bold"}
#: A pixel is dark when its luminance (composited over white) is below this (0 black, 1 white).
DARK_BELOW = 0.5


class FormationError(InputError):
    """A formation request that cannot be met (one line, for ``nbst generate``)."""

# --------------------------------------------------------------------------- the source picture


def is_image_source(src: str) -> bool:
    """SRC names an image file when it ends in an image extension (any case)."""
    return str(src).lower().endswith(IMAGE_EXTENSIONS)


def _read_image_bytes(path: Path) -> bytes:
    """The bytes of a regular, non-empty file of at most MAX_IMAGE_BYTES (``nbst.files.read_regular``:
    a FIFO, device or folder refused without blocking), or ProblemError."""
    try:
        return read_regular(path, max_bytes=MAX_IMAGE_BYTES, what="image file", allow_empty=False)
    except FileRefused as e:
        raise ProblemError(e.path, "", e.reason) from None


def image_mask(path: str | Path) -> np.ndarray:
    """(h, w) bool: the dark pixels of the image at ``path`` (first frame; transparent pixels
    count as white). Every failure is a one-line ProblemError naming the file."""
    import imageio.v3 as iio

    p = Path(path)
    data = _read_image_bytes(p)
    ext = p.suffix.lower()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            props = iio.improps(data, index=0, extension=ext)
        except Exception as e:  # noqa: BLE001 - any decoder failure is a bad input file
            raise ProblemError(p, "", f"cannot be read as a {ext[1:].upper()} image ({_why(e)})") from None
        shape = tuple(int(k) for k in props.shape)
        if len(shape) < 2 or math.prod(shape[:2]) > MAX_IMAGE_PIXELS:
            size = "x".join(map(str, shape[1::-1])) if len(shape) >= 2 else str(shape)
            raise ProblemError(p, "", f"a {size} picture; nbst reads images of at most {MAX_IMAGE_PIXELS:,} pixels")
        try:
            img = np.asarray(iio.imread(data, index=0, extension=ext))
        except Exception as e:  # noqa: BLE001
            raise ProblemError(p, "", f"cannot be decoded as a {ext[1:].upper()} image ({_why(e)})") from None
    return _dark(img, p)


def _why(e: Exception) -> str:
    return " ".join(str(e).split())[:160] or type(e).__name__


def _dark(img: np.ndarray, p: Path) -> np.ndarray:
    if img.ndim == 3 and img.shape[0] < 8 and img.shape[-1] > 8:  # channels first (rare TIFFs)
        img = np.moveaxis(img, 0, -1)
    if img.ndim not in (2, 3) or (img.ndim == 3 and img.shape[2] not in (1, 2, 3, 4)):
        raise ProblemError(p, "", f"pixels of shape {img.shape}: not a grey, RGB or RGBA picture")
    if img.dtype == bool:
        a = img.astype(float)
    elif np.issubdtype(img.dtype, np.integer):
        a = img.astype(float) / float(np.iinfo(img.dtype).max)
    else:
        a = np.nan_to_num(img.astype(float), nan=1.0).clip(0.0, 1.0)
    if a.ndim == 2:
        a = a[:, :, None]
    c = a.shape[2]
    colour = a[:, :, :3] if c >= 3 else a[:, :, :1]
    alpha = a[:, :, c - 1] if c in (2, 4) else np.ones(a.shape[:2])
    lum = colour @ np.array([0.299, 0.587, 0.114]) if colour.shape[2] == 3 else colour[:, :, 0]
    lum = alpha * lum + (1.0 - alpha)  # over white
    return lum < DARK_BELOW


def check_text(src: str) -> None:
    """FormationError (one line) for a SRC that is not a text to write: a picture nbst does not read
    (an .svg, a .pdf: else it would draw the name), an existing file that is not an image, bytes
    that are not UTF-8 (the shell passes them as they are; Python keeps them as lone surrogates),
    or control characters other than a line break or a tab."""
    ext = os.path.splitext(src)[1].lower()
    readable = ", ".join(e[1:].upper() for e in IMAGE_EXTENSIONS)
    if ext in OTHER_PICTURE_EXTENSIONS:
        raise FormationError(f"{src}: a {ext[1:].upper()} picture, which nbst does not read; "
                             f"convert it to PNG (it reads {readable})")
    try:  # a file's name (with an extension or a folder in it), not a word that happens to name a folder
        is_file = bool(ext or os.sep in src) and os.path.lexists(src)
    except (ValueError, OSError):  # a NUL byte, a name too long: not a file
        is_file = False
    if is_file:
        raise FormationError(f"{src}: an existing file, but not an image nbst reads ({readable}, "
                             "by extension); convert it to PNG, or give the text to write")
    for k, ch in enumerate(src):
        if 0xD800 <= ord(ch) <= 0xDFFF:
            byte = f"the byte 0x{ord(ch) - 0xDC00:02x}" if 0xDC80 <= ord(ch) <= 0xDCFF else f"U+{ord(ch):04X}"
            raise FormationError(f"the target text is not valid UTF-8 ({byte} at character {k + 1}); "
                                 "give the text in UTF-8")
    why = bad_text(src, allow_newlines=True)  # the rule of every text field nbst reads
    if why:
        raise FormationError(f"the target text {why}; only printable characters, line breaks and tabs "
                             "are drawn")


def text_mask(text: str) -> np.ndarray:
    """(h, w) bool: the glyphs of ``text`` drawn by matplotlib (Agg, offscreen, no display),
    TEXT_PX pixels a line, black on white, a little white around."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    dpi = 72.0  # one point = one pixel
    fig = Figure(figsize=(1, 1), dpi=dpi, facecolor="white")
    canvas = FigureCanvasAgg(fig)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a glyph DejaVu lacks is drawn as a box, not a warning
        t = fig.text(0, 0, text, fontsize=TEXT_PX, color="black", ha="left", va="bottom", parse_math=False,
                     **TEXT_FONT)
        bb = t.get_window_extent(renderer=canvas.get_renderer())
        pad = TEXT_PX / 4
        w, h = max(bb.width, 1.0) + 2 * pad, max(bb.height, 1.0) + 2 * pad
        fig.set_size_inches(w / dpi, h / dpi)
        t.set_position((pad / w, pad / h))
        canvas.draw()
        rgba = np.asarray(canvas.buffer_rgba())
    return rgba[:, :, :3].mean(axis=2) < 255 * DARK_BELOW


# --------------------------------------------------------------------------- points


def lattice_size(shape, h: float) -> int:
    """How many candidate points the hexagonal lattice of spacing h lays over a picture of ``shape``
    (rows x columns): the work and memory of :func:`hex_lattice`, known before it runs."""
    H, W = shape
    return (int(H / (h * math.sqrt(3.0) / 2.0)) + 1) * (int(W / h) + 1)


def hex_lattice(mask: np.ndarray, h: float) -> np.ndarray:
    """(M, 2) points (px, py: pixel units, column right and row down) of a hexagonal lattice of
    spacing h whose pixel is dark, row by row. Rows are h sqrt(3) / 2 apart, odd rows shifted by
    h / 2. Vectorised over the :func:`lattice_size` candidates (callers bound it)."""
    H, W = mask.shape
    dy = h * math.sqrt(3.0) / 2.0
    ys = (np.arange(max(int(H / dy) + 1, 1)) + 0.5) * dy
    ys = ys[ys < H]
    if not ys.size:
        return np.empty((0, 2))
    shift = 0.5 * (np.arange(ys.size) % 2)
    xs = ((np.arange(int(W / h) + 1) + 0.5)[None, :] + shift[:, None]) * h  # (rows, columns)
    inside = xs < W
    cols = np.where(inside, xs, 0.0).astype(np.int64)
    keep = inside & mask[ys.astype(np.int64)[:, None], cols]
    yy = np.broadcast_to(ys[:, None], xs.shape)
    return np.stack([xs[keep], yy[keep]], axis=1)


def lattice_for(mask: np.ndarray, n: int) -> tuple[float, np.ndarray]:
    """The largest hexagonal spacing h (pixels, to 1e-6 relative) whose lattice on ``mask``
    holds at least n points, and those points. FormationError (one line) when it would need
    targets less than :data:`MIN_LATTICE_PX` apart, or more than :data:`MAX_LATTICE_POINTS`
    candidates (a picture too thin or too scattered for n disks): the work is bounded by those
    two, whatever the picture's shape."""
    area = float(mask.sum())
    ph, pw = mask.shape

    def lattice(h):
        if h < MIN_LATTICE_PX:
            raise FormationError(f"the picture's dark part ({pw:,} x {ph:,} px, {int(area):,} dark pixels) cannot hold "
                                 f"{n:,} targets at least {MIN_LATTICE_PX:g} pixel apart: use a larger picture or "
                                 f"fewer disks")
        if lattice_size(mask.shape, h) > MAX_LATTICE_POINTS:
            raise FormationError(f"the picture's dark part ({pw:,} x {ph:,} px) is too thin or too scattered for "
                                 f"{n:,} targets: their lattice would need a spacing of {h:.3g} px, "
                                 f"{lattice_size(mask.shape, h):,} candidate points (limit {MAX_LATTICE_POINTS:,}); "
                                 f"crop it to its dark part, thicken it, or use fewer disks")
        return hex_lattice(mask, h)

    h0 = math.sqrt(2.0 * area / (math.sqrt(3.0) * n))
    lo = h0
    pts = lattice(lo)
    while pts.shape[0] < n:  # shrink until it holds n (the region's outline costs points)
        lo *= 0.5
        pts = lattice(lo)
    hi = lo * 2.0
    while lattice(hi).shape[0] >= n:
        lo, hi = hi, hi * 2.0
    for _ in range(40):
        if hi - lo <= 1e-6 * lo:
            break
        mid = 0.5 * (lo + hi)
        if lattice(mid).shape[0] >= n:
            lo = mid
        else:
            hi = mid
    return lo, lattice(lo)
