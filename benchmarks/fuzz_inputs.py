"""Fuzz nbst's input handling (issue 12): every bad file must be one line, exit 2.

    python benchmarks/fuzz_inputs.py                       # 100,000 loader inputs + 1,000 CLI runs
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
        "validate": ["validate", str(pf), str(sf), "--timestep", "0.001", "--report", str(out / "rep")],
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


# --------------------------------------------------------------------------- main

def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--loader", type=int, default=100_000, help="inputs fed to the loader in-process")
    ap.add_argument("--cli", type=int, default=1_000, help="CLI runs (subprocesses)")
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
        by = collections.defaultdict(collections.Counter)
        for r in res:
            by[r["cmd"]][str(r["rc"])] += 1
        for cmd in COMMANDS:
            print(f"  {cmd:18s} exit codes {dict(sorted(by[cmd].items()))}")
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
    if a.keep and bad_all:
        d = Path(a.keep)
        d.mkdir(parents=True, exist_ok=True)
        for i, (kind, data, why) in enumerate(bad_all):
            (d / f"bad{i}-{kind}.json").write_bytes(data)
            (d / f"bad{i}-{kind}.txt").write_text(why, encoding="utf-8", errors="replace")
        print(f"kept {len(bad_all)} failing inputs in {d}")
    if a.json:
        from nbst.solution import write_json_atomic
        write_json_atomic(a.json, summary)
    return 0


if __name__ == "__main__":
    sys.exit(main())
