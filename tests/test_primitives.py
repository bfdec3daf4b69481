"""nbst.sim.primitives against the slow references of tests/naive.py, and the simulator
against the naive event simulator at the lane-padding edges (N = 16, 17, 33, 63)."""
import math

import numpy as np
import pytest
from naive import _pair_time, _wall_time, fold as naive_fold, impulse, mirror_image, next_event

from nbst.sim import alloc_work, run
from nbst.sim.primitives import (IMPACT_NONE, IMPACT_PAIR, IMPACT_WALL, contact_normal, elastic_impulse, fold,
                                 images, impulse_share, mirror, pair_tau, replay_event, strike_ratio,
                                 transferred_speed, wall_tau)

RNG = np.random.default_rng(20260)


def test_pair_tau_matches_the_textbook_root_and_respects_the_horizon():
    for _ in range(2000):
        p1, p2 = RNG.uniform(0, 100, 2), RNG.uniform(0, 100, 2)
        v1, v2 = RNG.normal(0, 20, 2), RNG.normal(0, 20, 2)
        s = RNG.uniform(1, 10)
        if np.linalg.norm(p2 - p1) <= s:
            continue
        ref = _pair_time(p1, v1, p2, v2, s)
        d, dv = p2 - p1, v2 - v1
        got = pair_tau(d[0], d[1], dv[0], dv[1], s, math.inf)
        if math.isinf(ref):
            assert math.isinf(got)
        else:
            assert got == pytest.approx(ref, rel=1e-9, abs=1e-12)
            # at the predicted time the centres are exactly the contact distance apart
            assert np.linalg.norm(d + dv * got) == pytest.approx(s, rel=1e-9)
            h = RNG.uniform(0, 2 * ref)
            within = pair_tau(d[0], d[1], dv[0], dv[1], s, h)
            assert (within == got) if ref <= h * (1 - 1e-12) else (math.isinf(within) or ref <= h * (1 + 1e-12))


def test_pair_tau_is_zero_for_round_off_overlap_and_inf_when_separating():
    assert pair_tau(1.9, 0.0, -1.0, 0.0, 2.0, math.inf) == 0.0  # overlapping, approaching
    assert math.isinf(pair_tau(1.9, 0.0, 1.0, 0.0, 2.0, math.inf))  # overlapping, separating
    assert math.isinf(pair_tau(5.0, 0.0, 0.0, 1.0, 2.0, math.inf))  # moving sideways


def test_wall_tau_matches_the_reference_wall_and_time():
    W, H = 300.0, 200.0
    for _ in range(2000):
        r = RNG.uniform(1, 20)
        p = np.array([RNG.uniform(r, W - r), RNG.uniform(r, H - r)])
        v = RNG.normal(0, 50, 2)
        t_ref, w_ref = _wall_time(p, v, r, W, H)
        t, w = wall_tau(p[0], p[1], v[0], v[1], r, W, H)
        assert t == pytest.approx(t_ref, rel=1e-12)
        assert w == w_ref or t == pytest.approx(_wall_time(p, v * [1, 0], r, W, H)[0], rel=1e-12)


def test_elastic_impulse_matches_the_textbook_and_conserves_momentum_and_energy():
    for _ in range(2000):
        pi, vi, vj = RNG.uniform(0, 10, 2), RNG.normal(0, 10, 2), RNG.normal(0, 10, 2)
        pj = pi + RNG.normal(0, 1, 2)
        mi, mj = RNG.uniform(0.1, 10, 2)
        n = (pj - pi) / np.linalg.norm(pj - pi)
        got = np.array(elastic_impulse(vi[0], vi[1], vj[0], vj[1], n[0], n[1], mi, mj))
        ri, rj = impulse(vi, vj, pi, pj, mi, mj)
        np.testing.assert_allclose(got, np.r_[ri, rj], rtol=1e-12, atol=1e-12)
        p_before = mi * vi + mj * vj
        p_after = mi * got[:2] + mj * got[2:]
        np.testing.assert_allclose(p_after, p_before, rtol=1e-12, atol=1e-11)
        e_before = mi * vi @ vi + mj * vj @ vj
        assert mi * got[:2] @ got[:2] + mj * got[2:] @ got[2:] == pytest.approx(e_before, rel=1e-12)
    # head-on: a disk at rest leaves with impulse_share(striker, struck) times the striker's speed
    vi0 = 3.0
    out = elastic_impulse(vi0, 0.0, 0.0, 0.0, 1.0, 0.0, 2.0, 5.0)
    assert out[2] == pytest.approx(impulse_share(2.0, 5.0) * vi0, rel=1e-15)
    assert impulse_share(1.0, 1.0) == 1.0
    for ms, mt in ((2.0, 5.0), (0.3, 0.3), (7.0, 1.5)):
        assert transferred_speed(vi0, ms, mt) == pytest.approx(impulse_share(ms, mt) * vi0, rel=1e-15)
        assert strike_ratio(ms, mt) == pytest.approx(1.0 / impulse_share(ms, mt), rel=1e-15)


