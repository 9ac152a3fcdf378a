"""Grey-level morphology with a disc: OpenCV's results, computed as row segments.

OpenCV erodes and dilates with a non-rectangular kernel by visiting every one of its points for
every pixel, so the cost grows with the square of the disc's width (a white top-hat with a 41 px
disc took ~3 ms on a 320 × 320 crop). A disc is, row by row, a centred segment: the minimum (or
maximum) over the disc is the minimum over its rows of the minimum over each row's segment. The
segments' minima of every half-width ``k`` come from those of ``k - 1`` in one elementwise step,
and the rows combine in one step each, so the cost grows with the width itself: ``3 r`` passes of
``np.minimum`` / ``np.maximum`` over the padded crop for a disc of radius ``r``, in two buffers
(each row folded in as soon as its half-width is there: the passes stay in cache). The image is
handled as one flat array (rows laid end to end): a shift by a column is a shift by one element, a
shift by a row one by the padded width, and the padding (OpenCV's default border: ignored, i.e.
255 for an erosion, 0 for a dilation) keeps every segment inside its own row.

Minima and maxima are exact, so the results are OpenCV's, bit for bit (pinned by
tests/trackers/foreground/test_morphology.py).
"""

from __future__ import annotations

import functools
from collections.abc import Callable

import cv2
import numpy as np

MIN_SIDE = 17  # below, OpenCV's own loop over the kernel's points is as fast or faster (measured 43² to 320² crops)


@functools.lru_cache(maxsize=64)
def ellipse_rows(side: int) -> tuple[int, ...] | None:
    """Half-width of each row of ``cv2.getStructuringElement(MORPH_ELLIPSE, (side, side))``, top to
    bottom (-1: an empty row); None unless ``side`` is odd and every row is one centred run."""
    if side < 1 or side % 2 == 0:
        return None
    kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (side, side)) != 0
    rows = []
    for row in kernel:
        ones = np.flatnonzero(row)
        if not ones.size:
            rows.append(-1)
            continue
        left, right = int(ones[0]), int(ones[-1])
        if right - left + 1 != ones.size or left + right != side - 1:
            return None
        rows.append((side - 1) // 2 - left)
    return tuple(rows)


def _by_rows(image: np.ndarray, rows: tuple[int, ...], border: int,
             extreme: Callable[..., np.ndarray]) -> np.ndarray:
    """``extreme`` (``np.minimum``: erosion, ``np.maximum``: dilation) of ``image`` over a kernel of
    centred row segments ``rows`` (half-widths, top to bottom), out-of-image pixels ``border``."""
    ry, rx = (len(rows) - 1) // 2, max(rows)
    h, w = image.shape
    wp = w + 2 * rx
    # One spare row above and below: every slice below starts and ends inside the array.
    flat = cv2.copyMakeBorder(image, ry + 1, ry + 1, rx, rx, cv2.BORDER_CONSTANT, value=border).reshape(-1)
    by_width: dict[int, list[int]] = {}
    for dy, k in zip(range(-ry, ry + 1), rows):
        if k >= 0:
            by_width.setdefault(k, []).append(dy)
    start, n = (ry + 1) * wp, h * wp
    out = None
    # segment[i]: the extreme of flat[i : i + 2k + 1] (centred on i + k), for k = 0, 1, ... in turn;
    # the rows of half-width k are folded in as soon as it is there, so two buffers suffice.
    segment, spare = flat, np.empty_like(flat)
    for k in range(rx + 1):
        if k == 1:
            segment = extreme(extreme(flat[:-2], flat[1:-1], out=spare[:-2]), flat[2:], out=spare[:-2])
            spare = np.empty_like(flat)
        elif k >= 2:  # [i, i + 2k] = [i, i + 2k - 2] ∪ [i + 2, i + 2k]
            segment, spare = extreme(segment[:-2], segment[2:], out=spare[:len(segment) - 2]), segment.base
        for dy in by_width.get(k, ()):
            at = start + dy * wp - k
            part = segment[at:at + n]
            out = part.copy() if out is None else extreme(out, part, out=out)
    return out.reshape(h, wp)[:, rx:rx + w]


def disc_top_hat(y: np.ndarray, side: int) -> np.ndarray:
    """``cv2.morphologyEx(y, cv2.MORPH_TOPHAT, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (side, side)))``
    of a 2-D uint8 image (OpenCV itself for small discs, even sides and empty images)."""
    if side >= MIN_SIDE and y.size and ellipse_rows(side) is not None:
        return top_hat_by_rows(y, side)
    return cv2.morphologyEx(y, cv2.MORPH_TOPHAT, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (side, side)))


def top_hat_by_rows(y: np.ndarray, side: int) -> np.ndarray:
    """:func:`disc_top_hat` by row segments whatever the disc's size (an odd ``side``; non-empty ``y``)."""
    rows = ellipse_rows(side)
    opened = _by_rows(_by_rows(y, rows, 255, np.minimum), rows, 0, np.maximum)
    return cv2.subtract(y, opened)  # the opening is never above the image: OpenCV's saturating difference, exactly
