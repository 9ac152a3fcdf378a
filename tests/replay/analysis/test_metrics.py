"""Known answers: every expected number below is worked out by hand in the comments, not by the code."""

from __future__ import annotations

import math

import numpy as np
import polars as pl
import pytest

from trackreplay.replay.analysis.metrics import (
    IOU_THRESHOLDS, PRECISION_THRESHOLDS_PX, box_scores, point_scores, reliability, truth_has_boxes,
)
from trackreplay.replay.core.trajectory import state_row, trajectory_table
from trackreplay.replay.log.groundtruth import GT_SCHEMA
from trackreplay.schemas.errors import TrackreplayError
from trackreplay.trackers.base import TrackState


def _track(rows: dict[int, dict]) -> pl.DataFrame:
    return trajectory_table(state_row("t", f, f, TrackState(1, **kw)) for f, kw in rows.items())


def _truth(rows: dict[int, tuple]) -> pl.DataFrame:
    """frame -> (x, y, w, h, visible)."""
    return pl.DataFrame([(f, f, 1, x, y, w, h, None, None, None, None, None, vis, None) for f, (x, y, w, h, vis) in rows.items()],
                        schema=GT_SCHEMA, orient="row")


def test_reliability_by_hand() -> None:
    # bin [0, .1): .05 right -> |1 - .05| = .95; bin [.1, .2): .15 twice, one right -> |.5 - .15| = .35;
    # bin [.9, 1]: 1.0 right -> 0; NaN left out. ECE = (1 * .95 + 2 * .35 + 1 * 0) / 4 = .4125
    rel = reliability(np.array([0.05, 0.15, 0.15, 1.0, np.nan]), np.array([True, False, True, True, False]))
    assert rel.ece == pytest.approx(0.4125)
    assert rel.bin_count.tolist() == [1, 2, 0, 0, 0, 0, 0, 0, 0, 1]
    assert rel.bin_accuracy[[0, 1, 9]].tolist() == [1.0, 0.5, 1.0] and np.isnan(rel.bin_accuracy[2])
    assert rel.bin_confidence[1] == pytest.approx(0.15)
    assert rel.bin_lower[3] == pytest.approx(0.3) and rel.bin_upper[9] == 1.0
    # two bins: [0, .5) holds .05 .15 .15 (mean confidence .35/3, accuracy 2/3); [.5, 1] holds 1.0 (right): 0
    two = reliability(np.array([0.05, 0.15, 0.15, 1.0]), np.array([True, False, True, True]), bins=2)
    assert two.ece == pytest.approx(3 / 4 * abs(2 / 3 - 0.35 / 3))
    assert math.isnan(reliability(np.array([np.nan]), np.array([True])).ece)
    with pytest.raises(ValueError, match=r"\[0, 1\]"):
        reliability(np.array([1.5]), np.array([True]))


def test_box_scores_by_hand() -> None:
    # Truth: a 10x10 box centred (50, 50) on frames 0-7 and 9; frame 8 says the target is absent; frame 10
    # is not labelled. Tracker boxes are 10x10 unless said.
    truth = _truth({f: (50.0, 50.0, 10.0, 10.0, True) for f in range(10) if f != 8} | {8: (None, None, None, None, False)})
    track = _track({
        0: dict(x=50.0, y=50.0, w=10.0, h=10.0, confidence=0.95),  # IoU 1, error 0, right
        1: dict(x=55.0, y=50.0, w=10.0, h=10.0, confidence=0.85),  # overlap 5x10=50, union 150: IoU 1/3, error 5
        2: dict(x=52.0, y=50.0, w=10.0, h=10.0, confidence=0.65),  # overlap 80, union 120: IoU 2/3, error 2, right
        3: dict(x=60.0, y=50.0, w=10.0, h=10.0, status="predicted", confidence=0.35),  # touching: IoU 0, error 10
        4: dict(x=80.0, y=50.0, w=10.0, h=10.0, confidence=0.95),  # IoU 0 (wrong), error 30
        # 5: no row: IoU 0, no centre
        6: dict(status="lost"),  # no box: IoU 0
        7: dict(x=50.0, y=75.0, w=10.0, h=10.0, status="predicted", confidence=0.15),  # IoU 0, error 25
        8: dict(x=50.0, y=50.0, w=10.0, h=10.0, confidence=0.55),  # measured while absent: wrong
        9: dict(x=50.0, y=50.0, w=16.0, h=16.0),  # overlap 100, union 256: IoU 0.390625; no confidence
        10: dict(x=0.0, y=0.0, w=10.0, h=10.0, confidence=1.0),  # no truth: not scored
    })
    s = box_scores(track, truth)
    ious = [1.0, 1 / 3, 2 / 3, 0.0, 0.0, 0.0, 0.0, 0.0, 0.390625]  # the 9 visible frames 0-7, 9
    assert s.ious == pytest.approx(ious)
    assert s.mean_iou == pytest.approx(sum(ious) / 9)
    # IoU > t at the 21 thresholds k/20: 1 for k=0..19 (20), 2/3 for k=0..13 (14), 0.390625 for k=0..7 (8),
    # 1/3 for k=0..6 (7): 49 of 21 x 9
    assert s.success_auc == pytest.approx(49 / 189)
    assert s.success_curve[0] == pytest.approx(4 / 9) and s.success_curve[7] == pytest.approx(3 / 9)
    assert s.success_curve[14] == pytest.approx(1 / 9) and s.success_curve[20] == 0.0
    # centre errors 0, 5, 2, 10, 30, -, -, 25, 0: five within 20 px
    assert s.precision_20px == pytest.approx(5 / 9)
    curve = dict(zip(PRECISION_THRESHOLDS_PX.tolist(), s.precision_curve.tolist()))
    assert [curve[t] for t in (0.0, 5.0, 10.0, 25.0, 30.0, 50.0)] == pytest.approx([2 / 9, 4 / 9, 5 / 9, 6 / 9, 7 / 9, 7 / 9])
    # measured rows on labelled frames: 0, 1, 2, 4, 8, 9; wrong: 4 (IoU 0) and 8 (absent)
    assert (s.n_measured, s.n_wrong, s.wrong_rate) == (6, 2, pytest.approx(1 / 3))
    assert (s.n_predicted, s.n_predicted_wrong, s.predicted_wrong_rate) == (2, 2, 1.0)
    assert (s.n_truth_frames, s.n_visible) == (10, 9)
    assert s.coverage == pytest.approx(5 / 9)  # measured on visible frames 0, 1, 2, 4, 9
    # ECE over the 7 rows with a confidence: [.9,1] .95 .95 (1 right: |.5-.95|), [.8,.9) .85 wrong, [.6,.7) .65 right,
    # [.5,.6) .55 wrong, [.3,.4) .35 wrong, [.1,.2) .15 wrong: (2*.45 + .85 + .35 + .55 + .35 + .15) / 7
    assert s.n_calibrated == 7
    assert s.ece == pytest.approx(3.15 / 7)
    row = s.row()
    assert row["success_auc"] == pytest.approx(49 / 189) and row["n_wrong"] == 2 and isinstance(row["n_wrong"], int)
    assert all(isinstance(v, (int, float)) for v in row.values()) and "ious" not in row and "reliability" not in row


