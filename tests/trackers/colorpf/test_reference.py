"""Eq. (7) as corrected in docs/papers.md §3, on a crafted image, and the fallback without a background."""

import numpy as np
import pytest

from trackreplay.trackers.colorpf.config import ReferenceConfig
from trackreplay.trackers.colorpf.config import LikelihoodConfig
from trackreplay.trackers.colorpf.likelihood import ColourModel
from trackreplay.trackers.colorpf.reference import mixed_reference, subtract_and_mix

GREEN, RED = (0, 200, 0), (0, 0, 200)


def test_mixed_reference_formula():
    t, b = np.array([1.0, 0.0]), np.array([0.0, 1.0])
    np.testing.assert_allclose(mixed_reference(t, b, 30, 100), [0.3, 0.7])  # the printed P_d - P_s would give -0.7
    with pytest.raises(ValueError):
        mixed_reference(t, b, 120, 100)


def test_background_subtraction_mixes_target_and_whole_background():
    model = ColourModel(LikelihoodConfig(max_pixels=None, kernel="uniform"))  # the paper's eq. (7): pixel counts
    background = np.zeros((50, 80, 3), np.uint8)
    background[:] = GREEN
    background[:, 60:] = (200, 0, 0)  # the whole background: 3/4 green, 1/4 blue
    image = background.copy()
    image[10:30, 10:20] = RED  # the target: 200 px in a marked box of 20 x 20 = 400 px
    ref, why = subtract_and_mix(model, ReferenceConfig(open_px=1), image, background, np.array([5, 10, 25, 30]), "before")
    assert why == "" and ref.p_detect == 200 and ref.p_square == 400
    h = ref.histogram.reshape(10, 10)
    assert h[0, 9] == pytest.approx(0.5)  # red: P_d / P_s of H_target
    assert h[3, 9] == pytest.approx(0.5 * 0.75)  # green, H 60 -> bin 3: (P_s - P_d) / P_s of H_back
    assert h[6, 9] == pytest.approx(0.5 * 0.25)  # blue, H 120 -> bin 6
    assert h.sum() == pytest.approx(1.0)
    target_only, _ = subtract_and_mix(model, ReferenceConfig(mode="target", open_px=1), image, background,
                                      np.array([5, 10, 25, 30]), "before")
    assert target_only.histogram.reshape(10, 10)[0, 9] == pytest.approx(1.0)
    unusable, why = subtract_and_mix(model, ReferenceConfig(open_px=1), background, background, np.array([5, 10, 25, 30]), "before")
    assert unusable is None and "fills 0%" in why


def _scene():
    background = np.zeros((50, 80, 3), np.uint8)
    background[:] = GREEN
    background[:, 60:] = (200, 0, 0)  # the whole background: 3/4 green, 1/4 blue
    return background


def test_kernel_weighted_mix_counts_the_centre_more():
    from trackreplay.trackers.appearance.histogram import kernel_and_part

    background = _scene()
    image = background.copy()
    image[10:30, 10:20] = RED  # the central 10 of the box's 20 columns
    model = ColourModel(LikelihoodConfig(max_pixels=None, kernel="epanechnikov"))
    ref, _ = subtract_and_mix(model, ReferenceConfig(open_px=1), image, background, np.array([5, 10, 25, 30]), "before")
    w, _ = kernel_and_part(np.arange(20)[:, None] + 0.5, np.arange(20)[None, :] + 0.5, 20, 20, "epanechnikov")
    a = w[:, 5:15].sum() / w.sum()  # the kernel-weighted P_detect / P_square
    assert 0.5 < a < 1.0  # the target sits in the middle: it weighs more than its 200 of 400 pixels
    h = ref.histogram.reshape(10, 10)
    assert h[0, 9] == pytest.approx(a) and h[3, 9] == pytest.approx((1 - a) * 0.75)
    assert h.sum() == pytest.approx(1.0)


def test_two_parts_mix_per_part():
    background = _scene()
    image = background.copy()
    image[10:20, 5:25] = RED  # the top half of the marked box (rows 10-29) is all target, the bottom none
    model = ColourModel(LikelihoodConfig(max_pixels=None, kernel="uniform", parts=2))
    ref, _ = subtract_and_mix(model, ReferenceConfig(open_px=1, max_fill=1.0), image, background,
                              np.array([5, 10, 25, 30]), "before")
    top, bottom = ref.histogram.reshape(2, 10, 10)
    assert top[0, 9] == pytest.approx(1.0)  # a_top = 1: H_target alone
    assert bottom[0, 9] == 0.0 and bottom[3, 9] == pytest.approx(0.75)  # a_bottom = 0: H_back alone
