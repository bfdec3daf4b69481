"""Render benchmark: frames per second of ``nbst render``'s 2D view against the number of
disks (N = 10 .. 3,000 at fixed density, 1280x720), and the parts of one problem's video.

    python benchmarks/bench_render.py --quick              # N = 10 .. 1,000, 60 frames a size: < 60 s
    python benchmarks/bench_render.py                      # N = 10 .. 3,000, 301 frames a size (5 s at 60 fps)
    python benchmarks/bench_render.py --sizes 10,1000      # other sizes
    python benchmarks/bench_render.py --problem diamond-s14 [--solution sol.json] [--view 3d] [--no-trails]
    python benchmarks/bench_render.py --problem grid-1000  # the parts for the curve's problem at N = 1,000

The curve: for each N, disks of radius 1 on a jittered grid in a 16:9 box holding them at
8 % area density, random velocities (up to a quarter of the box's width in t_final = 5 s),
targets where that motion ends (so every disk ends on target and the lit rings are drawn);
the same picture at every N, the disks shrinking on screen as N grows. Prints frames per
second of: render (draw + RGBA readback, as the MP4 path reads it; numbers off), with
--trails, with --labels forced on (these over frames spread across the whole motion), and
end to end to an MP4 (render + H.264 encoding, overlapped, as ``nbst render``, of as many
consecutive frames at --fps but at least 2 s of video: x264's cost depends on the motion
between frames; in steady state, ffmpeg's start and the file's end left out), each with its ratio to N = 10 measured in the same run.
``--problem``: ms per frame of each part (draw, readback, encode, end to end) for one
problem. Figures, never assertions; the GL renderer and the load average are printed with
them (the development machine is shared).
"""
from __future__ import annotations

import argparse
import os
import tempfile
import time

import numpy as np

CURVE = (10, 30, 100, 300, 1000, 3000)
QUICK_CURVE = (10, 30, 100, 300, 1000)


def grid_problem(n: int, *, seed: int = 1, density: float = 0.08, t_final: float = 5.0, name: str | None = None):
    """(problem, velocities, trajectory): ``n`` radius-1 disks on a jittered grid in a 16:9 box
    at ``density`` (area share), random velocities up to a quarter of the box's width in
    ``t_final``, targets at the simulated final positions (an exact solution)."""
    from nbst import simulate
    from nbst.problem import problem_from_dict

    rng = np.random.default_rng(seed)
    r, aspect = 1.0, 16 / 9
    H = float(np.sqrt(n * np.pi * r * r / density / aspect))
    W = aspect * H
    cols = int(np.ceil(np.sqrt(n * aspect)))
    rows = int(np.ceil(n / cols))
    xs, ys = (np.arange(cols) + 0.5) * W / cols, (np.arange(rows) + 0.5) * H / rows
    start = np.stack(np.meshgrid(xs, ys), -1).reshape(-1, 2)[:n]
    pitch = min(W / cols, H / rows)  # >= 2r + 2 * 0.2 pitch at this density: no overlap after the jitter
    start = np.clip(start + rng.uniform(-0.2, 0.2, start.shape) * pitch, r, (W - r, H - r))
    ang = rng.uniform(0.0, 2 * np.pi, n)
    v = (0.25 * W / t_final) * rng.uniform(0.3, 1.0, n)[:, None] * np.stack([np.cos(ang), np.sin(ang)], 1)
    d = {"name": name or f"grid-{n}", "box": [W, H], "t_final": t_final, "target_radius": 2.5 * r,
         "disks": [{"start": [float(x), float(y)], "target": [float(x), float(y)], "radius": r} for x, y in start]}
    tr = simulate(problem_from_dict(d), v)
    for disk, (x, y) in zip(d["disks"], tr.final_positions):
        disk["target"] = [float(np.clip(x, r, W - r)), float(np.clip(y, r, H - r))]
    p = problem_from_dict(d)
    return p, v, simulate(p, v)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(allow_abbrev=False, description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="the curve with 60 frames a size (under a minute)")
    ap.add_argument("--sizes", default=None,
                    help="comma-separated N for the curve (default 10,30,100,300,1000,3000; --quick to 1000)")
    ap.add_argument("--frames", type=int, default=None, help="frames a size (default 301; 60 with --quick)")
    ap.add_argument("--problem", default=None,
                    help="instead of the curve: the parts of this problem's video (grid-N: the curve's problem)")
    ap.add_argument("--solution", default=None, help="with --problem: solution JSON (default: straight-line shots)")
    ap.add_argument("--size", default="1280x720")
    ap.add_argument("--fps", type=float, default=60.0)
    ap.add_argument("--view", choices=["2d", "3d"], default="2d")
    ap.add_argument("--no-trails", action="store_true")
    ap.add_argument("--repeat", type=int, default=None,
                    help="runs of each measurement; the best is printed (default 2; 1 with --quick)")
    args = ap.parse_args(argv)
    if args.repeat is None:
        args.repeat = 1 if args.quick else 2
    if args.problem is None:
        return curve(args)
    return parts(args)


