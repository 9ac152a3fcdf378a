"""The group tracker end to end on synthetic stereo crowds: accuracy, no false merge, determinism."""

from __future__ import annotations

import numpy as np
import polars as pl
import pytest

from trackreplay.recorder.synth.groups.scene import GROUNDTRUTH_GROUPS, GroupSceneConfig, write_group_scene
from trackreplay.replay.engine import ReplayRequest, replay
from trackreplay.replay.group_table import replay_groups
from trackreplay.replay.groundtruth import read_groundtruth
from trackreplay.replay.mot import mot_metrics
from trackreplay.replay.reader import LogReader


@pytest.fixture(scope="module")
def passing(tmp_path_factory):
    path = tmp_path_factory.mktemp("groups") / "passing.mcap"
    # 48 fps from 1.0 s: the clip on which both earlier merge settings (accel_sigma 0.004, and the
    # points' velocity spread in the velocity gate) merged the two groups, at frames 69 and 90
    write_group_scene(path, GroupSceneConfig(scene="groups-passing", fps=48.0, start_s=1.0, duration=2.0, encoding="jpeg"))
    return path


def test_passing_groups_are_tracked_apart_in_3d_and_never_merge(passing):
    traj, table, events = replay_groups(ReplayRequest(log=passing, tracker="groups", seed=0))
    assert not [e for _, e in events if "merged into" in e or "absorbed" in e], events
    gt = read_groundtruth(LogReader(passing), GROUNDTRUTH_GROUPS)
    m3 = mot_metrics(traj, gt, space="3d", max_distance_m=1.0)
    assert m3.id_switches == 0
    assert m3.mota > 0.8, m3
    # 3-D position RMSE of the matched groups (camera frame)
    live = traj.filter(pl.col("status") != "lost")
    joined = live.join(gt.rename({"id": "gt"}), on="frame")
    d = np.linalg.norm(joined.select("X", "Y", "Z").to_numpy() - joined.select("X_right", "Y_right", "Z_right").to_numpy(), axis=1)
    best = joined.with_columns(pl.Series("d", d)).group_by("frame", "track_id").agg(pl.col("d").min())
    assert float(np.sqrt((best["d"].to_numpy() ** 2).mean())) < 0.6
    # the second table: one row per live group per frame, a covariance and members
    assert table.height == live.height
    assert (table["members"] >= 0).all() and (table["cov_xx"] > 0).all()


def test_two_replays_give_one_digest(passing):
    a = replay(ReplayRequest(log=passing, tracker="groups", seed=0, end_s=1.2))
    b = replay(ReplayRequest(log=passing, tracker="groups", seed=3, end_s=1.2))
    assert a.digest == b.digest  # nothing in the tracker is random: the seed cannot matter
    assert a.trajectory.equals(b.trajectory)


# The merging and crossing scenes at the paper's 48 fps (the defaults are per frame at 48 fps; at 24
# fps the merge comes ~1.4 s late, docs/groups.md), cut short around the event with start_s.

@pytest.fixture(scope="module")
def merging(tmp_path_factory):
    path = tmp_path_factory.mktemp("groups") / "merging.mcap"
    cfg = GroupSceneConfig(scene="groups-merging", fps=48.0, start_s=1.3, duration=1.5, encoding="jpeg")
    write_group_scene(path, cfg)
    return path, cfg


@pytest.fixture(scope="module")
def crossing(tmp_path_factory):
    path = tmp_path_factory.mktemp("groups") / "crossing.mcap"
    write_group_scene(path, GroupSceneConfig(scene="groups-crossing", fps=48.0, start_s=1.2, duration=1.8, encoding="jpeg"))
    return path  # the groups' centres pass X = 0.2 m at 2.125 s: frame 54 of 96


def test_merging_groups_merge_within_a_few_frames_of_the_truth(merging):
    path, cfg = merging
    traj, table, events = replay_groups(ReplayRequest(log=path, tracker="groups", seed=0))
    true_frame = cfg.lead_in + int(np.ceil((cfg.merge_s - cfg.start_s) * cfg.fps))  # first frame with t >= merge_s
    merges = [(f, e) for f, e in events if "merged into" in e or "absorbed by" in e]
    assert merges, events
    frame, event = merges[0]
    # the overlap must hold merge.frames (8) frames, so the earliest possible merge is 8 frames late
    assert true_frame - 2 <= frame <= true_frame + 24, (frame, true_frame, events)
    assert "1,2" in event  # the two groups that walked in, not a splinter
    # groups 1 and 2 end there; the merged group lives on near the merged truth (group 3) in 3-D (a
    # splinter of a few points may start a group of its own later: it is absorbed ~12 frames on in
    # the full scene), and the second table says where it came from
    merged = int(event.split("group ")[-1])
    gt = read_groundtruth(LogReader(path), GROUNDTRUTH_GROUPS)
    end = traj["frame"].max()
    live = traj.filter((pl.col("frame") == end) & (pl.col("status") != "lost"))
    assert not set(live["track_id"].to_list()) & {1, 2}
    truth = gt.filter(pl.col("frame") == end).select("X", "Y", "Z").to_numpy()
    ours = live.filter(pl.col("track_id") == merged).select("X", "Y", "Z").to_numpy()
    assert truth.shape == (1, 3) and ours.shape == (1, 3) and np.linalg.norm(ours - truth) < 0.8
    assert table.filter(pl.col("frame") == frame)["merged_from"].drop_nulls().to_list() == ["1,2"]


def test_crossing_groups_keep_their_identities(crossing):
    traj, _, events = replay_groups(ReplayRequest(log=crossing, tracker="groups", seed=0))
    assert not [e for _, e in events if "merged into" in e or "absorbed" in e], events  # approach, but move apart
    gt = read_groundtruth(LogReader(crossing), GROUNDTRUTH_GROUPS)
    for space in ("image", "3d"):
        m = mot_metrics(traj, gt, space=space, min_iou=0.3, max_distance_m=1.0)
        assert m.id_switches == 0, (space, m)
        assert m.idf1 > 0.8, (space, m)
    # the track nearest each true group before the crossing is the one nearest it after
    live = traj.filter(pl.col("status") != "lost")
    joined = live.join(gt.select("frame", pl.col("id").alias("gt"), pl.col("X").alias("gX"), pl.col("Y").alias("gY"),
                                 pl.col("Z").alias("gZ")), on="frame")
    joined = joined.with_columns(((pl.col("X") - pl.col("gX")) ** 2 + (pl.col("Y") - pl.col("gY")) ** 2
                                  + (pl.col("Z") - pl.col("gZ")) ** 2).sqrt().alias("d"))
    nearest = joined.sort("d").group_by("frame", "gt").first()
    owner = {}
    for gid in (1, 2):
        for name, part in (("before", nearest.filter(pl.col("frame") < 45)), ("after", nearest.filter(pl.col("frame") > 70))):
            ids = part.filter(pl.col("gt") == gid)["track_id"]
            assert ids.len() > 10
            owner[(gid, name)] = ids.mode().sort()[0]
        assert owner[(gid, "before")] == owner[(gid, "after")], owner
    assert owner[(1, "before")] != owner[(2, "before")]
