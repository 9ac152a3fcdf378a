"""Eq. (2)'s transition with the switches of ours: the constant-velocity drift and the scale walk."""

import numpy as np

from trackreplay.trackers.colorpf.config import SizeConfig
from trackreplay.trackers.colorpf.motion import transition
from trackreplay.trackers.colorpf.size import WeakPerspectiveSize


def _step(size: SizeConfig, drift=None, sigma=(0.0, 0.0)):
    model = WeakPerspectiveSize(size.r_s, area0=20.0 * 40.0, distance0=float("nan"))  # no ground plane
    return transition(sigma=np.array(sigma), size=size, ratio=2.0, box_wh=np.array([20.0, 40.0]), model=model,
                      plane=None, side=1.0, initial_wh=np.array([20.0, 40.0]), drift=drift)


def test_drift_moves_every_particle_by_the_velocity():
    particles = np.array([[10.0, 20.0, 20.0, 40.0], [50.0, 60.0, 20.0, 40.0]])
    rng_a, rng_b = np.random.default_rng(4), np.random.default_rng(4)
    still = _step(SizeConfig(mode="fixed"), sigma=(3.0, 3.0))(particles, rng_a)
    moved = _step(SizeConfig(mode="fixed"), drift=np.array([5.0, -2.0]), sigma=(3.0, 3.0))(particles, rng_b)
    np.testing.assert_allclose(moved[:, :2] - still[:, :2], [[5.0, -2.0], [5.0, -2.0]])
    np.testing.assert_array_equal(moved[:, 2:], still[:, 2:])


def test_scale_walk_without_a_plane_keeps_the_aspect_and_spreads_the_size():
    particles = np.tile([50.0, 50.0, 20.0, 40.0], (400, 1))
    constant = _step(SizeConfig(no_plane="constant", r_s=0.0))(particles, np.random.default_rng(0))
    np.testing.assert_allclose(constant[:, 2:], np.tile([20.0, 40.0], (400, 1)))  # S' = S_0: the marked size
    walked = _step(SizeConfig(no_plane="random_walk", noise=0.05))(particles, np.random.default_rng(0))
    np.testing.assert_allclose(walked[:, 3] / walked[:, 2], 2.0)  # h = R w
    assert 0.03 < np.std(walked[:, 2] / 20.0) < 0.07  # w scaled by 1 + N(0, 0.05)
