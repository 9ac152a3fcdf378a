import numpy as np

from trackreplay.trackers.filters.gating import chi2_gate, gaussian_density, innovation, mahalanobis_sq
from trackreplay.trackers.filters import kalman
from trackreplay.trackers.filters.kalman import MotionModelEkf, linear_kalman


def test_ekf_with_a_linear_model_equals_the_linear_filter() -> None:
    F = np.array([[1.0, 1.0], [0.0, 1.0]])
    Q = np.diag([0.01, 0.1])
    H = np.array([[1.0, 0.0]])
    R = np.array([[0.5]])
    kf = linear_kalman([0.0, 1.0], np.eye(2), F, Q, H, R)
    ekf = MotionModelEkf(2, 1, lambda x, dt: F @ x)
    ekf.x = np.array([0.0, 1.0])
    ekf.P = np.eye(2)
    ekf.F, ekf.Q = F, Q
    rng = np.random.default_rng(0)
    for k in range(20):
        z = np.array([k + rng.normal(0, 0.7)])
        kf.predict()
        kf.update(z.reshape(1, 1))
        ekf.predict()
        ekf.update(z, lambda x: H, lambda x: H @ x, R=R)
        np.testing.assert_allclose(ekf.x, kf.x[:, 0], atol=1e-12)
        np.testing.assert_allclose(ekf.P, kf.P, atol=1e-12)


def test_nis_of_consistent_innovations_is_chi_square() -> None:
    rng = np.random.default_rng(1)
    P, H, R = np.diag([4.0, 1.0]), np.eye(2), np.diag([1.0, 2.0])
    S = H @ P @ H.T + R
    z = rng.multivariate_normal([0, 0], S, size=4000)
    nis = np.array([innovation(P, H, R, zi, np.zeros(2)).nis for zi in z])
    assert abs(nis.mean() - 2.0) < 0.1
    assert abs(np.mean(nis < chi2_gate(2, 0.95)) - 0.95) < 0.01
    np.testing.assert_allclose(mahalanobis_sq(z[:50], np.zeros(2), S), nis[:50])


def test_gaussian_density_integrates_to_one() -> None:
    xs = np.linspace(-10, 10, 401)
    grid = np.stack(np.meshgrid(xs, xs), axis=-1).reshape(-1, 2)
    cov = np.array([[2.0, 0.6], [0.6, 1.0]])
    total = gaussian_density(grid, np.array([0.5, -0.5]), cov).sum() * (xs[1] - xs[0]) ** 2
    assert abs(total - 1.0) < 1e-3


def test_update_is_filterpys_update_bit_for_bit() -> None:
    """Every EKF's update (the groups' and golf's): filterpy's Joseph-form ``update(z, HJacobian, Hx,
    R=)``, with ``P Hᵀ`` and ``S`` from the gate or not, R per call or the filter's own."""
    import scipy.linalg
    from filterpy.kalman import ExtendedKalmanFilter

    from trackreplay.trackers.filters.kalman import inverse

    rng = np.random.default_rng(3)
    for trial in range(200):
        A = rng.normal(0, 3, (6, 6))
        P = A @ A.T + np.eye(6) * rng.uniform(0.01, 5)
        H = rng.normal(0, 50, (3, 6)) * (rng.random((3, 6)) < 0.7)
        R = np.diag(rng.uniform(0.1, 400, 3))
        x, z, hx = rng.normal(0, 30, 6), rng.normal(0, 500, 3), rng.normal(0, 500, 3)
        plain, fast = MotionModelEkf(6, 3, lambda s, dt: s), MotionModelEkf(6, 3, lambda s, dt: s)
        for f in (plain, fast):
            f.x, f.P, f.R = x.copy(), P.copy(), R
        ExtendedKalmanFilter.update(plain, z, lambda _x: H, lambda _x: hx, R=R if trial % 3 else None)
        if trial % 2:
            fast.update(z, lambda _x: H, lambda _x: hx, R=R if trial % 3 else None)
        else:
            PHT = np.dot(P, H.T)
            S = np.dot(H, PHT) + R
            assert S.tobytes() == innovation(P, H, R, z, hx).S.tobytes()  # the gate's S is filterpy's
            fast.update(z, lambda _x: H, lambda _x: hx, R=R, PHT=PHT, S=S)
        for name in ("x", "P", "S", "SI", "K", "y", "x_post", "P_post", "z"):
            assert getattr(fast, name).tobytes() == getattr(plain, name).tobytes(), name
        assert inverse(plain.S).tobytes() == scipy.linalg.inv(plain.S).tobytes()


def test_update_takes_filterpys_scalar_forms() -> None:
    from filterpy.kalman import ExtendedKalmanFilter

    plain, fast = MotionModelEkf(2, 1, lambda s, dt: s), MotionModelEkf(2, 1, lambda s, dt: s)
    H = np.array([[1.0, 0.0]])
    for f in (plain, fast):
        f.x, f.P = np.array([1.0, 2.0]), np.diag([4.0, 1.0])
    ExtendedKalmanFilter.update(plain, 3.0, lambda _x: H, lambda x: H @ x, R=0.5)
    fast.update(3.0, lambda _x: H, lambda x: H @ x, R=0.5)  # a scalar z and a scalar R, as filterpy's
    assert fast.x.tobytes() == plain.x.tobytes() and fast.P.tobytes() == plain.P.tobytes()
    assert fast.x[0] == 1.0 + 4.0 / 4.5 * 2.0
    before = fast.x
    fast.update(None, lambda _x: H, lambda x: H @ x)  # no measurement: the state stands
    assert fast.x is before and fast.x_post is before


def test_inverse_of_a_non_finite_matrix_raises_as_scipys() -> None:
    import pytest

    from trackreplay.trackers.filters.kalman import inverse

    with pytest.raises(ValueError, match="infs or NaNs"):
        inverse(np.array([[1.0, np.nan], [0.0, 1.0]]))


def test_lean_predict_and_update_are_filterpys_bit_for_bit() -> None:
    """kalman.predict / kalman.update against filterpy's own calls on a twin filter: the same x and P,
    to the bit, over many steps (the flow tracker's 3-state model, random measurements)."""
    rng = np.random.default_rng(5)
    F = np.array([[1.0, 1.0, 0.5], [0.0, 1.0, 1.0], [0.0, 0.0, 0.9]])
    make = lambda: linear_kalman(x=[3.0, 0.0, 0.0], P=np.diag([4.0, 2.0, 1.0]), F=F, Q=np.diag([0.0, 0.0, 0.3]),  # noqa: E731
                                 H=np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]), R=np.diag([0.7, 1.9]))
    ours, theirs = make(), make()
    for _ in range(200):
        kalman.predict(ours)
        theirs.predict()
        assert ours.x.tobytes() == theirs.x.tobytes() and ours.P.tobytes() == theirs.P.tobytes()
        z = rng.normal(size=(2, 1)) * 5.0
        kalman.update(ours, z.copy())
        theirs.update(z.copy())
        assert ours.x.tobytes() == theirs.x.tobytes() and ours.P.tobytes() == theirs.P.tobytes()
        assert ours.K.tobytes() == theirs.K.tobytes() and ours.y.tobytes() == theirs.y.tobytes()
    assert ours.log_likelihood == theirs.log_likelihood  # filterpy's lazy properties read the same state
