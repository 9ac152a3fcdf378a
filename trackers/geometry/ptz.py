"""A pan-tilt-zoom camera that only rotates about a fixed world point.

World frame: right-handed, metres, Z up, ground plane Z = 0. Pan rotates about world Z
(degrees, counter-clockwise seen from above, 0 = looking along +X); tilt rotates about the
camera's horizontal axis (degrees, positive up). Camera frame as OpenCV: x right, y down,
z forward. Because the camera only rotates, a line of sight stored under one pose can be
drawn into the image of any other pose without knowing depth (seed 000, §2).

:class:`PtzCamera` is the one posed camera of the project (the frame bundle carries it): its
rotation ``R`` and the intrinsic matrices are computed once and cached, so a tracker may use it a
dozen times a frame (lines of sight, projections, the pose-change homography, an EKF Jacobian).
Projection and back-projection are the pinhole's (:mod:`trackreplay.trackers.geometry.pinhole`).
"""

from __future__ import annotations

from bisect import bisect_right
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from trackreplay.schemas.records import LensTable, PtzReading
from trackreplay.trackers.geometry.pinhole import Intrinsics

__all__ = ["Intrinsics", "PtzCamera", "intrinsics_at", "pan_tilt_towards", "pose_homography", "rotation_world_from_camera",
           "zoom_area_ratio"]


def intrinsics_at(lens: LensTable, zoom: float, focus: float) -> Intrinsics:
    """Pinhole intrinsics at a zoom/focus reading, interpolated linearly in the lens table.

    The table is a grid over (zoom, focus): interpolate along zoom within each focus row,
    then along focus. Readings beyond the table clamp to its edge.
    """
    focuses, rows_by_focus = _lens_grid(lens)
    zoom, focus = float(zoom), float(focus)
    if zoom != zoom or focus != focus:  # NaN: numpy's own answer
        return _intrinsics_at_numpy(lens, zoom, focus)
    rows = [[interp_one(zoom, zooms, column) for column in columns] for zooms, columns in rows_by_focus]
    values = [np.float64(interp_one(focus, focuses, [row[k] for row in rows])) for k in range(4)]
    return Intrinsics(*values, lens.width, lens.height)


def _intrinsics_at_numpy(lens: LensTable, zoom: float, focus: float) -> Intrinsics:
    """:func:`intrinsics_at` with ``np.interp`` (the plain form; a NaN reading takes it)."""
    focuses, rows_by_focus = _lens_grid(lens)
    rows = [[np.interp(zoom, zooms, column) for column in columns] for zooms, columns in rows_by_focus]
    rows_arr = np.array(rows)
    values = [np.interp(focus, focuses, rows_arr[:, k]) for k in range(4)]
    return Intrinsics(*values, lens.width, lens.height)


def interp_one(x: float, xs: list[float], ys: list[float]) -> float:
    """``np.interp(x, xs, ys)`` for one finite ``x`` over finite increasing ``xs``, in Python floats:
    numpy's own steps (the end value outside, ``ys[j]`` on a knot, else ``slope * (x - xs[j]) +
    ys[j]`` with ``slope = (ys[j+1] - ys[j]) / (xs[j+1] - xs[j])``), without its per-call cost (a
    lens table is interpolated eight times a frame)."""
    if x < xs[0]:
        return ys[0]
    if x > xs[-1]:
        return ys[-1]
    j = bisect_right(xs, x) - 1
    if j == len(xs) - 1 or xs[j] == x:
        return ys[j]
    slope = (ys[j + 1] - ys[j]) / (xs[j + 1] - xs[j])
    value = slope * (x - xs[j]) + ys[j]
    if value != value:  # numpy's retry from the other side (an infinite value)
        value = slope * (x - xs[j + 1]) + ys[j + 1]
        if value != value and ys[j] == ys[j + 1]:
            value = ys[j]
    return value


_GRID: tuple[LensTable, tuple] | None = None  # the last table's grid (a replay passes the same table every frame)


