"""The flow tracker's raw measurement per step, for the offline smoother: the centroid of the
moving set S carried to the frame and the mean flow over S (eq. 11), before its Kalman filter."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from trackreplay.trackers.base import TrackState
from trackreplay.trackers.flow.tracker import FlowIntermediates


def raw_observations(intermediates: FlowIntermediates, states: Sequence[TrackState], rig: Any = None,
                     config: Any = None) -> list[dict]:
    """One row for the tracked target (``zx, zy`` px; ``zvx, zvy`` px/frame) when either is finite."""
    c, v = intermediates.centroid, intermediates.raw_velocity
    if c is None or v is None or not states:
        return []
    if not (np.isfinite(c).all() or np.isfinite(v).all()):
        return []
    return [{"track_id": int(states[0].track_id), "zx": float(c[0]), "zy": float(c[1]),
             "zvx": float(v[0]), "zvy": float(v[1])}]
