"""The flow step's faster forms give numpy's and OpenCV's own results bit for bit (the digests rest on it)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from trackreplay.trackers.flow.local_flow import FlowField, _box, condition_number, normal_equations
from trackreplay.trackers.flow.refine import aligned, warp
from trackreplay.trackers.flow.velocity import count_percentiles, flow_histograms, histogram_edges


def test_count_percentiles_are_numpys_percentiles() -> None:
    rng = np.random.default_rng(0)
    for _ in range(2000):
        values = rng.integers(0, rng.integers(1, 80), rng.integers(1, 400))
        expected = np.percentile(values.astype(np.float64), [2.0, 98.0]).tolist()
        assert count_percentiles(np.bincount(values)) == expected  # exactly, not approximately


@pytest.mark.parametrize("half_range, width", [(8.0, 0.25), (8.0, 0.3), (3.0, 0.5), (2.5, 0.125), (1.0, 1 / 3)])
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_flow_histograms_are_numpys_histograms(half_range: float, width: float, dtype: type) -> None:
    edges = histogram_edges(half_range, width)
    lo, hi = edges[0], np.nextafter(edges[-1], -np.inf)
    rng = np.random.default_rng(1)
    for scale in (0.3, 3.0, 30.0):
        u = (rng.standard_normal((21, 21)) * scale).astype(dtype)
        v = u.T.copy()
        u.flat[rng.integers(0, u.size, 30)] = edges[rng.integers(0, len(edges), 30)]  # values on the edges
        v.flat[rng.integers(0, v.size, 5)] = np.nextafter(edges[rng.integers(0, len(edges), 5)], -np.inf)
        u.flat[:4] = [np.nan, np.inf, -np.inf, 1e30]
        valid = rng.random(u.shape) < 0.9
        got = flow_histograms(FlowField(u, v, valid, u), edges)
        for counts, values in zip(got, (u, v)):
            x = np.clip(values[valid].astype(np.float64), lo, hi)
            assert counts.dtype == np.int64
            assert np.array_equal(counts, np.histogram(x, edges)[0])


def test_normal_equations_in_one_call_equal_five_box_filters() -> None:
    rng = np.random.default_rng(2)
    ex, ey, et = (rng.standard_normal((51, 51)).astype(np.float32) * 40 for _ in range(3))
    for n in (3, 5, 7):
        expected = (_box(ex * ex, n), _box(ex * ey, n), _box(ey * ey, n), _box(ex * et, n), _box(ey * et, n))
        for got, ref in zip(normal_equations(ex, ey, et, n), expected):
            assert got.dtype == np.float64 and np.array_equal(got, ref)


def test_condition_number_matches_its_definition() -> None:
    rng = np.random.default_rng(3)
    a, c = rng.random((2, 30, 30)) * 10
    b = rng.standard_normal((30, 30)) * 5
    a[0, :3], b[0, :3], c[0, :3] = 0.0, 0.0, 0.0  # singular
    a[1, 0], b[1, 0], c[1, 0] = np.nan, 0.0, 1.0
    half = 0.5 * (a + c)
    root = np.sqrt(0.25 * (a - c) ** 2 + b * b)
    with np.errstate(divide="ignore", invalid="ignore"):
        cond = np.sqrt((half + root) / (half - root))
    expected = np.where(((half - root) > 0) & np.isfinite(cond), cond, np.inf)
    assert np.array_equal(condition_number(a, b, c), expected)


def test_aligned_is_two_warps() -> None:
    rng = np.random.default_rng(4)
    s0, s1 = (rng.random((33, 33)).astype(np.float32) * 255 for _ in range(2))
    u, v = (rng.standard_normal((33, 33)).astype(np.float32) for _ in range(2))
    hu, hv = np.float32(0.5) * u, np.float32(0.5) * v
    a0, a1 = aligned(s0, s1, u, v)
    assert np.array_equal(a0, warp(s0, -hu, -hv)) and np.array_equal(a1, warp(s1, hu, hv))
    h, w = s0.shape
    gx = (np.arange(w, dtype=np.float32)[None, :] + hu).astype(np.float32)
    gy = (np.arange(h, dtype=np.float32)[:, None] + hv).astype(np.float32)
    assert np.array_equal(a1, cv2.remap(s1, gx, gy, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE))
