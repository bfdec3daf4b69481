"""The rollout room (nbst.models.mjsearch) on a small model of its own: no bowling inside.

The claims checked are determinism claims (exact equality is the claim: the same initial
state and controls give the same bits, whatever the threads, chunks or workers), and search
claims on toy problems with a fixed seed and a stated threshold.
"""
from __future__ import annotations

import math
import os
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")

from nbst.models.mjsearch import archive, ladder, probability, robust  # noqa: E402
from nbst.models.mjsearch.engine import Engine  # noqa: E402
from nbst.models.mjsearch.pool import WorkerPool  # noqa: E402
from nbst.models.mjsearch.runner import Runner  # noqa: E402


def _xml(warmstart: bool = False, sleep: bool = False) -> str:
    """A driven block (slide x, slide y, hinge z, two motors) pushing two free boxes, a sensor."""
    flag = (f'<flag warmstart="{"enable" if warmstart else "disable"}" '
            f'sleep="{"enable" if sleep else "disable"}"/>')
    return f"""<mujoco><option timestep="0.002" integrator="implicitfast">{flag}</option>
<worldbody><geom type="plane" size="10 10 .1" friction="0.9"/>
<body name="car" pos="0 0 .2"><joint name="cx" type="slide" axis="1 0 0"/>
<joint name="cy" type="slide" axis="0 1 0"/><joint name="cr" type="hinge" axis="0 0 1"/>
<geom type="box" size=".4 .2 .2" mass="100"/></body>
<body name="b2" pos="2 0.1 .2"><freejoint/><geom type="box" size=".3 .3 .2" mass="50"/></body>
<body name="b3" pos="3 -0.3 .2"><freejoint/><geom type="box" size=".3 .3 .2" mass="50"/></body>
</worldbody><actuator><motor joint="cx" ctrlrange="-2000 2000" ctrllimited="true"/>
<motor joint="cr" ctrlrange="-50 50" ctrllimited="true"/></actuator>
<sensor><framepos objtype="body" objname="b2"/></sensor></mujoco>"""


def _model(**kw):
    return mujoco.MjModel.from_xml_string(_xml(**kw))


def _driver(i, step, data):
    """A numpy controller: drive to x = 2.5, steer by the pushed box's y (read from its sensor)."""
    return np.array([1500.0 * np.tanh(2.5 - data.qpos[0]) + 10.0 * i, 20.0 * np.sin(3.0 * data.time)
                     + 5.0 * data.sensordata[1]])


def _starts(R, B=3):
    m = R.model
    out = []
    for i in range(B):
        qv = np.zeros(m.nv)
        qv[0] = 0.5 * i
        out.append(R.initial_state(m.qpos0, qv))
    return np.array(out)


def test_open_loop_rollouts_equal_a_plain_mj_step_loop_for_any_jobs():
    """The runner's final states are those of a fresh MjData stepped by mj_step (the slow
    reference), bit for bit, with 1 thread or 2."""
    m = _model()
    with Runner(m, jobs=1, duration=0.5) as R1, Runner(m, jobs=2, duration=0.5) as R2:
        s0 = _starts(R1)
        ctrl = np.array([800.0, 5.0])
        a, b = R1.run(s0, control=ctrl), R2.run(s0, control=ctrl)
        assert np.array_equal(a.final, b.final)
        for k in range(len(s0)):
            d = mujoco.MjData(m)
            mujoco.mj_setState(m, d, s0[k], mujoco.mjtState.mjSTATE_FULLPHYSICS)
            d.ctrl[:] = ctrl
            mujoco.mj_step(m, d, nstep=R1.nstep)
            assert np.array_equal(R1.final_qpos(a.final)[k], d.qpos)
            assert np.array_equal(R1.final_qvel(a.final)[k], d.qvel)


