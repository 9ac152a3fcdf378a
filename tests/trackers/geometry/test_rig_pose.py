"""The stereo rig's world pose: quaternion <-> matrix, camera <-> world, and the pose the synthetic
group scenes write (/stereo/pose) agreeing with the scene's own rig."""

from __future__ import annotations

import numpy as np
import pytest

from trackreplay.recorder.synth.groups.world import Rig
from trackreplay.trackers.geometry.rig_pose import RigPose, matrix_from_quaternion, quaternion_from_matrix


def _rotation(rng: np.random.Generator) -> np.ndarray:
    q, r = np.linalg.qr(rng.standard_normal((3, 3)))
    q = q @ np.diag(np.sign(np.diag(r)))
    return q if np.linalg.det(q) > 0 else -q


def test_quaternion_round_trip_on_every_branch():
    rng = np.random.default_rng(0)
    mats = [_rotation(rng) for _ in range(50)]
    mats += [np.diag([1.0, -1.0, -1.0]), np.diag([-1.0, 1.0, -1.0]), np.diag([-1.0, -1.0, 1.0]), np.eye(3)]  # trace <= 0 branches
    for R in mats:
        q = quaternion_from_matrix(R)
        assert q[3] >= 0 and np.isclose(np.linalg.norm(q), 1.0)
        assert np.allclose(matrix_from_quaternion(q), R, atol=1e-12)


@pytest.mark.parametrize("rig", [Rig(), Rig(height=2.1, tilt_deg=15.0)])
def test_rig_pose_maps_camera_points_back_to_the_scene_world(rig):
    pose = RigPose.from_quaternion(quaternion_from_matrix(rig.R.T), rig.centre)
    world = np.array([[1.0, 7.0, 0.9], [-2.0, 4.0, 0.0], [0.5, 12.0, 1.7]])
    cam = rig.to_camera(world)
    assert np.allclose(pose.to_world(cam), world, atol=1e-12)
    assert np.allclose(pose.to_camera(world), cam, atol=1e-12)
    # the camera's forward axis points down by the tilt, its y axis (image down) has a negative world Z
    fwd = pose.rotate(np.array([0.0, 0.0, 1.0]))[0]
    assert np.isclose(np.degrees(np.arcsin(-fwd[2])), rig.tilt_deg)
    assert pose.rotate(np.array([0.0, 1.0, 0.0]))[0][2] < 0
    S = np.diag([0.04, 0.09, 0.25])
    assert np.isclose(np.trace(pose.rotate_cov(S)), np.trace(S))  # a rotation keeps the total variance


def test_rig_pose_rejects_a_non_rotation():
    with pytest.raises(ValueError):
        RigPose(tuple(np.diag([1.0, 1.0, -1.0]).ravel()), (0.0, 0.0, 0.0))
    with pytest.raises(ValueError):
        RigPose(tuple((2 * np.eye(3)).ravel()), (0.0, 0.0, 0.0))


@pytest.mark.parametrize("q, t", [((0.0, 0.0, 0.0, 0.0), (0.0, 0.0, 1.0)), ((0.0, 0.0, float("nan"), 1.0), (0.0, 0.0, 1.0)),
                                  ((0.0, 0.0, 0.0, 1.0), (float("nan"), 0.0, 1.0)), ((0.0, 0.0, 0.0, 1.0), (0.0, float("inf"), 1.0))])
def test_rig_pose_rejects_a_degenerate_quaternion_or_translation(q, t):
    with pytest.raises(ValueError):
        RigPose.from_quaternion(np.array(q), np.array(t))


@pytest.mark.parametrize("q, t", [((0.0, 0.0, 0.0, 0.0), (0.0, 0.0, 1.0)), ((0.0, 0.0, 0.0, 1.0), (float("nan"), 0.0, 1.0))])
def test_a_malformed_pose_message_is_one_log_error_naming_file_and_topic(tmp_path, q, t):
    from foxglove_schemas_protobuf.Quaternion_pb2 import Quaternion
    from foxglove_schemas_protobuf.Vector3_pb2 import Vector3

    from trackreplay.recorder.writer import LogWriter
    from trackreplay.replay.log.frames import read_rig_pose
    from trackreplay.replay.log.reader import LogReader
    from trackreplay.schemas import messages as m
    from trackreplay.schemas.errors import LogError

    path = tmp_path / "bad-pose.mcap"
    with LogWriter(path) as w:
        w.write("/stereo/pose", m.FrameTransform(parent_frame_id="world", child_frame_id="left",
                                                 translation=Vector3(x=t[0], y=t[1], z=t[2]),
                                                 rotation=Quaternion(x=q[0], y=q[1], z=q[2], w=q[3])), 1)
    with pytest.raises(LogError, match=r"bad-pose\.mcap: topic /stereo/pose is not a usable rig pose"):
        read_rig_pose(LogReader(path))
