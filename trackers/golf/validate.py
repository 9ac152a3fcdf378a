"""Honest status: is the selected blob the ball? (ours, on top of the paper's §2.1 gate)

The blob gate (:mod:`.blobs`) only asks whether a blob *looks* like the ball. This stage asks
whether it can *be* the ball given the motion model, and gives every frame a confidence:

- **validation gate** around the particles' predicted mean: radius ``gate_sigmas * s`` with
  ``s = sqrt(σx² + σy²) + D/2`` (the samples' spread after eq. (1) and the ball diameter), ``s``
  at most ``max_spread_px + D`` so a cloud spread wide after a loss does not accept anything in
  the picture. Only shape-accepted blobs inside the gate are the observation ``z_t`` of eq. (2);
- **confidence** of the in-gate blob nearest the prediction: ``fit * exp(-d² / 2s²)``, ``fit``
  from its area and roundness against the targets. ``measured`` needs ``min_confidence``; below,
  the row is ``predicted`` and nothing (targets, EKF, LUTs) learns from the blob;
- **no jumps without evidence**: a shape-accepted blob outside the gate, or any blob once the
  track is lost, or while the prediction has left the picture, starts or extends a *tentative*
  track. Only when it has been seen on ``confirm_frames`` consecutive frames, each within
  ``confirm_px + D`` of the constant-velocity extrapolation of the previous ones, is it accepted:
  the particles start again there (re-initialisation kind ``"confirmed"``), provided it then fits
  the target area and roundness (``confirm_fit``);
- **gone**: when the predicted mean is more than a ball diameter outside the picture nothing in
  the picture is accepted directly (the ball left it); the track is ``predicted`` and then
  ``lost`` (no position) after ``max_predicted_frames`` misses, like any other miss.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from trackreplay.trackers.golf.blobs import GatedBlobs, roundness, shape_tolerance
from trackreplay.trackers.golf.config import BlobConfig, ValidateConfig

VERDICTS = ("measured", "confirmed", "no_candidate", "low_confidence", "outside_gate", "outside_image", "lost", "start")


@dataclass(frozen=True, eq=False)
class Validation:
    """The validation stage's intermediates."""

    verdict: str  # one of VERDICTS: why this frame is (not) measured
    confidence: float  # of the ball blob considered (0: none)
    fit: float  # its area/roundness fit to the targets
    motion: float  # its agreement with the predicted position
    gate_px: float  # validation gate radius around the prediction
    candidate: int  # the blob row considered (-1: none)
    tentative: np.ndarray  # (n, 3) frame, x, y of the unconfirmed track (0 rows: none)
    in_gate: np.ndarray  # (K,) bool: blobs inside the gate that measure eq. (2)

    @classmethod
    def empty(cls) -> Validation:
        return cls("", 0.0, 0.0, 0.0, math.nan, -1, np.zeros((0, 3)), np.zeros(0, bool))


def blob_fit(gated: GatedBlobs, k: int, cfg: BlobConfig, scale: float) -> float:
    """How well blob ``k`` fits the target area and roundness, in (0, 1]."""
    slack = cfg.area_slack_px * scale * scale
    ratio = math.log((float(gated.blobs.area[k]) + slack) / (float(gated.targets[0]) + slack)) / math.log(cfg.area_tolerance)
    r = float(roundness(gated.blobs)[k])
    tol = float(shape_tolerance(gated.blobs.area[k], cfg, scale))
    short = max(0.0, float(gated.targets[1]) - r) / tol if math.isfinite(r) else 1.0
    return math.exp(-0.5 * ratio * ratio) * math.exp(-0.5 * short * short)


