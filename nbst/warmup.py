"""Compile nbst's numba kernels ahead of use, and tell when a command will compile.

numba compiles each kernel on its first call and caches the machine code on disk
(``__pycache__/*.nbi``, ``*.nbc`` beside the sources, or numba's user cache
when that folder is not writable). A cold cache costs tens of seconds on the
first solve; later runs load the cached code in about a second.

* ``python -m nbst.warmup`` (run by ``scripts/setup.sh``) compiles every kernel
  the main job uses (simulate, evaluate, both search loops, polish, Jacobian)
  by running each once on a built-in problem, and the bowling lane's friction
  kernel by one short throw, and fills the cache.
* :func:`is_cold` tells whether a kernel has nothing in the cache yet, so a
  command can say ``compiling numba kernels (one time, ~N s)`` before it waits.
"""
from __future__ import annotations

import sys
import time

#: Cold compile of everything :func:`warm_all` touches on the 2-core development machine (numba
#: 0.68, Python 3.11): 214-235 s of CPU (2026-12-03, `NUMBA_CACHE_DIR=EMPTY python -m nbst.warmup`),
#: on two cores at once (the searches in a second process) about half of it in wall time when the
#: cores are idle: what the one-time message quotes.
COLD_COMPILE_SECONDS = 120


def is_cold(*dispatchers) -> bool:
    """True if any of these ``njit(cache=True)`` dispatchers has no compiled code,
    neither in this process nor in numba's on-disk cache (an index stale for the
    source file counts as empty). numba's cache is private API: if it cannot be
    read, the answer is False (say nothing rather than something wrong)."""
    try:
        for d in dispatchers:
            if d.overloads:
                continue
            cache = d._cache
            index = cache._cache_file._load_index()
            if not index:
                return True
        return False
    except Exception:  # noqa: BLE001 - a numba internals change must not break a command
        return False


def search_kernels() -> tuple:
    """The dispatchers a search runs (nbst's loop and the paper's)."""
    from nbst.search.loop import run_chunk
    from nbst.search.nbst_loop import run_chunk_nbst
    from nbst.sim import evaluate_kernel, run

    return (run, evaluate_kernel, run_chunk, run_chunk_nbst)


def other_kernels() -> tuple:
    """The dispatchers of the Jacobian, the sensitivity report and the planner."""
    from nbst.search.aim import pair_contact
    from nbst.search.planner import aim_routes
    from nbst.sim.jacobian import jacobian_from_events
    from nbst.sim.sensitivity import late_impact_errors

    # Only kernels that a command calls from Python: polish_kernel runs inside nbst's loop
    # (compiled with it) and transition_from_events behind transition_jacobian, which no
    # command calls; listed here, they would stay "cold" after every warm-up.
    from nbst.sim.api import _keyframes, _replay_at
    from nbst.sim.cells import evaluate_words_kernel, run_cells

    return (jacobian_from_events, late_impact_errors, aim_routes, run_cells, evaluate_words_kernel, _keyframes,
            _replay_at, pair_contact)


def lane_kernels() -> tuple:
    """The bowling lane's kernel: the friction and oil at the ball's contact, called before every
    step of every throw from the foul line (``nbst bowl throw/frame/solve --foul-line/...``)."""
    from nbst.models.bowling.lane.friction import contact_step

    return (contact_step,)


def warm_lane() -> None:
    """Compile the lane's kernel with the arrays a throw passes it: one short throw of the default
    delivery (the ball alone on the house shot; MuJoCo's model compile included, under a second)."""
    from nbst.models.bowling.lane import phases
    from nbst.models.bowling.lane.delivery import Delivery

    phases.run(Delivery(at="foul", board=20.0, angle=2.0), "house")


