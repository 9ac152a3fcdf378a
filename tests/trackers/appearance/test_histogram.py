import numpy as np
import pytest

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


# --- kernel-weighted, multi-part box histograms (known answers) ----------------------------------
from trackreplay.trackers.appearance.histogram import (  # noqa: E402
    box_histograms, box_part_histograms, image_part_histograms, kernel_and_part)


def test_kernel_and_part_known_answers() -> None:
    # a 4 x 4 box: pixel centres at 0.5 .. 3.5, r^2 = u^2 + v^2 with u, v in {-0.75, -0.25, 0.25, 0.75}
    w, p = kernel_and_part(np.arange(4)[:, None] + 0.5, np.arange(4)[None, :] + 0.5, 4, 4, "epanechnikov", 2)
    assert w[1, 1] == 1 - 0.0625 - 0.0625 and w[0, 0] == 0.0 and w[0, 1] == 1 - 0.5625 - 0.0625
    assert np.array_equal(p[:, 0], [0, 0, 1, 1])  # parts: top half 0, bottom half 1
    u, _ = kernel_and_part(np.zeros(3), np.zeros(3), 4, 4, "uniform", 1)
    assert np.array_equal(u, np.ones(3))


def test_box_part_histograms_known_answer() -> None:
    index = np.zeros((4, 4), np.int64)
    index[2:, :] = 1  # bottom half bin 1, top half bin 0
    index[1, 1] = 2  # one pixel near the centre in bin 2
    box = np.array([[0, 0, 4, 4]])
    h, n = box_part_histograms(index, box, 3, kernel="uniform", parts=2)
    assert n[0] == 16
    np.testing.assert_allclose(h[0], [[7 / 8, 0, 1 / 8], [0, 1, 0]])
    # Epanechnikov: top-half weights per row 0: (0, .375, .375, 0), row 1: (.375, .875, .875, .375)
    hk, _ = box_part_histograms(index, box, 3, kernel="epanechnikov", parts=1)
    total = 2 * (0.75 + 2.5)
    np.testing.assert_allclose(hk[0, 0], [(0.75 + 2.5 - 0.875) / total, (0.75 + 2.5) / total, 0.875 / total])
    # uniform, one part: the same as box_histograms
    rng = np.random.default_rng(1)
    big = rng.integers(0, 7, (30, 40))
    boxes = np.array([[0, 0, 40, 30], [3, 5, 20, 17], [10, 10, 10, 20]])
    a, na = box_histograms(big, boxes, 7, max_pixels=100)
    b, nb = box_part_histograms(big, boxes, 7, max_pixels=100)
    np.testing.assert_allclose(b[:, 0], a)
    assert np.array_equal(na, nb)


def test_image_part_histograms_mask_share() -> None:
    index = np.array([[0, 1], [2, 2]])
    h, w_in, w_all = image_part_histograms(index, 3, parts=2, mask=np.array([[True, False], [True, True]]))
    np.testing.assert_allclose(h, [[1, 0, 0], [0, 0, 1]])
    np.testing.assert_allclose(w_in, [1, 2])
    np.testing.assert_allclose(w_all, [2, 2])


def test_box_histograms_sampled_grid_known_answer() -> None:
    # a 4 x 4 box with max_pixels = 4: stride ceil(sqrt(16 / 4)) = 2, the pixels (0,0) (0,2) (2,0) (2,2)
    index = np.arange(16).reshape(4, 4) % 5  # bins: row 0: 0 1 2 3, row 2: 3 4 0 1; sampled: 0 2 3 0
    h, n = box_histograms(index, np.array([[0, 0, 4, 4], [1, 1, 1, 3]]), 5, max_pixels=4)
    assert np.array_equal(n, [4, 0])
    assert np.array_equal(h, [[0.5, 0.0, 0.25, 0.25, 0.0], [0.0] * 5])  # the empty box: zeros
    # two parts: the sampled rows 0 and 2 fall in the top and the bottom band
    hp, _ = box_part_histograms(index, np.array([[0, 0, 4, 4]]), 5, parts=2, max_pixels=4)
    assert np.array_equal(hp[0], [[0.5, 0.0, 0.5, 0.0, 0.0], [0.5, 0.0, 0.0, 0.5, 0.0]])


def test_level_counts_are_numpys_bincount() -> None:
    """Counts by ``cv2.calcHist`` are ``np.bincount``'s, and anything out of range is left to ``np.bincount``."""
    from trackreplay.trackers.appearance.histogram import level_counts

    rng = np.random.default_rng(11)
    for shape in [(1, 1), (1, 50), (43, 43), (320, 320), (17, 3), (110, 110), (1, 13000)]:
        u8 = rng.integers(0, 256, shape, dtype=np.uint8)
        assert np.array_equal(level_counts(u8), np.bincount(u8.ravel().astype(np.intp), minlength=256))
        i16 = (rng.integers(-255, 256, shape)).astype(np.int16)
        expected = np.bincount((i16.ravel() + 255).astype(np.intp), minlength=511)
        got = level_counts(i16, -255, 511)
        assert got.dtype == expected.dtype and np.array_equal(got, expected)
        i16.flat[0] = 300  # beyond the levels: numpy's longer answer
        assert np.array_equal(level_counts(i16, -255, 511), np.bincount((i16.ravel() + 255).astype(np.intp), minlength=511))
    view = rng.integers(0, 256, (200, 180), dtype=np.uint8)[5:190, 7:170]  # a strided crop
    assert np.array_equal(level_counts(view), np.bincount(view.ravel().astype(np.intp), minlength=256))
    assert np.array_equal(level_counts(np.zeros((0, 4), np.uint8)), np.zeros(256, np.int64))
    with pytest.raises(ValueError):  # a value below the levels: numpy's error, as before
        level_counts(np.full((2, 2), -300, np.int16), -255, 511)


