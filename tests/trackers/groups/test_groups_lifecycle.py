"""The groups' life (trackers.lifecycle): "predicted" while no points update a group, deleted on the
(tracks.max_empty_frames + 1)-th such frame; a merged group is as recently updated as its freshest part."""

from __future__ import annotations

import numpy as np
import pytest

from trackreplay.trackers.geometry.stereo import StereoRig
from trackreplay.trackers.groups.config import GroupsConfig, TrackConfig
from trackreplay.trackers.groups.ekf import GroupEkf, state_from
from trackreplay.trackers.groups.features import ObservationPoints
from trackreplay.trackers.groups.tracker import Group, GroupTracker
from trackreplay.trackers.lifecycle import TrackLife

RIG = StereoRig(f=513.5, baseline=0.12, cx=319.5, cy=239.5)


def _group(tracker: GroupTracker, gid: int, xyz, members: int = 10) -> Group:
    ekf = GroupEkf(tracker.config.ekf, RIG, state_from(np.array(xyz, float), np.zeros(3)), np.eye(6) * 0.01)
    return Group(gid, ekf, np.eye(3) * 0.04, np.eye(3) * 1e-4, members, TrackLife(tracker.config.tracks.lifecycle))


@pytest.mark.parametrize("max_empty", [0, 2])
def test_a_group_without_points_is_predicted_then_deleted_on_the_frame_after_max_empty_frames(max_empty):
    tracker = GroupTracker(GroupsConfig(tracks=TrackConfig(max_empty_frames=max_empty)), np.random.default_rng(0))
    tracker.groups = [_group(tracker, 1, [0.0, 0.0, 5.0])]
    none = ObservationPoints.empty(tracker.config.klt.window)
    for frame in range(max_empty + 1):
        labels = tracker._associate_and_update(none, RIG)
        labels, ended, events = tracker._delete(labels)
        if frame < max_empty:
            assert ended == [] and tracker.groups[0].status == "predicted"
    assert ended == [1] and tracker.groups == []
    assert events == [f"group 1 deleted: no update for {max_empty + 1} frames"]


def test_a_merged_group_keeps_its_freshest_parts_misses():
    tracker = GroupTracker(GroupsConfig(), np.random.default_rng(0))
    a, b = _group(tracker, 1, [0.0, 0.0, 5.0], 30), _group(tracker, 2, [0.1, 0.0, 5.0], 5)
    a.life.missed(), a.life.missed(), a.life.missed(), b.life.missed()
    merged, absorbed = tracker._merged([a, b])
    assert absorbed and merged.gid == 1 and merged.life.misses == 1 and merged.merged_from == "1,2"


def test_the_lifecycle_follows_the_rescaled_deletion_count():
    assert TrackConfig(max_empty_frames=0).lifecycle.lost_after == 1
    assert GroupsConfig().at_rate(96.0).tracks.lifecycle.lost_after == 24 + 1
