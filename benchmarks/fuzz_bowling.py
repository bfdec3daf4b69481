"""Fuzz the bowling input gate: shot and atlas documents through the loaders, a sample through the CLI.

    .venv/bin/python benchmarks/fuzz_bowling.py                # 50,000 documents, 40 CLI runs
    .venv/bin/python benchmarks/fuzz_bowling.py --quick        # 5,000 documents, 10 CLI runs
    .venv/bin/python benchmarks/fuzz_bowling.py --docs N --cli K --seed S

Documents are mutations of a real shot (the shipped atlas's 7-10 split leave) and of small
atlases made from the shipped one: fields deleted or retyped (null, booleans, strings, huge
and non-finite numbers, deep nesting, 5,000-digit integers), qpos0/qvel0 lengths and entries
changed, ``scene`` pointed at absolute paths, ``../``, links out of the folder, FIFOs,
folders, non-scenes and scenes that read other files, plus byte-level damage of the JSON text
(flips, cuts, inserts, non-UTF-8). Each goes through ``deckfile.load_with_scene`` (shots) or
``deckfile.load_atlas`` (atlases); the outcome must be acceptance or one ShotFileError line,
within 5 s (SIGALRM). Parsing the 90 kB scene costs ~60 ms, so the loaders' ``load_scene`` is
wrapped in a cache for the one unchanged, known-good scene file only (every other scene file,
including mutated ones, goes through the real parser each time).

A sample then runs as commands (``nbst bowl replay``, ``nbst render --still``, ``nbst plot
problem``) in a scratch folder, each with a 120 s timeout: exit 0, 1 or 2, no traceback, stderr
at most one error line, no ``MUJOCO_LOG.TXT`` and no file other than the named output created.

Prints the counts; exit status 1 if any traceback, hang or stray file was seen.
"""
from __future__ import annotations

import argparse
import copy
import json
import os
import random
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SHIPPED = ROOT / "models" / "bowling"
NBST = [sys.executable, "-m", "nbst.cli"]

WEIRD = [None, True, False, "", "x", "\x1b[31m", [], {}, 0, -1, 1e300, -1e300, float("nan"), float("inf"),
         10 ** 30, 1e-320, "9" * 50, [[[[[]]]]], {"a": {"b": {"c": []}}}, 3.5, -0.0]


class Hang(Exception):
    pass


def _alarm(signum, frame):
    raise Hang


def mutate_value(rng: random.Random, v):
    r = rng.random()
    if r < 0.5:
        return copy.deepcopy(rng.choice(WEIRD))
    if isinstance(v, list) and v:
        v = list(v)
        k = rng.randrange(4)
        if k == 0:
            del v[rng.randrange(len(v)):]
        elif k == 1:
            v.extend(rng.choice(WEIRD) for _ in range(rng.randrange(1, 5)))
        else:
            v[rng.randrange(len(v))] = copy.deepcopy(rng.choice(WEIRD))
        return v
    if isinstance(v, (int, float)) and not isinstance(v, bool):
        return rng.choice([v * 1e6, -v, v + 1e-9, 0, 1e308, float("nan")])
    if r < 0.8:
        d = []
        for _ in range(rng.randrange(1, 200)):
            d = [d]
        return d
    return {"deep": mutate_value(rng, v)}


SCENES = ["scene.xml", "/etc/passwd", "../scene.xml", "../../../../etc/hostname", "sub/../scene.xml", "pipe.xml",
          "dir.xml", "missing.xml", "notxml.xml", "include.xml", "other.xml", "link-out.xml", "./scene.xml",
          "", "\x00", "a" * 5000, str(SHIPPED / "scene.xml"), "big.xml"]


def mutate_shot(rng: random.Random, base: dict) -> dict:
    d = copy.deepcopy(base)
    for _ in range(rng.randrange(1, 4)):
        k = rng.random()
        key = rng.choice(list(d) + ["extra"])
        if k < 0.15:
            d.pop(key, None)
        elif k < 0.35:
            d["scene"] = rng.choice(SCENES)
        elif k < 0.6 and key in ("qpos0", "qvel0"):
            d[key] = mutate_value(rng, d[key])
        elif k < 0.7:
            f = rng.choice(["qpos0", "qvel0"])
            v = list(d[f]) if isinstance(d.get(f), list) else []
            if v:
                v[rng.randrange(len(v))] = rng.choice([float("nan"), 1e300, True, "1", None, 1e3, 1001.0, -0.0])
            d[f] = v
        else:
            d[key] = mutate_value(rng, d.get(key))
    return d


