"""Experiments: many independent runs of the search and the baselines, and their summaries.

A run is a pure function of its :class:`RunSpec` (problem, entry, seed, trial budget):
:func:`run_one` returns a JSON-ready dict. :func:`run_specs` executes specs locally in a
process pool or on a Dask cluster and writes each finished run to its own JSON file
(atomically) as soon as it finishes, so a crash loses no finished run and running the
same specs again skips the finished ones. The summaries (:func:`curves_rows`,
:func:`ablation_rows`, :func:`compare_rows`) are pure functions of the results; plots
and tables are drawn by ``nbst.experiments.plots``.

Entries name what runs, read from the two registries: every variant of the signature search
(``nbst.search.variants.VARIANTS``: ``nbst``, ``nbst-noplan``, ``A`` .. ``H``) and every other
registered solver (``nbst.solvers.SOLVERS``: the baselines ``cma``, ``de``, ``ga``, ``random``, and
any solver registered since). Every run uses its whole budget (patience off) unless a target
cost is given.
"""
from __future__ import annotations

import hashlib
import json
import math
import os
import statistics
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Iterable

from nbst.domain import plain
from nbst.outputs import die_with_parent, signals_blocked, signals_deferred, write_json_atomic
from nbst.problem import Problem, ProblemError, problem_from_dict, read_json

__all__ = ["SCHEMA_VERSION", "RUNS_DIR", "SIGNATURE_MEANS", "variant_entries", "solver_entries", "entries",
           "parse_entry", "parse_entries", "problem_digest", "RunSpec", "MAX_NAME_PART", "safe_name", "make_specs",
           "run_one", "RUN_FILE_MAX", "check_run_file", "run_path", "run_specs", "best_so_far", "curves_rows",
           "ablation_rows", "solved_at", "compare_rows", "compare_detail_rows", "fmt"]

SCHEMA_VERSION = 1
#: Run files live under this folder of the output folder.
RUNS_DIR = "runs"
#: An entry that names the signature search itself means its default variant.
SIGNATURE_MEANS = "nbst"


def variant_entries() -> tuple[str, ...]:
    """The signature search's variants (``nbst.search.variants.VARIANTS``), as entries."""
    from nbst.search.variants import VARIANTS

    return VARIANTS.names()


def solver_entries() -> tuple[str, ...]:
    """The registered solvers that take no variant (the baselines, and any solver registered
    since), as entries."""
    from nbst.solvers import SOLVERS

    return tuple(e.name for e in SOLVERS.entries() if not e.value.variants)


def entries() -> tuple[str, ...]:
    """Every entry, variants first: what the ablation runs by default (the paper's Figures 7/8,
    A-H, plus nbst's default and each baseline)."""
    return variant_entries() + solver_entries()


def parse_entry(text: str) -> str:
    """"a" -> "A", "NBST" -> "nbst", "CMA" -> "cma"; "signature" -> "nbst"; ProblemError for an unknown name."""
    from nbst.search.variants import VARIANTS
    from nbst.solvers import SOLVERS

    if text.strip().lower() == "signature":
        return SIGNATURE_MEANS
    if text in VARIANTS:
        return VARIANTS.parse(text)
    if text in SOLVERS and text.strip().lower() in solver_entries():
        return SOLVERS.parse(text)
    raise ProblemError("<arguments>", "--algorithms",
                       f"unknown entry {text!r}; choose from {', '.join(entries())} (nbst, nbst-noplan and A-H are "
                       f"variants of the signature search; 'signature' means nbst)")


def parse_entries(text: str) -> tuple[str, ...]:
    """A comma-separated list of entries ("signature" means the default search, nbst)."""
    out: list[str] = []
    for part in text.split(","):
        if not part.strip():
            continue
        e = parse_entry(part)
        if e not in out:
            out.append(e)
    if not out:
        raise ProblemError("<arguments>", "--algorithms", "no entry given")
    return tuple(out)


def problem_digest(problem: Problem) -> str:
    """Short hash of the problem's content (so a changed file is never confused with a cached run)."""
    text = json.dumps(problem.to_dict(), sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:12]


