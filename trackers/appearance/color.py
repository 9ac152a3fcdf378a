"""Colour conversions of BGR (or grey) uint8 images, as the trackers' tables and histograms index them."""

from __future__ import annotations

import cv2
import numpy as np


def _bgr(image: np.ndarray) -> np.ndarray:
    # A crop of a frame goes to OpenCV as it is: OpenCV takes rows with a stride, so no copy first.
    if image.ndim == 2:
        return cv2.cvtColor(image, cv2.COLOR_GRAY2BGR)
    return image


def to_ycrcb(image: np.ndarray) -> np.ndarray:
    """(..., 3) uint8 in OpenCV's (Y, Cr, Cb) order, interleaved (C-ordered)."""
    return cv2.cvtColor(_bgr(image), cv2.COLOR_BGR2YCrCb)


def to_ycbcr(image: np.ndarray) -> np.ndarray:
    """(..., 3) uint8 in (Y, Cb, Cr) order (OpenCV gives Y, Cr, Cb).

    The channels are picked as planes (``(3, h, w)`` memory seen as ``(h, w, 3)``): the values and
    the memory layout of ``ycrcb[..., [0, 2, 1]]``, which numpy builds the same way, at a third of
    its cost on a large crop."""
    return to_ycrcb(image).transpose(2, 0, 1)[_YCBCR_PLANES].transpose(1, 2, 0)


_YCBCR_PLANES = np.array([0, 2, 1])  # Y, Cb, Cr out of OpenCV's Y, Cr, Cb


def to_hsv(image: np.ndarray) -> np.ndarray:
    """(..., 3) uint8 H, S, V with OpenCV's ranges: H in [0, 180), S and V in [0, 256)."""
    return cv2.cvtColor(_bgr(image), cv2.COLOR_BGR2HSV)


HSV_RANGES = ((0.0, 180.0), (0.0, 256.0), (0.0, 256.0))  # value ranges of to_hsv's channels


def saturated_share(image: np.ndarray, s_min: float) -> float:
    """The share of pixels whose HSV saturation is at least ``s_min`` (a fraction of its range):
    0 for a grey picture (one channel, or three equal ones), most of a colour one."""
    if image.ndim == 2 or image.shape[-1] == 1:
        return 0.0
    return float(np.count_nonzero(to_hsv(image)[..., 1] >= s_min * 256.0)) / max(image.shape[0] * image.shape[1], 1)
