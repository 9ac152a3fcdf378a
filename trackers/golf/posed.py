"""A PTZ camera pose with its rotation and intrinsic matrices computed once per frame.

``PtzCamera.R`` rebuilds the rotation at every call; the tracker needs it a dozen times a frame
(lines of sight, projections, the pose-change homography, the EKF Jacobian). ``PosedCamera`` has
the same ``line_of_sight`` / ``project_points`` / ``project_directions`` / ``position`` /
``intrinsics`` / ``R`` surface, so it stands in for the ``PtzCamera`` it wraps.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from trackreplay.trackers.geometry.ptz import Intrinsics, PtzCamera


@dataclass(frozen=True, eq=False)
class PosedCamera:
    camera: PtzCamera
    R: np.ndarray  # world from camera (columns: right, down, forward)
    K: np.ndarray
    K_inv: np.ndarray

    @classmethod
    def of(cls, camera: PtzCamera) -> PosedCamera:
        k = camera.intrinsics
        K = np.array([[k.fx, 0.0, k.cx], [0.0, k.fy, k.cy], [0.0, 0.0, 1.0]])
        return cls(camera, camera.R, K, np.linalg.inv(K))

    @property
    def position(self) -> np.ndarray:
        return self.camera.position

    @property
    def intrinsics(self) -> Intrinsics:
        return self.camera.intrinsics

    def line_of_sight(self, pixels: np.ndarray) -> np.ndarray:
        uv = np.atleast_2d(np.asarray(pixels, dtype=np.float64))
        rays = np.concatenate([uv, np.ones((len(uv), 1))], axis=1) @ self.K_inv.T @ self.R.T
        return rays / np.linalg.norm(rays, axis=1, keepdims=True)

    def project_directions(self, directions: np.ndarray) -> np.ndarray:
        cam = np.atleast_2d(np.asarray(directions, dtype=np.float64)) @ self.R
        ahead = cam[:, 2] > 1e-9
        z = np.where(ahead, cam[:, 2], 1.0)
        uv = (cam[:, :2] / z[:, None]) * [self.K[0, 0], self.K[1, 1]] + [self.K[0, 2], self.K[1, 2]]
        return np.where(ahead[:, None], uv, np.nan)

    def project_points(self, points: np.ndarray) -> np.ndarray:
        return self.project_directions(np.atleast_2d(points) - self.position)


def pose_homography(before: PosedCamera, after: PosedCamera) -> np.ndarray:
    """Pixels of the pose ``before`` -> pixels of ``after`` for a camera that only rotates/zooms."""
    return after.K @ after.R.T @ before.R @ before.K_inv
