"""The view's change between two pictures (ORB + RANSAC similarity), against a known warp."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from trackreplay.trackers.geometry.homography import apply_homography
from trackreplay.trackers.geometry.view_change import view_change


def _scene(seed: int = 0, size: tuple[int, int] = (720, 1280)) -> np.ndarray:
    rng = np.random.default_rng(seed)
    img = cv2.GaussianBlur(rng.integers(0, 256, (*size, 3), dtype=np.uint8), (0, 0), 3.0)
    for _ in range(60):  # corners for ORB
        x, y = int(rng.integers(0, size[1])), int(rng.integers(0, size[0]))
        cv2.rectangle(img, (x, y), (x + int(rng.integers(10, 60)), y + int(rng.integers(10, 60))),
                      tuple(int(c) for c in rng.integers(0, 256, 3)), -1)
    return img


def test_a_pan_and_zoom_is_measured_and_unrelated_pictures_are_not():
    before = _scene()
    a, t = 1.08, (-35.0, 12.0)  # zoomed in 8 % and panned
    M = np.array([[a, 0.0, t[0]], [0.0, a, t[1]]])
    after = cv2.warpAffine(before, M, (before.shape[1], before.shape[0]))
    H = view_change(before, after)
    assert H is not None
    points = np.array([[300.0, 200.0], [900.0, 500.0], [640.0, 360.0]])
    truth = points @ M[:, :2].T + M[:, 2]
    assert np.abs(apply_homography(H, points) - truth).max() < 1.5
    assert np.array_equal(H, view_change(before, after))  # deterministic
    assert view_change(before, _scene(seed=7)) is None  # another scene: no agreement


def test_both_fits_of_the_one_fitter():
    from trackreplay.trackers.geometry.view_change import at_full_size, fit_similarity

    rng = np.random.default_rng(1)
    p0 = rng.uniform(0, 400, (80, 2)).astype(np.float32)
    turn = np.array([[0.98, -0.05], [0.05, 0.98]])
    p1 = (p0 @ turn.T + [6.0, -4.0]).astype(np.float32)
    p1[:48] = rng.uniform(0, 400, (48, 2))  # 60 % wrong matches: RANSAC stands them, the medians do not
    cv2.setRNGSeed(0)
    fit = fit_similarity(p0, p1, method="ransac", ransac_px=3.0)
    cv2.setRNGSeed(0)
    M, inliers = cv2.estimateAffinePartial2D(p0, p1, method=cv2.RANSAC, ransacReprojThreshold=3.0)
    assert np.array_equal(fit.transform[:2], M) and np.array_equal(fit.inliers, inliers.ravel() == 1)
    assert np.allclose(fit.transform[:2, :2], turn, atol=1e-4) and fit.inliers[48:].all()
    clean = fit_similarity(p0[48:], p1[48:])  # the medians, on right matches
    assert np.allclose(clean.transform[:2], np.column_stack([turn, [6.0, -4.0]]), atol=1e-4) and clean.inliers.all()
    # a fit measured at a third of the size, in full-size pixels
    scaled = at_full_size(fit.transform, 1.0 / 3.0)
    assert np.allclose(scaled, np.linalg.inv(np.diag([1 / 3, 1 / 3, 1.0])) @ fit.transform @ np.diag([1 / 3, 1 / 3, 1.0]))
    with pytest.raises(ValueError, match="medians, ransac"):
        fit_similarity(p0, p1, method="lmeds")
