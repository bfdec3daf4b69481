"""Every colour, size and rendering choice of nbst.render in one place, each with why.

Colours are 0..1 RGB(A) floats, as GL takes them; ``rgb8`` gives the 8-bit
values a frame holds (tests look for them). The class colours and the meaning
of every mark are shared with the figures, the report and the MuJoCo scenes:
they live in :mod:`nbst.palette`.
"""
from __future__ import annotations

from nbst import palette

__all__ = ["AMBIENT", "BACKGROUND", "BOX_FLOOR", "BOX_WALL", "BOX_WALL_FRAC", "CAMERA_ELEVATION_DEG",
           "CAMERA_FOV_DEG", "CUEABLE", "DEFAULT_FPS", "DEFAULT_SIZE", "DISK_RIM_FRAC", "DISK_RIM_SHADE", "GHOST",
           "GHOST_LABEL", "GHOST_PX", "GIF_FPS", "GIF_SIZE", "LABEL", "LABELS_MIN_DISK_PX", "LABEL_FIT", "LABEL_FRAC",
           "LEGEND_PITCH", "LEGEND_TEXT_FRAC", "LIGHT_DIR", "MARGIN_FRAC", "MARKER", "MARKER_FRAC", "MARKER_HALO",
           "MARKER_HALO_PX", "MARKER_INSIDE_MAX", "MARKER_LABEL_GAP_PX", "MARKER_OUTSIDE_GAP_PX", "MARKER_OUTSIDE_PX",
           "MARKER_PX", "MAX_TRAIL_POINTS", "MIN_BOX_SHARE", "MIN_DISK_PX", "MIN_LEGEND_PX", "MIN_MARKER_PX",
           "MIN_READOUT_PX", "MIN_TRAIL_PX", "MSAA_SAMPLES", "NONCUEABLE", "PUCK_HEIGHT_FRAC", "QUEUE_FRAMES", "RAIL",
           "RAIL_HEIGHT_FRAC", "RING_DIM", "RING_DIM_PX", "RING_LIT_ALPHA", "RING_LIT_FILL_ALPHA", "RING_LIT_PX",
           "SWS_FLAGS", "TABLE", "TARGET_LABEL", "TARGET_LABEL_FRAC", "TEXT", "TEXT_DIM", "TEXT_FRAC", "TEXT_HALO",
           "TRAIL_ALPHA", "TRAIL_SAMPLE_BUDGET", "TRAIL_SECONDS", "TRAIL_WIDTH_FRAC", "X264_CRF", "X264_PRESET",
           "disk_colors", "rgb8", "trail_samples"]

#: Frame background outside the box. Dark, so trails can be drawn with MAX
#: blending (a trail colour must exceed the background in every channel).
BACKGROUND = (0.055, 0.063, 0.078)

#: Floor of the box: a shade lighter than the background so the walls read.
BOX_FLOOR = (0.098, 0.110, 0.133)

#: Walls (the box outline).
BOX_WALL = (0.62, 0.66, 0.72)

#: Wall thickness, as a fraction of the frame's shorter side (4 px at 720p; at least 2 px).
BOX_WALL_FRAC = 0.0055

#: Disk colours by class (cueable warm amber, noncueable cool blue): the
#: palette's, so every picture nbst makes agrees.
CUEABLE = palette.CUEABLE
NONCUEABLE = palette.NONCUEABLE

#: Disk rim: the disk's colour times this, so touching disks stay separable.
DISK_RIM_SHADE = 0.55

#: Rim width, as a fraction of the on-screen disk radius (at least 1 px).
DISK_RIM_FRAC = 0.12

#: Smallest on-screen disk radius in px: a radius-1 disk (diamond-s14-tiny)
#: would be under a pixel at 720p; drawn disks are never smaller than this.
MIN_DISK_PX = 3.0

