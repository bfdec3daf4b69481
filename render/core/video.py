"""Writers: frames in, files out. MP4 (H.264, yuv420p) and GIF through
imageio-ffmpeg's ffmpeg on a background thread; PNG stills through Pillow.

Frames travel in reusable buffers: ``VideoWriter.acquire()`` hands out one of a
few preallocated arrays, the renderer reads the GL frame into it, ``submit``
queues it, and the encoder thread returns it to the pool once ffmpeg has it.
Rendering and encoding overlap; no per-frame allocation. Frames go as RGBA
(the framebuffer's layout: the cheapest readback); ffmpeg converts them to
yuv420p with a bilinear scaler (its default bicubic one cost ~5 ms a frame).
"""
from __future__ import annotations

import os
import queue
import threading
from pathlib import Path

import numpy as np

from nbst.render.core import style
from nbst.errors import InputError, RenderError
from nbst.outputs import OutputError, PartialFile, atomic_path, signals_deferred, stop_requested
from nbst.render.core.gl import create_context

__all__ = ["VIDEO_SUFFIXES", "VideoWriter", "check_video", "encode", "render_output", "render_video", "video_kind",
           "write_png"]


#: The video files written, by extension (anything else is refused: .mov would be QuickTime).
VIDEO_SUFFIXES = {".mp4": "mp4", ".gif": "gif"}


def video_kind(path) -> str:
    """'mp4' or 'gif' from the file extension (:data:`VIDEO_SUFFIXES`).

    Raises:
        RenderError: any other extension (one line: the file and what is taken).
    """
    ext = Path(path).suffix.lower()
    if ext in VIDEO_SUFFIXES:
        return VIDEO_SUFFIXES[ext]
    raise RenderError(f"{path}: unknown video extension {ext or '(none)'!r}; use .mp4 or .gif (or a .png still)")


