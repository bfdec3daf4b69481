"""Experiments: many independent searches, in parallel or on a Dask cluster, and their
tables and figures (the paper's Figures 5-8, ablations, comparisons with the baselines).

* ``nbst.experiments.runs``: run specs, the run cache, tables (:func:`make_specs`,
  :func:`run_specs`, :func:`entries`);
* ``nbst.experiments.plots``: the figures (PNG and SVG) and the CSV and Markdown tables.

Layer: above ``nbst.solvers``; only the command line imports it. Importing this package imports
neither module; the names below load theirs on first use.
"""
from __future__ import annotations

import importlib

__all__ = ["RunSpec", "entries", "make_specs", "run_specs", "runs", "plots"]

_LAZY = {"RunSpec": "runs", "entries": "runs", "make_specs": "runs", "run_specs": "runs"}


def __getattr__(name):
    if name in _LAZY:
        return getattr(importlib.import_module(f"nbst.experiments.{_LAZY[name]}"), name)
    if name in ("runs", "plots"):
        return importlib.import_module(f"nbst.experiments.{name}")
    raise AttributeError(f"module 'nbst.experiments' has no attribute {name!r}")
