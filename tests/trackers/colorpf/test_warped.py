"""Eq. (7)'s background warped only where it is read (colorpf.warped): the whole-frame grid is the full warp's
bit for bit, a crop the full warp's but for rare one-level roundings, the band the band of those pixels."""

import cv2
import numpy as np
import pytest

from trackreplay.trackers.colorpf.camera import warp
from trackreplay.trackers.colorpf.foreground import tolerance_band
from trackreplay.trackers.colorpf.warped import WarpedBackground, warped_band


def _scene(rng: np.random.Generator, height: int, width: int) -> np.ndarray:
    return cv2.GaussianBlur(rng.integers(0, 256, (height, width, 3), dtype=np.uint8), (5, 5), 1.5)


def _similarity(rng: np.random.Generator) -> np.ndarray:
    s, a = 1 + rng.normal(0, 0.03), rng.normal(0, 0.02)
    return np.array([[s * np.cos(a), -s * np.sin(a), rng.normal(0, 10)],
                     [s * np.sin(a), s * np.cos(a), rng.normal(0, 10)], [0.0, 0.0, 1.0]])


def test_the_grid_and_the_whole_are_the_full_warp_exactly():
    rng = np.random.default_rng(0)
    for height, width in ((240, 360), (101, 157), (480, 640)):
        scene = _scene(rng, height, width)
        for _ in range(5):
            t = _similarity(rng)
            full = warp(scene, t)
            lazy = WarpedBackground(scene, t)
            assert np.array_equal(lazy[::4, ::4], full[::4, ::4])
            assert np.array_equal(lazy.full(), full)


def test_a_crop_is_the_full_warps_but_for_rare_one_level_roundings():
    rng = np.random.default_rng(1)
    scene = _scene(rng, 240, 360)
    differing = total = 0
    for _ in range(40):
        t = _similarity(rng)
        full, (low, high) = warp(scene, t), tolerance_band(warp(scene, t))
        lazy = WarpedBackground(scene, t)
        band = warped_band(lazy)
        x0, y0 = int(rng.integers(0, 300)), int(rng.integers(0, 200))
        x1, y1 = x0 + int(rng.integers(1, 60)), y0 + int(rng.integers(1, 40))
        crop = lazy[y0:y1, x0:x1].astype(int)
        assert crop.shape == full[y0:y1, x0:x1].shape
        assert np.abs(crop - full[y0:y1, x0:x1]).max() <= 1
        for side, whole in ((band[0], low), (band[1], high)):
            assert np.abs(side[y0:y1, x0:x1].astype(int) - whole[y0:y1, x0:x1]).max() <= 1
        differing += int((crop != full[y0:y1, x0:x1]).sum())
        total += crop.size
    assert differing <= 0.001 * total  # 1 in 1000 pixels at most (measured: 0 here)


def test_a_whole_pixel_shift_is_copied_exactly_and_a_large_read_warps_once():
    rng = np.random.default_rng(2)
    scene = _scene(rng, 120, 160)
    t = np.array([[1.0, 0.0, 3.0], [0.0, 1.0, -2.0], [0.0, 0.0, 1.0]])
    lazy = WarpedBackground(scene, t)
    assert np.array_equal(lazy[10:50, 20:90], warp(scene, t)[10:50, 20:90])
    assert lazy[5:5, 0:10].shape == (0, 10, 3)
    assert np.array_equal(lazy[0:120, 0:100], warp(scene, t)[:, :100])  # most of the picture: the whole warp
    with pytest.raises(IndexError):
        lazy[1::4, ::4]  # a grid is read over the whole picture
