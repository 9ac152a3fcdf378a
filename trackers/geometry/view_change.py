"""How the view moved between two pictures of the same scene: the one similarity fitter.

A camera that pans, tilts a little and zooms moves the scene by a similarity (scale, rotation,
translation). :func:`fit_similarity` fits one to matched points ``p0 -> p1`` in one of two ways,
each kept by its caller on purpose (they give different numbers):

- ``"medians"`` (deterministic, no random draw): scale, turn and shift as medians over the points,
  then least-squares refits on the points within 3x the median residual. A minority of other movers
  (under half the points) does not move it. The colour PF's camera motion (Lucas-Kanade corners
  against a key frame, ``colorpf.camera``) fits with it, every frame.
- ``"ransac"``: OpenCV's RANSAC (``cv2.estimateAffinePartial2D``), which stands a majority of wrong
  matches. :func:`view_change` fits with it: ORB features of both pictures (OpenCV), matched by
  Hamming distance with a cross-check, for pictures taken frames apart, where the per-frame
  trackers would have to be chained. RANSAC draws from OpenCV's generator, which the replay engine
  seeds (``cv2.setRNGSeed``): deterministic.

Both measure on smaller pictures when the frame is large; :func:`at_full_size` takes the fit back
to the frame's pixels.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from trackreplay.trackers.appearance.color import to_grey
from trackreplay.trackers.median import median

MAX_SIDE = 640  # view_change matches pictures at most this wide or high (the motion is scaled back)
MIN_BASELINE = 20.0  # px: points closer than this to the median say little about scale and rotation
FIT_METHODS = ("medians", "ransac")


@dataclass(frozen=True, eq=False)
class SimilarityFit:
    """A fitted similarity: ``transform`` (3x3, p1 ~ T p0; None when RANSAC found none) and the
    points it was fitted to (``inliers``, bool per point)."""

    transform: np.ndarray | None
    inliers: np.ndarray


def apply(transform: np.ndarray, xy: np.ndarray) -> np.ndarray:
    """Points ``xy`` (n, 2) moved by a 3x3 similarity (or affine) ``transform``."""
    xy = np.asarray(xy, np.float64).reshape(-1, 2)
    return xy @ transform[:2, :2].T + transform[:2, 2]


def at_full_size(transform: np.ndarray, scale: float) -> np.ndarray:
    """A transform measured on pictures scaled by ``scale``, in the full-size pictures' pixels
    (full size -> scaled -> moved -> full size)."""
    return np.diag([1.0 / scale, 1.0 / scale, 1.0]) @ transform @ np.diag([scale, scale, 1.0])


def least_squares_similarity(p0: np.ndarray, p1: np.ndarray) -> np.ndarray:
    """Least-squares ``x' = a x - b y + tx, y' = b x + a y + ty`` (3x3), in closed form: about the
    points' means the normal equations separate into ``a`` (dot products) and ``b`` (cross products)."""
    c0, c1 = p0.mean(axis=0), p1.mean(axis=0)
    q0, q1 = p0 - c0, p1 - c1
    spread = float(np.einsum("ij,ij->", q0, q0))
    if spread <= 0.0:  # all points on one spot: a translation
        a, b = 1.0, 0.0
    else:
        a = float(np.einsum("ij,ij->", q0, q1)) / spread
        b = float((q0[:, 0] * q1[:, 1] - q0[:, 1] * q1[:, 0]).sum()) / spread
    t = c1 - np.array([a * c0[0] - b * c0[1], b * c0[0] + a * c0[1]])
    return np.array([[a, -b, t[0]], [b, a, t[1]], [0.0, 0.0, 1.0]])


def _column_medians(xy: np.ndarray) -> np.ndarray:
    """``np.median(xy, axis=0)`` of (n, 2) points."""
    return np.array([median(xy[:, 0]), median(xy[:, 1])])


def median_similarity(p0: np.ndarray, p1: np.ndarray, min_baseline: float = MIN_BASELINE) -> np.ndarray:
    """Scale and rotation as the medians over the points of their distance ratio and turn about the
    points' (per-axis) median (points at least ``min_baseline`` from it), then the median
    translation: each a median, so a minority of other movers does not move it. O(n)."""
    v0, v1 = p0 - _column_medians(p0), p1 - _column_medians(p1)
    n0, n1 = np.hypot(*v0.T), np.hypot(*v1.T)
    far = n0 >= min_baseline
    scale, angle = 1.0, 0.0
    if np.count_nonzero(far) >= 3:
        scale = median(n1[far] / n0[far])
        u0, u1 = v0[far], v1[far]  # the turn from u0 to u1, in (-pi, pi]
        turn = np.arctan2(u0[:, 0] * u1[:, 1] - u0[:, 1] * u1[:, 0], (u0 * u1).sum(axis=1))
        angle = median(turn)
    a, b = scale * np.cos(angle), scale * np.sin(angle)
    linear = np.array([[a, -b], [b, a]])
    t = _column_medians(p1 - p0 @ linear.T)
    return np.array([[a, -b, t[0]], [b, a, t[1]], [0.0, 0.0, 1.0]])


def _refined(p0: np.ndarray, p1: np.ndarray, rounds: int, min_baseline: float) -> SimilarityFit:
    """From the medians (:func:`median_similarity`), each round keeps the points within 3x the median
    residual (at least 1 px) and refits by least squares."""
    transform = median_similarity(p0, p1, min_baseline)
    kept = None
    for _ in range(rounds):
        r = np.hypot(*(apply(transform, p0) - p1).T)
        keep = r <= max(3.0 * median(r), 1.0)
        if np.count_nonzero(keep) < 3 or (kept is not None and np.array_equal(keep, kept)):
            break  # the same points would give the same fit
        transform, kept = least_squares_similarity(p0[keep], p1[keep]), keep
    return SimilarityFit(transform, np.ones(len(p0), bool) if kept is None else kept)


def fit_similarity(p0: np.ndarray, p1: np.ndarray, *, method: str = "medians", rounds: int = 3,
                   min_baseline: float = MIN_BASELINE, ransac_px: float = 3.0) -> SimilarityFit:
    """A similarity ``p1 ~ T p0`` robust to wrong matches, by ``method`` (see the module's text):
    ``"medians"`` with up to ``rounds`` least-squares refits; ``"ransac"`` with inliers within
    ``ransac_px`` of the fit."""
    if method not in FIT_METHODS:
        raise ValueError(f"fit_similarity: method is one of {', '.join(FIT_METHODS)}, not {method!r}")
    if method == "medians":
        p0, p1 = np.asarray(p0, np.float64).reshape(-1, 2), np.asarray(p1, np.float64).reshape(-1, 2)
        return _refined(p0, p1, rounds, min_baseline)
    M, inliers = cv2.estimateAffinePartial2D(p0, p1, method=cv2.RANSAC, ransacReprojThreshold=ransac_px)
    if M is None or inliers is None:
        return SimilarityFit(None, np.zeros(len(p0), bool))
    return SimilarityFit(np.vstack([M.astype(np.float64), [0.0, 0.0, 1.0]]), inliers.ravel() != 0)


def _grey(image: np.ndarray) -> tuple[np.ndarray, float]:
    g = to_grey(image)
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
    fit = fit_similarity(pa, pb, method="ransac", ransac_px=3.0)
    if fit.transform is None:
        return None
    n = int(np.count_nonzero(fit.inliers))
    if n < min_inliers or n < min_share * len(matches):
        return None
    return at_full_size(fit.transform, s)
