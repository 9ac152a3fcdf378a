"""The view's change between two pictures (ORB + RANSAC similarity), against a known warp."""

from __future__ import annotations

import cv2
import numpy as np

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
