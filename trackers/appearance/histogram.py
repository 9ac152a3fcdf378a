"""n-D colour histograms and their similarity (Swain & Ballard's intersection)."""

from __future__ import annotations

from collections.abc import Sequence
from functools import lru_cache

import cv2
import numpy as np


def colour_histogram(
    pixels: np.ndarray, bins: Sequence[int], ranges: Sequence[tuple[float, float]], mask: np.ndarray | None = None
) -> np.ndarray:
    """Normalised histogram (sums to 1, or all zeros for no pixel) of ``pixels`` (..., C).

    ``bins`` and ``ranges`` give one entry per channel used (the first ``len(bins)`` channels);
    ``mask`` (same leading shape, bool) selects the pixels counted.
    """
    dims = len(bins)
    values = np.asarray(pixels).reshape(-1, np.asarray(pixels).shape[-1])[:, :dims]
    if mask is not None:
        values = values[np.asarray(mask, dtype=bool).reshape(-1)]
    index = np.zeros(len(values), dtype=np.int64)
    for channel, (n, (lo, hi)) in enumerate(zip(bins, ranges)):  # a loop over channels, not pixels
        b = ((values[:, channel].astype(np.float64) - lo) * (n / (hi - lo))).astype(np.int64)
        index = index * n + np.clip(b, 0, n - 1)
    counts = np.bincount(index, minlength=int(np.prod(bins))).astype(np.float64).reshape(tuple(bins))
    total = counts.sum()
    return counts / total if total > 0 else counts


def intersection(h: np.ndarray, reference: np.ndarray) -> np.ndarray | float:
    """Swain's histogram intersection ``S = Σ_u min(h_u, ref_u)``; ``h`` may be a stack (K, …)."""
    h = np.asarray(h, dtype=np.float64)
    reference = np.asarray(reference, dtype=np.float64)
    axes = tuple(range(h.ndim - reference.ndim, h.ndim))
    return np.minimum(h, reference).sum(axis=axes)


def mix(weights: Sequence[float], histograms: Sequence[np.ndarray]) -> np.ndarray:
    """``Σ w_i H_i`` (e.g. a target histogram mixed with its background)."""
    return sum(float(w) * np.asarray(h, dtype=np.float64) for w, h in zip(weights, histograms, strict=True))


# --- bin-index images: one histogram per box, many boxes at once --------------------------------
#
# A particle filter weighs N boxes per frame. Converting the pixels to a bin index once (a small
# integer image) and counting every box's pixels with one ``np.bincount`` (box k's bins offset by
# k * n_bins) costs one pass over the boxes' pixels and no Python loop over the boxes.


def _axis_lut(n: int, lo: float, hi: float) -> np.ndarray:
    """Bin of each uint8 value on one channel, as :func:`colour_histogram` bins it."""
    values = np.arange(256, dtype=np.float64)
    return np.clip(((values - lo) * (n / (hi - lo))).astype(np.int64), 0, n - 1)


def hs_index(hsv: np.ndarray, bins: Sequence[int], ranges: Sequence[tuple[float, float]]) -> tuple[np.ndarray, int]:
    """Bin index ``h_bin * n_s + s_bin`` per pixel of an HSV image (V ignored), and the bin count.

    The bins are :func:`colour_histogram`'s over the first two channels, so a histogram of the
    indices equals ``colour_histogram(hsv, bins[:2], ranges[:2])`` flattened.
    """
    nh, ns = int(bins[0]), int(bins[1])
    lut = _hs_lut(nh, ns, (float(ranges[0][0]), float(ranges[0][1])), (float(ranges[1][0]), float(ranges[1][1])))
    if hsv.dtype == np.uint8:  # one flat look-up at h * 256 + s: the same entries as lut[h, s], ~1.5x cheaper
        return np.take(lut.reshape(-1), (hsv[..., 0].astype(np.uint16) << 8) | hsv[..., 1]), nh * ns
    return lut[hsv[..., 0], hsv[..., 1]], nh * ns


