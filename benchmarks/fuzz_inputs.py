"""Fuzz nbst's input handling (issues 12, 23): every bad file or flag must be one line, exit 2.

    python benchmarks/fuzz_inputs.py                       # 100,000 loader inputs, 1,000 + 1,000 CLI runs
    python benchmarks/fuzz_inputs.py --loader 0 --cli 0 --flags 1000   # only every subcommand's flags
    python benchmarks/fuzz_inputs.py --loader 0 --cli 0 --flags 0 --huge   # huge files: time and memory
    python benchmarks/fuzz_inputs.py --loader 20000 --cli 0
    python benchmarks/fuzz_inputs.py --keep /tmp/fuzz      # keep the inputs that broke something

Run on demand, not in the test suite (a full run takes ~20-30 minutes on 2 cores).

Seeds: the built-in problems, planted problems from ``nbst generate`` (and their
planted solutions), straight-line solutions of the built-ins. Mutations, 1-3 per
input, at structure level (extreme and non-finite floats, huge integers, NaN /
Infinity literals, deep nesting, wrong types, missing fields, duplicate starts,
rescaled lengths / velocities / masses, control characters, ``$``, HTML and lone
surrogates in names, too many disks) and at byte level (flips, inserted bytes
including invalid UTF-8 and control characters, deleted / duplicated spans,
truncation, stray JSON tokens).

Part 0 (``--huge``): files of ~64 MB in the shapes that cost a JSON parser most per byte, and
files just under nbst's value cap, each loaded in a fresh process: seconds and peak memory.

Part 1, in-process over 2 processes: each input goes through ``load_problem`` or
``load_solution`` (the files every command reads). Counted: accepted / refused
with ProblemError / any other exception (a bug: a traceback in the CLI). An
accepted problem is simulated with its straight-line velocities, an accepted
solution with its velocities: the final positions must be finite and inside the box.

Part 2, subprocesses of ``python -m nbst.cli``: ``simulate`` (text and ``--json``),
``validate``, ``mjcf``, ``render --still 0`` and ``plot problem|trajectories`` on
small mutated problems and solutions, with a per-run timeout. Counted: exit
codes, tracebacks (stderr containing 'Traceback'), hangs (timeouts), stderr
errors longer than one line, and ``simulate --json`` output that a strict JSON
parser refuses.

Part 3, subprocesses again: every subcommand (problems, simulate, solve, generate, experiment,
validate, mjcf, render of a video, a still and a bowling shot, plot, gallery, bowl solve / atlas /
replay) with random flags: values that keep the work small, values just outside each flag's
domain, and hostile ones (NaN, inf, 1e309, 5,000-digit integers, words, hex). Each run has its own
empty working folder, TMPDIR and HOME (library caches go to one shared folder), its inputs in a
folder of their own and its outputs named under another. Counted: tracebacks, hangs (timeouts), deaths by a signal, multi-line errors, and runs that
leave a file anywhere but their named outputs (partial files included) or change an input.
"""
from __future__ import annotations

import argparse
import collections
import copy
import json
import math
import os
import random
import re
import shutil
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
HOLE = "\u2603HOLE\u2603"  # placeholder string, replaced by raw text after json.dumps

EXTREME_FLOATS = [0.0, -0.0, -1.0, 1e308, -1e308, 1.7976931348623157e308, 5e-324, 1e-300, 1e-165, 1e-12, 1e-7,
                  1e75, 1e200, 1e9, 1e6, 2.0 ** 53 + 1, 0.5, 3.0, math.nan, math.inf, -math.inf]
RAW_TOKENS = ["NaN", "Infinity", "-Infinity", "1e999", "-1e999", "1E400", "-0", "0e0", "1e-400", "1.0e+308",
              "123456789012345678901234567890", "true", "null", '""', "[]", "{}", '"\\ud800"', '"\\u0000"']
NAMES = ["$x^2$", "a$b", "$", "\\$", "\x1b[31mred\x1b[0m", "nul\x00", "two\nlines", "tab\tname", "\x7f", "\u202ertl",
         "<script>alert(1)</script>", "&amp;", "é\u0301", "\ud800", "x" * 300, "", " ", "../../etc/passwd",
         "name with \"quotes\"", "\\", "\u0085nel", "%s%n{}", "\\mathrm{x}", "$\\frac{1}{0}$", "_^{}"]
STRUCT_MUTATORS = ["extreme", "delete", "wrongtype", "dupstart", "scale_len", "scale_vel", "scale_mass", "name",
                   "deep", "bigint", "literal", "disks", "cueable", "velocities"]
BYTE_MUTATORS = ["flip", "insert", "delete", "dup", "truncate", "token", "utf8", "ctrl"]


# --------------------------------------------------------------------------- seeds

def make_seeds(work: Path) -> list[dict]:
    """[{kind, problem (dict), solution (dict or None), tiny}] from built-ins and `nbst generate`."""
    from nbst.problem import builtin_names, load_problem
    seeds = []
    for name in builtin_names():
        p = load_problem(name)
        v = p.straight_velocities()
        seeds.append({"problem": p.to_dict(), "solution": {"problem": p.name, "velocities": v.tolist()},
                      "tiny": False})
    gen = [  # disks, noncueable, radius, box side, t_final, R
        ("3", "0", "10", "200", "0.5", "40"), ("2", "1", "15", "150", "0.4", "30"), ("5", "2", "12", "300", "1", "50"),
        ("4", "0", "1", "100", "0.3", "20"), ("8", "3", "20", "800", "5", "75"), ("2", "0", "5", "60", "0.2", "15")]
    for k, (n, nc, r, box, t, R) in enumerate(gen):
        pf, sf = work / f"gen{k}.json", work / f"gen{k}-sol.json"
        cmd = [sys.executable, "-m", "nbst.cli", "generate", "--planted", n, "--noncue", nc, "--radius", r,
               "--box", box, box, "--t-final", t, "--target-radius", R, "--seed", str(k + 1), "-o", str(pf),
               "--solution", str(sf)]
        res = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT, timeout=300)
        if res.returncode != 0:
            print(f"  generate {k} failed: {res.stderr.strip()[:200]}", file=sys.stderr)
            continue
        seeds.append({"problem": json.loads(pf.read_text()), "solution": json.loads(sf.read_text()),
                      "tiny": int(n) <= 5 and float(t) <= 1})
    return seeds


