"""The generic 256³ colour LUT: counts, smoothing, the two-class decision, lookup."""

import numpy as np
import pytest

from trackreplay.trackers.appearance.lut import ColourCounts, ColourLut, coarse_counts, expand_table, flat_index, smooth3


def test_flat_index_and_lookup_agree_with_the_table():
    rng = np.random.default_rng(0)
    pixels = rng.integers(0, 256, size=(7, 9, 3), dtype=np.uint8)
    table = rng.random((256, 256, 256)) < 0.5
    lut = ColourLut(table)
    assert np.array_equal(lut.lookup(pixels), table[pixels[..., 0], pixels[..., 1], pixels[..., 2]])
    assert flat_index(np.array([[1, 2, 3]], np.uint8))[0] == 65536 + 2 * 256 + 3


def test_coarse_counts_and_expansion():
    px = np.array([[0, 0, 0], [3, 3, 3], [4, 0, 255]], np.uint8)
    c = coarse_counts(px, 4)
    assert c.shape == (64, 64, 64) and c[0, 0, 0] == 2 and c[1, 0, 63] == 1 and c.sum() == 3
    big = expand_table(c > 1, 4)
    assert big.shape == (256, 256, 256) and big[3, 2, 1] and not big[4, 0, 0]
    assert big.sum() == 64


def test_smoothing_keeps_mass_inside_and_spreads_it():
    v = np.zeros((16, 16, 16))
    v[8, 8, 8] = 1.0
    s = smooth3(v, 1.0)
    assert s.sum() == pytest.approx(1.0)
    assert s[8, 8, 8] < 0.1 and s[9, 8, 8] > 0 and s[8, 8, 8] == s.max()
    assert smooth3(v, 0.0) is v


def test_smoothing_over_the_support_is_the_smoothing_over_the_whole_cube():
    # smooth3 works on the non-zero cells' box (+ the kernel radius): the same numbers, bit for bit,
    # as the whole cube, near the cube's edges too; and nothing outside the widened box.
    from trackreplay.trackers.appearance.lut import _smooth3_dense

    rng = np.random.default_rng(4)
    for centre, spread in (((32, 30, 34), (6, 3, 2)), ((1, 62, 5), (2, 2, 9)), ((20, 20, 20), (40, 40, 40))):
        v = np.zeros((64, 64, 64))
        idx = tuple(np.clip(rng.normal(centre, spread, (300, 3)).astype(int), 0, 63).T)
        np.add.at(v, idx, rng.integers(1, 40, 300).astype(float))
        for sigma in (0.7, 1.0, 2.0):
            assert np.array_equal(smooth3(v, sigma), _smooth3_dense(v, sigma))
    assert not smooth3(np.zeros((8, 8, 8)), 1.0).any()


def test_two_classes_from_samples_with_the_count_prior():
    ball = np.tile(np.array([[240, 128, 128]], np.uint8), (50, 1))  # white
    sky = np.tile(np.array([[150, 160, 100]], np.uint8), (5000, 1))
    shared = np.tile(np.array([[200, 128, 128]], np.uint8), (10, 1))  # a grey both have
    counts = ColourCounts(4)
    counts.add(np.concatenate([ball, shared]), np.concatenate([sky, np.tile(shared, (200, 1))]))
    lut = counts.lut(smooth=0.0, foreground_weight=10.0, min_count=0.5)
    assert lut.lookup(np.array([240, 128, 128], np.uint8))  # ball colour
    assert lut.lookup(np.array([243, 130, 129], np.uint8))  # same coarse cell
    assert not lut.lookup(np.array([150, 160, 100], np.uint8))  # sky
    assert not lut.lookup(np.array([200, 128, 128], np.uint8))  # 10 x 10 ball < 2000 background
    assert lut.table.shape == (256, 256, 256)
    with pytest.raises(ValueError):
        ColourCounts(3)


def test_the_coarse_lookup_answers_exactly_as_the_expanded_table():
    rng = np.random.default_rng(1)
    coarse = rng.random((64, 64, 64)) < 0.3
    lut = ColourLut(coarse, 4)
    pixels = rng.integers(0, 256, size=(50, 40, 3), dtype=np.uint8)
    full = expand_table(coarse, 4)
    assert np.array_equal(lut.lookup(pixels), full[pixels[..., 0], pixels[..., 1], pixels[..., 2]])
    assert np.array_equal(lut.table, full)
    with pytest.raises(ValueError):
        ColourLut(coarse, 8)  # a 64³ table is not a bin-8 table


