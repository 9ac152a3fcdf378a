"""Innovation, NIS and Mahalanobis gating (the test a measurement passes before an update)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.stats import chi2


@dataclass(frozen=True)
class Innovation:
    y: np.ndarray  # z − h(x)
    S: np.ndarray  # H P Hᵀ + R

    @property
    def nis(self) -> float:
        """Normalised innovation squared ``yᵀ S⁻¹ y`` (χ² with dim z degrees of freedom)."""
        return float(self.y @ np.linalg.solve(self.S, self.y))


def innovation(P: np.ndarray, H: np.ndarray, R: np.ndarray, z: np.ndarray, hx: np.ndarray) -> Innovation:
    """The innovation of ``z`` against a prediction with covariance ``P``, as filterpy forms it."""
    S = H @ (P @ H.T) + R
    return Innovation(np.asarray(z, dtype=np.float64) - np.asarray(hx, dtype=np.float64), S)


def chi2_gate(dof: int, probability: float) -> float:
    """The NIS / squared-Mahalanobis threshold that keeps ``probability`` of true measurements."""
    return float(chi2.ppf(probability, dof))


def mahalanobis_sq(points: np.ndarray, mean: np.ndarray, cov: np.ndarray) -> np.ndarray:
    """``(y − μ)ᵀ Σ⁻¹ (y − μ)`` for every row of ``points`` (N, D)."""
    d = np.atleast_2d(np.asarray(points, dtype=np.float64)) - np.asarray(mean, dtype=np.float64)
    return np.einsum("nd,nd->n", d, np.linalg.solve(cov, d.T).T)


def gaussian_density(points: np.ndarray, mean: np.ndarray, cov: np.ndarray) -> np.ndarray:
    """``N(points; mean, cov)`` for every row of ``points``."""
    cov = np.asarray(cov, dtype=np.float64)
    dim = cov.shape[0]
    sign, logdet = np.linalg.slogdet(cov)
    if sign <= 0:
        raise np.linalg.LinAlgError("covariance is not positive definite")
    return np.exp(-0.5 * (mahalanobis_sq(points, mean, cov) + logdet + dim * np.log(2.0 * np.pi)))
