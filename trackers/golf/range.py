"""Range from the ball's apparent area: the EKF's third measurement (seed 000, §2.3).

A ball of known diameter ``D`` that covers ``A`` pixels is ``r = f D / d`` away, with
``d = 2 √(A/π)`` its apparent diameter and ``f = √(fx fy)``. Two corrections make this usable on a
ball only a few pixels across:

- **photometric area** (:func:`photometric_area`): the light the ball adds over the local
  background, divided by the contrast of a fully covered pixel (learnt on the marked ball at the
  start), instead of the silhouette's pixel count, which keeps only the brightest pixels;
- **calibration** (:meth:`RangeFromArea.calibrate`): where the start box is a ball resting on the
  ground, its line of sight meets the ground plane at the true range; the ratio corrects every
  later range (the silhouette of a small ball is not exactly its disc: blur, JPEG, the LUT's cut).

Ours: once the filter has the ball rolling on the ground, the same intersection *is* the range
(:meth:`RangeFromArea.on_ground`, to the ground's flatness), far tighter than any area.
"""

from __future__ import annotations

import math

import numpy as np

from trackreplay.trackers.geometry.ptz import PtzCamera
from trackreplay.trackers.golf.config import RangeConfig
from trackreplay.trackers.median import median

MAX_CALIBRATION_RANGE_M = 1000.0


def range_from_area(area_px: float, camera: PtzCamera, diameter_m: float) -> float:
    """Distance to a ball of diameter ``diameter_m`` that covers ``area_px`` pixels."""
    k = camera.intrinsics
    d = 2.0 * math.sqrt(max(area_px, 1e-9) / math.pi)
    return math.sqrt(k.fx * k.fy) * diameter_m / d


def range_rel_sigma(area_px: float, rel: float) -> float:
    """Relative range uncertainty: a floor ``rel`` plus +-0.7 px on the apparent diameter.

    The filter multiplies it by its *predicted* range: scaling by the measured range would
    trust short measurements more than long ones and pull the estimate short.
    """
    d = 2.0 * math.sqrt(max(area_px, 1e-9) / math.pi)
    return math.sqrt(rel * rel + (0.7 / d) ** 2)


def photometric_area(y: np.ndarray, cx: float, cy: float, radius: float, ball_luminance: float) -> float:
    """Apparent area of a small bright ball from the light it adds, robust to blur and sub-pixel size.

    The silhouette of a 2-4 px ball keeps only its brightest pixels (the LUT cannot tell a blended
    edge pixel from a cloud), so its pixel count says little about its size. The luminance it adds
    over the local background, ``sum(Y - bg)`` inside ``radius`` of ``(cx, cy)`` (crop pixels), is
    preserved by blur and JPEG; divided by the contrast of a fully covered pixel
    (``ball_luminance - bg``, learnt from the large marked ball at the start) it is the area.
    ``bg`` is the median of a 3 px ring outside ``radius``. NaN when there is no usable contrast.
    """
    r_out = radius + 3.0
    h, w = y.shape
    floor, ceil = math.floor, math.ceil  # the integers int(np.floor(...)), int(np.ceil(...)) give (and their errors)
    x0, x1 = max(0, floor(cx - r_out)), min(w, ceil(cx + r_out) + 1)
    y0, y1 = max(0, floor(cy - r_out)), min(h, ceil(cy + r_out) + 1)
    if x1 <= x0 or y1 <= y0:
        return float("nan")
    win = y[y0:y1, x0:x1].astype(np.float64)
    d2 = (np.arange(x0, x1) - cx)[None, :] ** 2 + (np.arange(y0, y1) - cy)[:, None] ** 2  # as np.mgrid's, broadcast
    inner, ring = d2 <= radius * radius, (d2 > radius * radius) & (d2 <= r_out * r_out)
    if not ring.any() or not inner.any():
        return float("nan")
    bg = median(win[ring])
    contrast = ball_luminance - bg
    if contrast < 10.0:
        return float("nan")
    return float(np.maximum(win[inner] - bg, 0.0).sum() / contrast)


