"""Golf-ball tracking in tee-shot broadcast video with a particle filter (seed 000)."""

from trackreplay.trackers.golf.config import GolfConfig
from trackreplay.trackers.golf.intermediates import GolfIntermediates
from trackreplay.trackers.golf.lut import build_luts
from trackreplay.trackers.golf.tracker import GolfTracker

__all__ = ["GolfConfig", "GolfIntermediates", "GolfTracker", "build_luts"]
