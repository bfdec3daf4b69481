"""The cell-grid event kernel (nbst.sim.cells) against the table kernel and the slow reference.

The contract: the same events, in the same order, with the same numbers as the table
(``nbst.sim.kernel.run``), for any N; physics facts (energy, momentum, no overlap) at sizes the
table cannot hold; multiword signatures past 63 disks.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from naive import naive_simulate

from nbst.problem import problem_from_dict
from nbst.sim import evaluate, simulate
from nbst.sim.api import uses_cells
from nbst.sim.cells import CELLS_MIN_DISKS, alloc_cells, grid_shape, run_cells
from nbst.sim.kernel import STATUS_OK, STATUS_STALLED, alloc_work, run


def scene(n, seed, *, frac=0.07, speed=3.0, t_final=8.0, mixed=False, resting=0.0):
    """n disks on a jittered grid at packing fraction ``frac`` (radius 1, or 0.5-1 mixed with
    mass ~ area), random velocities of scale ``speed``; a share ``resting`` at rest."""
    rng = np.random.default_rng(seed)
    side = math.sqrt(n * math.pi / frac)
    m = int(math.ceil(math.sqrt(n)))
    g = side / m
    idx = rng.permutation(m * m)[:n]
    x0 = np.stack([(idx % m + 0.5) * g, (idx // m + 0.5) * g], 1) + rng.uniform(-1, 1, (n, 2)) * (g / 2 - 1.01)
    rad = rng.uniform(0.5, 1.0, n) if mixed else np.ones(n)
    mass = rad ** 2 if mixed else np.ones(n)
    v = rng.normal(size=(n, 2)) * speed
    v[rng.random(n) < resting] = 0.0
    return _read_only(x0), v, _read_only(rad), _read_only(mass), side, side, t_final


def _read_only(a):
    """``a`` read-only, as Problem.kernel_arrays() gives the starts, radii and masses: the kernels'
    signatures that nbst.warmup compiled, not new ones (minutes of compiling on a cold cache)."""
    a.setflags(write=False)
    return a


def record(kernel, work, args, cap=500_000):
    x0, v, rad, mass, W, H, tf = args
    v = _read_only(np.array(v, dtype=np.float64))  # as simulate hands them over: read-only
    n = x0.shape[0]
    fin, vel = np.empty((n, 2)), np.empty((n, 2))
    et, ei, ej, es = np.empty(cap), np.empty(cap, np.int64), np.empty(cap, np.int64), np.empty((cap, 8))
    st, ne, ndd, nw = kernel(x0, v, rad, mass, W, H, tf, work, fin, vel, 10 ** 7, et, ei, ej, es)
    es = es[:ne].copy()
    es[ej[:ne] < 0, 4:] = 0.0  # the unused half of a wall event's record
    return (int(st), ne, ndd, nw), fin, vel, et[:ne], ei[:ne], ej[:ne], es


def assert_same_motion(args):
    a = record(run, alloc_work(args[0].shape[0]), args)
    b = record(run_cells, alloc_cells(args[0].shape[0]), args)
    assert a[0] == b[0]
    for x, y in zip(a[1:], b[1:]):
        np.testing.assert_array_equal(x, y)  # bit for bit: the same formulas from the same instants
    return a


@pytest.mark.parametrize("n,seed,mixed,resting", [(1, 1, False, 0.0), (2, 1, False, 0.0), (7, 2, True, 0.0),
                                                  (40, 3, False, 0.3), (150, 4, True, 0.0), (400, 5, False, 0.2),
                                                  (400, 6, True, 0.5)])
def test_same_events_as_the_table(n, seed, mixed, resting):
    st = assert_same_motion(scene(n, seed, mixed=mixed, resting=resting))[0]
    assert st[0] == STATUS_OK
    if n >= 40:
        assert st[2] > n // 4  # the motion really has collisions to get right


def test_same_events_when_dense():
    """A packed box (many disks per neighbourhood, constant collisions) and a box of fewer than
    3 x 3 cells (neighbourhoods clipped at the walls)."""
    assert_same_motion(scene(300, 7, frac=0.45, speed=2.0, t_final=3.0))
    args = scene(12, 8, frac=0.3, t_final=20.0)
    assert grid_shape(args[2], args[4], args[5], 12)[:2] <= (3, 3)
    assert_same_motion(args)


def test_same_events_at_1000_disks():
    """The issue's check: agreement with the O(N^2) kernel at N = 1,000 (here exact)."""
    st = assert_same_motion(scene(1000, 9, mixed=True, t_final=6.0))[0]
    assert st[2] > 1000  # disk-disk events


