import numpy as np
import pytest

from trackreplay.trackers.flow.derivatives import derivatives
from trackreplay.trackers.flow.local_flow import FlowField, condition_number, local_flow, normal_equations

INNER = (slice(8, -8), slice(8, -8))


def _flow(e0: np.ndarray, e1: np.ndarray, n: int = 5, cond_max: float = 20.0, min_energy: float = 1.0) -> FlowField:
    ex, ey, et = derivatives(e0, e1)
    return local_flow(ex, ey, et, n, cond_max, min_energy)


@pytest.mark.parametrize("n", [3, 5, 7])
def test_subpixel_translation_of_a_smooth_texture_is_recovered(texture_factory, n: int) -> None:
    d = (0.3, -0.2)
    e0, e1 = texture_factory(96, 2.5, 0, 0), texture_factory(96, 2.5, *d)
    flow = _flow(e0, e1, n)
    assert flow.valid[INNER].mean() > 0.99
    err = np.hypot(flow.u - d[0], flow.v - d[1])[INNER]
    assert np.nanmedian(err) < 0.02
    assert np.nanmean(flow.u[INNER]) == pytest.approx(d[0], abs=0.02)
    assert np.nanmean(flow.v[INNER]) == pytest.approx(d[1], abs=0.02)


def test_pure_edge_is_rejected_by_the_condition_number() -> None:
    """Aperture problem: a straight edge constrains only the normal flow, so cond(G) is huge (eq. 8)."""
    x = np.arange(64, dtype=np.float64)[None, :].repeat(64, axis=0)
    edge = lambda dx: (100 + 50 * np.tanh((x - 32 - dx) / 2.0)).astype(np.float32)  # noqa: E731
    flow = _flow(edge(0.0), edge(0.4))
    near = (slice(8, -8), slice(28, 37))
    assert not flow.valid[near].any()
    assert np.all(flow.cond[near] > 20.0)
    assert np.isnan(flow.u[near]).all() and np.isnan(flow.v[near]).all()


def test_flat_region_has_no_flow() -> None:
    flat = np.full((32, 32), 120.0, np.float32)
    flow = _flow(flat, flat + 0.01)
    assert not flow.valid.any()


def test_condition_number_is_the_2_norm_condition_of_g() -> None:
    rng = np.random.default_rng(0)
    for _ in range(20):
        g = rng.normal(size=(25, 2)) * rng.uniform(0.1, 10, size=2)
        gtg = g.T @ g
        cond = condition_number(np.array(gtg[0, 0]), np.array(gtg[0, 1]), np.array(gtg[1, 1]))
        assert float(cond) == pytest.approx(np.linalg.cond(g, 2), rel=1e-9)
    assert np.isinf(condition_number(np.array(1.0), np.array(1.0), np.array(1.0)))  # rank one


def test_closed_form_matches_lstsq_on_one_neighbourhood(texture_factory) -> None:
    e0, e1 = texture_factory(40, 2.0, 0, 0), texture_factory(40, 2.0, 0.4, 0.1)
    ex, ey, et = derivatives(e0, e1)
    flow = local_flow(ex, ey, et, 5, 1e9, 0.0)
    g = np.stack([ex[18:23, 18:23].ravel(), ey[18:23, 18:23].ravel()], 1).astype(np.float64)
    b = et[18:23, 18:23].ravel().astype(np.float64)
    w = np.linalg.lstsq(g, -b, rcond=None)[0]  # eq. 5–7: G w + b = 0
    assert [flow.u[20, 20], flow.v[20, 20]] == pytest.approx(w, rel=1e-4)
    a, bb, c, p, q = normal_equations(ex, ey, et, 5)
    assert a[20, 20] == pytest.approx((g[:, 0] ** 2).mean(), rel=1e-5)
