"""The shared GL core of nbst.render, under every world's room (the disks, bowling, the crash):
the one headless GL context and frame target (:mod:`.gl`), the 2D shapes and text
(:mod:`.shapes`), the 3D solids (:mod:`.solids`) and every MuJoCo geom type's triangles (:mod:`.geoms`), shaders (:mod:`.shaders`) and cameras
(:mod:`.camera`), the look (:mod:`.style`), the frame times (:mod:`.times`) and the video and PNG
writers (:mod:`.video`). Importing it loads none of them (nor moderngl)."""
from __future__ import annotations

__all__: list[str] = []
