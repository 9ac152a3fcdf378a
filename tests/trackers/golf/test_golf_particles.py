"""The golf tracker's CONDENSATION models (eqs. (1)-(3)) on the shared particle filter."""

import numpy as np
import pytest

from trackreplay.trackers.filters.particles import ParticleFilter
from trackreplay.trackers.golf.config import ParticleConfig
from trackreplay.trackers.golf.particles import DIM, likelihood, motion, spread_sigma, state, warp, with_camera_motion


def noise_config(pos: float, vel: float) -> ParticleConfig:
    return ParticleConfig(noise_pos_px=pos, noise_vel_px=vel)


def run(truth, detections, *, sigma=3.0, alpha=1e-4, pos=1.0, vel=0.5, seed=0, known_velocity=True):
    pf = ParticleFilter(1000, DIM, np.random.default_rng(seed))
    v0 = truth[1] - truth[0] if known_velocity else np.zeros(2)
    pf.initialise(state(truth[0], v0), spread_sigma(2.0, 1.0))
    estimates = []
    for k, z in enumerate(detections):
        if k:
            pf.resample()
            pf.predict(motion(noise_config(pos, vel), 1.0, damp=False, steps=1))
        pf.weigh(likelihood(z, sigma, alpha))
        estimates.append(pf.estimate())
    return np.array(estimates)


def noisy_detections(truth, rng, noise=1.0, missing=0.2, clutter=False):
    out = []
    for k, p in enumerate(truth):
        z = [] if (k > 3 and rng.random() < missing) else [p + rng.normal(0.0, noise, 2)]
        if clutter and rng.random() < 0.3:
            z.append(p + rng.uniform(-60, 60, 2) + 40)  # a far false candidate now and then
        out.append(np.array(z).reshape(-1, 2))
    return out


@pytest.mark.parametrize("kind", ["constant_velocity", "parabola"])
def test_follows_a_point_with_noise_and_gaps(kind):
    t = np.arange(80.0)
    if kind == "constant_velocity":
        truth = np.stack([100 + 4.0 * t, 300 - 2.5 * t], axis=1)
    else:
        truth = np.stack([100 + 3.0 * t, 500 - 12.0 * t + 0.15 * t * t], axis=1)  # image y: up, then down
    rng = np.random.default_rng(42)
    est = run(truth, noisy_detections(truth, rng))
    err = np.linalg.norm(est[:, :2] - truth, axis=1)[10:]
    assert err.mean() < 2.0
    assert err.max() < 7.0
    v_true = np.gradient(truth, axis=0)[10:]
    assert np.abs(est[10:, 2:] - v_true).mean() < 1.0


def test_picks_up_the_velocity_from_a_standing_start():
    t = np.arange(60.0)
    truth = np.stack([100 + 2.0 * t, 300 - 1.5 * t], axis=1)
    est = run(truth, noisy_detections(truth, np.random.default_rng(8), missing=0.0), known_velocity=False)
    assert np.linalg.norm(est[15:, :2] - truth[15:], axis=1).max() < 4.0
    assert np.abs(est[20:, 2:] - [2.0, -1.5]).mean() < 0.5


def test_a_far_false_candidate_does_not_capture_the_track():
    t = np.arange(60.0)
    truth = np.stack([200 + 3.0 * t, 200 + 1.0 * t], axis=1)
    est = run(truth, noisy_detections(truth, np.random.default_rng(5), clutter=True))
    assert np.linalg.norm(est[5:, :2] - truth[5:], axis=1).max() < 8.0


def test_without_candidates_the_weights_stay_uniform_and_the_cloud_spreads():
    pf = ParticleFilter(1000, DIM, np.random.default_rng(1))
    pf.initialise(np.array([50.0, 50.0, 2.0, 0.0]), spread_sigma(1.0, 0.2))
    before = pf.spread(slice(0, 2))
    for _ in range(10):
        pf.resample()
        pf.predict(motion(noise_config(1.0, 0.5), 1.0, damp=False, steps=1))
        pf.weigh(likelihood(np.zeros((0, 2)), 3.0, 1e-4))
    assert np.allclose(pf.weights, 1e-3)
    assert (pf.spread(slice(0, 2)) > 3 * before).all()
    assert pf.estimate()[0] == pytest.approx(70.0, abs=2.0)  # drifted at constant velocity


def test_with_alpha_zero_and_no_candidate_the_weights_stay_uniform():
    pf = ParticleFilter(100, DIM, np.random.default_rng(1))
    pf.initialise(np.zeros(DIM), spread_sigma(1.0, 1.0))
    pf.weigh(likelihood(np.zeros((0, 2)), 3.0, 0.0))
    assert np.array_equal(pf.weights, np.full(100, 0.01))


def test_likelihood_is_equation_2():
    particles = np.array([[0.0, 0.0, 9.0, 9.0], [3.0, 4.0, -1.0, 0.0]])
    z = np.array([[0.0, 0.0], [6.0, 8.0]])
    sigma, alpha = 2.0, 0.1
    expected = alpha + (np.exp(-np.array([0.0, 25.0]) / 8) + np.exp(-np.array([100.0, 25.0]) / 8)) / (np.sqrt(2 * np.pi) * sigma)
    assert likelihood(z, sigma, alpha)(particles) == pytest.approx(expected)


def test_motion_damps_after_a_miss_and_coasts_over_dropped_frames():
    s = np.array([[10.0, 20.0, 2.0, -1.0]])
    still = ParticleConfig(noise_pos_px=0.0, noise_vel_px=0.0, miss_velocity_damping=0.5)
    rng = np.random.default_rng(0)
    assert motion(still, 1.0, damp=False, steps=1)(s, rng) == pytest.approx(np.array([[12.0, 19.0, 2.0, -1.0]]))
    assert motion(still, 1.0, damp=True, steps=1)(s, rng) == pytest.approx(np.array([[11.0, 19.5, 1.0, -0.5]]))
    assert motion(still, 1.0, damp=False, steps=3)(s, rng) == pytest.approx(np.array([[16.0, 17.0, 2.0, -1.0]]))
    assert s.tolist() == [[10.0, 20.0, 2.0, -1.0]]  # the input is not modified
    # The noise grows with the square root of the frames covered.
    n = np.zeros((20000, 4))
    spread = motion(ParticleConfig(noise_pos_px=2.0, noise_vel_px=1.0), 0.5, damp=False, steps=4)(n, rng).std(axis=0)
    assert spread == pytest.approx([2.0, 2.0, 1.0, 1.0], rel=0.03)


def test_warp_moves_positions_and_velocities_through_the_homography():
    s = np.array([[10.0, 20.0, 1.0, -2.0]])
    shift_zoom = np.array([[2.0, 0.0, 5.0], [0.0, 2.0, -3.0], [0.0, 0.0, 1.0]])
    assert warp(s, shift_zoom) == pytest.approx(np.array([[25.0, 37.0, 2.0, -4.0]]))
    # A sample still in the world, at (25, 37) now, was at (10, 20) under the previous pose: the
    # camera's own motion moved it by (15, 17) pixels this frame.
    assert with_camera_motion((1.0, 0.0), (25.0, 37.0), shift_zoom) == pytest.approx((16.0, 17.0))
