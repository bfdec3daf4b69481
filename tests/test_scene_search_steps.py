"""The one-body scene search's restart steps: an aimed body (a place to be, a free flight) starts
its searching CMA-ES restarts at ONE_BODY_AIMED_STEP of the engine's step; a body that is not
aimed (no place: bank-shot; a rolling ball: billiards) keeps the engine's schedule."""
from __future__ import annotations

import numpy as np
import pytest

import nbst.scene.search as search
from nbst.models.mjsearch.engine import SCHEDULE
from nbst.scene.rollout import SceneSim
from nbst.scene.scenefile import load_fates
from nbst.seeds import check_random_state


@pytest.mark.parametrize("name, aimed", [("egg-in-cup", True), ("bank-shot", False), ("billiards", False)])
def test_an_aimed_body_starts_its_searching_restarts_at_a_smaller_step(name, aimed, monkeypatch):
    f, model = load_fates(name)
    seen: dict = {}

    class Made(Exception):
        pass

    def spy(*a, **k):  # the engine's options, then stop before any rollout
        seen.update(k)
        raise Made
    monkeypatch.setattr(search, "Engine", spy)
    with SceneSim(f, model) as sim:
        assert search._Scene(sim, 1, ()).aimable(0) is aimed
        with pytest.raises(Made):
            search.signature_search(sim, rng=check_random_state(1), max_rollouts=8)
    assert seen["cma"] and seen["cma_by_key"]  # the one-body search's CMA-ES restarts
    schedule = seen.get("schedule", SCHEDULE)
    want = [(s, fac * (search.ONE_BODY_AIMED_STEP if aimed else 1.0)) for s, fac in SCHEDULE]
    assert [s for s, _ in schedule] == [s for s, _ in want]
    np.testing.assert_allclose([fac for _, fac in schedule], [fac for _, fac in want], rtol=0, atol=1e-12)
    assert "polish" not in seen  # polishing keeps the engine's steps
    assert 0.0 < search.ONE_BODY_AIMED_STEP < 1.0
