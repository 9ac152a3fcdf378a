"""The early background with each frame's tracked box left out (reference.exclude, colorpf.early)."""

import numpy as np
import pytest

from trackreplay.trackers.colorpf.config import ReferenceConfig
from trackreplay.trackers.colorpf.early import ExcludingMedian
from trackreplay.trackers.colorpf.reference import BackgroundFrames
from trackreplay.trackers.foreground.background import MedianBackground

FLOOR = 60


def _frames(n: int, lefts: list[int] | None = None) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """A bright 10 x 20 block on a flat floor, its left edge at ``lefts`` (default: moving right 3 px
    per frame from x = 20); its boxes (x, y, w, h)."""
    images, boxes = [], []
    for i in range(n):
        image = np.full((60, 100, 3), FLOOR, np.uint8)
        x0 = lefts[i] if lefts else 20 + 3 * i
        image[20:40, x0:x0 + 10] = 200
        images.append(image)
        boxes.append(np.array([x0 + 4.5, 29.5, 10.0, 20.0]))
    return images, boxes


def test_the_tracked_box_is_left_out_of_the_median():
    images, boxes = _frames(8, [20] * 5 + [60, 70, 80])  # stands 5 frames, then leaves
    median, plain = ExcludingMedian(30, 3, 1.5), MedianBackground(30)
    for image, box in zip(images, boxes):
        median.add(image)
        median.leave_out(box)
        plain.add(image)
    model = median.model()
    assert model is not None and model.shape == images[0].shape and model.dtype == np.uint8
    # the block covered x 20-29 on 5 frames of 8: the plain median is the block there, without its box the floor
    assert (model[20:40, 20:30] == FLOOR).all()
    assert (plain.model()[20:40, 20:30] == 200).all()
    # where every frame's box covered a pixel, the plain median of all frames
    assert (model == np.where(median._inside(0, 0, 100, 60).all(axis=0)[..., None], plain.model(), model)).all()


def test_ready_once_the_marked_box_has_enough_frames_without_the_target():
    images, boxes = _frames(20)
    marked = np.array([20, 20, 30, 40])  # the first box's corners
    median = ExcludingMedian(30, 3, 1.5)
    ready_at = None
    for i, (image, box) in enumerate(zip(images, boxes)):
        median.add(image)
        assert not median.ready(marked) or ready_at is not None
        median.leave_out(box)
        if ready_at is None and median.ready(marked):
            ready_at = i
    # the box x 1.5 (15 px wide) leaves x 20-29 from frame 5 on (left edge 35 - 3 = 32): the third such is 7
    assert ready_at == 7
    assert (median.model()[20:40, 20:30] == FLOOR).all()
    assert ExcludingMedian(3, 5, 2.0).ready(marked) is False  # no frames yet


def test_a_frame_without_a_box_counts_for_no_pixel():
    images, _ = _frames(4)
    median = ExcludingMedian(30, 1, 2.0)
    for image in images:
        median.add(image)  # never told where the target is
    assert not median.ready(np.array([0, 0, 10, 10]))
    assert np.array_equal(median.model(), np.partition(np.stack(images), 2, axis=0)[2])  # the plain median


def test_background_frames_are_ready_earlier_with_the_exclusion():
    images, boxes = _frames(20)
    marked = np.array([20, 20, 30, 40])
    ready = {}
    for exclude in (0.0, 1.5):
        frames = BackgroundFrames(ReferenceConfig(background="early", frames=15, min_frames=3, exclude=exclude), 0)
        assert frames.at_start(images[0]) == (None, "early")
        frames.leave_out(boxes[0], marked=marked)
        for i in range(1, 20):
            if frames.early_ready:
                ready[exclude] = i
                break
            frames.offer(i, images[i])
            frames.leave_out(boxes[i])
    assert ready[0.0] == 15 and ready[1.5] < 10  # the plain median waits for all 15 frames


def test_exclude_must_be_off_or_at_least_one():
    with pytest.raises(ValueError):
        ReferenceConfig(exclude=0.5)


def test_the_median_equals_the_per_pixel_definition():
    rng = np.random.default_rng(3)
    median = ExcludingMedian(30, 1, 1.5)
    for i in range(7):
        median.add(rng.integers(0, 256, (12, 16, 3), dtype=np.uint8))
        if i != 3:  # frame 3: never told (left out everywhere)
            median.leave_out(np.array([4.0 + i, 6.0, 5.0, 6.0]))
    stack, out = np.stack(median._frames), median._inside(0, 0, 16, 12)
    expected = np.empty_like(stack[0])
    for y in range(12):
        for x in range(16):
            kept = stack[~out[:, y, x], y, x] if (~out[:, y, x]).any() else stack[:, y, x]
            expected[y, x] = np.sort(kept, axis=0)[len(kept) // 2]  # the upper middle value
    assert np.array_equal(median.model(), expected)
