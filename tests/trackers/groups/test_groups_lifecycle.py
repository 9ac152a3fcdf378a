"""The groups' life (trackers.lifecycle): "predicted" while no points update a group, deleted on the
(tracks.max_empty_frames + 1)-th such frame; a merged group is as recently updated as its freshest part."""

from __future__ import annotations

import numpy as np
import pytest

from trackreplay.trackers.geometry.rig_pose import RigPose
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


def _points(xyz: np.ndarray, rig: StereoRig = RIG) -> ObservationPoints:
    n = len(xyz)
    return ObservationPoints(np.arange(n), rig.to_uvd(xyz), xyz, np.zeros((n, 3)), np.zeros((n, 2, 2)))


def _one_frame(tracker: GroupTracker, points: ObservationPoints) -> tuple[np.ndarray, list[str]]:
    """The group's predict, association, deletion and group starts on ``points``: the labels and events."""
    tracker.groups[0].ekf.predict()
    labels = tracker._associate_and_update(points, RIG)
    labels, _, events = tracker._delete(labels)
    return tracker._start_groups(points, labels, RIG, events), events


@pytest.mark.parametrize("mode", ["join", "leave", "start"])
def test_a_splinter_beside_a_confirmed_group_joins_it_is_left_or_starts_one(mode):
    """12 points on an arc 1.25 m around a group (each outside its eq. 8 gate, 1.09 m, but the set's
    region overlaps it: legs or a side the gate does not reach) join the group, are left unassigned or
    start a group of their own (the paper), per grouping.near_gate; 12 points 4 m away start a group in
    every mode, and so does the arc beside a group not yet confirmed."""
    from dataclasses import replace

    cfg = GroupsConfig()
    cfg = replace(cfg, grouping=replace(cfg.grouping, near_gate=mode))
    tracker = GroupTracker(cfg, np.random.default_rng(0))
    g = _group(tracker, 1, [0.0, 0.0, 5.0], 12)
    g.hits = cfg.merge.frames
    tracker.groups = [g]
    rng = np.random.default_rng(1)
    body = np.array([0.0, 0.0, 5.0]) + rng.normal(0.0, 0.1, (12, 3))
    angle = np.linspace(-np.pi / 3, np.pi / 3, 12)
    beside = np.array([0.0, 0.0, 5.0]) + 1.25 * np.stack([np.cos(angle), np.zeros(12), np.sin(angle)], axis=1)
    far = np.array([4.0, 0.0, 5.0]) + rng.normal(0.0, 0.1, (12, 3))
    points = _points(np.concatenate([body, beside, far]))
    tracker.groups[0].ekf.predict()
    labels = tracker._associate_and_update(points, RIG)
    assert (labels[:12] == 0).all(), "the group's own points are in its gate"
    labels, _, events = tracker._delete(labels)
    labels = tracker._start_groups(points, labels, RIG, events)
    started = [e for e in events if "started" in e]
    if mode == "join":
        assert (labels[12:24] == 0).all() and tracker.groups[0].members == 24 and len(started) == 1
    elif mode == "leave":
        assert (labels[12:24] == -1).all() and tracker.groups[0].members == 12 and len(started) == 1
    else:
        assert len(set(labels[12:24].tolist())) == 1 and labels[12] >= 1 and len(started) == 2
    assert len(set(labels[24:].tolist())) == 1 and labels[24] >= 1, "a set far from every gate starts a group"

    young = GroupTracker(cfg, np.random.default_rng(0))
    young.groups = [_group(young, 1, [0.0, 0.0, 5.0], 12)]  # hits 0: not confirmed
    young.groups[0].ekf.predict()
    labels = young._associate_and_update(points, RIG)
    labels, _, events = young._delete(labels)
    young._start_groups(points, labels, RIG, events)
    assert sum("started" in e for e in events) == 2


