"""Connected blobs measured into named fields: centroid, area, circularity, box."""

import cv2
import numpy as np
import pytest

from trackreplay.trackers.foreground import blobs as blobs_module
from trackreplay.trackers.foreground.blobs import Blobs, chain_length, components, measure_blobs, nearest


def test_fields_of_a_disc_in_a_crop_are_in_frame_pixels():
    m = np.zeros((60, 80), np.uint8)
    cv2.circle(m, (30, 20), 5, 1, -1)  # area 81, box 11 x 11
    blobs = measure_blobs(m, (100, 200))
    assert isinstance(blobs, Blobs) and len(blobs) == 1
    assert blobs.centroid[0] == pytest.approx([130.0, 220.0])
    assert blobs.area[0] == 81
    assert blobs.bbox[0].tolist() == [125, 215, 11, 11]
    assert blobs.size[0].tolist() == [11, 11]
    assert 0.8 < blobs.circularity[0] < 1.05 and blobs.measured[0]


def test_circularity_of_discs_bars_and_single_pixels():
    for r in (2, 3, 5, 8, 15):
        m = np.zeros((60, 60), np.uint8)
        cv2.circle(m, (30, 30), r, 1, -1)
        circ = measure_blobs(m).circularity[0]
        assert 0.75 < circ < 1.1, (r, circ)
    m = np.zeros((60, 60), np.uint8)
    m[10:12, 5:45] = 1
    assert measure_blobs(m).circularity[0] < 0.35
    m = np.zeros((5, 5), np.uint8)
    m[2, 2] = 1
    assert measure_blobs(m).circularity[0] == pytest.approx(4 * np.pi / np.pi**2)  # perimeter pi: 1.27


def test_kulpa_length_of_a_square_contour():
    square = np.array([[0, 0], [1, 0], [2, 0], [2, 1], [2, 2], [1, 2], [0, 2], [0, 1]])
    assert chain_length(square) == pytest.approx(8 * 0.948)
    assert chain_length(np.array([[0, 0], [1, 1]])) == pytest.approx(2 * 1.343)


