"""The binary silhouette I_c inside the search region I_s only (seed 000, §2.1)."""

from __future__ import annotations

import numpy as np

from trackreplay.trackers.golf.lut import ColourLut, to_ycc


def region_slice(box: np.ndarray, width: int, height: int) -> tuple[int, int, int, int]:
    """Integer ``x0, y0, x1, y1`` of an ``(x0, y0, w, h)`` box, clipped to the image."""
    x0, y0, w, h = (float(v) for v in box)
    a = int(np.clip(np.floor(x0), 0, width))
    b = int(np.clip(np.floor(y0), 0, height))
    c = int(np.clip(np.ceil(x0 + w), a, width))
    d = int(np.clip(np.ceil(y0 + h), b, height))
    return a, b, c, d


def crop_ycc(image: np.ndarray, box: np.ndarray) -> tuple[np.ndarray, tuple[int, int]]:
    """The search region of ``image`` in (Y, Cb, Cr) and its top-left offset in the frame.

    Only the crop is converted: the full HD frame is never touched.
    """
    height, width = image.shape[:2]
    x0, y0, x1, y1 = region_slice(box, width, height)
    crop = image[y0:y1, x0:x1]
    if crop.size == 0:
        return np.zeros((0, 0, 3), np.uint8), (x0, y0)
    return to_ycc(crop), (x0, y0)


def silhouette(ycc: np.ndarray, lut: ColourLut | None) -> np.ndarray:
    """``I_c``: 1 where the LUT says ball, 0 elsewhere (uint8, the crop's shape)."""
    if lut is None or ycc.size == 0:
        return np.zeros(ycc.shape[:2], np.uint8)
    return lut.lookup(ycc).view(np.uint8)
