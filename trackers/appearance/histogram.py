"""n-D colour histograms and their similarity (Swain & Ballard's intersection)."""

from __future__ import annotations

from collections.abc import Sequence

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
