"""The disc top-hat by row segments is OpenCV's, bit for bit (the golf contrast silhouettes rest on it)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from trackreplay.trackers.foreground.morphology import disc_top_hat, ellipse_rows, top_hat_by_rows


def opencv_top_hat(y: np.ndarray, side: int) -> np.ndarray:
    return cv2.morphologyEx(y, cv2.MORPH_TOPHAT, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (side, side)))


@pytest.mark.parametrize("side", [1, 3, 7, 9, 11, 17, 19, 27, 41, 61, 121])
def test_disc_top_hat_is_opencvs(side: int) -> None:
    rng = np.random.default_rng(side)
    shapes = [(320, 320), (1, 1), (1, 200), (200, 1), (3, 50), (17, 5), (43, 43), (150, 70), (520, 320)]
    for shape in shapes:
        for smooth in (0.0, 2.0, 6.0):
            y = rng.integers(0, 256, shape, dtype=np.uint8)
            if smooth:
                y = cv2.GaussianBlur(y, (0, 0), smooth)
            y[rng.random(shape) < 0.01] = 255  # specks: what the top-hat is for
            y[rng.random(shape) < 0.01] = 0
            expected = opencv_top_hat(y, side)
            for got in (disc_top_hat(y, side), top_hat_by_rows(y, side)):  # the row form at every size too
                assert got.dtype == np.uint8 and got.shape == y.shape
                assert np.array_equal(got, expected)


def test_a_crop_of_a_frame_and_flat_images() -> None:
    rng = np.random.default_rng(7)
    frame = cv2.GaussianBlur(rng.integers(0, 256, (400, 500), dtype=np.uint8), (0, 0), 3)
    crop = frame[13:301, 27:333]  # a view with the frame's stride
    assert np.array_equal(disc_top_hat(crop, 23), opencv_top_hat(np.ascontiguousarray(crop), 23))
    for value in (0, 17, 255):
        flat = np.full((60, 80), value, np.uint8)
        assert np.array_equal(disc_top_hat(flat, 31), opencv_top_hat(flat, 31))


def test_ellipse_rows_are_the_kernels_rows() -> None:
    for side in range(1, 122, 2):
        rows = ellipse_rows(side)
        kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (side, side))
        rebuilt = np.zeros_like(kernel)
        for i, k in enumerate(rows):
            if k >= 0:
                rebuilt[i, side // 2 - k:side // 2 + k + 1] = 1
        assert np.array_equal(rebuilt, kernel)
    assert ellipse_rows(10) is None  # even: OpenCV's anchor is not the centre of a row
