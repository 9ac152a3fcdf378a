"""Rectified stereo: disparity ↔ 3-D in the left camera's frame (x right, y down, z forward).

``u = f x / z + cx``, ``v = f y / z + cy``, ``d = f b / z`` (seed 003, eq. for f(x)); inverted,
``z = f b / d``, ``x = (u − cx) z / f``, ``y = (v − cy) z / f``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from trackreplay.trackers.geometry.rig_pose import RigPose


@dataclass(frozen=True)
class StereoRig:
    f: float  # focal length, px (rectified, square pixels)
    baseline: float  # m
    cx: float
    cy: float
    pose: RigPose | None = None  # the left camera in a world frame (Z up), from the log's /stereo/pose

    def to_points(self, uvd: np.ndarray) -> np.ndarray:
        """(N, 3) ``u v d`` (d > 0) → (N, 3) ``X Y Z`` metres."""
        uvd = np.asarray(uvd, dtype=np.float64).reshape(-1, 3)
        z = self.f * self.baseline / uvd[:, 2]
        return np.stack([(uvd[:, 0] - self.cx) * z / self.f, (uvd[:, 1] - self.cy) * z / self.f, z], axis=1)

    def to_uvd(self, points: np.ndarray) -> np.ndarray:
        """(N, 3) ``X Y Z`` (Z > 0) → (N, 3) ``u v d``."""
        p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        inv_z = 1.0 / p[:, 2]
        return np.stack([self.f * p[:, 0] * inv_z + self.cx, self.f * p[:, 1] * inv_z + self.cy, self.f * self.baseline * inv_z], axis=1)

    def jacobian(self, point: np.ndarray) -> np.ndarray:
        """3×3 ``∂(u, v, d)/∂(X, Y, Z)`` at one point (the EKF's observation Jacobian)."""
        x, y, z = (float(c) for c in point)
        f, b = self.f, self.baseline
        return np.array([[f / z, 0.0, -f * x / z**2], [0.0, f / z, -f * y / z**2], [0.0, 0.0, -f * b / z**2]])
