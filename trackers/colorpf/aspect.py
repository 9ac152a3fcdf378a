"""The box's aspect ratio from the likelihood distribution, §4.2 eqs. (10)-(12).

Particles near the estimate (eq. 10, ``d_i`` within ``near * sqrt(S')``) whose likelihood exceeds
``l`` span the target: ``R_t = (y_max - y_min) / (x_max - x_min)`` (eq. 11). With few particles the
distribution is ragged, so an ``R_t`` that jumps from ``R_{t-1}`` (by more than ``max_jump`` either
way) is taken as wrong and ``R_{t-1}`` kept. By default ``l`` is read relative to the best
particle (``L > L_max / l``; ``aspect.relative``, see the config for why). The box then follows from the area: eq. (12) with
the correction of docs/papers.md §3, ``w = sqrt(S'/R)``, ``h = R w`` (the paper prints ``h = sqrt(S'/w)``, which does
not give ``w h = S'``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from trackreplay.trackers.colorpf.config import AspectConfig


def likelihood_extent_ratio(xy: np.ndarray, likelihood: np.ndarray, estimate: np.ndarray, radius: float,
                            threshold: float, min_particles: int = 3) -> float:
    """Eqs. (10)-(11): ``R_t`` from the particles within ``radius`` of ``estimate`` whose likelihood
    exceeds ``threshold``; NaN when fewer than ``min_particles`` qualify or they span no width/height."""
    xy = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    d = np.hypot(xy[:, 0] - estimate[0], xy[:, 1] - estimate[1])  # eq. (10)
    chosen = xy[(d <= radius) & (np.asarray(likelihood) > threshold)]
    if len(chosen) < min_particles:
        return float("nan")
    span = chosen.max(axis=0) - chosen.min(axis=0)
    if span[0] <= 0 or span[1] <= 0:
        return float("nan")
    return float(span[1] / span[0])  # eq. (11)


def box_from_area(area: np.ndarray | float, ratio: float) -> tuple[np.ndarray, np.ndarray]:
    """Eq. (12), fixed: ``w = sqrt(S'/R)``, ``h = R w``."""
    w = np.sqrt(np.asarray(area, dtype=np.float64) / ratio)
    return w, ratio * w


@dataclass(frozen=True)
class AspectUpdate:
    measured: float  # R_t of eq. (11) (NaN: not enough particles)
    ratio: float  # the R used from now on
    kept: bool  # R_t rejected (jump or undefined): R_{t-1} kept


class AspectEstimate:
    """``R`` carried from frame to frame with the jump rejection."""

    def __init__(self, cfg: AspectConfig, ratio0: float) -> None:
        self.cfg = cfg
        self.ratio = float(ratio0)

    def update(self, xy: np.ndarray, likelihood: np.ndarray, estimate: np.ndarray, area: float) -> AspectUpdate:
        cfg = self.cfg
        likelihood = np.asarray(likelihood, dtype=np.float64)
        threshold = cfg.threshold
        if cfg.relative and likelihood.size:
            threshold = float(likelihood.max()) / cfg.threshold
        r_t = likelihood_extent_ratio(xy, likelihood, estimate, cfg.near * np.sqrt(max(area, 0.0)),
                                      threshold, cfg.min_particles)
        jump = not np.isfinite(r_t) or not 1.0 / cfg.max_jump <= r_t / self.ratio <= cfg.max_jump
        if not jump:
            self.ratio = r_t
        return AspectUpdate(r_t, self.ratio, jump)