def test_point_scores_by_hand() -> None:
    # Truth: a point at (100, 100) on frames 0-5 and 7, invisible on 6; frames 8, 9 not labelled.
    truth = _truth({f: (100.0, 100.0, None, None, True) for f in (0, 1, 2, 3, 4, 5, 7)} | {6: (None, None, None, None, False)})
    track = _track({
        0: dict(x=103.0, y=104.0, confidence=0.95),  # error 5 (3-4-5): within 5 and 10, right
        1: dict(x=106.0, y=108.0, confidence=0.95),  # error 10 (6-8-10): within 10, right
        2: dict(x=100.0, y=120.0, confidence=0.75),  # error 20: not wrong (<= 25), not right (> 10)
        3: dict(x=130.0, y=140.0, confidence=0.95),  # error 50: wrong
        4: dict(x=100.0, y=103.0, status="predicted", confidence=0.25),  # error 3: right, not wrong
        # 5: no row
        6: dict(x=100.0, y=100.0, confidence=0.45),  # measured while invisible: wrong
        7: dict(x=100.0, y=130.0, status="predicted", confidence=0.65),  # error 30: wrong
        9: dict(x=0.0, y=0.0, confidence=0.95),  # not labelled: not scored
    })
    s = point_scores(track, truth)
    assert (s.n_truth_frames, s.n_visible) == (8, 7)
    assert s.errors == pytest.approx([5.0, 10.0, 20.0, 50.0])
    assert s.median_error_px == pytest.approx(15.0)
    assert s.within_5px == pytest.approx(1 / 7) and s.within_10px == pytest.approx(2 / 7)
    assert (s.n_measured, s.n_wrong, s.wrong_rate) == (5, 2, pytest.approx(0.4))  # rows 0 1 2 3 6; wrong 3, 6
    assert (s.n_predicted, s.n_predicted_wrong, s.predicted_wrong_rate) == (2, 1, 0.5)
    assert s.coverage == pytest.approx(4 / 7)
    # ECE: [.9,1] .95 x3, 2 right: 3*|2/3-.95| = .85; .75 wrong .75; .25 right .75; .45 wrong .45; .65 wrong .65
    assert s.ece == pytest.approx(3.45 / 7)
    assert set(s.row()) >= {"within_5px", "within_10px", "median_error_px", "wrong_rate", "predicted_wrong_rate", "ece", "coverage"}


def test_no_measured_rows_gives_nan_rates_and_a_point_truth_is_not_a_box_truth() -> None:
    truth = _truth({0: (5.0, 5.0, None, None, True)})
    s = point_scores(_track({0: dict(status="lost")}), truth)
    assert math.isnan(s.wrong_rate) and math.isnan(s.median_error_px) and math.isnan(s.ece)
    assert (s.within_5px, s.coverage, s.n_measured) == (0.0, 0.0, 0)
    assert not truth_has_boxes(truth) and truth_has_boxes(_truth({0: (5.0, 5.0, 2.0, 2.0, True)}))
    assert not truth_has_boxes(_truth({0: (5.0, 5.0, 2.0, 2.0, False)}))
    with pytest.raises(TrackreplayError, match="point_scores"):
        box_scores(_track({0: dict(x=5.0, y=5.0, w=2.0, h=2.0)}), truth)
    twice = pl.concat([_track({0: dict(x=5.0, y=5.0)}), _track({0: dict(x=6.0, y=5.0)})])
    with pytest.raises(TrackreplayError, match="several rows on one frame"):
        point_scores(twice, truth)


def test_thresholds_are_the_otb_ones() -> None:
    assert IOU_THRESHOLDS.size == 21 and IOU_THRESHOLDS[0] == 0.0 and IOU_THRESHOLDS[-1] == 1.0
    assert PRECISION_THRESHOLDS_PX[20] == 20.0
