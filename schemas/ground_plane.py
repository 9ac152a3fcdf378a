"""The typed record of ``trackreplay.GroundPlane`` (topic ``/camera/ground_plane``).

A fixed camera over flat ground: the 3x3 homography from image pixels to ground metres, the
ground point under the camera and the camera's height (so the distance from the camera to any
ground point follows), the image size it is for, and the principal point and focal length when
known. Kept beside ``records.py`` as its own module so the record and its message stay together.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from trackreplay.schemas import messages as m
from trackreplay.schemas.records import timestamp


@dataclass(frozen=True)
class GroundPlaneCalibration:
    """Image ↔ ground calibration of a fixed camera (metres on the ground, pixels in the image)."""

    width: int
    height: int
    image_to_ground: tuple[float, ...]  # 9, row-major: (u, v, 1) -> (X, Y, 1) up to scale
    camera_ground: tuple[float, float] = (0.0, 0.0)
    camera_height: float = 0.0
    principal_point: tuple[float, float] | None = None  # None: the image centre
    focal_px: float | None = None

    def __post_init__(self) -> None:
        if len(self.image_to_ground) != 9:
            raise ValueError(f"image_to_ground needs 9 values (3x3 row-major), not {len(self.image_to_ground)}")
        H = np.asarray(self.image_to_ground, dtype=np.float64)
        if not np.isfinite(H).all() or abs(np.linalg.det(H.reshape(3, 3))) < 1e-15 * max(np.abs(H).max(), 1e-300) ** 3:
            raise ValueError("image_to_ground must be a finite, invertible 3x3 matrix")
        if self.width < 1 or self.height < 1:
            raise ValueError(f"image size must be positive, not {self.width}x{self.height}")
        if not (np.isfinite(self.camera_height) and self.camera_height >= 0.0):
            raise ValueError(f"camera_height must be a finite height >= 0 m, not {self.camera_height}")
        if self.focal_px is not None and not self.focal_px > 0:
            raise ValueError(f"focal_px must be positive, not {self.focal_px}")

    @property
    def matrix(self) -> np.ndarray:
        """The homography as a 3x3 float64 array."""
        return np.asarray(self.image_to_ground, dtype=np.float64).reshape(3, 3)

    @property
    def centre(self) -> tuple[float, float]:
        """The principal point, or the image centre ``((W-1)/2, (H-1)/2)`` when not given."""
        if self.principal_point is not None:
            return self.principal_point
        return ((self.width - 1) / 2.0, (self.height - 1) / 2.0)

    def to_pb(self, t_ns: int = 0) -> m.GroundPlane:
        pb = m.GroundPlane(
            timestamp=timestamp(t_ns), width=self.width, height=self.height,
            image_to_ground=[float(v) for v in self.image_to_ground],
            camera_ground_x=float(self.camera_ground[0]), camera_ground_y=float(self.camera_ground[1]),
            camera_height=float(self.camera_height),
        )
        if self.principal_point is not None:
            pb.cx, pb.cy = (float(v) for v in self.principal_point)
        if self.focal_px is not None:
            pb.focal_px = float(self.focal_px)
        return pb

    @classmethod
    def from_pb(cls, pb) -> GroundPlaneCalibration:
        pp = (pb.cx, pb.cy) if pb.HasField("cx") and pb.HasField("cy") else None
        return cls(
            width=pb.width, height=pb.height, image_to_ground=tuple(pb.image_to_ground),
            camera_ground=(pb.camera_ground_x, pb.camera_ground_y), camera_height=pb.camera_height,
            principal_point=pp, focal_px=pb.focal_px if pb.HasField("focal_px") else None,
        )
