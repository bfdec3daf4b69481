"""The friction kernel's scan of the cover's cells (models/bowling/lane/friction.py): it looks only at
the cells whose polar angle is near the contact's, and must find exactly the cells a scan of all
2,048 finds (the band under the contact, or the nearest cell when the band falls between cells)."""
from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("mujoco")

from nbst.models.bowling import lane  # noqa: E402
from nbst.models.bowling.lane import friction, phases  # noqa: E402
from nbst.models.bowling.lane.delivery import quat_to_mat  # noqa: E402


def test_the_cover_lattice_has_the_heights_the_scan_assumes():
    c = friction.cover_cells()
    k = np.arange(friction.N_CELLS)
    assert np.allclose(c[:, 2], 1.0 - 2.0 * (k + 0.5) / friction.N_CELLS, atol=1e-12, rtol=0)
    assert np.allclose(np.linalg.norm(c, axis=1), 1.0, atol=1e-12)


@pytest.mark.parametrize("band_in", [1.0, 0.1])  # the fitted band, and one narrower than the lattice's spacing
def test_the_kernel_trades_oil_with_exactly_the_cells_a_full_scan_finds(band_in):
    """A ball sliding on oil with a dry cover: after one step, the cells that took oil are the
    band's (cells within band_in / 2 of the contact point, by a scan of every cell; the nearest
    cell alone when none is), for 200 random orientations, poles included."""
    import mujoco

    import math

    from nbst.models.bowling import scene

    model = phases.ball_model()
    data = mujoco.MjData(model)
    rng = np.random.default_rng(7)
    q = rng.standard_normal((200, 4))
    q[:4] = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [np.cos(0.7), 0, np.sin(0.7), 0]]  # poles and the equator
    q /= np.linalg.norm(q, axis=1)[:, None]
    law = lane.OilLaw(band_in=band_in)
    cos_b = math.cos(band_in * scene.INCH / 2 / scene.BALL_RADIUS)
    cells = friction.cover_cells()
    for qi in q:
        bol = friction.BallOnLane(model, lane.Ball(), lane.OilField.fresh(lane.pattern("house")), law)
        data.qpos[:3] = [-15.0, 0.0, scene.BALL_RADIUS]
        data.qpos[3:7] = qi
        data.qvel[:6] = [7.0, 0.1, 0.0, 20.0, 30.0, 10.0]
        bol.step(data)
        c = -quat_to_mat(qi[None])[0][2]  # the contact point in the ball's frame: R^T (0, 0, -1)
        d = cells @ c
        want = np.flatnonzero(d > cos_b) if (d > cos_b).any() else np.flatnonzero(d > d.max() - 1e-12)
        assert np.array_equal(np.flatnonzero(bol.cover > 0), want), qi
