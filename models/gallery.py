"""The MuJoCo scene gallery: ``models/scenes/NAME/`` for each built-in problem.

Regenerate (documented in ``models/scenes/README.md`` and ``docs/mujoco.md``)::

    python -m nbst.models.gallery            # or: nbst gallery
    python -m nbst.models.gallery over5 --max-trials 2000000
    python -m nbst.models.gallery --no-search   # re-render scenes from the stored solutions

Each folder holds ``problem.json`` (the built-in problem), ``solution.json`` (the best
solution nbst has found: the stored one unless a fresh ``nbst.search.solve`` run has a
lower cost), ``scene.xml`` (``nbst mjcf``) and ``preview.png`` (top view at t = 0,
rendered by MuJoCo, every puck and target numbered, a caption below). No search module, no stored solution: the folder gets the scene with
the disks at rest and no solution.json (never a placeholder).
"""
from __future__ import annotations

import argparse
import importlib.util
import os
import sys
from typing import Any
from pathlib import Path

import numpy as np

from nbst import palette
from nbst.models.scene import DEFAULT_UNIT, PUCK_HALF_HEIGHT_RADII, build_model, scene_xml
from nbst.outputs import write_bytes_atomic, write_text_atomic
from nbst.problem import builtin_names, display_name, load_problem
from nbst.solution import load_solution, make_solution, save_solution, write_json_atomic

__all__ = ["GALLERY_DIR", "FILES", "PREVIEW_SIZE", "PREVIEW_AMBIENT", "PREVIEW_DIFFUSE", "PREVIEW_NUMBER_PX",
           "PREVIEW_CAPTION_PX", "PREVIEW_INK", "PREVIEW_TARGET_INK", "PREVIEW_MIN_PUCK_PX", "preview_png",
           "build_entry", "main"]

#: Default gallery folder: models/scenes next to this file.
GALLERY_DIR = Path(__file__).resolve().parent / "scenes"
#: Preview size (pixels).
#: The files of each gallery folder (``nbst gallery`` checks each one before any work).
FILES = ("problem.json", "solution.json", "scene.xml", "preview.png")
PREVIEW_SIZE = 640
#: Preview lighting: MuJoCo's default headlight plus the scene's top light add up to
#: more than 1 and add a white specular highlight, which turns amber pucks yellow and
#: blue ones cyan. For the preview (only: scene.xml keeps its lights) ambient + diffuse
#: sum to 1 with no specular, so a puck's top face, lit straight from above, shows its
#: rgba exactly: nbst's class colours (nbst.palette), as in every other picture.
PREVIEW_AMBIENT = 0.35
PREVIEW_DIFFUSE = 0.65


#: Numbers on the preview (pixels): each puck's index upper left of it, each target's (its
#: disk's index) upper right of its dot, dark over a white halo; a caption band below the
#: view says what the picture is and what its marks mean.
PREVIEW_NUMBER_PX = 15
PREVIEW_CAPTION_PX = 13
PREVIEW_INK = (25, 25, 30)
PREVIEW_TARGET_INK = (20, 100, 35)  # the targets' green, darkened to read as text
PREVIEW_MIN_PUCK_PX = 3.0  # smaller pucks are drawn at this radius (with a dot at the target)


def _project(model, data, cam: str, size: int, xyz) -> np.ndarray:
    """World points (..., 3) -> image px (column, row) through MuJoCo camera ``cam`` (pinhole,
    square image of ``size`` px)."""
    import mujoco
    k = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, cam)
    pos, mat = data.cam_xpos[k], data.cam_xmat[k].reshape(3, 3)  # columns: camera x, y, z (looks along -z)
    f = 0.5 * size / np.tan(np.radians(model.cam_fovy[k]) / 2)
    local = (np.asarray(xyz, float) - pos) @ mat
    depth = -local[..., 2]
    return np.stack([size / 2 + f * local[..., 0] / depth, size / 2 - f * local[..., 1] / depth], axis=-1)


