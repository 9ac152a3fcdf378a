"""Everything one colour-PF step computed (hashed into the replay digest, drawn by the Rerun view)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from trackreplay.trackers.base import NOT_HASHED
from trackreplay.trackers.colorpf.calibration import RowEvidence

NAN4 = np.full(4, np.nan)


@dataclass(frozen=True, eq=False)
class ColorPfIntermediates:
    """``mode`` is "track" or "idle" (before the mark, or no mark: every array empty)."""

    mode: str
    particles: np.ndarray  # (N, 4) x, y, w, h after eq. (2)
    weights: np.ndarray  # (N,) normalised eq. (3)
    similarity: np.ndarray  # (N,) S of eq. (4)
    likelihood: np.ndarray  # (N,) L of eq. (5)
    estimate: np.ndarray  # (4,) eq. (6)
    reference: np.ndarray  # H_ref, the model's display shape ((T, T) for "hs")
    current: np.ndarray  # the estimate box's histogram, same shape
    estimate_similarity: float  # S of the estimate box: the confidence
    area: float  # S' of eq. (9) at the estimate's foot, without noise (NaN: not geometry)
    distance: float  # Z: camera to the estimate's foot point, m (NaN: no ground plane)
    aspect_measured: float  # R_t of eq. (11) (NaN: too few particles above l)
    aspect: float  # R used for the next frame
    aspect_kept: bool  # R_t rejected: R_{t-1} kept
    reference_kind: str  # "mixed" | "target" | "box"
    background: str  # "before" | "early" | "none"
    mask: np.ndarray  # the marked box's foreground (bool) on the frame the reference was built; else (0, 0)
    mask_offset: np.ndarray  # (2,) its top-left pixel
    status: str  # "measured" | "predicted" | "lost" | ""
    notice: str = ""
    # what the calibration reads of the row (None: lost, idle); read-only, not hashed (docs/colorpf_calibration.py
    # collects it to refit calibration.COEFFICIENTS)
    evidence: RowEvidence | None = field(default=None, repr=False, metadata=NOT_HASHED)

    @classmethod
    def idle(cls, notice: str = "") -> ColorPfIntermediates:
        empty = np.zeros((0, 4))
        return cls("idle", empty, np.zeros(0), np.zeros(0), np.zeros(0), NAN4.copy(), np.zeros((0, 0)),
                   np.zeros((0, 0)), float("nan"), float("nan"), float("nan"), float("nan"), float("nan"), False,
                   "", "", np.zeros((0, 0), bool), np.zeros(2, np.int64), "", notice)
