"""Compile nbst's numba kernels ahead of use, and tell when a command will compile.

numba compiles each kernel on its first call and caches the machine code on disk
(``__pycache__/*.nbi``, ``*.nbc`` beside the sources, or numba's user cache
when that folder is not writable). A cold cache costs minutes of one core; later runs
load the cached code in about a second.

* ``python -m nbst.warmup`` (run by ``scripts/setup.sh``) compiles every kernel
  the commands use by running each once on a built-in problem, in :data:`GROUPS`:
  the event kernel first (every other group calls it), then the other groups side by
  side, one process per core (numba compiles a kernel on one core), each saying how
  long it took as it finishes.
* :func:`is_cold` tells whether a kernel has nothing in the cache yet, so a
  command can say ``compiling numba kernels (one time)`` before it waits.

Two processes must not write the same kernel's cache at once (numba's index of a kernel's
compiled signatures is one file, read, extended and written back): each group compiles
kernels that no other group compiles, the shared event kernel being compiled before them all
(tests/test_setup.py holds the list: it finds what each group would add to a cold cache by
numba's type inference on a warm one, the signatures run and their callees', without the cold
compile; ``python -m nbst.warmup`` run twice compiles nothing the second time).
"""
from __future__ import annotations

import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, TextIO

__all__ = ["COLD_COMPILE_SECONDS", "FIRST", "GROUPS", "KernelGroup", "announce", "compile_message", "is_cold",
           "lane_kernels", "main", "many_disks_problem", "other_kernels", "search_kernels", "warm_all", "warm_events",
           "warm_lane", "warm_many_disks", "warm_searches"]

Log = Callable[[str], None]

#: What ``nbst solve --help`` quotes for a first solve's compile (the event kernel and nbst's
#: search, in the solve's process, on one core): 74 s of CPU for the whole of `nbst solve
#: diamond-s14 --jobs 1` on a cold cache (2026-12-06, the 2-core development machine; 430 s of
#: wall time there at load 10). The warm-up quotes no figure: it says each group's time as it
#: finishes.
COLD_COMPILE_SECONDS = 75


@dataclass(frozen=True)
class KernelGroup:
    """Kernels compiled together, by one call of a module-level function of this module.

    Attributes:
        name: what the progress line calls it (``"<name> ready"``).
        function: the name of the function in :mod:`nbst.warmup` that runs them once (a
            name, looked up when the group runs: picklable for a worker process).
    """

    name: str
    function: str

    def run(self) -> float:
        """Run the group here; returns its seconds."""
        t = time.perf_counter()
        getattr(sys.modules[__name__], self.function)()
        return time.perf_counter() - t


def is_cold(*dispatchers: Any) -> bool:
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


def search_kernels() -> tuple[Any, ...]:
    """The dispatchers a search runs (nbst's loop and the paper's)."""
    from nbst.search.loop import run_chunk
    from nbst.search.nbst_loop import run_chunk_nbst
    from nbst.sim import evaluate_kernel, run

    return (run, evaluate_kernel, run_chunk, run_chunk_nbst)


def other_kernels() -> tuple[Any, ...]:
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


def lane_kernels() -> tuple[Any, ...]:
    """The bowling lane's kernel: the friction and oil at the ball's contact, called before every
    step of every throw from the foul line (``nbst bowl throw/frame/solve --foul-line/...``)."""
    from nbst.models.bowling.lane.friction import contact_step

    return (contact_step,)