@pytest.mark.parametrize("warmstart", [False, True])
def test_closed_loop_in_chunks_replays_bit_for_bit_from_its_recorded_controls(warmstart):
    """A controller between chunks of mujoco.rollout: the final states and every step's sensor
    data equal one open-loop call with the controls it recorded, for chunks of 1, 7 and 25
    steps and the whole run, on 1 and 2 threads (warm-starting on and off: the runner carries
    qacc_warmstart across chunk boundaries)."""
    m = _model(warmstart=warmstart)
    with Runner(m, jobs=2, duration=1.0) as R, Runner(m, jobs=1, duration=1.0) as R1:
        s0 = _starts(R)
        for chunk in (1, 7, 25, R.nstep):
            got = R.run(s0, controller=_driver, chunk=chunk, sensors=True)
            assert got.control.shape == (len(s0), R.nstep, m.nu)
            again = R.run(s0, control=got.control, sensors=True)
            assert np.array_equal(got.final, again.final), chunk
            assert np.array_equal(got.sensordata, again.sensordata), chunk
            one = R1.run(s0, controller=_driver, chunk=chunk)
            assert np.array_equal(got.final, one.final), chunk
            # the controls are held for a chunk, and change between chunks (a closed loop)
            assert np.array_equal(got.control[:, 0], got.control[:, min(chunk, R.nstep) - 1])
        assert not np.array_equal(R.run(s0, controller=_driver, chunk=7).final,
                                  R.run(s0, controller=_driver, chunk=25).final)  # the loop's rate matters


def test_the_controller_sees_the_state_of_its_step():
    """At each call the data holds the state at that step: time = step x h, and the sensor
    (the pushed box's position) read after mj_forward."""
    m = _model()
    seen = []

    def ctrl(i, step, data):
        seen.append((step, data.time, data.sensordata[0], data.xpos[m.body("b2").id][0]))
        return np.zeros(m.nu)

    with Runner(m, jobs=1, nstep=30) as R:
        R.run(_starts(R, 1), controller=ctrl, chunk=10)
    assert [s[0] for s in seen] == [0, 10, 20]
    for step, t, sensor, x in seen:
        assert t == pytest.approx(step * m.opt.timestep, abs=1e-12)
        assert sensor == x


def test_run_refuses_mixed_or_bad_loops():
    m = _model()
    with Runner(m, jobs=1, nstep=5) as R:
        s0 = _starts(R, 1)
        with pytest.raises(ValueError, match="not both"):
            R.run(s0, control=np.zeros(m.nu), controller=_driver, chunk=1)
        with pytest.raises(ValueError, match="chunk"):
            R.run(s0, controller=_driver)
    with pytest.raises(ValueError, match="duration or nstep"):
        Runner(m, jobs=1)


def test_cluster_runner_gives_the_same_bits_as_threads():
    """The batch cut across two Dask workers (threads of this process here) comes back in order,
    open loop and closed loop, bit for bit as on this process's threads."""
    pytest.importorskip("dask.distributed")
    from dask.distributed import LocalCluster

    from nbst.models.mjsearch import cluster as C

    with Runner(_model(), jobs=1, duration=0.3) as R:
        s0 = _starts(R, 5)
        open_, closed = R.run(s0, control=np.array([500.0, 1.0])), R.run(s0, controller=_driver, chunk=10)
    C._WORKER_RUNNERS.clear()
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None) as cl:
        with C.ClusterRunner(cl.scheduler_address, _model, duration=0.3) as CR:
            assert CR.workers == 2
            assert np.array_equal(CR.run(s0, control=np.array([500.0, 1.0])).final, open_.final)
            got = CR.run(s0, controller=_driver, chunk=10)
            assert np.array_equal(got.final, closed.final) and np.array_equal(got.control, closed.control)
    assert C._WORKER_RUNNERS  # the rollouts ran on the workers


# --------------------------------------------------------------------------- the pool


def _square(x):
    return x * x


