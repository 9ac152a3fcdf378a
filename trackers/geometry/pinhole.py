"""The pinhole camera: camera-frame points ↔ pixels through the intrinsic matrix ``K``.

Camera frame as OpenCV: x right, y down, z forward. ``u = fx x/z + cx``, ``v = fy y/z + cy``;
back-projection gives the ray ``K⁻¹ [u v 1]ᵀ`` (z = 1). ``K`` and ``K⁻¹`` are computed once per
:class:`Intrinsics` (cached), so a camera used many times in a frame does not rebuild them.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np


@dataclass(frozen=True)
class Intrinsics:
    """Focal lengths and principal point in pixels, and the image size."""

    fx: float
    fy: float
    cx: float
    cy: float
    width: int
    height: int

    @cached_property
    def K(self) -> np.ndarray:  # noqa: N802 (the textbook symbol)
        return np.array([[self.fx, 0.0, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])

    @cached_property
    def K_inv(self) -> np.ndarray:  # noqa: N802
        return np.linalg.inv(self.K)

    def project(self, points: np.ndarray) -> np.ndarray:
        """``(N, 2)`` pixels of camera-frame points (or directions) ``(N, 3)``; NaN for z ≤ 0."""
        cam = np.atleast_2d(np.asarray(points, dtype=np.float64))
        ahead = cam[:, 2] > 1e-9
        z = np.where(ahead, cam[:, 2], 1.0)
        focal, centre = self._focal_centre
        uv = (cam[:, :2] / z[:, None]) * focal + centre
        return np.where(ahead[:, None], uv, np.nan)

    @cached_property
    def _focal_centre(self) -> tuple[np.ndarray, np.ndarray]:
        """``[fx, fy]`` and ``[cx, cy]`` as read from ``K`` (what :meth:`project` scales and shifts by)."""
        K = self.K
        return np.array([K[0, 0], K[1, 1]]), np.array([K[0, 2], K[1, 2]])

    def back_project(self, pixels: np.ndarray) -> np.ndarray:
        """``(N, 3)`` camera-frame rays ``K⁻¹ [u v 1]ᵀ`` (z = 1, not normalised) through ``(N, 2)`` pixels."""
        uv = np.atleast_2d(np.asarray(pixels, dtype=np.float64))
        return np.concatenate([uv, np.ones((len(uv), 1))], axis=1) @ self.K_inv.T

    def in_image(self, pixels: np.ndarray) -> np.ndarray:
        """Which ``(N, 2)`` pixels fall inside the ``width × height`` image."""
        uv = np.atleast_2d(pixels)
        return (uv[:, 0] >= 0) & (uv[:, 0] < self.width) & (uv[:, 1] >= 0) & (uv[:, 1] < self.height)
