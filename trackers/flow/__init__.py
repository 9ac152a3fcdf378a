"""Gradient-flow moving-object tracker (seed 004, Chiba & Ozawa): one file per stage.

derivatives (Beaudet 5x5 operators) → local_flow (eq. 5–8) → refine (eq. 9–10, 25) →
velocity (eq. 11) → kalman (eq. 23–24) → fov (§4.2, eq. 26) → tracker.
"""

from trackreplay.trackers.base import TrackerSpec
from trackreplay.trackers.flow.config import FlowConfig
from trackreplay.trackers.flow.observations import raw_observations
from trackreplay.trackers.flow.tracker import FlowIntermediates, FlowTracker
from trackreplay.trackers.smoothing import ImageSmoothing

SPEC = TrackerSpec(
    "flow", FlowConfig, FlowTracker, "trackreplay.replay.views.flow",
    mark_labels=FlowTracker.mark_labels, observations=raw_observations,
    # its image position follows seed 004 §4.3 (the third state, a Gauss–Markov acceleration, is the
    # white acceleration here); its velocity is its primary measurement (mean flow), observed too
    smoothing=ImageSmoothing("flow: image constant velocity; raw centroid (eq. 11) and the tracker's velocity "
                             "observed (seed 004 §4.3)", observe_velocity=True),
)

__all__ = ["SPEC", "FlowConfig", "FlowIntermediates", "FlowTracker"]
