"""The field of view that follows the target, and background compensation (§4.2, eq. 26).

The log holds the fixed camera's whole scene; the tracker's "camera" is a ``fov``×``fov`` window
at an integer centre. Cropping both frames of a flow step at the SAME centre undoes the camera
motion that followed the target (eq. 26), so the background's flow is zero and the target's is
its velocity. Where the window passes the image edge the edge pixels repeat.
"""

from __future__ import annotations

import math

import numpy as np


def fov_origin(centre: tuple[int, int], size: int) -> tuple[int, int]:
    """Column and row of the window's first pixel."""
    return centre[0] - size // 2, centre[1] - size // 2


def crop(image: np.ndarray, centre: tuple[int, int], size: int) -> np.ndarray:
    """``size``×``size`` window of ``image`` centred on integer ``centre`` (x, y), edge-replicated."""
    h, w = image.shape[:2]
    x0, y0 = fov_origin(centre, size)
    if 0 <= x0 and 0 <= y0 and x0 + size <= w and y0 + size <= h:
        return np.ascontiguousarray(image[y0 : y0 + size, x0 : x0 + size])
    rows = np.clip(np.arange(y0, y0 + size), 0, h - 1)
    cols = np.clip(np.arange(x0, x0 + size), 0, w - 1)
    return np.ascontiguousarray(image[np.ix_(rows, cols)])


def next_centre(position: np.ndarray, shape: tuple[int, int]) -> tuple[int, int]:
    """Integer FOV centre at the filtered position (the paper controls in whole pixels),
    kept on the image so the window always overlaps it."""
    h, w = shape[:2]
    x, y = float(position[0]), float(position[1])
    if math.isfinite(x) and math.isfinite(y):  # plain floats: what numpy's floor and clip give, faster
        return min(max(math.floor(x + 0.5), 0), w - 1), min(max(math.floor(y + 0.5), 0), h - 1)
    x = int(np.clip(np.floor(position[0] + 0.5), 0, w - 1))
    y = int(np.clip(np.floor(position[1] + 0.5), 0, h - 1))
    return x, y


def inside(position: np.ndarray, shape: tuple[int, int]) -> bool:
    h, w = shape[:2]
    x, y = float(position[0]), float(position[1])
    return math.isfinite(x) and math.isfinite(y) and -0.5 <= x < w - 0.5 and -0.5 <= y < h - 0.5


def shift_field(a: np.ndarray, dx: int, dy: int, fill: float = 0.0) -> np.ndarray:
    """``out[y, x] = a[y − dy, x − dx]``: content moves by (dx, dy); uncovered pixels get ``fill``."""
    out = np.full_like(a, fill)
    h, w = a.shape
    if abs(dx) >= w or abs(dy) >= h:
        return out
    ys, yd = (slice(0, h - dy), slice(dy, h)) if dy >= 0 else (slice(-dy, h), slice(0, h + dy))
    xs, xd = (slice(0, w - dx), slice(dx, w)) if dx >= 0 else (slice(-dx, w), slice(0, w + dx))
    out[yd, xd] = a[ys, xs]
    return out
