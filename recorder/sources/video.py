"""Frames of a video file, timed by frame index and frame rate (or a timestamps file).

Frame i is at ``t0 + i / fps``: a variable-frame-rate video (gaps, dropped frames) is timed at its
average rate, not at its container's per-frame times; give those with ``--timestamps`` (a review
found the gap of a VFR clip gone; OpenCV cannot write such a video for a test, so it is not detected).
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import cv2

from trackreplay.recorder.sources.base import FrameClock, ImageFrame, require_file
from trackreplay.schemas.errors import SourceError


def open_video(path: str | Path) -> cv2.VideoCapture:
    path = require_file(path, "video")
    cap = cv2.VideoCapture(str(path))
    if not cap.isOpened():
        raise SourceError(f"OpenCV cannot open video {path} (unsupported container or codec)")
    return cap


def video_fps(path: str | Path) -> float:
    """The frame rate the file declares (0.0 when it declares none)."""
    cap = open_video(path)
    try:
        fps = float(cap.get(cv2.CAP_PROP_FPS) or 0.0)
    finally:
        cap.release()
    return fps if fps > 0 else 0.0


def video_clock(path: str | Path, fps: float | None = None, t0_ns: int = 0) -> FrameClock:
    """Times from ``fps`` when given, else from the file's own frame rate."""
    rate = fps if fps is not None else video_fps(path)
    if not rate > 0:
        raise SourceError(f"video {path} declares no frame rate; pass --fps")
    return FrameClock(fps=rate, t0_ns=t0_ns)


def frame_count_hint(path: str | Path) -> int | None:
    """What the container claims (for progress bars only: it may be approximate)."""
    cap = open_video(path)
    try:
        n = int(cap.get(cv2.CAP_PROP_FRAME_COUNT) or 0)
    finally:
        cap.release()
    return n if n > 0 else None


def read_video(path: str | Path, clock: FrameClock) -> Iterator[ImageFrame]:
    """Decoded BGR frames, one at a time."""
    path = Path(path)
    cap = open_video(path)
    try:
        index = 0
        while True:
            ok, image = cap.read()
            if not ok:
                break
            yield ImageFrame(index, clock.t_ns(index), f"{path} frame {index}", image)
            index += 1
    finally:
        cap.release()
    if index == 0:
        raise SourceError(f"video {path} has no readable frames")
    if clock.timestamps is not None and index != len(clock.timestamps):
        raise SourceError(f"{clock.timestamps_path} has {len(clock.timestamps)} timestamps but video {path} has {index} frames")
