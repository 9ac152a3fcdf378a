"""Medians as ``np.median`` gives them, at less cost: the trackers take many small ones a frame.

:func:`median` partitions a float array once (``np.median``'s per-call overhead is most of a call on
~100 values); :func:`median_and_mad` reads an integer image's median and median absolute deviation
off its counts per grey level (no sort of the pixels).
"""

from __future__ import annotations

import numpy as np

from trackreplay.trackers.appearance.histogram import level_counts


def median(values: np.ndarray) -> float:
    """``float(np.median(values))`` of a 1-D float array: the same partition and the same mean of the
    two middle values in the array's precision; NaN for an empty array or one holding a NaN."""
    n = len(values)
    if n == 0:
        return float("nan")
    half = n // 2
    part = np.partition(values, (half - 1, half, n - 1) if n % 2 == 0 else (half, n - 1))
    if np.isnan(part[-1]):  # np.median: NaN in, NaN out
        return float("nan")
    return float(part[half]) if n % 2 else float((part[half - 1] + part[half]) / 2)


def median_and_mad(values: np.ndarray, low: int, levels: int) -> tuple[float, float]:
    """``np.median`` of integer ``values`` (all in ``[low, low + levels)``) and ``np.median`` of their
    absolute deviations from it, read off the counts per level: the middle one or two of the
    sorted values (and of the sorted deviations), averaged. The same numbers: every value,
    deviation and mean of two is a multiple of 1/4 far below 2^20, exact in float32 and float64."""
    counts = level_counts(values, low, levels)
    n = int(values.size)
    middle = np.array([(n - 1) // 2, n // 2])
    lo, hi = (np.searchsorted(np.cumsum(counts), middle, side="right") + low).tolist()
    med = (lo + hi) / 2
    deviation = np.abs(np.arange(low, low + levels) - med)
    order = np.argsort(deviation, kind="stable")
    a, b = deviation[order[np.searchsorted(np.cumsum(counts[order]), middle, side="right")]].tolist()
    return float(med), (a + b) / 2
