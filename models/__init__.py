"""nbst.models: MuJoCo scenes generated from a problem and its solution, and
cross-validation of the analytic simulator against MuJoCo.

Imported as ``nbst.models``: ``nbst/models`` is a link to this folder, in the checkout and installed alike.
Importing it does not import mujoco; the submodules that need it do.
"""
from __future__ import annotations

import importlib

__all__ = ["rollout", "run_mujoco", "build_spec", "build_model", "scene_xml", "validate"]

_LAZY = {"rollout": "nbst.models.mjrun", "run_mujoco": "nbst.models.mjrun", "build_spec": "nbst.models.scene",
         "build_model": "nbst.models.scene", "scene_xml": "nbst.models.scene", "validate": "nbst.models.validate"}


def __getattr__(name):
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'nbst.models' has no attribute {name!r}")
