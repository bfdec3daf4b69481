"""nbst.render: headless moderngl rendering of a choreography to frames, MP4/GIF
video, and matplotlib figures in the manner of the paper.

Imported as ``nbst.render``: ``nbst/render`` is a link to this folder, in the checkout and installed alike.

Rooms: ``nbst.render.core`` (the GL context, the 2D shapes and text, the solids, the shaders, the
cameras, the style, frame times and the video writer) under the worlds' rooms
``nbst.render.bowling`` (the 5 m deck video, the foul-line lane video, the recorded throw, the path
plot) and ``nbst.render.crash`` (the crash video, its motion, scene and readout). The disk
pictures stay at the top: ``scene2d``, ``scene3d`` and ``motion2d`` (the 2D/3D disk videos),
``figures``, ``report`` and ``report_figures`` (matplotlib and the HTML report).

Importing it does not import moderngl or imageio; the submodules that need them do, and the
entry points below load their module on first use:

* :func:`create_context` (``nbst.render.core.gl``): the one headless GL context; :class:`RenderError`
  (``nbst.errors``, loaded at once);
* :func:`render_video`, :func:`write_png` (``nbst.render.core.video``): frames to MP4/GIF, one frame to PNG;
* :func:`plot_problem`, :func:`plot_trajectories`, :func:`save_figure` (``nbst.render.figures``);
* :func:`report_html` (``nbst.render.report``): the validation report;
* :func:`render_motion` (``nbst.render.bowling.deck``), :func:`record_throw`
  (``nbst.render.bowling.throw``), :func:`render_throw` (``nbst.render.bowling.lane``): bowling;
* :func:`render_crash` (``nbst.render.crash.video``): a crash file's video.
"""
from __future__ import annotations

import importlib

from nbst.errors import RenderError

__all__ = ["RenderError", "create_context", "render_video", "write_png", "plot_problem", "plot_trajectories",
           "save_figure", "report_html", "render_motion", "record_throw", "render_throw", "render_crash"]

_LAZY = {"create_context": "core.gl", "render_video": "core.video", "write_png": "core.video",
         "plot_problem": "figures", "plot_trajectories": "figures", "save_figure": "figures",
         "report_html": "report", "render_motion": "bowling.deck", "record_throw": "bowling.throw",
         "render_throw": "bowling.lane", "render_crash": "crash.video"}


def __getattr__(name):
    if name in _LAZY:
        return getattr(importlib.import_module(f"nbst.render.{_LAZY[name]}"), name)
    raise AttributeError(f"module 'nbst.render' has no attribute {name!r}")