def test_small_and_far_blobs_keep_no_shape():
    m = np.zeros((100, 400), np.uint8)
    for k in range(60):
        m[10 + (k // 30) * 40 : 13 + (k // 30) * 40, 5 + 12 * (k % 30) : 8 + 12 * (k % 30)] = 1
    m[90, 390] = 1  # one pixel: below min_area
    blobs = measure_blobs(m, (10, 20), min_area=2, max_measured=8, near=np.array([15.0, 30.0]))
    assert len(blobs) == 61
    assert blobs.measured.sum() == 8
    d = np.hypot(blobs.centroid[:, 0] - 15.0, blobs.centroid[:, 1] - 30.0)
    big = blobs.area >= 2
    assert d[blobs.measured].max() <= d[big & ~blobs.measured].min()
    assert not blobs.measured[blobs.area < 2].any()


def test_empty_masks_and_nearest():
    assert len(measure_blobs(np.zeros((0, 0), np.uint8))) == 0
    assert len(measure_blobs(np.zeros((10, 10), np.uint8))) == 0
    points = np.array([[0.0, 0.0], [10.0, 0.0], [5.0, 5.0]])
    assert nearest(points, np.array([True, True, False]), np.array([6.0, 4.0])) == 1
    assert nearest(points, np.zeros(3, bool), np.zeros(2)) == -1


def test_pixel_covariance_of_a_bar_a_disc_and_a_tilted_line():
    m = np.zeros((60, 80), np.uint8)
    m[10:13, 5:25] = 1  # 20 x 3 bar: variances (20² and 3², each (n² - 1)/12 + 1/12 = n²/12)
    cv2.circle(m, (60, 40), 8, 1, -1)
    blobs = measure_blobs(m)
    bar, disc = (0, 1) if blobs.centroid[0, 1] < 20 else (1, 0)
    assert blobs.covariance[bar] == pytest.approx([400 / 12, 9 / 12, 0.0])
    assert blobs.axes[bar] == pytest.approx([400 / 12, 9 / 12])
    sxx, syy, sxy = blobs.covariance[disc]
    assert sxx == pytest.approx(syy) and abs(sxy) < 1e-9 and sxx == pytest.approx(blobs.area[disc] / (4 * np.pi), rel=0.03)
    d = np.zeros((40, 40), np.uint8)
    d[np.arange(5, 35), np.arange(5, 35)] = 1  # a diagonal line: all its extent along (1, 1)
    c = measure_blobs(d).covariance[0]
    assert c[2] == pytest.approx(c[0] - 1 / 12) and measure_blobs(d).axes[0, 1] == pytest.approx(1 / 12)


def test_unmeasured_blobs_have_no_covariance():
    m = np.zeros((20, 40), np.uint8)
    m[2:4, 2:4] = 1
    m[10:15, 30:35] = 1
    blobs = measure_blobs(m, min_area=10)
    assert np.isnan(blobs.covariance[0]).all() and np.isfinite(blobs.covariance[1]).all()


def test_chain_length_is_the_same_on_short_and_long_contours():
    # Contours up to SHORT_CONTOUR points are walked in Python, longer ones with numpy: one formula.
    import cv2

    from trackreplay.trackers.foreground import blobs

    for radius in (2, 5, 9, 20):
        mask = np.zeros((60, 60), np.uint8)
        cv2.circle(mask, (30, 30), radius, 1, -1)
        contour = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)[0][0][:, 0, :]
        short, long_ = contour[:blobs.SHORT_CONTOUR], contour  # the long one crosses the threshold for r >= 9
        saved = blobs.SHORT_CONTOUR
        try:
            blobs.SHORT_CONTOUR = 0  # numpy everywhere
            by_numpy = chain_length(short), chain_length(long_)
            blobs.SHORT_CONTOUR = 10**9  # Python everywhere
            by_python = chain_length(short), chain_length(long_)
        finally:
            blobs.SHORT_CONTOUR = saved
        assert by_numpy == by_python


def _masks(seed: int, count: int):
    """Random masks: specks, dilated clumps, 255s, blobs on the border, odd and even sizes."""
    rng = np.random.default_rng(seed)
    for i in range(count):
        size = rng.integers(1, 90, 2) if i % 50 else rng.integers(200, 500, 2)  # a few big enough for OpenCV's threads
        h, w = (int(v) for v in size)
        m = (rng.random((h, w)) < rng.choice([0.002, 0.02, 0.1, 0.4, 0.8])).astype(np.uint8)
        if i % 3 == 0:
            m = cv2.dilate(m, np.ones((int(rng.integers(2, 5)),) * 2, np.uint8))
        yield m * 255 if i % 5 == 0 else m


def _whole_mask(mask):
    """The plain form: OpenCV's statistics over the whole mask."""
    n, labels, stats, centroids = cv2.connectedComponentsWithStats(mask, connectivity=8, ltype=cv2.CV_32S)
    return n, (0, 0), labels, stats[1:], centroids[1:]


def test_components_over_the_foreground_window_are_opencvs_over_the_whole_mask():
    for m in _masks(0, 1500):
        n, (x0, y0), labels, stats, centroids = components(m)
        n_all, _, labels_all, stats_all, centroids_all = _whole_mask(m)
        placed = np.zeros(m.shape, np.int32)
        placed[y0:y0 + labels.shape[0], x0:x0 + labels.shape[1]] = labels
        assert n == n_all and np.array_equal(placed, labels_all)
        assert stats.dtype == stats_all.dtype and np.array_equal(stats, stats_all)
        assert centroids.tobytes() == centroids_all.tobytes()


def test_measure_blobs_in_the_window_equals_the_whole_mask(monkeypatch):
    masks = list(_masks(1, 600))
    near = np.array([30.0, 20.0])
    args = [dict(), dict(min_area=3.0, max_measured=4, near=near), dict(min_area=2.0, moments=False)]
    ours = [measure_blobs(m, (7, 11), **a) for m in masks for a in args]
    monkeypatch.setattr(blobs_module, "components", _whole_mask)
    plain = [measure_blobs(m, (7, 11), **a) for m in masks for a in args]
    for a, b in zip(ours, plain):
        for field in ("centroid", "area", "circularity", "bbox", "covariance"):
            x, y = getattr(a, field), getattr(b, field)
            assert x.dtype == y.dtype and x.shape == y.shape and x.tobytes() == y.tobytes(), field
