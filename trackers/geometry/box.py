"""Axis-aligned boxes in pixels: clip to the image, crop with the offset that places the crop."""

from __future__ import annotations

import numpy as np


def clip_box(x0: float, y0: float, x1: float, y1: float, width: int, height: int) -> tuple[int, int, int, int]:
    """Integer ``(x0, y0, x1, y1)`` inside a ``width × height`` image (half-open; may be empty)."""
    cx0 = int(min(max(np.floor(x0), 0), width))
    cy0 = int(min(max(np.floor(y0), 0), height))
    cx1 = int(min(max(np.ceil(x1), cx0), width))
    cy1 = int(min(max(np.ceil(y1), cy0), height))
    return cx0, cy0, cx1, cy1


def centre_box(cx: float, cy: float, w: float, h: float) -> tuple[float, float, float, float]:
    """Corners of the box with centre ``(cx, cy)`` and size ``w × h``."""
    return cx - w / 2.0, cy - h / 2.0, cx + w / 2.0, cy + h / 2.0


def crop(image: np.ndarray, box: tuple[int, int, int, int]) -> tuple[np.ndarray, tuple[int, int]]:
    """The pixels of a clipped box (a view, not a copy) and its top-left offset ``(x0, y0)``."""
    x0, y0, x1, y1 = box
    return image[y0:y1, x0:x1], (x0, y0)


def iou(a: np.ndarray, b: np.ndarray, *, centred: bool = False) -> np.ndarray:
    """Intersection over union of boxes ``(x, y, w, h)`` (the last axis), broadcast over the other
    axes: rows pair row by row, ``a[:, None]`` with ``b[None]`` gives every pair. ``(x, y)`` is the
    top-left corner, or the centre when ``centred``; 0 where the union is empty."""
    a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
    if centred:
        a_lo, a_hi = a[..., :2] - a[..., 2:] / 2, a[..., :2] + a[..., 2:] / 2
        b_lo, b_hi = b[..., :2] - b[..., 2:] / 2, b[..., :2] + b[..., 2:] / 2
    else:
        a_lo, a_hi = a[..., :2], a[..., :2] + a[..., 2:]
        b_lo, b_hi = b[..., :2], b[..., :2] + b[..., 2:]
    side = np.clip(np.minimum(a_hi, b_hi) - np.maximum(a_lo, b_lo), 0.0, None)
    inter = side[..., 0] * side[..., 1]
    union = a[..., 2] * a[..., 3] + b[..., 2] * b[..., 3] - inter
    return np.where(union > 0, inter / np.where(union > 0, union, 1.0), 0.0)
