"""§3.4 initial grouping (eq. 12): unassigned points are related when their search regions overlap
(paper: within 1 m, Euclidean); connected sets with enough points start trackers."""

from __future__ import annotations

import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import connected_components


def initial_groups(points: np.ndarray, radius: float, min_points: int) -> list[np.ndarray]:
    """Index arrays of the connected sets (distance < ``radius``) of at least ``min_points``,
    ordered by their smallest index (deterministic)."""
    n = len(points)
    if n < min_points:
        return []
    d = np.linalg.norm(points[:, None, :] - points[None, :, :], axis=2)
    _, labels = connected_components(csr_matrix(d < radius), directed=False)
    out = []
    for lab in np.unique(labels):
        idx = np.flatnonzero(labels == lab)
        if len(idx) >= min_points:
            out.append(idx)
    return sorted(out, key=lambda idx: int(idx[0]))
