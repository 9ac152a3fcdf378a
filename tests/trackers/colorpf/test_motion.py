"""Eq. (2)'s transition with the switches of ours: the constant-velocity drift and the scale walk."""

import numpy as np

from trackreplay.trackers.colorpf.config import SizeConfig
from trackreplay.trackers.colorpf.motion import standing_box, transition
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


def test_standing_box_without_a_plane_is_its_four_substitutions():
    from trackreplay.trackers.colorpf.aspect import box_from_area
    from trackreplay.trackers.colorpf.size import foot_points, ground_distance
    rng = np.random.default_rng(6)
    xy, omega = rng.uniform(0, 300, (40, 2)), rng.normal(0, 0.2, 40)
    for model in (WeakPerspectiveSize(0.2, 850.0, np.nan), WeakPerspectiveSize(0.2, 850.0, 7.5)):
        h = np.full(40, 50.0)
        for _ in range(4):  # the plain form: every substitution
            distance = ground_distance(None, foot_points(xy, h), 1.0)
            area = model.areas_for(distance, omega)
            h = box_from_area(area, 2.9)[1]
        got = standing_box(xy, 50.0, model, None, 1.0, 2.9, omega)
        assert np.array_equal(got[0], area) and np.array_equal(got[1], distance, equal_nan=True)
