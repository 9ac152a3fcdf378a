import numpy as np
import pytest

from trackreplay.trackers.flow.derivatives import beaudet_kernels, derivatives, spatial_gradient


def _grid(n: int = 32) -> tuple[np.ndarray, np.ndarray]:
    y, x = np.mgrid[0:n, 0:n].astype(np.float64)
    return x, y


def test_cubic_5x5_kernel_is_beaudets_operator() -> None:
    _, kx, ky = beaudet_kernels(5, 3)
    rows = [[31, -44, 0, 44, -31], [-5, -62, 0, 62, 5], [-17, -68, 0, 68, 17], [-5, -62, 0, 62, 5], [31, -44, 0, 44, -31]]
    expected = np.array(rows) / 420
    assert kx == pytest.approx(expected, abs=1e-15)
    assert ky == pytest.approx(expected.T, abs=1e-15)


@pytest.mark.parametrize("order", [2, 3])
def test_kernel_moments(order: int) -> None:
    smooth, kx, _ = beaudet_kernels(5, order)
    _, x = np.mgrid[-2:3, -2:3]  # (rows = y, columns = x)
    assert smooth.sum() == pytest.approx(1.0)
    assert kx.sum() == pytest.approx(0.0, abs=1e-15)
    assert (kx * x).sum() == pytest.approx(1.0)


def test_ramp_gives_exact_gradient() -> None:
    x, y = _grid()
    ex, ey = spatial_gradient((3.0 * x - 2.0 * y + 50.0).astype(np.float32))
    inner = (slice(2, -2), slice(2, -2))  # the border repeats edge pixels
    assert ex[inner] == pytest.approx(3.0, abs=1e-4)
    assert ey[inner] == pytest.approx(-2.0, abs=1e-4)


@pytest.mark.parametrize("order", [2, 3])
def test_quadratic_surface_gives_exact_gradient(order: int) -> None:
    x, y = _grid()
    x, y = (x - 16) / 4, (y - 16) / 4
    img = 40 + 3 * x * x - 2 * x * y + y * y + 5 * x
    ex, ey = spatial_gradient(img.astype(np.float32), 5, order)
    inner = (slice(2, -2), slice(2, -2))
    assert ex[inner] == pytest.approx(((6 * x - 2 * y + 5) / 4)[inner], abs=1e-3)
    assert ey[inner] == pytest.approx(((-2 * x + 2 * y) / 4)[inner], abs=1e-3)


def test_cubic_surface_needs_the_cubic_fit() -> None:
    x, y = _grid()
    x, y = (x - 16) / 4, (y - 16) / 4
    img = (x**3 + x * y * y).astype(np.float32)
    truth = (3 * x * x + y * y) / 4
    inner = (slice(2, -2), slice(2, -2))
    ex3, _ = spatial_gradient(img, 5, 3)
    ex2, _ = spatial_gradient(img, 5, 2)
    assert ex3[inner] == pytest.approx(truth[inner], abs=1e-3)
    assert np.abs(ex2[inner] - truth[inner]).max() > 0.05


def test_temporal_derivative_is_the_smoothed_difference() -> None:
    x, y = _grid()
    e0 = (2.0 * x + y).astype(np.float32)
    ex, ey, et = derivatives(e0, e0 + 7.0)
    assert et == pytest.approx(7.0, abs=1e-4)
    assert ex[2:-2, 2:-2] == pytest.approx(2.0, abs=1e-4)  # gradient of the mean frame
    assert ey[2:-2, 2:-2] == pytest.approx(1.0, abs=1e-4)


def test_bad_windows_are_rejected() -> None:
    with pytest.raises(ValueError):
        beaudet_kernels(4, 2)
    with pytest.raises(ValueError):
        beaudet_kernels(3, 3)
