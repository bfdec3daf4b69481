"""Render benchmark: a t_final-second video of diamond-s14 (default 5 s, 60 fps,
1280x720), rendered and encoded end to end, and its parts.

    python benchmarks/bench_render.py                      # straight-line shots, 2D, trails
    python benchmarks/bench_render.py --solution sol.json  # a solution from `nbst solve`
    python benchmarks/bench_render.py --view 3d --no-trails

Prints ms per frame for: draw alone, render alone (draw + read_into a
preallocated buffer; RGB, and RGBA as videos read it), readback alone,
encode alone (H.264 of pre-rendered frames through the threaded writer, from
RGB and from RGBA), end to end (render + encode overlapped, as `nbst render`),
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
    from nbst.cli.render import make_renderer, parse_size
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
          f"trails {not args.no_trails}, x264 preset {style.X264_PRESET} crf {style.X264_CRF} "
          f"sws {style.SWS_FLAGS}; "
          f"{os.cpu_count()} CPUs, GL {ctx.info['GL_RENDERER']}")

    def best(fn):
        out = []
        for _ in range(max(1, args.repeat)):
            t0 = time.perf_counter()
            fn()
            out.append(time.perf_counter() - t0)
        return min(out)

    buf = r.target.new_frame()
    abuf = r.target.new_frame(4)
    r.render(0.0, out=buf)  # warm-up (shader compile, static layer)
    r.render_rgba(0.0, out=abuf)

    def render_only():
        for t in times:
            r.render(t, out=buf)

    def render_rgba():
        for t in times:
            r.render_rgba(t, out=abuf)

    def draw_only():
        for t in times:
            r.draw(t)
        r.target.read(buf)  # one sync at the end

    def read_only():
        for _ in range(n):
            r.target.read(buf)

    def read_rgba():
        for _ in range(n):
            r.target.read(abuf, components=4)

    def read_fresh():
        for _ in range(n):
            r.target.read(None)

    t_draw = best(draw_only)
    t_render = best(render_only)
    t_rgba = best(render_rgba)
    t_read = best(read_only)
    t_read4 = best(read_rgba)
    t_fresh = best(read_fresh)

    # pre-rendered frames (a cycle of 30 distinct ones) for the encoder alone, both input formats
    picks = times[:: max(1, n // 30)][:30]
    bank = [r.render(t).copy() for t in picks]
    abank = [r.render_rgba(t).copy() for t in picks]
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "bench.mp4")

        def encode_rgb():
            with VideoWriter(path, size, args.fps) as wr:
                encode((bank[k % len(bank)] for k in range(n)), wr)

        def encode_rgba():
            with VideoWriter(path, size, args.fps, rgba=True) as wr:
                encode((abank[k % len(abank)] for k in range(n)), wr)

        def end_to_end():
            render_video(r, times, path, fps=args.fps)

        t_enc_rgb = best(encode_rgb)
        t_enc_rgba = best(encode_rgba)
        t_e2e = best(end_to_end)
        mb = os.path.getsize(path) / 1e6
    r.release()
    ctx.release()
    ms = lambda s: 1e3 * s / n  # noqa: E731
    print(f"draw alone       {ms(t_draw):7.2f} ms/frame  (GL commands, no readback)")
    print(f"render alone     {ms(t_render):7.2f} ms/frame  RGB  (draw + read_into a preallocated buffer)")
    print(f"                 {ms(t_rgba):7.2f} ms/frame  RGBA (what the MP4 path reads)")
    print(f"  readback alone {ms(t_read):7.2f} ms/frame  RGB read_into ({ms(t_fresh):.2f} ms into a fresh array), "
          f"RGBA {ms(t_read4):.2f} ms")
    print(f"encode alone     {ms(t_enc_rgb):7.2f} ms/frame  from RGB  (H.264 via imageio-ffmpeg, writer thread, "
          "a copy per frame into its pool)")
    print(f"                 {ms(t_enc_rgba):7.2f} ms/frame  from RGBA (the MP4 path)")
    print(f"end to end       {ms(t_e2e):7.2f} ms/frame  = {n / t_e2e:6.1f} fps  ({n} frames in {t_e2e:.2f} s, "
          f"{mb:.2f} MB MP4; as `nbst render`)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