def _plain_box_part_histograms(index, boxes, n_bins, kernel, parts, max_pixels):
    """box_part_histograms as first written: padding masked out and counted into a spare bin."""
    from trackreplay.trackers.appearance.histogram import kernel_and_part
    boxes = np.asarray(boxes, dtype=np.int64).reshape(-1, 4)
    k = len(boxes)
    x0, y0 = boxes[:, 0], boxes[:, 1]
    w, h = np.maximum(boxes[:, 2] - x0, 0), np.maximum(boxes[:, 3] - y0, 0)
    stride = np.ones(k, dtype=np.int64)
    if max_pixels is not None:
        stride = np.maximum(np.ceil(np.sqrt(w * h / float(max_pixels))).astype(np.int64), 1)
    nx, ny = -(-w // stride), -(-h // stride)
    rows, cols = np.arange(int(ny.max())), np.arange(int(nx.max()))
    inside = (rows[None, :, None] < ny[:, None, None]) & (cols[None, None, :] < nx[:, None, None])
    s = stride[:, None, None]
    flat = (y0 * index.shape[1] + x0)[:, None, None] + s * (rows[None, :, None] * index.shape[1] + cols[None, None, :])
    weight, part = kernel_and_part(s * rows[None, :, None] + 0.5, s * cols[None, None, :] + 0.5,
                                   h[:, None, None], w[:, None, None], kernel, parts)
    slot = np.arange(k)[:, None, None] * parts + part
    bins = index.reshape(-1)[np.where(inside, flat, 0)] + slot * n_bins
    spare = k * parts * n_bins
    weight = np.where(inside, weight, 0.0).reshape(-1)
    counts = np.bincount(np.where(inside, bins, spare).reshape(-1), weights=weight, minlength=spare + 1)[:-1]
    counts = counts.reshape(k, parts, n_bins)
    total = counts.sum(axis=2, keepdims=True)
    return np.where(total > 0, counts / np.where(total > 0, total, 1.0), 0.0), nx * ny


@pytest.mark.parametrize("kernel", ["uniform", "epanechnikov"])
@pytest.mark.parametrize("parts", [1, 2, 3])
@pytest.mark.parametrize("max_pixels", [None, 50, 1024])
def test_box_part_histograms_equal_their_plain_form_bit_for_bit(kernel, parts, max_pixels):
    rng = np.random.default_rng(parts)
    index = rng.integers(0, 100, (90, 70)).astype(np.int32)
    scratch: dict = {}  # kept buffers, reused (and grown) from one block shape to the next
    for k in (1, 7, 40, 3):
        corners = np.sort(rng.integers(0, 71, (k, 2, 2)), axis=1)  # x0 <= x1, y0 <= y1 (some empty)
        boxes = np.column_stack([corners[:, 0, 0], corners[:, 0, 1], corners[:, 1, 0], corners[:, 1, 1]])
        boxes[:, [1, 3]] = np.minimum(boxes[:, [1, 3]] + rng.integers(0, 20, (k, 1)), 90)
        want, n_want = _plain_box_part_histograms(index, boxes, 100, kernel, parts, max_pixels)
        for buffers in (None, scratch):
            got, n = box_part_histograms(index, boxes, 100, kernel=kernel, parts=parts, max_pixels=max_pixels,
                                         scratch=buffers)
            assert np.array_equal(got, want) and np.array_equal(n, n_want)
            assert not any(np.shares_memory(got, b) for b in scratch.values())
    assert scratch  # the buffers were used


def test_hs_index_is_the_plain_table_look_up():
    from trackreplay.trackers.appearance.histogram import _axis_lut, hs_index
    rng = np.random.default_rng(8)
    hsv = to_hsv(rng.integers(0, 256, (37, 23, 3), dtype=np.uint8))
    for bins in ((10, 10), (8, 4), (16, 16)):
        lut = (_axis_lut(bins[0], *HSV_RANGES[0])[:, None] * bins[1]
               + _axis_lut(bins[1], *HSV_RANGES[1])[None, :]).astype(np.int32)
        got, n = hs_index(hsv, bins, HSV_RANGES)
        want = lut[hsv[..., 0], hsv[..., 1]]
        assert got.dtype == want.dtype and np.array_equal(got, want) and n == bins[0] * bins[1]
        assert np.array_equal(hs_index(hsv.astype(np.int64), bins, HSV_RANGES)[0], want)  # not uint8: the 2-D look-up
