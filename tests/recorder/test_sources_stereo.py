"""Stereo pairs and calibration files."""

from __future__ import annotations

import json

import cv2
import numpy as np
import pytest

from trackreplay.recorder.record import record
from trackreplay.recorder.sources.stereo import load_calibration
from trackreplay.schemas.errors import SourceError

K = [[100.0, 0.0, 32.0], [0.0, 110.0, 24.0], [0.0, 0.0, 1.0]]


def write_json(path, **extra):
    data = {"width": 64, "height": 48, "K": K, "D": [0.1, -0.01, 0.0, 0.0, 0.0], **extra}
    path.write_text(json.dumps(data))
    return path


def test_stereo_folders_same_time_and_calibration(tmp_path, make_images, log_messages):
    left, right = make_images(tmp_path / "L", 4), make_images(tmp_path / "R", 4, ext="png")
    calib = write_json(tmp_path / "calib.json", baseline_m=0.12)
    report = record(tmp_path / "out.mcap", stereo=(left, right), calibration=calib, fps=10, quiet=True)
    assert report.frames == 4
    msgs = log_messages(tmp_path / "out.mcap")
    lt = [m.log_time for m in msgs if m.topic == "/stereo/left/image"]
    rt = [m.log_time for m in msgs if m.topic == "/stereo/right/image"]
    assert lt == rt == [i * 100_000_000 for i in range(4)]
    cal = {m.topic: m.pb for m in msgs if m.schema == "foxglove.CameraCalibration"}
    assert set(cal) == {"/stereo/left/calibration", "/stereo/right/calibration"}
    lc, rc = cal["/stereo/left/calibration"], cal["/stereo/right/calibration"]
    assert (lc.width, lc.height) == (64, 48) and list(lc.K) == sum(K, [])
    assert lc.P[3] == 0.0 and rc.P[3] == pytest.approx(-100.0 * 0.12)
    assert list(rc.D) == pytest.approx([0.1, -0.01, 0, 0, 0]) and lc.distortion_model == "plumb_bob"
    assert all(m.log_time == 0 for m in msgs if m.schema == "foxglove.CameraCalibration")


def test_stereo_videos(tmp_path, make_video, log_messages):
    left, right = make_video(tmp_path / "l.avi", 3, fps=5), make_video(tmp_path / "r.avi", 3, fps=5)
    record(tmp_path / "out.mcap", stereo=(left, right), encoding="png", quiet=True)
    msgs = log_messages(tmp_path / "out.mcap")
    assert [m.log_time for m in msgs if m.topic.endswith("left/image")] == [0, 200_000_000, 400_000_000]
    assert sum(m.topic.endswith("right/image") for m in msgs) == 3


def test_mono_calibration_from_opencv_yaml(tmp_path, make_images, log_messages):
    path = tmp_path / "cam.yaml"
    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_WRITE)
    fs.write("image_width", 64)
    fs.write("image_height", 48)
    fs.write("camera_matrix", np.array(K))
    fs.write("distortion_coefficients", np.zeros((1, 5)))
    fs.release()
    folder = make_images(tmp_path / "img", 2)
    record(tmp_path / "out.mcap", images=folder, fps=10, calibration=path, quiet=True)
    cal = [m for m in log_messages(tmp_path / "out.mcap") if m.topic == "/camera/calibration"]
    assert len(cal) == 1 and list(cal[0].pb.K) == sum(K, []) and list(cal[0].pb.P)[:3] == [100.0, 0.0, 32.0]


def test_right_projection_given_directly(tmp_path):
    p = [100.0, 0, 32, -15.0, 0, 110, 24, 0, 0, 0, 1, 0]
    calib = load_calibration(write_json(tmp_path / "c.json", right_P=p), stereo=True)
    assert calib.baseline_m == pytest.approx(0.15)


def test_unequal_stereo_counts(tmp_path, make_images, make_video):
    left, right = make_images(tmp_path / "L", 4), make_images(tmp_path / "R", 3)
    with pytest.raises(SourceError, match=r"L has 4 images, .*R has 3"):
        record(tmp_path / "out.mcap", stereo=(left, right), fps=10, quiet=True)
    lv, rv = make_video(tmp_path / "l.avi", 4), make_video(tmp_path / "r.avi", 3)
    for pair in ((lv, rv), (rv, lv)):
        with pytest.raises(SourceError, match=r"r\.avi ends after 3 frames, .*l\.avi goes on"):
            record(tmp_path / "out.mcap", stereo=pair, quiet=True)
    assert not (tmp_path / "out.mcap").exists()


