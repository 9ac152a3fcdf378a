"""Moment-matched merging of Gaussians (group tracker, seed 003, eqs. 14–15)."""

from __future__ import annotations

import numpy as np


def merge_gaussians(counts: np.ndarray, means: np.ndarray, covs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One Gaussian with the mean and covariance of the mixture.

    ``N̄_i = N_i / Σ N_i``; ``x_m = Σ N̄_i x_i`` (eq. 14);
    ``Σ_m = Σ N̄_i (Σ_i + (x_i − x_m)(x_i − x_m)ᵀ)`` (eq. 15). ``counts`` (K,) are the members
    behind each Gaussian (or any positive weights), ``means`` (K, D), ``covs`` (K, D, D).
    """
    counts = np.asarray(counts, dtype=np.float64)
    means = np.asarray(means, dtype=np.float64)
    covs = np.asarray(covs, dtype=np.float64)
    if counts.ndim != 1 or len(counts) == 0 or np.any(counts < 0) or counts.sum() <= 0:
        raise ValueError("merge_gaussians needs at least one non-negative count with a positive sum")
    w = counts / counts.sum()
    mean = w @ means
    d = means - mean
    cov = np.einsum("k,kij->ij", w, covs + d[:, :, None] * d[:, None, :])
    return mean, 0.5 * (cov + cov.T)
