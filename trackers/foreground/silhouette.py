"""Binary silhouettes inside a crop: a colour LUT (or any per-pixel mask) -> uint8 0/1.

Only the crop is converted and looked up, never the whole frame (seed 000 §2.1: the HD frame is
too costly to scan; all extraction runs inside the search region).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from trackreplay.trackers.appearance.lut import ColourLut
from trackreplay.trackers.geometry.box import clip_box, crop


def crop_pixels(image: np.ndarray, box: np.ndarray, convert: Callable[[np.ndarray], np.ndarray]) -> tuple[np.ndarray, tuple[int, int]]:
    """The pixels of an ``(x0, y0, w, h)`` box, clipped to the image and passed through ``convert``
    (e.g. ``to_ycbcr``), and the crop's top-left offset in the frame. An empty crop is ``(0, 0, 3)``."""
    x0, y0, w, h = (float(v) for v in box)
    height, width = image.shape[:2]
    pixels, offset = crop(image, clip_box(x0, y0, x0 + w, y0 + h, width, height))
    if pixels.size == 0:
        return np.zeros((0, 0, 3), np.uint8), offset
    return convert(pixels), offset


def silhouette(pixels: np.ndarray, lut: ColourLut | None) -> np.ndarray:
    """1 where the LUT says foreground, 0 elsewhere (uint8, the crop's shape); all 0 without a LUT."""
    if lut is None or pixels.size == 0:
        return np.zeros(pixels.shape[:2], np.uint8)
    return lut.lookup(pixels).view(np.uint8)