def _annotate(rgb: np.ndarray, problem, pucks_px, pucks_r_px, targets_px) -> np.ndarray:
    """The preview with numbers (pucks upper left in black, targets upper right of their dots
    in green) and a caption band below it (what the picture shows, what the marks mean)."""
    from matplotlib import font_manager
    from PIL import Image, ImageDraw, ImageFont

    bold = ImageFont.truetype(font_manager.findfont(font_manager.FontProperties(family="DejaVu Sans",
                                                                                weight="bold")), PREVIEW_NUMBER_PX)
    plain = ImageFont.truetype(font_manager.findfont(font_manager.FontProperties(family="DejaVu Sans")),
                               PREVIEW_CAPTION_PX)
    size = rgb.shape[1]
    p = problem
    ncue = int(p.cueable.sum())
    kinds = "amber: cueable puck" + (", blue: noncueable puck" if ncue < p.n else "")
    lines = [f"{display_name(p.name)}: the MuJoCo scene at t = 0, seen from the top camera",
             f"{kinds}; black number: the puck's disk index",
             "green disc: a target's neighbourhood of radius R, its dot the target;",
             "green number: the index of the disk that must end there"]
    pitch = int(PREVIEW_CAPTION_PX * 1.45)
    band = len(lines) * pitch + 12
    img = Image.new("RGB", (size, rgb.shape[0] + band), (255, 255, 255))
    img.paste(Image.fromarray(np.ascontiguousarray(rgb)), (0, 0))
    d = ImageDraw.Draw(img)
    small = np.asarray(pucks_r_px) < PREVIEW_MIN_PUCK_PX
    for i in np.flatnonzero(small):  # pucks too small to see (diamond-s14-tiny): drawn at the least size
        (cx, cy), r = pucks_px[i], PREVIEW_MIN_PUCK_PX
        d.ellipse((cx - r, cy - r, cx + r, cy + r), fill=palette.rgb8(palette.class_color(p.cueable[i])),
                  outline=PREVIEW_INK)
        (tx, ty), r = targets_px[i], 2.0
        d.ellipse((tx - r, ty - r, tx + r, ty + r), fill=PREVIEW_TARGET_INK)
    if small.any():
        lines[1] += f" (pucks under {PREVIEW_MIN_PUCK_PX:g} px drawn at {PREVIEW_MIN_PUCK_PX:g})"
    halo: dict[str, Any] = dict(stroke_width=2, stroke_fill=(255, 255, 255))
    for k in range(p.n):
        s = str(k)
        w = d.textlength(s, font=bold)
        c, r = pucks_px[k], pucks_r_px[k]
        off = 0.72 * r + 1
        d.text((c[0] - off - w, c[1] - off - PREVIEW_NUMBER_PX), s, font=bold, fill=PREVIEW_INK, **halo)
        t = targets_px[k]
        d.text((t[0] + 4, t[1] - 4 - PREVIEW_NUMBER_PX), s, font=bold, fill=PREVIEW_TARGET_INK, **halo)
    y = rgb.shape[0] + 6
    for ln in lines:
        d.text((8, y), ln, font=plain, fill=PREVIEW_INK)
        y += pitch
    return np.asarray(img)


def preview_png(problem, velocities=None, *, size: int = PREVIEW_SIZE) -> bytes:
    """A top view of the scene at t = 0 as PNG bytes (MuJoCo's renderer, EGL when headless),
    lit so that the pucks show their class colours exactly (PREVIEW_AMBIENT); every puck and
    target numbered with its disk's index and a caption below (``_annotate``)."""
    os.environ.setdefault("MUJOCO_GL", "egl")
    import io

    import mujoco
    from matplotlib import image as mpimg

    model = build_model(problem, velocities)
    model.vis.headlight.ambient[:] = PREVIEW_AMBIENT
    model.vis.headlight.diffuse[:] = 0.0
    model.vis.headlight.specular[:] = 0.0
    model.light_ambient[:] = 0.0
    model.light_diffuse[:] = PREVIEW_DIFFUSE
    model.light_specular[:] = 0.0
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, 0)
    mujoco.mj_forward(model, data)
    with mujoco.Renderer(model, size, size) as r:
        r.update_scene(data, camera="top")
        rgb = r.render()
    u = DEFAULT_UNIT
    rad = np.asarray(problem.radius, float) * u
    top = np.concatenate([np.asarray(problem.start, float) * u, (rad * (1 + PUCK_HALF_HEIGHT_RADII))[:, None]], axis=1)
    pucks = _project(model, data, "top", size, top)
    edge = _project(model, data, "top", size, top + np.stack([rad, 0 * rad, 0 * rad], axis=1))
    targets = _project(model, data, "top", size, np.concatenate([np.asarray(problem.target, float) * u,
                                                                 np.zeros((problem.n, 1))], axis=1))
    rgb = _annotate(rgb, problem, pucks, np.linalg.norm(edge - pucks, axis=1), targets)
    buf = io.BytesIO()
    mpimg.imsave(buf, rgb, format="png")
    return buf.getvalue()


