"""nbst.render: headless moderngl rendering of a choreography to frames, MP4/GIF
video, and matplotlib figures in the manner of the paper.

Imported as ``nbst.render``: ``nbst/render`` is a link to this folder, in the checkout and installed alike.
Importing it does not import moderngl or imageio; the submodules that need them do, and the
entry points below load their module on first use:

* :func:`create_context` (``nbst.render.gl``): the one headless GL context; :class:`RenderError`
  (``nbst.errors``, loaded at once);
* :func:`render_video`, :func:`write_png` (``nbst.render.video``): frames to MP4/GIF, one frame to PNG;
* :func:`plot_problem`, :func:`plot_trajectories`, :func:`save_figure` (``nbst.render.figures``);
* :func:`report_html` (``nbst.render.report``): the validation report;
* :func:`render_motion` (``nbst.render.bowling``), :func:`record_throw`
  (``nbst.render.bowling_throw``), :func:`render_throw` (``nbst.render.bowling_lane``): bowling;
* :func:`render_crash` (``nbst.render.crash``): a crash file's video.
"""
from __future__ import annotations

import importlib

from nbst.errors import RenderError

__all__ = ["RenderError", "create_context", "render_video", "write_png", "plot_problem", "plot_trajectories",
           "save_figure", "report_html", "render_motion", "record_throw", "render_throw", "render_crash"]

_LAZY = {"create_context": "gl", "render_video": "video", "write_png": "video",
         "plot_problem": "figures", "plot_trajectories": "figures", "save_figure": "figures",
         "report_html": "report", "render_motion": "bowling", "record_throw": "bowling_throw",
         "render_throw": "bowling_lane", "render_crash": "crash"}


def __getattr__(name):
    if name in _LAZY:
        return getattr(importlib.import_module(f"nbst.render.{_LAZY[name]}"), name)
    raise AttributeError(f"module 'nbst.render' has no attribute {name!r}")
