"""§3.3 points to trackers: the Mahalanobis gate (eq. 8) and, where several trackers gate a point,
the arg max of ``m_p · m_v`` (eqs. 9–11; the paper prints ``m_v · m_v``: corrected in docs/papers.md §4).

``m_p = k_p N(y_i; ξ_j, P_ξj)``, ``m_v = k_v N(λ_i; v_j, P_vj)`` with ``P_ξj`` the group's position
extent plus its EKF position covariance and ``P_vj`` its velocity spread plus its EKF velocity
covariance. Vectorised over points × trackers.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from trackreplay.trackers.filters.gating import gaussian_density, mahalanobis_sq


@dataclass(frozen=True, eq=False)
class Association:
    labels: np.ndarray  # (M,) tracker index per point, -1 none
    d2: np.ndarray  # (M, J) squared Mahalanobis distances (eq. 8)
    score: np.ndarray  # (M, J) m_p · m_v (0 outside the gate)
    contested: np.ndarray  # (M,) bool: gated by two or more trackers


def associate(points: np.ndarray, velocities: np.ndarray, centres: np.ndarray, gate_covs: np.ndarray,
              velocity_means: np.ndarray, velocity_covs: np.ndarray, gamma: float,
              k_p: float = 1.0, k_v: float = 1.0) -> Association:
    """Assign each point (M, 3) with its velocity (M, 3) to one of J trackers (or none)."""
    M, J = len(points), len(centres)
    if M == 0 or J == 0:
        return Association(np.full(M, -1, np.int64), np.zeros((M, J)), np.zeros((M, J)), np.zeros(M, bool))
    d2 = np.stack([mahalanobis_sq(points, centres[j], gate_covs[j]) for j in range(J)], axis=1)
    gated = d2 < gamma
    m_p = np.stack([k_p * gaussian_density(points, centres[j], gate_covs[j]) for j in range(J)], axis=1)
    m_v = np.stack([k_v * gaussian_density(velocities, velocity_means[j], velocity_covs[j]) for j in range(J)], axis=1)
    score = np.where(gated, m_p * m_v, 0.0)
    labels = np.where(gated.any(axis=1), np.argmax(np.where(gated, score, -1.0), axis=1), -1)
    return Association(labels.astype(np.int64), d2, score, gated.sum(axis=1) >= 2)