def curve(args) -> int:
    from nbst.cli.render import parse_size
    from nbst.render.core.gl import create_context
    from nbst.render.scene2d import Renderer2D

    sizes = [int(x) for x in args.sizes.split(",")] if args.sizes else list(QUICK_CURVE if args.quick else CURVE)
    frames = args.frames or (60 if args.quick else 301)
    size = parse_size(args.size)
    ctx = create_context()
    load0 = os.getloadavg()[0]
    print(f"nbst render, 2D, {size[0]}x{size[1]}, {frames} frames a size over t_final = 5 s; disks at 8 % density; "
          f"best of {args.repeat}")
    print(f"GL_RENDERER: {ctx.info['GL_RENDERER']}; {os.cpu_count()} CPUs; load average {load0:.1f} at the start")
    cols = ("render", "+trails", "+labels", "MP4")
    print(f"{'N':>6} {'events':>7} " + " ".join(f"{c + ' fps':>12} {'vs N0':>6}" for c in cols))
    base = None
    rows = []
    for n in sizes:
        p, v, tr = grid_problem(n)
        times = np.linspace(0.0, p.t_final, frames)
        fps = []
        for trails, labels in ((False, False), (True, False), (False, True)):
            r = Renderer2D(ctx, p, tr, size=size, trails=trails, labels=labels)
            buf = r.target.new_frame(4)
            r.render_rgba(times[len(times) // 2], out=buf)  # warm-up: shaders, buffers

            def run():
                for t in times:
                    r.render_rgba(t, out=buf)
            fps.append(frames / _best(run, args.repeat))
            if not (trails or labels):
                # consecutive frames of a real video (the encoder's cost depends on the motion between
                # frames), at least 2 s of it, from t = 1 s or from 0 when they span all of it
                m = max(frames, 2 * int(args.fps))
                clip = np.minimum(p.t_final, np.arange(m) / args.fps + max(0.0, min(1.0, p.t_final - m / args.fps)))
                mp4 = max(_mp4_fps(r, clip, args.fps) for _ in range(max(1, args.repeat)))
            r.release()
        fps.append(mp4)
        base = base or fps
        rows.append((n, fps))
        print(f"{n:>6} {len(tr.events):>7} " + " ".join(f"{f:>12.0f} {f / b:>6.2f}" for f, b in zip(fps, base)),
              flush=True)
    ctx.release()
    print(f"load average {os.getloadavg()[0]:.1f} at the end; 'vs N0': fps / fps at N = {sizes[0]} in this run")
    return 0


#: Frames the encoder swallows before its pace shows (ffmpeg's pipe and x264's lookahead and
#: frame threads hold that many): left out of the MP4 rate, as ffmpeg's start and the file's end.
MP4_SETTLE = 30


def _mp4_fps(r, times, fps) -> float:
    """Frames per second of rendering and encoding ``times`` to an MP4 as ``nbst render`` does
    (frames drawn into the writer's buffers, encoded on its thread, overlapped), in steady
    state: the render loop waits for a free buffer, so past the first MP4_SETTLE frames it
    runs at the pace of the slower of the two. ffmpeg's start and the file's end (both a
    fixed cost of about half a second a video) are left out."""
    from nbst.render.core.video import VideoWriter, encode

    stamps = []

    def draw(k, out):
        if k >= len(times):
            return None
        stamps.append(time.perf_counter())
        return r.render_rgba(times[k], out=out)

    with tempfile.TemporaryDirectory() as d:
        with VideoWriter(os.path.join(d, "bench.mp4"), r.size, fps, rgba=True) as w:
            encode(draw, w)
            end = time.perf_counter()
    k0 = min(MP4_SETTLE, len(stamps) // 2)
    return (len(stamps) - k0) / (end - stamps[k0])


def _best(fn, repeat: int) -> float:
    out = []
    for _ in range(max(1, repeat)):
        t0 = time.perf_counter()
        fn()
        out.append(time.perf_counter() - t0)
    return min(out)


def parts(args) -> int:

    from nbst import load_problem, load_solution, simulate
    from nbst.render.core import style
    from nbst.cli.render import make_renderer, parse_size
    from nbst.render.core.gl import create_context
    from nbst.render.core.times import frame_times
    from nbst.render.core.video import VideoWriter, encode, render_video

    if args.problem.startswith("grid-") and args.problem[5:].isdigit():  # the curve's problem at one N
        p, v, tr = grid_problem(int(args.problem[5:]))
    else:
        p = load_problem(args.problem)
        v = load_solution(args.solution, p).velocities if args.solution else p.straight_velocities()
        tr = simulate(p, v)
    size = parse_size(args.size)
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
