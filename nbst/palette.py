"""nbst's visual language: the colours and marks every picture shares.

One place for what a colour or a mark means, so the video and stills
(``nbst render``), the figures (``nbst plot``), the validation report
(``nbst validate --report``), the MuJoCo scenes (``nbst mjcf``) and the gallery
previews agree. Plain constants and small helpers: this module imports nothing,
so ``import nbst`` stays light; the drawing code (moderngl, matplotlib, MuJoCo)
imports it.

Colours are RGB floats in 0..1 (the values written into a frame or an MJCF
``rgba``, no gamma conversion); :func:`hex_color` gives matplotlib's ``#rrggbb``.

The marks (docs/render.md, "Visual language"):

* **colour = class**: cueable disks warm amber, noncueable disks cool blue,
  everywhere (fills, trails, paths, lit target rings).
* **number = disk index**, as in ``nbst simulate``'s table: on the disk at its
  start in still figures, on the moving disk in the video (``--labels``), and
  small beside each target, naming the disk that target belongs to.
* **filled disk** = the disk (at its start in still figures; where it is now in
  the video); **small hollow circle** = a target; **dotted ring** = the target's
  neighbourhood of radius R; **thin outline circle** = the final position
  (figures that show the end).
* **paths**: in the disk's class colour (figures: a per-disk shade of it),
  solid for cueable disks, dashed for noncueable ones (as the paper's broken
  arrows).
* **events**: a wall bounce is a black dot, a disk-disk collision a red star.
"""
from __future__ import annotations

__all__ = ["CUEABLE", "NONCUEABLE", "SHADE_STEPS", "DISK_MARKERS", "INK", "TARGET_INK", "RING_INK", "WALL_BOUNCE",
           "COLLISION", "WALL_BOUNCE_MARKER", "COLLISION_MARKER", "PATH_CUEABLE", "PATH_NONCUEABLE", "LEGEND_CUEABLE",
           "LEGEND_NONCUEABLE", "LEGEND_START", "LEGEND_TARGET", "LEGEND_RING", "LEGEND_FINAL", "LEGEND_PATH_CUEABLE",
           "LEGEND_PATH_NONCUEABLE", "LEGEND_WALL_BOUNCE", "LEGEND_COLLISION", "class_color", "class_colors", "shade",
           "disk_shades", "disk_marker", "units", "path_style", "rgb8", "hex_color"]

#: Cueable disks: warm amber; the paper's cue can strike them.
CUEABLE = (0.97, 0.62, 0.18)

#: Noncueable disks: cool blue; they move only when struck. Distinct from
#: CUEABLE in hue and in every channel, so a pixel tells the class.
NONCUEABLE = (0.30, 0.62, 0.96)

#: Per-disk shades in figures: disk k of a class (k counted within its class) is
#: its class colour mixed towards black by SHADE_STEPS[k % len]. Neighbouring
#: paths of one class then differ in lightness while keeping the class hue; the
#: darkest step keeps amber readable as a thin line on white. Every two steps of a
#: class are at least 15 CIELAB units apart (CIE76), also as a deuteranope sees them
#: (tests/cvd.py; the old steps 0, .38, .18, .55 gave 13.2 for blue): hue alone would
#: not tell amber from brown for a colour-blind reader.
SHADE_STEPS = (0.0, 0.42, 0.21, 0.62)

#: Per-disk marks where curves of many disks share an axes (the report's error plot):
#: disk k gets DISK_MARKERS[k % len], hollow, in its shade, so each curve is told apart
#: by shape, not only by colour. A filled dot and a star are left out: they mean a wall
#: bounce and a disk-disk collision.
DISK_MARKERS = ("o", "s", "^", "v", "D", "<", ">", "p", "h", "d", "P", "X", "8", "H")

#: Marks that belong to no class (figures on white): target markers and their
#: numbers, the dotted neighbourhood ring, disk edges.
INK = (0.0, 0.0, 0.0)
TARGET_INK = (0.15, 0.15, 0.17)
RING_INK = (0.62, 0.62, 0.64)

#: Events, in every figure that marks them (plot trajectories, the report's timeline).
WALL_BOUNCE = (0.0, 0.0, 0.0)   # black dot
COLLISION = (0.84, 0.15, 0.16)  # red star
WALL_BOUNCE_MARKER = "o"
COLLISION_MARKER = "*"

#: Line styles of paths (matplotlib names): solid cueable, dashed noncueable.
PATH_CUEABLE = "-"
PATH_NONCUEABLE = "--"

#: The words of every legend: what each mark means.
LEGEND_CUEABLE = "cueable"
LEGEND_NONCUEABLE = "noncueable"
LEGEND_START = "disk at its start (number = disk)"
LEGEND_TARGET = "target (number = disk)"
LEGEND_RING = "target neighbourhood, radius R"
LEGEND_FINAL = "final position"
LEGEND_PATH_CUEABLE = "path, cueable disk"
LEGEND_PATH_NONCUEABLE = "path, noncueable disk"
LEGEND_WALL_BOUNCE = "wall bounce"
LEGEND_COLLISION = "disk-disk collision"


def class_color(cueable) -> tuple[float, float, float]:
    """The class colour of one disk: CUEABLE or NONCUEABLE."""
    return CUEABLE if bool(cueable) else NONCUEABLE


def class_colors(cueable) -> list[tuple[float, float, float]]:
    """One class colour per disk."""
    return [class_color(c) for c in cueable]


def shade(color, step: float) -> tuple[float, float, float]:
    """``color`` mixed towards black by ``step`` (0: unchanged, 1: black)."""
    r, g, b = (float(c) * (1.0 - step) for c in color[:3])
    return r, g, b


def disk_shades(cueable) -> list[tuple[float, float, float]]:
    """One colour per disk for figures: a shade of its class colour, stepping
    through SHADE_STEPS by the disk's rank within its class."""
    out, seen = [], {True: 0, False: 0}
    for c in cueable:
        c = bool(c)
        out.append(shade(class_color(c), SHADE_STEPS[seen[c] % len(SHADE_STEPS)]))
        seen[c] += 1
    return out


def disk_marker(i: int) -> str:
    """The hollow mark of disk ``i`` in plots of many disks' curves (matplotlib marker)."""
    return DISK_MARKERS[int(i) % len(DISK_MARKERS)]


def units(x, fmt: str = "g") -> str:
    """``x`` in problem units, in words: "1 unit", "0.5 units", "2 units"."""
    return f"{format(x, fmt)} unit" + ("" if float(x) == 1.0 else "s")


def path_style(cueable) -> str:
    """Line style of a disk's path (matplotlib): solid cueable, dashed noncueable."""
    return PATH_CUEABLE if bool(cueable) else PATH_NONCUEABLE


def rgb8(color) -> tuple[int, int, int]:
    """The 8-bit RGB of a 0..1 colour (alpha dropped): what a frame or a PNG holds."""
    r, g, b = (int(round(max(0.0, min(1.0, float(x))) * 255)) for x in color[:3])
    return r, g, b


def hex_color(color) -> str:
    """``#rrggbb`` of an RGB(A) colour in 0..1 (alpha dropped), for matplotlib."""
    return "#" + "".join(f"{x:02x}" for x in rgb8(color))
