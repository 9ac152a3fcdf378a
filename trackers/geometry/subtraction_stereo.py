"""Subtraction stereo (seed 003 §2): SGBM run only on crops around the foreground.

Background subtraction gives a foreground mask of the left view; each 8-connected foreground
region's box, grown by ``margin`` px and widened to the left by the disparity range (a left pixel
at column ``c`` is matched with right columns ``c − d``, and SGBM leaves the first
``num_disparities`` columns of a crop unmatched), is cut from both images at the same place and
matched with ``cv2.StereoSGBM``. The crop's disparity is kept on the region's foreground pixels
only. Crops that overlap are joined first, so no pixel is matched twice.

SGBM aggregates costs along paths through the whole image, so a crop can differ from the
full-frame result near its border; ``margin`` trades speed for agreement (measured in
``benchmarks/bench_subtraction_stereo.py``). With ``right_mask`` the disparity is also required to
land on the right view's foreground (dilated by ``right_tolerance_px``): the paper's "matching
inside the foreground of both views".

Disparities are float32 px, NaN where there is none (background, unmatched, rejected).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np


@dataclass(frozen=True)
class SgbmConfig:
    """``cv2.StereoSGBM_create`` parameters (OpenCV's recommended P1 = 8·c·b², P2 = 32·c·b², c = 1)."""

    num_disparities: int = 16  # multiple of 16; the paper's rig (f 513 px, b 0.12 m) sees d <= 12 px beyond 5 m
    min_disparity: int = 0
    block_size: int = 5
    uniqueness_ratio: int = 10
    speckle_window: int = 0
    speckle_range: int = 2
    disp12_max_diff: int = 1
    mode: str = "sgbm"  # "sgbm" | "3way" | "hh"

    def __post_init__(self) -> None:
        if self.num_disparities <= 0 or self.num_disparities % 16:
            raise ValueError("num_disparities must be a positive multiple of 16")
        if self.block_size < 1 or self.block_size % 2 == 0:
            raise ValueError("block_size must be odd and positive")
        if self.mode not in _MODES:
            raise ValueError(f"mode must be one of {sorted(_MODES)}")


_MODES = {"sgbm": cv2.STEREO_SGBM_MODE_SGBM, "3way": cv2.STEREO_SGBM_MODE_SGBM_3WAY, "hh": cv2.STEREO_SGBM_MODE_HH}


def make_matcher(cfg: SgbmConfig) -> cv2.StereoSGBM:
    b = cfg.block_size
    return cv2.StereoSGBM_create(
        minDisparity=cfg.min_disparity, numDisparities=cfg.num_disparities, blockSize=b, P1=8 * b * b, P2=32 * b * b,
        disp12MaxDiff=cfg.disp12_max_diff, uniquenessRatio=cfg.uniqueness_ratio, speckleWindowSize=cfg.speckle_window,
        speckleRange=cfg.speckle_range, mode=_MODES[cfg.mode])


def _grey(image: np.ndarray) -> np.ndarray:
    return image if image.ndim == 2 else cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)


def _to_float(raw: np.ndarray, cfg: SgbmConfig) -> np.ndarray:
    disp = raw.astype(np.float32) / 16.0
    disp[raw < (cfg.min_disparity * 16)] = np.nan  # SGBM marks "no match" with (min_disparity - 1) * 16
    return disp


def full_disparity(left: np.ndarray, right: np.ndarray, cfg: SgbmConfig, matcher: cv2.StereoSGBM | None = None) -> np.ndarray:
    """SGBM over the whole frame (the reference subtraction stereo is compared with)."""
    matcher = matcher or make_matcher(cfg)
    return _to_float(matcher.compute(_grey(left), _grey(right)), cfg)


