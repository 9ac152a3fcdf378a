import numpy as np

from trackreplay.trackers.appearance.color import HSV_RANGES, to_hsv, to_ycbcr
from trackreplay.trackers.appearance.histogram import colour_histogram, intersection, mix


def test_histogram_matches_numpy_histogramdd() -> None:
    rng = np.random.default_rng(0)
    hsv = to_hsv(rng.integers(0, 256, (40, 30, 3), dtype=np.uint8))
    ours = colour_histogram(hsv, (10, 10), HSV_RANGES[:2])
    ref, _ = np.histogramdd(hsv.reshape(-1, 3)[:, :2].astype(float), bins=(10, 10), range=HSV_RANGES[:2])
    np.testing.assert_allclose(ours, ref / ref.sum())


def test_mask_selects_pixels_and_intersection_bounds() -> None:
    img = np.zeros((10, 10, 3), np.uint8)
    img[:, 5:] = (0, 0, 255)  # red in BGR
    hsv = to_hsv(img)
    left = colour_histogram(hsv, (10, 10), HSV_RANGES[:2], mask=np.arange(10)[None, :].repeat(10, 0) < 5)
    right = colour_histogram(hsv, (10, 10), HSV_RANGES[:2], mask=np.arange(10)[None, :].repeat(10, 0) >= 5)
    assert intersection(left, left) == 1.0
    assert intersection(left, right) == 0.0
    assert np.isclose(intersection(np.stack([left, right]), mix((0.5, 0.5), (left, right))), 0.5).all()


def test_ycbcr_order_is_y_cb_cr() -> None:
    blue = np.zeros((1, 1, 3), np.uint8)
    blue[..., 0] = 255
    y, cb, cr = to_ycbcr(blue)[0, 0]
    assert cb > 200 and cr < 128 and y < 64
