"""Gradient-flow moving-object tracker (seed 004, Chiba & Ozawa): one file per stage.

derivatives (Beaudet 5x5 operators) → local_flow (eq. 5–8) → refine (eq. 9–10, 25) →
velocity (eq. 11) → kalman (eq. 23–24) → fov (§4.2, eq. 26) → tracker.
"""

from trackreplay.trackers.flow.config import FlowConfig
from trackreplay.trackers.flow.tracker import FlowIntermediates, FlowTracker

__all__ = ["FlowConfig", "FlowIntermediates", "FlowTracker"]
