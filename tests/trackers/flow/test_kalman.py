import numpy as np
import pytest

from trackreplay.trackers.flow.kalman import OBSERVATION, AxisFilters, transition


def test_matrices_are_eq_23_and_24() -> None:
    assert transition(0.4).tolist() == [[1, 1, 0.5], [0, 1, 1], [0, 0, 0.4]]
    assert OBSERVATION.tolist() == [[1, 0, 0], [0, 1, 0]]
    kf = AxisFilters((0.0, 0.0), 0.5, 0.3, 0.25, 0.5, (1.0, 16.0, 1.0))
    assert np.diag(kf.filters[0].Q).tolist() == [0.0, 0.0, 0.3]  # noise drives the acceleration only
    assert np.diag(kf.filters[1].R).tolist() == [0.25, 0.5]


def test_converges_to_a_constant_velocity() -> None:
    rng = np.random.default_rng(0)
    kf = AxisFilters((100.0, 50.0), 0.5, 0.01, 0.25, 0.5, (1.0, 16.0, 1.0))  # small q: it averages
    v = np.array([2.0, -1.5])
    late = []
    for k in range(1, 61):
        kf.predict()
        truth = np.array([100.0, 50.0]) + v * k
        kf.update(truth + rng.normal(0, 0.5, 2), v + rng.normal(0, 0.5, 2))
        if k > 30:
            late.append(kf.velocity)
    assert np.mean(late, axis=0) == pytest.approx(v, abs=0.1)  # unbiased
    assert np.std(late, axis=0).max() < 0.25  # and smoother than the 0.5 px/frame measurements
    assert kf.position == pytest.approx(np.array([100.0, 50.0]) + v * 60, abs=1.0)
    noiseless = AxisFilters((0.0, 0.0), 0.5, 1.0, 0.25, 0.5, (1.0, 16.0, 1.0))
    for k in range(1, 31):
        noiseless.predict()
        noiseless.update(v * k, v)
    assert noiseless.velocity == pytest.approx(v, abs=1e-6)
    assert noiseless.state[:, 2] == pytest.approx([0, 0], abs=1e-6)


def test_predicts_without_a_measurement() -> None:
    kf = AxisFilters((0.0, 0.0), 0.5, 1.0, 0.25, 0.5, (1.0, 16.0, 1.0))
    v = np.array([3.0, 1.0])
    for k in range(1, 21):
        kf.predict()
        kf.update(v * k, v)
    before = kf.position
    p_before = kf.covariance[:, 0, 0]
    kf.predict()  # eq. 19–20 only: no moving pixels this frame
    assert kf.position == pytest.approx(before + v, abs=1e-6)
    assert np.all(kf.covariance[:, 0, 0] > p_before)
    assert kf.state.shape == (2, 3) and kf.covariance.shape == (2, 3, 3)