def ground_range(camera: PtzCamera, pixel: np.ndarray, centre_height_m: float) -> float | None:
    """Distance along ``pixel``'s line of sight to a ball lying on the ground (its centre
    ``centre_height_m`` up), or None when that line does not come down to the ground in front of
    the camera within ``MAX_CALIBRATION_RANGE_M``."""
    los = camera.line_of_sight(np.asarray(pixel, dtype=np.float64).reshape(1, 2))[0]
    height = camera.position[2] - centre_height_m
    if los[2] >= -1e-6 or height <= 0:
        return None
    r = height / -float(los[2])
    return r if r <= MAX_CALIBRATION_RANGE_M else None


def nearer_than_predicted(range_m: float, position: np.ndarray, covariance: np.ndarray, viewpoint: np.ndarray,
                          factor: float, sigmas: float = 3.0) -> bool:
    """A ball seen at ``range_m`` is more than ``factor`` times nearer than a predicted 3-D
    ``position`` (with its 3 x 3 ``covariance``) allows, seen from ``viewpoint``: nearer than the
    predicted range less ``sigmas`` of its spread along the line of sight, divided by ``factor``."""
    offset = np.asarray(position, float) - np.asarray(viewpoint, float)
    predicted = float(np.linalg.norm(offset))
    if not predicted > 0 or not math.isfinite(range_m):
        return False
    along = offset / predicted
    spread = math.sqrt(max(float(along @ np.asarray(covariance, float) @ along), 0.0))
    return range_m * factor < predicted - sigmas * spread


class RangeFromArea:
    """Range measurements of one ball: the area to use, the calibrated range and its uncertainty."""

    def __init__(self, config: RangeConfig, diameter_m: float) -> None:
        self.config = config
        self.diameter_m = diameter_m
        self.scale = 1.0  # the calibration (1: none)
        self.ball_luminance = math.nan  # mean Y of the marked ball's silhouette (photometric area)

    def learn_ball(self, y: np.ndarray, mask: np.ndarray) -> None:
        """The luminance of a fully covered pixel: the mean ``y`` under the marked ball's silhouette."""
        inside = mask.astype(bool)
        if inside.any():
            self.ball_luminance = float(y[inside].mean())

    def area(self, y: np.ndarray, centre: np.ndarray, size: np.ndarray, silhouette_area: float) -> float:
        """The ball's area: photometric when it can be, else the silhouette's pixel count.

        ``y`` is the crop's luminance, ``centre`` the blob's centroid in crop pixels, ``size`` its
        bounding box (w, h).
        """
        area = silhouette_area
        if self.config.photometric and np.isfinite(self.ball_luminance):
            radius = max(3.0, 0.75 * max(float(size[0]), float(size[1])) + 2.0)
            photo = photometric_area(y, float(centre[0]), float(centre[1]), radius, self.ball_luminance)
            if np.isfinite(photo) and photo > 0.5 * area:
                area = photo
        return area

    def measure(self, area: float, camera: PtzCamera) -> tuple[float, float]:
        """Range (m, calibrated) and its relative sigma for a ball of ``area`` pixels."""
        return self.scale * range_from_area(area, camera, self.diameter_m), range_rel_sigma(area, self.config.rel_sigma)

    def on_ground(self, camera: PtzCamera, pixel: np.ndarray) -> tuple[float, float] | None:
        """Range (m) and relative sigma of a ball known to lie on the ground at ``pixel``: where its
        line of sight meets the ground (``ground_sigma``; None when it does not)."""
        r = ground_range(camera, pixel, self.diameter_m / 2.0)
        return None if r is None else (r, self.config.ground_sigma)

    def calibrate(self, camera: PtzCamera, pixel: np.ndarray, area: float) -> None:
        """Correct later ranges by the ground-plane range of a ball resting at ``pixel`` (of ``area`` px).

        No correction when that line of sight does not meet the ground in front of the camera within
        1 km; the correction is clamped to [0.5, 2].
        """
        true_range = ground_range(camera, pixel, self.diameter_m / 2.0)
        if true_range is None:
            self.scale = 1.0
            return
        self.scale = float(np.clip(true_range / range_from_area(area, camera, self.diameter_m), 0.5, 2.0))