class VideoWriter:
    """Encode frames to ``path`` (.mp4: H.264 yuv420p; .gif) on a background
    thread. Use as a context manager; ``close()`` waits for ffmpeg.

    size : (W, H) px; fps : frames per second of the file
    rgba : frames are (H, W, 4) uint8 RGBA (alpha ignored), else (H, W, 3) RGB
    """

    def __init__(self, path, size, fps, *, rgba: bool = False, buffers: int = style.QUEUE_FRAMES,
                 crf: int = style.X264_CRF, preset: str = style.X264_PRESET):

        self.final_path = str(path)
        self.kind = video_kind(path)
        # ffmpeg writes a hidden partial file beside the target (same extension: it picks the
        # muxer); close() checks the finished file (check_video: whole, with every frame) and
        # renames it over the target, so a failed, interrupted (Ctrl-C, or SIGTERM under the CLI)
        # or silently truncated run (a full disk: ffmpeg's exit status is not reported) leaves no
        # half-written video under the requested name, and the previous file as it was.
        # Links, special files and folders are refused (nbst.outputs.refuse_not_a_file).
        self.size = (int(size[0]), int(size[1]))
        self.fps = float(fps)
        w, h = self.size
        if self.kind == "mp4" and (w % 2 or h % 2):
            raise RenderError(f"H.264 in yuv420p needs an even width and height, got {w}x{h}")
        self._part = PartialFile(path)
        self._target = str(path)
        self.path = self._part.path
        self.frame_shape = (h, w, 4 if rgba else 3)
        if self.kind == "mp4":
            kw = dict(codec="libx264", pix_fmt_out="yuv420p",
                      output_params=["-sws_flags", style.SWS_FLAGS, "-preset", preset, "-crf", str(int(crf)),
                                     "-movflags", "+faststart"])
        else:  # palette from all frames (a static floor must be in it exactly), ordered dither: no flicker
            kw = dict(codec="gif", pix_fmt_out="pal8",
                      output_params=["-vf", "split[a][b];[a]palettegen[p];[b][p]paletteuse=dither=bayer:bayer_scale=4",
                                     "-loop", "0"])

        try:
            with signals_deferred():  # ffmpeg and its partial file start together with the thread that ends them
                self._start(rgba, buffers, kw)
        except KeyboardInterrupt:  # a signal during the start: stop ffmpeg, remove its partial file
            if hasattr(self, "_thread"):
                self.close(discard=True)
            self._part.discard()
            raise
        except BaseException:
            self._part.discard()
            raise

    def _start(self, rgba: bool, buffers: int, kw: dict) -> None:
        self._proc, self._log = _start_ffmpeg(self.path, self.size, self.fps, "rgba" if rgba else "rgb24", **kw)
        self._pool = [np.empty(self.frame_shape, np.uint8) for _ in range(max(1, buffers))]
        self._ids = {id(b) for b in self._pool}
        self._free: queue.Queue = queue.Queue()
        for b in self._pool:
            self._free.put(b)
        self._todo: queue.Queue = queue.Queue(maxsize=max(1, buffers))
        self._error: BaseException | None = None
        self.frames = 0
        self._closed = False
        self._thread = threading.Thread(target=self._run, name="nbst-encoder", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while True:
            buf = self._todo.get()
            if buf is None:
                return
            try:
                if self._error is None:
                    self._proc.stdin.write(memoryview(buf).cast("B"))
            except BaseException as e:  # ffmpeg died: report on the next call
                self._error = e
            finally:
                if id(buf) in self._ids:
                    self._free.put(buf)

    def _check(self) -> None:
        if self._error is not None:
            msg = _ffmpeg_reason(self._log) or str(self._error).strip().splitlines()[:1]
            raise RenderError(f"{self.final_path}: the encoder failed "
                              f"({msg[0] if msg else type(self._error).__name__}); {self._kept()}")

    def _kept(self) -> str:
        return self._part.kept()

    def acquire(self) -> np.ndarray:
        """A free frame buffer of ``frame_shape``, uint8 (blocks while all are queued)."""
        while True:
            self._check()
            try:
                return self._free.get(timeout=0.5)
            except queue.Empty:
                if not self._thread.is_alive():
                    raise RenderError(f"{self.path}: the encoder thread stopped") from None

    def unused(self, buf: np.ndarray) -> None:
        """Return a buffer from ``acquire`` that will not be submitted."""
        if id(buf) in self._ids:
            self._free.put(buf)

    def submit(self, frame: np.ndarray) -> None:
        """Queue one frame. A buffer from ``acquire`` is recycled once written;
        any other array is copied into one first."""
        self._check()
        if id(frame) not in self._ids:
            if frame.shape != self.frame_shape:
                raise InputError(f"frame shape {frame.shape}, expected {self.frame_shape}")
            buf = self.acquire()
            np.copyto(buf, frame, casting="unsafe")
            frame = buf
        self._todo.put(frame)
        self.frames += 1

    def close(self, *, discard: bool = False) -> None:
        """Flush the queue and finish the file (waits for ffmpeg), then rename it
        to ``path``; with ``discard`` (or on an encoder error) delete it instead."""
        if self._closed:
            return

        with signals_deferred():  # a Ctrl-C now waits: the file is published, or the partial file removed
            self._close(discard)

    def _close(self, discard: bool) -> None:
        self._closed = True
        self._todo.put(None)
        self._thread.join()
        try:
            _stop_ffmpeg(self._proc, kill=discard or self._error is not None)
            if self._proc.returncode and not discard and self._error is None:
                self._error = RuntimeError(f"ffmpeg exited with status {self._proc.returncode}")
            if discard or self._error is not None:
                self._part.discard()
            if not discard:
                self._check()
                self._publish()
        finally:
            if self._log is not None:
                self._log.close()

    def _publish(self) -> None:
        """Check the finished partial file (``check_video``), fsync it and rename it over the target
        (RenderError, one line, if any of it fails; the previous file stays)."""

        def check(path):
            why = check_video(path, self.kind, self.frames)
            if why:
                reason = _ffmpeg_reason(self._log)
                return f"{why}{'; ffmpeg: ' + reason[0] if reason else ''}"
            return None

        try:
            self._part.commit(check)
        except OutputError as e:
            raise RenderError(str(e).removeprefix("-o ")) from None

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb):
        # on an error in the render loop (Ctrl-C included) leave no half-written video
        self.close(discard=exc_type is not None)