def damage_text(rng: random.Random, text: str) -> bytes:
    b = bytearray(text.encode())
    for _ in range(rng.randrange(1, 6)):
        k = rng.randrange(5)
        i = rng.randrange(len(b) + 1)
        if k == 0 and b:
            del b[i:i + rng.randrange(1, 50)]
        elif k == 1:
            b[i:i] = rng.choice([b"\xff\xfe", b"NaN", b"Infinity", b"[" * 3000, b"9" * 5000, b"\x00", b",", b"}"])
        elif k == 2 and b:
            b[min(i, len(b) - 1)] ^= 1 << rng.randrange(8)
        elif k == 3:
            b = b[:i]
        else:
            b[i:i] = b'"kind": "nbst-bowling-shot", '
    return bytes(b)


def setup_folder(folder: Path) -> None:
    shutil.copyfile(SHIPPED / "scene.xml", folder / "scene.xml")
    shutil.copyfile(SHIPPED / "scene.xml", folder / "big.xml")
    with open(folder / "big.xml", "a") as f:
        f.write("<!--" + "x" * (9 * 1024 * 1024) + "-->")
    os.mkfifo(folder / "pipe.xml")
    (folder / "dir.xml").mkdir()
    (folder / "notxml.xml").write_text("hello\n")
    (folder / "include.xml").write_text('<mujoco><include file="/etc/passwd"/></mujoco>')
    (folder / "other.xml").write_text('<mujoco><worldbody><body><freejoint name="ball_free"/><geom size="1"/>'
                                      '</body></worldbody></mujoco>')
    os.symlink(SHIPPED / "scene.xml", folder / "link-out.xml")
    (folder / "sub").mkdir()


def fuzz_loaders(n: int, seed: int, folder: Path) -> dict:
    from nbst.models.bowling.deck import throwfile as deckfile

    real_load_scene = deckfile.load_scene
    good = (folder / "scene.xml").resolve()
    st0 = os.stat(good)
    cache = {}

    def cached_load_scene(xml_path, src, field="scene"):
        p = Path(xml_path).resolve()
        try:
            st = os.stat(p)
        except OSError:
            st = None
        if p == good and st is not None and (st.st_size, st.st_mtime_ns) == (st0.st_size, st0.st_mtime_ns):
            if "m" not in cache:
                cache["m"] = real_load_scene(xml_path, src, field)
            return cache["m"]
        return real_load_scene(xml_path, src, field)

    deckfile.load_scene = cached_load_scene
    atlas = json.loads((SHIPPED / "atlas.json").read_text())
    base = next(s for s in atlas["shots"] if s["down"] == [1, 2, 3, 4, 5, 6, 8, 9])
    base = {**base, "scene": "scene.xml"}
    rng = random.Random(seed)
    out = {"documents": 0, "shots": 0, "atlases": 0, "accepted": 0, "refused": 0, "tracebacks": 0, "hangs": 0,
           "slowest_s": 0.0, "examples": []}
    old = signal.signal(signal.SIGALRM, _alarm)
    path = folder / "doc.json"
    try:
        for i in range(n):
            is_atlas = rng.random() < 0.2
            if is_atlas:
                shots = [copy.deepcopy(rng.choice(atlas["shots"])) for _ in range(rng.randrange(0, 4))]
                shots = [{**s, "scene": "scene.xml"} if rng.random() < 0.7 else mutate_shot(rng, s) for s in shots]
                doc = {"kind": "nbst-bowling-atlas", "schema_version": 1, "scene": "scene.xml", "shots": shots}
                if rng.random() < 0.5:
                    doc = mutate_shot(rng, doc) if rng.random() < 0.5 else {**doc, "scene": rng.choice(SCENES)}
            else:
                doc = mutate_shot(rng, base) if rng.random() < 0.9 else copy.deepcopy(rng.choice(WEIRD))
            text = json.dumps(doc, allow_nan=True)
            data = damage_text(rng, text) if rng.random() < 0.3 else text.encode()
            target = path
            if rng.random() < 0.02:
                target = folder / rng.choice(["pipe.xml", "dir.xml", "missing.json"])
            else:
                path.write_bytes(data)
            t0 = time.perf_counter()
            signal.setitimer(signal.ITIMER_REAL, 5.0)
            try:
                if is_atlas:
                    deckfile.load_atlas(target)
                else:
                    deckfile.load_with_scene(target)
                out["accepted"] += 1
            except deckfile.ThrowFileError as e:
                out["refused"] += 1
                if "\n" in str(e):
                    out["tracebacks"] += 1
                    out["examples"].append(f"multi-line error: {str(e)[:200]!r}")
            except Hang:
                out["hangs"] += 1
                out["examples"].append(f"hang: {data[:200]!r}")
            except Exception as e:  # noqa: BLE001 - what the fuzzer is looking for
                out["tracebacks"] += 1
                out["examples"].append(f"{type(e).__name__}: {str(e)[:160]} <- {data[:160]!r}")
            finally:
                signal.setitimer(signal.ITIMER_REAL, 0)
            out["slowest_s"] = max(out["slowest_s"], time.perf_counter() - t0)
            out["documents"] += 1
            out["atlases" if is_atlas else "shots"] += 1
    finally:
        signal.signal(signal.SIGALRM, old)
        deckfile.load_scene = real_load_scene
    return out


