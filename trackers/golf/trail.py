"""The trajectory so far, for drawing (seed 000, §2; docs/papers.md §2: lines of sight drawn into any later pose).

Each measured position keeps its pixel and, with a camera pose, its line of sight; a camera that
only rotates needs no depth to draw the stored directions into the image of its pose *now*.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field

import numpy as np

from trackreplay.trackers.base import NOT_HASHED
from trackreplay.trackers.geometry.ptz import PtzCamera


class Ring:
    """The last ``capacity`` rows of a growing table, without per-frame reallocation."""

    def __init__(self, capacity: int, width: int) -> None:
        self.data = np.full((max(capacity, 1), width), np.nan)
        self.count = 0

    def __len__(self) -> int:
        return min(self.count, len(self.data))

    def append(self, row) -> None:
        self.data[self.count % len(self.data)] = row
        self.count += 1

    def ordered(self) -> np.ndarray:
        """Oldest first (a new array: safe to keep in the intermediates)."""
        n, cap = len(self), len(self.data)
        if self.count <= cap:
            return self.data[:n].copy()
        k = self.count % cap
        return np.concatenate([self.data[k:], self.data[:k]])


class Trail:
    """Past measured pixels with their lines of sight, and past EKF positions."""

    def __init__(self, capacity: int) -> None:
        self.image = Ring(capacity, 5)  # x, y, dx, dy, dz (NaN directions without a pose)
        self.world = Ring(capacity, 3)

    def add(self, measured: tuple[float, float] | None, line_of_sight: np.ndarray, ekf_x: np.ndarray | None) -> None:
        """This frame's measured pixel (None: not measured) and its line of sight, and the EKF's state (None: none)."""
        if measured is not None:
            self.image.append((measured[0], measured[1], line_of_sight[0], line_of_sight[1], line_of_sight[2]))
        if ekf_x is not None:
            self.world.append(ekf_x[:3])

    def in_image(self, camera: PtzCamera | None) -> np.ndarray:
        """(K, 2) past measurements drawn into this frame (:func:`drawn_into`)."""
        return drawn_into(self.image.ordered(), camera)

    def points(self, camera: PtzCamera | None) -> TrailPoints:
        """This frame's intermediates: the trail as stored, drawn into ``camera``'s image when read."""
        return TrailPoints.of(self.image.ordered(), self.world.ordered(), camera)


def drawn_into(measured: np.ndarray, camera: PtzCamera | None) -> np.ndarray:
    """(K, 2) measured rows ``(x, y, dx, dy, dz)`` drawn into ``camera``'s image: stored lines of
    sight projected with this pose (the stored pixel where there is no pose)."""
    if not len(measured):
        return np.zeros((0, 2))
    if camera is None:
        return measured[:, :2].copy()
    has = np.isfinite(measured[:, 2])
    if has.all():  # every point has its line of sight (the usual case with encoders): all projected
        return camera.project_directions(np.ascontiguousarray(measured[:, 2:5]))  # the rows measured[has, 2:5] copies
    out = measured[:, :2].copy()
    if has.any():
        out[has] = camera.project_directions(measured[has, 2:5])
    return out


@dataclass(frozen=True, eq=False)
class TrailPoints:
    """The trail's intermediates. ``image`` (the measured positions drawn into this frame's pose)
    is only drawn: projected on first read from ``measured``, which the digest hashes."""

    measured: np.ndarray  # (K, 5) past measured pixels x, y and their lines of sight dx, dy, dz (NaN: no pose)
    world: np.ndarray  # (K, 3) past EKF positions
    camera: PtzCamera | None = field(default=None, repr=False, metadata=NOT_HASHED)  # the pose they are drawn into

    @classmethod
    def of(cls, measured: np.ndarray, world: np.ndarray, camera: PtzCamera | None) -> TrailPoints:
        return cls(measured, world, camera)

    @classmethod
    def empty(cls) -> TrailPoints:
        return cls(np.zeros((0, 5)), np.zeros((0, 3)))

    @functools.cached_property
    def image(self) -> np.ndarray:
        """(K, 2) past measured positions drawn into this frame's pose (:func:`drawn_into`)."""
        return drawn_into(self.measured, self.camera)
