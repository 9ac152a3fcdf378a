import numpy as np
import polars as pl
import pytest

from trackreplay.replay.eval import evaluate, iou
from trackreplay.replay.groundtruth import GT_SCHEMA
from trackreplay.replay.trajectory import state_row, trajectory_table
from trackreplay.trackers.base import TrackState


def _gt(n: int) -> pl.DataFrame:
    rows = [(f, f, 1, 10.0 + f, 20.0, 10.0, 10.0, None, None, None, 1.0, 0.0, True, None) for f in range(n)]
    return pl.DataFrame(rows, schema=GT_SCHEMA, orient="row")


def test_iou_known_values() -> None:
    a = np.array([[5.0, 5.0, 10.0, 10.0], [0.0, 0.0, 2.0, 2.0]])
    b = np.array([[10.0, 5.0, 10.0, 10.0], [10.0, 10.0, 2.0, 2.0]])
    assert iou(a, b) == pytest.approx([50 / 150, 0.0])


def test_metrics_against_known_offsets() -> None:
    gt = _gt(10)
    rows = [state_row("flow", f, f, TrackState(1, x=13.0 + f, y=24.0, w=10.0, h=10.0, vx=1.5, vy=0.0)) for f in range(8)]
    summary, frames = evaluate(trajectory_table(rows), gt)
    assert summary.gt_frames == 10 and summary.tracked_frames == 8
    assert summary.centre_error_mean == pytest.approx(5.0)  # a 3-4-5 offset
    assert summary.precision_at_20px == pytest.approx(0.8)  # two missed frames count as failures
    assert summary.velocity_rmse_x == pytest.approx(0.5) and summary.velocity_rmse_y == pytest.approx(0.0)
    expected_iou = (7 * 6) / (200 - 42)
    assert summary.iou_mean == pytest.approx(expected_iou * 0.8)
    assert frames.height == 10


def test_frames_at_different_times_are_refused() -> None:
    """Frame k of the trajectory and of the truth must be the same moment (e.g. not a log cut or
    recovered without renumbering its ground truth)."""
    from trackreplay.schemas.errors import TrackreplayError

    gt = _gt(10)
    rows = [state_row("flow", f, f + (5 if f >= 4 else 0), TrackState(1, x=10.0 + f, y=20.0, w=10.0, h=10.0))
            for f in range(8)]
    with pytest.raises(TrackreplayError, match="frame 4 is at t=9 ns in the trajectory but at t=4 ns"):
        evaluate(trajectory_table(rows), gt)


def test_truth_that_places_nothing_is_one_sentence() -> None:
    """OTB's 0,0,0,0 rows mark the target absent: a file of only those once crashed eval (IndexError)."""
    from trackreplay.schemas.errors import TrackreplayError

    rows = [(f, f, 1, None, None, None, None, None, None, None, None, None, False, None) for f in range(3)]
    gt = pl.DataFrame(rows, schema=GT_SCHEMA, orient="row")
    traj = trajectory_table([state_row("flow", f, f, TrackState(1, x=1.0, y=1.0)) for f in range(3)])
    with pytest.raises(TrackreplayError, match="places no object on any frame"):
        evaluate(traj, gt)