def fuzz_cli(k: int, seed: int, folder: Path) -> dict:
    rng = random.Random(seed + 1)
    atlas = json.loads((SHIPPED / "atlas.json").read_text())
    base = {**next(s for s in atlas["shots"] if s["down"] == [1, 2, 3, 4, 5, 6, 8, 9]), "scene": "scene.xml"}
    out = {"runs": 0, "exit_codes": {}, "tracebacks": 0, "hangs": 0, "stray_files": 0, "mujoco_logs": 0,
           "examples": []}
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    for i in range(k):
        doc = mutate_shot(rng, base) if i % 4 else base
        kind = ["replay", "render", "render", "plot"][i % 4]
        p = folder / f"cli-{i}.json"
        text = json.dumps(doc, allow_nan=True)
        p.write_bytes(damage_text(rng, text) if rng.random() < 0.3 else text.encode())
        o = folder / f"out-{i}.png"
        if kind == "replay":
            argv = ["bowl", "replay", str(p)]
        elif kind == "render":
            flag = rng.choice([[], ["--fps", rng.choice(["nan", "1e9", "-5", "30"])], ["--trails"],
                               ["--size", rng.choice(["64x36", "0x0", "99999x2"])]])
            argv = ["render", str(p), "-o", str(o), "--still", rng.choice(["0.5", "nan", "-1", "1e9"]), *flag]
        else:
            argv = ["plot", "problem", str(p), "-o", str(o)]
        before = set(os.listdir(folder))
        try:
            r = subprocess.run(NBST + argv, cwd=folder, capture_output=True, text=True, timeout=120, env=env)
        except subprocess.TimeoutExpired:
            out["hangs"] += 1
            out["examples"].append(f"hang: {argv}")
            continue
        out["runs"] += 1
        out["exit_codes"][r.returncode] = out["exit_codes"].get(r.returncode, 0) + 1
        errs = [x for x in r.stderr.splitlines() if "error" in x]
        if "Traceback" in r.stderr or r.returncode not in (0, 1, 2) or len(errs) > 1:
            out["tracebacks"] += 1
            out["examples"].append(f"rc {r.returncode} {argv}: {r.stderr[-300:]!r}")
        new = set(os.listdir(folder)) - before - {o.name}
        if "MUJOCO_LOG.TXT" in new:
            out["mujoco_logs"] += 1
        if new:
            out["stray_files"] += 1
            out["examples"].append(f"stray files {sorted(new)} after {argv}")
            for f in new:
                (folder / f).unlink(missing_ok=True)
        o.unlink(missing_ok=True)
    return out


def main() -> int:
    ap = argparse.ArgumentParser(allow_abbrev=False, description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--docs", type=int, default=None, help="documents through the loaders (default 50,000)")
    ap.add_argument("--cli", type=int, default=None, help="command runs (default 40)")
    ap.add_argument("--quick", action="store_true", help="5,000 documents and 10 command runs")
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    n = a.docs if a.docs is not None else (5000 if a.quick else 50_000)
    k = a.cli if a.cli is not None else (10 if a.quick else 40)
    with tempfile.TemporaryDirectory(prefix="fuzz-bowling-") as tmp:
        folder = Path(tmp)
        setup_folder(folder)
        t0 = time.perf_counter()
        lo = fuzz_loaders(n, a.seed, folder)
        t1 = time.perf_counter()
        cl = fuzz_cli(k, a.seed, folder)
        t2 = time.perf_counter()
    print(f"loaders: {lo['documents']:,} documents ({lo['shots']:,} shots, {lo['atlases']:,} atlases) in "
          f"{t1 - t0:.0f} s: {lo['accepted']:,} accepted, {lo['refused']:,} refused in one line, "
          f"{lo['tracebacks']} tracebacks, {lo['hangs']} hangs; slowest call {lo['slowest_s']:.2f} s")
    print(f"commands: {cl['runs']} runs in {t2 - t1:.0f} s (exit codes {dict(sorted(cl['exit_codes'].items()))}): "
          f"{cl['tracebacks']} tracebacks or multi-line errors, {cl['hangs']} hangs, {cl['stray_files']} runs left "
          f"stray files, {cl['mujoco_logs']} MUJOCO_LOG.TXT")
    for e in (lo["examples"] + cl["examples"])[:10]:
        print("  example:", e)
    bad = lo["tracebacks"] + lo["hangs"] + cl["tracebacks"] + cl["hangs"] + cl["stray_files"]
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
