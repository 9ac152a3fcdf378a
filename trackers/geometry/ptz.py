"""A pan-tilt-zoom camera that only rotates about a fixed world point.

World frame: right-handed, metres, Z up, ground plane Z = 0. Pan rotates about world Z
(degrees, counter-clockwise seen from above, 0 = looking along +X); tilt rotates about the
camera's horizontal axis (degrees, positive up). Camera frame as OpenCV: x right, y down,
z forward. Because the camera only rotates, a line of sight stored under one pose can be
drawn into the image of any other pose without knowing depth (seed 000, §2).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from trackreplay.schemas.records import LensTable, PtzReading


@dataclass(frozen=True)
class Intrinsics:
    fx: float
    fy: float
    cx: float
    cy: float
    width: int
    height: int


def intrinsics_at(lens: LensTable, zoom: float, focus: float) -> Intrinsics:
    """Pinhole intrinsics at a zoom/focus reading, interpolated linearly in the lens table.

    The table is a grid over (zoom, focus): interpolate along zoom within each focus row,
    then along focus. Readings beyond the table clamp to its edge.
    """
    if not lens.entries:
        raise ValueError("the lens table has no entries")
    table = np.array([(e.zoom, e.focus, e.fx, e.fy, e.cx, e.cy) for e in lens.entries], dtype=np.float64)
    focuses = np.unique(table[:, 1])
    rows = []
    for f in focuses:
        sub = table[table[:, 1] == f]
        sub = sub[np.argsort(sub[:, 0], kind="stable")]
        rows.append([np.interp(zoom, sub[:, 0], sub[:, k]) for k in range(2, 6)])
    rows_arr = np.array(rows)
    values = [np.interp(focus, focuses, rows_arr[:, k]) for k in range(4)]
    return Intrinsics(*values, lens.width, lens.height)


def rotation_world_from_camera(pan_deg: float, tilt_deg: float) -> np.ndarray:
    """3x3 matrix whose columns are the camera's x (right), y (down), z (forward) in world axes."""
    p, t = np.deg2rad(pan_deg), np.deg2rad(tilt_deg)
    forward = np.array([np.cos(t) * np.cos(p), np.cos(t) * np.sin(p), np.sin(t)])
    right = np.array([np.sin(p), -np.cos(p), 0.0])
    down = np.cross(forward, right)
    return np.stack([right, down, forward], axis=1)


def pan_tilt_towards(direction: np.ndarray) -> tuple[float, float]:
    """Pan and tilt (degrees) whose optical axis points along ``direction``."""
    d = np.asarray(direction, dtype=np.float64)
    d = d / np.linalg.norm(d)
    return float(np.rad2deg(np.arctan2(d[1], d[0]))), float(np.rad2deg(np.arcsin(np.clip(d[2], -1.0, 1.0))))


@dataclass(frozen=True, eq=False)
class PtzCamera:
    """A posed PTZ camera: world position, pan/tilt in degrees, and intrinsics."""

    position: np.ndarray
    pan: float
    tilt: float
    intrinsics: Intrinsics

    @classmethod
    def from_reading(cls, reading: PtzReading, lens: LensTable) -> PtzCamera:
        return cls(np.asarray(lens.camera_position, dtype=np.float64), reading.pan, reading.tilt,
                   intrinsics_at(lens, reading.zoom, reading.focus))

    @property
    def R(self) -> np.ndarray:
        return rotation_world_from_camera(self.pan, self.tilt)

    def line_of_sight(self, pixels: np.ndarray) -> np.ndarray:
        """Unit world vectors from the camera through image points ``(N, 2)`` (u, v)."""
        k = self.intrinsics
        uv = np.atleast_2d(np.asarray(pixels, dtype=np.float64))
        rays = np.stack([(uv[:, 0] - k.cx) / k.fx, (uv[:, 1] - k.cy) / k.fy, np.ones(len(uv))], axis=1)
        world = rays @ self.R.T
        return world / np.linalg.norm(world, axis=1, keepdims=True)

    def project_directions(self, directions: np.ndarray) -> np.ndarray:
        """Image points ``(N, 2)`` of world directions; NaN for directions behind the camera."""
        k = self.intrinsics
        cam = np.atleast_2d(np.asarray(directions, dtype=np.float64)) @ self.R
        with np.errstate(divide="ignore", invalid="ignore"):
            u = k.fx * cam[:, 0] / cam[:, 2] + k.cx
            v = k.fy * cam[:, 1] / cam[:, 2] + k.cy
        ahead = cam[:, 2] > 1e-9
        return np.stack([np.where(ahead, u, np.nan), np.where(ahead, v, np.nan)], axis=1)

    def project_points(self, points: np.ndarray) -> np.ndarray:
        """Image points of world points ``(N, 3)``."""
        return self.project_directions(np.atleast_2d(points) - self.position)

    def in_image(self, pixels: np.ndarray) -> np.ndarray:
        k = self.intrinsics
        uv = np.atleast_2d(pixels)
        return (uv[:, 0] >= 0) & (uv[:, 0] < k.width) & (uv[:, 1] >= 0) & (uv[:, 1] < k.height)
