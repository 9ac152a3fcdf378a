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
