"""Golf-ball tracking in tee-shot broadcast video with a particle filter (seed 000)."""

from trackers.golf.config import GolfConfig
from trackers.golf.lut import build_luts
from trackers.golf.tracker import GolfIntermediates, GolfTracker

__all__ = ["GolfConfig", "GolfIntermediates", "GolfTracker", "build_luts"]