def test_agrees_with_the_slow_reference():
    """Against tests/naive.py (every event rescans every pair): same events, and final positions
    within 1e-9 of the box side (the reference moves every disk at every event: its round-off)."""
    x0, v, rad, mass, W, H, tf = scene(25, 10, mixed=True, t_final=6.0)
    st, fin, vel, et, ei, ej, es = record(run_cells, alloc_cells(25), (x0, v, rad, mass, W, H, tf))
    fp, fv, evs = naive_simulate(x0, v, rad, mass, W, H, tf)
    assert len(evs) == st[1] > 20
    assert [(i, j) for _, i, j in evs] == list(zip(ei.tolist(), ej.tolist()))
    np.testing.assert_allclose(et, [t for t, _, _ in evs], rtol=0, atol=1e-9 * tf)
    np.testing.assert_allclose(fin, fp, rtol=0, atol=1e-9 * W)


def test_a_jam_stalls_as_in_the_table():
    """A disk exactly as wide as the box bounces infinitely often at one instant: both kernels
    stop with STALLED at the same event."""
    x0 = _read_only(np.array([[1.0, 5.0], [3.5, 2.0]]))
    v = np.array([[1.0, 0.0], [0.0, 0.0]])
    args = (x0, v, _read_only(np.array([1.0, 1.0])), _read_only(np.ones(2)), 2.0 + 1e-300, 10.0, 1.0)
    a = assert_same_motion(args)
    b = record(run_cells, alloc_cells(2), args)
    assert a[0][0] == b[0][0]
    args2 = (_read_only(np.array([[1.0, 1.0]])), np.array([[3.0, 0.0]]), _read_only(np.array([1.0])),
             _read_only(np.ones(1)), 2.0, 2.0, 1.0)
    assert record(run_cells, alloc_cells(1), args2)[0][0] == STATUS_STALLED


def _problem(args, name="cells"):
    x0, v, rad, mass, W, H, tf = args
    d = {"name": name, "box": [W, H], "t_final": tf, "target_radius": 2.0,
         "disks": [{"start": x0[i].tolist(), "target": x0[i].tolist(), "radius": float(rad[i]), "mass": float(mass[i])}
                   for i in range(len(x0))]}
    return problem_from_dict(d), v


def test_physics_at_3000_disks():
    """Where the table would need 72 MB per run: kinetic energy and momentum change only at the
    walls (energy to 1e-12 relative), and no two disks overlap at sampled times (1e-9 of a radius)."""
    p, v = _problem(scene(3000, 11, mixed=True, t_final=4.0))
    assert uses_cells(p.n)
    tr = simulate(p, v)
    assert not tr.truncated and tr.n_disk_disk > 1500
    ke0 = 0.5 * np.sum(p.mass[:, None] * v ** 2)
    ke1 = 0.5 * np.sum(p.mass[:, None] * tr.final_velocities ** 2)
    assert abs(ke1 - ke0) <= 1e-12 * ke0
    assert "_keyframes" not in tr.__dict__  # at() replays the record; no K x N x 2 arrays
    for t in (0.7, 2.1, 4.0):
        pos = tr.at(t)
        assert "_keyframes" not in tr.__dict__
        lo = p.radius[:, None] * (1 - 1e-9)
        assert np.all(pos >= lo - 1e-9) and np.all(pos <= np.array(p.box) - lo + 1e-9)
        # neighbours through a sort on x: every pair closer than 2 in x is checked
        o = np.argsort(pos[:, 0])
        ps, rs = pos[o], p.radius[o]
        for lag in range(1, 60):
            d = np.hypot(*(ps[lag:] - ps[:-lag]).T)
            near = (ps[lag:, 0] - ps[:-lag, 0]) < 2.0
            assert np.all(d[near] >= (rs[lag:] + rs[:-lag])[near] * (1 - 1e-9))


def test_replay_gives_the_keyframes_numbers():
    p, v = _problem(scene(200, 12, t_final=5.0))
    tr = simulate(p, v)
    ts = np.array([0.0, 0.3, 2.5, 2.5, 1.0, 5.0])
    np.testing.assert_array_equal(tr.at(ts, replay=True), tr.at(ts, replay=False))
    np.testing.assert_array_equal(tr.velocity_at(ts, replay=True), tr.velocity_at(ts, replay=False))


def test_multiword_signatures():
    """Past 63 disks the signature is a Python int with bit i iff disk i ends within R, the
    same from evaluate and simulate; the string in files has N characters."""
    p, v = _problem(scene(130, 13, t_final=3.0))
    assert p.n > 64 and p.n < CELLS_MIN_DISKS + 10
    tr = simulate(p, v)
    d = np.hypot(*(tr.final_positions - p.target).T)
    want = sum(1 << i for i in range(p.n) if d[i] <= p.target_radius)
    assert tr.signature == want and 0 < tr.order < p.n
    assert tr.signature_string == "".join("1" if d[i] <= p.target_radius else "0" for i in range(p.n))
    _, cost, sig = evaluate(p, np.stack([v, v * 0.5]), jobs=2)
    assert sig[0] == want and cost[0] == pytest.approx(tr.cost, rel=1e-15)
    assert sig.dtype == object and (p.n - 1) > 63
