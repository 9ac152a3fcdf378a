"""The golf tracker's reported confidence: the fitted P(within 10 px) of each row's evidence."""

from pathlib import Path

from trackreplay.replay.core.engine import ReplayRequest, iter_steps
from trackreplay.trackers.golf.calibration import RowEvidence, calibrated

GOLDEN = Path(__file__).resolve().parents[2] / "golden" / "golf-teeshot-640x360.mcap"


def test_a_measured_ball_is_more_likely_right_than_one_predicted_long_after_it_was_seen():
    measured = calibrated(RowEvidence(0.9, True, 0.0))
    assert 0.0 < calibrated(RowEvidence(0.0, False, 5 / 6)) < calibrated(RowEvidence(0.0, False, 1 / 6)) < measured < 1.0


def test_each_reported_confidence_is_the_calibration_of_the_evidence_the_tracker_reports():
    rows = {}
    for calibrate in (False, True):
        steps = iter_steps(ReplayRequest(log=GOLDEN, tracker="golf", seed=0, config={"calibrate": calibrate}))
        rows[calibrate] = [(step.states[0], step.intermediates.evidence) for step in steps if step.states]
    seen = 0
    for (raw, evidence), (reported, same) in zip(rows[False], rows[True]):
        assert (raw.status, raw.x, raw.y) == (reported.status, reported.x, reported.y) and evidence == same
        if raw.status != "lost":
            assert evidence.measured == (raw.status == "measured") and (evidence.misses == 0) == evidence.measured
            assert raw.confidence == evidence.gate and reported.confidence == calibrated(evidence)
            seen += 1
    assert seen > 20 and len(rows[False]) == len(rows[True])
