"""Render benchmark: a t_final-second video of diamond-s14 (default 5 s, 60 fps,
1280x720), rendered and encoded end to end, and its parts.

    python benchmarks/bench_render.py                      # straight-line shots, 2D, trails
    python benchmarks/bench_render.py --solution sol.json  # a solution from `nbst solve`
    python benchmarks/bench_render.py --view 3d --no-trails

Prints ms per frame for: render alone (GL draw + read_into a preallocated
buffer), readback alone, encode alone (H.264 of pre-rendered frames through the
threaded writer), end to end (render + encode overlapped, as `nbst render`),
and frames per second. Figures, never assertions.
"""
from __future__ import annotations

import argparse
import os
import tempfile
import time

import numpy as np


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--problem", default="diamond-s14")
    ap.add_argument("--solution", default=None, help="solution JSON (default: straight-line shots)")
    ap.add_argument("--size", default="1280x720")
    ap.add_argument("--fps", type=float, default=60.0)
    ap.add_argument("--view", choices=["2d", "3d"], default="2d")
    ap.add_argument("--no-trails", action="store_true")
    ap.add_argument("--repeat", type=int, default=2, help="runs of each measurement; the best is printed")
    args = ap.parse_args(argv)

    from nbst import load_problem, load_solution, simulate
    from nbst.render import style
    from nbst.render.cli import make_renderer, parse_size
    from nbst.render.gl import create_context
    from nbst.render.video import VideoWriter, encode, frame_times, render_video

    p = load_problem(args.problem)
    v = load_solution(args.solution, p).velocities if args.solution else p.straight_velocities()
    size = parse_size(args.size)
    tr = simulate(p, v)
    times = frame_times(p.t_final, args.fps)
    n = len(times)
    ctx = create_context()
    r = make_renderer(ctx, p, tr, view=args.view, size=size, trails=not args.no_trails)
    print(f"{p.name}: {n} frames ({p.t_final:g} s at {args.fps:g} fps), {size[0]}x{size[1]}, view {args.view}, "
          f"trails {not args.no_trails}, x264 preset {style.X264_PRESET} crf {style.X264_CRF}; "
          f"{os.cpu_count()} CPUs, GL {ctx.info['GL_RENDERER']}")

    def best(fn):
        out = []
        for _ in range(max(1, args.repeat)):
            t0 = time.perf_counter()
            fn()
            out.append(time.perf_counter() - t0)
        return min(out)

    buf = r.target.new_frame() if hasattr(r, "target") else np.empty((size[1], size[0], 3), np.uint8)
    r.render(0.0, out=buf)  # warm-up (shader compile, static layer)

    def render_only():
        for t in times:
            r.render(t, out=buf)

    def read_only():
        for _ in range(n):
            r.target.read(buf)

    def read_fresh():
        for _ in range(n):
            r.target.read(None)

    t_render = best(render_only)
    t_read = best(read_only)
    t_fresh = best(read_fresh)

    # pre-rendered frames (a cycle of 30 distinct ones) for the encoder alone
    bank = [r.render(t).copy() for t in times[:: max(1, n // 30)][:30]]
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "bench.mp4")

        def encode_only():
            with VideoWriter(path, size, args.fps) as w:
                encode((bank[k % len(bank)] for k in range(n)), w)

        def end_to_end():
            render_video(r, times, path, fps=args.fps)

        t_encode = best(encode_only)
        t_e2e = best(end_to_end)
        mb = os.path.getsize(path) / 1e6
    r.release()
    ctx.release()
    ms = lambda s: 1e3 * s / n  # noqa: E731
    print(f"render alone     {ms(t_render):7.2f} ms/frame  (draw + read_into a preallocated buffer)")
    print(f"  readback alone {ms(t_read):7.2f} ms/frame  (read_into); a fresh array per frame: {ms(t_fresh):.2f} ms")
    print(f"encode alone     {ms(t_encode):7.2f} ms/frame  (H.264 yuv420p via imageio-ffmpeg, writer thread; "
          "one copy per frame into the writer's pool)")
    print(f"end to end       {ms(t_e2e):7.2f} ms/frame  = {n / t_e2e:6.1f} fps  ({n} frames in {t_e2e:.2f} s, "
          f"{mb:.2f} MB MP4)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
