"""The warm-up compiles the bowling lane's friction kernel (nbst/warmup.py, models/bowling/lane/friction.py):
after it, a frame from the foul line compiles nothing (issue 34: every first bowl command compiled it)."""
from __future__ import annotations

import subprocess
import sys
import textwrap

import pytest

pytest.importorskip("mujoco")

_PROBE = textwrap.dedent("""
    from nbst import warmup
    from nbst.models.bowling.lane import frame
    from nbst.models.bowling.lane.delivery import Delivery
    from nbst.models.bowling.lane.friction import contact_step
    cold = warmup.is_cold(*warmup.lane_kernels())
    warmup.warm_lane()
    after = warmup.is_cold(*warmup.lane_kernels())
    n = len(contact_step.signatures)
    frame.run_frame(Delivery(at="foul", board=20.0, angle=2.0), "house")  # what `nbst bowl frame` runs
    print(cold, after, n, len(contact_step.signatures))
""")


@pytest.mark.slow
def test_the_warm_up_compiles_the_lane_kernel_that_a_frame_calls(tmp_path):
    """On an empty numba cache the kernel is cold; warm_lane compiles it (warm after); a full frame
    (the ball, then the pins) then calls the one signature the warm-up compiled, no other."""
    import os

    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path))
    r = subprocess.run([sys.executable, "-c", _PROBE], capture_output=True, text=True, timeout=600, env=env)
    assert r.returncode == 0, r.stderr
    assert r.stdout.split() == ["True", "False", "1", "1"]


@pytest.mark.slow
def test_warm_all_runs_the_lane_warm_up(monkeypatch):
    """``python -m nbst.warmup`` (scripts/setup.sh) reaches the lane's kernel: warm_all calls warm_lane."""
    from nbst import warmup

    calls = []
    monkeypatch.setattr(warmup, "warm_lane", lambda: calls.append(1))
    lines = []
    warmup.warm_all(lines.append)
    assert calls == [1] and any(s.startswith("bowling lane ready") for s in lines)
