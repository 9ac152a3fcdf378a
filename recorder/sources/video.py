"""Frames of a video file, timed by frame index and frame rate (or a timestamps file).

Frame i is at ``t0 + i / fps``: a variable-frame-rate video (gaps, dropped frames) is timed at its
average rate, not at its container's per-frame times; give those with ``--timestamps`` (a review
found the gap of a VFR clip gone; OpenCV cannot write such a video for a test, so it is not detected).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import cv2

from trackreplay.recorder.sources.base import FrameClock, ImageFrame, require_file
from trackreplay.schemas.errors import SourceError


def open_video(path: str | Path) -> cv2.VideoCapture:
    path = require_file(path, "video")
    cap = cv2.VideoCapture(str(path))
    if not cap.isOpened():
        raise SourceError(f"OpenCV cannot open video {path} (truncated or damaged, or an unsupported container or codec)")
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


MAX_FAILED_READS = 30  # failed reads in a row before the video is taken as ended (OpenCV reads on past a bad frame)


@dataclass
class VideoLosses:
    """What reading a video could not decode: ``lost`` index ranges (first, last) inside it, and the
    frames it declares (``declared``, approximate: an intact MP4 may claim a few more) against those read."""

    path: str
    declared: int = 0
    read: int = 0
    last_index: int = -1
    lost: list[tuple[int, int]] = field(default_factory=list)

    def warnings(self) -> tuple[str, ...]:
        out = []
        if self.lost:
            ranges = ", ".join(str(a) if a == b else f"{a}-{b}" for a, b in self.lost[:10]) + (" ..." if len(self.lost) > 10 else "")
            n = sum(b - a + 1 for a, b in self.lost)
            out.append(f"video {self.path}: {n} frame(s) could not be decoded (damaged) and are missing from the log: "
                       f"frames {ranges}; the frames after them keep their own times")
        tail = self.declared - (self.last_index + 1)
        # the declared count is estimated from the duration in some containers (an intact variable-rate
        # .mkv declared 93 of its 90 frames): only a clear shortfall is damage
        if tail > max(5, 0.05 * self.declared):
            out.append(f"video {self.path}: decoding stopped after frame {self.last_index} of the {self.declared} the file "
                       "declares (truncated or damaged): the log holds what could be read")
        return tuple(out)


def read_video(path: str | Path, clock: FrameClock, losses: VideoLosses | None = None) -> Iterator[ImageFrame]:
    """Decoded BGR frames, one at a time, each at its own index: a frame that does not decode is
    skipped and the reading goes on (``losses``, when given, says which; after failed reads the next
    frame's index comes from its presentation time, ``CAP_PROP_POS_MSEC``, so a gap keeps the later
    frames' times; a frame that decodes after none failed is the next one, as before)."""
    path = Path(path)
    cap = open_video(path)
    losses = losses if losses is not None else VideoLosses(str(path))
    losses.declared = int(cap.get(cv2.CAP_PROP_FRAME_COUNT) or 0)
    rate = float(cap.get(cv2.CAP_PROP_FPS) or 0.0)
    expected = 0  # the next frame's index when nothing is lost
    try:
        failed, damaged = 0, False
        while failed <= MAX_FAILED_READS:
            ok, image = cap.read()
            if not ok:
                failed += 1
                continue
            index = expected
            damaged = damaged or failed > 0
            # Only once a read has failed: a variable-rate video's late frame is no lost frame (a review's
            # intact 30 fps clip with a 200 ms pause was reported damaged), and with --timestamps every
            # decoded frame is the next line. Once damaged, the decoder may also skip a frame silently
            # (no failed read): the presentation time tells.
            if damaged and clock.timestamps is None:
                msec = float(cap.get(cv2.CAP_PROP_POS_MSEC) or 0.0)
                by_time = int(round(msec * rate / 1000.0)) if rate > 0 and msec > 0 else expected + failed
                if by_time > expected:  # the frames between did not decode
                    losses.lost.append((expected, by_time - 1))
                    index = by_time
            failed = 0
            yield ImageFrame(index, clock.t_ns(index), f"{path} frame {index}", image)
            losses.read += 1
            losses.last_index = index
            expected = index + 1
    finally:
        cap.release()
    if losses.read == 0:
        raise SourceError(f"video {path} has no readable frames")
    if clock.timestamps is not None and expected != len(clock.timestamps):
        raise SourceError(f"{clock.timestamps_path} has {len(clock.timestamps)} timestamps but video {path} has {expected} frames")
