"""Golf-ball tracking in tee-shot broadcast video with a particle filter (seed 000)."""

from operator import attrgetter

from trackreplay.trackers.base import TrackerSpec
from trackreplay.trackers.golf.config import GolfConfig
from trackreplay.trackers.golf.intermediates import GolfIntermediates
from trackreplay.trackers.golf.lut import build_luts
from trackreplay.trackers.golf.tracker import GolfTracker
from trackreplay.trackers.smoothing import ImageSmoothing

SPEC = TrackerSpec(
    "golf", GolfConfig, GolfTracker, "trackreplay.replay.views.golf",
    needs="mark", one_start_per_frame=True, notice=attrgetter("notice"),
    # its image position follows a ball the operator keeps near the centre; its 3-D flight has its
    # own offline fit (`trackreplay flight`)
    smoothing=ImageSmoothing("golf: image constant velocity (3-D: trackreplay flight)"),
    ball_flight=True,
)

__all__ = ["SPEC", "GolfConfig", "GolfIntermediates", "GolfTracker", "build_luts"]
