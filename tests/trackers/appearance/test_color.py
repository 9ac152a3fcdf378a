"""Colour conversions take crops and strided views as they are: the values of a contiguous copy."""

import numpy as np

from trackreplay.trackers.appearance.color import to_hsv, to_ycbcr, to_ycrcb


def test_views_convert_as_their_contiguous_copies():
    frame = np.random.default_rng(0).integers(0, 256, (60, 80, 3)).astype(np.uint8)
    for view in (frame[3:50, 5:71], frame[::2, ::3], frame[10:40, 7:60].transpose(1, 0, 2), frame[::-1]):
        copy = np.ascontiguousarray(view)
        for convert in (to_ycrcb, to_ycbcr, to_hsv):
            assert np.array_equal(convert(view), convert(copy))
