"""Subcommands ``nbst bowl solve``, ``nbst bowl replay`` and ``nbst bowl atlas``.

Registration is light: mujoco and cma are imported inside the commands.

Exit codes: 0 done (solve: the requested pins exactly; replay: the file's pins; atlas:
finished), 1 a check failed (solve: the request was not found within the budget and
the nearest shot was written; replay: the pins down differ from the file's ``down``),
2 bad input, 130 interrupted (solve: the best shot so far is written; atlas: the shots
found so far, the summary and atlas.json are written).
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from nbst.cli.args import int_at_least
from nbst.parallel import default_jobs


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
    _runner_args(s, "the same shot as --jobs for the same seed")
    s.add_argument("--distance", choices=("hamming", "geometry"), default="hamming",
                   help="distance between subsets that ranks restart points: hamming (pins that differ; "
                        "default) or geometry (an extra pin down next to a wanted one counts 1/2)")
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
                        description="Search for all 1,023 non-empty subsets, keeping an archive keyed by subset. "
                                    "--method elites (default, MAP-Elites style): after 256 uniform throws, "
                                    "each batch of 16 holds 2 uniform throws and 14 children of archived "
                                    "throws (parents of rare subsets, of sizes with few subsets found, and "
                                    "whose children found new subsets are drawn more often), moved by a "
                                    "Gaussian step of 0.4 mm, 4 mm or 42 mm sideways (and alike on the other "
                                    "axes). --method targeted: a shared uniform exploration (a quarter of the "
                                    "budget), then targeted solves (--per-subset launches each) for the missing "
                                    "subsets nearest the archive. --method uniform: random throws. Writes "
                                    "DIR/subset-<pins>.json for every subset found (all naming one DIR/scene.xml), "
                                    "each with its robustness (16 more launches; see docs/bowling.md), "
                                    "DIR/summary.md (+ .csv, + .png: every subset found as a triangle) and "
                                    "DIR/atlas.json. Rerunning resumes: the shots already in DIR are the archive.")
    a.add_argument("--out", required=True, metavar="DIR", help="output folder")
    a.add_argument("--max-rollouts", type=int_at_least(0, "max rollouts"), default=20000, metavar="N",
                   help="search launch budget of this run (default 20000; robustness probes not counted)")
    a.add_argument("--method", choices=("elites", "targeted", "uniform"), default="elites",
                   help="how to spend the budget (default elites)")
    a.add_argument("--per-subset", type=int_at_least(1, "per-subset"), default=200, metavar="N",
                   help="--method targeted: launch budget of each targeted solve (default 200)")
    a.add_argument("--from", dest="from_atlas", metavar="ATLAS.json", default=None,
                   help="start from the shots of this atlas file (e.g. models/bowling/atlas.json): they are "
                        "written into DIR first (those not there yet), then the search resumes from them")
    a.add_argument("--robustness-only", action="store_true",
                   help="no search: add the robustness to every shot in DIR that lacks it, then the summary")
    a.add_argument("--no-robustness", action="store_true", help="write new shots without the robustness probes")
    a.add_argument("--seed", type=int_at_least(0, "seed"), default=1, help="random seed (default 1)")
    _runner_args(a, "the same shots as --jobs for the same seed and folder")
    a.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    a.set_defaults(func=cmd_atlas)


def _runner_args(parser, same: str) -> None:
    """--jobs K | --cluster ADDRESS: where the rollouts run (see :func:`launcher`)."""
    g = parser.add_mutually_exclusive_group()
    g.add_argument("--jobs", type=int_at_least(1, "jobs"), default=None, metavar="K",
                   help="threads running rollouts (default: all cores)")
    g.add_argument("--cluster", default=None, metavar="ADDRESS",
                   help=f"run the rollouts on the workers of this Dask scheduler (tcp://host:8786) instead; {same}")


def _err(cmd: str, msg: str) -> int:
    from nbst.domain import plain

    print(f"nbst bowl {cmd}: error: {plain(msg)}", file=sys.stderr)
    return 2


def launcher(args, jobs: int):
    """The rollout runner of a subcommand: K threads here, or a Dask cluster's workers
    (``--cluster``; ValueError, one line, when the scheduler cannot be reached)."""
    from nbst.models.bowling import shot

    if getattr(args, "cluster", None):
        from nbst.models.bowling.cluster import ClusterLauncher

        return ClusterLauncher(args.cluster)
    return shot.Launcher(jobs=jobs)


def write_shot(path, model, launch, mask: int, *, shared_scene: str | None = None, **kw) -> None:
    """Write SHOT.json and its scene XML (``<stem>.scene.xml``, with keyframe ``shot``) beside
    it, atomically; with ``shared_scene`` the file names that scene (written by the caller)."""
    from nbst.outputs import write_text_atomic

    from nbst.models.bowling import shotfile

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

    from nbst.models.bowling import search, shot

    prepare_output(args.output)
    seed = args.seed if args.seed is not None else int(np.random.SeedSequence().entropy % (2**31))
    jobs = args.jobs or default_jobs()
    want = shot.pins_of(args.down)
    bar = []

    def progress(p) -> None:
        if args.quiet:
            return
        if not bar:
            from nbst.progress import progress_bar

            bar.append(progress_bar(total=args.max_rollouts, unit="launch", file=sys.stderr, dynamic_ncols=True,
                            desc=f"bowl {','.join(map(str, want))}", smoothing=0.1))
        bar[0].update(p.rollouts - bar[0].n)
        if p.rollouts:
            near = ",".join(map(str, shot.pins_of(p.best_mask))) or "none"
            bar[0].set_postfix_str(f"nearest {near} ({p.best_hamming} off), {p.subsets} subsets seen",
                                   refresh=False)

    try:
        L = launcher(args, jobs)
    except ValueError as e:
        return _err("solve", f"--cluster: {e}")
    progress(search.Progress(0, 10, 0, 0))  # the bar starts with the clock
    try:
        with sigterm_as_interrupt():
            res = search.solve(args.down, seed=seed, max_rollouts=args.max_rollouts, launcher=L, callback=progress,
                               distance=args.distance)
        if bar:
            bar[0].close()
        rob = None
        if not args.no_robustness and res.stopped != "interrupted":
            try:
                with sigterm_as_interrupt():
                    rob = search.robustness(L, res.launch, res.mask)
            except KeyboardInterrupt:
                res.stopped = "interrupted"
        runner = {"cluster": args.cluster} if args.cluster else {"jobs": jobs}
        meta = {"seed": seed, "rollouts": res.rollouts, "restarts": res.restarts, **runner,
                "max_rollouts": args.max_rollouts, "stopped": res.stopped, "wall_time_s": round(res.wall_time, 3),
                "subsets_seen": len(res.archive), "algorithm": "explore + CMA-ES restarts from nearest subsets",
                "distance": args.distance}
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
    from nbst.models.bowling import shotfile

    try:
        d, down = shotfile.replay_file(args.shot)
    except shotfile.ShotFileError as e:
        return _err("replay", str(e))
    want = sorted(d["down"])
    ok = down == want
    if args.json:
        from nbst.cli.args import print_json

        print_json({"shot": str(args.shot), "down": down, "expected": want, "match": ok})
    else:
        print(f"pins down  {','.join(map(str, down)) or 'none'}")
        print(f"expected   {','.join(map(str, want)) or 'none'}  ({'match' if ok else 'DIFFERENT'})")
    return 0 if ok else 1


def shot_name(mask: int) -> str:
    from nbst.models.bowling import shot

    return "subset-" + "_".join(map(str, shot.pins_of(mask))) + ".json"


def unpack_atlas(atlas_path, folder) -> int:
    """Write the shots of an atlas file as FOLDER/subset-<pins>.json (those not there yet)
    and its scene as FOLDER/scene.xml (when absent); returns how many shots were written."""
    import json
    import shutil

    from nbst.outputs import write_text_atomic

    from nbst.models.bowling import shot, shotfile

    atlas_path, folder = Path(atlas_path), Path(folder)
    a = json.loads(atlas_path.read_text(encoding="utf-8"))
    if not (isinstance(a, dict) and a.get("kind") == "nbst-bowling-atlas"):
        raise ValueError(f"{atlas_path}: not an nbst bowling atlas")
    scene = atlas_path.parent / a["scene"]
    if not scene.is_file():
        raise ValueError(f"{atlas_path}: its shots need their scene {a['scene']!r} beside it, and {scene} "
                         f"is missing (copy it from where the atlas came from)")
    if not (folder / "scene.xml").exists():
        shutil.copyfile(scene, folder / "scene.xml")
    n = 0
    for d in a["shots"]:
        f = folder / shot_name(shot.mask_from_pins(d["down"]))
        if not f.exists():
            write_text_atomic(f, shotfile.dumps({**d, "scene": "scene.xml"}))
            n += 1
    return n


def cmd_atlas(args) -> int:
    import csv
    import io
    import json

    import numpy as np

    from nbst.outputs import prepare_output, sigterm_as_interrupt, write_text_atomic

    from nbst.models.bowling import atlas as atlasmod
    from nbst.models.bowling import scene as scenemod
    from nbst.models.bowling import search, shot, shotfile

    out = prepare_output(args.out, directory=True, option="--out")
    if args.from_atlas:
        try:
            unpack_atlas(args.from_atlas, out)
        except (OSError, ValueError, KeyError, TypeError) as e:
            return _err("atlas", f"--from: {e}")
    xml = scenemod.scene_xml()
    if not (out / "scene.xml").exists():
        write_text_atomic(out / "scene.xml", xml)  # one scene for every shot (the same model)
    elif (out / "scene.xml").read_text() != xml:  # shots of another scene: new ones would not replay there
        return _err("atlas", f"{out / 'scene.xml'} is not this version's scene; use a new --out folder")
    jobs = args.jobs or default_jobs()
    try:
        L = launcher(args, jobs)
    except ValueError as e:
        return _err("atlas", f"--cluster: {e}")
    files = {}
    for f in out.glob("subset-*.json"):
        try:
            files[shot.mask_from_pins(int(p) for p in f.stem.split("-", 1)[1].split("_"))] = f
        except ValueError:
            continue
    launches = {}
    for m, f in files.items():  # resume: the launches of the shots already written
        try:
            la = json.loads(f.read_text())["launch"]
            launches[m] = np.array([la[k] for k in shot.KEYS], dtype=float)
        except (OSError, ValueError, KeyError, TypeError):
            continue
    arch = atlasmod.Archive.from_launches(launches)
    t0 = time.perf_counter()
    probes = [0]
    bar = None
    if not args.quiet:
        from nbst.progress import progress_bar

        total = 0 if args.robustness_only else args.max_rollouts
        bar = progress_bar(total=total or None, unit="launch", file=sys.stderr, dynamic_ncols=True, desc="atlas")

    def add_robustness(mask, f):
        d = json.loads(f.read_text())
        rob = search.robustness_ladder(L, launches[mask], mask)
        probes[0] += rob["lateral_m_rollouts"] + rob["speed_m_s_rollouts"]
        d["robustness"] = rob
        write_text_atomic(f, shotfile.dumps(d))

    def on_new(masks):
        for m in masks:
            f = out / shot_name(m)
            write_shot(f, L.model, arch.elite[m], m, shared_scene="scene.xml", requested=m,
                       search={"seed": args.seed, "method": args.method, "found_after": arch.found_at[m]})
            files[m], launches[m] = f, arch.elite[m]
            if not args.no_robustness:
                add_robustness(m, f)

    def progress(a):
        if bar:
            bar.update(a.rollouts - bar.n)
            bar.set_postfix_str(f"{len(a)} subsets", refresh=False)

    stopped = False
    try:
        with sigterm_as_interrupt():
            if args.robustness_only:
                for m in sorted(files):
                    if m in launches and "robustness" not in json.loads(files[m].read_text()):
                        add_robustness(m, files[m])
                        if bar:
                            bar.update(1)
            elif args.max_rollouts:
                atlasmod.run(L, arch, method=args.method, budget=args.max_rollouts, seed=args.seed,
                             per_subset=args.per_subset, on_new=on_new, callback=progress)
    except KeyboardInterrupt:
        stopped = True
    finally:
        if bar:
            bar.close()
        L.close()
    have = {m: f.name for m, f in files.items()}
    rows = [(m, len(shot.pins_of(m)), have.get(m, "")) for m in range(1, 1024)]
    buf = io.StringIO()
    w = csv.writer(buf)
    w.writerow(["mask", "pins", "size", "file"])
    for m, k, f in rows:
        w.writerow([m, "-".join(map(str, shot.pins_of(m))), k, f])
    write_text_atomic(out / "summary.csv", buf.getvalue())
    write_text_atomic(out / "summary.md", summary_md(have, launches=arch.rollouts, probes=probes[0],
                                                     seconds=time.perf_counter() - t0, seed=args.seed,
                                                     method=args.method, archive=arch))
    atlas_json(out, seed=args.seed)
    from nbst.models.bowling import figure

    fig = figure.atlas_figure(have, title=f"{len(have)} of 1,023 subsets (red frame: needs a flying pin)")
    figure.save(fig, out / "summary.png")
    n = len(have)
    print(f"nbst bowl atlas: {n} of 1023 subsets have a shot in {out} ({arch.rollouts} search launches and "
          f"{probes[0]} robustness launches this run{', interrupted' if stopped else ''})", file=sys.stderr)
    return 130 if stopped else 0


def summary_md(have: dict, *, launches: int, probes: int, seconds: float, seed: int, method: str,
               archive=None) -> str:
    """The atlas's summary table (markdown): found / possible by size, and the geometry classes."""
    from nbst.models.bowling import geometry

    found = sorted(have)
    lines = ["# Bowling atlas", "", f"{len(found)} of 1023 subsets found; this run: {launches} search launches "
             f"({method}) and {probes} robustness launches in {seconds:.0f} s (seed {seed}).", ""]
    if archive is not None and method.startswith("elites") and launches:
        (nu, hu), kids = archive.uniform, sum(archive.children.values())
        new = sum(1 for v in archive.found_at.values() if v >= 0)
        lines[-1:-1] = ["", f"New subsets this run: {new}; from its {nu} uniform launches: {hu}; from its "
                            f"{kids} children of elites: {sum(archive.hits.values())}."]
    return "\n".join(lines + geometry.summary_lines(found)) + "\n"
