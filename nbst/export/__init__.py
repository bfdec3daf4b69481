"""nbst.export: motion out, for animators (``nbst export FILE --gltf OUT.glb``; docs/render.md).

Every world's file (a 2D solution, a 5 m or foul-line bowling throw, a crash file, a scene
solution) is replayed by its own room and written as glTF 2.0: one node per body with its
geometry and colours, and one animation moving each body (translation and rotation, LINEAR,
keyframes at a stated rate). Blender and any glTF viewer import it. One module each:

* :mod:`.worlds` -- each world's file replayed to body poses (:func:`~.worlds.file_motion`);
* :mod:`.mjbodies` -- a MuJoCo model's bodies and geoms as meshes, recorded states as body poses;
* :mod:`.gltf` -- the world-agnostic writer (:func:`~.gltf.write_glb`, pygltflib).

Importing this package imports neither mujoco, numba, trimesh nor pygltflib.
"""
from __future__ import annotations

import importlib

__all__ = ["write_glb", "file_motion", "BodyMotion", "gltf", "mjbodies", "worlds"]

_LAZY = {"write_glb": "gltf", "BodyMotion": "gltf", "file_motion": "worlds"}


def __getattr__(name: str) -> object:
    if name in _LAZY:
        return getattr(importlib.import_module(f"nbst.export.{_LAZY[name]}"), name)
    if name in __all__:
        return importlib.import_module(f"nbst.export.{name}")
    raise AttributeError(f"module 'nbst.export' has no attribute {name!r}")
