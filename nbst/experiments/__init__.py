"""Experiments: many independent searches, in parallel or on a Dask cluster, and their
tables and figures (the paper's Figures 5-8, ablations, comparisons with the baselines).

* ``nbst.experiments.runs``: run specs, the run cache, tables;
* ``nbst.experiments.runs.plots``: the figures (PNG and SVG).

Layer: above ``nbst.solvers``; only the command line imports it.
"""
