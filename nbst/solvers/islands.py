"""Independent searches on every core ("islands"), stopped together, reproducible for a given K.

``nbst solve --jobs K`` runs K copies of one registered solver (``nbst.solvers.dispatch.run_solver``),
each from its own seed and with 1/K of the trial budget: island 0 in this process, the others in
K - 1 worker processes started after island 0's first chunk of trials (if that did not already
reach the target). They run in lockstep: after every chunk each island reports its best cost to
the parent and waits for a go-ahead. The parent stops all of them at the first round in which
any island has reached the target cost (or when every island has ended by budget or patience),
then takes the best island's solution. Every decision is taken at a round boundary, from states
that depend only on each island's seed: the same (seed, K) gives the same result.

Seeds: island k gets ``island_seeds(seed, K)[k]`` (numpy's ``SeedSequence(seed).spawn``);
with K = 1 there is no worker and the search is exactly ``solve(seed=seed)``.

Trial accounting: ``result.trials`` is the sum over islands (every simulation counted),
``result.islands`` lists each island's seed, configuration, trials, cost and why it stopped.

The portfolio: nbst's default search on a problem with noncueable disks is a portfolio of
two configurations, ``PORTFOLIO`` = ("nbst", "nbst-noplan"): island k runs
``PORTFOLIO[k % 2]`` (with the backward planner on even islands, without it on odd
ones), because neither dominates the other on over5 (docs/search.md, "The portfolio").
With ``jobs`` = 1 its two islands take turns in threads of this process, chunk by chunk (one
core): the result of ``jobs`` = 2. A portfolio island whose search stops by patience with budget
left restarts with the next configuration from a fresh seed (``run_island``). On an all-cueable
problem the planner never runs: one search, no portfolio (``portfolio_for``).

Length: the parent's lockstep rounds (``_Rounds``, ``solve_islands``) and the islands' side of
them (``_island_body``, its process, thread and Dask hosts) are one protocol, read together.
"""
from __future__ import annotations

import dataclasses
import math
import multiprocessing as mp
import os
import queue
import threading
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from nbst.errors import SolveError
from nbst.outputs import die_with_parent, signals_blocked, signals_deferred
from nbst.problem import Problem
from nbst.search.params import SearchProgress
from nbst.search.variants import DEFAULT_MAX_TRIALS
from nbst.seeds import SEED_MAX, resolve_seed
from nbst.solution import SolveResult
from nbst.solvers.dispatch import SIGNATURE, SOLVERS, SolveRequest, run_solver

if TYPE_CHECKING:
    from nbst.search.params import ProgressCallback

__all__ = ["ISLAND_TIMEOUT", "PORTFOLIO", "portfolio_for", "IslandTask", "island_seeds", "RESTART_MIN_TRIALS",
           "run_island", "restart_seed", "solve_islands", "run_islands"]

#: Seconds the parent waits for an island's report before it declares the island lost.
ISLAND_TIMEOUT = 600.0

#: nbst's portfolio: island k runs the variant ``PORTFOLIO[k % len(PORTFOLIO)]``.
PORTFOLIO = ("nbst", "nbst-noplan")


def portfolio_for(problem: Problem, algorithm: str = SIGNATURE, *, variant: str | None = None,
                  robust: bool = False) -> tuple[str, ...] | None:
    """The configurations the islands take in turn, or None where every island runs the same search.

    The portfolio applies to nbst's default search (algorithm "signature", variant "nbst", not
    robust) on a problem with at least one noncueable disk: the backward planner runs only there,
    so elsewhere "nbst" and "nbst-noplan" are one search, bit for bit. Robust mode keeps its
    single configuration (its results were measured with the planner)."""
    if str(algorithm).strip().lower() != SIGNATURE or robust:
        return None
    if str(variant or "nbst").strip().lower() != "nbst":
        return None
    if bool(np.all(problem.cueable)):
        return None
    return PORTFOLIO


