"""People-group tracking with subtraction stereo (or one camera over a ground plane), KLT and a per-group EKF (seed 003)."""

from operator import attrgetter

from trackreplay.trackers.base import TrackerSpec
from trackreplay.trackers.groups.config import GroupsConfig
from trackreplay.trackers.groups.intermediates import GroupsIntermediates
from trackreplay.trackers.groups.observations import raw_observations
from trackreplay.trackers.groups.smoothing import smoothing_model
from trackreplay.trackers.groups.tracker import GroupTracker


def position_frame(tracker: GroupTracker) -> str:
    """"world" when the log carries the rig's pose or a ground plane (Z up), else "camera" (the left camera's frame)."""
    return tracker.position_frame


SPEC = TrackerSpec(
    "groups", GroupsConfig, GroupTracker, "trackreplay.replay.views.groups",
    needs="depth", position_frame=position_frame, observations=raw_observations,
    extra_rows=GroupsIntermediates.extra_rows, notice=attrgetter("notice"), smoothing=smoothing_model,
    multi_object=True,
)

__all__ = ["SPEC", "GroupTracker", "GroupsConfig", "GroupsIntermediates"]
