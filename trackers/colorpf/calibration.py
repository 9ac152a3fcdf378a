"""The confidence a row reports as a probability that it is right (``calibrate``, ours; issue 31).

The colour's confidence places the estimate's intersection ``S`` between the background's score and
the mark's: it says how well the colours match, not how often such a row is right. On the colour PF's
box corpus its expected calibration error against "IoU >= 0.5" was 0.31 (docs/colorpf.md, "Calibrated
confidence"): rows placed by a foreground region on otb_crossing are right at a colour confidence near
0, "measured" rows on otb_human3 are wrong at near 1. The reported confidence is therefore a logistic
model of what the filter knows about the row (:class:`RowEvidence`), fitted by weighted maximum
likelihood on that corpus's rows (each sequence weighs alike, seeds 0-2, an L2 penalty of 1 on the
slopes), checked by leaving each sequence out of the fit in turn. The status is not changed, nor the
colour confidence the filter's own stages use (the adaptive reference's guard).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from trackreplay.trackers.confidence import logistic

# Intercept, then one slope per feature of RowEvidence.features(), in that order; fitted on
# benchmarks/corpora/colorpf-box.toml (docs/colorpf.md, "Calibrated confidence").
COEFFICIENTS = (1.26, -1.751, 0.749, 1.218, 3.921, -3.523, -2.967, -0.577)
UNSUPPORTED_SCALE = 60  # frames without support are counted in units of 60 (2 s at 30 fps), capped at 1


@dataclass(frozen=True)
class RowEvidence:
    """What the filter knows about a row when it reports it."""

    colour: float  # the colour's confidence (S between the background's score and the mark's), [0, 1]
    measured: bool  # the row is "measured"
    placed: bool  # a "predicted" row placed by a foreground region (supported)
    separation: float  # S_mark - S_back: how far the mark stands out from the whole background
    effective_share: float  # the particles' effective sample size over N (1: uniform weights)
    spread: float  # the cloud's weighted std (mean of x and y) over the estimate's sqrt(w h)
    unsupported: int  # frames without support before this one

    def features(self) -> np.ndarray:
        return np.array([1.0, self.colour, float(self.measured), float(self.placed),
                         float(np.clip(self.separation, -0.5, 0.5)), self.effective_share, min(self.spread, 2.0),
                         min(self.unsupported, UNSUPPORTED_SCALE) / UNSUPPORTED_SCALE])


def calibrated(evidence: RowEvidence, coefficients: tuple[float, ...] = COEFFICIENTS) -> float:
    """P(IoU >= 0.5) for the row (:func:`trackreplay.trackers.confidence.logistic`)."""
    return logistic(evidence.features().tolist(), coefficients)


def cloud_evidence(weights: np.ndarray, particles: np.ndarray, estimate: np.ndarray) -> tuple[float, float]:
    """The effective sample size over N and the cloud's spread relative to the estimate's size."""
    w = np.asarray(weights, dtype=np.float64)
    xy = np.asarray(particles, dtype=np.float64)[:, :2]
    share = float(1.0 / np.sum(w ** 2)) / len(w)
    std = np.sqrt(w @ ((xy - w @ xy) ** 2))
    return share, float(std.mean() / max(np.sqrt(estimate[2] * estimate[3]), 1e-6))


__all__ = ["RowEvidence", "calibrated", "cloud_evidence", "COEFFICIENTS"]
