"""Drawing shared by all tracker views (the pieces themselves live in ``views.parts``)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from trackreplay.replay.views.rerun_sink import FrameLogger
from trackreplay.replay.views import parts
from trackreplay.replay.views.parts import STATUS_COLOURS, to_uint8  # noqa: F401  (used by views)
from trackreplay.trackers.base import TrackState


def log_estimates(rec: FrameLogger, path: str, states: Sequence[TrackState]) -> None:
    """Boxes (centre/size) at one path, coloured by status, labelled with the track id.

    New views draw tracks with ``parts.tracks`` (one entity per track under ``tracks/``).
    """
    boxed = [s for s in states if s.x is not None and s.y is not None]
    parts.boxes(rec, path, np.array([[s.x, s.y] for s in boxed]), np.array([[s.w or 2.0, s.h or 2.0] for s in boxed]),
                colors=[STATUS_COLOURS[s.status] for s in boxed], labels=[f"{s.track_id} {s.status}" for s in boxed])


def log_scalar(rec: FrameLogger, path: str, value: float) -> None:
    """A time-series point; NaN (no value this frame) is skipped rather than drawn."""
    parts.scalar(rec, path, value)
