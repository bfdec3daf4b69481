"""The built-in problems, shipped unchanged from the canonical benchmark set, registered once.

Each is addressable by ``nbst.load_problem(NAME)``; ``PROBLEMS`` (a ``nbst.registry.Registry``)
maps NAME to its file here (``NAME.json``), in the order ``nbst problems`` lists them. The
command line, the experiments and the docs read the names from it. A new built-in is a JSON
file here and one line below.
"""
from __future__ import annotations

from nbst.registry import Registry

__all__ = ["PROBLEMS"]

PROBLEMS: Registry[str] = Registry("built-in problem")
PROBLEMS.register("diamond-s14", "diamond-s14.json",
                  help="14 disks from a diamond to an S (the paper's Figure 1)")
PROBLEMS.register("diamond-s14-tiny", "diamond-s14-tiny.json",
                  help="diamond-s14 with near-zero radius: disks barely interact (the paper's footnote 4)")
PROBLEMS.register("over5", "over5.json",
                  help="overconstrained: 2 cueable and 3 noncueable disks; a zero-cost solution exists")