@dataclass(frozen=True)
class IslandTask:
    """What one island runs: a registered solver (``algorithm``) with its own ``request`` (seed and
    budget), or, in nbst's portfolio, searches of the ``portfolio`` configurations in turn."""

    algorithm: str
    request: SolveRequest
    portfolio: tuple[str, ...] | None = None


def island_seeds(seed: int, jobs: int) -> list[int]:
    """K independent seeds derived from ``seed`` (non-negative int64s)."""
    if jobs == 1:
        return [int(seed)]
    return [int(s.generate_state(1, np.uint64)[0] & np.uint64(SEED_MAX))
            for s in np.random.SeedSequence(int(seed)).spawn(int(jobs))]


def _island_body(k: int, task: IslandTask, problem: Problem, conn, baton=None) -> None:
    """Run one search; report after every chunk and wait for the parent's word; send the
    result (or the error) at the end. ``baton`` (a lock, islands in threads): held while a
    chunk runs, so that the threads of one process take turns."""

    def callback(p: SearchProgress) -> bool:
        if baton is not None:
            baton.release()
        conn.send(("progress", k, p.trials, p.best_cost, p.best_order))
        word = conn.recv()
        if baton is not None:
            baton.acquire()
        return word == "stop"

    if baton is not None:
        baton.acquire()
    try:
        result = run_island(task, problem, callback=callback)
        _give(baton)
        conn.send(("done", k, result))
    except BaseException as e:  # noqa: BLE001 - reported to the parent, which raises it
        _give(baton)
        try:
            conn.send(("error", k, f"{type(e).__name__}: {e}"))
        except OSError:
            pass


#: A portfolio island restarts (next configuration, fresh seed) when its search stops by patience
#: with at least this many trials of its budget left.
RESTART_MIN_TRIALS = 2048


def run_island(task: IslandTask, problem: Problem, callback: ProgressCallback | None = None) -> SolveResult:
    """One island's search: the solver of ``task``, or in a portfolio island a sequence of searches:
    the first with the request's variant and seed; whenever one stops by patience with at least
    ``RESTART_MIN_TRIALS`` of the island's budget left, the next configuration starts from a fresh
    seed (``restart_seed``) with what is left. The best search's result is returned, with
    ``trials`` the island's total and ``meta["runs"]`` one entry per search."""
    request = task.request
    configs = task.portfolio
    if not configs:
        return run_solver(task.algorithm, problem, request, callback)
    budget, seed0 = int(request.max_trials), int(request.seed or 0)
    first = configs.index(request.variant or configs[0])
    spent, best, best_run = 0, None, 0
    runs: list[dict[str, Any]] = []
    while True:
        j = len(runs)
        run_request = dataclasses.replace(request, variant=configs[(first + j) % len(configs)],
                                          seed=restart_seed(seed0, j), max_trials=budget - spent)
        base, floor = spent, (math.inf if best is None else best.cost)

        def cb(p: SearchProgress, base: int = base, floor: float = floor) -> bool:
            if callback is None:
                return False
            return bool(callback(SearchProgress(trials=base + p.trials, best_cost=min(floor, p.best_cost),
                                                best_order=p.best_order, elapsed=p.elapsed,
                                                population=p.population, phase=p.phase)))

        result = run_solver(task.algorithm, problem, run_request, cb)
        spent += result.trials
        runs.append({"seed": run_request.seed, "variant": run_request.variant, "trials": result.trials,
                     "cost": result.cost, "stopped": result.stopped})
        if best is None or result.cost < best.cost:
            best, best_run = result, j
        if result.stopped != "patience" or budget - spent < RESTART_MIN_TRIALS:
            break
    return best.with_meta({"trials": spent, "runs": runs, "run": best_run, "stopped": runs[-1]["stopped"]})


def restart_seed(seed: int, j: int) -> int:
    """The seed of a portfolio island's j-th search: ``seed`` itself for j = 0, then derived."""
    if j == 0:
        return int(seed)
    return int(np.random.SeedSequence([int(seed), int(j)]).generate_state(1, np.uint64)[0] & np.uint64(SEED_MAX))


