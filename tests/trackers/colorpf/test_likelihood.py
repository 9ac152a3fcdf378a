"""Eqs. (4)-(5): H-S histogram, Swain intersection and L = exp(k S^2), on known answers."""

import numpy as np

from trackreplay.trackers.appearance.color import to_hsv
from trackreplay.trackers.colorpf.config import LikelihoodConfig
from trackreplay.trackers.colorpf.likelihood import ColourModel, box_corners, box_histogram, measure


def _two_colour_image() -> np.ndarray:
    img = np.zeros((40, 60, 3), np.uint8)
    img[:, :30] = (0, 0, 255)  # red: H 0, S 255
    img[:, 30:] = (255, 0, 0)  # blue: H 120, S 255
    return img


def test_hs_histogram_known_answer_and_brightness_invariance():
    model = ColourModel(LikelihoodConfig(max_pixels=None))
    img = _two_colour_image()
    h = box_histogram(model, img, np.array([29.5, 19.5, 60.0, 40.0])).reshape(10, 10)
    assert h.sum() == 1.0
    assert h[0, 9] == 0.5 and h[6, 9] == 0.5  # red: H bin 0, blue: H 120/18 = bin 6; S bin 9
    darker = (img * 0.4).astype(np.uint8)  # a uniform brightness change leaves H and S alone
    assert np.array_equal(box_histogram(model, darker, np.array([29.5, 19.5, 60.0, 40.0])), h.reshape(-1))
    hsv_model = ColourModel(LikelihoodConfig(histogram="hsv", max_pixels=None))
    assert hsv_model.n_bins == 110
    grey = np.full((10, 10, 3), 100, np.uint8)  # not coloured: a V bin
    hg = box_histogram(hsv_model, grey, np.array([4.5, 4.5, 10.0, 10.0]))
    assert hg[100 + int(to_hsv(grey)[0, 0, 2]) * 10 // 256] == 1.0


def test_intersection_and_likelihood_per_particle():
    model = ColourModel(LikelihoodConfig(max_pixels=None))
    img = _two_colour_image()
    ref = box_histogram(model, img, np.array([14.5, 19.5, 30.0, 40.0]))  # all red
    states = np.array([[14.5, 19.5, 30.0, 40.0],  # all red: S = 1
                       [29.5, 19.5, 30.0, 40.0],  # half red: S = 0.5
                       [44.5, 19.5, 30.0, 40.0],  # all blue: S = 0
                       [500.0, 500.0, 10.0, 10.0]])  # outside: no pixel
    m = measure(model, img, states, ref)
    np.testing.assert_allclose(m.similarity, [1.0, 0.5, 0.0, 0.0])
    np.testing.assert_allclose(m.likelihood, np.exp(20.0 * np.array([1.0, 0.25, 0.0, 0.0])))
    assert m.pixels[3] == 0
    assert abs(model.similarity_for(25.0) - np.sqrt(np.log(25.0) / 20.0)) < 1e-12


def test_parts_similarity_is_the_geometric_mean_of_the_parts():
    model = ColourModel(LikelihoodConfig(parts=2, max_pixels=None))
    img = np.zeros((40, 20, 3), np.uint8)
    img[:20] = (0, 0, 255)  # red top half
    img[20:] = (255, 0, 0)  # blue bottom half
    box = np.array([9.5, 19.5, 20.0, 40.0])
    ref = box_histogram(model, img, box)
    assert ref.shape == (200,) and model.shape == (20, 10)
    assert ref.reshape(2, 10, 10)[0, 0, 9] == 1.0 and ref.reshape(2, 10, 10)[1, 6, 9] == 1.0
    assert model.similarity(ref, ref) == 1.0
    flipped = np.concatenate([ref[100:], ref[:100]])  # upper and lower swapped: the same colours, wrong places
    assert model.similarity(flipped, ref) == 0.0
    half = np.concatenate([ref[:100], 0.5 * ref[100:] + 0.5 * ref[:100]])  # S_top 1, S_bottom 0.5
    assert np.isclose(model.similarity(half, ref), np.sqrt(0.5))
    # the one-part model sees only the colours: the swap costs nothing
    one = ColourModel(LikelihoodConfig(max_pixels=None))
    assert one.similarity(box_histogram(one, img, box), box_histogram(one, img, box)) == 1.0


def test_mean_shift_climbs_to_the_target():
    from trackreplay.trackers.colorpf.likelihood import mean_shift

    img = np.full((80, 100, 3), (0, 160, 0), np.uint8)  # green field
    img[30:50, 40:56] = (0, 0, 255)  # a 16 x 20 red target centred at (48, 40)
    for kernel in ("uniform", "epanechnikov"):
        model = ColourModel(LikelihoodConfig(kernel=kernel, max_pixels=None))
        ref = box_histogram(model, img, np.array([48.0, 40.0, 16.0, 20.0]))
        start = np.array([43.0, 36.0, 16.0, 20.0])
        s0 = float(model.similarity(box_histogram(model, img, start), ref))
        out, s = mean_shift(model, img, start, ref, iterations=10)
        assert s > s0 and abs(out[0] - 48.0) < 2.0 and abs(out[1] - 40.0) < 2.0
        assert np.array_equal(out[2:], start[2:])  # the size is kept


def test_pooled_similarity_ignores_where_in_the_box_the_colours_are():
    model = ColourModel(LikelihoodConfig(parts=2, max_pixels=None))
    img = np.zeros((40, 20, 3), np.uint8)
    img[:20] = (0, 0, 255)  # red top half
    img[20:] = (255, 0, 0)  # blue bottom half
    ref = box_histogram(model, img, np.array([9.5, 19.5, 20.0, 40.0]))
    flipped = np.concatenate([ref[100:], ref[:100]])
    assert model.similarity(flipped, ref) == 0.0 and model.pooled_similarity(flipped, ref) == 1.0
    top_only = np.concatenate([ref[:100], ref[:100]])  # red in both bands: half the colours
    assert model.pooled_similarity(top_only, ref) == 0.5
    assert np.array_equal(model.pooled_similarity(np.stack([flipped, top_only]), ref), [1.0, 0.5])  # rows
    one = ColourModel(LikelihoodConfig(max_pixels=None))
    red, whole = (box_histogram(one, img, np.array([9.5, y, 20.0, h])) for y, h in ((9.5, 20.0), (19.5, 40.0)))
    assert one.pooled_similarity(red, whole) == one.similarity(red, whole)  # one part: the same
    assert np.isclose(one.similarity(red, whole), 0.5)


def test_box_corners_is_its_plain_clip_form():
    rng = np.random.default_rng(2)
    states = np.column_stack([rng.normal(150, 250, (500, 2)), np.abs(rng.normal(0, 80, (500, 2)))])
    states[::7, :2] = np.round(states[::7, :2]) + 0.5  # on a pixel boundary
    s = states
    half = s[:, 2:4] / 2.0
    lo, hi = np.floor(s[:, :2] - half + 0.5), np.floor(s[:, :2] + half + 0.5)
    limit = np.array([360, 240], dtype=np.float64)
    lo = np.clip(lo, 0, limit)
    expected = np.concatenate([lo, np.clip(np.maximum(hi, lo), 0, limit)], axis=1).astype(np.int64)
    assert np.array_equal(box_corners(states, 360, 240), expected)
    assert np.array_equal(box_corners(states[3], 360, 240), expected[3:4])


def test_a_crop_within_the_last_index_made_is_cut_from_it():
    """ColourModel.crop_index: a crop within the last one made of the same picture is that crop's own index (H-S:
    per pixel; the grey gradient index: its derivatives read the neighbours the larger crop holds)."""
    rng = np.random.default_rng(4)
    image = rng.integers(0, 256, (60, 80, 3), dtype=np.uint8)
    for config in (LikelihoodConfig(), LikelihoodConfig(histogram="gradient")):
        model, fresh = ColourModel(config, 20.0), ColourModel(config, 20.0)
        union = model.crop_index(image, 10, 5, 70, 55)
        for x0, y0, x1, y1 in ((10, 5, 70, 55), (11, 6, 30, 40), (10, 5, 12, 7), (40, 30, 70, 55)):
            cut = model.crop_index(image, x0, y0, x1, y1)
            assert np.shares_memory(cut, union)  # cut from it
            fresh.recent.clear()
            assert np.array_equal(cut, fresh.crop_index(image, x0, y0, x1, y1))
        outside = model.crop_index(image, 0, 0, 20, 20)  # not within: made afresh, and the last one from then on
        assert not np.shares_memory(outside, union)
        assert np.array_equal(model.crop_index(image.copy(), 0, 0, 10, 10), fresh.crop_index(image, 0, 0, 10, 10))
