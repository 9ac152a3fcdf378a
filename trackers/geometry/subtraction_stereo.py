"""Subtraction stereo (seed 003 §2): SGBM run only on crops around the foreground.

Background subtraction gives a foreground mask of the left view; each 8-connected foreground
region's box (found on a grid of 4x4-px cells: connected components at full VGA cost ~2 ms, more
than SGBM on a small crop), grown by ``margin`` px and widened to the left by the disparity range (a
left pixel at column ``c`` is matched with right columns ``c − d``, and SGBM leaves the first
``num_disparities`` columns of a crop unmatched), is cut from both images at the same place and
matched with ``cv2.StereoSGBM``. The crop's disparity is kept on the region's foreground pixels
only. Crops that overlap are joined when the joined box is no larger than the two; otherwise both
are matched and a pixel they share keeps the value of the crop it lies deeper inside. With ``band_px > 0`` the
crops hug the silhouette instead: one per run of foreground columns in each band of rows, with
``margin`` rows of context above and below that are matched but not kept.

SGBM's cost follows the pixels it is run on (~45-68 ns per pixel at 16 disparities, crops 32 to
640 px wide; a call costs ~0.1 ms on its own), so the gain is bounded by frame pixels / (foreground
pixels + the disparity range's columns left of each row's foreground run): 4.2x at 20 %
foreground for people-shaped regions at 16 disparities (benchmarks/results/subtraction_stereo.json).

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

from trackreplay.trackers.appearance.color import to_grey


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


def _to_float(raw: np.ndarray, cfg: SgbmConfig) -> np.ndarray:
    disp = raw.astype(np.float32) / 16.0
    disp[raw < (cfg.min_disparity * 16)] = np.nan  # SGBM marks "no match" with (min_disparity - 1) * 16
    return disp


def full_disparity(left: np.ndarray, right: np.ndarray, cfg: SgbmConfig, matcher: cv2.StereoSGBM | None = None) -> np.ndarray:
    """SGBM over the whole frame (the reference subtraction stereo is compared with)."""
    matcher = matcher or make_matcher(cfg)
    return _to_float(matcher.compute(to_grey(left), to_grey(right)), cfg)


CELL = 4  # px: crops are found on a grid of CELL x CELL cells (connected components on VGA took ~2 ms, ~10x SGBM's per-call cost)


def _cells(mask: np.ndarray, min_area: int) -> np.ndarray:
    """(ceil(H/CELL), ceil(W/CELL)) bool: cells holding foreground of an 8-connected cell region
    with at least ``min_area`` foreground pixels (isolated specks dropped)."""
    h, w = mask.shape
    H, W = -(-h // CELL), -(-w // CELL)
    m8 = mask.astype(np.uint8) * np.uint8(255)
    if (H * CELL, W * CELL) != (h, w):
        m8 = cv2.copyMakeBorder(m8, 0, H * CELL - h, 0, W * CELL - w, cv2.BORDER_CONSTANT, value=0)
    # INTER_AREA at an integer factor is the cell mean, rounded: 255 k / 16 for k foreground pixels
    counts = np.rint(cv2.resize(m8, (W, H), interpolation=cv2.INTER_AREA).astype(np.float64) * (CELL * CELL) / 255.0)
    occ = (counts > 0).astype(np.uint8)
    n, lab = cv2.connectedComponents(occ, connectivity=8)
    area = np.bincount(lab.ravel(), weights=counts.ravel(), minlength=n)
    keep = area >= min_area
    keep[0] = False
    return keep[lab]


def _area(b: np.ndarray) -> np.ndarray:
    return (b[..., 2] - b[..., 0]) * (b[..., 3] - b[..., 1])


def _join(boxes: np.ndarray) -> np.ndarray:
    """Join overlapping ``x0 y0 x1 y1`` boxes while the joined box is no larger than the two (then
    no pixel is matched twice for nothing); boxes whose union would be larger stay apart and their
    overlap is matched twice. Few boxes: the quadratic pass is cheap."""
    merged = True
    while merged and len(boxes) > 1:
        merged = False
        lo = np.maximum(boxes[:, None, :2], boxes[None, :, :2])
        hi = np.minimum(boxes[:, None, 2:], boxes[None, :, 2:])
        union = np.concatenate([np.minimum(boxes[:, None, :2], boxes[None, :, :2]),
                                np.maximum(boxes[:, None, 2:], boxes[None, :, 2:])], axis=2)
        area = _area(boxes)
        cheaper = (hi > lo).all(axis=2) & (_area(union) <= area[:, None] + area[None, :])
        np.fill_diagonal(cheaper, False)
        if cheaper.any():
            i, j = (int(v) for v in np.argwhere(cheaper)[0])
            boxes = np.vstack([np.delete(boxes, [i, j], axis=0), union[i, j][None]])
            merged = True
    return boxes


def foreground_crops(mask: np.ndarray, cfg: SgbmConfig, margin: int = 8, min_area: int = 20, band_px: int = 0) -> np.ndarray:
    """(K, 6) int ``x0 y0 x1 y1 c0 c1``: crops ``[y0, y1) x [x0, x1)`` (half-open) to match, whose
    rows ``[c0, c1)`` are kept (the rest is context above and below).

    ``band_px == 0``: each foreground region's box (on the 4-px cell grid) grown by ``margin`` and by
    ``min_disparity + num_disparities`` to the left, overlapping crops joined where that costs no
    more pixels; every row kept.
    ``band_px > 0``: crops that hug the silhouette: per band of ``band_px`` rows, one crop per run
    of foreground columns (grown the same way), ``margin`` rows of context above and below; a
    crop is joined with the one below it when the joined box is no larger than the two."""
    h, w = mask.shape
    reach = cfg.min_disparity + cfg.num_disparities
    occ = _cells(mask, min_area)
    if not occ.any():
        return np.zeros((0, 6), np.int64)
    if band_px <= 0:
        n, _, stats, _ = cv2.connectedComponentsWithStats(occ.astype(np.uint8), connectivity=8)
        s = stats[1:].astype(np.int64) * CELL
        boxes = np.stack([s[:, 0] - margin - reach, s[:, 1] - margin, s[:, 0] + s[:, 2] + margin,
                          s[:, 1] + s[:, 3] + margin], axis=1)
        boxes = _join(np.clip(boxes, 0, [w, h, w, h]))
        boxes = boxes[np.lexsort((boxes[:, 0], boxes[:, 1]))]
        return np.concatenate([boxes, boxes[:, [1, 3]]], axis=1)
    H, W = occ.shape
    bc = max(band_px // CELL, 1)
    nb = -(-H // bc)
    grid = np.zeros((nb * bc, W), bool)
    grid[:H] = occ
    cols = grid.reshape(nb, bc, W).any(axis=1)  # (bands, cell columns) holding foreground
    left, right = -(-(margin + reach) // CELL), -(-margin // CELL)
    cs = np.concatenate([np.zeros((nb, 1), np.int32), np.cumsum(cols, axis=1, dtype=np.int32)], axis=1)
    cover = (cs[:, np.clip(np.arange(W) + left + 1, 0, W)] - cs[:, np.clip(np.arange(W) - right, 0, W)]) > 0
    edges = np.diff(np.pad(cover.astype(np.int8), ((0, 0), (1, 1))), axis=1)
    band, start = np.nonzero(edges == 1)
    end = np.nonzero(edges == -1)[1]
    crops: list[list[int]] = []
    for b, c0, c1 in zip(band.tolist(), start.tolist(), end.tolist()):  # runs (tens), not pixels
        rows = np.flatnonzero(grid[b * bc:(b + 1) * bc, c0:c1].any(axis=1))
        if len(rows) == 0:
            continue
        k0, k1 = (b * bc + int(rows[0])) * CELL, min((b * bc + int(rows[-1]) + 1) * CELL, h)
        # a run reaches `left` cells before its first foreground cell and `right` after its last
        # (unless cut at the image's edge), margin + reach and margin rounded up to cells: the
        # crop is grown by the exact pixels, as the box crops are
        x0 = (c0 + left) * CELL - margin - reach if c0 > 0 else 0
        x1 = min((c1 - right) * CELL + margin, w) if c1 < W else w
        box = [x0, max(k0 - margin, 0), x1, min(k1 + margin, h), k0, k1]
        for o in crops[::-1]:  # join with a crop of the band above whose kept rows end where these start
            if o[5] == k0 and o[0] < x1 and x0 < o[2]:
                jx0, jx1 = min(o[0], x0), max(o[2], x1)
                if (jx1 - jx0) * (box[3] - o[1]) <= (o[2] - o[0]) * (o[3] - o[1]) + (x1 - x0) * (box[3] - box[1]):
                    o[:] = [jx0, o[1], jx1, box[3], o[4], k1]
                    box = None
                break
        if box is not None:
            crops.append(box)
    return np.array(crops, np.int64).reshape(-1, 6)


@dataclass(frozen=True, eq=False)
class SubtractionStereo:
    disparity: np.ndarray  # (H, W) float32 px on the left foreground, NaN elsewhere
    crops: np.ndarray  # (K, 4) x0 y0 x1 y1 matched crops
    matched_px: int  # pixels SGBM was run on (sum of crop areas)
    kept_rows: np.ndarray | None = None  # (K, 2) c0 c1: the rows of each crop whose disparity is kept


def subtraction_stereo(left: np.ndarray, right: np.ndarray, left_mask: np.ndarray, cfg: SgbmConfig, *,
                       right_mask: np.ndarray | None = None, margin: int = 8, right_tolerance_px: int = 2,
                       matcher: cv2.StereoSGBM | None = None, band_px: int = 0) -> SubtractionStereo:
    """Disparity of the left foreground from SGBM on foreground crops only (see module docstring)."""
    matcher = matcher or make_matcher(cfg)
    gl, gr = to_grey(left), to_grey(right)
    disparity = np.full(gl.shape, np.nan, np.float32)
    crops = foreground_crops(left_mask, cfg, margin, band_px=band_px)
    depth = np.full(gl.shape, -1, np.int64)
    reach = cfg.min_disparity + cfg.num_disparities
    matched = 0
    for x0, y0, x1, y1, c0, c1 in crops.tolist():
        if x1 - x0 <= reach or y1 - y0 < cfg.block_size:
            continue
        raw = matcher.compute(np.ascontiguousarray(gl[y0:y1, x0:x1]), np.ascontiguousarray(gr[y0:y1, x0:x1]))
        d = _to_float(raw[c0 - y0:c1 - y0], cfg)
        if x0 > 0:  # the first `reach` columns of a crop that does not start at the image edge have no match
            d[:, :reach] = np.nan
        # a pixel two crops hold keeps the value of the crop where it lies deeper inside (more
        # context for SGBM's paths): depth = distance to the crop's nearest matched border
        left = x0 + (reach if x0 > 0 else 0)
        cols = np.minimum(np.arange(x0, x1) - left, x1 - 1 - np.arange(x0, x1))
        rows = np.minimum(np.arange(c0, c1) - y0, y1 - 1 - np.arange(c0, c1))
        deep = np.minimum.outer(rows, cols)
        better = np.isfinite(d) & (deep > depth[c0:c1, x0:x1])
        np.copyto(disparity[c0:c1, x0:x1], d, where=better)
        np.copyto(depth[c0:c1, x0:x1], deep, where=better)
        matched += (x1 - x0) * (y1 - y0)
    disparity[~left_mask.astype(bool)] = np.nan
    if right_mask is not None:
        disparity = on_right_foreground(disparity, right_mask, right_tolerance_px)
    return SubtractionStereo(disparity, crops[:, :4], matched, crops[:, 4:])


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