def _lens_grid(lens: LensTable) -> tuple[list[float], list[tuple[list[float], tuple[list[float], ...]]]]:
    """The table's focus values and, per focus row, its zooms (sorted) and fx, fy, cx, cy columns:
    what every ``intrinsics_at`` on the table interpolates in (as Python lists), built once per table
    object (was ~60 µs of a ~90 µs call on a 123-entry table)."""
    global _GRID
    last = _GRID
    if last is not None and last[0] is lens:
        return last[1]
    if not lens.entries:
        raise ValueError("the lens table has no entries")
    table = np.array([(e.zoom, e.focus, e.fx, e.fy, e.cx, e.cy) for e in lens.entries], dtype=np.float64)
    focuses = np.unique(table[:, 1])
    rows = []
    for f in focuses:
        sub = table[table[:, 1] == f]
        sub = sub[np.argsort(sub[:, 0], kind="stable")]
        rows.append((sub[:, 0].tolist(), tuple(sub[:, k].tolist() for k in range(2, 6))))
    grid = (focuses.tolist(), rows)
    _GRID = (lens, grid)
    return grid


def rotation_world_from_camera(pan_deg: float, tilt_deg: float) -> np.ndarray:
    """3x3 matrix whose columns are the camera's x (right), y (down), z (forward) in world axes."""
    p, t = np.deg2rad(pan_deg), np.deg2rad(tilt_deg)
    cos_t, sin_t, cos_p, sin_p = float(np.cos(t)), float(np.sin(t)), float(np.cos(p)), float(np.sin(p))
    fx, fy, fz = cos_t * cos_p, cos_t * sin_p, sin_t  # forward
    rx, ry, rz = sin_p, -cos_p, 0.0  # right
    # down = forward x right, in np.cross's steps (each product rounded, then the difference)
    dx, dy, dz = fy * rz - fz * ry, fz * rx - fx * rz, fx * ry - fy * rx
    return np.array([[rx, dx, fx], [ry, dy, fy], [rz, dz, fz]])


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

    @cached_property
    def R(self) -> np.ndarray:  # noqa: N802 (the textbook symbol)
        """World from camera: columns are the camera's right, down and forward axes in world axes."""
        return rotation_world_from_camera(self.pan, self.tilt)

    @property
    def K(self) -> np.ndarray:  # noqa: N802
        return self.intrinsics.K

    @property
    def K_inv(self) -> np.ndarray:  # noqa: N802
        return self.intrinsics.K_inv

    def line_of_sight(self, pixels: np.ndarray) -> np.ndarray:
        """Unit world vectors from the camera through image points ``(N, 2)`` (u, v)."""
        rays = self.intrinsics.back_project(pixels) @ self.R.T
        return rays / np.sqrt(np.add.reduce(rays * rays, axis=1, keepdims=True))  # np.linalg.norm's own steps

    def project_directions(self, directions: np.ndarray) -> np.ndarray:
        """Image points ``(N, 2)`` of world directions; NaN for directions behind the camera."""
        return self.intrinsics.project(np.atleast_2d(np.asarray(directions, dtype=np.float64)) @ self.R)

    def project_points(self, points: np.ndarray) -> np.ndarray:
        """Image points of world points ``(N, 3)``."""
        return self.project_directions(np.atleast_2d(points) - self.position)

    def project_point(self, point: np.ndarray) -> np.ndarray:
        """``project_points(point.reshape(1, 3))[0]`` for one world point: the same rotation (one
        matmul), then the pinhole's divide, scale and shift in Python floats (numpy's elementwise
        steps, without a dozen calls' overhead)."""
        x, y, z = ((np.asarray(point, dtype=np.float64).reshape(1, 3) - self.position) @ self.R)[0].tolist()
        if not z > 1e-9:  # behind the camera (or NaN)
            return np.array([np.nan, np.nan])
        (fx, _, cx), (_, fy, cy), _ = self.K.tolist()  # as Intrinsics.project reads them from K
        return np.array([(x / z) * fx + cx, (y / z) * fy + cy])

    def in_image(self, pixels: np.ndarray) -> np.ndarray:
        return self.intrinsics.in_image(pixels)


def pose_homography(before: PtzCamera, after: PtzCamera) -> np.ndarray:
    """Pixels under the pose ``before`` -> pixels under ``after``, for a camera that only rotates
    and zooms about a fixed point: ``K_a R_aᵀ R_b K_b⁻¹``."""
    return after.K @ after.R.T @ before.R @ before.K_inv


def zoom_area_ratio(before: PtzCamera, after: PtzCamera) -> float:
    """How much a zoom from ``before`` to ``after`` multiplies apparent areas: ``(fx fy)_a / (fx fy)_b``."""
    return after.intrinsics.fx * after.intrinsics.fy / (before.intrinsics.fx * before.intrinsics.fy)
