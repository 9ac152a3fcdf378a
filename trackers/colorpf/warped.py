"""Eq. (7)'s background in this frame's view, warped only where it is read (``camera.compensate``).

A moving camera carries the background (kept in the marked frame's view) into each frame's view
(:func:`.camera.warp`), and the registration-tolerant test reads its 3x3 minimum and maximum
(:func:`.foreground.tolerance_band`). Warping the whole picture every frame was a seventh of the tracker's
time on otb_human3 (profiled, docs/colorpf.md "Speed, issue 31"), while a frame reads only the whole-frame
statistics' grid (every 4th pixel per axis, :func:`.foreground.scene_changed`, :func:`.foreground.brightness_gain`)
and crops round the particles and the estimate (a few per cent of the picture).

:class:`WarpedBackground` warps what is read: the grid at a quarter of the size with the inverse map's linear
part times 4 (OpenCV computes an output pixel from its own coordinates: the grid is the full warp's, bit for
bit), and each crop on its own with the map shifted to the crop's corner (the same pixels but for the
rounding of that shift: a pixel now and then one grey level off, at most 0.1 % of them in the test; the
foreground threshold is 25 levels). A read of most of the picture warps it whole, once. :class:`WarpedBand`
is the band of such a background, each crop's 3x3 minimum or maximum taken over the crop and a pixel of margin
(at the picture's edge the crop's edge is the picture's, elsewhere the margin holds the neighbours). On the box
corpus every replay (seeds 0-4) has the digest it had with the whole warp.
"""

from __future__ import annotations

import cv2
import numpy as np

from trackreplay.trackers.colorpf.camera import resamples

_NEIGHBOURHOOD = np.ones((3, 3), np.uint8)


def _bounds(key: tuple[slice, slice], height: int, width: int) -> tuple[int, int, int, int, int]:
    """``(y0, y1, x0, x1, step)`` of a 2-D slice with one step on both axes."""
    rows, cols = key
    y0, y1, sy = rows.indices(height)
    x0, x1, sx = cols.indices(width)
    if sy != sx or sy < 1:
        raise IndexError("a warped background is read by crops or by one grid step on both axes")
    return y0, y1, x0, x1, sy


class WarpedBackground:
    """``source`` (the marked frame's view) carried by ``transform`` (3x3; content at p goes to T p, the
    uncovered border repeating the edge, as :func:`.camera.warp`), read as ``[y0:y1, x0:x1]`` or
    ``[::k, ::k]``; a not-whole-pixel transform interpolates (bilinear), a whole-pixel one copies pixels."""

    def __init__(self, source: np.ndarray, transform: np.ndarray) -> None:
        self.source = source
        self.shape = source.shape
        self.dtype = source.dtype
        self.ndim = source.ndim
        self._inverse = cv2.invertAffineTransform(np.asarray(transform, dtype=np.float64)[:2])
        self._flags = (cv2.INTER_LINEAR if resamples(transform) else cv2.INTER_NEAREST) | cv2.WARP_INVERSE_MAP
        self._whole: np.ndarray | None = None  # the whole warp, once a read asked for most of it
        self._crops: dict[tuple[int, int, int, int], np.ndarray] = {}  # each crop read, warped on its own
        self._grids: dict[int, np.ndarray] = {}

    def _warp(self, inverse: np.ndarray, size: tuple[int, int]) -> np.ndarray:
        return cv2.warpAffine(self.source, inverse, size, flags=self._flags, borderMode=cv2.BORDER_REPLICATE)

    def __getitem__(self, key: tuple[slice, slice]) -> np.ndarray:
        height, width = self.shape[:2]
        y0, y1, x0, x1, step = _bounds(key, height, width)
        if step > 1:
            if (y0, x0) != (0, 0) or y1 < height or x1 < width:
                raise IndexError("a warped background's grid is read over the whole picture")
            grid = self._grids.get(step)
            if grid is None:
                inverse = self._inverse.copy()
                inverse[:, :2] *= step  # grid pixel (i, j) is the picture's (step i, step j): the same coordinates
                grid = self._warp(inverse, (-(-width // step), -(-height // step)))
                self._grids[step] = grid
            return grid
        if y1 <= y0 or x1 <= x0:
            return np.empty((max(y1 - y0, 0), max(x1 - x0, 0)) + self.shape[2:], self.dtype)
        if self._whole is not None:
            return self._whole[y0:y1, x0:x1]
        crop = self._crops.get((y0, y1, x0, x1))
        if crop is None:
            if (y1 - y0) * (x1 - x0) * 2 >= height * width:  # most of the picture: the whole warp, once
                self._whole = self._warp(self._inverse, (width, height))
                return self._whole[y0:y1, x0:x1]
            inverse = self._inverse.copy()
            inverse[:, 2] += self._inverse[:, :2] @ np.array([x0, y0], dtype=np.float64)  # output (0, 0) is (x0, y0)
            crop = self._warp(inverse, (x1 - x0, y1 - y0))
            self._crops[(y0, y1, x0, x1)] = crop
        return crop

    def full(self) -> np.ndarray:
        """The whole warp."""
        return self[0:self.shape[0], 0:self.shape[1]]


class WarpedBand:
    """One side of :func:`.foreground.tolerance_band` of a :class:`WarpedBackground` (``cv2.erode``: the 3x3
    minimum; ``cv2.dilate``: the maximum), read by crops ``[y0:y1, x0:x1]``."""

    def __init__(self, background: WarpedBackground, morph) -> None:
        self.background = background
        self.shape = background.shape
        self.dtype = background.dtype
        self.ndim = background.ndim
        self._morph = morph

    def __getitem__(self, key: tuple[slice, slice]) -> np.ndarray:
        height, width = self.shape[:2]
        y0, y1, x0, x1, step = _bounds(key, height, width)
        if step != 1:
            raise IndexError("a warped band is read by crops")
        if y1 <= y0 or x1 <= x0:
            return self.background[y0:y1, x0:x1]  # empty
        b0, b1, a0, a1 = max(y0 - 1, 0), min(y1 + 1, height), max(x0 - 1, 0), min(x1 + 1, width)
        out = self._morph(np.ascontiguousarray(self.background[b0:b1, a0:a1]), _NEIGHBOURHOOD)
        return out[y0 - b0:y1 - b0, x0 - a0:x1 - a0]


def warped_band(background: WarpedBackground) -> tuple[WarpedBand, WarpedBand]:
    """:func:`.foreground.tolerance_band` of ``background``, made crop by crop as it is read."""
    return WarpedBand(background, cv2.erode), WarpedBand(background, cv2.dilate)


__all__ = ["WarpedBackground", "WarpedBand", "warped_band"]
