"""Image ↔ ground plane through a homography (a calibrated camera looking at flat ground).

``H`` maps image pixels ``(u, v)`` to ground coordinates ``(X, Y)`` in metres; the camera's
ground point (the foot of its perpendicular) and height then give the distance to any ground point.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from trackreplay.trackers.geometry.homography import apply_homography


@dataclass(frozen=True, eq=False)
class GroundPlane:
    image_to_ground: np.ndarray  # 3×3, pixels → metres on the ground
    camera_ground: tuple[float, float] = (0.0, 0.0)  # (X, Y) of the point under the camera
    camera_height: float = 0.0  # metres above the ground
    principal_point: tuple[float, float] | None = None  # pixels; None: the image centre
    focal_px: float | None = None  # None: unknown (trackers.groups.ground_depth finds it from the homography)

    @property
    def ground_to_image(self) -> np.ndarray:
        return np.linalg.inv(self.image_to_ground)

    def to_ground(self, pixels: np.ndarray) -> np.ndarray:
        """(N, 2) pixels → (N, 2) ground metres. Pixels above the horizon give points behind the camera."""
        return apply_homography(self.image_to_ground, pixels)

    def to_image(self, ground: np.ndarray) -> np.ndarray:
        return apply_homography(self.ground_to_image, ground)

    def distance(self, pixels: np.ndarray) -> np.ndarray:
        """Camera-to-ground-point distance (m) for each pixel's ground point: ``√(d² + height²)``."""
        g = self.to_ground(pixels) - np.asarray(self.camera_ground, dtype=np.float64)
        return np.sqrt(np.einsum("nd,nd->n", g, g) + self.camera_height**2)