#: Target marker: a small hollow circle (the paper's Figure 1), radius as a
#: fraction of the disk radius, at least MIN_MARKER_PX. Drawn above the disks, in a
#: dark halo (MARKER_HALO, MARKER_HALO_PX wide on each side), so a disk never hides a
#: target: not a disk passing over it at t = 0, not its own disk resting on it at the
#: end. Where a disk's number is written on the disk (--labels), the marker is widened
#: to clear the digits (by MARKER_LABEL_GAP_PX) so a disk on its target stays readable.
MARKER_FRAC = 0.35
MIN_MARKER_PX = 3.0
MARKER = (0.85, 0.87, 0.90, 0.9)
MARKER_PX = 1.5
MARKER_HALO = (0.055, 0.063, 0.078, 0.75)
MARKER_HALO_PX = 1.0
MARKER_LABEL_GAP_PX = 1.5
#: A marker inside a small disk would hide it: the smallest marker (MIN_MARKER_PX and its
#: halo) covers most of a disk under 8 px in radius (1,000 disks at 720p are 4.1 px), so a
#: disk resting on its target showed as a grey dot. Where the marker with its halo would reach
#: past this fraction of the disk's radius, the marker is instead a thin ring just outside the
#: disk's rim (MARKER_OUTSIDE_GAP_PX clear of it, MARKER_OUTSIDE_PX wide), drawn *under* the
#: disks with the static layer: a disk resting on its target lies inside its ring and hides
#: none of it, and no target covers a passing disk (with a halo, drawn above the disks, 1,000
#: such rings had covered a quarter of the floor and the centres of 28% of the disks).
MARKER_INSIDE_MAX = 0.5
MARKER_OUTSIDE_GAP_PX = 1.0
MARKER_OUTSIDE_PX = 1.2

#: Target neighbourhood ring of radius R while its disk is outside: faint.
RING_DIM = (0.55, 0.58, 0.64, 0.22)
RING_DIM_PX = 1.2

#: ... and while its disk is inside (lit): the disk's colour, thicker, with a
#: faint fill of the neighbourhood so a lit ring reads at a glance.
RING_LIT_ALPHA = 0.95
RING_LIT_FILL_ALPHA = 0.10
RING_LIT_PX = 2.6

#: Trails: how many seconds of path stay visible, the alpha at the disk, and
#: the width as a fraction of the on-screen disk radius (at least 1.5 px).
TRAIL_SECONDS = 1.2
TRAIL_ALPHA = 0.9
TRAIL_WIDTH_FRAC = 0.36
MIN_TRAIL_PX = 1.5

#: Most keyframes in a trail window; beyond it the path is sampled uniformly
#: (a jammed cluster can have thousands of events in TRAIL_SECONDS).
MAX_TRAIL_POINTS = 256

#: MuJoCo ghosts (``--source both``): a white ring at the disk's radius, on top
#: of the analytic disk, so any drift between the two shows as an offset ring.
GHOST = (0.95, 0.97, 1.0, 0.9)
GHOST_PX = 2.0
#: With --labels, each ring carries its disk's number (lower right of the ring, white).
GHOST_LABEL = (0.95, 0.97, 1.0)

#: Text (time readout, legend).
TEXT = (0.90, 0.92, 0.95)
TEXT_DIM = (0.60, 0.64, 0.70)

#: Halo behind text drawn over the scene (target and ring numbers, disk numbers beside
#: their disks): the background colour, one pixel around every glyph.
TEXT_HALO = BACKGROUND

#: Disk labels (``--labels``): dark digits on the disk, text height as a fraction of
#: the disk's on-screen radius, never under MIN_LABEL_PX: at 12 px a digit's ink is 9 px
#: tall and "0" no longer reads as "8" (at 8 px it was 6 px). A number that does not fit
#: inside its disk at that size is written beside the disk instead (upper left, in the
#: disk's colour over a dark halo), so numbers are legible at every disk size.
LABEL = (0.08, 0.08, 0.10)
LABEL_FRAC = 0.95
MIN_LABEL_PX, MAX_LABEL_PX = 12, 22
#: ``nbst render`` without --labels or --no-labels numbers the disks only where the numbers
#: stay legible: when every disk is at least LABELS_MIN_DISK_PX across in the frame (its
#: drawn diameter). A number is never under MIN_LABEL_PX (12 px), so on a smaller disk it
#: would sit beside the disk, larger than the disk itself; with hundreds of such disks
#: (1,000 radius-1 disks at 720p are 9 px across) the numbers bury the motion.
LABELS_MIN_DISK_PX = 12.0
#: A number fits on its disk when the half-diagonal of its digits' box is at most this
#: fraction of the disk's on-screen radius (the rest is rim and air).
LABEL_FIT = 0.92

