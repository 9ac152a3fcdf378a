"""The colour likelihood of a box, eqs. (4)-(5): Swain's intersection with the reference, then exp(k S²).

Pixels become bin indices once per frame (only inside the union of the particles' boxes), then all
N box histograms are counted together (:func:`box_histograms`). ``"hs"`` bins H and S only (§3.1:
a uniform brightness change leaves them alone); ``"hsv"`` is Pérez et al.'s H-S + V histogram, the
paper's comparison in Table 1.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from trackreplay.trackers.appearance.color import HSV_RANGES, to_hsv
from trackreplay.trackers.appearance.histogram import box_histograms, hs_index, hs_v_index, intersection
from trackreplay.trackers.colorpf.config import LikelihoodConfig


@dataclass(frozen=True)
class ColourModel:
    """Which bins a BGR pixel falls in; ``n_bins`` in all."""

    config: LikelihoodConfig

    @property
    def shape(self) -> tuple[int, ...]:
        """The histogram's shape for display: (T, T) for "hs", (T*T + T,) for "hsv"."""
        t = self.config.bins
        return (t, t) if self.config.histogram == "hs" else (t * t + t,)

    @property
    def n_bins(self) -> int:
        return int(np.prod(self.shape))

    def index(self, bgr: np.ndarray) -> np.ndarray:
        """Bin index per pixel (int32, the image's shape without channels)."""
        cfg = self.config
        hsv = to_hsv(bgr)
        if cfg.histogram == "hs":
            return hs_index(hsv, (cfg.bins, cfg.bins), HSV_RANGES)[0]
        return hs_v_index(hsv, (cfg.bins,) * 3, HSV_RANGES, s_min=cfg.s_min, v_min=cfg.v_min)[0]

    def likelihood(self, similarity: np.ndarray) -> np.ndarray:
        """Eq. (5): ``L = exp(k S²)``."""
        return np.exp(self.config.k * np.asarray(similarity, dtype=np.float64) ** 2)

    def similarity_for(self, likelihood: float) -> float:
        """The intersection S at which eq. (5) reaches ``likelihood`` (e.g. l = 25 -> 0.40)."""
        return float(np.sqrt(np.log(likelihood) / self.config.k))


def box_corners(states: np.ndarray, width: int, height: int) -> np.ndarray:
    """(N, 4) integer ``x0, y0, x1, y1`` of the boxes ``(x, y, w, h)`` (centre, size), clipped to
    the image (a box wholly outside becomes empty). Pixel ``i`` covers ``[i - 0.5, i + 0.5)``."""
    s = np.asarray(states, dtype=np.float64).reshape(-1, 4)
    half = s[:, 2:4] / 2.0
    lo = np.floor(s[:, :2] - half + 0.5)
    hi = np.floor(s[:, :2] + half + 0.5)
    limit = np.array([width, height], dtype=np.float64)
    lo = np.clip(lo, 0, limit)
    hi = np.clip(np.maximum(hi, lo), 0, limit)
    return np.concatenate([lo, hi], axis=1).astype(np.int64)


@dataclass(frozen=True, eq=False)
class Measurement:
    """Every particle's histogram score this frame."""

    similarity: np.ndarray  # (N,) S, eq. (4)
    likelihood: np.ndarray  # (N,) L, eq. (5)
    pixels: np.ndarray  # (N,) pixels counted per box (0: the box left the image)


def measure(model: ColourModel, image: np.ndarray, states: np.ndarray, reference: np.ndarray) -> Measurement:
    """Eqs. (4)-(5) for every particle box ``(x, y, w, h)`` against the reference histogram."""
    height, width = image.shape[:2]
    corners = box_corners(states, width, height)
    x0, y0 = corners[:, :2].min(axis=0)
    x1, y1 = corners[:, 2:].max(axis=0)
    if x1 <= x0 or y1 <= y0:  # every box is outside the image
        n = len(corners)
        zero = np.zeros(n)
        return Measurement(zero, model.likelihood(zero), np.zeros(n, dtype=np.int64))
    index = model.index(image[y0:y1, x0:x1])  # only the union of the boxes is converted
    local = corners - np.array([x0, y0, x0, y0])
    hists, pixels = box_histograms(index, local, model.n_bins, max_pixels=model.config.max_pixels)
    similarity = np.asarray(intersection(hists, reference.reshape(-1)), dtype=np.float64)
    return Measurement(similarity, model.likelihood(similarity), pixels)


def box_histogram(model: ColourModel, image: np.ndarray, state: np.ndarray) -> np.ndarray:
    """The histogram of one box ``(x, y, w, h)`` (e.g. the estimate), flat, zeros if outside."""
    height, width = image.shape[:2]
    x0, y0, x1, y1 = box_corners(state, width, height)[0]
    if x1 <= x0 or y1 <= y0:
        return np.zeros(model.n_bins)
    index = model.index(image[y0:y1, x0:x1])
    return box_histograms(index, np.array([[0, 0, x1 - x0, y1 - y0]]), model.n_bins,
                          max_pixels=model.config.max_pixels)[0][0]
