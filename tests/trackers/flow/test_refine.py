import numpy as np
import pytest

from trackreplay.trackers.flow.config import FlowConfig
from trackreplay.trackers.flow.refine import online_step, refine_flow

INNER = (slice(12, -12), slice(12, -12))


def _error(flow, d) -> float:
    return float(np.nanmean(np.hypot(flow.u - d[0], flow.v - d[1])[INNER]))


@pytest.mark.parametrize("d", [(2.0, -1.0), (2.5, -1.5), (-3.0, 2.0)])
def test_refinement_beats_a_single_least_squares_solve(texture_factory, d) -> None:
    e0, e1 = texture_factory(96, 2.5, 0, 0), texture_factory(96, 2.5, *d)
    single = refine_flow(e0, e1, FlowConfig(sigmas=(0.0,), refine_iterations=1))  # eq. 7 alone
    refined = refine_flow(e0, e1, FlowConfig())  # eq. 9–10 with σ = 2, 1, 0.5, 0
    assert _error(single, d) > 0.2
    assert _error(refined, d) < min(0.05, _error(single, d) / 10)
    assert refined.iterations >= 2
    assert refined.residual < single.residual


def test_online_steps_converge_with_time(texture_factory) -> None:
    """§4.1: one refinement per frame, warm-started; repeated on one pair it converges like eq. 9."""
    d = (2.0, 1.5)
    e0, e1 = texture_factory(96, 2.5, 0, 0), texture_factory(96, 2.5, *d)
    cfg = FlowConfig()
    flow, errors = None, []
    for step in range(5):
        flow = online_step(e0, e1, flow, cfg, step=step)
        errors.append(_error(flow, d))
    assert errors[-1] < 0.1
    assert errors[-1] < errors[0] / 4


def test_identical_frames_give_zero_flow_and_residual(texture_factory) -> None:
    e0 = texture_factory(64, 2.5, 0, 0)
    flow = refine_flow(e0, e0.copy(), FlowConfig())
    assert np.nanmax(np.abs(flow.u)) < 1e-4 and np.nanmax(np.abs(flow.v)) < 1e-4
    assert flow.residual == pytest.approx(0.0, abs=1e-3)


def test_the_residual_never_grows_over_accepted_iterations(texture_factory) -> None:
    """Eq. 10: each accepted refinement leaves a residual no larger than before it."""
    d = (2.5, -1.5)
    e0, e1 = texture_factory(96, 2.5, 0, 0), texture_factory(96, 2.5, *d)
    residuals = []
    for n in range(1, 5):
        flow = refine_flow(e0, e1, FlowConfig(sigmas=(0.0,), refine_iterations=n))
        residuals.append(flow.residual)
    assert residuals == sorted(residuals, reverse=True)


def test_pyramid_option_handles_motions_beyond_single_scale(texture_factory) -> None:
    d = (5.0, -4.0)
    e0, e1 = texture_factory(128, 2.5, 0, 0), texture_factory(128, 2.5, *d)
    single = refine_flow(e0, e1, FlowConfig())
    pyramid = refine_flow(e0, e1, FlowConfig(pyramid_levels=2))
    assert _error(pyramid, d) < 0.1 < _error(single, d)