def foreground_crops(mask: np.ndarray, cfg: SgbmConfig, margin: int = 8, min_area: int = 20) -> np.ndarray:
    """(K, 4) int ``x0 y0 x1 y1`` (half-open) crops to match: each foreground region's box grown by
    ``margin`` and by ``min_disparity + num_disparities`` to the left, overlapping crops joined."""
    h, w = mask.shape
    n, _, stats, _ = cv2.connectedComponentsWithStats(mask.astype(np.uint8), connectivity=8)
    keep = stats[1:, cv2.CC_STAT_AREA] >= min_area
    s = stats[1:][keep]
    if len(s) == 0:
        return np.zeros((0, 4), np.int64)
    reach = cfg.min_disparity + cfg.num_disparities
    boxes = np.stack([s[:, 0] - margin - reach, s[:, 1] - margin,
                      s[:, 0] + s[:, 2] + margin, s[:, 1] + s[:, 3] + margin], axis=1).astype(np.int64)
    boxes = np.clip(boxes, 0, [w, h, w, h])
    # join overlapping boxes until none overlap (few boxes: the quadratic pass is cheap)
    merged = True
    while merged and len(boxes) > 1:
        merged = False
        lo = np.maximum(boxes[:, None, :2], boxes[None, :, :2])
        hi = np.minimum(boxes[:, None, 2:], boxes[None, :, 2:])
        overlap = (hi > lo).all(axis=2)
        np.fill_diagonal(overlap, False)
        if overlap.any():
            i, j = (int(v) for v in np.argwhere(overlap)[0])
            joined = np.concatenate([np.minimum(boxes[i, :2], boxes[j, :2]), np.maximum(boxes[i, 2:], boxes[j, 2:])])
            boxes = np.vstack([np.delete(boxes, [i, j], axis=0), joined[None]])
            merged = True
    return boxes[np.lexsort((boxes[:, 0], boxes[:, 1]))]


@dataclass(frozen=True, eq=False)
class SubtractionStereo:
    disparity: np.ndarray  # (H, W) float32 px on the left foreground, NaN elsewhere
    crops: np.ndarray  # (K, 4) x0 y0 x1 y1 matched crops
    matched_px: int  # pixels SGBM was run on (sum of crop areas)


def subtraction_stereo(left: np.ndarray, right: np.ndarray, left_mask: np.ndarray, cfg: SgbmConfig, *,
                       right_mask: np.ndarray | None = None, margin: int = 8, right_tolerance_px: int = 2,
                       matcher: cv2.StereoSGBM | None = None) -> SubtractionStereo:
    """Disparity of the left foreground from SGBM on foreground crops only (see module docstring)."""
    matcher = matcher or make_matcher(cfg)
    gl, gr = _grey(left), _grey(right)
    disparity = np.full(gl.shape, np.nan, np.float32)
    crops = foreground_crops(left_mask, cfg, margin)
    reach = cfg.min_disparity + cfg.num_disparities
    matched = 0
    for x0, y0, x1, y1 in crops.tolist():
        if x1 - x0 <= reach or y1 - y0 < cfg.block_size:
            continue
        raw = matcher.compute(np.ascontiguousarray(gl[y0:y1, x0:x1]), np.ascontiguousarray(gr[y0:y1, x0:x1]))
        d = _to_float(raw, cfg)
        if x0 > 0:  # the first `reach` columns of a crop that does not start at the image edge have no match
            d[:, :reach] = np.nan
        disparity[y0:y1, x0:x1] = np.where(np.isnan(disparity[y0:y1, x0:x1]), d, disparity[y0:y1, x0:x1])
        matched += (x1 - x0) * (y1 - y0)
    disparity[~left_mask.astype(bool)] = np.nan
    if right_mask is not None:
        disparity = on_right_foreground(disparity, right_mask, right_tolerance_px)
    return SubtractionStereo(disparity, crops, matched)


def on_right_foreground(disparity: np.ndarray, right_mask: np.ndarray, tolerance_px: int = 2) -> np.ndarray:
    """NaN where a left pixel's match ``(u − d, v)`` is not on the right foreground (dilated)."""
    grown = right_mask.astype(np.uint8)
    if tolerance_px > 0:
        grown = cv2.dilate(grown, np.ones((2 * tolerance_px + 1, 2 * tolerance_px + 1), np.uint8))
    v, u = np.nonzero(np.isfinite(disparity))
    ur = np.clip(np.round(u - disparity[v, u]).astype(np.int64), 0, disparity.shape[1] - 1)
    out = disparity.copy()
    bad = grown[v, ur] == 0
    out[v[bad], u[bad]] = np.nan
    return out


def disparity_agreement(a: np.ndarray, b: np.ndarray, where: np.ndarray, tolerance: float = 1.0) -> tuple[float, float, int]:
    """``(within tolerance, exactly equal, pixels compared)`` of two disparity images on ``where``
    where both have a value; fractions in [0, 1] (NaN when nothing is compared)."""
    both = where.astype(bool) & np.isfinite(a) & np.isfinite(b)
    n = int(both.sum())
    if n == 0:
        return float("nan"), float("nan"), 0
    diff = np.abs(a[both] - b[both])
    return float((diff <= tolerance).mean()), float((diff == 0).mean()), n
