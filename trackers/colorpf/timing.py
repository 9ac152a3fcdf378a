"""The log's frame interval against the rate the per-frame constants are stated at (``ColorPfConfig.frame_rate``).

Some constants of the tracker describe time, not frames: the position noise of eq. (2) is a random
walk's spread per frame, the hold's velocity smoothing a memory of so many frames, its horizon and the
early median's window so many frames. They were set on 30 fps logs (otb_crossing, the synthetic
scenes). On a log at another rate (frames dropped, a 15 fps camera) the same numbers mean other
physical quantities: at 15 fps the early median spans 2 s instead of 1 s, and the walker moves twice as
far between frames while the particles spread as far as at 30 fps. :class:`FrameClock` measures each
step's interval from ``frame.t_ns``; the helpers convert a constant to that interval:

- a random walk's standard deviation grows with the square root of time: ``sigma * sqrt(r)``;
- an exponential smoothing factor per frame keeps its time constant: ``s ** r``;
- a number of frames keeps its duration: ``round(n / r)`` (at least 1);

``r`` the step's interval over the stated one. Within ``TOLERANCE`` of 1, ``r`` is exactly 1: whole-
millisecond timestamps (33 / 34 ms at 30 fps) and NTSC's 29.97 fps are the stated rate, and such logs
replay bit for bit as before. Without timing (a first frame, equal or decreasing timestamps, or
``frame_rate = None``) ``r`` is 1: per frame, as before.
"""

from __future__ import annotations

import math
from collections import deque

import numpy as np

TOLERANCE = 0.05  # |r - 1| up to this: the stated rate (timestamp rounding, 29.97 vs 30 fps)


def interval_ratio(dt_ns: float | None, frame_rate: float | None) -> float:
    """``r = dt / (1 / frame_rate)`` for a step of ``dt_ns`` nanoseconds (1 without timing or within ``TOLERANCE``)."""
    if frame_rate is None or dt_ns is None or dt_ns <= 0:
        return 1.0
    r = float(dt_ns) * frame_rate / 1e9
    return 1.0 if abs(r - 1.0) <= TOLERANCE else r


def noise_for(sigma, r: float):
    """A random walk's per-frame standard deviation ``sigma`` over a step of ``r`` stated frames."""
    return sigma if r == 1.0 else sigma * math.sqrt(r)


def smoothing_for(s: float, r: float) -> float:
    """A per-frame smoothing factor ``s`` (``v <- s v + (1 - s) x``) over a step of ``r`` stated frames."""
    return s if r == 1.0 else s ** r


def frames_for(n: int, r: float) -> int:
    """``n`` stated frames as this log's frames (the same duration; at least 1; 0, "none", stays 0)."""
    return n if r == 1.0 or n <= 0 else max(1, int(round(n / r)))


RECENT_STEPS = 9  # the log's typical interval: the median of this many last steps


class FrameClock:
    """Each step's ``r`` from consecutive ``frame.t_ns`` (``ratio``: for what happens over that step, the
    noise and the smoothing), and the log's typical ``r`` (``typical``: the median interval of the last
    RECENT_STEPS steps, for durations: one dropped or late frame does not shorten a window)."""

    def __init__(self, frame_rate: float | None) -> None:
        self.frame_rate = frame_rate
        self._last: int | None = None
        self._recent: deque[int] = deque(maxlen=RECENT_STEPS)
        self.ratio = 1.0  # the last step's
        self.typical = 1.0

    def step(self, t_ns: int) -> float:
        dt = None if self._last is None else t_ns - self._last
        self._last = t_ns
        self.ratio = interval_ratio(dt, self.frame_rate)
        if dt is not None and dt > 0:
            self._recent.append(dt)
            self.typical = interval_ratio(float(np.median(np.array(self._recent, dtype=np.float64))), self.frame_rate)
        return self.ratio
