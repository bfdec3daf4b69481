"""Colour-vision-deficiency views of pictures: what a deuteranope (no green cones, the
commonest colour blindness, ~5% of men) sees of a PNG or a colour.

Machado, Oliveira & Fernandes (2009), "A physiologically-based model for simulation of
color vision deficiency", severity 1.0 deuteranopia matrix, applied in linear RGB (sRGB
decoded, transformed, encoded again).

    python tests/cvd.py report-figure.png deuteranopia.png     # look at it with any viewer

Tests import :func:`deuteranopia` and :func:`delta_e` to check that colours that must
differ still differ in that view.
"""
from __future__ import annotations

import sys

import numpy as np

#: Machado et al. 2009, deuteranopia, severity 1.0 (linear RGB).
DEUTERANOPIA = np.array([[0.367322, 0.860646, -0.227968],
                         [0.280085, 0.672501, 0.047413],
                         [-0.011820, 0.042940, 0.968881]])


def _to_linear(c):
    c = np.asarray(c, float)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def _to_srgb(c):
    c = np.clip(c, 0.0, 1.0)
    return np.where(c <= 0.0031308, 12.92 * c, 1.055 * c ** (1 / 2.4) - 0.055)


def deuteranopia(rgb):
    """Colours (..., 3) in 0..1 (floats) or 0..255 (uint8) as a deuteranope sees them, same type."""
    a = np.asarray(rgb)
    is8 = a.dtype == np.uint8
    x = a.astype(float) / 255.0 if is8 else a.astype(float)
    y = _to_srgb(_to_linear(x[..., :3]) @ DEUTERANOPIA.T)
    return np.round(y * 255).astype(np.uint8) if is8 else y


def lab(rgb):
    """CIELAB (D65) of sRGB colours (..., 3) in 0..1."""
    lin = _to_linear(np.asarray(rgb, float)[..., :3])
    m = np.array([[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]])
    xyz = lin @ m.T / np.array([0.95047, 1.0, 1.08883])
    f = np.where(xyz > (6 / 29) ** 3, np.cbrt(xyz), xyz / (3 * (6 / 29) ** 2) + 4 / 29)
    return np.stack([116 * f[..., 1] - 16, 500 * (f[..., 0] - f[..., 1]), 200 * (f[..., 1] - f[..., 2])], axis=-1)


def delta_e(a, b) -> float:
    """CIE76 colour difference of two sRGB colours in 0..1 (about 2: just noticeable; 10+: clearly apart)."""
    return float(np.linalg.norm(lab(a) - lab(b), axis=-1))


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) != 2:
        print("usage: python tests/cvd.py IN.png OUT.png  (OUT: IN as a deuteranope sees it)", file=sys.stderr)
        return 2
    from PIL import Image
    with Image.open(argv[0]) as im:
        a = np.asarray(im.convert("RGB"))
    Image.fromarray(deuteranopia(a)).save(argv[1])
    return 0


if __name__ == "__main__":
    sys.exit(main())
