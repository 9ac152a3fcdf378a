"""The group tracker end to end on synthetic stereo crowds: accuracy, no false merge, determinism."""

from __future__ import annotations

import numpy as np
import polars as pl
import pytest

from trackreplay.recorder.synth.groups.scene import GROUNDTRUTH_GROUPS, GroupSceneConfig, write_group_scene
from trackreplay.replay.core.engine import ReplayRequest, replay
from trackreplay.replay.core.group_table import replay_groups
from trackreplay.replay.log.groundtruth import read_groundtruth
from trackreplay.replay.analysis.mot import mot_metrics
from trackreplay.replay.log.reader import LogReader

pytestmark = pytest.mark.slow  # minutes of synthetic scenes: run by `pytest -m slow` (CI runs both)


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


# The merging and crossing scenes at the paper's 48 fps (the defaults are per frame at 48 fps and
# rescaled to the log's rate: 24 fps below), cut short around the event with start_s.

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


def test_positions_are_world_z_up_with_the_rig_pose_and_camera_frame_without(passing, tmp_path):
    from trackreplay.recorder.filter import filter_log
    from trackreplay.recorder.synth.groups.people import TORSO_Z
    from trackreplay.replay.log.frames import read_rig_pose

    reader = LogReader(passing)
    pose = read_rig_pose(reader)
    assert pose is not None  # the synthetic scenes write /stereo/pose
    no_pose = tmp_path / "no_pose.mcap"
    filter_log(passing, no_pose, topics=[t for t in sorted(reader.topics()) if t != "/stereo/pose"])
    world = replay(ReplayRequest(log=passing, tracker="groups", seed=0, end_s=1.5))
    camera = replay(ReplayRequest(log=no_pose, tracker="groups", seed=0, end_s=1.5))
    assert world.summary(passing)["position_frame"] == "world" and camera.summary(no_pose)["position_frame"] == "camera"
    w = world.trajectory.filter(pl.col("status") == "measured")
    c = camera.trajectory.filter(pl.col("status") == "measured")
    assert w.height > 20 and w.select("track_id", "frame").equals(c.select("track_id", "frame"))
    # the same tracks, rotated and shifted by the pose; the EKF itself runs in the camera frame
    assert np.allclose(pose.to_world(c.select("X", "Y", "Z").to_numpy()), w.select("X", "Y", "Z").to_numpy(), atol=1e-9)
    # Z up: the groups' centres (their members' torsos) are about a torso's height above the ground
    assert abs(float(w["Z"].median()) - TORSO_Z) < 0.35, w["Z"].describe()
    # the truth is read in the same frame as the trajectory, so 3-D metrics do not depend on it
    gt_w, gt_c = (read_groundtruth(LogReader(p), GROUNDTRUTH_GROUPS) for p in (passing, no_pose))
    assert np.allclose(pose.to_world(gt_c.select("X", "Y", "Z").to_numpy()), gt_w.select("X", "Y", "Z").to_numpy())
    assert np.allclose(gt_w["Z"].to_numpy(), TORSO_Z, atol=0.05)
    mw = mot_metrics(world.trajectory, gt_w, space="3d", max_distance_m=1.0)
    mc = mot_metrics(camera.trajectory, gt_c, space="3d", max_distance_m=1.0)
    assert mw.mota == pytest.approx(mc.mota) and mw.motp == pytest.approx(mc.motp)
    # the second table says its frame, and its velocities and covariances are rotated once (no shift)
    assert set(world.extra_rows[0]) >= {"position_frame", "VX"} and world.extra_rows[0]["position_frame"] == "world"
    assert {r["position_frame"] for r in camera.extra_rows} == {"camera"}
    assert len(world.extra_rows) == len(camera.extra_rows) > 20
    cov = ("cov_xx", "cov_xy", "cov_xz", "cov_xy", "cov_yy", "cov_yz", "cov_xz", "cov_yz", "cov_zz")
    for rw, rc in zip(world.extra_rows, camera.extra_rows):
        assert (rw["frame"], rw["track_id"]) == (rc["frame"], rc["track_id"])
        vw, vc = (np.array([r["VX"], r["VY"], r["VZ"]]) for r in (rw, rc))
        assert np.allclose(vw, pose.rotate(vc)[0], atol=1e-9, equal_nan=True)
        Sw, Sc = (np.array([r[k] for k in cov]).reshape(3, 3) for r in (rw, rc))
        assert np.allclose(Sw, pose.rotate_cov(Sc), atol=1e-12)
        sw, sc = (np.array([r["sigma_X"], r["sigma_Y"], r["sigma_Z"]]) for r in (rw, rc))
        assert np.isclose(np.sum(sw**2), np.sum(sc**2))  # a rotation keeps the trace of the EKF position covariance


def test_the_same_defaults_at_24_fps_detect_the_merge(tmp_path):
    """Per-frame parameters follow the log's frame rate: at 24 fps the merge is found (with the
    48-fps frame counts it was missed in 4 s) within 0.5 s of the truth."""
    merging = tmp_path / "merging24.mcap"
    cfg = GroupSceneConfig(scene="groups-merging", fps=24.0, start_s=1.3, duration=1.5, encoding="jpeg")
    write_group_scene(merging, cfg)
    _, _, events = replay_groups(ReplayRequest(log=merging, tracker="groups", seed=0))
    merges = [f for f, e in events if "1,2 merged into" in e]
    true_frame = cfg.lead_in + int(np.ceil((cfg.merge_s - cfg.start_s) * cfg.fps))
    assert merges and true_frame <= merges[0] <= true_frame + 12, (true_frame, events)


@pytest.mark.parametrize("scene_seed", [0, 5])
def test_passing_groups_at_24_fps_do_not_merge_on_a_clip_from_1s(tmp_path, scene_seed):
    """While the fast group passes behind the slow one its EKF velocity drifts towards the slow
    group's (the mean of its points moves slower; seed 0: 1.85 -> 1.56 m/s, truth 1.9) and the EKF
    velocity gate held for the 4-frame hold: merged at frame 53 (seed 0) and 59 (seed 5) with the
    EKF test alone. The member points' own velocities across the line of sight keep them apart
    (merge.measured_velocity)."""
    passing = tmp_path / "passing24.mcap"
    write_group_scene(passing, GroupSceneConfig(scene="groups-passing", seed=scene_seed, fps=24.0, start_s=1.0, duration=3.0,
                                                encoding="jpeg"))
    _, _, events = replay_groups(ReplayRequest(log=passing, tracker="groups", seed=0))
    assert not [e for _, e in events if "merged into" in e or "absorbed" in e], events