def test_pool_returns_results_in_order_and_counts_progress():
    done = []
    with WorkerPool(2) as P:
        assert P.map(_square, [(k,) for k in range(7)], on_done=lambda: done.append(1)) == [k * k for k in range(7)]
    assert len(done) == 7


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_pool_workers_die_with_a_parent_killed_by_sigkill(tmp_path):
    """SIGKILL cannot be handled: the workers must notice by themselves (PR_SET_PDEATHSIG or the
    watchdog) and exit, within a few seconds, instead of living on as orphans."""
    script = tmp_path / "parent.py"
    script.write_text(textwrap.dedent("""
        import time
        from nbst.models.mjsearch.pool import WorkerPool
        if __name__ == "__main__":
            P = WorkerPool(2)
            P.map(time.sleep, [(0.01,), (0.01,)])
            print(" ".join(map(str, P.pids())), flush=True)
            P.map(time.sleep, [(60,), (60,)])
    """))
    p = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE, text=True)
    pids = [int(x) for x in p.stdout.readline().split()]
    assert len(pids) == 2
    p.send_signal(signal.SIGKILL)
    p.wait(10)
    t0 = time.monotonic()
    while time.monotonic() - t0 < 10 and any(os.path.exists(f"/proc/{q}") and _alive(q) for q in pids):
        time.sleep(0.1)
    assert not [q for q in pids if os.path.exists(f"/proc/{q}") and _alive(q)], "workers outlived their parent"


def _alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().split(")")[-1].split()[0] != "Z"
    except OSError:
        return False


# --------------------------------------------------------------------------- archive and search


def _grid_signature(X):
    """A toy outcome: the cell (1..16) of a 4 x 4 grid over the unit square; 0 off the square."""
    X = np.atleast_2d(X)
    i, j = np.clip((X[:, 0] * 4).astype(int), 0, 3), np.clip((X[:, 1] * 4).astype(int), 0, 3)
    return 1 + 4 * i + j


SQUARE = archive.box_space([0.0, 0.0], [1.0, 1.0], (0.01, 0.05, 0.2))


def test_grow_is_reproducible_and_finds_every_cell():
    """The MAP-Elites loop from a seed: the same archive twice; all 16 cells found in 320 rollouts
    (16 cells of 1/16 of the square each: uniform throws alone find them all in ~55)."""
    runs = []
    for _ in range(2):
        a = archive.grow(_grid_signature, archive.Archive(), np.random.default_rng(3), SQUARE, budget=320, explore=64)
        runs.append(a)
    a, b = runs
    assert a.rollouts == 320 and len(a) == 16
    assert a.elite.keys() == b.elite.keys() and all(np.array_equal(a.elite[k], b.elite[k]) for k in a.elite)
    assert a.curve == b.curve and sum(a.children.values()) > 0


def test_emit_draws_the_same_uniform_block_whatever_the_archive():
    """The emitter's stream does not depend on the archive: its uniform part is the same draw."""
    full = archive.Archive.from_elites({5: [0.4, 0.4], 9: [0.6, 0.1]})
    Xa, pa = archive.emit(archive.Archive(), np.random.default_rng(1), SQUARE, 8)
    Xb, pb = archive.emit(full, np.random.default_rng(1), SQUARE, 8)
    assert (pa == -1).all() and (pb[:2] == -1).all() and set(pb[2:]) <= {5, 9}
    assert np.array_equal(Xa[:2], Xb[:2])


def test_parent_weights_favour_rare_signatures_of_sparse_groups():
    a = archive.Archive.from_elites({1: [0.1, 0.1], 2: [0.2, 0.2], 3: [0.3, 0.3]})
    a.seen[1] = 100
    w = archive.parent_weights(a, [1, 2, 3])
    assert w.sum() == pytest.approx(1.0) and w[0] < w[1] == w[2]
    # groups: 1 alone in a group of 1 (found: the floor), 2 and 3 in a group of 10 (8 missing)
    wg = archive.parent_weights(a, [1, 2, 3], group=lambda m: 0 if m == 1 else 1, group_total=[1, 10])
    assert wg[0] < w[0] and wg[1] == wg[2]