def _stored(folder: Path, problem):
    from nbst.sim import simulate
    path = folder / "solution.json"
    if not path.is_file():
        return None, np.inf
    sol = load_solution(path, problem)
    return sol, simulate(problem, sol.velocities).cost


def build_entry(name: str, folder: Path, *, seed: int, max_trials: int, search: bool, log=print) -> dict:
    """Regenerate one gallery folder; returns what was done."""
    from nbst.sim import simulate

    problem = load_problem(name)
    folder.mkdir(parents=True, exist_ok=True)
    write_json_atomic(folder / "problem.json", problem.to_dict())
    best, best_cost = _stored(folder, problem)
    source = "stored" if best is not None else None
    if search and importlib.util.find_spec("nbst.search") is not None:
        from nbst.search import solve
        log(f"{name}: searching (seed {seed}, up to {max_trials} trials) ...")
        sol = solve(problem, seed=seed, max_trials=max_trials)
        cost = simulate(problem, sol.velocities).cost
        kept = f"the gallery's solution has cost {best_cost:.6g}" if best is not None else "no solution stored yet"
        log(f"{name}: search found cost {cost:.6g}; {kept}")
        if cost < best_cost:
            best, best_cost, source = sol, cost, "search"
    elif search:
        log(f"{name}: nbst.search is not available; keeping the stored solution")
    v = None
    if best is not None:
        v = best.velocities
        tr = simulate(problem, v)
        if source == "search":
            meta = dict(best.meta)
            meta.update(cost=tr.cost, signature=tr.signature_string, order=tr.order)
            save_solution(folder / "solution.json", make_solution(problem, v, **meta))
    write_text_atomic(folder / "scene.xml", scene_xml(problem, v), option="--out-dir")
    write_bytes_atomic(folder / "preview.png", preview_png(problem, v), option="--out-dir")
    return {"name": name, "source": source, "cost": best_cost}


def main(argv=None) -> int:
    os.environ.setdefault("MUJOCO_GL", "egl")  # before mujoco is imported: headless rendering

    ap = argparse.ArgumentParser(allow_abbrev=False, prog="python -m nbst.models.gallery",
                                 description=__doc__.split("\n\n")[0])
    ap.add_argument("names", nargs="*", metavar="NAME", help="built-in problems (default: all)")
    ap.add_argument("--dir", default=str(GALLERY_DIR), help="gallery folder (default: models/scenes)")
    ap.add_argument("--seed", type=int, default=1, help="search seed (default 1)")
    ap.add_argument("--max-trials", type=int, default=1_000_000, help="search budget per problem (default 1e6)")
    ap.add_argument("--no-search", action="store_true", help="only re-render scenes from the stored solutions")
    args = ap.parse_args(argv)
    names = args.names or list(builtin_names())
    unknown = [n for n in names if n not in builtin_names()]
    if unknown:
        print(f"gallery: error: not built-in: {', '.join(unknown)} (see `nbst problems`)", file=sys.stderr)
        return 2
    for name in names:
        r = build_entry(name, Path(args.dir) / name, seed=args.seed, max_trials=args.max_trials,
                        search=not args.no_search)
        what = "no solution" if r["source"] is None else f"{r['source']} solution, cost {r['cost']:.6g}"
        print(f"{name}: {Path(args.dir) / name} ({what})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
