"""The one pinhole projection and back-projection."""

import numpy as np
import pytest

from trackreplay.trackers.geometry.pinhole import Intrinsics

K = Intrinsics(fx=800.0, fy=820.0, cx=320.0, cy=240.0, width=640, height=480)


def test_projection_is_the_pinhole_formula():
    pts = np.array([[0.5, -0.25, 4.0], [0.0, 0.0, 1.0]])
    assert K.project(pts) == pytest.approx(np.array([[800 * 0.125 + 320, 820 * -0.0625 + 240], [320.0, 240.0]]))
    assert np.isnan(K.project(np.array([[0.0, 0.0, -1.0], [1.0, 1.0, 0.0]]))).all()  # behind or at the camera


def test_back_projection_round_trip_and_matrices():
    rng = np.random.default_rng(0)
    pixels = rng.uniform([0, 0], [640, 480], size=(100, 2))
    rays = K.back_project(pixels)
    assert rays[:, 2] == pytest.approx(np.ones(100))
    assert K.project(rays * rng.uniform(0.5, 50, size=(100, 1))) == pytest.approx(pixels, abs=1e-9)
    assert K.K @ K.K_inv == pytest.approx(np.eye(3))
    assert K.K is K.K  # computed once
    assert K.in_image(np.array([[0, 0], [639.9, 479.9], [640, 10], [-0.1, 10]])).tolist() == [True, True, False, False]
