"""The object's velocity from the flow histogram (§3.1, eq. 11), with its position and extent.

Pixels whose flow has ``|u| ≥ ε`` or ``|v| ≥ ε`` form the set S; the velocity is the mean flow over
S, which cancels rotation (Fig. 2) and dilation (Fig. 3) about the object's centre. The centroid
of S is the object's position half-way between the two frames (the refinement puts the flow on
that grid, see ``refine``), so half the mean flow carries it to the second frame.

Known bias: S also holds pixels whose neighbourhood straddles the object's boundary or the
strip it covers or uncovers; their flow lies between 0 and the object's, so eq. 11 reads about
3/4 of the true speed on the flow-sim scenes. The centroid is unbiased (that fringe surrounds
the object evenly), which is why the Kalman filter weights position more than velocity.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass

import numpy as np

from trackreplay.trackers.flow.local_flow import FlowField


@dataclass(frozen=True, eq=False)
class VelocityEstimate:
    velocity: np.ndarray  # (2,) mean (u, v) over S, px/frame; NaN when S is empty
    moving: np.ndarray  # bool mask of S
    count: int  # k_z of eq. 11
    centroid: np.ndarray  # (2,) mean (x, y) of S on the flow's grid; NaN when empty
    extent: np.ndarray  # (2,) object width and height, px; NaN when empty
    hist_edges: np.ndarray
    hist_u: np.ndarray
    hist_v: np.ndarray


def histogram_edges(half_range: float, bin_width: float) -> np.ndarray:
    n = int(round(2 * half_range / bin_width))
    return np.linspace(-half_range, half_range, n + 1)


def _power_of_two_grid(edges: np.ndarray) -> tuple[float, int] | None:
    """``(scale, offset)`` when ``edges[i] * scale == i - offset`` exactly with ``scale`` a power of
    two (the default ±8 px in 0.25 px bins): then a value's bin is ``floor(value * scale) + offset``
    with no rounding at all (scaling by a power of two is exact), else None."""
    if len(edges) < 2:
        return None
    width = float(edges[1] - edges[0])
    if not width > 0:
        return None
    mantissa, exponent = math.frexp(width)
    if mantissa != 0.5:
        return None
    scale = math.ldexp(1.0, 1 - exponent)  # 1 / width, exactly
    offset = -float(edges[0]) * scale
    if offset != math.floor(offset) or abs(offset) > 2**30:
        return None
    if not np.array_equal(edges * scale, np.arange(len(edges), dtype=np.float64) - offset):
        return None
    return scale, int(offset)


_GRIDS: dict[bytes, tuple[float, int] | None] = {}


def flow_histograms(flow: FlowField, edges: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Counts of u and of v over the valid pixels; the outer bins collect values beyond the range.

    The counts of ``np.histogram(np.clip(values, edges[0], nextafter(edges[-1], -inf)), edges)``
    (bins ``[e_i, e_i+1)``; a NaN is not counted), found without its sort: on a power-of-two grid
    of edges by scaling and flooring (exact), else by binary search among the edges.
    """
    n = len(edges) - 1
    both = np.concatenate((flow.u[flow.valid], flow.v[flow.valid]))
    half = len(both) // 2
    key = edges.tobytes()
    grid = _GRIDS[key] if key in _GRIDS else _GRIDS.setdefault(key, _power_of_two_grid(edges))
    if grid is not None:
        scale, offset = grid
        bins = np.floor(both * both.dtype.type(scale))  # exact in float32 and float64
        np.clip(bins, -offset, n - 1 - offset, out=bins)  # as clipping the value into the outer bins
        if np.isnan(bins).any():
            bins[np.isnan(bins)] = n - offset  # past the last bin: dropped below
        index = bins.astype(np.intp) + offset
    else:
        lo, hi = edges[0], np.nextafter(edges[-1], -np.inf)
        index = np.searchsorted(edges, np.clip(both.astype(np.float64), lo, hi), side="right") - 1
    hist_u = np.bincount(index[:half], minlength=n + 1)[:n].astype(np.int64)
    hist_v = np.bincount(index[half:], minlength=n + 1)[:n].astype(np.int64)
    return hist_u, hist_v