@lru_cache(maxsize=16)
def _hs_lut(nh: int, ns: int, range_h: tuple[float, float], range_s: tuple[float, float]) -> np.ndarray:
    """:func:`hs_index`'s (256, 256) int32 table of H-S bins, built once per binning (it costs more
    than looking up a box's pixels in it); read-only."""
    lut = (_axis_lut(nh, *range_h)[:, None] * ns + _axis_lut(ns, *range_s)[None, :]).astype(np.int32)
    lut.flags.writeable = False
    return lut


def hs_v_index(hsv: np.ndarray, bins: Sequence[int], ranges: Sequence[tuple[float, float]], *,
               s_min: float = 0.1, v_min: float = 0.2) -> tuple[np.ndarray, int]:
    """Pérez et al.'s HSV bins (ECCV 2002, §2): an H-S histogram of the coloured pixels next to a V
    histogram of the rest, ``n_h n_s + n_v`` bins in all.

    A pixel is coloured when its saturation and value reach ``s_min`` and ``v_min`` (fractions of
    their ranges, Pérez's 0.1 and 0.2); its index is its H-S bin. Any other pixel (grey, dark) gets
    ``n_h n_s + v_bin``.
    """
    hs, n_hs = hs_index(hsv, bins[:2], ranges[:2])
    nv = int(bins[2])
    (slo, shi), (vlo, vhi) = ranges[1], ranges[2]
    coloured = (hsv[..., 1] >= slo + s_min * (shi - slo)) & (hsv[..., 2] >= vlo + v_min * (vhi - vlo))
    v_bin = (n_hs + _axis_lut(nv, vlo, vhi)).astype(np.int32)[hsv[..., 2]]
    return np.where(coloured, hs, v_bin), n_hs + nv


def index_histogram(index: np.ndarray, n_bins: int, mask: np.ndarray | None = None) -> np.ndarray:
    """Normalised histogram (sums to 1, or all zeros) of a bin-index image, over ``mask`` if given."""
    values = index[np.asarray(mask, dtype=bool)] if mask is not None else index.reshape(-1)
    counts = np.bincount(values.reshape(-1), minlength=n_bins).astype(np.float64)
    total = counts.sum()
    return counts / total if total > 0 else counts


