"""Foreground blobs of the silhouette, gated by area and circularity (seed 000, §2.1).

Each blob gets its pixel area and circularity ``4 pi A / P^2``. The perimeter ``P`` is the
length of the blob's outer 8-connected contour through pixel centres with Kulpa's chain-code
weights (0.948 per straight, 1.343 per diagonal step: unbiased over edge orientations) plus
``pi`` (the half-pixel ring the centre line misses). Digital discs of radius 1-20 px then score
0.8-0.96, squares about 0.9, a single pixel 1.27, and a 2 x 20 bar 0.3. Blobs far from the target values are dropped; the
targets follow the blobs selected as the ball in past frames (an exponential moving average of
log-area and circularity), so a zoom change is followed. Among the survivors the one nearest to
the predicted position is the ball.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

REASONS = ("ok", "tiny", "area_small", "area_large", "circularity", "excess")
OK, TINY, AREA_SMALL, AREA_LARGE, CIRCULARITY, EXCESS = range(len(REASONS))
BLOB_COLUMNS = ("cx", "cy", "area", "circularity", "accepted", "reason", "w", "h")


@dataclass(frozen=True)
class BlobTargets:
    """Target area (px) and circularity that candidates are gated against."""

    area: float
    circularity: float

    def follow(self, area: float, circularity: float, rate: float) -> BlobTargets:
        """EMA towards a newly selected ball blob (log domain for the area: zoom is multiplicative)."""
        log_area = (1 - rate) * np.log(self.area) + rate * np.log(max(area, 1e-6))
        return BlobTargets(float(np.exp(log_area)), float((1 - rate) * self.circularity + rate * circularity))


def chain_length(points: np.ndarray) -> float:
    """Kulpa's length estimate of a closed 8-connected contour given as (n, 2) points."""
    if len(points) < 2:
        return 0.0
    steps = np.abs(np.diff(np.vstack([points, points[:1]]), axis=0))
    diagonal = int(np.count_nonzero((steps[:, 0] > 0) & (steps[:, 1] > 0)))
    return 0.948 * (len(points) - diagonal) + 1.343 * diagonal


def measure_blobs(mask: np.ndarray, offset: tuple[int, int], predicted: np.ndarray, *,
                  min_area: float, max_blobs: int) -> np.ndarray:
    """Rows ``BLOB_COLUMNS`` for every 8-connected blob of ``mask`` (frame coordinates).

    Blobs smaller than ``min_area`` are marked ``tiny``; of the rest only the ``max_blobs``
    nearest to ``predicted`` are measured (circularity), the others are marked ``excess``.
    ``accepted`` is 0 here; :func:`gate` fills it.
    """
    if mask.size == 0:
        return np.zeros((0, len(BLOB_COLUMNS)))
    n, labels, stats, centroids = cv2.connectedComponentsWithStats(mask, connectivity=8, ltype=cv2.CV_32S)
    if n <= 1:
        return np.zeros((0, len(BLOB_COLUMNS)))
    stats, centroids = stats[1:], centroids[1:]
    rows = np.zeros((n - 1, len(BLOB_COLUMNS)))
    rows[:, 0] = centroids[:, 0] + offset[0]
    rows[:, 1] = centroids[:, 1] + offset[1]
    rows[:, 2] = stats[:, cv2.CC_STAT_AREA]
    rows[:, 3] = np.nan
    rows[:, 5] = OK
    rows[:, 6] = stats[:, cv2.CC_STAT_WIDTH]
    rows[:, 7] = stats[:, cv2.CC_STAT_HEIGHT]
    tiny = rows[:, 2] < min_area
    rows[tiny, 5] = TINY
    big = np.flatnonzero(~tiny)
    if big.size > max_blobs:
        d2 = (rows[big, 0] - predicted[0]) ** 2 + (rows[big, 1] - predicted[1]) ** 2
        order = big[np.argsort(d2, kind="stable")]
        rows[order[max_blobs:], 5] = EXCESS
        big = np.sort(order[:max_blobs])
    if big.size == 0:
        return rows
    if big.size == n - 1:
        measured = mask
    else:
        keep = np.zeros(n, np.uint8)
        keep[big + 1] = 1
        measured = keep[labels]
    contours, _ = cv2.findContours(measured, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    perimeter = np.full(n - 1, np.nan)
    for contour in contours:
        px, py = contour[0, 0]
        label = labels[py, px] - 1
        if label >= 0:
            perimeter[label] = chain_length(contour[:, 0, :]) + np.pi
    rows[big, 3] = 4.0 * np.pi * rows[big, 2] / perimeter[big] ** 2
    return rows


def gate(rows: np.ndarray, targets: BlobTargets, *, area_tolerance: float, circularity_tolerance: float,
         widen: float = 1.0, area_slack: float = 0.0) -> np.ndarray:
    """Fill ``accepted`` and ``reason`` of measured rows in place; returns ``rows``.

    Area passes when ``(target+s)/tol' <= area+s <= (target+s)*tol'`` with ``log tol' = widen * log tol``
    and ``s = area_slack`` (which keeps a 1-2 px ball from failing against a 3 px target)
    (the tracker widens after misses: the ball may have changed size while unseen);
    circularity passes when ``circ >= target - circularity_tolerance`` (shape does not change with zoom).
    """
    if not len(rows):
        return rows
    live = rows[:, 5] == OK
    lim = widen * np.log(area_tolerance)
    ratio = np.log((rows[:, 2] + area_slack) / (targets.area + area_slack))
    small = live & (ratio < -lim)
    large = live & (ratio > lim)
    rows[small, 5] = AREA_SMALL
    rows[large, 5] = AREA_LARGE
    live &= ~(small | large)
    round_enough = rows[:, 3] >= targets.circularity - circularity_tolerance
    rows[live & ~round_enough, 5] = CIRCULARITY
    rows[:, 4] = (rows[:, 5] == OK).astype(np.float64)
    return rows


def nearest(rows: np.ndarray, predicted: np.ndarray) -> int:
    """Index of the accepted blob nearest to the prediction, or -1."""
    if not len(rows):
        return -1
    ok = np.flatnonzero(rows[:, 4] > 0)
    if not ok.size:
        return -1
    d2 = (rows[ok, 0] - predicted[0]) ** 2 + (rows[ok, 1] - predicted[1]) ** 2
    return int(ok[int(np.argmin(d2))])


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
    x0, x1 = max(0, int(np.floor(cx - r_out))), min(w, int(np.ceil(cx + r_out)) + 1)
    y0, y1 = max(0, int(np.floor(cy - r_out))), min(h, int(np.ceil(cy + r_out)) + 1)
    if x1 <= x0 or y1 <= y0:
        return float("nan")
    win = y[y0:y1, x0:x1].astype(np.float64)
    ys, xs = np.mgrid[y0:y1, x0:x1]
    d2 = (xs - cx) ** 2 + (ys - cy) ** 2
    inner, ring = d2 <= radius * radius, (d2 > radius * radius) & (d2 <= r_out * r_out)
    if not ring.any() or not inner.any():
        return float("nan")
    bg = float(np.median(win[ring]))
    contrast = ball_luminance - bg
    if contrast < 10.0:
        return float("nan")
    return float(np.maximum(win[inner] - bg, 0.0).sum() / contrast)
