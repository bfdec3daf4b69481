"""The analytic Jacobian against finite differences; polish never worsens and aims lone disks exactly."""
import numpy as np
import pytest

from conftest import make_problem
from nbst import load_problem
from nbst.sim.jacobian import final_jacobian
from nbst.search.polish import polish
from nbst.sim import simulate


def _same_sequence(a, b):
    return len(a.events) == len(b.events) and np.array_equal(a.events[["kind", "i", "j"]], b.events[["kind", "i", "j"]])


def test_jacobian_matches_central_differences():
    rng = np.random.default_rng(0)
    checked = 0
    while checked < 40:
        n = 4
        starts = []
        while len(starts) < n:
            c = rng.uniform(30, 370, 2)
            if all(np.hypot(*(c - s)) >= 45 for s in starts):
                starts.append(c)
        p = make_problem(starts, 20.0, box=(400, 400), t_final=3.0, masses=rng.uniform(0.5, 2, n),
                         cueable=[True, True, True, False])
        v = rng.uniform(-150, 150, (n, 2))
        v[3] = 0.0
        tr = simulate(p, v)
        if tr.n_disk_disk < 1 or len(tr.events) > 12:
            continue
        _, J = final_jacobian(p, v)
        assert J.shape == (8, 6)
        h = 1e-5
        Jfd = np.empty_like(J)
        ok = True
        for q in range(6):
            dv = np.zeros((n, 2))
            dv[q // 2, q % 2] = h
            tp, tm = simulate(p, v + dv), simulate(p, v - dv)
            if not (_same_sequence(tp, tr) and _same_sequence(tm, tr)):
                ok = False  # the step crossed a change of collision sequence: no derivative there
                break
            Jfd[:, q] = (tp.final_positions - tm.final_positions).ravel() / (2 * h)
        if not ok:
            continue
        # central differences err by ~h^2 * curvature + round-off/h ~ 1e-8 here; 1e-5 is the bound
        assert np.abs(J - Jfd).max() <= 1e-5 * max(1.0, np.abs(Jfd).max())
        checked += 1


def test_polish_never_worse_and_reports_true_cost():
    rng = np.random.default_rng(2)
    for name in ("diamond-s14", "over5", "diamond-s14-tiny"):
        p = load_problem(name)
        for _ in range(6):
            v0 = rng.uniform(-200, 200, (p.n, 2)) * p.cueable[:, None]
            c0 = simulate(p, v0).cost
            v, c, sig, sims = polish(p, v0, max_sims=40)
            tr = simulate(p, v)
            assert c <= c0
            assert tr.cost == c and tr.signature == sig  # the reported cost is the simulated one
            assert 1 <= sims <= 40
            assert np.all(v[~p.cueable] == 0.0)


def test_lone_disk_with_bounces_is_aimed_exactly():
    p = make_problem([(100, 100)], 10.0, box=(300, 200), t_final=4.0, targets=[(250, 37)])
    v0 = np.array([[410.0, -230.0]])  # several bounces, far from the target
    assert simulate(p, v0).cost > 100
    v, c, _, sims = polish(p, v0, max_sims=20, tol=1e-18)
    # Linear in v within a bounce sequence: one Gauss-Newton step lands it, up to round-off
    assert c < 1e-18
    assert sims <= 6


def test_free_disks_of_tiny_problem_land_exactly():
    p = load_problem("diamond-s14-tiny")
    rng = np.random.default_rng(5)
    v0 = p.straight_velocities() + rng.normal(0, 5, (14, 2))
    v, c, sig, _ = polish(p, v0, max_sims=60, tol=1e-12)
    assert c < 1e-12 and sig == (1 << 14) - 1


def test_cholesky_solve_matches_numpy_and_refuses_non_spd():
    from nbst.search.polish import _cholesky_solve

    rng = np.random.default_rng(7)
    for P in (1, 2, 5, 12):
        M = rng.normal(size=(P + 3, P))
        A = M.T @ M + 1e-3 * np.eye(P)  # symmetric positive definite
        b = rng.normal(size=P)
        out = np.empty(P)
        assert _cholesky_solve(A, b, out)
        np.testing.assert_allclose(out, np.linalg.solve(A, b), rtol=1e-9, atol=1e-12)
    A = np.array([[1.0, 2.0], [2.0, 1.0]])  # indefinite: eigenvalues 3 and -1
    assert not _cholesky_solve(A, np.ones(2), np.empty(2))


def test_polish_kernel_says_why_it_stopped():
    from nbst.search.polish import POLISH_EVENT_CAP, PolishStop, alloc_polish, polish_kernel
    from nbst.sim import alloc_work

    p = make_problem([(100.0, 100.0), (400.0, 300.0)], targets=[(700.0, 650.0), (150.0, 500.0)])
    ka = p.kernel_arrays()
    cue = np.arange(2, dtype=np.int64)

    def run(v, max_sims, tol):
        v = np.array(v, float)
        return polish_kernel(ka.start, v, ka.radius, ka.mass, ka.target, ka.W, ka.H, ka.t_final, ka.R, cue,
                             max_sims, tol, alloc_work(2), alloc_polish(2, 2, POLISH_EVENT_CAP))

    off = p.straight_velocities() + 3.0
    assert run(off, 50, 1e-6)[3] == PolishStop.TOLERANCE  # lone disks: aimed exactly
    assert run(off, 2, 0.0)[3] == PolishStop.BUDGET
    c, s, sims, why = run(p.straight_velocities(), 50, -1.0)  # already exact: no step lowers a zero cost
    assert why == PolishStop.NO_DESCENT and c == pytest.approx(0.0, abs=1e-18) and sims < 50
