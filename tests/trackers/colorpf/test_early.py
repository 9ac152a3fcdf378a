"""The colour PF's early background with each frame's tracked box left out (reference.exclude)."""

import numpy as np
import pytest

from trackreplay.trackers.colorpf.config import ReferenceConfig
from trackreplay.trackers.colorpf.reference import BackgroundFrames

FLOOR = 60
SIZE = (100, 60)


def _frames(n: int) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """A bright 10 x 20 block on a flat floor moving right 3 px a frame from x = 20; its boxes (x, y, w, h)."""
    images, boxes = [], []
    for i in range(n):
        image = np.full((60, 100, 3), FLOOR, np.uint8)
        x0 = 20 + 3 * i
        image[20:40, x0:x0 + 10] = 200
        images.append(image)
        boxes.append(np.array([x0 + 4.5, 29.5, 10.0, 20.0]))
    return images, boxes


def test_background_frames_are_ready_earlier_with_the_exclusion():
    images, boxes = _frames(20)
    marked = np.array([20, 20, 30, 40])
    ready, models = {}, {}
    for exclude in (0.0, 1.5):
        frames = BackgroundFrames(ReferenceConfig(background="early", frames=15, min_frames=3, exclude=exclude), 0)
        assert frames.at_start(images[0]) == (None, "early")
        frames.leave_out(boxes[0], SIZE, marked=marked)
        for i in range(1, 20):
            if frames.early_ready:
                ready[exclude], models[exclude] = i, frames.early_model()
                break
            frames.offer(i, images[i])
            frames.leave_out(boxes[i], SIZE)
    assert ready[0.0] == 15 and ready[1.5] < 10  # the plain median waits for all 15 frames
    assert (models[1.5][20:40, 20:30] == FLOOR).all()  # the marked box's pixels: the floor, not the block


def test_exclude_must_be_off_or_at_least_one():
    with pytest.raises(ValueError):
        ReferenceConfig(exclude=0.5)
