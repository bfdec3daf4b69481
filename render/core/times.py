"""The frames' times, one rule for every video (the disks, both bowling videos, the crash): frame k
is shown at video time k / fps, and the simulation advances ``speed`` seconds per second of video,
``slow`` times slower inside slow-motion ``windows``; the last frame is the motion's end exactly,
then ``hold`` seconds of video hold it. Sim time is a piecewise-linear function of video time, so a
window of length L adds ``(slow - 1) x L x fps / speed`` frames.

Compute only (numpy).
"""
from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from nbst.errors import InputError, RenderError

__all__ = ["MAX_FRAMES", "check_frames", "frame_count", "frame_times"]

#: Most frames one video may have unless the caller says otherwise (``max_frames``): 30 minutes at
#: 60 fps, hours of rendering and gigabytes of MP4. A t_final of 1e6 s at 60 fps would be
#: 60 million frames (days of rendering, a 480 MB time array before the first frame).
MAX_FRAMES = 108_000


def _check(fps: float, speed: float, hold: float) -> None:
    if not (fps > 0 and speed > 0 and hold >= 0):
        raise InputError(f"fps and speed must be > 0 and hold >= 0, got fps {fps:g}, speed {speed:g}, "
                         f"hold {hold:g}")


def frame_count(t_final: float, fps: float, *, speed: float = 1.0, hold: float = 0.0) -> int:
    """How many frames :func:`frame_times` returns without slow-motion windows, computed without
    building them (may be huge: capped at 2**62).

    Raises:
        InputError: fps or speed not > 0, or hold < 0.
    """
    _check(fps, speed, hold)
    x = t_final / (speed / fps) + 1e-9
    if not math.isfinite(x) or x > 2**62:
        return 2**62
    n = int(math.floor(x)) + 1
    if (n - 1) * (speed / fps) < t_final - 1e-12:
        n += 1
    return n + int(round(hold * fps))


def check_frames(t_final: float, fps: float, *, speed: float = 1.0, hold: float = 0.0,
                 max_frames: int = MAX_FRAMES) -> int:
    """The frame count (:func:`frame_count`), checked against ``max_frames``.

    Raises:
        RenderError: over ``max_frames`` (one line: how many, and what makes fewer).
        InputError: fps or speed not > 0, or hold < 0.
    """
    n = frame_count(t_final, fps, speed=speed, hold=hold)
    if n > max_frames:
        raise RenderError(f"t_final = {t_final:g} s at {fps:g} fps and speed {speed:g} is {n:,} frames, over the "
                          f"limit of {max_frames:,} (max_frames); raise the limit, or shorten the video with a "
                          f"higher speed (simulated seconds per second of video) or a lower fps")
    return n


def frame_times(duration: float, fps: float, *, speed: float = 1.0, windows: Sequence[tuple[float, float]] = (),
                slow: float = 1.0, hold: float = 0.0) -> np.ndarray:
    """The simulation time of each frame of a video of a motion from 0 to ``duration`` seconds.

    Args:
        duration: seconds of motion; the last frame (before the hold) is at ``duration`` exactly.
        fps: frames per second of video.
        speed: simulated seconds per second of video outside the windows (0.5: half speed).
        windows: the (start, end) sim seconds of slow motion, sorted and not overlapping (the
            crash's ``slow_windows`` merges them).
        slow: how many times slower the motion runs inside ``windows`` (>= 1).
        hold: seconds of video holding the last frame.

    Returns:
        (nframes,) float64 array: k * speed / fps for k = 0, 1, ... without windows, else sim time
        as a piecewise-linear function of video time k / fps; then round(hold * fps) frames at
        ``duration``.

    Raises:
        InputError: fps or speed not > 0, slow < 1, duration or hold < 0.
    """
    _check(fps, speed, hold)
    if not (slow >= 1 and duration >= 0):
        raise InputError(f"slow must be >= 1 and duration >= 0, got slow {slow:g}, duration {duration:g}")
    extra = int(round(hold * fps))
    if not windows:  # a constant rate: frame k at k steps, the last one at duration
        step = speed / fps
        n = int(math.floor(duration / step + 1e-9)) + 1
        t = np.arange(n) * step
        if t[-1] < duration - 1e-12:
            t = np.append(t, duration)
        t[-1] = min(t[-1], duration)
        return np.concatenate((t, np.full(extra, duration))) if extra else t
    s_knots, v_knots = [0.0], [0.0]  # sim time at the knots of video time
    for a, b in windows:
        for s, rate in ((a, 1.0 / speed), (b, slow / speed)):
            v_knots.append(v_knots[-1] + (s - s_knots[-1]) * rate)
            s_knots.append(s)
    v_knots.append(v_knots[-1] + duration / speed - s_knots[-1] / speed)
    s_knots.append(duration)
    k = np.arange(int(math.floor(v_knots[-1] * fps + 1e-9)) + 1)
    t = np.interp(k / fps, v_knots, s_knots)
    if t[-1] < duration - 1e-12:
        t = np.append(t, duration)
    t[-1] = duration
    return np.concatenate((t, np.full(extra, duration)))