def box_histograms(index: np.ndarray, boxes: np.ndarray, n_bins: int, *,
                   max_pixels: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Normalised histograms of K boxes over one bin-index image, counted with one ``np.bincount``.

    ``boxes`` is (K, 4) integer ``x0, y0, x1, y1`` (half-open) inside ``index`` (clip them first,
    e.g. with :func:`trackreplay.trackers.geometry.box.clip_box`); an empty box gets an all-zero
    row. With ``max_pixels``, a box of more pixels is sampled on a regular grid of stride
    ``ceil(sqrt(area / max_pixels))`` from its top-left pixel. Returns the (K, n_bins) histograms
    and the (K,) number of pixels counted per box.

    Uniform pixel weights and one part of :func:`box_part_histograms`, which does the counting.
    """
    hists, n = box_part_histograms(index, boxes, n_bins, max_pixels=max_pixels)
    return hists[:, 0], n


# --- kernel-weighted, multi-part box histograms ---------------------------------------------------
#
# Comaniciu et al. (2003) and Pérez et al. (2002) weight each pixel by an Epanechnikov kernel of its
# distance from the box centre, ``k(r) = max(1 - r², 0)`` with ``r`` measured in half-widths and
# half-heights, so the box's border (where background leaks in) counts little. Pérez et al.'s
# multi-part model splits the box into parts (here horizontal bands, top to bottom), one histogram
# each. Both are weights and an extra index in the same single ``np.bincount``.

KERNELS = ("uniform", "epanechnikov")


def kernel_and_part(dy: np.ndarray, dx: np.ndarray, height: np.ndarray | float, width: np.ndarray | float,
                    kernel: str = "uniform", parts: int = 1, *,
                    out: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Weight and part index of pixels at offsets ``(dy, dx)`` (pixel centres, from the box's
    top-left corner) in boxes of ``height`` x ``width`` (all broadcast together).

    ``"uniform"``: weight 1; ``"epanechnikov"``: ``max(1 - u² - v², 0)`` with ``u = (dx - w/2)/(w/2)``,
    ``v = (dy - h/2)/(h/2)``. The part is the horizontal band ``floor(parts dy / h)`` (0 = top).
    ``out``: a float64 array of the broadcast shape the Epanechnikov weights are written into (the same numbers).
    """
    dy = np.asarray(dy, dtype=np.float64)
    dx = np.asarray(dx, dtype=np.float64)
    hh = np.maximum(np.asarray(height, dtype=np.float64), 1e-9)
    ww = np.maximum(np.asarray(width, dtype=np.float64), 1e-9)
    if kernel == "uniform":
        weight = np.ones(np.broadcast_shapes(dy.shape, dx.shape, hh.shape, ww.shape))
    elif kernel == "epanechnikov":
        u = (dx - ww / 2.0) / (ww / 2.0)
        v = (dy - hh / 2.0) / (hh / 2.0)
        weight = np.subtract(1.0 - u * u, v * v, out=out)  # (1 - u²) - v², as written out; then clipped in place
        np.maximum(weight, 0.0, out=weight)
    else:
        raise ValueError(f"kernel must be one of {', '.join(KERNELS)}, not {kernel!r}")
    part = np.clip(np.floor(parts * dy / hh), 0, parts - 1).astype(np.int64)
    return weight, np.broadcast_to(part, weight.shape)


SCRATCH_MAX = 1 << 20  # elements: a larger block (a scan of thousands of boxes) is allocated afresh, not kept


def _scratch(scratch: dict[str, np.ndarray] | None, name: str, shape: tuple[int, int, int],
             dtype: np.dtype) -> np.ndarray | None:
    """A C-ordered array of ``shape`` in ``scratch``'s buffer ``name`` (grown as needed), or None without one."""
    n = shape[0] * shape[1] * shape[2]
    if scratch is None or n > SCRATCH_MAX:
        return None
    kept = scratch.get(name)
    if kept is None or kept.size < n or kept.dtype != dtype:
        kept = np.empty(max(n, 1), dtype)
        scratch[name] = kept
    return kept[:n].reshape(shape)


def box_part_histograms(index: np.ndarray, boxes: np.ndarray, n_bins: int, *, kernel: str = "uniform",
                        parts: int = 1, max_pixels: int | None = None,
                        scratch: dict[str, np.ndarray] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Like :func:`box_histograms`, with kernel weights and ``parts`` bands per box: (K, parts, n_bins)
    histograms, each part normalised to sum 1 over its weights (all zeros when it holds no weight),
    and the (K,) number of pixels counted per box. One ``np.bincount`` over all boxes and parts.

    The boxes' pixels are gathered as one (K, rows, columns) block padded to the largest box
    (boxes of one tracker differ in size by tens of per cent), the padding weighted 0. ``scratch``: a dict
    the caller keeps between calls, whose buffers hold the block's weights, pixel offsets and bins (the same
    numbers; a fresh block of ~100,000 elements a call costs more in page faults than in arithmetic). The
    returned arrays never share its memory.
    """
    boxes = np.asarray(boxes, dtype=np.int64).reshape(-1, 4)
    k = len(boxes)
    x0, y0 = boxes[:, 0], boxes[:, 1]
    w = np.maximum(boxes[:, 2] - x0, 0)
    h = np.maximum(boxes[:, 3] - y0, 0)
    stride = np.ones(k, dtype=np.int64)
    if max_pixels is not None:
        stride = np.maximum(np.ceil(np.sqrt(w * h / float(max_pixels))).astype(np.int64), 1)
    nx, ny = -(-w // stride), -(-h // stride)
    n = nx * ny
    if k == 0 or n.max(initial=0) == 0:
        return np.zeros((k, parts, n_bins)), n
    rows, cols = np.arange(int(ny.max())), np.arange(int(nx.max()))
    block = (k, len(rows), len(cols))
    s = stride[:, None, None]
    dy, dx = s * rows[None, :, None] + 0.5, s * cols[None, None, :] + 0.5  # (K, R, 1), (K, 1, C)
    weight_out = _scratch(scratch, "weight", block, np.dtype(np.float64))
    weight, part = kernel_and_part(dy, dx, h[:, None, None], w[:, None, None], kernel, parts,
                                   out=weight_out if kernel == "epanechnikov" else None)
    if kernel == "uniform":
        inside = (rows[None, :, None] < ny[:, None, None], cols[None, None, :] < nx[:, None, None])
        weight = np.logical_and(*inside).astype(np.float64) if weight_out is None else \
            np.logical_and(*inside, out=weight_out)  # 1.0 and 0.0 either way
    # else the padding (dy >= h + 1/2 or dx >= w + 1/2: r > 1) already weighs +0.0: it reads any pixel
    # (np.take clips), and adding +0.0 to its box's bin leaves the sums in the same order, the same bits
    flat = np.add((y0 * index.shape[1] + x0)[:, None, None] + s * rows[None, :, None] * index.shape[1],
                  s * cols[None, None, :], out=_scratch(scratch, "flat", block, np.dtype(np.int64)))
    slot = np.arange(k)[:, None, None] * parts + part[:, :, :1]  # (box, part): a part is a band of rows
    taken = np.take(index.reshape(-1), flat, mode="clip", out=_scratch(scratch, "taken", block, index.dtype))
    # the bins written over the pixel offsets, no longer needed (one large array fewer: the same numbers)
    bins = np.add(taken, slot * n_bins, out=flat)
    counts = np.bincount(bins.reshape(-1), weights=weight.reshape(-1), minlength=k * parts * n_bins)
    counts = counts.reshape(k, parts, n_bins)
    total = counts.sum(axis=2, keepdims=True)
    return np.where(total > 0, counts / np.where(total > 0, total, 1.0), 0.0), n


def image_part_histograms(index: np.ndarray, n_bins: int, *, kernel: str = "uniform", parts: int = 1,
                          mask: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every pixel of a bin-index image taken as one box: the (parts, n_bins) kernel-weighted
    histograms over ``mask`` (all pixels if None), and per part the weight inside ``mask`` and in all.

    ``weight_in[p] / weight_all[p]`` is the kernel-weighted share of part ``p`` that ``mask`` covers
    (e.g. eq. (7)'s ``P_detect / P_square`` per part).
    """
    hgt, wid = index.shape[:2]
    weight, part = kernel_and_part(np.arange(hgt)[:, None] + 0.5, np.arange(wid)[None, :] + 0.5, hgt, wid,
                                   kernel, parts)
    keep = np.ones((hgt, wid), bool) if mask is None else np.asarray(mask, dtype=bool)
    slot = (part * n_bins + index).reshape(-1)
    counts = np.bincount(slot, weights=np.where(keep, weight, 0.0).reshape(-1),
                         minlength=parts * n_bins).reshape(parts, n_bins)
    weight_all = np.bincount(part.reshape(-1), weights=weight.reshape(-1), minlength=parts)
    weight_in = counts.sum(axis=1)
    return np.where(weight_in[:, None] > 0, counts / np.where(weight_in > 0, weight_in, 1.0)[:, None], 0.0), \
        weight_in, weight_all


# --- counts per level of small integers ------------------------------------------------------------

_CALCHIST_MAX = 1 << 24  # float32 counts are exact integers up to here
_CALCHIST_MIN = 12_000  # below (~110 x 110 px), np.bincount's cost is less than cv2.calcHist's call (measured)


def level_counts(values: np.ndarray, low: int = 0, levels: int = 256) -> np.ndarray:
    """``np.bincount((values.ravel() - low).astype(np.intp), minlength=levels)`` for a 2-D uint8 or
    int16 image whose values lie in ``[low, low + levels)``, counted by ``cv2.calcHist`` (no
    8-byte index per pixel; its float32 counts are exact below 2^24 pixels). A small image, any
    other input, or a value outside the range, is counted by ``np.bincount`` itself (the same
    answer, or its error)."""
    if values.ndim == 2 and _CALCHIST_MIN <= values.size < _CALCHIST_MAX and levels <= 65536:
        source = None
        if values.dtype == np.uint8 and low == 0:
            source = values
        elif values.dtype == np.int16 and -32768 <= low <= 0 and low + levels <= 32768:
            source = (values - np.int16(low)).view(np.uint16)  # values below low wrap to large ones: out of range
        if source is not None:
            counts = cv2.calcHist([source], [0], None, [levels], [0, levels]).reshape(-1).astype(np.int64)
            if int(counts.sum()) == values.size:  # every value was in range
                return counts
    return np.bincount((values.ravel() - low).astype(np.intp), minlength=levels)