def check_video(path, kind: str, frames: int) -> str | None:
    """Why the encoded file at ``path`` is not a whole video of ``frames`` frames, or None.

    ffmpeg can end without a complete file and imageio-ffmpeg does not report its exit status (a
    full disk while the MP4 index is written leaves a file that no player opens: "moov atom not
    found"). This reads the container, not the pictures (milliseconds): an MP4 must be a chain of
    boxes that ends exactly at the end of the file, with ``moov`` and ``mdat``, and its video track's
    sample table must hold ``frames`` samples; a GIF must be a chain of blocks from its header to
    its trailer with at least one image (ffmpeg merges repeated frames, so not one per frame).
    """
    try:
        with open(path, "rb") as f:
            data = f.read()
    except OSError as e:
        return e.strerror or str(e)
    if not data:
        return "the file is empty"
    return _check_mp4(data, frames) if kind == "mp4" else _check_gif(data)


class _Damaged(Exception):
    """A container that does not parse (the reason: its message); caught where the file is checked."""


def _boxes(data: bytes, start: int, end: int):
    """(type, body start, body end) of the MP4 boxes that tile data[start:end]; _Damaged if they do not."""
    k = start
    while k < end:
        if end - k < 8:
            raise _Damaged(f"{end - k} stray bytes at the end")
        size = int.from_bytes(data[k:k + 4], "big")
        kind = data[k + 4:k + 8].decode("latin-1")
        head = 8
        if size == 1:
            if end - k < 16:
                raise _Damaged("a box header is cut short")
            size, head = int.from_bytes(data[k + 8:k + 16], "big"), 16
        elif size == 0:
            size = end - k
        if size < head or k + size > end:
            raise _Damaged(f"the box at byte {k:,} runs past the end of the file (cut short)")
        yield kind, k + head, k + size
        k += size


def _check_mp4(data: bytes, frames: int) -> str | None:
    try:
        top = {kind: (a, b) for kind, a, b in _boxes(data, 0, len(data))}
        for need in ("ftyp", "moov", "mdat"):
            if need not in top:
                return f"no {need!r} box: the MP4 is incomplete"
        samples = 0
        for kind, a, b in _boxes(data, *top["moov"]):
            if kind != "trak":
                continue
            span = (a, b)
            found: tuple[int, int] | None = span
            for step in ("mdia", "minf", "stbl", "stsz"):
                found = next(((x, y) for k, x, y in _boxes(data, *span) if k == step), None)
                if found is None:
                    break
                span = found
            if found is not None and found[1] - found[0] >= 12:
                samples = max(samples, int.from_bytes(data[found[0] + 8:found[0] + 12], "big"))
    except _Damaged as e:
        return str(e)
    if samples != frames:
        return f"{samples} frames in the file, {frames} sent to the encoder"
    return None


def _check_gif(data: bytes) -> str | None:
    if data[:6] not in (b"GIF87a", b"GIF89a") or len(data) < 13:
        return "no GIF header"
    k = 13
    if data[10] & 0x80:
        k += 3 * (2 << (data[10] & 7))
    images = 0
    n = len(data)

    def sub_blocks(k):
        while True:
            if k >= n:
                raise _Damaged("the GIF is cut short")
            size = data[k]
            k += 1 + size
            if size == 0:
                return k
    try:
        while True:
            if k >= n:
                return "the GIF is cut short (no trailer)"
            b = data[k]
            if b == 0x3B:
                break
            if b == 0x21:  # an extension: label, sub-blocks
                k = sub_blocks(k + 2)
            elif b == 0x2C:  # an image: descriptor, local colour table, LZW code size, sub-blocks
                if k + 10 > n:
                    return "the GIF is cut short"
                flags = data[k + 9]
                k += 10 + (3 * (2 << (flags & 7)) if flags & 0x80 else 0)
                k = sub_blocks(k + 1)
                images += 1
            else:
                return f"an unknown GIF block 0x{b:02x} at byte {k}"
    except _Damaged as e:
        return str(e)
    if images == 0:
        return "the GIF has no image"
    if k + 1 != n:
        return f"{n - k - 1} bytes after the GIF trailer"
    return None


