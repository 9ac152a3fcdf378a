"""§3.5 merging (eq. 13): trackers whose position and velocity regions overlap become one (eqs. 14–15).

Position regions: the centres' squared Mahalanobis distance under the sum of the two extents
(``Σ_i + Σ_j``) is below ``gamma_position``. Velocity regions: the velocities' under the sum of
the EKF velocity covariances (optionally plus each group's point-velocity spread over its member
count, ``MergeConfig.velocity_spread_in_gate``) is below ``gamma_velocity``. Both must hold, so groups that
pass close but move differently do not merge. The relation's connected sets are merged.
"""

from __future__ import annotations

import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import connected_components


def overlap_pairs(centres: np.ndarray, extents: np.ndarray, velocities: np.ndarray, velocity_covs: np.ndarray,
                  gamma_position: float, gamma_velocity: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(J, J) bool overlap (eq. 13) and the position and velocity squared distances (J, J)."""
    J = len(centres)
    dp = centres[:, None, :] - centres[None, :, :]
    dv = velocities[:, None, :] - velocities[None, :, :]
    Sp = extents[:, None] + extents[None, :]
    Sv = velocity_covs[:, None] + velocity_covs[None, :]
    d2p = np.einsum("ijk,ijk->ij", dp, np.linalg.solve(Sp, dp[..., None])[..., 0]) if J else np.zeros((0, 0))
    d2v = np.einsum("ijk,ijk->ij", dv, np.linalg.solve(Sv, dv[..., None])[..., 0]) if J else np.zeros((0, 0))
    both = (d2p < gamma_position) & (d2v < gamma_velocity)
    np.fill_diagonal(both, False)
    return both, d2p, d2v


def merge_sets(overlap: np.ndarray) -> list[np.ndarray]:
    """Connected sets of two or more trackers (indices ascending, sets by their first index)."""
    if len(overlap) == 0:
        return []
    _, labels = connected_components(csr_matrix(overlap), directed=False)
    sets = [np.flatnonzero(labels == lab) for lab in np.unique(labels)]
    return sorted([s for s in sets if len(s) >= 2], key=lambda s: int(s[0]))
