"""The golf tracker's reported confidence as P(the row is within 10 px of the ball) (ours; issue 30).

The validation's confidence (:mod:`.validate`: the blob's shape fit times the motion term) says how well
the blob agrees with the targets and the prediction. On the ball corpus (benchmarks/corpora/ball.toml,
seeds 0-2, marks jittered by 2 px) `measured` rows at 0.3-0.7 were right 92-100 % of the time, and
`predicted` rows at 0 were right about a fifth of the time. The reported confidence is a logistic model
of the row's evidence (:class:`RowEvidence`) fitted on those rows (docs/golf_calibration.py; each case
weighs alike, an L2 penalty of 1 on the slopes, checked by leaving each case out). What the tracker's
own stages use (the LUTs' ``learn_confidence``, the validation's thresholds) stays the validation's.
"""

from __future__ import annotations

from dataclasses import dataclass

from trackreplay.trackers.confidence import logistic

# Intercept, then one slope per feature of RowEvidence.features(), in that order: fitted by
# docs/golf_calibration.py on benchmarks/corpora/ball.toml (docs/ball_corpus.md, "Calibrated confidence").
COEFFICIENTS = (0.018, 2.345, 2.505, -1.252)


@dataclass(frozen=True)
class RowEvidence:
    """What the tracker knows about a "measured" or "predicted" row when it reports it."""

    gate: float  # the validation's confidence of the blob considered (0: none), [0, 1]
    measured: bool  # the row is "measured"
    misses: float  # frames in a row without the ball over the frames after which the track is lost, [0, 1]

    def features(self) -> tuple[float, float, float, float]:
        return (1.0, min(max(self.gate, 0.0), 1.0), float(self.measured), min(max(self.misses, 0.0), 1.0))


def calibrated(evidence: RowEvidence, coefficients: tuple[float, ...] = COEFFICIENTS) -> float:
    """P(within 10 px) for the row (:func:`trackreplay.trackers.confidence.logistic`)."""
    return logistic(evidence.features(), coefficients)


__all__ = ["COEFFICIENTS", "RowEvidence", "calibrated"]
