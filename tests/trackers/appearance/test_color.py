"""Colour conversions take crops and strided views as they are: the values of a contiguous copy."""

import cv2
import numpy as np
import pytest

from trackreplay.trackers.appearance.color import to_grey, to_hsv, to_ycbcr, to_ycrcb


def test_views_convert_as_their_contiguous_copies():
    frame = np.random.default_rng(0).integers(0, 256, (60, 80, 3)).astype(np.uint8)
    for view in (frame[3:50, 5:71], frame[::2, ::3], frame[10:40, 7:60].transpose(1, 0, 2), frame[::-1]):
        copy = np.ascontiguousarray(view)
        for convert in (to_ycrcb, to_ycbcr, to_hsv):
            assert np.array_equal(convert(view), convert(copy))


def test_grey_luma_is_opencvs_and_mean_is_the_float32_channel_mean():
    frame = np.random.default_rng(3).integers(0, 256, (37, 53, 3), dtype=np.uint8)
    for view in (frame, frame[::4, ::3], frame[5:20, 7:40]):
        assert np.array_equal(to_grey(view), cv2.cvtColor(np.ascontiguousarray(view), cv2.COLOR_BGR2GRAY))
        assert np.array_equal(to_grey(view, "mean"), view.astype(np.float32).mean(axis=-1))
    grey = frame[..., 1]  # a strided grey view: luma comes back contiguous uint8, mean as float32
    assert to_grey(grey).flags.c_contiguous and np.array_equal(to_grey(grey), grey)
    assert to_grey(grey, "mean").dtype == np.float32 and np.array_equal(to_grey(grey, "mean"), grey)
    # OpenCV's fixed-point luma and the channel mean differ: the formula is the caller's choice
    assert not np.array_equal(to_grey(frame).astype(np.float32), to_grey(frame, "mean"))
    with pytest.raises(ValueError, match="luma"):
        to_grey(frame, "average")


def test_grey_mean_fast_path_is_the_float32_mean_for_every_channel_sum():
    # every (b, g, r) sum 0..765 and a random million triples: the integer sum divided by 3 is
    # numpy's float32 mean bit for bit
    s = np.arange(766)
    sums = np.stack([np.minimum(s, 255), np.clip(s - 255, 0, 255), np.clip(s - 510, 0, 255)], axis=-1).astype(np.uint8)
    triples = np.random.default_rng(0).integers(0, 256, (1000, 1000, 3), dtype=np.uint8)
    for image in (sums[None], triples):
        assert np.array_equal(to_grey(image, "mean"), image.astype(np.float32).mean(axis=-1))