def _start_ffmpeg(path: str, size, fps: float, pix_fmt_in: str, *, codec: str, pix_fmt_out: str,
                  output_params: list):
    """Start ffmpeg (imageio-ffmpeg's binary) reading raw frames on its stdin and writing ``path``:
    (the process, its stderr log or None). The command is ``imageio_ffmpeg.write_frames``'s, started
    here for three reasons. Its own process group by ``process_group=0`` (set in C between fork and
    exec; imageio-ffmpeg runs ``os.setpgrp`` as ``preexec_fn``, Python in the forked child, which
    ``subprocess``'s docs warn can deadlock beside other threads: Mesa's llvmpipe runs 6 here. A
    render under the signal tests hung once in seven full test runs; 2,300 forks beside a drawing
    llvmpipe did not hang here: a suspect removed, not a cause shown). ffmpeg's stderr goes to a
    temporary file (``_ffmpeg_reason`` makes a failure one line) without pointing our fd 2 there
    while other threads write. And its exit status is read (``write_frames`` drops it). A Ctrl-C
    at the terminal reaches only nbst, which stops ffmpeg itself."""
    import subprocess
    import tempfile
    from fractions import Fraction

    import imageio_ffmpeg

    cmd = [imageio_ffmpeg.get_ffmpeg_exe(), "-y", "-f", "rawvideo", "-vcodec", "rawvideo",
           "-s", f"{int(size[0])}x{int(size[1])}", "-pix_fmt", pix_fmt_in,
           "-r", str(Fraction(fps).limit_denominator()), "-i", "-", "-an",
           "-vcodec", codec, "-pix_fmt", pix_fmt_out, "-v", "error", *output_params, str(path)]
    try:
        log = tempfile.TemporaryFile()
    except OSError:
        log = None
    try:
        proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.DEVNULL,
                                stderr=log if log is not None else None, process_group=0)
    except OSError as e:
        if log is not None:
            log.close()
        raise RenderError(f"{path}: cannot start ffmpeg ({e.strerror or e})") from None
    return proc, log


def _stop_ffmpeg(proc, *, kill: bool) -> None:
    """End ffmpeg: close its stdin and wait for it to finish the file, or (``kill``: the video is
    discarded) kill it. Always reaps it."""
    if kill:
        proc.kill()
    try:
        proc.stdin.close()
    except OSError:  # a broken pipe: ffmpeg has gone; its status tells
        pass
    try:
        proc.wait()
    except BaseException:  # (signals are held here; a KeyboardInterrupt from a library) do not leave it running
        proc.kill()
        proc.wait()
        raise


def _ffmpeg_reason(log) -> list[str]:
    """The most telling line of ffmpeg's log (a system error if any), without its '[muxer @ 0x..]' tag."""
    import re

    if log is None:
        return []
    try:
        log.seek(0)
        lines = [re.sub(r"^\[[^]]*\]\s*", "", ln).strip()
                 for ln in log.read(1 << 16).decode("utf-8", "replace").splitlines()]
    except OSError:
        return []
    lines = [ln for ln in lines if ln]
    for ln in lines:
        m = re.search(r"(No space left on device|Disk quota exceeded|Permission denied|Read-only file system|"
                      r"Input/output error|File too large)", ln)
        if m:
            return [m.group(1)]
    return lines[:1]