def test_mirror_matches_repeated_reflection_and_fold_undoes_it():
    lo, hi = 3.0, 17.0
    for k in range(-7, 8):
        for u in (lo, 5.5, 12.25, hi):
            assert mirror(u, k, lo, hi) == pytest.approx(mirror_image(u, k, lo, hi), abs=1e-12)
            assert fold(mirror(u, k, lo, hi), lo, hi) == pytest.approx(u, abs=1e-12)
    # fold is the lone-disk motion of the naive reference (walls at 0 and L, radius r)
    r, L = 2.0, 20.0
    for x0, v, t in ((5.0, 13.0, 7.3), (17.0, -9.0, 4.1), (10.0, 0.5, 1.0)):
        assert fold(x0 + v * t, r, L - r) == pytest.approx(naive_fold(x0, v, t, r, L), abs=1e-12)


def test_images_are_every_image_within_the_bounce_range():
    for lo_b, hi_b in ((0, 0), (0, 1), (0, 5), (1, 3), (2, 2)):
        got = images(lo_b, hi_b)
        ref = [(kx, ky) for kx in range(-hi_b, hi_b + 1) for ky in range(-hi_b, hi_b + 1)
               if lo_b <= abs(kx) + abs(ky) <= hi_b]
        assert [tuple(x) for x in got] == ref
    assert images(0, 5).shape == (61, 2)


def _read_only(a):
    """A read-only float64 copy: the arrays a Problem hands the kernel (the signature the warm-up compiled)."""
    a = np.array(a, dtype=np.float64)
    a.flags.writeable = False
    return a


def _record(x0, v0, radius, mass, W, H, t_final, cap=20000):
    n = len(x0)
    x0, v0, radius, mass = (_read_only(a) for a in (x0, v0, radius, mass))
    ev_t, ev_i, ev_j, ev_s = np.empty(cap), np.empty(cap, np.int64), np.empty(cap, np.int64), np.empty((cap, 8))
    final, vel = np.empty((n, 2)), np.empty((n, 2))
    st, n_ev, n_dd, n_w = run(x0, v0, radius, mass, W, H, t_final, alloc_work(n), final, vel, 10 ** 6, ev_t, ev_i,
                              ev_j, ev_s)
    assert st == 0
    return final, vel, n_ev, n_dd, n_w, ev_t, ev_i, ev_j, ev_s


def _sparse_motion(n, seed, box=(2000.0, 1500.0), r=6.0, speed=900.0):
    """n small fast disks on a jittered grid: hundreds of wall bounces, tens of contacts."""
    rng = np.random.default_rng(seed)
    W, H = box
    cols = int(math.ceil(math.sqrt(n * W / H)))
    rows = int(math.ceil(n / cols))
    gx, gy = np.meshgrid((np.arange(cols) + 0.5) * W / cols, (np.arange(rows) + 0.5) * H / rows)
    x0 = np.stack([gx.ravel(), gy.ravel()], axis=1)[:n] + rng.uniform(-10, 10, (n, 2))
    ang = rng.uniform(0, 2 * np.pi, n)
    v0 = speed * np.stack([np.cos(ang), np.sin(ang)], axis=1) * rng.uniform(0.5, 1.0, (n, 1))
    return np.ascontiguousarray(x0), np.ascontiguousarray(v0), np.full(n, r), rng.uniform(0.5, 2.0, n), W, H