@pytest.mark.parametrize("extra, match", [
    ({}, "needs 'baseline_m' or 'right_P'"),
    ({"baseline_m": -1}, "baseline_m must be a finite positive number"),
    ({"baseline_m": 0.1, "K": [1, 2, 3]}, "K has 3 numbers, expected 9"),
    # a review: accepted, then an empty trajectory with exit 0 (inf) or a replay refusing the log (right_P)
    ({"baseline_m": 1e309}, "baseline_m must be a finite positive number"),
    ({"baseline_m": "0.12"}, "baseline_m is not a number"),
    ({"baseline_m": True}, "baseline_m is not a number"),
    ({"right_P": [100, 0, 32, 0, 0, 100, 24, 0, 0, 0, 1, 0]}, "right_P puts the right camera 0 m to the right"),
    ({"baseline_m": 0.5, "right_P": [100, 0, 32, -12, 0, 100, 24, 0, 0, 0, 1, 0]}, "baseline_m 0.5 and right_P \\(0.12 m\\) disagree"),
    ({"baseline_m": 0.1, "width": "64"}, "width and height must be integers"),
    ({"baseline_m": 0.1, "width": 64.5}, "width and height must be integers"),
])
def test_bad_stereo_calibration(tmp_path, make_images, extra, match):
    left, right = make_images(tmp_path / "L", 2), make_images(tmp_path / "R", 2)
    calib = write_json(tmp_path / "calib.json", **extra)
    with pytest.raises(SourceError, match=match):
        record(tmp_path / "out.mcap", stereo=(left, right), calibration=calib, fps=10, quiet=True)


def test_calibration_size_must_match_images(tmp_path, make_images):
    folder = make_images(tmp_path / "img", 2, size=(32, 24))
    with pytest.raises(SourceError, match=r"calibration .*c\.json is for 64x48 images but .*frame0\.jpg is 32x24"):
        record(tmp_path / "out.mcap", images=folder, fps=10, calibration=write_json(tmp_path / "c.json"), quiet=True)
    bad = tmp_path / "bad.json"
    bad.write_text('{"width": 64,\n "height": }')
    with pytest.raises(SourceError, match=r"bad\.json:2: not valid JSON"):
        record(tmp_path / "out.mcap", images=folder, fps=10, calibration=bad, quiet=True)


def test_rig_pose_in_the_calibration_reaches_the_log_and_the_reader(tmp_path, make_images, log_messages):
    """A rig 2 m up, looking along world +Y and tilted 30° down: written on /stereo/pose, read back
    as the same rotation and centre."""
    from trackreplay.replay.log.frames import read_rig_pose
    from trackreplay.replay.log.reader import LogReader

    tilt = np.radians(30.0)
    # camera axes in the world: x right = world +X; z forward = (0, cos, -sin); y down = z x x
    x, z = np.array([1.0, 0, 0]), np.array([0.0, np.cos(tilt), -np.sin(tilt)])
    R = np.stack([x, np.cross(z, x), z], axis=1)  # columns: the camera axes in world coordinates
    left, right = make_images(tmp_path / "L", 3), make_images(tmp_path / "R", 3)
    calib = write_json(tmp_path / "calib.json", baseline_m=0.12, world_t=[0.5, -1.0, 2.0], world_R=R.tolist())
    record(tmp_path / "out.mcap", stereo=(left, right), calibration=calib, fps=10, quiet=True)
    poses = [m for m in log_messages(tmp_path / "out.mcap") if m.topic == "/stereo/pose"]
    assert len(poses) == 1 and poses[0].schema == "foxglove.FrameTransform" and poses[0].pb.parent_frame_id == "world"
    pose = read_rig_pose(LogReader(tmp_path / "out.mcap"))
    assert np.allclose(pose.R, R) and np.allclose(pose.t, [0.5, -1.0, 2.0])
    assert np.allclose(pose.to_world(np.array([[0.0, 0.0, 4.0]]))[0], [0.5, -1.0 + 4 * np.cos(tilt), 2.0 - 4 * np.sin(tilt)])
    q = write_json(tmp_path / "q.json", baseline_m=0.12, world_t=[0.5, -1.0, 2.0], world_quaternion=list(pose.quaternion))
    assert np.allclose(load_calibration(q, stereo=True).pose.R, R)
    assert load_calibration(write_json(tmp_path / "none.json", baseline_m=0.12), stereo=True).pose is None


