"""The search region ``I_s`` inside the full frame ``I_t`` (seed 000, §2.1 and §2.2, last paragraph).

All extraction runs inside ``I_s``: the HD frame is too costly to scan. It is centred on the
particles' predicted mean; "the horizontal and vertical variance of the particles set the search
region's size and aspect": per axis ``size = 2 (k σ + D)`` for the samples' standard deviation
``σ``, ``k = sigmas`` and the ball diameter ``D`` (so it grows while the ball is missed, §2.3),
clamped to ``[min_px, max_px]`` (scaled with the frame) and to the frame, and kept inside it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from trackreplay.trackers.golf.config import SearchConfig


@dataclass(frozen=True, eq=False)
class SearchRegion:
    """The search stage's intermediates."""

    box: np.ndarray  # (4,) x0, y0, w, h of I_s in frame pixels (integers)
    centre: np.ndarray  # (2,) the predicted mean it is centred on
    spread: np.ndarray  # (2,) the samples' standard deviation in x and y

    @classmethod
    def empty(cls) -> SearchRegion:
        return cls(np.zeros(4), np.full(2, np.nan), np.full(2, np.nan))


def search_region(centre: np.ndarray, spread: np.ndarray, diameter: float, width: int, height: int, scale: float,
                  cfg: SearchConfig) -> SearchRegion:
    """``I_s`` around ``centre`` from the particle ``spread`` and the ball ``diameter`` (px)."""
    # np.clip / np.minimum / np.floor / np.ceil on two numbers, as Python floats (the same values, NaN included)
    lo, hi = cfg.min_px * scale, cfg.max_px * scale
    sx, sy = (2.0 * (cfg.sigmas * spread + diameter)).tolist()
    sx, sy = _clip(_clip(sx, lo, hi), -math.inf, width), _clip(_clip(sy, lo, hi), -math.inf, height)
    cx, cy = float(centre[0]), float(centre[1])
    x0, y0 = _clip(cx - sx / 2, 0, width - sx), _clip(cy - sy / 2, 0, height - sy)
    box = np.array([_floor(x0), _floor(y0), _ceil(sx), _ceil(sy)])
    return SearchRegion(box, np.asarray(centre, dtype=np.float64), spread)


def reaching(region: SearchRegion, point: np.ndarray, reach: float, width: int, height: int) -> SearchRegion:
    """``region`` grown (centre and spread kept) to also hold the square of half-side ``reach``
    around ``point``, within the frame: where a tentative track (:mod:`.validate`) looks next."""
    x0, y0, w, h = region.box.tolist()
    if not all(math.isfinite(v) for v in (x0, y0, w, h, *point.tolist(), reach)):
        return region
    px, py = float(point[0]), float(point[1])
    lo_x, lo_y = max(0.0, min(x0, _floor(px - reach))), max(0.0, min(y0, _floor(py - reach)))
    hi_x, hi_y = min(float(width), max(x0 + w, _ceil(px + reach))), min(float(height), max(y0 + h, _ceil(py + reach)))
    if lo_x == x0 and lo_y == y0 and hi_x == x0 + w and hi_y == y0 + h:
        return region
    return SearchRegion(np.array([lo_x, lo_y, hi_x - lo_x, hi_y - lo_y]), region.centre, region.spread)


def _clip(v: float, lo: float, hi: float) -> float:
    """``np.clip`` of one number: ``min(max(v, lo), hi)``, NaN kept."""
    return v if v != v else min(max(v, lo), hi)


def _floor(v: float) -> float:
    return float(math.floor(v)) if math.isfinite(v) else v


def _ceil(v: float) -> float:
    return float(math.ceil(v)) if math.isfinite(v) else v


def filling_sigma(size_px: float, cfg: SearchConfig) -> float:
    """The particle standard deviation whose search region is ``size_px`` wide (ball aside)."""
    return size_px / (2.0 * cfg.sigmas)
