"""Connected foreground blobs of a binary mask, measured into named fields.

Each 8-connected blob gets its centroid, pixel area and bounding box (frame pixels: the mask's
``offset`` added) and, for the blobs worth it, its circularity ``4 π A / P²``. The perimeter ``P``
is the length of the blob's outer 8-connected contour through pixel centres with Kulpa's chain-code
weights (0.948 per straight, 1.343 per diagonal step: unbiased over edge orientations) plus ``π``
(the half-pixel ring the centre line misses). Digital discs of radius 1-20 px then score 0.8-0.96,
squares about 0.9, a single pixel 1.27 and a 2 × 20 bar 0.3.

Tracing contours costs; :func:`measure_blobs` measures the shape of blobs of at least
``min_area`` only, and of those only the ``max_measured`` nearest to a point (the prediction).
The others keep a NaN circularity.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np


@dataclass(frozen=True, eq=False)
class Blobs:
    """K blobs as parallel arrays (row k of every field is blob k, in label order)."""

    centroid: np.ndarray  # (K, 2) float64 x, y in frame pixels
    area: np.ndarray  # (K,) float64 pixels
    circularity: np.ndarray  # (K,) float64 4 pi A / P^2; NaN where not measured
    bbox: np.ndarray  # (K, 4) int64 x0, y0, w, h in frame pixels
    covariance: np.ndarray  # (K, 3) float64 sxx, syy, sxy (px²); NaN where not measured

    def __len__(self) -> int:
        return len(self.area)

    @property
    def size(self) -> np.ndarray:
        """(K, 2) bounding-box width and height."""
        return self.bbox[:, 2:]

    @property
    def measured(self) -> np.ndarray:
        """(K,) bool: the shape was measured (finite circularity)."""
        return np.isfinite(self.circularity)

    @property
    def axes(self) -> np.ndarray:
        """(K, 2) variances along the major and minor axes (eigenvalues of the covariance; NaN where not measured)."""
        cov = self.covariance
        mean = 0.5 * (cov[:, 0] + cov[:, 1])
        half = np.hypot(0.5 * (cov[:, 0] - cov[:, 1]), cov[:, 2])
        return np.stack([mean + half, mean - half], axis=1)

    @classmethod
    def empty(cls) -> Blobs:
        return cls(np.zeros((0, 2)), np.zeros(0), np.zeros(0), np.zeros((0, 4), np.int64), np.zeros((0, 3)))


def pixel_covariance(labels: np.ndarray, label: int, box: np.ndarray) -> tuple[float, float, float]:
    """``(sxx, syy, sxy)`` of the pixels of ``label`` inside ``box`` (x0, y0, w, h of the crop), each
    pixel a unit square (hence the 1/12 on the diagonal: a single pixel is not a point)."""
    x0, y0, w, h = (int(v) for v in np.asarray(box).tolist())
    return _window_covariance((labels[y0:y0 + h, x0:x0 + w] == label).view(np.uint8))


def _window_covariance(window: np.ndarray) -> tuple[float, float, float]:
    """:func:`pixel_covariance` of the set pixels of a binary uint8 window."""
    m = cv2.moments(window, binaryImage=True)
    return m["mu20"] / m["m00"] + 1 / 12, m["mu02"] / m["m00"] + 1 / 12, m["mu11"] / m["m00"]


WHOLE_MASK_PX = 48 * 48  # masks up to this many pixels are labelled whole (one OpenCV thread: ~20 µs either way)


def components(mask: np.ndarray) -> tuple[int, tuple[int, int], np.ndarray, np.ndarray, np.ndarray]:
    """``cv2.connectedComponentsWithStats(mask, connectivity=8, ltype=CV_32S)`` over the window of
    ``mask`` that holds its foreground: the label count, the window's origin ``(x, y)`` in the mask,
    the window's labels, and the blobs' stats and centroids in the mask's coordinates (the
    background's row dropped). The same numbers as over the whole mask, where OpenCV gathers the
    background's statistics over every pixel (most of the cost on a sparse mask).

    The window starts on an even row and column: OpenCV numbers the blobs in the order its scan of
    2 × 2 blocks meets them, and such a window holds the same blocks in the same order. OpenCV's
    centroid is a blob's integer coordinate sum over its area; the window's sums are recovered
    exactly by rounding centroid × area (they are far below 2^52), moved by the origin times the
    area and divided again: the quotient OpenCV computes over the whole mask."""
    if mask.size <= WHOLE_MASK_PX:  # OpenCV's statistics cost less than the window's bookkeeping here
        n, labels, stats, centroids = cv2.connectedComponentsWithStats(mask, connectivity=8, ltype=cv2.CV_32S)
        return n, (0, 0), labels, stats[1:], centroids[1:]
    x, y, w, h = cv2.boundingRect(mask)
    x0, y0 = x - x % 2, y - y % 2
    if w == 0:
        return 1, (x0, y0), np.zeros((0, 0), np.int32), np.zeros((0, 5), np.int32), np.zeros((0, 2))
    n, labels, stats, centroids = cv2.connectedComponentsWithStats(mask[y0:y + h, x0:x + w], connectivity=8,
                                                                    ltype=cv2.CV_32S)
    stats, centroids = stats[1:] + np.array([x0, y0, 0, 0, 0], np.int32), centroids[1:]
    if x0 or y0:
        area = stats[:, cv2.CC_STAT_AREA:].astype(np.float64)
        centroids = (np.rint(centroids * area) + np.array([x0, y0], np.float64) * area) / area
    return n, (x0, y0), labels, stats, centroids


SHORT_CONTOUR = 48  # points: up to this many, a Python loop beats numpy's calls


def chain_length(points: np.ndarray) -> float:
    """Kulpa's length estimate of a closed 8-connected contour given as (n, 2) points."""
    n = len(points)
    if n < 2:
        return 0.0
    if n <= SHORT_CONTOUR:  # step by step in Python (the same count): numpy's per-call cost was most of it
        pts = points.tolist()
        diagonal = 0
        px, py = pts[-1]  # the closing step, last -> first, comes first
        for x, y in pts:
            if x != px and y != py:
                diagonal += 1
            px, py = x, y
        return 0.948 * (n - diagonal) + 1.343 * diagonal
    steps = points[1:] - points[:-1]  # and the closing step, last -> first, below
    diagonal = int(np.count_nonzero((steps[:, 0] != 0) & (steps[:, 1] != 0)))
    close = points[0] - points[-1]
    diagonal += int(close[0] != 0 and close[1] != 0)
    return 0.948 * (len(points) - diagonal) + 1.343 * diagonal