_PERCENTILES = (2.0, 98.0)


def count_percentiles(counts: np.ndarray, percentiles: tuple[float, ...] = _PERCENTILES) -> list[float]:
    """``np.percentile(values, percentiles)`` (method "linear") of the integers ``values`` given as
    ``counts[i]`` = how many equal ``i``: the same float operations as numpy's, without sorting
    (numpy's virtual index ``(n − 1) q`` and its two-sided lerp)."""
    cumulative = np.cumsum(counts).tolist()
    n = cumulative[-1]
    out = []
    for pct in percentiles:
        q = pct / 100
        virtual = (n - 1) * q
        if virtual >= n - 1:  # numpy takes the last value (and gamma from index -1)
            below = above = n - 1
            gamma = virtual + 1
        else:
            below = math.floor(virtual)
            above = below + 1
            gamma = virtual - below
        # the k-th smallest value: the first i whose running count exceeds k
        a, b = float(bisect.bisect_right(cumulative, below)), float(bisect.bisect_right(cumulative, above))
        diff = b - a
        out.append(b - diff * (1 - gamma) if gamma >= 0.5 else a + diff * gamma)
    return out


def extent_of(xs: np.ndarray, ys: np.ndarray, velocity: np.ndarray, spread: float) -> np.ndarray:
    """Width and height of the object from S.

    S covers the object at both instants (the flow lives half-way between the frames) and reaches
    ``spread`` px beyond its edges (the derivative and neighbourhood windows), so the object's size
    is the 2nd–98th percentile span of S (robust to stray pixels) plus one pixel, less the motion
    ``|u|`` (``|v|``) and twice the spread. A bounding box would take the stray pixels too.
    """
    out = []
    for c, motion in zip((xs, ys), np.abs(velocity)):
        lo, hi = np.percentile(c, [2.0, 98.0])
        out.append(max(1.0, hi - lo + 1.0 - motion - 2.0 * spread))
    return np.array(out, dtype=np.float64)


def _extent_from_counts(col_counts: np.ndarray, row_counts: np.ndarray, velocity: np.ndarray, spread: float) -> np.ndarray:
    """:func:`extent_of` of S given as pixel counts per column and per row (the same numbers)."""
    out = []
    for counts, motion in zip((col_counts, row_counts), np.abs(velocity)):
        lo, hi = count_percentiles(counts)
        out.append(max(1.0, hi - lo + 1.0 - motion - 2.0 * spread))
    return np.array(out, dtype=np.float64)


def object_velocity(flow: FlowField, epsilon: float, edges: np.ndarray, spread: float = 0.0) -> VelocityEstimate:
    """Eq. 11 over the pixels of ``flow`` that move by at least ``epsilon`` px/frame in x or y.

    S is a 2-D mask, so its centroid and percentiles come from its column and row counts (integer
    coordinates: the sums are exact) rather than from a list of coordinates and a sort.
    """
    # u, v are NaN where not valid, and NaN >= epsilon is False
    with np.errstate(invalid="ignore"):
        moving = flow.valid & ((np.abs(flow.u) >= epsilon) | (np.abs(flow.v) >= epsilon))
    hist_u, hist_v = flow_histograms(flow, edges)
    count = int(np.count_nonzero(moving))
    nan2 = np.full(2, np.nan)
    if count == 0:
        return VelocityEstimate(nan2, moving, 0, nan2.copy(), nan2.copy(), edges, hist_u, hist_v)
    # means in float64 of the float32 flow (np.mean's own sum, then one division)
    velocity = np.array([float(np.add.reduce(flow.u[moving], dtype=np.float64)) / count,
                         float(np.add.reduce(flow.v[moving], dtype=np.float64)) / count])
    col_counts = np.count_nonzero(moving, axis=0)
    row_counts = np.count_nonzero(moving, axis=1)
    centroid = np.array([int(np.dot(np.arange(len(col_counts)), col_counts)) / count,
                         int(np.dot(np.arange(len(row_counts)), row_counts)) / count])
    extent = _extent_from_counts(col_counts, row_counts, velocity, spread)
    return VelocityEstimate(velocity, moving, count, centroid, extent, edges, hist_u, hist_v)