def many_disks_problem(n: int = 144) -> Any:
    """A small many-disk problem (n disks on a grid, targets shifted): what the warm-up runs
    so the cell-grid kernel and multiword signatures are compiled too.

    Args:
        n: the number of disks (144 by default: past ``CELLS_MIN_DISKS``, on the cell grid).

    Returns:
        The :class:`nbst.problem.Problem`.
    """
    from nbst.problem import problem_from_dict

    side = int(n ** 0.5 + 0.999)
    disks = [{"start": [20.0 + 40.0 * (k % side), 20.0 + 40.0 * (k // side)],
              "target": [40.0 + 40.0 * (k % side), 20.0 + 40.0 * (k // side)], "radius": 5.0} for k in range(n)]
    return problem_from_dict({"name": f"grid-{n}", "box": [40.0 * side + 40.0, 40.0 * side], "t_final": 2.0,
                              "target_radius": 5.0, "disks": disks})


# --- the groups: each runs its kernels once, with the arrays the commands pass them -------------

def _over5() -> tuple[Any, Any, Any]:
    """over5 (cueable and noncueable disks: every branch's types), its straight shots, and 3x them
    as a solution file gives them: read-only arrays, which numba compiles as other signatures than
    writable ones (a motion with events: a record of one event or none is typed as a contiguous
    array, of two or more as a strided one)."""
    from nbst.problem import load_problem
    from nbst.solution import solution_from_dict

    p = load_problem("over5")
    V = p.straight_velocities()
    return p, V, solution_from_dict({"velocities": (3.0 * V).tolist()}, p).velocities


def warm_events() -> None:
    """The event kernel and its batch evaluation, which every other group calls, with writable and
    read-only velocities (simulate hands the event kernels read-only velocities whatever it is given)."""
    import numpy as np

    from nbst.sim import evaluate, simulate

    p, V, Vro = _over5()
    simulate(p, V).at([0.0, 1.0])
    evaluate(p, np.stack([V, V]))
    simulate(p, Vro).at([0.0, 1.0])


def warm_searches() -> None:
    """nbst's search loop (plain and ``--robust``) and the paper's (``--variant A`` and its simplified
    variants), which share their population kernels; and validate's sensitivity report (the Jacobian;
    from a file, and from the library: the tests) and the many-body search's two-disk contacts, which
    share the Jacobian and aiming kernels with nbst's loop, as ``nbst generate``'s placing of disks
    shares the aiming kernel (other signatures of the same kernels: compiled in this group, never
    beside it)."""
    import numpy as np

    from nbst.planted import planted
    from nbst.search.aim import pair_contact
    from nbst.sim.jacobian import final_jacobian
    from nbst.sim.sensitivity import analyze
    from nbst.solvers.dispatch import solve_with

    p, V, Vro = _over5()
    solve_with("signature", p, seed=0, max_trials=3000, patience=0, variant="nbst")
    solve_with("signature", p, seed=0, max_trials=3000, patience=0, variant="nbst", robust=True)
    solve_with("signature", p, seed=0, max_trials=3000, patience=0, variant="A")
    for v in (Vro, 3.0 * V):
        final_jacobian(p, v)
        analyze(p, v, timestep=0.00025)
    ka = many_disks_problem().kernel_arrays()
    pair_contact(ka.start[0], ka.start[1], ka.target[0], ka.target[1], 1.0, 1.0, 5.0, 5.0, ka.W, ka.H, ka.t_final, 8,
                 np.empty((2, 5)))
    planted(20, noncue=2, seed=0)


def warm_many_disks() -> None:
    """The cell-grid kernel (``CELLS_MIN_DISKS`` disks and more), the keyframes and replays for N
    disks, the multiword signatures' batch evaluation; and ``nbst generate``'s assigning of a
    formation's targets."""
    import numpy as np

    from nbst.formation import formation
    from nbst.sim import evaluate, simulate

    many = many_disks_problem()
    Vm = many.straight_velocities()
    tr = simulate(many, Vm)
    tr.at([0.0, 1.0], replay=False)
    tr.at([0.0, 1.0], replay=True)
    tr.velocity_at([0.5], replay=True)
    evaluate(many, np.stack([Vm, Vm]), jobs=1)
    formation("nbst", 40, seed=0)


def warm_lane() -> None:
    """Compile the lane's kernel with the arrays a throw passes it: one short throw of the default
    delivery (the ball alone on the house shot; MuJoCo's model compile included, under a second)."""
    from nbst.models.bowling.lane import phases
    from nbst.models.bowling.lane.delivery import Delivery

    phases.run(Delivery(at="foul", board=20.0, angle=2.0), "house")


#: What every other group calls: compiled first, alone, so that the groups after it load it from
#: the cache and no two processes write its cache at once.
FIRST = KernelGroup("event kernel", "warm_events")

#: Every other kernel the commands call, in groups that compile no kernel in common (beyond
#: :data:`FIRST`'s, in the cache before them: numba's index of a kernel's signatures is one file, and
#: of two processes adding to it at once, one loses its addition), the slowest first (the order the
#: processes take them in). Both paths of :func:`warm_all` run this list. Single-core CPU time on a
#: cold cache after :data:`FIRST` (2026-12-06, the 2-core development machine): searches 94 s,
#: many-disk simulator 80 s, bowling lane 4 s; :data:`FIRST` 17 s (docs/install.md).
GROUPS: tuple[KernelGroup, ...] = (
    KernelGroup("searches", "warm_searches"),
    KernelGroup("many-disk simulator", "warm_many_disks"),
    KernelGroup("bowling lane", "warm_lane"),
)


def _run_group(function: str) -> float:
    """A worker process's job: one group, by its function's name; returns its seconds."""
    return KernelGroup(function, function).run()


def warm_all(log: Log | None = None, *, jobs: int = 1) -> float:
    """Compile (or load from the cache) every kernel the commands use: :data:`FIRST`, then each of
    :data:`GROUPS`.

    Args:
        log: gets one line per group as it finishes: ``"<name> ready (<its s>, <s since the start> in
            all)"``.
        jobs: processes: 1 runs the groups here, one after the other (and leaves every kernel loaded
            in this process); more runs the groups after the first in up to that many worker
            processes at once (numba compiles a kernel on one core), which write the cache and
            leave this process with the event kernel only. A worker that fails has its group run
            here after the others.

    Returns:
        The seconds it took.
    """
    say = log or (lambda s: None)
    t0 = time.perf_counter()

    def done(g: KernelGroup, secs: float) -> None:
        say(f"{g.name} ready ({secs:.0f} s; {time.perf_counter() - t0:.0f} s in all)")

    done(FIRST, FIRST.run())
    left = list(GROUPS)
    if jobs > 1:
        left = _in_workers(left, min(jobs, len(left)), done)
    for g in left:
        done(g, g.run())
    return time.perf_counter() - t0


def _in_workers(groups: Sequence[KernelGroup], workers: int,
                done: Callable[[KernelGroup, float], None]) -> list[KernelGroup]:
    """Run ``groups`` in ``workers`` fresh processes (spawned: no fork of a process that has numba's
    threads), reporting each to ``done`` as it finishes; returns the groups that did not run."""
    import concurrent.futures as cf
    import multiprocessing

    from nbst.warmup import _run_group  # by its module's name, also under `python -m nbst.warmup`

    try:
        pool = cf.ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn"))
    except (OSError, ValueError):
        return list(groups)
    failed = []
    with pool:
        futures = {pool.submit(_run_group, g.function): g for g in groups}
        for f in cf.as_completed(futures):
            try:
                done(futures[f], f.result())
            except Exception:  # noqa: BLE001 - a worker that cannot run (or died): run its group here
                failed.append(futures[f])
    return failed


def compile_message() -> str:
    """The one-time message before numba compiles (setup and the first solve say the same)."""
    return "nbst: compiling numba kernels (one time)"


def announce(kernels: Sequence[Any], *, stream: TextIO | None = None) -> bool:
    """If ``kernels`` are cold, write the one-time compile message to ``stream``
    (stderr by default) and return True."""
    if not is_cold(*kernels):
        return False
    print(f"{compile_message()}; `python -m nbst.warmup` does it ahead", file=sys.stderr if stream is None else stream,
          flush=True)
    return True


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m nbst.warmup [--quiet] [--jobs N]``: compile what is not in the cache yet, one
    process per core (``--jobs``: how many; 1 compiles here, one group after the other). Says so,
    each group's time as it finishes and the total, only when there was something to compile."""
    import argparse

    from nbst.parallel import default_jobs

    ap = argparse.ArgumentParser(prog="python -m nbst.warmup", description=main.__doc__, allow_abbrev=False)
    ap.add_argument("-q", "--quiet", action="store_true", help="say nothing")
    ap.add_argument("--jobs", type=int, default=default_jobs(), metavar="N",
                    help="processes at once (default: every core; 1: here, one group after the other)")
    args = ap.parse_args(argv)
    quiet, jobs = args.quiet, max(1, args.jobs)
    cold = is_cold(*search_kernels(), *other_kernels(), *lane_kernels())
    talk = cold and not quiet
    if talk:
        n = min(jobs, len(GROUPS))
        print(f"{compile_message()}: {FIRST.name} first, then {len(GROUPS)} groups "
              f"{f'on {n} processes at once' if n > 1 else 'one after the other'}", file=sys.stderr, flush=True)
    secs = warm_all((lambda s: print(f"nbst:   {s}", file=sys.stderr, flush=True)) if talk else None,
                    jobs=jobs if cold else 1)
    if talk:
        print(f"nbst: numba kernels compiled and cached in {secs:.0f} s", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
