"""Eq. (9) from a known homography; eqs. (10)-(12) on a crafted likelihood field with jump rejection."""

import numpy as np
import pytest

from trackreplay.recorder.synth.colorpf import Camera, ColorPfSceneConfig
from trackreplay.trackers.colorpf.aspect import AspectEstimate, box_from_area, likelihood_extent_ratio
from trackreplay.trackers.colorpf.config import AspectConfig
from trackreplay.trackers.colorpf.motion import standing_box
from trackreplay.trackers.colorpf.size import WeakPerspectiveSize, ground_distance, horizon_side
from trackreplay.trackers.geometry.ground_plane import GroundPlane


def _plane() -> tuple[GroundPlane, Camera]:
    cam = Camera.of(ColorPfSceneConfig())
    cal = cam.calibration(ColorPfSceneConfig())
    return GroundPlane(cal.matrix, cal.camera_ground, cal.camera_height), cam


def test_weak_perspective_area_from_known_homography():
    plane, cam = _plane()
    feet = cam.project(np.array([[0.0, 5.0, 0.0], [0.0, 10.0, 0.0], [2.0, 20.0, 0.0]]))
    side = float(horizon_side(plane, feet[:1])[0])
    d = ground_distance(plane, feet, side)
    np.testing.assert_allclose(d, np.sqrt(np.array([25.0, 100.0, 404.0]) + 9.0), rtol=1e-9)
    size = WeakPerspectiveSize(0.2, area0=4000.0, distance0=d[1])
    np.testing.assert_allclose(size.areas_for(d), 4000.0 * d[1] ** 2 / d**2)  # S' = f^2 S / Z^2, S from S'_0, Z_0
    np.testing.assert_allclose(size.areas_for(d[1], 0.1), 4400.0)  # omega relative to S
    rng = np.random.default_rng(0)
    draws = size.areas(np.full(20000, d[1]), rng) / 4000.0 - 1.0
    assert abs(draws.std() - 0.2) < 0.01 and abs(draws.mean()) < 0.01
    above = cam.project(np.array([[0.0, 10.0, 6.0]]))  # a point above the horizon is no ground point
    assert np.isnan(ground_distance(plane, above, side)[0])


def test_standing_box_puts_the_bottom_on_the_ground():
    plane, cam = _plane()
    foot = cam.project(np.array([[1.0, 12.0, 0.0]]))[0]
    d0 = float(np.hypot(np.hypot(1.0, 12.0), 3.0))
    size = WeakPerspectiveSize(0.2, area0=40.0 * 100.0, distance0=d0)
    area, dist = standing_box(np.array([[foot[0], foot[1] - 50.0]]), 80.0, size, plane, 0.0, 2.5, iterations=8)
    w, h = box_from_area(area, 2.5)
    assert w * h == pytest.approx(area[0]) and h / w == pytest.approx(2.5)
    assert h[0] == pytest.approx(100.0, abs=1.0) and dist[0] == pytest.approx(d0, rel=0.01)


def test_aspect_from_a_crafted_likelihood_field():
    # particles on a grid; the likelihood is high inside an ellipse 3x taller than wide
    ys, xs = np.mgrid[-30:31:3, -30:31:3]
    xy = np.stack([xs.ravel(), ys.ravel()], axis=1).astype(float) + [100.0, 200.0]
    inside = (xs.ravel() / 8.0) ** 2 + (ys.ravel() / 24.0) ** 2 <= 1.0
    lik = np.where(inside, 100.0, 1.0)
    r = likelihood_extent_ratio(xy, lik, np.array([100.0, 200.0]), radius=40.0, threshold=25.0)
    assert r == pytest.approx(48.0 / 12.0, rel=0.35)  # extents 2*24 by 2*6 on the 3 px grid
    assert np.isnan(likelihood_extent_ratio(xy, lik, np.array([100.0, 200.0]), radius=40.0, threshold=1000.0))
    est = AspectEstimate(AspectConfig(mode="likelihood", relative=False, max_jump=1.5, near=10.0), ratio0=3.0)
    up = est.update(xy, lik, np.array([100.0, 200.0]), area=100.0)
    assert not up.kept and up.ratio == pytest.approx(r)
    flat = np.where((xs.ravel() / 24.0) ** 2 + (ys.ravel() / 8.0) ** 2 <= 1.0, 100.0, 1.0)  # a jump to 1/4
    jumped = est.update(xy, flat, np.array([100.0, 200.0]), area=100.0)
    assert jumped.kept and jumped.ratio == pytest.approx(r) and jumped.measured < 0.5
    w, h = box_from_area(1200.0, 3.0)
    assert w == pytest.approx(20.0) and h == pytest.approx(60.0)  # docs/papers.md §3's correction: w h = S'