def measure_blobs(mask: np.ndarray, offset: tuple[int, int] = (0, 0), *, min_area: float = 0.0,
                  max_measured: int | None = None, near: np.ndarray | None = None, moments: bool = True) -> Blobs:
    """Every 8-connected blob of the uint8 ``mask`` (a crop whose top-left is ``offset`` in the frame).

    Circularity (and, with ``moments``, the covariance) is measured for blobs with ``area >= min_area``;
    when more than ``max_measured`` qualify, only those nearest to ``near`` (frame pixels) are
    measured (ties by label order).
    """
    if mask.size == 0:
        return Blobs.empty()
    n, (wx, wy), labels, stats, centroids = components(mask)
    if n <= 1:
        return Blobs.empty()
    window = mask[wy:wy + labels.shape[0], wx:wx + labels.shape[1]]  # every blob, and what labels covers
    centre = centroids + np.array([offset[0], offset[1]], np.float64)  # (x, y) + offset, column by column
    area = stats[:, cv2.CC_STAT_AREA].astype(np.float64)
    bbox = stats[:, :4].astype(np.int64) + np.array([offset[0], offset[1], 0, 0], np.int64)
    circularity = np.full(n - 1, np.nan)
    big = np.flatnonzero(~(area < min_area))
    if max_measured is not None and big.size > max_measured:
        target = np.zeros(2) if near is None else near
        d2 = (centre[big, 0] - target[0]) ** 2 + (centre[big, 1] - target[1]) ** 2
        big = np.sort(big[np.argsort(d2, kind="stable")][:max_measured])
    big = big.tolist()
    if big:
        if len(big) == n - 1:
            measured = window
        else:
            keep = np.zeros(n, np.uint8)
            keep[np.array(big) + 1] = 1
            measured = keep[labels]
        contours, _ = cv2.findContours(measured, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
        perimeter = {}
        for contour in contours:  # one contour per measured blob (a loop over blobs, not pixels)
            px, py = contour[0, 0]
            label = int(labels[py, px]) - 1
            if label >= 0:
                perimeter[label] = chain_length(contour[:, 0, :]) + math.pi
        # Blob by blob in Python floats, as 4.0 * np.pi * area[big] / perimeter[big] ** 2 computes
        # each (NaN for a blob without its contour).
        areas = area.tolist()
        for k in big:
            p = perimeter.get(k, math.nan)
            circularity[k] = 4.0 * math.pi * areas[k] / (p * p)
    covariance = np.full((n - 1, 3), np.nan)
    if moments and big:  # the measured blobs only (a few), each within its own box
        boxes = stats[:, :4].tolist()
        for k in big:
            x0, y0, w, h = boxes[k]
            x0, y0 = x0 - wx, y0 - wy  # in the window
            # One blob: its label's pixels are the mask's (a binary image's moments see only which
            # pixels are set), without comparing the labels.
            box = window[y0:y0 + h, x0:x0 + w] if n == 2 else (labels[y0:y0 + h, x0:x0 + w] == k + 1).view(np.uint8)
            covariance[k] = _window_covariance(box)
    return Blobs(centre, area, circularity, bbox, covariance)


def nearest(points: np.ndarray, candidates: np.ndarray, to: np.ndarray) -> int:
    """Index (into ``points``) of the candidate nearest to ``to``, -1 without candidates.

    ``candidates`` is a boolean mask over the ``(K, 2)`` ``points``; ties go to the lower index.
    """
    ok = np.flatnonzero(candidates)
    if not ok.size:
        return -1
    d2 = (points[ok, 0] - to[0]) ** 2 + (points[ok, 1] - to[1]) ** 2
    return int(ok[int(np.argmin(d2))])