# --------------------------------------------------------------------------- mutations

def _paths(obj, prefix=()):
    """Every path to a node, with the node."""
    out = [(prefix, obj)]
    if isinstance(obj, dict):
        for k, v in obj.items():
            out += _paths(v, prefix + (k,))
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            out += _paths(v, prefix + (i,))
    return out


def _set(obj, path, value):
    if not path:
        return value
    node = obj
    for k in path[:-1]:
        node = node[k]
    node[path[-1]] = value
    return obj


def _random_value(rng: random.Random):
    c = rng.randrange(8)
    return [rng.choice(EXTREME_FLOATS), rng.choice(NAMES), None, rng.random() < 0.5, [], {},
            [rng.choice(EXTREME_FLOATS)] * rng.randrange(4), rng.randrange(-5, 10 ** rng.randrange(1, 30))][c]


def mutate_struct(doc, kind: str, rng: random.Random, holes: list[str]):
    """One structural mutation of the decoded doc (in place where possible); returns the doc."""
    m = rng.choice(STRUCT_MUTATORS)
    nodes = _paths(doc)
    numbers = [p for p, v in nodes if isinstance(v, (int, float)) and not isinstance(v, bool)]
    if m == "extreme" and numbers:
        return _set(doc, rng.choice(numbers), rng.choice(EXTREME_FLOATS))
    if m == "delete":
        dicts = [(p, v) for p, v in nodes if isinstance(v, dict) and v]
        if dicts:
            p, v = rng.choice(dicts)
            del v[rng.choice(list(v))]
        return doc
    if m == "wrongtype" and len(nodes) > 1:
        return _set(doc, rng.choice(nodes[1:])[0], _random_value(rng))
    if m == "dupstart" and isinstance(doc, dict) and isinstance(doc.get("disks"), list) and len(doc["disks"]) >= 2:
        d = doc["disks"]
        i, j = rng.sample(range(len(d)), 2)
        if isinstance(d[i], dict) and isinstance(d[j], dict):
            d[j]["start"] = copy.deepcopy(d[i].get("start"))
            if rng.random() < 0.5:
                r = rng.choice([1e-300, 1e-12, 1e-6, 1e-3])
                d[i]["radius"] = d[j]["radius"] = r
        return doc
    if m in ("scale_len", "scale_vel", "scale_mass"):
        f = 10.0 ** rng.choice([-320, -300, -200, -165, -100, -12, -6, -3, 1, 1.5, 2, 2.5, 3, 6, 9, 12, 75, 100, 154,
                                200, 300])
        keys = {"scale_len": ("box", "start", "target", "radius", "target_radius"), "scale_vel": ("velocities",),
                "scale_mass": ("mass",)}[m]
        for p, v in nodes:
            if p and any(k in keys for k in p if isinstance(k, str)) and isinstance(v, float):
                _set(doc, p, v * f)
        if m == "scale_mass" and isinstance(doc, dict) and isinstance(doc.get("disks"), list):
            for d in doc["disks"]:
                if isinstance(d, dict) and "mass" not in d:
                    d["mass"] = f if rng.random() < 0.5 else rng.choice([1e308, 1e-308, 1e100, 1e-100])
        return doc
    if m == "name" and isinstance(doc, dict):
        key = rng.choice(["name", "description", "problem"])
        doc[key] = "".join(rng.choice(NAMES) for _ in range(rng.randrange(1, 3)))
        return doc
    if m in ("deep", "bigint", "literal") and len(nodes) > 1:
        path = rng.choice(nodes[1:])[0]
        if m == "deep":
            depth = rng.choice([10, 63, 64, 65, 500, 990, 1000, 5000, 100_000])
            inner = json.dumps(_get(doc, path))
            open_, close = ("[", "]") if rng.random() < 0.7 else ('{"a":', "}")
            holes.append(open_ * depth + inner + close * depth)
        elif m == "bigint":
            digits = rng.choice([20, 308, 309, 310, 399, 400, 401, 4300, 4301, 5001, 20_000])
            holes.append(rng.choice(["", "-"]) + "1" + "0" * (digits - 1))
        else:
            holes.append(rng.choice(RAW_TOKENS))
        return _set(doc, path, HOLE)
    if m == "disks" and isinstance(doc, dict) and isinstance(doc.get("disks"), list) and doc["disks"]:
        how = rng.randrange(3)
        if how == 0:
            doc["disks"] = []
        elif how == 1:
            doc["disks"] = [copy.deepcopy(doc["disks"][0]) for _ in range(rng.choice([64, 100]))]
        else:
            doc["disks"].append(copy.deepcopy(rng.choice(doc["disks"])))
        return doc
    if m == "cueable" and isinstance(doc, dict) and isinstance(doc.get("disks"), list):
        for d in doc["disks"]:
            if isinstance(d, dict) and rng.random() < 0.7:
                d["cueable"] = rng.choice([False, True, 0, 1, "yes", None])
        return doc
    if m == "velocities" and isinstance(doc, dict) and isinstance(doc.get("velocities"), list):
        vel = doc["velocities"]
        how = rng.randrange(4)
        if how == 0 and vel:
            vel.pop()
        elif how == 1:
            vel.append([0.0, 0.0])
        elif how == 2 and vel and isinstance(vel[0], list):
            i = rng.randrange(len(vel))
            vel[i] = [rng.choice(EXTREME_FLOATS), rng.choice(EXTREME_FLOATS)]
        elif vel:
            vel[rng.randrange(len(vel))] = rng.choice([[1.0], [1.0, 2.0, 3.0], "fast", None, [[1.0, 2.0]]])
        return doc
    return doc


