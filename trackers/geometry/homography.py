"""Applying a 3×3 homography to points (and to velocities attached to them)."""

from __future__ import annotations

import numpy as np


def apply_homography(H: np.ndarray, points: np.ndarray) -> np.ndarray:
    """``(N, 2)`` points through ``H``: ``q = H [p; 1]``, then divided by ``q_3``."""
    p = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    q = p @ H[:, :2].T + H[:, 2]
    return q[:, :2] / q[:, 2:3]


def transfer_velocities(H: np.ndarray, points: np.ndarray, velocities: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Points and their per-frame displacements expressed through ``H``.

    A displacement maps as the difference of the images of ``p`` and ``p + v``.
    """
    p2 = apply_homography(H, points)
    v2 = apply_homography(H, np.asarray(points, dtype=np.float64).reshape(-1, 2) + velocities) - p2
    return p2, v2