@pytest.mark.parametrize("inside_box", [True, False])
def test_a_set_seen_through_a_confirmed_group_s_box_at_another_depth_waits(inside_box):
    """12 points 3 m behind a group (far outside its gate) whose image centre lies in the group's
    image box start no group with grouping.inside_box (a part of the group at a wrong disparity, or
    someone it hides), and start one without it."""
    from dataclasses import replace

    cfg = GroupsConfig()
    cfg = replace(cfg, grouping=replace(cfg.grouping, inside_box=inside_box))
    tracker = GroupTracker(cfg, np.random.default_rng(0))
    tracker.source = "stereo"  # the box test is the stereo source's (one camera: each column's own foot)
    g = _group(tracker, 1, [0.0, 0.0, 5.0], 12)
    g.hits = cfg.merge.frames
    centre = RIG.to_uvd(np.array([[0.0, 0.0, 5.0]]))[0]
    g.box = np.array([centre[0] - 40.0, centre[1] - 80.0, centre[0] + 40.0, centre[1] + 80.0])
    tracker.groups = [g]
    rng = np.random.default_rng(1)
    body = np.array([0.0, 0.0, 5.0]) + rng.normal(0.0, 0.1, (12, 3))
    behind = np.array([0.0, -0.3, 8.0]) + rng.normal(0.0, 0.1, (12, 3))
    points = _points(np.concatenate([body, behind]))
    labels, events = _one_frame(tracker, points)
    assert (labels[:12] == 0).all()
    if inside_box:
        assert (labels[12:] == -1).all() and not any("started" in e for e in events)
    else:
        assert (labels[12:] == 1).all() and sum("started" in e for e in events) == 1


# the camera looking level along the world's Y: camera x -> world X, camera y (down) -> world -Z, z -> Y
LEVEL = ((1.0, 0.0, 0.0), (0.0, 0.0, 1.0), (0.0, -1.0, 0.0))


@pytest.mark.parametrize("near_gate_ground", [True, False])
def test_legs_under_a_confirmed_group_join_it_on_the_ground(near_gate_ground):
    """With a stereo rig's pose, 12 points 1.5 m under a group's points (its legs: out of the 3-D gate
    of a group tracked on its torsos, at its ground position) join it with grouping.near_gate_ground and
    start a group of their own without; 12 points 1.5 m beside it, at its height, start a group either way."""
    from dataclasses import replace

    from trackreplay.trackers.geometry.rig_pose import RigPose

    cfg = GroupsConfig()
    cfg = replace(cfg, grouping=replace(cfg.grouping, near_gate_ground=near_gate_ground, inside_box=False))
    rng = np.random.default_rng(1)
    body = np.array([0.0, 0.0, 5.0]) + rng.normal(0.0, 0.05, (12, 3))
    for offset, joins in ((np.array([0.0, 1.5, 0.0]), near_gate_ground), (np.array([1.5, 0.0, 0.0]), False)):
        tracker = GroupTracker(cfg, np.random.default_rng(0))
        tracker.source = "stereo"
        tracker.pose = RigPose(tuple(float(v) for v in np.ravel(LEVEL)), (0.0, 0.0, 1.5))
        g = _group(tracker, 1, [0.0, 0.0, 5.0], 12)
        g.hits = cfg.merge.frames
        tracker.groups = [g]
        other = np.array([0.0, 0.0, 5.0]) + offset + rng.normal(0.0, 0.02, (12, 3))
        points = _points(np.concatenate([body, other]))
        tracker.groups[0].ekf.predict()
        labels = tracker._associate_and_update(points, RIG)
        assert (labels[:12] == 0).all() and (labels[12:] == (0 if joins else -1)).all(), offset
        labels, _, events = tracker._delete(labels)
        labels = tracker._start_groups(points, labels, RIG, events)
        assert sum("started" in e for e in events) == (0 if joins else 1), offset


@pytest.mark.parametrize("box_overlap", [True, False])
def test_a_set_at_another_depth_overlapping_a_confirmed_group_s_box_waits(box_overlap):
    """12 points 3 m behind a group whose image centre lies just above the group's image box but whose
    own image box overlaps it (heads matched at half their disparity, on the box's top edge) start no
    group with grouping.box_overlap, and start one with the centre test alone."""
    from dataclasses import replace

    cfg = GroupsConfig()
    cfg = replace(cfg, grouping=replace(cfg.grouping, box_overlap=box_overlap))
    tracker = GroupTracker(cfg, np.random.default_rng(0))
    tracker.source = "stereo"
    g = _group(tracker, 1, [0.0, 0.0, 5.0], 12)
    g.hits = cfg.merge.frames
    rng = np.random.default_rng(1)
    behind = np.array([0.0, -0.3, 8.0]) + rng.normal(0.0, 0.1, (12, 3))
    uv = RIG.to_uvd(behind)[:, :2]
    centre = RIG.to_uvd(np.array([[0.0, 0.0, 5.0]]))[0]
    top = float(uv[:, 1].mean()) + 2.0  # the set's centre 2 rows above the box; its lowest points inside it
    assert uv[:, 1].max() > top
    g.box = np.array([centre[0] - 40.0, top, centre[0] + 40.0, centre[1] + 80.0])
    tracker.groups = [g]
    body = np.array([0.0, 0.0, 5.0]) + rng.normal(0.0, 0.1, (12, 3))
    points = _points(np.concatenate([body, behind]))
    labels, events = _one_frame(tracker, points)
    assert (labels[:12] == 0).all()
    if box_overlap:
        assert (labels[12:] == -1).all() and not any("started" in e for e in events)
    else:
        assert (labels[12:] == 1).all() and sum("started" in e for e in events) == 1


