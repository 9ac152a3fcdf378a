"""§3.5 merging (eq. 13): trackers whose position and velocity regions overlap become one (eqs. 14–15).

Position regions: the centres' squared Mahalanobis distance under the sum of the two extents
(``Σ_i + Σ_j``) is below ``gamma_position``. Velocity regions: the velocities' under the sum of
the EKF velocity covariances (optionally plus each group's point-velocity spread over its member
count, ``MergeConfig.velocity_spread_in_gate``) is below ``gamma_velocity``. Both must hold, so groups that
pass close but move differently do not merge. The relation's connected sets are merged.

With ``MergeConfig.measured_velocity`` (:func:`merge_overlap`) the velocities must agree also as
the groups' member points measure them: the mean of their own velocities λ_i (eq. 10's λ) across
the line of sight, where KLT measures them (along it a point's velocity is its disparity's slope,
and SGBM's disparity errors are shared by the points of one surface, so a mean over points does
not average them out). The EKF sees only the mean position of a group's points: while a fast
group passes behind a slower one, its visible part and the points it takes from the other near
the boundary make that mean move slower than the group, and its EKF velocity drifts towards the
other group's; the points' own velocities do not drift. Points gated by both groups (contested)
are left out of the means when a group has enough of its own: a point either group could own
says nothing about whether they move apart.
"""

from __future__ import annotations

from dataclasses import dataclass

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


def measured_velocities(velocities: np.ndarray, labels: np.ndarray, J: int, min_points: int,
                        contested: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Per group (``labels`` 0..J-1, -1 none) the mean of its points' own velocities (J, 3) and that
    mean's covariance ``cov(λ)/N`` (J, 3, 3), from the group's uncontested points (``contested``:
    gated by two or more groups) when it has ``min_points`` of them, else from all its points; NaN
    for a group with fewer than ``min_points`` (at least 2) points."""
    need = max(min_points, 2)
    means, covs = np.full((J, 3), np.nan), np.full((J, 3, 3), np.nan)
    for j in range(J):
        mine = labels == j
        if contested is not None and np.count_nonzero(mine & ~contested) >= need:
            mine = mine & ~contested
        lam = velocities[mine]
        if len(lam) >= need:
            d = lam - lam.mean(axis=0)
            means[j], covs[j] = lam.mean(axis=0), d.T @ d / ((len(lam) - 1) * len(lam))
    return means, covs


def across_sight(centre: np.ndarray, up: np.ndarray | None) -> np.ndarray:
    """Unit directions (k, 3), camera frame, across the line of sight to ``centre``: the horizontal
    one (k = 1) when the world's ``up`` (camera frame) is known, else both (k = 2). A point's motion
    along these moves it in the image, which KLT measures; along the line of sight it changes only
    the disparity."""
    s = centre / np.linalg.norm(centre)
    ref = up if up is not None else np.array([0.0, 1.0, 0.0])  # camera y (image down) without a pose
    e1 = np.cross(s, ref)
    e1 /= np.linalg.norm(e1)
    return e1[None] if up is not None else np.stack([e1, np.cross(s, e1)])


@dataclass(frozen=True, eq=False)
class MergeGate:
    """One frame's eq. (13) test over every pair of groups; the ratios are squared distances over their γ."""

    overlap: np.ndarray  # (J, J) bool: position, EKF velocity and (where measured) member velocity all inside
    position: np.ndarray  # (J, J) d2p / gamma_position
    velocity: np.ndarray  # (J, J) d2v / γ_v, the EKF velocities
    measured: np.ndarray  # (J, J) the member points' mean velocities across the line of sight / their γ (NaN: not tested)


def merge_overlap(centres: np.ndarray, extents: np.ndarray, velocities: np.ndarray, velocity_covs: np.ndarray,
                  measured: tuple[np.ndarray, np.ndarray], cfg, pose=None) -> MergeGate:
    """The tracker's merge test (``cfg`` a :class:`MergeConfig`; camera-frame inputs, m and m/frame).

    :func:`overlap_pairs` on the EKF states, in the ground plane when ``pose`` (the rig's
    :class:`RigPose`) is given and ``cfg.ground_velocity``. With ``cfg.measured_velocity`` a pair
    must also agree on the member points' measured mean velocities ``measured`` (means and their
    covariances, :func:`measured_velocities`) across the line of sight to the pair's midpoint
    (horizontal, 1 dof, ``gamma_measured_1dof`` with the pose; the 2 image-plane directions,
    ``gamma_measured_2dof``, without), under the EKF velocity covariances plus those of the means.
    Pairs where either group has no measured velocity keep the EKF test alone."""
    vel, vcov, gamma_v = velocities, velocity_covs, cfg.gamma_velocity
    ground = cfg.ground_velocity and pose is not None
    if ground:  # the ground plane's 2 dof of the velocity
        vel, vcov, gamma_v = pose.rotate(vel)[:, :2], pose.rotate_cov(vcov)[:, :2, :2], cfg.gamma_velocity_ground
    both, d2p, d2v = overlap_pairs(centres, extents, vel, vcov, cfg.gamma_position, gamma_v)
    J = len(centres)
    ratio_m = np.full((J, J), np.nan)
    if cfg.measured_velocity:
        mean, mcov = measured
        up = pose.R.T @ np.array([0.0, 0.0, 1.0]) if pose is not None else None  # world Z up, in the camera frame
        gamma_m = cfg.gamma_measured_1dof if up is not None else cfg.gamma_measured_2dof
        ok = np.isfinite(mean).all(axis=1)
        for i, j in zip(*np.triu_indices(J, 1)):
            if not (ok[i] and ok[j]):
                continue
            E = across_sight((centres[i] + centres[j]) / 2.0, up)
            dv = E @ (mean[i] - mean[j])
            S = E @ (velocity_covs[i] + velocity_covs[j] + mcov[i] + mcov[j]) @ E.T
            ratio_m[i, j] = ratio_m[j, i] = float(dv @ np.linalg.solve(S, dv)) / gamma_m
        both = both & ~(ratio_m >= 1.0)  # NaN (no measured velocity) keeps the EKF test
    return MergeGate(both, d2p / cfg.gamma_position, d2v / gamma_v, ratio_m)


def merge_sets(overlap: np.ndarray) -> list[np.ndarray]:
    """Connected sets of two or more trackers (indices ascending, sets by their first index)."""
    if len(overlap) == 0:
        return []
    _, labels = connected_components(csr_matrix(overlap), directed=False)
    sets = [np.flatnonzero(labels == lab) for lab in np.unique(labels)]
    return sorted([s for s in sets if len(s) >= 2], key=lambda s: int(s[0]))
