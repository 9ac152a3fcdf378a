"""Rauch–Tung–Striebel smoothing of many 3-D tracks at once (groups; issue 33).

:class:`trackreplay.trackers.smoothing.SpaceSmoothing`: state ``[X Ẋ Y Ẏ Z Ż]``, the tracker's own
transition and process noise, the 3-D position observed with a full covariance ``R`` (the stereo
points' covariance couples the axes, so the filter does not split into axes as the image one does,
:mod:`.rts`). Each step is numpy's stacked matrix products and solves over ``(grid, track)``, frames
in a Python loop; the RTS gains of every frame are one stacked solve. It replaces filterpy's
``batch_filter`` / ``rts_smoother`` per track and noise, which gave the same numbers to 10⁻¹³ m.
Kalman filter: seed 004 §3.2, eqs. 12–24 (docs/papers.md); smoother: Rauch, Tung and Striebel (1965).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

PRIOR = np.diag([1.0, 0.05, 1.0, 0.05, 1.0, 0.05]) ** 2  # m, m/frame around the first observation (plus its R)
LOG_2PI = math.log(2.0 * math.pi)


@dataclass(frozen=True)
class SpaceColumns:
    """Observations of ``B`` tracks on ``N`` frames (shorter tracks padded with unobserved frames)."""

    z: np.ndarray  # (N, B, 3) observed position (m), 0 where not observed
    R0: np.ndarray  # (N, B, 3, 3) its covariance before the grid's scale, I where not observed
    seen: np.ndarray  # (N, B) 1.0 on an observed frame
    counted: np.ndarray  # (N, B) 1.0 where it counts in the likelihood (observed, not the first)
    x0: np.ndarray  # (B, 6) the prior's mean: the first observation, at rest
    R_first: np.ndarray  # (B, 3, 3) the first observation's R0

    @staticmethod
    def pack(zs: list[np.ndarray], Rs: list[np.ndarray]) -> SpaceColumns:
        """``zs[i]`` (n_i, 3) NaN rows unobserved, ``Rs[i]`` (n_i, 3, 3) (I on those rows)."""
        b, n = len(zs), max(len(z) for z in zs)
        z, R0 = np.zeros((n, b, 3)), np.broadcast_to(np.eye(3), (n, b, 3, 3)).copy()
        seen, counted = np.zeros((n, b)), np.zeros((n, b))
        x0, R_first = np.zeros((b, 6)), np.zeros((b, 3, 3))
        for i, (zi, Ri) in enumerate(zip(zs, Rs)):
            ok = np.isfinite(zi).all(axis=1)
            first, m = int(np.flatnonzero(ok)[0]), len(zi)
            z[:m, i] = np.where(ok[:, None], zi, 0.0)
            R0[:m, i] = Ri
            seen[:m, i] = ok
            counted[:m, i] = ok
            counted[first, i] = 0.0
            x0[i, ::2], R_first[i] = zi[first], Ri[first]
        return SpaceColumns(z, R0, seen, counted, x0, R_first)


def filter_space(cols: SpaceColumns, F: np.ndarray, Q: np.ndarray, s2: np.ndarray, keep: bool):
    """Kalman filter of every track with transition ``F`` (6, 6), process noise ``Q`` (…, 1|B, 6, 6)
    and ``R = R0 s²`` (``s2`` (…, 1|B, 1, 1)). Returns the log-likelihood (…, B) and, with ``keep``,
    the filtered means (N, …, B, 6) and covariances (N, …, B, 6, 6)."""
    shape = np.broadcast_shapes(Q.shape[:-2], s2.shape[:-2], (cols.z.shape[1],))
    P = np.broadcast_to(PRIOR, (*shape, 6, 6)).copy()
    P[..., ::2, ::2] += cols.R_first * s2
    x = np.broadcast_to(cols.x0, (*shape, 6)).copy()
    ll = np.zeros(shape)
    n, Ft = len(cols.z), F.T
    xs = np.empty((n, *x.shape)) if keep else None
    Ps = np.empty((n, *P.shape)) if keep else None
    for k in range(n):
        x = x @ Ft
        P = F @ P @ Ft + Q
        S = P[..., ::2, ::2] + cols.R0[k] * s2
        HP = P[..., ::2, :]
        y = cols.z[k] - x[..., ::2]
        sol = np.linalg.solve(S, np.concatenate([HP, y[..., None]], axis=-1))  # S⁻¹ [H P | y]
        K = sol[..., :6].swapaxes(-1, -2) * cols.seen[k][..., None, None]
        x = x + (K @ y[..., None])[..., 0]
        P = P - K @ HP
        if not keep:
            quad = (y * sol[..., 6]).sum(axis=-1)
            ll -= 0.5 * (quad + np.linalg.slogdet(S)[1] + 3 * LOG_2PI) * cols.counted[k]
        else:
            xs[k], Ps[k] = x, P
    return ll, xs, Ps


def rts_space(xs: np.ndarray, Ps: np.ndarray, F: np.ndarray, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """RTS backward pass over filtered ``xs`` (N, …, 6), ``Ps`` (N, …, 6, 6); the gains
    ``G = P Fᵀ (F P Fᵀ + Q)⁻¹`` of every frame in one stacked solve."""
    Pp = F @ Ps @ F.T + Q
    G = np.linalg.solve(Pp, F @ Ps).swapaxes(-1, -2)  # (Pp⁻¹ F P)ᵀ = P Fᵀ Pp⁻¹ (symmetric P, Pp)
    Fx = xs @ F.T
    xs, Ps = xs.copy(), Ps.copy()
    for k in range(len(xs) - 2, -1, -1):
        xs[k] += (G[k] @ (xs[k + 1] - Fx[k])[..., None])[..., 0]
        Ps[k] += G[k] @ (Ps[k + 1] - Pp[k]) @ G[k].swapaxes(-1, -2)
    return xs, Ps