# one camera over a ground plane: the camera looks along the ground's Y (camera x -> X, z -> Y, y -> -Z)
ALONG_Y = RigPose((1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, -1.0, 0.0), (0.0, 0.0, 0.0))


@pytest.mark.parametrize("source", ["ground", "stereo"])
def test_a_passer_by_in_a_wide_gate_is_not_the_group_s(source):
    """A group whose extent grew wide (σ 1 m: its gate reaches 4 m) gates 12 points of its own and 8 of a
    passer-by 2.5 m away, not within the grouping radius of any of them. With one camera
    (``grouping.connected = "ground"``) the group keeps the connected set with the most points and the
    passer-by's points start a group of their own; with stereo (as the paper) the group takes all 20."""
    tracker = GroupTracker(GroupsConfig(), np.random.default_rng(0))
    tracker.source, tracker.pose = source, ALONG_Y
    g = _group(tracker, 1, [0.0, 0.0, 5.0], 12)
    g.extent = np.eye(3) * 1.0
    tracker.groups = [g]
    rng = np.random.default_rng(2)
    own = np.array([0.0, 0.0, 5.0]) + rng.normal(0.0, 0.1, (12, 3))
    other = np.array([2.5, 0.0, 5.0]) + rng.normal(0.0, 0.1, (8, 3))
    labels, events = _one_frame(tracker, _points(np.concatenate([own, other])))
    assert (labels[:12] == 0).all()
    if source == "ground":
        assert tracker.groups[0].members == 12 and (labels[12:] == 1).all()
        assert [e.split(" ", 2)[2] for e in events] == ["started with 8 points"]
    else:
        assert tracker.groups[0].members == 20 and (labels[12:] == 0).all() and events == []


def _ground_sigma(g: Group) -> float:
    P = ALONG_Y.rotate_cov(g.ekf.P[np.ix_([0, 2, 4], [0, 2, 4])][None])[0][:2, :2]
    return float(np.sqrt(np.linalg.eigvalsh(P)[-1]))


@pytest.mark.parametrize("source", ["ground", "stereo"])
def test_with_one_camera_a_group_coasts_while_the_ekf_places_it_within_the_coasting_sigma(source):
    """Without points, a group is deleted after ``tracks.max_empty_frames`` with stereo; with one camera it
    coasts while its predicted position's standard deviation on the ground is within
    ``tracks.ground_coast_sigma_m`` (0.5 m) and is deleted on the first frame it is not."""
    tracker = GroupTracker(GroupsConfig(), np.random.default_rng(0))
    tracker.source, tracker.pose = source, ALONG_Y
    g = _group(tracker, 1, [0.0, 0.0, 5.0])
    g.ekf.set(g.ekf.x, np.diag([0.01, 1e-4, 0.01, 1e-4, 0.01, 1e-4]))  # σ 0.1 m, 0.01 m/frame
    tracker.groups = [g]
    none = ObservationPoints.empty(tracker.config.klt.window)
    sigmas = []
    for frame in range(1, 200):
        g.ekf.predict()
        sigmas.append(_ground_sigma(g))
        labels = tracker._associate_and_update(none, RIG)
        _, ended, events = tracker._delete(labels)
        if ended:
            break
    assert ended == [1] and events == [f"group 1 deleted: no update for {frame} frames"]
    if source == "stereo":
        assert frame == tracker.config.tracks.max_empty_frames + 1
    else:
        assert frame > tracker.config.tracks.max_empty_frames + 1
        assert sigmas[-1] > 0.5 >= sigmas[-2]