def _give(baton) -> None:
    """Release ``baton`` (an RLock) if this thread holds it."""
    if baton is not None:
        try:
            baton.release()
        except RuntimeError:  # not held by this thread
            pass


def _island(k: int, task: IslandTask, problem: Problem, conn, parent_pid: int, inherited: list) -> None:
    """Forked worker: one island over a pipe. It ignores Ctrl-C, SIGTERM and SIGHUP (the parent
    decides and stops its islands) and dies with the parent, even one killed by SIGKILL
    (``die_with_parent``). The parent's ends of the pipes that fork copied here (``inherited``)
    are closed, so the parent's death also reads as end-of-file on this island's pipe."""
    die_with_parent(parent_pid)
    for c in inherited:
        c.close()
    try:
        _island_body(k, task, problem, conn)
    finally:
        conn.close()
        os._exit(0)  # nothing to tear down: skip the interpreter's exit work (tens of ms)


class _ThreadConn:
    """One end of a pipe made of two ``queue.Queue`` (islands in threads): send, recv, poll, close."""

    _EMPTY: type[Exception] = queue.Empty  # what the in-queue's get raises on a timeout

    def __init__(self, out_q, in_q):
        self._out, self._in = out_q, in_q
        self._held: list = []

    def send(self, obj) -> None:
        self._out.put(obj)

    def poll(self, timeout: float) -> bool:
        if not self._held:
            try:
                self._held.append(self._in.get(timeout=timeout))
            except self._EMPTY:
                return False
        return True

    def recv(self):
        if self._held:
            return self._held.pop()
        return self._in.get()

    def close(self) -> None:
        pass


class _QueueConn(_ThreadConn):
    """One end of a pipe made of two Dask queues (``--cluster``): the same ends as ``_ThreadConn``."""

    _EMPTY = TimeoutError

    def __init__(self, out_name: str, in_name: str, client=None):
        from dask.distributed import Queue

        super().__init__(Queue(out_name, client=client), Queue(in_name, client=client))


def _island_dask(k: int, task: IslandTask, problem: Problem, names: tuple) -> int:
    """A Dask task: one island, talking to the parent through two named queues."""
    _island_body(k, task, problem, _QueueConn(*names))
    return k


class _Rounds:
    """The parent's side of the lockstep: one round = one report from every live island."""

    def __init__(self, jobs: int, conns: dict, target: float, callback, t0: float):
        self.jobs, self.conns, self.target, self.callback, self.t0 = jobs, conns, target, callback, t0
        self.trials = [0] * jobs
        self.best = [math.inf] * jobs
        self.order = [0] * jobs
        self.results: dict[int, SolveResult] = {}
        self.live: set[int] = set()  # worker islands still running
        self.stop_reason: str | None = None
        self.pending: list[int] = []

    def barrier(self, local=None) -> bool:
        """Collect this round's reports (``local``: island 0's own (trials, cost, order) when the
        parent runs it), decide, answer the workers; True = stop."""
        from nbst.search import SearchProgress

        if local is not None:
            self.trials[0], self.best[0], self.order[0] = local
        self.answer_pending()
        waiting = self.pending  # workers that reported this round and wait for the word
        for k in sorted(self.live):
            try:
                if not self.conns[k].poll(ISLAND_TIMEOUT):
                    raise SolveError(f"island {k} stopped answering")
                with signals_deferred():  # a message taken is a message booked: a Ctrl-C waits for it
                    self._book(k, self.conns[k].recv(), waiting)
            except (EOFError, OSError):  # the worker died (killed): lost, the others go on
                self.live.discard(k)
        stop = min(self.best) <= self.target or self.stop_reason is not None
        if self.callback is not None and (waiting or local is not None):
            i = int(np.argmin(self.best))
            prog = SearchProgress(trials=int(sum(self.trials)), best_cost=float(self.best[i]),
                                  best_order=int(self.order[i]), elapsed=time.perf_counter() - self.t0,
                                  population=0, phase=f"islands: {len(self.live) + (local is not None)}")
            if self.callback(prog):
                stop, self.stop_reason = True, self.stop_reason or "callback"
        if stop and self.stop_reason is None:
            self.stop_reason = "target"
        self.answer_pending()
        return stop

    def _book(self, k: int, msg: tuple, waiting: list) -> None:
        """One island's report: its progress (it then waits for the word), its result or its error."""
        if msg[0] == "progress":
            _, _, self.trials[k], self.best[k], self.order[k] = msg
            waiting.append(k)
        elif msg[0] == "done":
            self.results[k] = msg[2]
            self.trials[k] = msg[2].trials
            self.live.discard(k)
        else:
            raise SolveError(f"island {k} failed: {msg[2]}")

    def answer_pending(self) -> None:
        """Give the waiting workers the word (also those a Ctrl-C left unanswered); a Ctrl-C cannot
        come between taking a worker off the list and answering it."""
        say = "go" if self.stop_reason is None else "stop"
        with signals_deferred():
            while self.pending:
                k = self.pending[-1]
                try:
                    self.conns[k].send(say)
                except (BrokenPipeError, OSError):
                    self.live.discard(k)
                self.pending.pop()