@dataclass(frozen=True, kw_only=True)
class RunSpec:
    """One run: entry (variant A-H / nbst, or a baseline) on a problem with a seed and budget.

    problem     : the problem's JSON dict (self-contained: workers need no file)
    target_cost : stop once the best cost is <= this (None: use the whole budget)
    """

    problem: dict
    entry: str
    seed: int
    trials: int
    target_cost: float | None = None

    @property
    def problem_name(self) -> str:
        return str(self.problem.get("name", "problem"))

    def key(self) -> dict:
        """What identifies the run (stored in its file; a file whose key differs is rerun)."""
        return {"problem": self.problem_name, "problem_sha": problem_digest(problem_from_dict(self.problem)),
                "entry": self.entry, "seed": self.seed, "trials": self.trials, "target_cost": self.target_cost}

    def relpath(self) -> str:
        tc = "" if self.target_cost is None else f"-c{self.target_cost:g}"
        return f"{RUNS_DIR}/{_safe(self.problem_name)}/{self.entry}/t{self.trials}{tc}-s{self.seed}.json"


#: Longest file-name part made from a user's name (ASCII characters): far below the usual
#: 255-byte limit of one file name, with room for a prefix, a hash and an extension.
MAX_NAME_PART = 80


def safe_name(name: str) -> str:
    """A file-name part made from a user's name (a problem's, ``--name``): ASCII letters, digits,
    '-', '_' and '.' only, at most MAX_NAME_PART characters, never empty and never starting with
    '.' (so never '.', '..' or a hidden name; a cache path built from it stays inside ``runs/``).
    A name that had to change gets 8 hex digits of its hash, so two names never share a file."""
    out = "".join(ch if (ch.isascii() and ch.isalnum()) or ch in "-_." else "_" for ch in str(name))
    out = out[:MAX_NAME_PART]
    if out.startswith("."):
        out = "_" + out[1:]
    if out != name or not out:
        digest = hashlib.sha256(str(name).encode("utf-8", "surrogatepass")).hexdigest()[:8]
        out = f"{out or 'problem'}-{digest}"
    return out


_safe = safe_name  # the name nbst.cli.experiment imports


def make_specs(problems: Iterable[Problem], entries: Iterable[str], *, runs: int, trials: int, seed: int = 1,
               target_cost: float | None = None) -> list[RunSpec]:
    """runs x entries x problems specs; run k uses seed ``seed + k`` (the same seeds for every entry).

    ``seed`` defaults to 1 on purpose: an experiment is a fixed, repeatable set of runs.
    """
    problems, entries = list(problems), list(entries)
    return [RunSpec(problem=p.to_dict(), entry=e, seed=seed + k, trials=int(trials), target_cost=target_cost)
            for p in problems for e in entries for k in range(int(runs))]


def run_one(spec: RunSpec) -> dict:
    """Run one spec (pure: the same spec gives the same result, except wall time)."""
    from nbst.solvers import SIGNATURE, SolveRequest, run_solver

    problem = problem_from_dict(spec.problem, source=f"<experiment {spec.problem_name}>")
    variant = spec.entry in variant_entries()
    request = SolveRequest(seed=spec.seed, max_trials=spec.trials, patience=0, target_cost=spec.target_cost,
                           variant=spec.entry if variant else None)
    result = run_solver(SIGNATURE if variant else spec.entry, problem, request)
    m = result.meta  # the run file keeps these of the solution's keys, in this order
    keep = ("algorithm", "cost", "signature", "order", "trials", "seed", "stopped", "wall_time", "trials_per_s",
            "first_full_order_trial", "nbst_version", "history", "restarts")
    return {"schema_version": SCHEMA_VERSION, "kind": "nbst-experiment-run", "key": spec.key(), "n": problem.n,
            **{k: m[k] for k in keep if k in m}, "velocities": result.velocities.tolist()}


#: Largest number a run file may hold where nbst writes a count or a cost (far above any real
#: run: 10^12 trials is the CLI's budget limit; a cost is at most N x the box diagonal squared).
RUN_FILE_MAX = 1e300


def _finite(x, lo: float = 0.0, hi: float = RUN_FILE_MAX) -> bool:
    """A finite number (not a bool) in [lo, hi]."""
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) and lo <= x <= hi


def _cost(x) -> bool:
    """A cost as nbst writes it: a finite number >= 0, or "inf" (strict JSON's infinity: a run
    whose every simulation was cut off). Never -inf, NaN or a JSON ``Infinity``."""
    return x == "inf" or _finite(x)