#: Text height as a fraction of the frame's shorter side (20 px at 720p); the readout
#: shrinks to fit the margin beside the box, never under MIN_READOUT_PX: where that
#: does not fit, the box moves right (and shrinks) to make room. One fact a line.
TEXT_FRAC = 0.028
MIN_READOUT_PX = 11
MIN_BOX_SHARE = 0.7

#: Target numbers (``--labels``): each target's disk index, small and dim, just
#: above and right of its marker (as in the figures); text height as a fraction
#: of the frame's shorter side, clamped.
TARGET_LABEL = TEXT_DIM
TARGET_LABEL_FRAC = 0.017
MIN_TARGET_LABEL_PX, MAX_TARGET_LABEL_PX = 12, 14

#: Legend under the time readout (top left): swatches for the classes, the target
#: mark and MuJoCo rings; text height as a fraction of the frame's shorter side,
#: line pitch in text heights. Drawn only where it fits beside the box.
LEGEND_TEXT_FRAC = 0.022
MIN_LEGEND_PX = 10
LEGEND_PITCH = 1.35

#: Margin around the box, as a fraction of the frame's shorter side.
MARGIN_FRAC = 0.04

#: Defaults of ``nbst render``.
DEFAULT_FPS = 60
DEFAULT_SIZE = (1280, 720)

#: GIFs store frame delays in centiseconds and browsers slow delays under 2 cs
#: down to 10 cs, so 60 fps cannot play as 60 fps: GIFs default to 25 fps (4 cs)
#: and a smaller frame (GIFs are stored uncompressed-ish and palette-limited).
GIF_FPS = 25
GIF_SIZE = (640, 360)

#: H.264 settings: x264 ``veryfast`` keeps encoding ahead of rendering on a
#: laptop CPU; CRF 20 is visually lossless for flat-shaded graphics.
X264_PRESET = "veryfast"
X264_CRF = 20

#: ffmpeg's RGB -> yuv420p scaler: bilinear chroma halves the encoder's time
#: against the default bicubic (5 ms a frame at 720p) with no visible change on
#: flat-shaded frames.
SWS_FLAGS = "bilinear"

#: Frames in flight between the renderer and the encoder thread: enough to
#: absorb jitter, few enough to bound memory (4 x 2.7 MB at 720p).
QUEUE_FRAMES = 4

#: 3D view: table colours, camera and light.
TABLE = (0.10, 0.30, 0.20)
RAIL = (0.36, 0.22, 0.12)
PUCK_HEIGHT_FRAC = 0.6  # puck height as a fraction of its radius
RAIL_HEIGHT_FRAC = 0.05  # rail height as a fraction of the box's shorter side
CAMERA_FOV_DEG = 38.0
CAMERA_ELEVATION_DEG = 52.0  # above the table plane
LIGHT_DIR = (-0.35, -0.5, 0.8)  # towards the light, world axes (z up)
AMBIENT = 0.35
MSAA_SAMPLES = 4


def rgb8(c) -> tuple[int, int, int]:
    """The 8-bit RGB a frame holds for an opaque colour ``c``."""
    return palette.rgb8(c)


def disk_colors(cueable) -> list[tuple[float, float, float]]:
    """One fill colour per disk: CUEABLE or NONCUEABLE."""
    return palette.class_colors(cueable)


#: Trails of a motion known only at sample times (a MuJoCo replay): each disk's last
#: TRAIL_SECONDS sampled this many times in all (at most 64 steps a disk, at least 12), so
#: 1,000 disks cost 16,384 capsules a frame, not 64,000 (exact motions bend at their own
#: events instead, and need no samples).
TRAIL_SAMPLE_BUDGET = 16_384


def trail_samples(n: int) -> int:
    """Steps per disk of a sampled trail for ``n`` disks (TRAIL_SAMPLE_BUDGET in all, 12..64)."""
    return int(min(64, max(12, TRAIL_SAMPLE_BUDGET // max(1, int(n)))))
