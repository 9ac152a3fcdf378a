"""Honest status: is the selected blob the ball? (ours, on top of the paper's §2.1 gate)

The blob gate (:mod:`.blobs`) only asks whether a blob *looks* like the ball. This stage asks
whether it can *be* the ball given the motion model, and gives every frame a confidence:

- **validation gate** around the particles' predicted mean: radius ``gate_sigmas * s`` with
  ``s = sqrt(σx² + σy²) + D/2`` (the samples' spread after eq. (1) and the ball diameter), ``s``
  at most ``max_spread_px + D`` so a cloud spread wide after a loss does not accept anything in
  the picture. Only shape-accepted blobs inside the gate are the observation ``z_t`` of eq. (2);
- **confidence** of the in-gate blob nearest the prediction: ``fit * exp(-d² / 2s²)``, ``fit``
  from its area and roundness against the targets. ``measured`` needs ``min_confidence``, and
  ``min_fit`` from the shape alone (a speck a fifth of the ball's area right on the predicted path
  is not the ball: the edge of a cup's liner after the ball merged with it); below, the row is
  ``predicted`` and nothing (targets, EKF, LUTs) learns from the blob;
- **no jumps without evidence**: a shape-accepted blob outside the gate, or any blob once the
  track is lost, or while the prediction has left the picture, starts or extends a *tentative*
  track. Only when it has been seen on ``confirm_frames`` consecutive frames, each within
  ``confirm_px + D`` of the constant-velocity extrapolation of the previous ones, is it accepted:
  the particles start again there (re-initialisation kind ``"confirmed"``), provided the tentative
  blobs agree with *each other*: their areas within ``area_tolerance`` of one another and their
  roundness within the shape tolerance of a disc (``confirm_fit`` of :func:`track_fit`). The
  targets are not asked: after a loss they are stale (a receding ball under a zooming lens, a
  streak's fragments), and the ball's size starts again from the confirmed blobs. When another
  accepted blob of a similar size is in view, nothing is confirmed (verdict ``ambiguous``): after
  a loss the tracker cannot tell its ball from a spare one;
- **gone**: when the predicted mean is more than a ball diameter outside the picture nothing in
  the picture is accepted directly (the ball left it); the track is ``predicted`` and then
  ``lost`` (no position) after ``max_predicted_frames`` misses, like any other miss. When the
  camera does not follow the ball (``entry_only``), a tentative track must then start within
  ``entry_margin_px`` (+ 2 D) of the picture's edge: the ball comes back in through it.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from trackreplay.trackers.golf.blobs import GatedBlobs, roundness, shape_tolerance
from trackreplay.trackers.golf.config import BlobConfig, ValidateConfig

VERDICTS = ("measured", "confirmed", "no_candidate", "low_confidence", "outside_gate", "outside_image", "lost", "start",
            "ambiguous")


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


def track_fit(areas: np.ndarray, rounds: np.ndarray, cfg: BlobConfig, scale: float, min_area: float = 2.0) -> float:
    """How well the blobs of a tentative track agree with one another and with a disc, in [0, 1]:
    the spread of their log-areas (in units of ``log area_tolerance``) and how far their median
    roundness falls short of a disc's (in units of the shape tolerance). 0 when a blob has fewer
    than ``min_area`` pixels: a single pixel has no shape, and noise specks are single pixels."""
    if np.asarray(areas, float).size and float(np.min(areas)) < min_area:
        return 0.0
    slack = cfg.area_slack_px * scale * scale
    la = np.log(np.asarray(areas, float) + slack)
    spread = float(la.max() - la.min()) / math.log(cfg.area_tolerance) if la.size else 0.0
    r = float(np.nanmedian(rounds)) if np.isfinite(rounds).any() else 0.0
    tol = float(shape_tolerance(np.median(areas), cfg, scale))
    short = max(0.0, 1.0 - cfg.circularity_tolerance - r) / tol
    return math.exp(-0.5 * spread * spread) * math.exp(-0.5 * short * short)


class Validator:
    """Decides per frame whether the ball was seen, with a tentative track for jumps."""

    def __init__(self, cfg: ValidateConfig, blobs: BlobConfig) -> None:
        self.cfg = cfg
        self.blobs = blobs
        self.tentative: list[tuple[int, float, float]] = []
        self.shapes: list[tuple[float, float]] = []  # (area, roundness) of each tentative blob

    def reset(self) -> None:
        self.tentative = []
        self.shapes = []

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
        verdict = "measured" if confidence >= self.cfg.min_confidence and fit >= self.cfg.min_fit else "low_confidence"
        return Validation(verdict, confidence, fit, motion, radius, k, np.zeros((0, 3)), in_gate), in_gate, outside

    def validate(self, *, index: int, gated: GatedBlobs, predicted: np.ndarray, spread: np.ndarray, diameter: float,
                 size: tuple[int, int], scale: float, lost: bool, entry_only: bool = False) -> Validation:
        """The frame's verdict. ``entry_only``: the camera does not follow the ball, so once the
        prediction has left the picture a new tentative track may only start near the border (a
        ball comes back into a fixed view through its edge, not out of a white cap mid-picture)."""
        cfg = self.cfg
        _, radius = self.gate(spread, diameter, scale)
        ok = gated.accepted
        found, in_gate, outside = self.seen_in_gate(gated=gated, predicted=predicted, spread=spread, diameter=diameter,
                                                    size=size, scale=scale, lost=lost)
        if found is not None:
            if found.verdict == "measured":
                self.reset()
                return found
            return dataclasses.replace(found, tentative=self._rows())
        verdict = "outside_image" if outside else "lost" if lost else "outside_gate" if ok.any() else "no_candidate"
        border = None
        if outside and entry_only:
            border = (size, cfg.entry_margin_px * scale + 2.0 * diameter)
        k = self._extend(index, gated, predicted, diameter, scale, border)
        fit = 0.0
        if k >= 0:
            shapes = np.array(self.shapes[-cfg.confirm_frames:], float).reshape(-1, 2)
            fit = track_fit(shapes[:, 0], shapes[:, 1], self.blobs, scale, cfg.confirm_min_area_px)
        if k >= 0 and len(self.tentative) >= cfg.confirm_frames and fit >= cfg.confirm_fit:
            if self._ambiguous(gated, k, scale):
                return Validation("ambiguous", 0.0, fit, 0.0, radius, k, self._rows(), in_gate)
            return Validation("confirmed", fit, fit, 0.0, radius, k, self._rows(), in_gate)
        return Validation(verdict, 0.0, 0.0, 0.0, radius, k, self._rows(), in_gate)

    def _ambiguous(self, gated: GatedBlobs, k: int, scale: float) -> bool:
        """Another shape-accepted blob this frame looks as much like the tentative ball (area within
        ``area_tolerance`` of the tentative blobs' median): after a loss the tracker cannot tell which
        of two such balls is its own (a spare ball, a tee marker), so it confirms neither."""
        others = np.flatnonzero(gated.accepted)
        others = others[others != k]
        if not others.size:
            return False
        slack = self.blobs.area_slack_px * scale * scale
        typical = float(np.median(np.array(self.shapes, float).reshape(-1, 2)[:, 0]))
        ratio = np.abs(np.log((gated.blobs.area[others] + slack) / (typical + slack)))
        return bool((ratio <= math.log(self.blobs.area_tolerance)).any())

    def confirmed_velocity(self) -> np.ndarray:
        """Per-frame velocity of the confirmed tentative track (px/frame)."""
        t = np.array(self.tentative, float)
        return (t[-1, 1:] - t[0, 1:]) / max(t[-1, 0] - t[0, 0], 1.0)

    def _rows(self) -> np.ndarray:
        return np.array(self.tentative, float).reshape(-1, 3)

    def _extend(self, index: int, gated: GatedBlobs, predicted: np.ndarray, diameter: float, scale: float,
                border: tuple[tuple[int, int], float] | None = None) -> int:
        """Continue the tentative track with a shape-accepted blob (or start one: only within
        ``border = ((width, height), margin)`` of the picture's edge when given); the blob row or -1."""
        ok = np.flatnonzero(gated.accepted)
        if not ok.size:
            if self.tentative and index - self.tentative[-1][0] > 1:
                self.reset()
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
                self.shapes.append((float(gated.blobs.area[k]), float(roundness(gated.blobs)[k])))
                return k
        if border is not None:
            (width, height), margin = border
            x, y = c[ok, 0], c[ok, 1]
            ok = ok[(x < margin) | (y < margin) | (x > width - 1 - margin) | (y > height - 1 - margin)]
            if not ok.size:
                self.reset()
                return -1
        dist = np.hypot(c[ok, 0] - predicted[0], c[ok, 1] - predicted[1])
        k = int(ok[int(np.argmin(dist))])
        self.tentative = [(index, float(c[k, 0]), float(c[k, 1]))]
        self.shapes = [(float(gated.blobs.area[k]), float(roundness(gated.blobs)[k]))]
        return k

    def confirmed_shape(self) -> tuple[float, float]:
        """Median area and roundness of the confirmed tentative blobs: the ball's new targets."""
        shapes = np.array(self.shapes, float).reshape(-1, 2)
        return float(np.median(shapes[:, 0])), float(np.nanmedian(shapes[:, 1])) if np.isfinite(shapes[:, 1]).any() else 0.9
