"""How the view moved between two pictures of the same scene, without encoders.

ORB features of both pictures (OpenCV), matched by Hamming distance with a cross-check, and a
similarity (scale, rotation, translation: a camera that pans, tilts a little and zooms) fitted to
the matches with RANSAC (``cv2.estimateAffinePartial2D``). For pictures taken frames apart, where
the per-frame trackers (Lucas-Kanade from the last position) would have to be chained. RANSAC draws
from OpenCV's generator, which the replay engine seeds (``cv2.setRNGSeed``): deterministic.
"""

from __future__ import annotations

import cv2
import numpy as np

MAX_SIDE = 640  # pictures are matched at most this wide or high (the motion is scaled back)


def _grey(image: np.ndarray) -> tuple[np.ndarray, float]:
    g = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY) if image.ndim == 3 else np.ascontiguousarray(image, np.uint8)
    s = min(1.0, MAX_SIDE / max(g.shape[:2]))
    if s < 1.0:
        g = cv2.resize(g, (max(int(round(g.shape[1] * s)), 1), max(int(round(g.shape[0] * s)), 1)), interpolation=cv2.INTER_AREA)
    return g, s


def view_change(before: np.ndarray, after: np.ndarray, min_inliers: int = 25, min_share: float = 0.3,
                features: int = 800) -> np.ndarray | None:
    """The 3x3 similarity taking pixels of ``before`` to pixels of ``after`` (same size), or None
    when fewer than ``min_inliers`` matches (or ``min_share`` of them) agree on one."""
    a, s = _grey(before)
    b, _ = _grey(after)
    orb = cv2.ORB_create(nfeatures=features)
    ka, da = orb.detectAndCompute(a, None)
    kb, db = orb.detectAndCompute(b, None)
    if da is None or db is None or len(ka) < min_inliers or len(kb) < min_inliers:
        return None
    matches = cv2.BFMatcher(cv2.NORM_HAMMING, crossCheck=True).match(da, db)
    if len(matches) < min_inliers:
        return None
    matches = sorted(matches, key=lambda m: (m.distance, m.queryIdx, m.trainIdx))  # a fixed order for RANSAC
    pa = np.float32([ka[m.queryIdx].pt for m in matches])
    pb = np.float32([kb[m.trainIdx].pt for m in matches])
    M, inliers = cv2.estimateAffinePartial2D(pa, pb, method=cv2.RANSAC, ransacReprojThreshold=3.0)
    if M is None or inliers is None:
        return None
    n = int(inliers.sum())
    if n < min_inliers or n < min_share * len(matches):
        return None
    H = np.vstack([M.astype(np.float64), [0.0, 0.0, 1.0]])
    scale = np.diag([s, s, 1.0])  # matched at scale s: full-size pixels -> scaled -> moved -> full size
    return np.linalg.inv(scale) @ H @ scale
