"""Drawing shared by all tracker views."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import rerun as rr

from trackreplay.trackers.base import TrackState

from trackreplay.replay.rerun_sink import FrameLogger

STATUS_COLOURS = {"measured": (0, 220, 0), "predicted": (255, 170, 0), "interpolated": (0, 160, 255), "lost": (255, 0, 0)}


def log_estimates(rec: FrameLogger, path: str, states: Sequence[TrackState]) -> None:
    """Boxes (centre/size) coloured by status, labelled with the track id."""
    boxed = [s for s in states if s.x is not None and s.y is not None]
    if not boxed:
        rec.log(path, rr.Clear(recursive=False))
        return
    centres = np.array([[s.x, s.y] for s in boxed])
    sizes = np.array([[s.w or 2.0, s.h or 2.0] for s in boxed])
    rec.log(
        path,
        rr.Boxes2D(
            centers=centres,
            sizes=sizes,
            colors=[STATUS_COLOURS[s.status] for s in boxed],
            labels=[f"{s.track_id} {s.status}" for s in boxed],
        ),
    )


def log_scalar(rec: FrameLogger, path: str, value: float) -> None:
    """A time-series point; NaN (no value this frame) is skipped rather than drawn."""
    if np.isfinite(value):
        rec.scalar(path, float(value))


def to_uint8(values: np.ndarray, lo: float, hi: float) -> np.ndarray:
    scaled = (np.nan_to_num(values, nan=lo) - lo) / (hi - lo)
    return np.round(np.clip(scaled, 0.0, 1.0) * 255.0).astype(np.uint8)