@pytest.mark.slow
def test_the_engine_restarts_from_a_known_cell_to_a_far_one():
    """The engine without its GA (bowling's set-up: CMA-ES restarts from the nearest archived cell,
    steps alternating sigma0 and a tenth of it) reaches cell 16 (the far corner, distance in
    cells) from a start known in cell 1, with 200 rollouts at most (seed 2), twice the same."""
    target = 16

    def evaluate(U):
        s = _grid_signature(U)
        d = np.abs((s - 1) // 4 - 3) + np.abs((s - 1) % 4 - 3)
        return s, d, d + 0.01 * np.hypot(*(U - 0.99).T)

    runs = []
    for _ in range(2):
        e = Engine(2, seed=2, max_rollouts=200, explore=4, ga_batches=0, popsize=8, sigma0=0.05,
                   schedule=(("cell", 1.0), ("cell", 0.1)), explore_between=16)
        e.know({1: [0.05, 0.05]}, prior=lambda m: (6, 6.0))
        runs.append(e.run(evaluate))
    f, again = runs
    assert "solved" in f.stopped and f.signature == target and f.distance == 0 and f.rollouts <= 200
    assert np.array_equal(f.x, again.x) and f.rollouts == again.rollouts


def test_no_second_cma_loop_remains():
    """One CMA-ES loop for rollout searches: pycma is imported only by the engine and the 2D
    solvers' baseline (nbst.solvers.baselines); the crash's reconstruction fits on the engine."""
    root = os.path.join(os.path.dirname(__file__), "..")
    allowed = {os.path.normpath(p) for p in ("models/mjsearch/engine.py", "nbst/solvers/baselines.py")}
    found = set()
    for top in ("nbst", "models"):
        for d, dirs, files in os.walk(os.path.join(root, top), followlinks=False):
            dirs[:] = [x for x in dirs if x != "__pycache__"]
            for f in files:
                if f.endswith(".py"):
                    path = os.path.join(d, f)
                    text = open(path, encoding="utf-8").read()
                    if "import cma" in text or "from cma" in text:
                        found.add(os.path.normpath(os.path.relpath(path, root)))
    assert "models/mjsearch/engine.py" in found and found <= allowed, sorted(found - allowed)
    assert not os.path.exists(os.path.join(root, "models", "mjsearch", "restarts.py"))


# --------------------------------------------------------------------------- probability and robustness


def test_wilson_interval_matches_its_formula_and_stays_in_bounds():
    lo, hi = probability.wilson(5, 10)
    assert (lo, hi) == pytest.approx((0.2366, 0.7634), abs=1e-4)  # the textbook value for 5/10
    assert probability.wilson(0, 7)[0] == 0.0 and probability.wilson(7, 7)[1] == 1.0
    assert probability.Probability.of(3, 4).text() == "75 % (3/4; 95 % CI 30-95 %)"
    with pytest.raises(ValueError):
        probability.wilson(5, 4)


def test_common_random_numbers_are_the_same_draws_for_every_vector():
    z = probability.normal_draws(11, 5, 3)
    assert np.array_equal(z, probability.normal_draws(11, 5, 3))
    a = probability.perturb([0.0, 1.0, 2.0], [1.0, 0.5, 0.0], z, [-1, -1, -1], [1, 2, 3])
    b = probability.perturb([0.5, 1.0, 2.0], [1.0, 0.5, 0.0], z, [-1, -1, -1], [1, 2, 3])
    assert a.min() >= -1 and (a <= [1, 2, 3]).all() and (a[:, 2] == 2.0).all()
    inside = (np.abs(a[:, 0]) < 1) & (np.abs(b[:, 0]) < 1)
    assert np.allclose(b[inside, 0] - a[inside, 0], 0.5)  # the same noise, paired


class _Window:
    """A toy Problem: success when x + noise (sigma 1) lands in [-1, 1]; best at x = 0."""

    moved = np.array([1.0])

    def project(self, x):
        return np.clip(np.asarray(x, dtype=float), -10, 10)

    def make(self, x):
        return float(x[0])

    def point(self, c):
        return np.array([c])

    def noisy(self, c, m, seed):
        return list(c + probability.normal_draws(seed, m, 1)[:, 0])

    def run(self, copies):
        return copies

    def judge(self, r):
        return abs(r) <= 1.0, int(abs(r) <= 2.0), "in" if abs(r) <= 1 else "out"

    def ladder(self, c):
        return [[0.001, abs(c) <= 1]], abs(c) <= 1, 1

    def fresh(self, c, n, seed):
        k = sum(1 for v in self.noisy(c, n, seed) if abs(v) <= 1)
        return probability.Probability.of(k, n)


def test_robust_maximise_climbs_the_probability_of_a_window():
    """From x = 2.2 (P = 0.11 under unit noise) the pick lands within 0.5 of the best x = 0
    (P(|x + z| <= 1) = 0.68 there) on 600 trials (seed 4), reproducibly."""
    res = robust.maximise(_Window(), [2.2], budget=600, seed=4, n=400)
    assert abs(res.best) < 0.5 and res.ladder_holds
    assert res.fresh.p > 0.55 and res.screen.k > res.start_screen.k
    again = robust.maximise(_Window(), [2.2], budget=600, seed=4, n=400)
    assert again.best == res.best and again.frames == res.frames


class _WideWindow(_Window):
    """Success when x + noise lands in [-2, 2] (P = 0.95 at x = 0); counts its candidates."""

    def __init__(self):
        self.made = 0

    def make(self, x):
        self.made += 1
        if self.made > 3000:
            raise RuntimeError("maximise is still proposing after 3,000 candidates")
        return float(x[0])

    def judge(self, r):
        return abs(r) <= 2.0, 0, "in" if abs(r) <= 2.0 else "out"


def test_robust_maximise_ends_when_the_budget_left_fits_no_new_candidate():
    """From the best x = 0 nothing is accepted, the step narrows to STEP_MIN and the cross-entropy
    steps repeat points already run; once what is left of the budget fits no new candidate the
    search ends (it looped for ever: nbst bowl spares hung in the 10 pin's polish on lane-3)."""
    for budget, seed in ((522, 1), (614, 5)):
        P = _WideWindow()
        res = robust.maximise(P, [0.0], budget=budget, seed=seed, n=50)
        assert res.frames <= budget + 1 and P.made < 500  # a few hundred proposals at most
        assert budget - (res.frames - 1) < 2 * res.history[0]["m"]  # the budget was (nearly) spent


def test_the_ladder_says_which_timesteps_keep_an_outcome():
    lad = ladder.climb(lambda h: round(math.sin(1 / h)), (0.001, 0.0005, 0.00025), wanted=1)
    assert lad.outcomes == [1, 1, -1] and lad.kept == [0.001, 0.0005] and not lad.holds
    assert ladder.kept_text([0.001, 0.0005, 0.00025], [0.001]) == "kept at h = 1 ms only; changes at 0.5 and 0.25 ms"
    assert ladder.kept_text([0.001, 0.0005], [0.001, 0.0005]) == "kept at h = 1 and 0.5 ms"
    assert ladder.kept_text([0.001, 0.0005], []) == "kept at no timestep (1 and 0.5 ms)"
    assert ladder.climb(lambda h: 3, (0.002, 0.001)).holds


def test_the_batch_runner_is_replayed_by_mj_step_and_ignores_threads():
    """BatchRunner (a batch-wide controller every period, an observer every step): the recorded
    controls replayed by a plain mj_step loop give the same bits, for 1 and 2 threads."""
    from nbst.models.mjsearch.batch import BatchRunner

    m = _model()
    s, nstep, period = 3, 500, 7  # a period that does not divide the run: the last row is short
    qv = np.zeros((s, m.nv))
    qv[:, 0] = [0.0, 0.5, 1.0]
    q0 = np.repeat(m.qpos0[None], s, axis=0)
    seen = []

    def drive(v):  # numpy over the batch, reading the sensors
        return np.stack([1500.0 * np.tanh(2.5 - v.qpos[:, 0]), 5.0 * v.sensordata[:, 1]], axis=1)

    outs = []
    for jobs in (1, 2):
        seen.clear()
        with_obs = BatchRunner(m, jobs=jobs, size=4).run(q0, qv, nstep, period=period, controller=drive,
                                                         observer=lambda v: seen.append(v.step))
        outs.append(with_obs)
    assert seen == list(range(1, nstep + 1))
    assert np.array_equal(outs[0].final_qpos, outs[1].final_qpos)  # bitwise: threads change nothing
    for i in range(s):
        d = mujoco.MjData(m)
        d.qpos[:], d.qvel[:] = q0[i], qv[i]
        for k, row in enumerate(outs[0].controls[i]):
            d.ctrl[:] = row
            mujoco.mj_step(m, d, nstep=min(period, nstep - k * period))
        assert np.array_equal(d.qpos, outs[0].final_qpos[i])
