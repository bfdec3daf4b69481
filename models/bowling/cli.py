"""Subcommands ``nbst bowl solve``, ``nbst bowl replay`` and ``nbst bowl atlas``.

Registration is light: mujoco and cma are imported inside the commands.

Exit codes: 0 done (solve: the requested pins exactly; replay: the file's pins; atlas:
finished), 1 a check failed (solve: the request was not found within the budget and
the nearest shot was written; replay: the pins down differ from the file's ``down``),
2 bad input, 130 interrupted (solve: the best shot so far is written).
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from nbst.cli_solve import int_at_least
from nbst.islands import default_jobs


def _pins(text: str) -> int:
    """``--down``: pin numbers "1,2,4,7" (or "strike"/"all") -> 10-bit mask."""
    t = text.strip().lower()
    if t in ("strike", "all"):
        return 1023
    try:
        pins = [int(p) for p in t.replace(" ", "").split(",") if p]
    except ValueError:
        raise argparse.ArgumentTypeError(f"pins must be numbers 1..10 separated by commas (e.g. 1,2,4,7), "
                                         f"got {text!r}") from None
    bad = [p for p in pins if not 1 <= p <= 10]
    if bad or not pins:
        raise argparse.ArgumentTypeError(f"pins must be numbers 1..10 (at least one), got {text!r}")
    return sum(1 << (p - 1) for p in set(pins))


def register(sub) -> None:
    p = sub.add_parser("bowl", help="10-pin bowling in MuJoCo: find a throw that knocks down given pins",
                       description="Ten-pin bowling, synthesized on MuJoCo rollouts (docs/bowling.md): a USBC "
                                   "lane with oil, pins and a 15 lb ball; a throw is lateral position, speed, "
                                   "angle and spin, clamped to what a bowler can throw.")
    bowl = p.add_subparsers(dest="bowl_command", metavar="SUBCOMMAND", parser_class=type(p))
    p.set_defaults(func=lambda args: (p.print_help(sys.stderr), 2)[1])

    s = bowl.add_parser("solve", help="search for a throw that knocks down exactly the given pins",
                        description="Search the launch space (uniform exploration, then CMA-ES restarts from "
                                    "the throws whose pins-down sets are nearest the request) with mujoco.rollout "
                                    "on --jobs threads, and write the shot: JSON plus the scene XML beside it "
                                    "(replayable with plain mujoco). Ctrl-C writes the best shot so far (exit 130). "
                                    "The same --seed gives the same shot, for any --jobs.",
                        epilog="Exit 0: found; 1: not found within --max-rollouts (the nearest shot is written "
                               "and its pins named); 2: bad input; 130: interrupted.")
    s.add_argument("--down", required=True, type=_pins, metavar="PINS",
                   help="pins to knock down, e.g. 1,2,4,7 (USBC numbers: 1 in front, 7 back left, 10 back "
                        "right); 'strike' = all ten")
    s.add_argument("-o", "--output", required=True, metavar="SHOT.json", help="where to write the shot")
    s.add_argument("--seed", type=int_at_least(0, "seed"), default=None, help="random seed (default: drawn, recorded)")
    s.add_argument("--max-rollouts", type=int_at_least(1, "max rollouts"), default=3000, metavar="N",
                   help="launch budget (default 3000)")
    s.add_argument("--jobs", type=int_at_least(1, "jobs"), default=None, metavar="K",
                   help="threads running rollouts (default: all cores)")
    s.add_argument("--no-robustness", action="store_true",
                   help="skip the robustness probes (~50 extra rollouts) after the search")
    s.add_argument("-q", "--quiet", action="store_true", help="no progress bar and no summary line")
    s.set_defaults(func=cmd_solve)

    r = bowl.add_parser("replay", help="replay a shot file and check its pins down",
                        description="Replay SHOT.json from its scene XML with plain MuJoCo (fresh MjData, qpos0 "
                                    "and qvel0 set, mj_step for duration) and print the pins down; exit 1 if they "
                                    "differ from the file's `down`.")
    r.add_argument("shot", metavar="SHOT.json")
    r.add_argument("--json", action="store_true", help="print one JSON object: down, expected, match")
    r.set_defaults(func=cmd_replay)

    a = bowl.add_parser("atlas", help="try for every one of the 1,023 subsets; one shot per subset found",
                        description="Search for all 1,023 non-empty subsets: a shared exploration (a quarter of "
                                    "the budget) fills an archive keyed by subset, then targeted solves (--per-subset "
                                    "launches each, restarting from the archive) go after the missing subsets nearest "
                                    "the archive first. Writes DIR/subset-<pins>.json (+ scene XML) for every subset "
                                    "found (all naming one DIR/scene.xml) and DIR/summary.md (+ .csv). "
                                    "Rerunning resumes: the shots already in DIR "
                                    "are the archive, and their subsets are skipped.")
    a.add_argument("--out", required=True, metavar="DIR", help="output folder")
    a.add_argument("--max-rollouts", type=int_at_least(1, "max rollouts"), default=20000, metavar="N",
                   help="total launch budget (default 20000)")
    a.add_argument("--per-subset", type=int_at_least(1, "per-subset"), default=200, metavar="N",
                   help="launch budget of each targeted solve (default 200)")
    a.add_argument("--seed", type=int_at_least(0, "seed"), default=1, help="random seed (default 1)")
    a.add_argument("--jobs", type=int_at_least(1, "jobs"), default=None, metavar="K",
                   help="threads running rollouts (default: all cores)")
    a.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    a.set_defaults(func=cmd_atlas)


def _err(cmd: str, msg: str) -> int:
    from nbst.domain import plain

    print(f"nbst bowl {cmd}: error: {plain(msg)}", file=sys.stderr)
    return 2


def write_shot(path, model, launch, mask: int, *, shared_scene: str | None = None, **kw) -> None:
    """Write SHOT.json and its scene XML (``<stem>.scene.xml``, with keyframe ``shot``) beside
    it, atomically; with ``shared_scene`` the file names that scene (written by the caller)."""
    from nbst.outputs import write_text_atomic

    from . import shotfile

    path = Path(path)
    scene_name = shared_scene or f"{path.stem}.scene.xml"
    d = shotfile.shot_dict(model, launch, scene_name=scene_name, down_mask=mask, **kw)
    if shared_scene is None:
        write_text_atomic(path.parent / scene_name, shotfile.scene_with_shot(d["qpos0"], d["qvel0"]))
    write_text_atomic(path, shotfile.dumps(d))


def atlas_json(folder, *, seed=None) -> Path:
    """Gather an atlas folder's shot files into FOLDER/atlas.json: one file a MuJoCo user
    replays without nbst, ``{"kind": "nbst-bowling-atlas", "scene": "scene.xml", "shots":
    [shot, ...]}``, each shot with the shot-file keys (``scene`` relative to the atlas file),
    sorted by subset size, then pins."""
    import json

    from nbst.outputs import write_text_atomic

    folder = Path(folder)
    shots = []
    for f in sorted(folder.glob("subset-*.json")):
        try:
            d = json.loads(f.read_text(encoding="utf-8"))
        except (OSError, ValueError, RecursionError):
            continue
        if isinstance(d, dict) and "down" in d and "qpos0" in d:
            shots.append(d)
    shots.sort(key=lambda d: (len(d["down"]), d["down"]))
    atlas = {"kind": "nbst-bowling-atlas", "schema_version": 1, "scene": "scene.xml", "seed": seed,
             "subsets": len(shots), "shots": shots}
    path = folder / "atlas.json"
    write_text_atomic(path, json.dumps(atlas, indent=1) + "\n")  # floats by repr: exact
    return path


def cmd_solve(args) -> int:
    import numpy as np

    from nbst.outputs import prepare_output, signals_deferred, sigterm_as_interrupt

    from . import search, shot

    prepare_output(args.output)
    seed = args.seed if args.seed is not None else int(np.random.SeedSequence().entropy % (2**31))
    jobs = args.jobs or default_jobs()
    want = shot.pins_of(args.down)
    bar = []

    def progress(p) -> None:
        if args.quiet:
            return
        if not bar:
            from tqdm import tqdm

            bar.append(tqdm(total=args.max_rollouts, unit="launch", file=sys.stderr, dynamic_ncols=True,
                            desc=f"bowl {','.join(map(str, want))}", smoothing=0.1))
        bar[0].update(p.rollouts - bar[0].n)
        if p.rollouts:
            near = ",".join(map(str, shot.pins_of(p.best_mask))) or "none"
            bar[0].set_postfix_str(f"nearest {near} ({p.best_hamming} off), {p.subsets} subsets seen",
                                   refresh=False)

    L = shot.Launcher(jobs=jobs)
    progress(search.Progress(0, 10, 0, 0))  # the bar starts with the clock
    try:
        with sigterm_as_interrupt():
            res = search.solve(args.down, seed=seed, max_rollouts=args.max_rollouts, launcher=L, callback=progress)
        if bar:
            bar[0].close()
        rob = None
        if not args.no_robustness and res.stopped != "interrupted":
            try:
                with sigterm_as_interrupt():
                    rob = search.robustness(L, res.launch, res.mask)
            except KeyboardInterrupt:
                res.stopped = "interrupted"
        meta = {"seed": seed, "rollouts": res.rollouts, "restarts": res.restarts, "jobs": jobs,
                "max_rollouts": args.max_rollouts, "stopped": res.stopped, "wall_time_s": round(res.wall_time, 3),
                "subsets_seen": len(res.archive), "algorithm": "explore + CMA-ES restarts from nearest subsets"}
        with signals_deferred(reraise=False) as late:
            write_shot(args.output, L.model, res.launch, res.mask, requested=args.down, robustness=rob, search=meta)
    finally:
        if bar:
            bar[0].close()
        L.close()
    got = ",".join(map(str, shot.pins_of(res.mask))) or "none"
    line = (f"pins down {got} ({res.hamming} off the request) after {res.rollouts} launches in "
            f"{res.wall_time:.1f} s, seed {seed}; wrote {args.output}")
    if res.stopped == "interrupted" or late:
        print(f"nbst bowl solve: interrupted; best so far written: {line}", file=sys.stderr)
        return 130
    if res.hamming:
        print(f"nbst bowl solve: not found within {args.max_rollouts} launches; nearest written: {line}",
              file=sys.stderr)
        return 1
    if not args.quiet:
        r = (f"; keeps the outcome within +/-{rob['lateral_m'] * 1000:.3g} mm sideways, "
             f"+/-{rob['speed_m_s'] * 1000:.3g} mm/s speed") if rob else ""
        print(f"nbst bowl solve: found: {line}{r}", file=sys.stderr)
    return 0


def cmd_replay(args) -> int:
    from . import shotfile

    try:
        d, down = shotfile.replay_file(args.shot)
    except shotfile.ShotFileError as e:
        return _err("replay", str(e))
    want = sorted(d["down"])
    ok = down == want
    if args.json:
        from nbst.cli import print_json

        print_json({"shot": str(args.shot), "down": down, "expected": want, "match": ok})
    else:
        print(f"pins down  {','.join(map(str, down)) or 'none'}")
        print(f"expected   {','.join(map(str, want)) or 'none'}  ({'match' if ok else 'DIFFERENT'})")
    return 0 if ok else 1


def cmd_atlas(args) -> int:
    import csv
    import io
    import json

    import numpy as np

    from nbst.outputs import prepare_output, write_text_atomic

    from . import search, shot

    out = prepare_output(args.out, directory=True, option="--out")
    jobs = args.jobs or default_jobs()
    L = shot.Launcher(jobs=jobs)
    have = {}
    for f in out.glob("subset-*.json"):
        try:
            have[shot.mask_from_pins(int(p) for p in f.stem.split("-", 1)[1].split("_"))] = f.name
        except ValueError:
            continue
    spent = 0
    tried: set[int] = set()
    t0 = time.perf_counter()
    bar = None
    if not args.quiet:
        from tqdm import tqdm

        bar = tqdm(total=args.max_rollouts, unit="launch", file=sys.stderr, dynamic_ncols=True, desc="atlas")

    def name(mask):
        return "subset-" + "_".join(map(str, shot.pins_of(mask))) + ".json"

    from . import scene as scenemod

    write_text_atomic(out / "scene.xml", scenemod.scene_xml())  # one scene for every shot (the same model)

    def save(archive):
        for m, x in archive.items():
            if m and m not in have:
                write_shot(out / name(m), L.model, x, m, shared_scene="scene.xml", requested=m)
                have[m] = name(m)

    try:
        rng = np.random.default_rng(args.seed)
        shared = {}
        for m, f in have.items():  # resume: the launches of the shots already written
            try:
                la = json.loads((out / f).read_text())["launch"]
                shared[m] = np.array([la[k] for k in shot.KEYS], dtype=float)
            except (OSError, ValueError, KeyError, TypeError):
                continue
        # a shared exploration first (a quarter of the budget), then targeted solves from it,
        # most reachable subsets (nearest an archived one) first
        n0 = max(0, min(args.max_rollouts // 4, args.max_rollouts - spent)) if not shared else 0
        if n0:
            ev = search.Evaluator(L, 1023, max_rollouts=n0)
            for i in range(0, n0, 4 * search.BATCH):
                ev(search.from_unit(rng.random((min(4 * search.BATCH, n0 - i), 4))))
                if bar:
                    bar.update(ev.rollouts - bar.n)
            spent += ev.rollouts
            shared.update({m: x for m, x in ev.archive.items() if m not in shared})
            save(shared)
        while spent < args.max_rollouts:
            todo = [t for t in range(1, 1024) if t not in have and t not in tried]
            if not todo:
                break
            near = {t: min(int(search.hamming(t, m)) for m in shared) if shared else 10 for t in todo}
            target = min(todo, key=lambda t: (near[t], t))
            tried.add(target)
            budget = min(args.per_subset, args.max_rollouts - spent)
            res = search.solve(target, seed=int(rng.integers(0, 2**31 - 1)), max_rollouts=budget, launcher=L,
                               explore=0, archive=shared)
            spent += res.rollouts
            shared.update({m: x for m, x in res.archive.items() if m not in shared})
            save(shared)
            if bar:
                bar.update(res.rollouts)
                bar.set_postfix_str(f"{len(have)} subsets", refresh=False)
    except KeyboardInterrupt:
        pass
    finally:
        if bar:
            bar.close()
        L.close()
    rows = [(m, len(shot.pins_of(m)), have.get(m, "")) for m in range(1, 1024)]
    buf = io.StringIO()
    w = csv.writer(buf)
    w.writerow(["mask", "pins", "size", "file"])
    for m, k, f in rows:
        w.writerow([m, "-".join(map(str, shot.pins_of(m))), k, f])
    write_text_atomic(out / "summary.csv", buf.getvalue())
    lines = ["# Bowling atlas", "", f"{sum(1 for r in rows if r[2])} of 1023 subsets found; "
             f"{spent} launches this run in {time.perf_counter() - t0:.0f} s (seed {args.seed}).", "",
             "| pins down | found / possible |", "|---|---|"]
    for k in range(1, 11):
        tot = sum(1 for r in rows if r[1] == k)
        got = sum(1 for r in rows if r[1] == k and r[2])
        lines.append(f"| {k} | {got} / {tot} |")
    write_text_atomic(out / "summary.md", "\n".join(lines) + "\n")
    atlas_json(out, seed=args.seed)
    print(f"nbst bowl atlas: {sum(1 for r in rows if r[2])} of 1023 subsets have a shot in {out}", file=sys.stderr)
    return 0