def many_disks_problem(n: int = 144):
    """A small many-disk problem (n disks on a grid, targets shifted): what the warm-up runs
    so the cell-grid kernel and multiword signatures are compiled too."""
    from nbst.problem import problem_from_dict

    side = int(n ** 0.5 + 0.999)
    disks = [{"start": [20.0 + 40.0 * (k % side), 20.0 + 40.0 * (k // side)],
              "target": [40.0 + 40.0 * (k % side), 20.0 + 40.0 * (k // side)], "radius": 5.0} for k in range(n)]
    return problem_from_dict({"name": f"grid-{n}", "box": [40.0 * side + 40.0, 40.0 * side], "t_final": 2.0,
                              "target_radius": 5.0, "disks": disks})


def compile_message() -> str:
    """The one-time message before numba compiles (setup and the first solve say the same)."""
    return f"nbst: compiling numba kernels (one time, ~{COLD_COMPILE_SECONDS} s on 2 cores)"


def announce(kernels, *, stream=None) -> bool:
    """If ``kernels`` are cold, write the one-time compile message to ``stream``
    (stderr by default) and return True."""
    if not is_cold(*kernels):
        return False
    print(f"{compile_message()}; `python -m nbst.warmup` does it ahead", file=sys.stderr if stream is None else stream,
          flush=True)
    return True


def warm_all(log=None, *, parallel: bool = False) -> float:
    """Compile (or load from the cache) every kernel the commands use; returns seconds.
    ``log(str)`` gets one line per stage. ``parallel``: once the event kernel that both call is
    compiled, the searches compile in a second process while this one compiles the rest of the
    simulator (numba compiles on one core; ``python -m nbst.warmup`` does this on 2 cores or more)."""
    import numpy as np

    from nbst.problem import load_problem
    from nbst.sim import evaluate, simulate
    from nbst.solution import solution_from_dict
    from nbst.sim.jacobian import final_jacobian
    from nbst.sim.sensitivity import analyze

    log = log or (lambda s: None)
    t0 = time.perf_counter()
    p = load_problem("over5")  # cueable and noncueable disks: every branch's types
    V = p.straight_velocities()
    simulate(p, V).at([0.0, 1.0])  # the event kernel, which the searches call too
    evaluate(p, np.stack([V, V]))
    search = _start_search() if parallel else None
    # The commands read velocities from solution files: read-only arrays, which numba compiles as
    # other signatures than writable ones. Warm with what they pass (solution_from_dict, the reader
    # of every solution file), through the calls they make (simulate, the keyframes and replays
    # behind positions at given times, the Jacobian and sensitivity behind validate's report).
    # 3x the straight shots: a motion with events (a record of one event or none is typed as a
    # contiguous array, of two or more as a strided one: another signature of the keyframes)
    # (simulate hands the event kernels read-only velocities whatever it is given: one signature)
    Vro = solution_from_dict({"velocities": (3.0 * V).tolist()}, p).velocities
    simulate(p, Vro).at([0.0, 1.0])
    many = many_disks_problem()
    Vm = many.straight_velocities()
    tr = simulate(many, Vm)
    tr.at([0.0, 1.0], replay=False)  # the keyframes, for N disks and their multiword signature
    tr.at([0.0, 1.0], replay=True)
    tr.velocity_at([0.5], replay=True)
    evaluate(many, np.stack([Vm, Vm]), jobs=1)
    from nbst.search.aim import pair_contact  # the many-body search's two-disk contacts

    ka = many.kernel_arrays()
    pair_contact(ka.start[0], ka.start[1], ka.target[0], ka.target[1], 1.0, 1.0, 5.0, 5.0, ka.W, ka.H, ka.t_final, 8,
                 np.empty((2, 5)))
    from nbst.formation import formation
    from nbst.planted import planted

    planted(20, noncue=2, seed=0)  # nbst generate's kernels: placing disks, assigning a formation's targets
    formation("nbst", 40, seed=0)
    for v in (Vro, 3.0 * V):  # validate's sensitivity report: from a file, and from the library (the tests)
        final_jacobian(p, v)
        analyze(p, v, timestep=0.00025)
    log(f"simulator ready ({time.perf_counter() - t0:.0f} s)")
    warm_lane()
    log(f"bowling lane ready ({time.perf_counter() - t0:.0f} s)")
    if search is not None and search.wait() == 0:
        log(f"searches ready ({time.perf_counter() - t0:.0f} s, compiled beside it)")
    else:  # one core, or the second process failed: here, one after the other
        warm_search(lambda s: log(f"{s} ({time.perf_counter() - t0:.0f} s)"))
    return time.perf_counter() - t0


def warm_search(log=None) -> None:
    """Compile the searches: nbst's (plain and ``--robust``) and the paper's."""
    from nbst.problem import load_problem
    from nbst.solvers.dispatch import solve_with

    log = log or (lambda s: None)
    p = load_problem("over5")
    solve_with("signature", p, seed=0, max_trials=3000, patience=0, variant="nbst")
    solve_with("signature", p, seed=0, max_trials=3000, patience=0, variant="nbst", robust=True)
    log("nbst search ready")
    solve_with("signature", p, seed=0, max_trials=3000, patience=0, variant="A")
    log("paper search ready")


def _start_search():
    """``python -m nbst.warmup --search`` in a second process (None if it cannot start)."""
    import subprocess

    try:
        return subprocess.Popen([sys.executable, "-m", "nbst.warmup", "--search"], stdin=subprocess.DEVNULL)
    except OSError:
        return None


def main(argv=None) -> int:
    """``python -m nbst.warmup [--quiet]``: compile what is not in the cache yet, on two cores when
    there are two. Says so (and how long it took) only when there was something to compile."""
    argv = sys.argv[1:] if argv is None else argv
    if "--search" in argv:  # the second process of a parallel warm-up
        warm_search()
        return 0
    quiet = "-q" in argv or "--quiet" in argv
    cold = is_cold(*search_kernels(), *other_kernels(), *lane_kernels())
    talk = cold and not quiet
    if talk:
        print(compile_message(), file=sys.stderr, flush=True)
    from nbst.parallel import default_jobs

    secs = warm_all((lambda s: print(f"nbst:   {s}", file=sys.stderr, flush=True)) if talk else None,
                    parallel=default_jobs() >= 2)
    if talk:
        print(f"nbst: numba kernels compiled and cached in {secs:.0f} s", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