def _get(obj, path):
    for k in path:
        obj = obj[k]
    return obj


def mutate_bytes(b: bytes, rng: random.Random) -> bytes:
    m = rng.choice(BYTE_MUTATORS)
    b = bytearray(b)
    n = len(b)
    if n == 0:
        return bytes(b) + b"{"
    i = rng.randrange(n)
    if m == "flip":
        b[i] ^= 1 << rng.randrange(8)
    elif m == "insert":
        b[i:i] = bytes(rng.randrange(256) for _ in range(rng.randrange(1, 5)))
    elif m == "delete":
        del b[i:i + rng.randrange(1, 20)]
    elif m == "dup":
        j = min(n, i + rng.randrange(1, 200))
        b[j:j] = b[i:j]
    elif m == "truncate":
        del b[i:]
    elif m == "token":
        b[i:i] = rng.choice([b"[", b"]", b"{", b"}", b'"', b",", b":", b"1e999", b"NaN", b"-", b"\\", b"\\u"])
    elif m == "utf8":
        b[i:i] = rng.choice([b"\xff", b"\xc3", b"\xed\xa0\x80", b"\xef\xbb\xbf", b"\xc0\xaf"])
    else:
        b[i:i] = bytes([rng.choice([0, 7, 8, 27, 10, 13, 127])])
    return bytes(b)


def make_input(seed: dict, rng: random.Random, kind: str | None = None) -> tuple[str, bytes]:
    """(kind 'problem' | 'solution', file bytes) for one fuzz case (kind drawn unless given)."""
    if kind is None:
        kind = "solution" if seed["solution"] is not None and rng.random() < 0.4 else "problem"
    doc = copy.deepcopy(seed[kind])
    holes: list[str] = []
    for _ in range(rng.choice([0, 1, 1, 2, 3]) if rng.random() < 0.9 else 0):
        doc = mutate_struct(doc, kind, rng, holes)
    text = json.dumps(doc)  # NaN / Infinity literals where the doc holds non-finite floats
    for h in holes:
        text = text.replace(json.dumps(HOLE), h, 1)
    data = text.encode("utf-8", "surrogatepass")
    if rng.random() < 0.35 or (not holes and rng.random() < 0.2):
        for _ in range(rng.choice([1, 1, 2, 4])):
            data = mutate_bytes(data, rng)
    return kind, data


# --------------------------------------------------------------------------- part 1: the loader

_SEEDS: list = []
_BASES: list = []


def _init_worker(seeds):
    global _SEEDS, _BASES
    import warnings

    from nbst.problem import problem_from_dict
    warnings.simplefilter("ignore")
    _SEEDS = seeds
    _BASES = [problem_from_dict(s["problem"], source="<seed>") for s in seeds]


def loader_chunk(args):
    """Run n cases from rng seed; returns counts and up to a few failing inputs."""
    chunk_seed, n, keep = args
    import numpy as np

    from nbst.problem import ProblemError, load_problem
    from nbst.sim import simulate
    from nbst.solution import load_solution

    rng = random.Random(chunk_seed)
    counts = collections.Counter()
    bad = []
    tmp = Path(tempfile.mkdtemp(prefix="nbst-fuzz-"))
    try:
        for k in range(n):
            si = rng.randrange(len(_SEEDS))
            kind, data = make_input(_SEEDS[si], rng)
            f = tmp / f"case-{k % 2}.json"
            f.write_bytes(data)
            try:
                if kind == "problem":
                    p = load_problem(f)
                    v = p.straight_velocities()
                else:
                    p = _BASES[si]
                    v = load_solution(f, p).velocities
            except ProblemError as e:
                counts["refused"] += 1
                field = re.sub(r"\[\d+\]", "[i]", e.field) or "(file)"
                counts[f"refused:{field}"] += 1
                continue
            except Exception as e:  # noqa: BLE001 - this is what the fuzzer looks for
                counts["other"] += 1
                counts[f"other:{type(e).__name__}"] += 1
                if len(bad) < keep:
                    bad.append((kind, data[:100_000], f"{type(e).__name__}: {str(e)[:200]}"))
                continue
            counts["accepted"] += 1
            counts[f"accepted:{kind}"] += 1
            try:
                tr = simulate(p, v)
            except Exception as e:  # noqa: BLE001
                counts["sim_error"] += 1
                if len(bad) < keep:
                    bad.append((kind, data[:100_000], f"simulate: {type(e).__name__}: {str(e)[:200]}"))
                continue
            fp = tr.final_positions
            W, H = p.box
            s = 1e-9 * max(W, H)
            inside = (np.isfinite(fp).all()
                      and (fp[:, 0] >= p.radius - s).all() and (fp[:, 0] <= W - p.radius + s).all()
                      and (fp[:, 1] >= p.radius - s).all() and (fp[:, 1] <= H - p.radius + s).all())
            counts["simulated"] += 1
            if tr.truncated or getattr(tr, "stalled", False):
                counts["sim_truncated"] += 1
            elif not inside:
                counts["sim_outside_or_nonfinite"] += 1
                if len(bad) < keep:
                    bad.append((kind, data[:100_000], "final positions non-finite or outside the box"))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return counts, bad