def solve_islands(problem: Problem, *, jobs: int, seed: int | None = None, algorithm: str = SIGNATURE,
                  max_trials: int = DEFAULT_MAX_TRIALS, patience: int | None = None,
                  target_cost: float | None = None, variant: str | None = None, robust: bool = False,
                  callback: ProgressCallback | None = None, cluster=None, portfolio: bool = True) -> SolveResult:
    """Run ``jobs`` islands of ``algorithm`` on ``problem`` and return the best island's result.

    Island 0 runs in this process; islands 1..K-1 run in forked workers that start after
    island 0's first round (chunk) if that round has not reached the target, and then keep
    in lockstep one round behind it (a fixed pairing, so the result stays deterministic).
    A solver that runs in one process on this problem (``SolverInfo.one_process``: the
    many-body search past 63 disks) runs once, here, with ``jobs`` threads.

    Args:
        problem: the problem.
        jobs: islands (K >= 1).
        seed: the seed the islands' seeds are derived from (``island_seeds``); None draws one.
        algorithm: a name of ``nbst.solvers.dispatch.SOLVERS``.
        max_trials: the total budget: each island gets ceil(max_trials / K).
        patience, target_cost, variant, robust: as ``nbst.solvers.dispatch.SolveRequest``;
            ``patience`` applies per island.
        callback: sees the islands' sum of trials and the best island's cost and order after
            every round; a truthy return stops all of them (``stopped == "callback"``).
        cluster: a ``dask.distributed.Client``; islands 1..K-1 then run as tasks on its workers
            (one worker thread each, for as long as the search runs) and talk to the parent
            through named Dask queues; the rounds are the same, so the result is the same as on
            local processes for the same (seed, K).
        portfolio: True (default): where :func:`portfolio_for` applies (nbst's default search on
            a problem with noncueable disks), island k runs ``PORTFOLIO[k % 2]``, and ``jobs`` = 1
            runs the portfolio's two islands in threads of this process, taking turns chunk by
            chunk (the same result as ``jobs`` = 2); ``result.configuration`` names the variant
            of the written solution's island and ``meta["portfolio"]`` the islands' variants.
            False: every island runs ``variant`` (``jobs`` = 1 is then exactly one search).

    Returns:
        The best island's :class:`~nbst.solution.SolveResult` (lowest cost, ties to the lowest
        island), with ``trials`` the sum over islands, ``island`` and ``islands`` set. Ctrl-C
        stops all islands and returns the best so far (``stopped == "interrupted"``).
    """
    request = SolveRequest(seed=seed, max_trials=max_trials, patience=patience, target_cost=target_cost,
                           variant=variant, robust=robust)
    return run_islands(problem, request, jobs=jobs, algorithm=algorithm, callback=callback, cluster=cluster,
                       portfolio=portfolio)


