"""Colour conversions of BGR (or grey) uint8 images, as the trackers' tables and histograms index them."""

from __future__ import annotations

import cv2
import numpy as np


def _bgr(image: np.ndarray) -> np.ndarray:
    # A crop of a frame goes to OpenCV as it is: OpenCV takes rows with a stride, so no copy first.
    if image.ndim == 2:
        return cv2.cvtColor(image, cv2.COLOR_GRAY2BGR)
    return image


def to_grey(image: np.ndarray, formula: str = "luma") -> np.ndarray:
    """The grey levels of a BGR (or already grey) uint8 image, by one of two formulas each caller
    keeps on purpose (their numbers differ):

    - ``"luma"``: OpenCV's ``COLOR_BGR2GRAY``, 0.299 R + 0.587 G + 0.114 B in fixed point, rounded
      to uint8 (what OpenCV's corner finders, LK and SGBM take); a grey image comes back as
      contiguous uint8;
    - ``"mean"``: the float32 mean of the channels (``image.astype(np.float32).mean(axis=-1)``); a grey
      image comes back as float32."""
    if formula == "luma":
        return cv2.cvtColor(image, cv2.COLOR_BGR2GRAY) if image.ndim == 3 else np.ascontiguousarray(image, np.uint8)
    if formula != "mean":
        raise ValueError(f"to_grey: formula is 'luma' or 'mean', not {formula!r}")
    if image.ndim == 3 and image.dtype == np.uint8 and image.shape[-1] == 3:
        # The float32 channel sum of uint8 is an exact integer (<= 765): summed as integers, then
        # divided, it is the same number as image.astype(np.float32).mean(axis=-1), ~8x cheaper.
        return (image[..., 0].astype(np.uint16) + image[..., 1] + image[..., 2]).astype(np.float32) / np.float32(3)
    return image.astype(np.float32).mean(axis=-1) if image.ndim == 3 else image.astype(np.float32)


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
