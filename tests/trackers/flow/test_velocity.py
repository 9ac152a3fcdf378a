import cv2
import numpy as np
import pytest

from trackreplay.trackers.flow.config import FlowConfig
from trackreplay.trackers.flow.local_flow import FlowField
from trackreplay.trackers.flow.refine import refine_flow
from trackreplay.trackers.flow.velocity import histogram_edges, object_velocity

EDGES = histogram_edges(8.0, 0.25)


def _field(u: np.ndarray, v: np.ndarray) -> FlowField:
    valid = np.isfinite(u) & np.isfinite(v)
    return FlowField(u.astype(np.float32), v.astype(np.float32), valid, np.ones_like(u, np.float32))


def test_background_below_epsilon_is_ignored() -> None:
    rng = np.random.default_rng(0)
    u = rng.uniform(-0.45, 0.45, (51, 51))
    v = rng.uniform(-0.45, 0.45, (51, 51))
    u[20:30, 10:20], v[20:30, 10:20] = 2.0, -1.0
    u[0, 0] = np.nan  # rejected by eq. 8
    est = object_velocity(_field(u, v), 0.5, EDGES)
    assert est.count == 100
    assert est.velocity == pytest.approx([2.0, -1.0])
    assert est.centroid == pytest.approx([14.5, 24.5])
    assert est.moving[20:30, 10:20].all() and est.moving.sum() == 100


def test_the_set_s_uses_u_or_v() -> None:
    """Eq. 11: S holds pixels with |u| ≥ ε OR |v| ≥ ε, and both means run over the same S."""
    u = np.zeros((9, 9))
    v = np.zeros((9, 9))
    u[1, 1], v[1, 1] = 1.0, 0.0
    u[5, 5], v[5, 5] = 0.2, -0.8
    est = object_velocity(_field(u, v), 0.5, EDGES)
    assert est.count == 2
    assert est.velocity == pytest.approx([0.6, -0.4])


def test_nothing_moving_gives_nan() -> None:
    est = object_velocity(_field(np.zeros((11, 11)), np.zeros((11, 11))), 0.5, EDGES)
    assert est.count == 0
    assert np.isnan(est.velocity).all() and np.isnan(est.centroid).all()


def test_histograms_count_every_valid_pixel() -> None:
    rng = np.random.default_rng(1)
    u = rng.normal(0, 3, (40, 40))
    v = rng.normal(0, 5, (40, 40))
    u[0, :5] = np.nan
    est = object_velocity(_field(u, v), 0.5, EDGES)
    assert len(est.hist_edges) == 65 and np.diff(est.hist_edges) == pytest.approx(0.25)
    assert est.hist_u.sum() == est.hist_v.sum() == 40 * 40 - 5  # outer bins hold the overflow
    assert est.hist_u.dtype == np.int64


def _textured_disc(radius: int = 15, size: int = 64) -> np.ndarray:
    rng = np.random.default_rng(0)
    tex = cv2.GaussianBlur(rng.normal(0, 1, (size, size)), (0, 0), 2.0)
    tex = 120 + 40 * tex / tex.std()
    yy, xx = np.mgrid[0:size, 0:size]
    c = (size - 1) / 2
    disc = (xx - c) ** 2 + (yy - c) ** 2 <= radius**2
    return np.where(disc, tex, 60.0).astype(np.float32)


@pytest.mark.parametrize("kind", ["rotation", "dilation"])
def test_rotation_and_dilation_average_out(kind: str) -> None:
    """Figs. 2–3: a symmetric object turning or growing about its centre has no mean flow."""
    e0 = _textured_disc()
    c = (e0.shape[1] - 1) / 2
    m = cv2.getRotationMatrix2D((c, c), 3.0, 1.0) if kind == "rotation" else cv2.getRotationMatrix2D((c, c), 0.0, 1.06)
    e1 = cv2.warpAffine(e0, m, e0.shape[::-1], flags=cv2.INTER_CUBIC, borderMode=cv2.BORDER_REPLICATE)
    flow = refine_flow(e0, e1, FlowConfig())
    est = object_velocity(flow, 0.5, EDGES)
    assert est.count > 50  # the object does move
    assert np.hypot(*est.velocity) < 0.1
    assert est.centroid == pytest.approx([c, c], abs=2.0)  # S is a textured ring about the centre


def test_extent_of_a_moving_block() -> None:
    u = np.zeros((51, 51))
    u[15:36, 10:29] = 1.0  # 19 wide, 21 high, moving 1 px/frame in x
    est = object_velocity(_field(u, np.zeros_like(u)), 0.5, EDGES, spread=2.0)
    ys, xs = np.nonzero(u)

    def span(c: np.ndarray) -> float:  # 2nd–98th percentile span + 1
        return float(np.percentile(c, 98) - np.percentile(c, 2) + 1)

    # less the motion (S covers both instants) and twice the spread
    assert est.extent == pytest.approx([span(xs) - 1.0 - 4.0, span(ys) - 0.0 - 4.0])
    assert 13 <= est.extent[0] <= 14 and 16 <= est.extent[1] <= 17
