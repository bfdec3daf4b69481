import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))  # tests/naive.py

from nbst.problem import problem_from_dict  # noqa: E402


def make_problem(starts, radii=10.0, *, box=(800.0, 800.0), t_final=5.0, R=75.0, masses=None, cueable=None,
                 targets=None, name="test"):
    """A Problem from plain lists (targets default to the starts)."""
    n = len(starts)
    radii = np.broadcast_to(np.asarray(radii, float), (n,))
    disks = []
    for i in range(n):
        d = {"start": list(map(float, starts[i])),
             "target": list(map(float, (targets[i] if targets is not None else starts[i]))),
             "radius": float(radii[i])}
        if masses is not None:
            d["mass"] = float(masses[i])
        if cueable is not None:
            d["cueable"] = bool(cueable[i])
        disks.append(d)
    return problem_from_dict({"name": name, "box": list(box), "t_final": t_final, "target_radius": R,
                              "disks": disks})


@pytest.fixture
def mk():
    return make_problem