@pytest.mark.parametrize("extra, match", [
    ({"world_t": [0, 0, 1]}, "needs world_t and one of world_R or world_quaternion"),
    ({"world_R": np.eye(3).tolist()}, "needs world_t"),
    ({"world_t": [0, 0, 1], "world_R": (2 * np.eye(3)).tolist()}, "not a rotation"),
    ({"world_t": [0, 0], "world_quaternion": [0, 0, 0, 1]}, "world_t has 2 numbers"),
    ({"world_t": [0, 0, 1], "world_quaternion": [0, 0, 0, 0]}, "not a finite non-zero"),
])
def test_bad_rig_pose_is_named(tmp_path, extra, match):
    with pytest.raises(SourceError, match=match):
        load_calibration(write_json(tmp_path / "c.json", baseline_m=0.12, **extra), stereo=True)


def test_a_grey_right_view_of_a_colour_left_is_refused(tmp_path, make_images):
    """A review: recorded (exit 0), then the replay refused it as "640x480 but earlier images are 640x480"."""
    import cv2
    import numpy as np

    left, right = make_images(tmp_path / "L", 2), tmp_path / "R"
    right.mkdir()
    for k in range(2):
        cv2.imwrite(str(right / f"frame{k}.png"), np.full((48, 64), 90, np.uint8))
    with pytest.raises(SourceError, match=r"frame0\.png is grey but .*frame0\.jpg is colour; record both views alike"):
        record(tmp_path / "out.mcap", stereo=(left, right), calibration=write_json(tmp_path / "c.json", baseline_m=0.1),
               fps=10, quiet=True)


def test_stereo_videos_at_different_rates_are_refused(tmp_path, make_video):
    """A review: a 48 fps left and a 24 fps right were paired frame by frame, silently."""
    lv, rv = make_video(tmp_path / "l.avi", 4, fps=48.0), make_video(tmp_path / "r.avi", 4, fps=24.0)
    with pytest.raises(SourceError, match=r"stereo videos run at different rates: .*l\.avi 48 fps, .*r\.avi 24 fps"):
        record(tmp_path / "out.mcap", stereo=(lv, rv), calibration=write_json(tmp_path / "c.json", baseline_m=0.1), quiet=True)


def test_a_missing_stereo_input_is_named(tmp_path, make_images):
    """A review: `--stereo L nonexist` said "must both be folders or both be videos"."""
    left = make_images(tmp_path / "L", 2)
    with pytest.raises(SourceError, match=r"stereo input .*nonexist does not exist"):
        record(tmp_path / "out.mcap", stereo=(left, tmp_path / "nonexist"),
               calibration=write_json(tmp_path / "c.json", baseline_m=0.1), fps=10, quiet=True)


def test_a_ros_camera_info_yaml_is_read(tmp_path):
    """A code review: ROS camera_info matrices ({rows, cols, data}, no OpenCV dt) made OpenCV's parser
    assert, so a calibration written by ROS could not be read at all."""
    from trackreplay.recorder.sources.stereo import load_calibration

    path = tmp_path / "left.yaml"
    path.write_text(
        "image_width: 64\nimage_height: 48\ncamera_name: left\n"
        "camera_matrix:\n  rows: 3\n  cols: 3\n  data: [100.0, 0.0, 32.0, 0.0, 100.0, 24.0, 0.0, 0.0, 1.0]\n"
        "distortion_model: plumb_bob\n"
        "distortion_coefficients:\n  rows: 1\n  cols: 5\n  data: [0.1, 0.0, 0.0, 0.0, 0.0]\n"
        "rectification_matrix:\n  rows: 3\n  cols: 3\n  data: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]\n"
        "projection_matrix:\n  rows: 3\n  cols: 4\n  data: [90.0, 0.0, 30.0, 0.0, 0.0, 90.0, 22.0, 0.0, 0.0, 0.0, 1.0, 0.0]\n")
    left = load_calibration(path).left
    assert (left.width, left.height, left.K[0], left.D[0], left.P[0], left.P[2]) == (64, 48, 100.0, 0.1, 90.0, 30.0)