def _int(x, lo: int = 0, hi: float = RUN_FILE_MAX) -> bool:
    return isinstance(x, int) and not isinstance(x, bool) and lo <= x <= hi


def _run_file_rules(d: dict, spec: "RunSpec") -> tuple:
    """(field, test, required) for every field of a run file that the summaries read."""
    n = len(spec.problem.get("disks", ()))
    trials: int = d["trials"] if _int(d.get("trials")) else 0

    def history(h) -> bool:
        return isinstance(h, list) and len(h) <= trials + 1 and all(
            isinstance(e, list) and len(e) == 3 and _int(e[0], 0, trials) and _cost(e[1]) and _int(e[2], 0, n)
            for e in h)

    def velocities(v) -> bool:
        return isinstance(v, list) and len(v) == n and all(
            isinstance(p, list) and len(p) == 2 and _finite(p[0], -RUN_FILE_MAX) and _finite(p[1], -RUN_FILE_MAX)
            for p in v)

    return (("n", lambda x: x == n, True),
            ("trials", lambda x: _int(x, 0, 10**12), True),
            ("seed", lambda x: x == spec.seed, True),
            ("cost", _cost, True),
            ("order", lambda x: _int(x, 0, n), True),
            ("history", history, True),
            ("velocities", velocities, True),
            ("first_full_order_trial", lambda x: x is None or _int(x, 1, trials), False),
            ("trials_per_s", lambda x: x is None or _finite(x), False),
            ("wall_time", lambda x: x is None or _finite(x), False),
            ("restarts", lambda x: x is None or _int(x), False),
            ("stopped", lambda x: x is None or isinstance(x, str), False))


def check_run_file(path: Path, spec: RunSpec) -> tuple[dict | None, str | None]:
    """A finished run's file, checked: ``(result, None)`` when it can be reused, ``(None, None)``
    when there is no file, ``(None, why)`` when a file is there but cannot be used (not JSON, not
    a run file, another run's, or damaged: a field the summaries read is missing, of the wrong
    type, not finite, or out of its bounds); the caller reports ``why`` in one line and runs it
    again. The file goes through nbst's input gate (``nbst.problem.read_json``: a regular file,
    size and shape bounded), then every number through a finite and bounded test."""
    if not os.path.lexists(path):
        return None, None
    try:
        d = read_json(path)
    except ProblemError as e:
        return None, e.reason
    if not isinstance(d, dict) or d.get("kind") != "nbst-experiment-run":
        return None, "not an nbst experiment run file"
    if d.get("key") != spec.key():
        return None, "holds another run (its key differs: the problem file or settings changed)"
    for field, ok, required in _run_file_rules(d, spec):
        if field not in d:
            if required:
                return None, f"damaged: {field!r} is missing"
            continue
        if not ok(d[field]):
            return None, f"damaged: {field!r} is not what nbst writes there ({_shown(d[field])})"
    return d, None


def _shown(x) -> str:
    """A refused value, short and printable."""
    text = repr(x)
    return text if len(text) <= 40 else text[:37] + "..."


def _load_finished(path: Path, spec: RunSpec) -> dict | None:
    """The reusable result in ``path`` for ``spec``, or None (see ``check_run_file``)."""
    return check_run_file(path, spec)[0]


def run_path(out_dir: str | Path, spec: RunSpec) -> Path:
    """``out_dir / spec.relpath()``, checked to lie inside ``out_dir/runs/`` (ProblemError if not)."""
    out = Path(out_dir)
    path = out / spec.relpath()
    runs = os.path.realpath(out / RUNS_DIR)
    if not os.path.realpath(path).startswith(runs + os.sep):
        raise ProblemError("<experiment>", "", f"the run file of {spec.problem_name!r} would lie outside "
                                               f"{out / RUNS_DIR}")
    return path


