"""LUT silhouettes inside a crop."""

import numpy as np

from trackreplay.trackers.appearance.lut import ColourLut
from trackreplay.trackers.foreground.silhouette import crop_pixels, silhouette


def test_a_lut_silhouette_in_a_clipped_crop():
    image = np.zeros((50, 60, 3), np.uint8)
    image[20:25, 30:33] = (10, 200, 30)
    table = np.zeros((256, 256, 256), bool)
    table[10, 200, 30] = True
    pixels, offset = crop_pixels(image, np.array([25.5, -5.0, 100.0, 40.0]), lambda p: p.copy())
    assert offset == (25, 0) and pixels.shape == (35, 35, 3)  # clipped to the image, floor/ceil
    mask = silhouette(pixels, ColourLut(table))
    assert mask.dtype == np.uint8 and mask.sum() == 15
    assert mask[20:25, 5:8].all()
    assert silhouette(pixels, None).sum() == 0
    empty, where = crop_pixels(image, np.array([70.0, 10.0, 5.0, 5.0]), lambda p: p)
    assert empty.shape == (0, 0, 3) and silhouette(empty, ColourLut(table)).shape == (0, 0)