class Validator:
    """Decides per frame whether the ball was seen, with a tentative track for jumps."""

    def __init__(self, cfg: ValidateConfig, blobs: BlobConfig) -> None:
        self.cfg = cfg
        self.blobs = blobs
        self.tentative: list[tuple[int, float, float]] = []

    def reset(self) -> None:
        self.tentative = []

    def gate(self, spread: np.ndarray, diameter: float, scale: float) -> tuple[float, float]:
        """``(s, radius)``: the motion scale and the gate radius for this frame."""
        s = min(float(np.hypot(*spread)), self.cfg.max_spread_px * scale) + 0.5 * diameter
        return s, self.cfg.gate_sigmas * s

    def seen_in_gate(self, *, gated: GatedBlobs, predicted: np.ndarray, spread: np.ndarray, diameter: float,
                     size: tuple[int, int], scale: float, lost: bool) -> tuple[Validation | None, np.ndarray, bool]:
        """The in-gate blob nearest the prediction as a "measured" or "low_confidence" validation
        (None: no blob in the gate), the in-gate mask and whether the prediction left the picture.
        Changes nothing (the tracker also asks it of the other LUT's silhouette)."""
        width, height = size
        s, radius = self.gate(spread, diameter, scale)
        ok = gated.accepted
        c = gated.blobs.centroid
        d = np.hypot(c[:, 0] - predicted[0], c[:, 1] - predicted[1]) if len(c) else np.zeros(0)
        outside = bool(predicted[0] < -diameter or predicted[1] < -diameter or predicted[0] > width - 1 + diameter
                       or predicted[1] > height - 1 + diameter)
        in_gate = ok & (d <= radius) & (not outside) & (not lost)
        if not in_gate.any():
            return None, in_gate, outside
        k = int(np.flatnonzero(in_gate)[np.argmin(d[in_gate])])
        fit = blob_fit(gated, k, self.blobs, scale)
        motion = math.exp(-0.5 * (float(d[k]) / s) ** 2)
        confidence = fit * motion
        verdict = "measured" if confidence >= self.cfg.min_confidence else "low_confidence"
        return Validation(verdict, confidence, fit, motion, radius, k, np.zeros((0, 3)), in_gate), in_gate, outside

    def validate(self, *, index: int, gated: GatedBlobs, predicted: np.ndarray, spread: np.ndarray, diameter: float,
                 size: tuple[int, int], scale: float, lost: bool) -> Validation:
        cfg = self.cfg
        _, radius = self.gate(spread, diameter, scale)
        ok = gated.accepted
        found, in_gate, outside = self.seen_in_gate(gated=gated, predicted=predicted, spread=spread, diameter=diameter,
                                                    size=size, scale=scale, lost=lost)
        if found is not None:
            if found.verdict == "measured":
                self.tentative = []
                return found
            return dataclasses.replace(found, tentative=self._rows())
        verdict = "outside_image" if outside else "lost" if lost else "outside_gate" if ok.any() else "no_candidate"
        k = self._extend(index, gated, predicted, diameter, scale)
        fit = blob_fit(gated, k, self.blobs, scale) if k >= 0 else 0.0
        if k >= 0 and len(self.tentative) >= cfg.confirm_frames and fit >= cfg.confirm_fit:
            return Validation("confirmed", fit, fit, 0.0, radius, k, self._rows(), in_gate)
        return Validation(verdict, 0.0, 0.0, 0.0, radius, k, self._rows(), in_gate)

    def confirmed_velocity(self) -> np.ndarray:
        """Per-frame velocity of the confirmed tentative track (px/frame)."""
        t = np.array(self.tentative, float)
        return (t[-1, 1:] - t[0, 1:]) / max(t[-1, 0] - t[0, 0], 1.0)

    def _rows(self) -> np.ndarray:
        return np.array(self.tentative, float).reshape(-1, 3)

    def _extend(self, index: int, gated: GatedBlobs, predicted: np.ndarray, diameter: float, scale: float) -> int:
        """Continue the tentative track with a shape-accepted blob (or start one); the blob row or -1."""
        ok = np.flatnonzero(gated.accepted)
        if not ok.size:
            if self.tentative and index - self.tentative[-1][0] > 1:
                self.tentative = []
            return -1
        c = gated.blobs.centroid
        if self.tentative and index - self.tentative[-1][0] == 1:
            last = np.array(self.tentative[-1][1:])
            velocity = last - np.array(self.tentative[-2][1:]) if len(self.tentative) > 1 else np.zeros(2)
            expected = last + velocity
            dist = np.hypot(c[ok, 0] - expected[0], c[ok, 1] - expected[1])
            j = int(np.argmin(dist))
            if dist[j] <= self.cfg.confirm_px * scale + diameter:
                k = int(ok[j])
                self.tentative.append((index, float(c[k, 0]), float(c[k, 1])))
                return k
        dist = np.hypot(c[ok, 0] - predicted[0], c[ok, 1] - predicted[1])
        k = int(ok[int(np.argmin(dist))])
        self.tentative = [(index, float(c[k, 0]), float(c[k, 1]))]
        return k