def run_specs(specs: list[RunSpec], out_dir: str | Path, *, workers: int | None = None, cluster=None,
              progress: bool = True, desc: str = "runs",
              on_result: Callable[[RunSpec, dict], None] | None = None) -> list[dict]:
    """Execute ``specs``; each finished run is written to ``out_dir/spec.relpath()`` at once.

    Finished runs (a file that parses and has the same key) are loaded, not rerun.
    workers : local processes (default: the machine's cores); 1 runs in this process
    cluster : a Dask scheduler address (``tcp://host:8786``) or a ``dask.distributed.Client``;
              results come back to this process, which writes them
    Returns the results in the order of ``specs``.
    """
    out = Path(out_dir)
    results: list[dict | None] = [None] * len(specs)
    todo = []
    for i, spec in enumerate(specs):
        path = run_path(out, spec)
        d, why = check_run_file(path, spec)
        if d is not None:
            results[i] = d
        else:
            if why:
                print(f"nbst experiment: {plain(path)}: {plain(why)}; running it again", file=sys.stderr)
            todo.append(i)
    bar = None
    if progress:
        from nbst.progress import progress_bar

        bar = progress_bar(total=len(specs), initial=len(specs) - len(todo), unit="run", file=sys.stderr, desc=desc,
                   dynamic_ncols=True)

    def done(i: int, res: dict) -> None:
        if res.get("stopped") == "interrupted":  # Ctrl-C reached the worker: not a finished run
            raise KeyboardInterrupt
        write_json_atomic(run_path(out, specs[i]), res, option="--out")
        results[i] = res
        if on_result is not None:
            on_result(specs[i], res)
        if bar is not None:
            bar.update(1)
            bar.set_postfix_str(f"{specs[i].entry} seed {specs[i].seed}: cost {res['cost']:.6g}", refresh=False)

    try:
        if not todo:
            pass
        elif cluster is not None:
            _run_dask(specs, todo, cluster, done)
        elif (workers or os.cpu_count() or 1) <= 1 or len(todo) == 1 or not _spawn_finds_main():
            for i in todo:
                done(i, run_one(specs[i]))
        else:
            _run_pool(specs, todo, workers or os.cpu_count() or 1, done)
    finally:
        if bar is not None:
            bar.close()
    return results  # type: ignore[return-value]


def _spawn_finds_main() -> bool:
    """Whether spawned workers can start: they re-run the main script from its path, which fails
    when it has none on disk (``python - <<EOF``, an embedding); the runs are then done in this
    process (the same results, one at a time)."""
    main = sys.modules.get("__main__")
    if getattr(getattr(main, "__spec__", None), "name", None):
        return True  # python -m ...: found by name
    path = getattr(main, "__file__", None)
    return path is None or os.path.isfile(path)


def _worker_init(parent_pid: int) -> None:
    """Pool worker setup: leave Ctrl-C, SIGTERM and SIGHUP to the parent, which stops the workers
    (no traceback per worker), and die with the parent even when it is killed by SIGKILL
    (``nbst.outputs.die_with_parent``: PR_SET_PDEATHSIG on Linux, a getppid watchdog everywhere)."""
    die_with_parent(parent_pid)


def _run_pool(specs, todo, workers: int, done) -> None:
    import multiprocessing as mp
    from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait

    # spawn: numba's compiled state and fork do not mix; workers load the cached kernels

    ex = ProcessPoolExecutor(max_workers=min(workers, len(todo)), mp_context=mp.get_context("spawn"),
                             initializer=_worker_init, initargs=(os.getpid(),))
    try:
        with signals_blocked():  # workers start here, signals blocked until their initializer ignores them
            pending = {ex.submit(run_one, specs[i]): i for i in todo}
        while pending:
            finished, _ = wait(pending, return_when=FIRST_COMPLETED)
            for f in finished:
                done(pending.pop(f), f.result())
    except BaseException:
        # interrupted or failed: finished runs are on disk; stop the workers now (they are ours),
        # a second Ctrl-C waiting for it
        with signals_deferred(reraise=False):
            procs = list(getattr(ex, "_processes", {}).values())
            ex.shutdown(wait=False, cancel_futures=True)
            for proc in procs:
                proc.kill()  # the workers ignore SIGTERM (the parent decides); their runs are not finished
            for proc in procs:
                proc.join(5.0)
            ex.shutdown(wait=True)  # now quick: lets the pool release its queues (no leaked-semaphore warning)
        raise
    ex.shutdown(wait=True)


def _run_dask(specs, todo, cluster, done) -> None:
    from dask.distributed import Client, as_completed

    client = cluster if isinstance(cluster, Client) else Client(cluster)
    try:
        futures = client.map(run_one, [specs[i] for i in todo], pure=False)
        index = {f.key: i for f, i in zip(futures, todo)}
        for f in as_completed(futures):
            done(index[f.key], f.result())
    finally:
        if client is not cluster:
            client.close()


# --------------------------------------------------------------------------- summaries (pure)

