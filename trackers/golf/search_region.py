"""The search region ``I_s`` inside the full frame ``I_t`` (seed 000, §2.1 and §2.2, last paragraph).

All extraction runs inside ``I_s``: the HD frame is too costly to scan. It is centred on the
particles' predicted mean; "the horizontal and vertical variance of the particles set the search
region's size and aspect": per axis ``size = 2 (k σ + D)`` for the samples' standard deviation
``σ``, ``k = sigmas`` and the ball diameter ``D`` (so it grows while the ball is missed, §2.3),
clamped to ``[min_px, max_px]`` (scaled with the frame) and to the frame, and kept inside it.
"""

from __future__ import annotations

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
    size = np.clip(2.0 * (cfg.sigmas * spread + diameter), cfg.min_px * scale, cfg.max_px * scale)
    size = np.minimum(size, [width, height])
    x0 = float(np.clip(centre[0] - size[0] / 2, 0, width - size[0]))
    y0 = float(np.clip(centre[1] - size[1] / 2, 0, height - size[1]))
    box = np.array([np.floor(x0), np.floor(y0), np.ceil(size[0]), np.ceil(size[1])])
    return SearchRegion(box, np.asarray(centre, dtype=np.float64), spread)


def filling_sigma(size_px: float, cfg: SearchConfig) -> float:
    """The particle standard deviation whose search region is ``size_px`` wide (ball aside)."""
    return size_px / (2.0 * cfg.sigmas)