def run_islands(problem: Problem, request: SolveRequest, *, jobs: int, algorithm: str = SIGNATURE,
                callback: ProgressCallback | None = None, cluster=None, portfolio: bool = True) -> SolveResult:
    """:func:`solve_islands` with the search's settings as one object (what ``nbst solve`` builds).

    Args:
        problem: the problem.
        request: seed (None draws one), the total budget ``max_trials`` (each island gets
            ceil(max_trials / K)), patience (per island), target cost, variant and robust mode
            (:class:`~nbst.search.variants.SolveRequest`; its ``jobs`` is not read: ``jobs`` is).
        jobs, algorithm, callback, cluster, portfolio: as :func:`solve_islands`.

    Returns:
        The best island's :class:`~nbst.solution.SolveResult`, as :func:`solve_islands`.

    Raises:
        SolveError: ``jobs`` < 1, or an island failed.
        InputError: an unknown algorithm, or a seed out of range.
    """
    jobs = int(jobs)
    if jobs < 1:
        raise SolveError(f"jobs must be >= 1, got {jobs}")
    algorithm = SOLVERS.parse(algorithm, source="<search parameters>", field="algorithm")
    if SOLVERS[algorithm].one_process(problem):
        return run_solver(algorithm, problem, dataclasses.replace(request, jobs=jobs), callback)
    seed = resolve_seed(request.seed)
    variant, max_trials, target_cost = request.variant, request.max_trials, request.target_cost
    configs = portfolio_for(problem, algorithm, variant=variant, robust=bool(request.robust)) if portfolio else None
    request = dataclasses.replace(request, seed=seed, jobs=None)
    if jobs == 1 and configs is None:
        return run_solver(algorithm, problem, request, callback)
    threads = jobs == 1  # the portfolio on one core: its islands take turns in threads of this process
    cycle = configs or ()
    n_islands = len(cycle) if threads else jobs
    seeds = island_seeds(seed, n_islands)
    budget = max(1, math.ceil(int(max_trials) / n_islands))
    target = -math.inf if target_cost is None else float(target_cost)
    ctx: Any = mp.get_context("fork" if "fork" in mp.get_all_start_methods() else "spawn")
    tasks = [IslandTask(algorithm, dataclasses.replace(request, seed=seeds[k], max_trials=budget,
                                                       variant=cycle[k % len(cycle)] if cycle else variant),
                        configs) for k in range(n_islands)]
    conns: dict[int, Any] = {}  # the parent's end of each worker's pipe
    procs: list[Any] = []  # threads, processes or Dask futures
    baton = threading.RLock() if threads else None  # held by the island whose chunk runs

    def start_workers() -> None:
        if threads:
            for k in range(1, n_islands):
                q_down: queue.Queue = queue.Queue()
                q_up: queue.Queue = queue.Queue()
                conns[k] = _ThreadConn(q_down, q_up)  # the parent sends down, hears up
                t = threading.Thread(target=_island_body, daemon=True, name=f"nbst-island-{k}",
                                     args=(k, tasks[k], problem, _ThreadConn(q_up, q_down), baton))
                t.start()
                rounds.live.add(k)
                procs.append(t)
            return
        if cluster is not None:
            tag = f"nbst-islands-{os.getpid()}-{time.monotonic_ns()}"
            for k in range(1, n_islands):
                up, down = f"{tag}-{k}-up", f"{tag}-{k}-down"
                conns[k] = _QueueConn(down, up, client=cluster)  # the parent sends down, hears up
                procs.append(cluster.submit(_island_dask, k, tasks[k], problem, (up, down), pure=False))
                rounds.live.add(k)
            return

        for k in range(1, n_islands):
            parent, child = ctx.Pipe()
            p = ctx.Process(target=_island, daemon=True,
                            args=(k, tasks[k], problem, child, os.getpid(),
                                  [parent, *conns.values()]))
            with signals_blocked():  # no Ctrl-C reaches the child before it ignores it (die_with_parent),
                p.start()  # nor comes between starting a worker and booking it
                child.close()
                conns[k] = parent
                rounds.live.add(k)
                procs.append(p)

    rounds = _Rounds(n_islands, conns, target, callback, time.perf_counter())
    interrupted = False
    try:
        def local(p) -> bool:
            _give(baton)  # the thread islands run their chunks while this one waits at the barrier
            if rounds.barrier((p.trials, p.best_cost, p.best_order)):
                return True
            if not procs:  # island 0's first round ran alone (most easy problems end there)
                start_workers()
            if baton is not None:
                baton.acquire()
            return False

        if baton is not None:
            baton.acquire()
        result0 = run_island(tasks[0], problem, callback=local)
        _give(baton)
        rounds.results[0] = result0
        interrupted = result0.stopped == "interrupted"
        if interrupted:
            rounds.stop_reason = "interrupted"
        while rounds.live:
            rounds.barrier()
    except KeyboardInterrupt:
        interrupted = True
    finally:
        _give(baton)  # an interrupted island 0 may still hold it
        with signals_deferred(reraise=False) as late:  # a Ctrl-C cannot cut the drain short: the islands' best
            if interrupted or rounds.live:
                rounds.stop_reason = "interrupted" if interrupted else (rounds.stop_reason or "error")
                rounds.answer_pending()
                _drain(conns, rounds.live, rounds.results, say="stop")
            for p in procs:
                if cluster is not None and not threads:
                    p.cancel()  # a task still running after the drain (lost island)
                    continue
                p.join(timeout=5)
                if threads:
                    continue  # a daemon thread: nothing to kill
                if p.is_alive():
                    p.kill()
        if late:  # a signal during the drain: the result says so (the CLI exits 130 with it written)
            interrupted = True
    results = rounds.results
    if not results:
        raise KeyboardInterrupt  # interrupted before any island had a result: nothing to write
    # the best island: lowest cost, ties to the lowest index (deterministic)
    k = min(results, key=lambda i: (results[i].cost, i))
    best = results[k]
    meta = dict(best.meta)
    meta["islands"] = [{"island": i, "seed": seeds[i], "trials": results[i].trials, "cost": results[i].cost,
                        "stopped": results[i].stopped}
                       if i in results else {"island": i, "seed": seeds[i], "trials": rounds.trials[i],
                                             "cost": None, "stopped": "lost"} for i in range(n_islands)]
    if configs:
        for e in meta["islands"]:
            e["variant"] = tasks[e["island"]].request.variant
            if e["island"] in results:
                e["runs"] = results[e["island"]].meta["runs"]
        meta["configuration"] = best.variant  # the variant that produced the written solution
        meta["search_seed"] = meta.pop("runs")[meta.pop("run")]["seed"]  # and its seed
        meta["variant"] = "nbst"  # what was asked for: nbst's search, the portfolio
        meta["portfolio"] = [e["variant"] for e in meta["islands"]]
    meta["jobs"] = jobs
    meta["island"] = k
    meta["seed"] = int(seed)
    meta["island_seed"] = seeds[k]
    meta["trials"] = int(sum(e["trials"] for e in meta["islands"]))
    meta["wall_time"] = time.perf_counter() - rounds.t0
    if interrupted:
        meta["stopped"] = "interrupted"
    elif rounds.stop_reason in ("callback", "error"):
        meta["stopped"] = rounds.stop_reason
    elif best.stopped == "callback":  # stopped because another island reached the target
        meta["stopped"] = "target_cost"
    return SolveResult.from_meta(problem, best.velocities, meta)


def _drain(conns, live, results, *, say: str) -> None:
    """Tell the live islands to stop and collect what they return (best so far)."""
    deadline = time.monotonic() + 30
    pending = set(live)
    while pending and time.monotonic() < deadline:
        for k in sorted(pending):
            try:
                if not conns[k].poll(0.05):
                    continue
                msg = conns[k].recv()
            except (EOFError, OSError):
                pending.discard(k)
                continue
            if msg[0] == "progress":
                conns[k].send(say)
            elif msg[0] == "done":
                results[k] = msg[2]
                pending.discard(k)
            else:
                pending.discard(k)
