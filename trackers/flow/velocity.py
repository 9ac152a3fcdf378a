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


def flow_histograms(flow: FlowField, edges: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Counts of u and of v over the valid pixels; the outer bins collect values beyond the range."""
    lo, hi = edges[0], np.nextafter(edges[-1], -np.inf)
    u = np.clip(flow.u[flow.valid].astype(np.float64), lo, hi)
    v = np.clip(flow.v[flow.valid].astype(np.float64), lo, hi)
    return np.histogram(u, edges)[0].astype(np.int64), np.histogram(v, edges)[0].astype(np.int64)


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


def object_velocity(flow: FlowField, epsilon: float, edges: np.ndarray, spread: float = 0.0) -> VelocityEstimate:
    """Eq. 11 over the pixels of ``flow`` that move by at least ``epsilon`` px/frame in x or y."""
    u = np.where(flow.valid, flow.u, 0.0)
    v = np.where(flow.valid, flow.v, 0.0)
    moving = flow.valid & ((np.abs(u) >= epsilon) | (np.abs(v) >= epsilon))
    hist_u, hist_v = flow_histograms(flow, edges)
    count = int(np.count_nonzero(moving))
    nan2 = np.full(2, np.nan)
    if count == 0:
        return VelocityEstimate(nan2, moving, 0, nan2.copy(), nan2.copy(), edges, hist_u, hist_v)
    ys, xs = np.nonzero(moving)
    velocity = np.array([np.mean(u[moving], dtype=np.float64), np.mean(v[moving], dtype=np.float64)])
    centroid = np.array([np.mean(xs, dtype=np.float64), np.mean(ys, dtype=np.float64)])
    extent = extent_of(xs.astype(np.float64), ys.astype(np.float64), velocity, spread)
    return VelocityEstimate(velocity, moving, count, centroid, extent, edges, hist_u, hist_v)
