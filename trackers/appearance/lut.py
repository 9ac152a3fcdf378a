"""Colour lookup tables: a 256 × 256 × 256 boolean per colour, learnt from sample pixels.

A table answers "foreground or not?" for a pixel with one index (``c0·65536 + c1·256 + c2``),
so segmenting a region is a single fancy index however complex the colour boundary is.

Learning (:class:`ColourCounts`): foreground and background sample pixels are counted on a coarse
grid (``256 / bin`` levels per channel), both counts are smoothed in colour space (a colour near a
foreground colour counts as foreground too), and a colour is foreground where
``foreground_weight × smoothed foreground count > background_scale × smoothed background count``
and the smoothed foreground count exceeds ``min_count`` (:func:`two_class_table`). Counts, not
densities: the prior that foreground samples are few is kept, so a colour the background shares
with the target stays background unless the target dominates it. The coarse decision *is* the
table: a lookup indexes it with each channel shifted down by ``log2(bin)``, which answers exactly
what the expanded 256³ table (:func:`expand_table`, :attr:`ColourLut.table`) would, without
building 16 MB on every relearn, and from a table small enough to stay in cache. The channel
order is the caller's (the golf tracker uses Y, Cb, Cr).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np


def flat_index(pixels: np.ndarray) -> np.ndarray:
    """Flat index ``c0*65536 + c1*256 + c2`` of ``(..., 3)`` uint8 pixels into a C-ordered 256³ table."""
    c0 = pixels[..., 0].astype(np.int32)
    return (c0 << 16) | (pixels[..., 1].astype(np.int32) << 8) | pixels[..., 2].astype(np.int32)


def coarse_counts(pixels: np.ndarray, bin_: int) -> np.ndarray:
    """Counts of ``(..., 3)`` uint8 pixels on a ``(256/bin_)³`` grid (float64).

    Each pixel's cell ``(c0 // bin_ * q + c1 // bin_) * q + c2 // bin_`` is :func:`coarse_index`'s
    (``bin_`` divides 256: a power of 2, so the divisions are shifts)."""
    q = 256 // bin_
    cells = coarse_index(pixels.reshape(-1, 3), bin_)
    return np.bincount(cells, minlength=q**3).astype(np.float64).reshape(q, q, q)


def smooth3(values: np.ndarray, sigma: float) -> np.ndarray:
    """Separable Gaussian smoothing of a 3-D array (``sigma`` in cells, zero outside the array).

    Computed over the non-zero cells' bounding box widened by the kernel's radius only (a colour
    histogram fills a small part of its cube): every cell outside it is 0 and every cell inside gets
    the same sums in the same order as over the whole array, since the terms left out are all 0."""
    if sigma <= 0:
        return values
    r = int(np.ceil(3 * sigma))
    support = support_box(values)
    out = np.zeros_like(values)
    if support is None:
        return out
    box = tuple(slice(max(lo - r, 0), min(hi + r + 1, n)) for (lo, hi), n in zip(support, values.shape))
    out[box] = _smooth3_dense(np.ascontiguousarray(values[box]), sigma)
    return out


def support_box(values: np.ndarray) -> list[tuple[int, int]] | None:
    """Per axis, the lowest and highest index of a non-zero value (the min and max of
    ``np.nonzero(values)``'s indices; None when all are zero), from one occupancy test and a
    reduction per axis (``np.nonzero`` builds every index of the cube: ~1 ms on 64³)."""
    occupied = values != 0
    box = []
    for axis in range(values.ndim):
        along = np.flatnonzero(occupied.any(axis=tuple(a for a in range(values.ndim) if a != axis)))
        if not along.size:
            return None
        box.append((int(along[0]), int(along[-1])))
    return box


def _smooth3_dense(values: np.ndarray, sigma: float) -> np.ndarray:
    """:func:`smooth3` over the whole array."""
    r = int(np.ceil(3 * sigma))
    k = np.exp(-0.5 * (np.arange(-r, r + 1) / sigma) ** 2)
    k /= k.sum()
    out = values
    for axis in range(3):  # a loop over axes and kernel taps, each a whole-array operation
        acc = np.zeros_like(out)
        n = out.shape[axis]
        for off, wgt in zip(range(-r, r + 1), k):
            src = [slice(None)] * 3
            dst = [slice(None)] * 3
            if off >= 0:
                src[axis], dst[axis] = slice(0, n - off), slice(off, n)
            else:
                src[axis], dst[axis] = slice(-off, n), slice(0, n + off)
            acc[tuple(dst)] += wgt * out[tuple(src)]
        out = acc
    return out


def expand_table(coarse: np.ndarray, bin_: int) -> np.ndarray:
    """Coarse ``(q, q, q)`` booleans -> the 256³ table (each coarse cell repeated ``bin_³`` times)."""
    if bin_ == 1:
        return np.ascontiguousarray(coarse)
    q = coarse.shape[0]
    big = np.broadcast_to(coarse[:, None, :, None, :, None], (q, bin_, q, bin_, q, bin_))
    return np.ascontiguousarray(big).reshape(256, 256, 256)


def two_class_table(foreground: np.ndarray, background: np.ndarray, *, smooth: float, foreground_weight: float,
                    min_count: float, background_scale: float = 1.0) -> np.ndarray:
    """The coarse decision: ``w·smooth(fg) > s·smooth(bg)`` and ``smooth(fg) > min_count``.

    ``background_scale`` puts subsampled background counts back on the foreground's footing
    (e.g. ``stride²`` when every ``stride``-th pixel per axis was counted).
    """
    if smooth <= 0:
        return (foreground_weight * foreground > background * background_scale) & (foreground > min_count)
    # Only where the smoothed foreground is non-zero can a cell be "ball": the decision is made over
    # the foreground's support (+ the kernel radius), the background smoothed over that box widened
    # by the radius again (every sum the box's cells need, in the same order: the same numbers).
    r = int(np.ceil(3 * smooth))
    out = np.zeros(foreground.shape, bool)
    support = support_box(foreground)
    if support is None:
        return out
    shape = foreground.shape
    lo = [max(a - r, 0) for a, _ in support]
    hi = [min(b + r + 1, n) for (_, b), n in zip(support, shape)]
    wide_lo, wide_hi = [max(v - r, 0) for v in lo], [min(v + r, n) for v, n in zip(hi, shape)]
    box = tuple(slice(a, b) for a, b in zip(lo, hi))
    inner = tuple(slice(a - w, b - w) for a, b, w in zip(lo, hi, wide_lo))
    fg = _smooth3_dense(np.ascontiguousarray(foreground[box]), smooth)
    wide = tuple(slice(a, b) for a, b in zip(wide_lo, wide_hi))
    bg = _smooth3_dense(np.ascontiguousarray(background[wide]), smooth)[inner] * background_scale
    out[box] = (foreground_weight * fg > bg) & (fg > min_count)
    return out


def coarse_index(pixels: np.ndarray, bin_: int) -> np.ndarray:
    """Flat index of ``(..., 3)`` uint8 pixels into a C-ordered ``(256/bin_)³`` table (``bin_`` a power of 2)."""
    shift = int(bin_).bit_length() - 1
    bits = 8 - shift
    # Shifted down as uint8 (a quarter of the memory traffic), widened once, combined in place.
    index = (pixels[..., 0] >> shift).astype(np.int32)
    index <<= 2 * bits
    middle = (pixels[..., 1] >> shift).astype(np.int32)
    middle <<= bits
    index |= middle
    index |= pixels[..., 2] >> shift
    return index


@dataclass(frozen=True, eq=False)
class ColourLut:
    """A boolean table over three uint8 channels: ``coarse`` holds one decision per ``bin³`` cell
    (``bin`` = 1: the full 256³ table)."""

    coarse: np.ndarray
    bin: int = 1

    def __post_init__(self) -> None:
        if self.bin < 1 or 256 % self.bin:
            raise ValueError(f"a LUT's bin must be a power of 2 up to 256, not {self.bin}")
        q = 256 // self.bin
        if self.coarse.shape != (q, q, q):
            raise ValueError(f"a LUT with bin {self.bin} needs a ({q}, {q}, {q}) table, not {self.coarse.shape}")

    def lookup(self, pixels: np.ndarray) -> np.ndarray:
        """Boolean mask (the pixels' leading shape): one fancy index into the coarse table."""
        # bin 1: flat_index's index; ``take`` gathers what fancy indexing does, faster for an int32 index
        return self.coarse.reshape(-1).take(coarse_index(pixels, self.bin))

    @functools.cached_property
    def table(self) -> np.ndarray:
        """The full 256³ table (built on first use: for inspection; lookups never need it)."""
        return expand_table(self.coarse, self.bin)


class ColourCounts:
    """Foreground and background sample counts on the coarse grid, accumulated over many images."""

    def __init__(self, bin_: int) -> None:
        if bin_ < 1 or 256 % bin_:
            raise ValueError(f"the LUT bin must divide 256, not {bin_}")
        q = 256 // bin_
        self.bin = bin_
        self.foreground = np.zeros((q, q, q))
        self.background = np.zeros((q, q, q))

    def add(self, foreground: np.ndarray, background: np.ndarray) -> None:
        """Count ``(..., 3)`` uint8 foreground and background sample pixels."""
        self.foreground += coarse_counts(foreground, self.bin)
        self.background += coarse_counts(background, self.bin)

    def lut(self, *, smooth: float, foreground_weight: float, min_count: float, background_scale: float = 1.0) -> ColourLut:
        """The 256³ table of the counts so far (see :func:`two_class_table`)."""
        coarse = two_class_table(self.foreground, self.background, smooth=smooth, foreground_weight=foreground_weight,
                                 min_count=min_count, background_scale=background_scale)
        return ColourLut(np.ascontiguousarray(coarse), self.bin)
