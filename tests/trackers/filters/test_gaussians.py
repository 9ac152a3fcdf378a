import numpy as np
import pytest

from trackreplay.trackers.filters.gaussians import merge_gaussians


def test_merge_equals_the_pooled_moments_of_the_members() -> None:
    rng = np.random.default_rng(0)
    groups = [rng.normal(c, s, size=(n, 3)) for c, s, n in [((0, 0, 5), 0.3, 40), ((1, 0.5, 5), 0.5, 10), ((0, 2, 6), 0.2, 25)]]
    means = np.array([g.mean(axis=0) for g in groups])
    covs = np.array([np.cov(g.T, bias=True) for g in groups])
    mean, cov = merge_gaussians(np.array([len(g) for g in groups]), means, covs)
    pooled = np.concatenate(groups)
    np.testing.assert_allclose(mean, pooled.mean(axis=0), atol=1e-12)
    np.testing.assert_allclose(cov, np.cov(pooled.T, bias=True), atol=1e-12)


def test_merge_of_one_is_itself_and_empty_is_refused() -> None:
    mean, cov = merge_gaussians(np.array([3.0]), np.array([[1.0, 2.0]]), np.array([np.eye(2)]))
    assert np.array_equal(mean, [1.0, 2.0]) and np.array_equal(cov, np.eye(2))
    with pytest.raises(ValueError):
        merge_gaussians(np.array([]), np.zeros((0, 2)), np.zeros((0, 2, 2)))
