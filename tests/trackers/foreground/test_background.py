"""The median backgrounds: plain, and with each frame's box left out."""

import numpy as np
import pytest

from trackreplay.trackers.foreground.background import ExcludingMedianBackground, MedianBackground, sort_frames

FLOOR = 60


def block_frames(lefts: list[int]) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """A bright 10 x 20 block on a flat floor, its left edge at ``lefts[i]``; the corners of a box
    15 px wide around it (x0, y0, x1, y1)."""
    images, corners = [], []
    for x0 in lefts:
        image = np.full((60, 100, 3), FLOOR, np.uint8)
        image[20:40, x0:x0 + 10] = 200
        images.append(image)
        corners.append(np.array([x0 - 2, 15, x0 + 13, 45]))
    return images, corners


def test_plain_median_is_the_upper_middle_value_and_frames_share_a_shape():
    median = MedianBackground(3)
    for v in (10, 30, 20, 40):
        median.add(np.full((2, 2), v, np.uint8))
    assert (median.model() == 20).all() and len(median) == 3  # capacity: the fourth frame is ignored
    mixed = ExcludingMedianBackground(3)
    mixed.add(np.zeros((2, 2), np.uint8))
    with pytest.raises(ValueError, match="share one shape"):
        mixed.add(np.zeros((3, 2), np.uint8))


def test_the_left_out_box_is_not_in_the_median():
    images, corners = block_frames([20] * 5 + [60, 70, 80])  # stands 5 frames of 8, then leaves
    median, plain = ExcludingMedianBackground(30), MedianBackground(30)
    for image, c in zip(images, corners):
        median.add(image)
        median.leave_out(c)
        plain.add(image)
    model = median.model()
    assert model.shape == images[0].shape and model.dtype == np.uint8
    assert (plain.model()[20:40, 20:30] == 200).all()  # the plain median: the block, there 5 of 8 frames
    assert (model[20:40, 20:30] == FLOOR).all()  # without its box: the floor
    everywhere = median._inside(0, 0, 100, 60).all(axis=0)  # left out of every frame: the plain median
    assert (model[everywhere] == plain.model()[everywhere]).all()


def test_ready_once_a_region_has_enough_frames_that_leave_it_in():
    images, corners = block_frames([20 + 3 * i for i in range(20)])
    marked = np.array([20, 20, 30, 40])
    median = ExcludingMedianBackground(30, min_samples=3)
    ready_at = None
    for i, (image, c) in enumerate(zip(images, corners)):
        median.add(image)
        assert not median.ready(marked) or ready_at is not None  # a frame with no box yet leaves out everything
        median.leave_out(c)
        if ready_at is None and median.ready(marked):
            ready_at = i
    assert ready_at == 6  # the box leaves x 20-29 once its left edge (18 + 3i) passes 29: frames 4, 5, 6
    assert (median.model()[20:40, 20:30] == FLOOR).all()
    assert ExcludingMedianBackground(3, 5).ready(marked) is False  # no frames yet
    with pytest.raises(ValueError):
        ExcludingMedianBackground(3, 0)


def test_a_frame_without_a_box_counts_for_no_pixel():
    images, _ = block_frames([20, 23, 26, 29])
    median = ExcludingMedianBackground(30)
    for image in images:
        median.add(image)
    assert not median.ready(np.array([0, 0, 10, 10]))
    assert np.array_equal(median.model(), np.partition(np.stack(images), 2, axis=0)[2])


def test_the_excluding_median_equals_the_per_pixel_definition():
    rng = np.random.default_rng(3)
    median = ExcludingMedianBackground(30)
    for i in range(7):
        median.add(rng.integers(0, 256, (12, 16, 3), dtype=np.uint8))
        if i != 3:  # frame 3: never told (left out everywhere)
            median.leave_out(np.array([2 + i, 3, 6 + i, 9]))
    stack, out = np.stack(median._frames), median._inside(0, 0, 16, 12)
    expected = np.empty_like(stack[0])
    for y in range(12):
        for x in range(16):
            kept = stack[~out[:, y, x], y, x] if (~out[:, y, x]).any() else stack[:, y, x]
            expected[y, x] = np.sort(kept, axis=0)[len(kept) // 2]  # the upper middle value
    assert np.array_equal(median.model(), expected)
    median.clear()
    assert len(median) == 0 and median.model() is None


@pytest.mark.parametrize("dtype", [np.uint8, np.uint16, np.float64])
def test_sort_frames_is_numpys_sort_along_the_frames(dtype):
    rng = np.random.default_rng(5)
    for n in range(1, 41):
        stack = rng.integers(0, 6 if n % 2 else 256, (n, 5, 7, 3)).astype(dtype)  # few levels: many ties
        assert np.array_equal(sort_frames(stack), np.sort(stack, axis=0))
        assert np.array_equal(sort_frames(stack[..., 0].transpose(0, 2, 1)), np.sort(stack[..., 0].transpose(0, 2, 1), axis=0))


@pytest.mark.parametrize("frames", [1, 2, 5, 8, 25, 30])
def test_the_medians_equal_the_plain_forms_with_extreme_values(frames):
    rng = np.random.default_rng(frames)
    median = ExcludingMedianBackground(30)
    for i in range(frames):
        median.add(rng.choice(np.array([0, 1, 254, 255], np.uint8), (9, 11, 3)))  # 255: the left-out stand-in
        if i % 3:
            median.leave_out(rng.integers(0, 11, 4))
    stack, out = np.stack(median._frames), median._inside(0, 0, 11, 9)
    plain = np.partition(stack, frames // 2, axis=0)[frames // 2]
    assert np.array_equal(MedianBackground.model(median), plain)
    expected = plain.copy()
    some = out.any(axis=0) & ~out.all(axis=0)
    ranked = np.sort(np.where(out[..., None], np.uint16(256), stack.astype(np.uint16)), axis=0)  # the former form
    k = (~out).sum(axis=0) // 2
    expected[some] = np.take_along_axis(ranked, k[None, ..., None].repeat(3, -1), axis=0)[0][some]
    assert np.array_equal(median.model(), expected)


def test_pixels_every_frame_leaves_out_take_the_plain_median():
    rng = np.random.default_rng(11)
    median = ExcludingMedianBackground(30)
    for _ in range(6):
        median.add(rng.integers(0, 256, (10, 12, 3), dtype=np.uint8))
        median.leave_out(np.array([2, 2, 7, 6]) + rng.integers(0, 2, 4))  # all cover x 3-6, y 3-5
    stack = np.stack(median._frames)
    got = median.model()
    assert np.array_equal(got[3:6, 3:7], np.partition(stack, 3, axis=0)[3][3:6, 3:7])
    assert np.array_equal(got[8:, :], np.partition(stack, 3, axis=0)[3][8:, :])  # left in by every frame