def encode(frames, writer: VideoWriter, *, progress=None) -> int:
    """Render-and-encode loop: ``frames`` is a callable ``f(k, out) -> frame``
    drawing frame k into the buffer ``out``, or an iterable of arrays.
    Returns the number of frames written. A stop signal ends it (KeyboardInterrupt) even when its
    exception was dropped in a finalizer (``nbst.outputs.stop_requested``)."""
    n = 0
    if callable(frames):
        k = 0
        while True:
            if stop_requested():
                raise KeyboardInterrupt
            buf = writer.acquire()
            fr = frames(k, buf)
            if fr is None:
                writer.unused(buf)
                break
            writer.submit(buf)
            k += 1
            n += 1
            if progress is not None:
                progress.update(1)
    else:
        for fr in frames:
            if stop_requested():
                raise KeyboardInterrupt
            writer.submit(fr)
            n += 1
            if progress is not None:
                progress.update(1)
    return n


def render_video(renderer, times, path, *, fps, progress=None) -> int:
    """Render the frame at each of ``times`` and encode to ``path`` (.mp4 or .gif).
    For MP4 frames go to the encoder as RGBA (``renderer.render_rgba``), for GIF
    as RGB (``renderer.render``: no alpha for the palette to reserve a slot for).

    Args:
        renderer: a frame renderer (``render(t)`` -> (H, W, 3) uint8, and ``size``), e.g. a
            ``nbst.render.scene2d`` scene.
        times: the frames' times, seconds of the motion (``frame_times`` gives them).
        path: the .mp4 or .gif to write, through the one atomic writer.
        fps: frames per second of the video.
        progress: None, or an object whose ``update(1)`` is called after each frame (a bar).

    Returns:
        The number of frames written.

    Raises:
        RenderError: an extension other than .mp4 or .gif, an odd size for MP4, or the encoder failed
            (one line; no partial file is left and a previous file stays).
    """
    times = np.asarray(times, float)
    rgba = video_kind(path) == "mp4" and hasattr(renderer, "render_rgba")
    render = renderer.render_rgba if rgba else renderer.render

    def draw(k, out):
        if k >= len(times):
            return None
        return render(times[k], out=out)

    with VideoWriter(path, renderer.size, fps, rgba=rgba) as w:
        n = encode(draw, w, progress=progress)
    return n


def render_output(make_renderer, output, *, still=None, times=None, fps=None, progress=None) -> int:
    """Make a headless GL context and on it a frame renderer, write ``output``, release both.

    Args:
        make_renderer: ``make_renderer(ctx)`` -> a frame renderer (``render(t)``, ``size``,
            ``release()``) on the context.
        output: the .png (with ``still``), .mp4 or .gif to write.
        still: None for a video; seconds: the one frame of a PNG.
        times: ``times(renderer, fps)`` -> the frames' times, seconds of the motion.
        fps: frames per second (default ``style.DEFAULT_FPS``).
        progress: None, or an object whose ``update(1)`` is called after each frame.

    Returns:
        The number of frames written (1 for a still).
    """

    ctx = create_context()
    try:
        renderer = make_renderer(ctx)
        try:
            if still is not None:
                write_png(output, renderer.render(float(still)))
                return 1
            fps = float(fps or style.DEFAULT_FPS)
            return render_video(renderer, times(renderer, fps), output, fps=fps, progress=progress)
        finally:
            renderer.release()
    finally:
        ctx.release()


def write_png(path, frame: np.ndarray) -> None:
    """Write one frame as a PNG, whole or not at all (the previous file stays on an error).

    Args:
        path: the .png to write.
        frame: (H, W, 3) uint8 array, RGB.

    Raises:
        OutputError: the file cannot be written (a full disk, a folder in the way).
    """
    from PIL import Image


    with atomic_path(path) as tmp:  # whole PNG or the previous file, never a truncated one
        Image.fromarray(np.ascontiguousarray(frame)).save(tmp, format="PNG")
