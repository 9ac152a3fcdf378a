import numpy as np
import pytest

from trackreplay.trackers.filters.particles import (
    ParticleFilter,
    constant_velocity,
    linear_gaussian,
    systematic_resample,
)


def test_systematic_resample_copies_in_proportion_to_weight() -> None:
    w = np.array([0.5, 0.25, 0.125, 0.125])
    idx = systematic_resample(np.repeat(w, 250) / 250, np.random.default_rng(0))
    counts = np.bincount(idx // 250, minlength=4)
    assert np.all(np.abs(counts - w * 1000) <= 1)


def test_same_generator_seed_same_particles_other_seed_other() -> None:
    def run(seed: int) -> np.ndarray:
        pf = ParticleFilter(200, 4, np.random.default_rng(seed))
        pf.initialise(np.array([10.0, 20.0, 1.0, 0.0]), np.array([2.0, 2.0, 0.5, 0.5]))
        for _ in range(5):
            pf.resample()
            pf.predict(linear_gaussian(constant_velocity(2), [1.0, 1.0, 0.2, 0.2]))
            pf.weigh(lambda p: np.exp(-0.5 * ((p[:, 0] - 15.0) ** 2 + (p[:, 1] - 20.0) ** 2) / 4.0))
        return pf.particles.copy()

    assert np.array_equal(run(1), run(1))
    assert not np.array_equal(run(1), run(2))


def test_filter_follows_a_constant_velocity_target_in_three_dimensions() -> None:
    rng = np.random.default_rng(3)
    pf = ParticleFilter(2000, 6, rng)
    truth = np.array([0.0, 0.0, 0.0, 1.0, -0.5, 0.25])
    pf.initialise(truth + [1.0, -1.0, 0.5, 0, 0, 0], np.array([2.0, 2.0, 2.0, 1.0, 1.0, 1.0]))
    F = constant_velocity(3)
    for _ in range(30):
        truth = F @ truth
        z = truth[:3] + rng.normal(0, 0.3, 3)
        pf.resample()
        pf.predict(linear_gaussian(F, [0.2] * 3 + [0.05] * 3))
        pf.weigh(lambda p: np.exp(-0.5 * np.sum((p[:, :3] - z) ** 2, axis=1) / 0.3**2))
    est = pf.estimate()
    assert np.linalg.norm(est[:3] - truth[:3]) < 0.5
    assert np.linalg.norm(est[3:] - truth[3:]) < 0.2
    assert 1.0 <= pf.effective_size() <= pf.n


def test_zero_likelihood_everywhere_keeps_the_weights() -> None:
    pf = ParticleFilter(10, 2, np.random.default_rng(0))
    before = pf.weights.copy()
    pf.weigh(lambda p: np.zeros(len(p)))
    assert np.array_equal(pf.weights, before)


def test_bad_sizes_are_refused() -> None:
    with pytest.raises(ValueError):
        ParticleFilter(0, 4, np.random.default_rng(0))


def test_inject_replaces_a_share_of_the_particles_around_a_detection() -> None:
    pf = ParticleFilter(2000, 2, np.random.default_rng(3))
    pf.initialise(np.zeros(2), 1.0)
    chosen = pf.inject(0.1, np.array([50.0, -20.0]), 0.5)
    assert 150 <= chosen.sum() <= 250
    assert np.allclose(pf.particles[chosen].mean(axis=0), [50.0, -20.0], atol=0.1)
    assert np.all(np.abs(pf.particles[~chosen]) < 6.0)  # the others untouched
    assert pf.weights.sum() == pytest.approx(1.0)
    again = ParticleFilter(2000, 2, np.random.default_rng(3))
    again.initialise(np.zeros(2), 1.0)
    again.inject(0.1, np.array([50.0, -20.0]), 0.5)
    assert np.array_equal(again.particles, pf.particles)  # the caller's generator: same seed, same draws


def test_squared_deviations_are_the_broadcast_ones():
    from trackreplay.trackers.filters.particles import squared_deviations

    p = np.random.default_rng(2).normal(size=(500, 4))
    mean = p.mean(axis=0)
    assert np.array_equal(squared_deviations(p, mean), (p - mean) ** 2)
    assert np.array_equal(squared_deviations(p[:, 1:3], mean[1:3]), (p[:, 1:3] - mean[1:3]) ** 2)  # a column view
    assert np.array_equal(squared_deviations(p.T.copy().T, mean), (p - mean) ** 2)  # column-major
