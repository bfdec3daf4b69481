"""The ``nbst`` command line: one module per group of subcommands, each a thin layer
that parses arguments, calls the rooms below (search, solvers, experiments, models,
render) and writes files. ``nbst.cli.main`` is the entry point; ``nbst.cli.args`` holds
the argparse types and helpers that every subcommand shares.
"""
from __future__ import annotations

from nbst.cli.main import build_parser, main

__all__ = ["build_parser", "main"]