def run_loader(seeds, n: int, workers: int, seed: int, keep: int):
    chunk = 2000
    jobs = [(seed * 1_000_003 + i, min(chunk, n - i * chunk), keep) for i in range((n + chunk - 1) // chunk)]
    total = collections.Counter()
    bad = []
    t0 = time.perf_counter()
    with ProcessPoolExecutor(workers, initializer=_init_worker, initargs=(seeds,)) as ex:
        for i, (c, b) in enumerate(ex.map(loader_chunk, jobs)):
            total.update(c)
            bad += b
            done = sum(j[1] for j in jobs[: i + 1])
            print(f"\r  loader {done:,}/{n:,} ({time.perf_counter() - t0:.0f} s)", end="", file=sys.stderr)
    print(file=sys.stderr)
    return total, bad, time.perf_counter() - t0


# --------------------------------------------------------------------------- part 2: the CLI

COMMANDS = ["simulate", "simulate-json", "validate", "mjcf", "render", "plot-problem", "plot-trajectories"]


def _argv(cmd: str, pf: Path, sf: Path, out: Path) -> list[str]:
    return {
        "simulate": ["simulate", str(pf), str(sf)],
        "simulate-json": ["simulate", str(pf), str(sf), "--json"],
        "validate": ["validate", str(pf), str(sf), "--timestep", "0.001", "--out-dir", str(out / "rep")],
        "mjcf": ["mjcf", str(pf), str(sf), "-o", str(out / "scene.xml")],
        "render": ["render", str(pf), str(sf), "--still", "0", "-o", str(out / "still.png"), "--size", "64x64", "-q"],
        "plot-problem": ["plot", "problem", str(pf), "-o", str(out / "p.png"), "--dpi", "30"],
        "plot-trajectories": ["plot", "trajectories", str(pf), str(sf), "-o", str(out / "t.png"), "--dpi", "30"],
    }[cmd]


def _strict_json(text: str) -> bool:
    def no(c):
        raise ValueError(c)
    try:
        json.loads(text, parse_constant=no)
        return True
    except ValueError:
        return False


def cli_case(args):
    k, seeds, seed, timeout, base = args
    rng = random.Random(seed * 7_919 + k)
    tiny = [s for s in seeds if s["tiny"]]
    s = rng.choice(tiny)
    cmd = COMMANDS[k % len(COMMANDS)]
    out = base / f"run{k}"
    out.mkdir()
    pf, sf = out / "problem.json", out / "solution.json"
    pdata = json.dumps(s["problem"]).encode()
    sdata = json.dumps(s["solution"]).encode()
    what = rng.randrange(3)  # 0: problem mutated, 1: solution mutated, 2: both
    for kind in (["problem"], ["solution"], ["problem", "solution"])[what]:
        for _ in range(8):  # prefer an input the loader accepts half the time: exercises the commands
            _, data = make_input(s, rng, kind)
            if rng.random() < 0.5 or _loads_ok(kind, data, s):
                break
        if kind == "problem":
            pdata = data
        else:
            sdata = data
    pf.write_bytes(pdata)
    sf.write_bytes(sdata)
    argv = [sys.executable, "-m", "nbst.cli", *_argv(cmd, pf, sf, out)]
    t0 = time.perf_counter()
    try:
        res = subprocess.run(argv, capture_output=True, timeout=timeout, cwd=ROOT,
                             env={**os.environ, "MPLBACKEND": "Agg"})
        rc, so, se = res.returncode, res.stdout, res.stderr
    except subprocess.TimeoutExpired as e:
        rc, so, se = "timeout", e.stdout or b"", e.stderr or b""
    dt = time.perf_counter() - t0
    err = se.decode("utf-8", "replace")
    r = {"cmd": cmd, "rc": rc, "traceback": "Traceback" in err, "seconds": dt,
         "multiline": rc == 2 and err.strip().count("\n") > 0 and "usage:" not in err,
         "ctrl": any(ord(c) < 32 and c not in "\n\t" for c in err)}
    if cmd == "simulate-json" and rc == 0:
        r["json_ok"] = _strict_json(so.decode("utf-8", "replace"))
    if r["traceback"] or rc == "timeout" or r.get("json_ok") is False or r["multiline"] or r["ctrl"]:
        r["stderr"] = err[-600:]
        r["files"] = (pdata[:20_000].decode("utf-8", "replace"), sdata[:20_000].decode("utf-8", "replace"))
    shutil.rmtree(out, ignore_errors=True)
    return r


def _loads_ok(kind, data, s) -> bool:
    from nbst.problem import ProblemError, parse_json, problem_from_dict
    from nbst.solution import solution_from_dict
    try:
        d = parse_json(data.decode("utf-8"), "x")
        if kind == "problem":
            problem_from_dict(d)
        else:
            solution_from_dict(d, problem_from_dict(s["problem"]))
        return True
    except (ProblemError, UnicodeDecodeError):
        return False
    except Exception:  # noqa: BLE001 - a loader bug: keep the case, the CLI run will show it
        return True


def run_cli(seeds, n: int, workers: int, seed: int, timeout: float):
    base = Path(tempfile.mkdtemp(prefix="nbst-fuzz-cli-"))
    results = []
    t0 = time.perf_counter()
    try:
        with ThreadPoolExecutor(workers) as ex:
            for i, r in enumerate(ex.map(cli_case, [(k, seeds, seed, timeout, base) for k in range(n)])):
                results.append(r)
                print(f"\r  cli {i + 1:,}/{n:,} ({time.perf_counter() - t0:.0f} s)", end="", file=sys.stderr)
    finally:
        shutil.rmtree(base, ignore_errors=True)
    print(file=sys.stderr)
    return results, time.perf_counter() - t0


# --------------------------------------------------------------------------- part 3: every subcommand's flags

#: Values no numeric flag may take without a one-line refusal: non-finite, negative, empty, words,
#: literals beyond float64 or Python's int limit, hex, separators, spaces.
BAD_NUMBERS = ["nan", "NaN", "inf", "-inf", "-1", "-0.5", "1e309", "", "abc", "1e-400", "9" * 25, "9" * 5000,
               "0x1f", "1,5", " ", "1e", "--", "1.5.2", "+-3", "\u0663"]
#: Per kind: values that keep the command's work small (drawn 75% of the time), and edges just outside
#: the flag's domain.
GOOD = {
    "seed": (["0", "1", "7", "123456789", str(2**62)], [str(2**63), "-1"]),
    "trials": (["1", "50", "300", "1500"], ["0", "1000000000001"]),
    "patience": (["0", "100", "500"], ["1000000000001"]),
    "jobs": (["1", "2"], ["0", "257"]),
    "runs": (["1", "2"], ["0", "100001"]),
    "cost": (["0", "1e-9", "100", "1e300"], ["-1e-300"]),
    "fps": (["1", "10", "24.5", "240"], ["0", "240.01", "1e9"]),
    "size": (["64x64", "32x48", "16x16", "100x60"], ["15x15", "8193x16", "0x0", "axb", "64", "64x64x64", "-64x64",
                                                      "1e3x1e3", "99999999x9"]),
    "speed": (["1", "2", "10", "0.5"], ["0", "1e7"]),
    "hold": (["0", "0.1", "0.5"], ["61", "60.5"]),
    "still": (["0", "0.1", "0.25", "0.5"], ["1e7", "1e6"]),
    "frames": (["1", "30", "200"], ["0", "10000001"]),
    "dpi": (["10", "30", "50"], ["9", "1201"]),
    "timestep": (["0.001", "0.0005", "0.002"], ["0.02", "1e-8", "0"]),
    "unit": (["0.001", "0.01", "1"], ["1e-7", "1e4", "1e300"]),
    "tol": (["0.5", "1", "1e12"], ["0", "1e13"]),
    "steps": (["100", "2000", "100000"], ["0", "100000001"]),
    "disks": (["1", "2", "3", "4"], ["0", "64", "100"]),
    "noncue": (["0", "1"], ["63", "5"]),
    "radius": (["5", "10", "20"], ["0", "1e9", "500"]),
    "box": (["200", "300", "150"], ["1e-7", "2e9", "0"]),
    "tfinal": (["0.3", "0.5", "1"], ["1e-7", "2e6"]),
    "R": (["20", "50"], ["0", "3e9"]),
    "rollouts": (["0", "1", "3", "5"], ["-1"]),
    "persubset": (["1", "2"], ["0"]),
}


def _value(kind: str, rng: random.Random) -> str:
    good, edge = GOOD[kind]
    r = rng.random()
    if r < 0.75:
        return rng.choice(good)
    if r < 0.88:
        return rng.choice(edge)
    return rng.choice(BAD_NUMBERS)


def _flags(rng: random.Random, table: dict, p: float = 0.4) -> list[str]:
    """Each flag of ``table`` (flag -> kind, or flag -> (kind, nargs)) with probability p."""
    out = []
    for flag, kind in table.items():
        if rng.random() < p:
            if isinstance(kind, tuple):
                out += [flag] + [_value(kind[0], rng) for _ in range(kind[1])]
            else:
                out += [flag, _value(kind, rng)]
    return out


SEARCH_FLAGS = {"--seed": "seed", "--max-trials": "trials", "--patience": "patience", "--target-cost": "cost",
                "--jobs": "jobs"}
RENDER_FLAGS = {"--fps": "fps", "--size": "size", "--speed": "speed", "--hold": "hold", "--max-frames": "frames"}
SCENE_FLAGS = {"--timestep": "timestep", "--unit": "unit"}
FLAG_COMMANDS = ["problems", "simulate", "solve", "generate", "experiment", "validate", "mjcf", "render-video",
                 "render-still", "plot-problem", "plot-trajectories", "gallery", "bowl-solve", "bowl-atlas",
                 "bowl-replay", "render-shot"]


def flag_argv(cmd: str, rng: random.Random, inp: dict, out: Path) -> tuple[list[str], list[Path]]:
    """argv (after ``nbst``) and the outputs it names (files or folders) for one random run of ``cmd``."""
    pf, sf = str(inp["problem"]), str(inp["solution"])
    if cmd == "problems":
        return ["problems", *rng.choice([[], ["show", "over5"], [pf], ["show", pf]])], []
    if cmd == "simulate":
        return ["simulate", pf, sf, *(["--json"] if rng.random() < 0.5 else [])], []
    if cmd == "solve":
        o = out / "sol.json"
        return ["solve", pf, "-o", str(o), "-q", *_flags(rng, SEARCH_FLAGS, 0.7),
                *(["--variant", rng.choice(["A", "nbst", "C"])] if rng.random() < 0.3 else [])], [o]
    if cmd == "generate":
        o, so = out / "gen.json", out / "gen-sol.json"
        fl = _flags(rng, {"--noncue": "noncue", "--radius": "radius", "--box": ("box", 2), "--t-final": "tfinal",
                          "--target-radius": "R", "--seed": "seed"}, 0.5)
        return ["generate", "--planted", _value("disks", rng), "-o", str(o), "--solution", str(so), *fl], [o, so]
    if cmd == "experiment":
        d = out / "exp"
        action = rng.choice(["curves", "ablation", "compare"])
        fl = _flags(rng, {"--runs": "runs", "--seed": "seed", "--jobs": "jobs"}, 0.5)
        trials = ["--max-trials", rng.choice(["1", "50", "200"]) if rng.random() < 0.8 else _value("trials", rng)]
        extra = _flags(rng, {"--target-cost": "cost"}, 0.5) if action == "compare" else []
        return ["experiment", action, pf, "--algorithms", rng.choice(["A", "random", "cma,A"]), "--out-dir", str(d),
                "-q", *trials, *fl, *extra], [d]
    if cmd == "validate":
        d = out / "rep"
        fl = _flags(rng, {**SCENE_FLAGS, "--tol": "tol", "--max-steps": "steps"}, 0.5)
        return ["validate", pf, sf, "-q", *(["--out-dir", str(d)] if rng.random() < 0.5 else []), *fl], [d]
    if cmd == "mjcf":
        o = out / "scene.xml"
        return ["mjcf", pf, sf, "-o", str(o), *_flags(rng, SCENE_FLAGS, 0.6)], [o]
    if cmd == "render-video":
        o = out / rng.choice(["v.mp4", "v.gif"])
        fl = _flags(rng, RENDER_FLAGS, 0.6)
        if "--size" not in fl:
            fl += ["--size", "32x32"]
        return ["render", pf, sf, "-o", str(o), "-q", *fl], [o]
    if cmd == "render-still":
        o = out / "still.png"
        return ["render", pf, sf, "-o", str(o), "-q", "--still", _value("still", rng), "--size",
                _value("size", rng) if rng.random() < 0.5 else "48x32"], [o]
    if cmd in ("plot-problem", "plot-trajectories"):
        o = out / rng.choice(["f.png", "f.svg", "f.pdf"])
        args = ["problem", pf] if cmd == "plot-problem" else ["trajectories", pf, sf]
        return ["plot", *args, "-o", str(o), "-q", *_flags(rng, {"--dpi": "dpi"}, 0.8)], [o]
    if cmd == "gallery":
        d = out / "gal"
        return ["gallery", "over5", "--out-dir", str(d), "--no-search", "-q",
                *_flags(rng, {"--seed": "seed", "--max-trials": "trials"}, 0.5)], [d]
    if cmd == "bowl-solve":
        o = out / "shot.json"
        return ["bowl", "solve", "--down", rng.choice(["1", "7,10", "1,2,4"]), "-o", str(o), "-q", "--no-robustness",
                "--no-atlas", "--jobs", "1", "--max-rollouts", rng.choice(["1", "3", "5"]) if rng.random() < 0.7
                else _value("rollouts", rng), *_flags(rng, {"--seed": "seed"}, 0.5)], \
            [o, o.with_name("shot.scene.xml")]  # and its documented scene beside it
    if cmd == "bowl-atlas":
        d = out / "atlas"
        return ["bowl", "atlas", "--out-dir", str(d), "-q", "--no-robustness", "--jobs", "1", "--max-rollouts",
                rng.choice(["0", "2", "5"]) if rng.random() < 0.7 else _value("rollouts", rng),
                *_flags(rng, {"--seed": "seed", "--per-subset": "persubset"}, 0.4)], [d]
    if cmd == "bowl-replay":
        return ["bowl", "replay", str(inp["shot"]), *(["--json"] if rng.random() < 0.5 else [])], []
    if cmd == "render-shot":
        o = out / rng.choice(["s.png", "s.mp4"])
        still = ["--still", _value("still", rng)] if o.suffix == ".png" else []
        fl = _flags(rng, {k: v for k, v in RENDER_FLAGS.items() if k != "--max-frames"}, 0.6)
        if "--size" not in fl:
            fl += ["--size", "32x32"]
        if "--fps" not in fl and not still:
            fl += ["--fps", "5"]
        return ["render", str(inp["shot"]), "-o", str(o), "-q", *still, *fl], [o]
    raise ValueError(cmd)


def _tree(root: Path) -> dict[str, str]:
    """Every file under root (relative path -> sha256 of its first MB; links as 'link')."""
    import hashlib

    out = {}
    for dirpath, dirs, files in os.walk(root):
        for f in files + [d for d in dirs if os.path.islink(os.path.join(dirpath, d))]:
            p = Path(dirpath) / f
            rel = str(p.relative_to(root))
            if p.is_symlink() or not p.is_file():
                out[rel] = "special"
                continue
            with open(p, "rb") as fh:
                out[rel] = hashlib.sha256(fh.read(1 << 20)).hexdigest()
    return out


def flag_case(args):
    """One random command run in a sandbox: cwd, TMPDIR, inputs and outputs in their own folders;
    afterwards every file there must be an input (unchanged) or a named output."""
    k, seed, timeout, base, inputs = args
    rng = random.Random(seed * 104_729 + k)
    cmd = FLAG_COMMANDS[k % len(FLAG_COMMANDS)]
    root = base / f"flag{k}"
    cwd, tmp, inp, out, home = root / "cwd", root / "tmp", root / "in", root / "out", root / "home"
    for d in (cwd, tmp, inp, out, home):
        d.mkdir(parents=True)
    local = {}
    for name, src in inputs.items():
        local[name] = inp / src.name
        shutil.copyfile(src, local[name])
    before = _tree(inp)
    argv, named = flag_argv(cmd, rng, local, out)
    # HOME is the run's own too; the libraries' caches (matplotlib's fonts, fontconfig) go to one
    # shared folder outside the sandbox, made before the runs
    env = {**os.environ, "MPLBACKEND": "Agg", "TMPDIR": str(tmp), "HOME": str(home),
           "MPLCONFIGDIR": str(base / "cache" / "matplotlib"), "XDG_CACHE_HOME": str(base / "cache")}
    t0 = time.perf_counter()
    try:
        res = subprocess.run([sys.executable, "-m", "nbst.cli", *argv], capture_output=True, timeout=timeout,
                             cwd=cwd, env=env)
        rc, se = res.returncode, res.stderr
    except subprocess.TimeoutExpired as e:
        rc, se = "timeout", e.stderr or b""
    dt = time.perf_counter() - t0
    err = se.decode("utf-8", "replace")
    stray = [f"cwd/{f}" for f in _tree(cwd)] + [f"tmp/{f}" for f in _tree(tmp)] + [f"home/{f}" for f in _tree(home)]
    after = _tree(inp)
    stray += [f"in/{f} (changed)" for f in after if before.get(f) != after[f]]
    for f in _tree(out):
        p = out / f
        if ".partial-" in f or not any(p == n or n in p.parents for n in named):
            stray.append(f"out/{f}")
    lines = [ln for ln in err.strip().splitlines() if ln.strip()]
    r = {"cmd": cmd, "rc": rc, "seconds": dt, "traceback": "Traceback" in err, "stray": stray,
         "multiline": rc == 2 and len([ln for ln in lines if not ln.startswith("nbst: note:")]) > 1,
         "argv": argv}
    if r["traceback"] or rc == "timeout" or stray or r["multiline"] or (isinstance(rc, int) and rc < 0):
        r["stderr"] = err[-800:]
    shutil.rmtree(root, ignore_errors=True)
    return r


def make_flag_inputs(work: Path, seeds: list[dict]) -> dict:
    """The input files of the flag runs: a tiny planted problem, its solution, a bowling shot."""
    tiny = next(s for s in seeds if s["tiny"])
    files = {"problem": work / "problem.json", "solution": work / "solution.json"}
    files["problem"].write_text(json.dumps(tiny["problem"]))
    files["solution"].write_text(json.dumps(tiny["solution"]))
    shot = work / "shot.json"
    res = subprocess.run([sys.executable, "-m", "nbst.cli", "bowl", "solve", "--down", "1", "-o", str(shot), "-q",
                          "--seed", "1", "--max-rollouts", "5", "--no-robustness", "--no-atlas", "--jobs", "1"],
                         capture_output=True, text=True, cwd=ROOT, timeout=300)
    if shot.exists() and shot.with_name("shot.scene.xml").exists():
        files["shot"] = shot
        files["shot_scene"] = shot.with_name("shot.scene.xml")  # the shot names its scene beside it
    else:
        print(f"  no shot file for the bowling runs: {res.stderr.strip()[-200:]}", file=sys.stderr)
    return files


def run_flags(seeds, n: int, workers: int, seed: int, timeout: float):
    base = Path(tempfile.mkdtemp(prefix="nbst-fuzz-flags-"))
    results = []
    t0 = time.perf_counter()
    try:
        (base / "cache" / "matplotlib").mkdir(parents=True)
        inputs = make_flag_inputs(base, seeds)
        cases = [(k, seed, timeout, base, inputs) for k in range(n)
                 if "shot" in inputs or FLAG_COMMANDS[k % len(FLAG_COMMANDS)] not in ("bowl-replay", "render-shot")]
        with ThreadPoolExecutor(workers) as ex:
            for i, r in enumerate(ex.map(flag_case, cases)):
                results.append(r)
                print(f"\r  flags {i + 1:,}/{len(cases):,} ({time.perf_counter() - t0:.0f} s)", end="",
                      file=sys.stderr)
    finally:
        shutil.rmtree(base, ignore_errors=True)
    print(file=sys.stderr)
    return results, time.perf_counter() - t0


# --------------------------------------------------------------------------- part 0: huge files

#: (name, repeated unit, count): files of ~64 MB or at nbst's value cap, in the shapes that cost the
#: parser most per byte.
HUGE_SHAPES = [("empty lists, 63 MiB", "[],", 22_000_000), ("small ints, 63 MiB", "1,", 33_000_000),
               ("empty objects, 63 MiB", "{},", 22_000_000), ("nesting, 63 MiB", "[", 33_000_000),
               ("one string, 63 MiB", "\u00e9", 33_000_000),
               ("empty lists at the value cap", "[],", 499_000), ("objects at the value cap", '{"a":[]},', 249_000),
               ("floats at the value cap", "1.5e300,", 999_000),
               ("strings at the value cap", '"abcdefghijklmnopqrstuvwxyz",', 999_000)]


def run_huge(work: Path) -> list[dict]:
    """Each huge shape loaded as a problem in a fresh process: seconds, peak memory (VmHWM: the
    process's own, where ru_maxrss would carry this one's across fork), the verdict."""
    code = ("import resource, sys, time\nfrom nbst.problem import ProblemError, load_problem\nt = time.perf_counter()\n"
            "try:\n    load_problem(sys.argv[1]); msg = 'accepted'\nexcept ProblemError as e:\n    msg = e.reason\n"
            "hwm = [ln for ln in open('/proc/self/status') if ln.startswith('VmHWM')]\n"
            "mb = int(hwm[0].split()[1]) // 1024 if hwm else resource.getrusage(resource.RUSAGE_SELF).ru_maxrss // 1024\n"
            "print(round(time.perf_counter() - t, 2), mb, msg)")
    rows = []
    for name, unit, count in HUGE_SHAPES:
        f = work / "huge.json"
        body = unit * count
        text = body + "]" * count if unit == "[" else ('["' + body + '"]' if unit == "\u00e9" else "[" + body + "1]")
        f.write_text(text, encoding="utf-8")
        t0 = time.perf_counter()
        res = subprocess.run([sys.executable, "-c", code, str(f)], capture_output=True, text=True, timeout=600)
        wall = time.perf_counter() - t0
        dt, mb, msg = (res.stdout.split(" ", 2) + ["?", "?", res.stderr.strip()[-200:]])[:3]
        rows.append({"shape": name, "bytes": f.stat().st_size, "load_s": dt, "process_s": round(wall, 2),
                     "peak_mb": mb, "verdict": msg.strip()[:90], "traceback": "Traceback" in res.stderr})
        f.unlink()
    return rows


# --------------------------------------------------------------------------- main


def print_exit_codes(res: list, commands) -> dict:
    """Print each command's exit codes over the runs ``res``; return them by command."""
    by = collections.defaultdict(collections.Counter)
    for r in res:
        by[r["cmd"]][str(r["rc"])] += 1
    for cmd in commands:
        print(f"  {cmd:18s} exit codes {dict(sorted(by[cmd].items()))}")
    return by


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(allow_abbrev=False, description=__doc__.split("\n\n")[0])
    ap.add_argument("--loader", type=int, default=100_000, help="inputs fed to the loader in-process")
    ap.add_argument("--cli", type=int, default=1_000, help="CLI runs (subprocesses)")
    ap.add_argument("--flags", type=int, default=1_000, help="runs of every subcommand with random flags (subprocesses)")
    ap.add_argument("--huge", action="store_true", help="also load huge files of the costliest shapes (time, memory)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--seed", type=int, default=12)
    ap.add_argument("--timeout", type=float, default=120.0, help="seconds per CLI run")
    ap.add_argument("--keep", default=None, metavar="DIR", help="write failing inputs here")
    ap.add_argument("--json", default=None, metavar="FILE", help="also write the figures as JSON")
    a = ap.parse_args(argv)
    work = Path(tempfile.mkdtemp(prefix="nbst-fuzz-seeds-"))
    try:
        seeds = make_seeds(work)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    print(f"seeds: {len(seeds)} problems ({sum(s['tiny'] for s in seeds)} tiny, used by the CLI part)")
    summary = {"seed": a.seed, "seeds": len(seeds)}
    bad_all = []
    if a.huge:
        work = Path(tempfile.mkdtemp(prefix="nbst-fuzz-huge-"))
        try:
            rows = run_huge(work)
        finally:
            shutil.rmtree(work, ignore_errors=True)
        print("huge files (load_problem in a fresh process; peak = its maximum resident memory):")
        for r in rows:
            print(f"  {r['shape']:30s} {r['bytes'] / 2**20:6.1f} MiB  load {r['load_s']:>5} s  peak {r['peak_mb']:>4} MB  "
                  f"{'TRACEBACK ' if r['traceback'] else ''}{r['verdict']}")
        summary["huge"] = rows
    if a.loader:
        c, bad, dt = run_loader(seeds, a.loader, a.workers, a.seed, 5 if a.keep else 0)
        bad_all += bad
        n = a.loader
        print(f"loader: {n:,} inputs in {dt:.0f} s ({n / dt:,.0f}/s)")
        print(f"  accepted {c['accepted']:,} ({c['accepted:problem']:,} problems, {c['accepted:solution']:,} "
              f"solutions), refused with ProblemError {c['refused']:,}, other exception {c['other']:,}")
        fields = sorted(((v, k[8:]) for k, v in c.items() if k.startswith("refused:")), reverse=True)
        print("  refusals by field: " + ", ".join(f"{f} {v:,}" for v, f in fields[:14]))
        others = {k[6:]: v for k, v in c.items() if k.startswith("other:")}
        if others:
            print(f"  other exceptions: {others}")
        print(f"  accepted inputs simulated {c['simulated']:,}: truncated {c['sim_truncated']:,}, non-finite or "
              f"outside the box {c['sim_outside_or_nonfinite']:,}, simulate raised {c['sim_error']:,}")
        summary["loader"] = {"inputs": n, "seconds": round(dt, 1), **dict(c)}
    if a.cli:
        res, dt = run_cli(seeds, a.cli, a.workers, a.seed, a.timeout)
        print(f"cli: {len(res):,} runs in {dt:.0f} s (timeout {a.timeout:g} s per run)")
        by = print_exit_codes(res, COMMANDS)
        tb = [r for r in res if r["traceback"]]
        hang = [r for r in res if r["rc"] == "timeout"]
        ml = [r for r in res if r["multiline"]]
        ctrl = [r for r in res if r["ctrl"]]
        js = [r for r in res if r["cmd"] == "simulate-json" and r["rc"] == 0]
        nonjson = [r for r in js if not r["json_ok"]]
        print(f"  tracebacks {len(tb)}, hangs {len(hang)}, multi-line errors {len(ml)}, control characters "
              f"on stderr {len(ctrl)}; simulate --json: {len(js)} outputs, {len(nonjson)} not strict JSON")
        print(f"  slowest run {max(r['seconds'] for r in res):.1f} s, median "
              f"{sorted(r['seconds'] for r in res)[len(res) // 2]:.1f} s")
        for r in (tb + hang + nonjson + ml + ctrl)[:8]:
            last = r["stderr"].strip().splitlines()[-1][:300] if r["stderr"].strip() else ""
            print(f"  -- {r['cmd']} rc={r['rc']}: {last}")
        summary["cli"] = {"runs": len(res), "seconds": round(dt, 1), "tracebacks": len(tb), "hangs": len(hang),
                          "multiline_errors": len(ml), "control_chars": len(ctrl), "json_outputs": len(js),
                          "json_not_strict": len(nonjson),
                          "exit_codes": {k: dict(v) for k, v in by.items()}}
        bad_all += [(r["cmd"], json.dumps(r["files"]).encode(), r["stderr"]) for r in tb + hang + nonjson + ml + ctrl]
    if a.flags:
        res, dt = run_flags(seeds, a.flags, a.workers, a.seed, a.timeout)
        print(f"flags: {len(res):,} runs in {dt:.0f} s (timeout {a.timeout:g} s per run)")
        by = print_exit_codes(res, FLAG_COMMANDS)
        tb = [r for r in res if r["traceback"]]
        hang = [r for r in res if r["rc"] == "timeout"]
        killed = [r for r in res if isinstance(r["rc"], int) and r["rc"] < 0]
        stray = [r for r in res if r["stray"]]
        ml = [r for r in res if r["multiline"]]
        print(f"  tracebacks {len(tb)}, hangs {len(hang)}, killed by a signal {len(killed)}, runs leaving files "
              f"outside their named outputs {len(stray)}, multi-line errors {len(ml)}")
        print(f"  slowest run {max(r['seconds'] for r in res):.1f} s, median "
              f"{sorted(r['seconds'] for r in res)[len(res) // 2]:.1f} s")
        for r in (tb + hang + killed + stray + ml)[:10]:
            last = r["stderr"].strip().splitlines()[-1][:200] if r.get("stderr", "").strip() else ""
            print(f"  -- {r['cmd']} rc={r['rc']} {' '.join(r['argv'])[:200]}\n     {last} {r['stray'][:3]}")
        summary["flags"] = {"runs": len(res), "seconds": round(dt, 1), "tracebacks": len(tb), "hangs": len(hang),
                            "killed": len(killed), "stray_files": len(stray), "multiline_errors": len(ml),
                            "exit_codes": {k: dict(v) for k, v in by.items()}}
        bad_all += [(r["cmd"], json.dumps(r["argv"]).encode(), r.get("stderr", "") + str(r["stray"]))
                    for r in tb + hang + killed + stray + ml]
    if a.keep and bad_all:
        d = Path(a.keep)
        d.mkdir(parents=True, exist_ok=True)
        for i, (kind, data, why) in enumerate(bad_all):
            (d / f"bad{i}-{kind}.json").write_bytes(data)
            (d / f"bad{i}-{kind}.txt").write_text(why, encoding="utf-8", errors="replace")
        print(f"kept {len(bad_all)} failing inputs in {d}")
    if a.json:
        from nbst.outputs import write_json_atomic
        write_json_atomic(a.json, summary)
    return 0


if __name__ == "__main__":
    sys.exit(main())
