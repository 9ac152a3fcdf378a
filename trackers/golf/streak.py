"""Ours: the whole motion streak of which a measured blob is only the bright end.

A ball moving fast during the exposure is a streak, as bright at each point as the time the ball
spent there: going up after a bounce (or climbing at launch) it slows, and the streak's far end is
brighter than the rest. A silhouette with one threshold (the LUT's classes, the contrast silhouette's
level) then keeps that end alone, and its centroid is the ball's position late in the exposure, not
at its middle (synthetic 1080p tee shot: 14-17 px off on the two frames after the hop, with the
streak 8 x 48 px and the blob 8 x 12).

:func:`whole_streak` grows the blob by hysteresis (as Canny does for edges; scikit-image's
``apply_hysteresis_threshold``): the pixels of the white top-hat above a lower level, connected to
the blob, are the streak. The grown region's centroid replaces the blob's only when the region is
a streak this ball can make: much larger than the blob, and no longer than the predicted motion
allows (:func:`~trackreplay.trackers.golf.blobs.streak_excess`). Otherwise nothing changes.
"""

from __future__ import annotations

from collections.abc import Callable

import cv2
import numpy as np

from trackreplay.trackers.foreground.blobs import Blobs, measure_blobs
from trackreplay.trackers.golf.blobs import ApparentMotion, streak_excess
from trackreplay.trackers.golf.config import BlobConfig
from trackreplay.trackers.median import median_and_mad


def whole_streak(top_hat: Callable[[], np.ndarray], blob_pixels: np.ndarray, corner: tuple[int, int], offset: tuple[int, int],
                 motion: ApparentMotion | None, diameter: float, cfg: BlobConfig, scale: float, *, low_fraction: float = 0.35,
                 noise_sigmas: float = 4.0, min_growth: float = 1.5) -> np.ndarray | None:
    """The centroid (frame pixels) of the streak the blob belongs to, or None (keep the blob's).

    ``top_hat()``: the search crop's white top-hat (uint8), top-left ``offset`` in the frame (asked
    for only when a streak is expected);
    ``blob_pixels``: the blob's pixels (bool) in its bounding box, whose top-left is ``corner`` in
    the frame. The lower level: ``low_fraction`` of the blob's median top-hat, and at least
    ``noise_sigmas`` robust sigmas above the crop's median."""
    if motion is None or not blob_pixels.any() or not float(np.hypot(*motion.velocity)) >= diameter:
        return None  # (no streak is expected of a ball predicted to move less than its diameter)
    hat = top_hat()
    if hat.size == 0:
        return None
    bx, by = corner[0] - offset[0], corner[1] - offset[1]
    bh, bw = blob_pixels.shape
    if bx < 0 or by < 0 or by + bh > hat.shape[0] or bx + bw > hat.shape[1]:
        return None
    level = float(np.median(hat[by:by + bh, bx:bx + bw][blob_pixels]))
    med, mad = median_and_mad(hat, 0, 256)
    low = max(low_fraction * level, med + noise_sigmas * 1.4826 * mad, 1.0)
    # only as far from the blob as the ball moves in a frame (and a diameter): the streak cannot be longer
    reach = int(np.ceil(float(np.hypot(*motion.velocity)) + 3.0 * motion.sigma + diameter))
    x0, y0 = max(bx - reach, 0), max(by - reach, 0)
    x1, y1 = min(bx + bw + reach, hat.shape[1]), min(by + bh + reach, hat.shape[0])
    grown = (hat[y0:y1, x0:x1] >= low).astype(np.uint8)
    n, labels = cv2.connectedComponents(grown, connectivity=8)
    if n <= 1:
        return None
    ids = np.unique(labels[by - y0:by - y0 + bh, bx - x0:bx - x0 + bw][blob_pixels])
    ids = ids[ids > 0]
    if ids.size != 1:  # the blob's pixels under the lower level, or split: nothing to grow
        return None
    region = (labels == ids[0]).astype(np.uint8)
    streak = measure_blobs(region, (offset[0] + x0, offset[1] + y0))
    if len(streak) != 1 or streak.area[0] < min_growth * float(blob_pixels.sum()):
        return None
    if not streak_excess(streak, motion, cfg, scale)[0] <= 1.0:  # longer than this ball can smear (or unmeasured)
        return None
    if not along_the_motion(streak, blob_pixels, corner, motion.velocity):
        return None
    return streak.centroid[0]


def along_the_motion(streak: Blobs, blob_pixels: np.ndarray, corner: tuple[int, int], velocity: np.ndarray,
                     max_angle_deg: float = 30.0, min_elongation: float = 1.5) -> bool:
    """The grown region is a streak of this motion: elongated (major over minor axis at least
    ``min_elongation``) within ``max_angle_deg`` of the velocity, and the centre moved from the blob's
    along it (sideways by at most 1.5 px and a fifth of the move). (A review: on a repeated picture
    of a round ball the lagging prediction still expected a streak, and the region grown into a
    bunker beside the ball moved the measurement 20 px sideways.)"""
    u = np.asarray(velocity, float) / float(np.hypot(*velocity))
    major, minor = (float(v) for v in streak.axes[0])
    if not major >= min_elongation ** 2 * max(minor, 1e-9):
        return False
    sxx, syy, sxy = (float(v) for v in streak.covariance[0])
    angle = 0.5 * np.arctan2(2.0 * sxy, sxx - syy)  # the major axis's direction
    if abs(float(np.cos(angle) * u[0] + np.sin(angle) * u[1])) < np.cos(np.radians(max_angle_deg)):
        return False
    ys, xs = np.nonzero(blob_pixels)
    shift = streak.centroid[0] - np.array([corner[0] + xs.mean(), corner[1] + ys.mean()])
    sideways = abs(float(shift[0] * u[1] - shift[1] * u[0]))
    return sideways <= 1.5 + 0.2 * float(np.hypot(*shift))