def best_so_far(history: list, trials: int) -> list[tuple[int, float]]:
    """The step curve [(trial, best cost)] from a run's history, ending at its last trial."""
    pts = [(int(t), float(c)) for t, c, _ in history]
    if pts and pts[-1][0] < trials:
        pts.append((int(trials), pts[-1][1]))
    return pts


def curves_rows(results: list[dict]) -> list[dict]:
    """CSV rows of the best-so-far curves: entry, run, seed, trial, best_cost, order (one per improvement,
    plus the run's last trial)."""
    rows = []
    counters: dict[str, int] = {}
    for r in results:
        e = r["key"]["entry"]
        k = counters[e] = counters.get(e, 0) + 1
        orders = {int(t): int(o) for t, _, o in r["history"]}
        for t, c in best_so_far(r["history"], r["trials"]):
            last = max((tt for tt in orders if tt <= t), default=None)
            rows.append({"problem": r["key"]["problem"], "entry": e, "run": k, "seed": r["seed"], "trial": t,
                         "best_cost": c, "order": orders[last] if last is not None else 0})
    return rows


def _median(xs):
    return statistics.median(xs) if xs else None


def _median_rate(rs: list[dict]):
    m = _median([r["trials_per_s"] for r in rs if r.get("trials_per_s")])
    return None if m is None else round(m)


def ablation_rows(results: list[dict], entries: Iterable[str]) -> list[dict]:
    """Per entry: runs, mean / best / worst final cost, runs reaching order N, median trials/s."""
    rows = []
    for e in entries:
        rs = [r for r in results if r["key"]["entry"] == e]
        if not rs:
            continue
        costs = [float(r["cost"]) for r in rs]
        rows.append({"entry": e, "runs": len(rs), "mean": statistics.fmean(costs), "best": min(costs),
                     "worst": max(costs), "full_order": sum(1 for r in rs if r["order"] == r["n"]),
                     "median_trials": _median([r["trials"] for r in rs]),
                     "median_trials_per_s": _median_rate(rs)})
    return rows


def solved_at(r: dict, target_cost: float | None) -> int | None:
    """The trial at which a run counts as solved: the first with cost <= target_cost (when given),
    else the first with every disk within R (order N)."""
    if target_cost is None:
        return r.get("first_full_order_trial")
    return next((int(t) for t, c, _ in r["history"] if c <= target_cost), None)


def compare_rows(results: list[dict], entries: Iterable[str], *, target_cost: float | None = None) -> list[dict]:
    """Per entry over every problem and run: success rate, trials to solve (median, mean over the
    solved runs; a failed run counts as its budget in ``mean_trials_budget``), median final cost."""
    rows = []
    for e in entries:
        rs = [r for r in results if r["key"]["entry"] == e]
        if not rs:
            continue
        at = [solved_at(r, target_cost) for r in rs]
        ok = [t for t in at if t is not None]
        rows.append({"entry": e, "problems": len({r["key"]["problem_sha"] for r in rs}), "runs": len(rs),
                     "solved": len(ok), "success_rate": len(ok) / len(rs),
                     "median_trials_to_solve": _median(ok),
                     "mean_trials_to_solve": statistics.fmean(ok) if ok else None,
                     "mean_trials_budget": statistics.fmean([t if t is not None else r["key"]["trials"]
                                                            for t, r in zip(at, rs)]),
                     "median_cost": _median([float(r["cost"]) for r in rs]),
                     "median_trials_per_s": _median_rate(rs)})
    return rows


def compare_detail_rows(results: list[dict], *, target_cost: float | None = None) -> list[dict]:
    """One row per run: problem, entry, seed, cost, order, solved_at."""
    return [{"problem": r["key"]["problem"], "entry": r["key"]["entry"], "seed": r["seed"], "cost": r["cost"],
             "order": r["order"], "n": r["n"], "trials": r["trials"], "solved_at": solved_at(r, target_cost)}
            for r in results]


def fmt(x, digits: int = 6) -> str:
    """A table cell: numbers with ``digits`` significant digits, None as an em dash."""
    if x is None:
        return "—"
    if isinstance(x, float):
        if not math.isfinite(x):
            return str(x)
        if x == int(x) and abs(x) < 1e15:
            return f"{int(x):,}"
        return f"{x:.{digits}g}"
    if isinstance(x, int):
        return f"{x:,}"
    return str(x)
