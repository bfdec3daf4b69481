"""Any MJCF drawn with moderngl: a scene solution's motion (``nbst render SOL.json``, docs/scene.md).

One module each, top to bottom: :mod:`.video` (the frames: every visible geom in its model's
colours, lit and shadowed, the fates drawn, the readout; the writer), :mod:`.framing` (the default
camera), :mod:`.readout` (asked vs happened, text lines; the GLSL is the core's,
:mod:`nbst.render.core.shaders`),
:mod:`.motion` (the solution replayed, the poses at the frames' times, the first touches). Each geom type's triangles are the core's
(:mod:`nbst.render.core.geoms`). Importing it loads none of them (nor moderngl or MuJoCo)."""
from __future__ import annotations

__all__: list[str] = []
