"""Single-target scores of one track against one object's truth: boxes (OTB success and precision),
points (share within 5 and 10 px, median error), how often a ``measured`` or ``predicted`` row is
wrong, and the calibration of ``confidence`` (expected calibration error, reliability diagram).

Defined once here; ``trackreplay evaluate`` writes :meth:`BoxScores.row` / :meth:`PointScores.row`
as its table's columns. Protocols: OTB's success and precision plots (Wu, Lim & Yang, "Online Object
Tracking: A Benchmark", CVPR 2013); expected calibration error and the reliability diagram
(Guo, Pleiss, Sun & Weinberger, "On Calibration of Modern Neural Networks", ICML 2017).

Which rows count: only frames the truth labels (a frame without a truth row is not scored). A truth
frame is *visible* when its ``visible`` is true or unknown (null) and it has a position (boxes: a
box of positive size); any other truth frame says the target is absent there.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np
import polars as pl

from trackreplay.schemas.errors import TrackreplayError
from trackreplay.trackers.geometry.box import iou

IOU_THRESHOLDS = np.linspace(0.0, 1.0, 21)  # OTB success plot: overlap thresholds 0, 0.05 … 1
PRECISION_THRESHOLDS_PX = np.arange(0.0, 51.0)  # OTB precision plot: centre error 0 … 50 px
PRECISION_PX = 20.0  # OTB's reported precision
RIGHT_IOU = 0.5  # a box row is "right" (calibration) at IoU >= 0.5
POINT_NEAR_PX = (5.0, 10.0)  # shares of visible truth frames with a measured point this close
POINT_RIGHT_PX = 10.0  # a point row is "right" (calibration) within 10 px of a visible truth
POINT_WRONG_PX = 25.0  # a point row farther than this from the truth is wrong
CALIBRATION_BINS = 10
MEASURED, PREDICTED = "measured", "predicted"


@dataclass(frozen=True)
class Reliability:
    """Reliability diagram and expected calibration error over equal-width confidence bins on [0, 1]
    (``bin_lower <= c < bin_upper``; the last bin includes 1.0). ``ece = Σ_b (n_b / N) |acc_b − conf_b|``
    (Guo et al. 2017); an empty bin has NaN confidence and accuracy and count 0; ``ece`` is NaN when
    no row has a confidence."""

    ece: float
    bin_lower: np.ndarray
    bin_upper: np.ndarray
    bin_confidence: np.ndarray  # mean confidence of the bin's rows
    bin_accuracy: np.ndarray  # share of the bin's rows that are right
    bin_count: np.ndarray  # int64


def reliability(confidence: np.ndarray, right: np.ndarray, bins: int = CALIBRATION_BINS) -> Reliability:
    """Calibration of ``confidence`` (in [0, 1]; NaN = no confidence, excluded) against ``right`` (bool)."""
    conf = np.asarray(confidence, dtype=np.float64).ravel()
    ok = np.asarray(right, dtype=bool).ravel()
    if conf.shape != ok.shape:
        raise ValueError(f"confidence ({conf.size}) and right ({ok.size}) must have one value per row")
    if bins < 1:
        raise ValueError(f"bins must be at least 1, not {bins}")
    keep = ~np.isnan(conf)
    conf, ok = conf[keep], ok[keep]
    if np.any((conf < 0.0) | (conf > 1.0)):
        raise ValueError("confidence must lie in [0, 1]")
    edges = np.linspace(0.0, 1.0, bins + 1)
    index = np.clip(np.searchsorted(edges, conf, side="right") - 1, 0, bins - 1)  # bin_lower <= c < bin_upper
    count = np.bincount(index, minlength=bins).astype(np.int64)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean_conf = np.bincount(index, weights=conf, minlength=bins) / count
        accuracy = np.bincount(index, weights=ok.astype(np.float64), minlength=bins) / count
    filled = count > 0
    ece = float(np.sum(count[filled] / conf.size * np.abs(accuracy[filled] - mean_conf[filled]))) if conf.size else float("nan")
    return Reliability(ece, edges[:-1].copy(), edges[1:].copy(), mean_conf, accuracy, count)


class _Row:
    """``row()``: the scalar fields as flat columns (arrays and the reliability diagram left out)."""

    def row(self) -> dict[str, float | int]:
        out: dict[str, float | int] = {}
        for f in fields(self):  # type: ignore[arg-type]
            value = getattr(self, f.name)
            if isinstance(value, (bool, np.bool_)):
                out[f.name] = int(value)
            elif isinstance(value, (int, np.integer)):
                out[f.name] = int(value)
            elif isinstance(value, (float, np.floating)):
                out[f.name] = float(value)
        return out


@dataclass(frozen=True)
class BoxScores(_Row):
    """OTB-style scores of one track's boxes. Success and precision count every truth frame with a
    visible box; the tracker's box there is its row whatever the status (``measured``,
    ``predicted``, ``interpolated``), and a frame where it gives no box counts IoU 0 and an infinite
    centre error. Rates whose denominator is 0 are NaN."""

    success_auc: float  # mean of success_curve
    precision_20px: float  # share of visible truth frames with centre error <= 20 px
    mean_iou: float  # over visible truth frames (no box: 0)
    wrong_rate: float  # n_wrong / n_measured
    predicted_wrong_rate: float  # n_predicted_wrong / n_predicted
    ece: float  # calibration of confidence, right := truth visible and IoU >= 0.5
    coverage: float  # share of visible truth frames with a measured row
    n_truth_frames: int  # labelled frames
    n_visible: int  # labelled frames with a visible box
    n_measured: int  # measured rows on labelled frames
    n_wrong: int  # of those: IoU 0 with the truth box, or measured while the truth says absent
    n_predicted: int  # predicted rows with a position on labelled frames
    n_predicted_wrong: int
    n_calibrated: int  # rows with a confidence that the ECE counts
    success_curve: np.ndarray  # at IOU_THRESHOLDS: share of visible truth frames with IoU > threshold
    precision_curve: np.ndarray  # at PRECISION_THRESHOLDS_PX: share with centre error <= threshold
    ious: np.ndarray  # per visible truth frame, in frame order
    reliability: Reliability


@dataclass(frozen=True)
class PointScores(_Row):
    """Scores of one track's centre against a point (or box centre) truth. Only ``measured`` rows
    count as found; ``errors`` (px, frame order) are those of measured rows on visible truth frames,
    for an error CDF. Rates whose denominator is 0 are NaN."""

    within_5px: float  # share of visible truth frames with a measured row within 5 px
    within_10px: float  # ... within 10 px
    median_error_px: float  # of errors
    wrong_rate: float  # n_wrong / n_measured
    predicted_wrong_rate: float  # n_predicted_wrong / n_predicted
    ece: float  # calibration of confidence, right := truth visible and within 10 px
    coverage: float  # share of visible truth frames with a measured row
    n_truth_frames: int
    n_visible: int
    n_measured: int
    n_wrong: int  # measured rows > 25 px from the truth, or measured while the truth says invisible
    n_predicted: int
    n_predicted_wrong: int
    n_calibrated: int
    errors: np.ndarray
    reliability: Reliability


def _rate(num: int | float, den: int) -> float:
    return float(num) / den if den else float("nan")


def _joined(track: pl.DataFrame, truth: pl.DataFrame) -> dict[str, np.ndarray]:
    """The truth's frames with the track's row beside each (``est_*``; NaN where it has none)."""
    for name, table in (("track", track), ("truth", truth)):
        if table.height and table["frame"].is_duplicated().any():
            raise TrackreplayError(f"the {name} has several rows on one frame: give one track and one truth object")
    est = track.select("frame", pl.col("status").alias("est_status"),
                       *(pl.col(c).cast(pl.Float64).alias(f"est_{c}") for c in ("x", "y", "w", "h", "confidence")))
    gt = truth.select("frame", "x", "y", *(c for c in ("w", "h") if c in truth.columns), "visible")
    j = gt.join(est, on="frame", how="left").sort("frame")
    out = {c: j[c].cast(pl.Float64).fill_null(np.nan).to_numpy() for c in j.columns
           if c not in ("est_status", "visible", "frame")}
    out["status"] = j["est_status"].fill_null("").to_numpy().astype(str)
    out["visible"] = j["visible"].fill_null(True).to_numpy().astype(bool)
    return out


def _error(j: dict[str, np.ndarray]) -> np.ndarray:
    """Centre error per truth frame (NaN where either side has no position)."""
    return np.hypot(j["est_x"] - j["x"], j["est_y"] - j["y"])


def _honesty(visible: np.ndarray, measured: np.ndarray, predicted: np.ndarray, wrong: np.ndarray,
             rel: Reliability) -> dict[str, float | int]:
    """What boxes and points share: how often ``measured`` / ``predicted`` rows are wrong, calibration
    and coverage, with their counts."""
    n_visible = int(visible.sum())
    return dict(
        wrong_rate=_rate(int(np.sum(measured & wrong)), int(measured.sum())),
        predicted_wrong_rate=_rate(int(np.sum(predicted & wrong)), int(predicted.sum())),
        ece=rel.ece, coverage=_rate(int(np.sum(visible & measured)), n_visible),
        n_truth_frames=int(visible.size), n_visible=n_visible, n_measured=int(measured.sum()),
        n_wrong=int(np.sum(measured & wrong)), n_predicted=int(predicted.sum()),
        n_predicted_wrong=int(np.sum(predicted & wrong)), n_calibrated=int(rel.bin_count.sum()))


def truth_has_boxes(truth: pl.DataFrame) -> bool:
    """Whether a truth gives boxes (score with :func:`box_scores`) rather than points (:func:`point_scores`):
    some visible row has a box of positive size."""
    if "w" not in truth.columns or "h" not in truth.columns:
        return False
    return bool(truth.filter(pl.col("visible").fill_null(True) & (pl.col("w") > 0) & (pl.col("h") > 0)).height)


def box_scores(track: pl.DataFrame, truth: pl.DataFrame) -> BoxScores:
    """Score one track (trajectory rows: frame, x, y (centre), w, h, status, confidence) against one
    object's box truth (rows of :func:`trackreplay.replay.log.groundtruth.read_groundtruth`)."""
    j = _joined(track, truth)
    has_box = np.isfinite(j["x"]) & np.isfinite(j["y"]) & (j["w"] > 0) & (j["h"] > 0)
    if np.any(j["visible"] & np.isfinite(j["x"]) & ~has_box):
        raise TrackreplayError("the truth marks points, not boxes: score it with point_scores")
    visible = j["visible"] & has_box
    est_box = np.isfinite(j["est_x"]) & np.isfinite(j["est_y"]) & np.isfinite(j["est_w"]) & np.isfinite(j["est_h"])
    gt_xywh = np.column_stack([j[c] for c in ("x", "y", "w", "h")])
    est_xywh = np.column_stack([j[f"est_{c}"] for c in ("x", "y", "w", "h")])
    overlap = np.zeros(visible.size)
    both = visible & est_box
    overlap[both] = iou(est_xywh[both], gt_xywh[both], centred=True)
    error = np.where(visible & np.isfinite(j["est_x"]), _error(j), np.inf)
    n_visible = int(visible.sum())
    ious, err_v = overlap[visible], error[visible]
    success = (ious[None, :] > IOU_THRESHOLDS[:, None]).mean(axis=1) if n_visible else np.full(IOU_THRESHOLDS.size, np.nan)
    precision = ((err_v[None, :] <= PRECISION_THRESHOLDS_PX[:, None]).mean(axis=1) if n_visible
                 else np.full(PRECISION_THRESHOLDS_PX.size, np.nan))
    positioned = np.isfinite(j["est_x"]) & np.isfinite(j["est_y"])
    measured = j["status"] == MEASURED
    predicted = (j["status"] == PREDICTED) & positioned
    wrong = ~visible | (overlap == 0.0)
    right = visible & (overlap >= RIGHT_IOU)
    calibrated = (measured | predicted) & positioned
    rel = reliability(j["est_confidence"][calibrated], right[calibrated])
    return BoxScores(
        success_auc=float(success.mean()), precision_20px=_rate(int(np.sum(err_v <= PRECISION_PX)), n_visible),
        mean_iou=float(ious.mean()) if n_visible else float("nan"),
        **_honesty(visible, measured, predicted, wrong, rel),
        success_curve=success, precision_curve=precision, ious=ious, reliability=rel)


def point_scores(track: pl.DataFrame, truth: pl.DataFrame) -> PointScores:
    """Score one track's centres against one object's point truth (or a box truth's centres)."""
    j = _joined(track, truth)
    visible = j["visible"] & np.isfinite(j["x"]) & np.isfinite(j["y"])
    positioned = np.isfinite(j["est_x"]) & np.isfinite(j["est_y"])
    measured = j["status"] == MEASURED
    predicted = (j["status"] == PREDICTED) & positioned
    error = np.where(visible & positioned, _error(j), np.inf)
    found = visible & measured & positioned
    errors = error[found]
    n_visible = int(visible.sum())
    wrong = ~visible | (error > POINT_WRONG_PX)
    right = visible & (error <= POINT_RIGHT_PX)
    calibrated = (measured | predicted) & positioned
    rel = reliability(j["est_confidence"][calibrated], right[calibrated])
    near5, near10 = (_rate(int(np.sum(errors <= r)), n_visible) for r in POINT_NEAR_PX)
    return PointScores(
        within_5px=near5, within_10px=near10,
        median_error_px=float(np.median(errors)) if errors.size else float("nan"),
        **_honesty(visible, measured, predicted, wrong, rel),
        errors=errors, reliability=rel)