def test_replay_event_rebuilds_the_final_velocities_from_the_record():
    x0, v0, radius, mass, W, H = _sparse_motion(17, 3)
    final, vel, n_ev, n_dd, n_w, ev_t, ev_i, ev_j, ev_s = _record(x0, v0, radius, mass, W, H, 6.0)
    V = v0.copy()
    kinds = [replay_event(e, ev_i, ev_j, ev_s, V) for e in range(n_ev)]
    np.testing.assert_array_equal(V, vel)
    assert kinds.count(IMPACT_WALL) == n_w
    assert kinds.count(IMPACT_PAIR) + kinds.count(IMPACT_NONE) == n_dd
    for e in np.flatnonzero(ev_j[:n_ev] >= 0):
        nx, ny, s = contact_normal(ev_s, e)
        assert math.hypot(nx, ny) == pytest.approx(1.0, rel=1e-14)
        assert s == pytest.approx(radius[ev_i[e]] + radius[ev_j[e]], rel=1e-9)


def _keyframes(x0, v0, n_ev, ev_t, ev_i, ev_j, ev_s):
    """Every disk's position and velocity just after each event (as ``nbst.sim.simulate``)."""
    cur_p, cur_v, cur_t = x0.copy(), v0.copy(), np.zeros(len(x0))
    for e in range(n_ev):
        t = ev_t[e]
        for k, d in ((0, ev_i[e]), (4, ev_j[e])):
            if d >= 0:
                cur_p[d], cur_v[d], cur_t[d] = ev_s[e, k:k + 2], ev_s[e, k + 2:k + 4], t
        yield t, cur_p + cur_v * (t - cur_t)[:, None], cur_v.copy()


@pytest.mark.parametrize("n", [16, 17, 33, 63])
def test_simulator_matches_naive_event_by_event_at_lane_padding_edges(n):
    """The kernel pads per-disk arrays to 16 lanes: N = 16, 17, 33 and 63 straddle the
    padding. Each run has hundreds of events; at every one, the naive reference (all walls
    and pairs rescanned with the textbook formulas) started from the kernel's state after the
    previous event finds the same event at the same time and the same velocities after it.
    (Event by event: over hundreds of contacts the motion is chaotic, so two correct
    simulators drift apart from round-off; one step at a time they agree to round-off.)"""
    x0, v0, radius, mass, W, H = _sparse_motion(n, n, box=(600.0, 450.0), r=4.0)
    t_final = 4.0
    final, vel, n_ev, n_dd, n_w, ev_t, ev_i, ev_j, ev_s = _record(x0, v0, radius, mass, W, H, t_final)
    assert n_ev >= 130 and n_dd >= 20
    t_prev, p_prev, v_prev = 0.0, x0, v0
    for e, (t, p_after, v_after) in enumerate(_keyframes(x0, v0, n_ev, ev_t, ev_i, ev_j, ev_s)):
        dt, i, j = next_event(p_prev, v_prev, radius, W, H)
        assert (i, j) == (ev_i[e], ev_j[e])
        assert t_prev + dt == pytest.approx(t, rel=1e-9, abs=1e-12)
        p = p_prev + v_prev * (t - t_prev)
        v = v_prev.copy()
        if j < 0:
            v[i, 0 if -1 - j <= 1 else 1] *= -1
        else:
            v[i], v[j] = impulse(v[i], v[j], p[i], p[j], mass[i], mass[j])
        np.testing.assert_allclose(p_after, p, rtol=0, atol=1e-9 * max(W, H))
        np.testing.assert_allclose(v_after, v, rtol=1e-9, atol=1e-9 * np.abs(v0).max())
        changed = np.flatnonzero(np.any(v_after != v_prev, axis=1))
        assert set(changed.tolist()) <= {i, j}
        t_prev, p_prev, v_prev = t, p_after, v_after
    assert next_event(p_prev, v_prev, radius, W, H)[0] > t_final - t_prev
