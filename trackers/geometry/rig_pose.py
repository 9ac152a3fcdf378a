"""A stereo rig's pose in a world frame (right-handed, metres, Z up): the left camera's frame
(x right, y down, z forward) → world, ``p_world = R p_cam + t``.

Stored in a log as a ``foxglove.FrameTransform`` on ``/stereo/pose`` (parent ``world``, child the
left camera; translation = the left camera's centre in the world, rotation = ``R`` as a unit
quaternion ``x y z w``), which is what Foxglove and Rerun read as the child's pose in its parent.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def quaternion_from_matrix(R: np.ndarray) -> np.ndarray:
    """Unit quaternion ``(x, y, z, w)`` with ``w >= 0`` of a 3×3 rotation (Shepperd's branches)."""
    R = np.asarray(R, dtype=np.float64)
    tr = np.trace(R)
    if tr > 0:
        s = 2.0 * np.sqrt(1.0 + tr)
        q = np.array([(R[2, 1] - R[1, 2]) / s, (R[0, 2] - R[2, 0]) / s, (R[1, 0] - R[0, 1]) / s, s / 4])
    elif R[0, 0] >= R[1, 1] and R[0, 0] >= R[2, 2]:
        s = 2.0 * np.sqrt(1.0 + R[0, 0] - R[1, 1] - R[2, 2])
        q = np.array([s / 4, (R[0, 1] + R[1, 0]) / s, (R[0, 2] + R[2, 0]) / s, (R[2, 1] - R[1, 2]) / s])
    elif R[1, 1] >= R[2, 2]:
        s = 2.0 * np.sqrt(1.0 + R[1, 1] - R[0, 0] - R[2, 2])
        q = np.array([(R[0, 1] + R[1, 0]) / s, s / 4, (R[1, 2] + R[2, 1]) / s, (R[0, 2] - R[2, 0]) / s])
    else:
        s = 2.0 * np.sqrt(1.0 + R[2, 2] - R[0, 0] - R[1, 1])
        q = np.array([(R[0, 2] + R[2, 0]) / s, (R[1, 2] + R[2, 1]) / s, s / 4, (R[1, 0] - R[0, 1]) / s])
    q /= np.linalg.norm(q)
    return -q if q[3] < 0 else q


def matrix_from_quaternion(q: np.ndarray) -> np.ndarray:
    """3×3 rotation of a quaternion ``(x, y, z, w)`` of any non-zero finite length."""
    q = np.asarray(q, dtype=np.float64).reshape(-1)
    norm = float(np.linalg.norm(q)) if len(q) == 4 and np.isfinite(q).all() else float("nan")
    if not norm > 0:
        raise ValueError(f"the rotation quaternion (x y z w) {q.tolist()} is not a finite non-zero 4-vector")
    x, y, z, w = q / norm
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


@dataclass(frozen=True)
class RigPose:
    """``p_world = R p_cam + t``; ``rotation`` row-major (9), ``translation`` (3)."""

    rotation: tuple[float, ...]
    translation: tuple[float, float, float]

    def __post_init__(self) -> None:
        if len(self.rotation) != 9 or len(self.translation) != 3 or not (np.isfinite(self.rotation).all()
                                                                         and np.isfinite(self.translation).all()):
            raise ValueError("a rig pose needs a finite 3x3 rotation and a finite 3-vector translation")
        R = self.R
        if not np.allclose(R @ R.T, np.eye(3), atol=1e-6) or np.linalg.det(R) < 0:
            raise ValueError("the rig pose's rotation is not a rotation (R R^T != I or det < 0)")

    @classmethod
    def from_quaternion(cls, q: np.ndarray, t: np.ndarray) -> RigPose:
        return cls(tuple(float(v) for v in matrix_from_quaternion(q).ravel()), tuple(float(v) for v in t))

    @property
    def R(self) -> np.ndarray:
        return np.asarray(self.rotation, dtype=np.float64).reshape(3, 3)

    @property
    def t(self) -> np.ndarray:
        return np.asarray(self.translation, dtype=np.float64)

    @property
    def quaternion(self) -> np.ndarray:
        return quaternion_from_matrix(self.R)

    def to_world(self, points: np.ndarray) -> np.ndarray:
        """(N, 3) camera-frame points → world."""
        return np.asarray(points, dtype=np.float64).reshape(-1, 3) @ self.R.T + self.t

    def to_camera(self, points: np.ndarray) -> np.ndarray:
        return (np.asarray(points, dtype=np.float64).reshape(-1, 3) - self.t) @ self.R

    def rotate(self, vectors: np.ndarray) -> np.ndarray:
        """(N, 3) camera-frame directions or velocities → world (no translation)."""
        return np.asarray(vectors, dtype=np.float64).reshape(-1, 3) @ self.R.T

    def rotate_cov(self, cov: np.ndarray) -> np.ndarray:
        """(..., 3, 3) camera-frame covariances → world: ``R Σ Rᵀ``."""
        R = self.R
        return R @ np.asarray(cov, dtype=np.float64) @ R.T
