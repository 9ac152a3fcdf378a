"""Colour particle filter robust to background, illumination and size changes (seed 002)."""

from operator import attrgetter

from trackreplay.trackers.base import TrackerSpec
from trackreplay.trackers.colorpf.config import ColorPfConfig
from trackreplay.trackers.colorpf.tracker import ColorPfTracker
from trackreplay.trackers.smoothing import ImageSmoothing

SPEC = TrackerSpec(
    "colorpf", ColorPfConfig, ColorPfTracker, "trackreplay.replay.views.colorpf",
    needs="mark", notice=attrgetter("notice"),
    smoothing=ImageSmoothing("colorpf: image constant velocity (seed 002 transition)"),
)

__all__ = ["SPEC", "ColorPfConfig", "ColorPfTracker"]