def test_bin_one_lookup_is_the_full_table_and_bad_bins_are_refused():
    rng = np.random.default_rng(2)
    pixels = rng.integers(0, 256, size=(30, 20, 3), dtype=np.uint8)
    full = np.zeros((256, 256, 256), bool)
    full[pixels[0, 0, 0], pixels[0, 0, 1], pixels[0, 0, 2]] = True
    hits = ColourLut(full).lookup(pixels)
    assert hits[0, 0] and hits.sum() == (pixels == pixels[0, 0]).all(axis=-1).sum()
    for bad in (0, 3):
        with pytest.raises(ValueError, match="power of 2"):
            ColourLut(np.zeros((1, 1, 1), bool), bad)


def test_the_decision_over_the_foreground_support_is_the_whole_cube_decision():
    from trackreplay.trackers.appearance.lut import _smooth3_dense, two_class_table

    rng = np.random.default_rng(5)
    for _ in range(10):
        fg, bg = np.zeros((64, 64, 64)), np.zeros((64, 64, 64))
        c = rng.integers(0, 64, 3)
        np.add.at(fg, tuple(np.clip(rng.normal(c, 4, (40, 3)).astype(int), 0, 63).T), 3.0)
        np.add.at(bg, tuple(np.clip(rng.normal(c, 12, (2000, 3)).astype(int), 0, 63).T), 1.0)
        sf, sb = _smooth3_dense(fg, 1.0), _smooth3_dense(bg, 1.0) * 16.0
        expected = (1000.0 * sf > sb) & (sf > 0.02)
        got = two_class_table(fg, bg, smooth=1.0, foreground_weight=1000.0, min_count=0.02, background_scale=16.0)
        assert np.array_equal(got, expected)


def test_coarse_counts_by_shifts_are_the_counts_by_division():
    px = np.random.default_rng(3).integers(0, 256, (5000, 3)).astype(np.uint8)
    for bin_ in (1, 2, 4, 8, 32, 256):
        q = 256 // bin_
        c = px.astype(np.int64) // bin_  # the plain form
        plain = np.bincount((c[:, 0] * q + c[:, 1]) * q + c[:, 2], minlength=q**3).astype(np.float64).reshape(q, q, q)
        assert np.array_equal(coarse_counts(px, bin_), plain)
        assert np.array_equal(coarse_counts(px.reshape(50, 100, 3), bin_), plain)


def test_coarse_index_is_the_plain_int32_form():
    """Shifting as uint8 before widening gives the index (and dtype) of widening first."""
    from trackreplay.trackers.appearance.color import to_ycbcr
    from trackreplay.trackers.appearance.lut import coarse_index

    rng = np.random.default_rng(5)
    image = rng.integers(0, 256, (37, 53, 3), dtype=np.uint8)
    for pixels in (image, image[3:30, 5:40], to_ycbcr(image), image.reshape(-1, 3)):
        for bin_ in (1, 2, 4, 8, 16, 256):
            shift = bin_.bit_length() - 1
            bits = 8 - shift
            plain = ((pixels[..., 0].astype(np.int32) >> shift) << (2 * bits)) | (
                (pixels[..., 1].astype(np.int32) >> shift) << bits) | (pixels[..., 2].astype(np.int32) >> shift)
            got = coarse_index(pixels, bin_)
            assert got.dtype == plain.dtype and np.array_equal(got, plain)


def test_support_box_is_the_extent_of_numpys_nonzero():
    from trackreplay.trackers.appearance.lut import support_box

    rng = np.random.default_rng(6)
    for _ in range(50):
        cube = np.zeros((16, 16, 16))
        k = rng.integers(1, 20)
        cube[tuple(rng.integers(0, 16, (3, k)))] = rng.choice([1.0, 0.5, -2.0, np.nan], k)
        support = np.nonzero(cube)
        assert support_box(cube) == [(int(a.min()), int(a.max())) for a in support]
    assert support_box(np.zeros((4, 4, 4))) is None
