"""Crash video benchmark: frames per second of ``nbst render CRASH.json`` at 1280x720, and the
README's example (a built-in script solved, then rendered) end to end.

    python benchmarks/bench_render_crash.py                      # t-bone, solved here with --seed 1
    python benchmarks/bench_render_crash.py --crash tbone.json   # a crash file you have
    python benchmarks/bench_render_crash.py --readme             # also: the README's two commands, timed

Prints, for the overhead camera and for ``--follow`` (chase + overhead): the renderer's set-up
(buffers, and the chase camera's framing over every pose), ms per frame of the
render alone (draw + MSAA resolve + RGBA readback, as the MP4 path reads it, over frames spread
across the crash), its ratio to an empty frame's (clear + resolve + readback, the floor, measured
in the same run), and the whole video end to end (render + H.264 encoding, as ``nbst render``:
every frame of the real-time, slowed and held parts) in frames per second. With ``--readme``:
the wall time of ``nbst crash solve t-bone -o tbone.json --seed 1`` and of ``nbst render tbone.json
-o tbone.mp4 --follow A``, run as the README runs them. Figures, never assertions; the GL
renderer and the load average are printed with them (the development machine is shared).
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

#: The ``nbst`` beside this Python (the checkout's .venv/bin/nbst), as the README runs it.
NBST = str(Path(sys.executable).with_name("nbst"))


def solve(script: str, seed: int, out: Path) -> float:
    """Solve ``script`` with ``nbst crash solve`` into ``out``; its wall time (s)."""
    t = time.perf_counter()
    subprocess.run([NBST, "crash", "solve", script, "-o", str(out), "--seed", str(seed), "-q"],
                   check=False)
    return time.perf_counter() - t


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], allow_abbrev=False)
    ap.add_argument("--crash", type=Path, default=None, help="a crash file (default: t-bone solved with --seed 1)")
    ap.add_argument("--frames", type=int, default=60, help="frames timed for the render alone (default 60)")
    ap.add_argument("--size", default="1280x720")
    ap.add_argument("--readme", action="store_true", help="also time the README's solve and render commands")
    args = ap.parse_args(argv)
    w, h = (int(v) for v in args.size.lower().split("x"))

    from nbst.render.crash import video as crash
    from nbst.render.core.times import frame_times
    from nbst.render.crash.motion import SLOW, slow_windows
    from nbst.render.core.gl import FrameTarget, create_context
    from nbst.render.core import style

    tmp = Path(tempfile.mkdtemp(prefix="nbst-bench-crash-"))
    path = args.crash
    if path is None:
        path = tmp / "tbone.json"
        print(f"solving t-bone --seed 1: {solve('t-bone', 1, path):.1f} s wall", flush=True)
    t0 = time.perf_counter()
    d, script, model, motion = crash.load(path)
    print(f"{script.name}: {script.n} vehicles, {script.duration:g} s; load + replay + record "
          f"{time.perf_counter() - t0:.2f} s ({len(motion.times)} poses, {len(motion.marks)} marks)", flush=True)
    ctx = create_context()
    print(f"GL: {ctx.info['GL_RENDERER']}; load average {os.getloadavg()[0]:.1f} (1 min), {os.cpu_count()} cores")
    times = np.linspace(0.0, motion.duration, args.frames)

    floor_target = FrameTarget(ctx, (w, h), samples=style.MSAA_SAMPLES, depth=True)
    buf = floor_target.new_frame(4)
    t = time.perf_counter()
    for _ in times:
        floor_target.draw_fbo.use()
        floor_target.draw_fbo.clear(0.1, 0.1, 0.1, 1.0, depth=1.0)
        floor_target.read(buf, components=4)
    floor = (time.perf_counter() - t) / len(times) * 1e3
    floor_target.release()
    print(f"empty frame (clear + resolve + RGBA readback): {floor:.1f} ms")
    for camera, follow in (("overhead", None), ("both", 0)):
        t = time.perf_counter()
        r = crash.CrashRenderer(ctx, d, script, model, motion, size=(w, h), camera=camera, follow=follow or 0)
        setup = time.perf_counter() - t
        buf = r.target.new_frame(4)
        r.render_rgba(times[0], out=buf)
        t = time.perf_counter()
        for x in times:
            r.render_rgba(float(x), out=buf)
        ms = (time.perf_counter() - t) / len(times) * 1e3
        r.release()
        out = tmp / f"{camera}.mp4"
        ft = frame_times(motion.duration, style.DEFAULT_FPS, slow=SLOW, hold=1.0,
                         windows=slow_windows([im.t for im in motion.impacts], motion.duration))
        t = time.perf_counter()
        n = crash.render_crash(d, script, model, motion, out, camera=camera, follow=follow or 0, size=(w, h),
                               fps=style.DEFAULT_FPS, times=ft)
        e2e = time.perf_counter() - t
        name = "overhead" if follow is None else f"--follow {script.names()[0]} (chase + overhead)"
        print(f"{name:36s} set-up {setup:.2f} s; render {ms:6.1f} ms/frame ({ms / floor:4.1f}x the empty frame); "
              f"end to end {n} frames "
              f"({n / style.DEFAULT_FPS:.1f} s of video) in {e2e:.1f} s = {n / e2e:.1f} fps; "
              f"{out.stat().st_size / 1e6:.2f} MB", flush=True)
    ctx.release()
    if args.readme:
        json_ = tmp / "readme.json"
        s = solve("t-bone", 1, json_)
        t = time.perf_counter()
        subprocess.run([NBST, "render", str(json_), "-o", str(tmp / "readme.mp4"), "--follow",
                        "A", "-q"], check=False)
        r_ = time.perf_counter() - t
        print(f"README example: nbst crash solve t-bone --seed 1 {s:.1f} s + nbst render --follow A {r_:.1f} s = "
              f"{s + r_:.1f} s wall (load average {os.getloadavg()[0]:.1f})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
