"""Kalman and extended Kalman filters: filterpy's, in its textbook vocabulary (x, P, F, Q, H, R).

Linear models use ``filterpy.kalman.KalmanFilter`` (``update(z, R=, H=)`` takes the measurement
model per call). Nonlinear ones use :class:`MotionModelEkf`, filterpy's ``ExtendedKalmanFilter``
whose state prediction is a function the tracker passes in (filterpy's documented way: override
``predict_x``); its ``update(z, HJacobian, Hx, R=)``, filterpy's call, takes the measurement model
per call. Every EKF of the trackers (the groups' stereo filter, golf's ballistic one) updates
through it.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import scipy.linalg
from filterpy.kalman import ExtendedKalmanFilter, KalmanFilter


def linear_kalman(x: np.ndarray, P: np.ndarray, F: np.ndarray, Q: np.ndarray, H: np.ndarray, R: np.ndarray) -> KalmanFilter:
    """A filterpy ``KalmanFilter`` with every matrix set (x as a column)."""
    H = np.asarray(H, dtype=np.float64)
    kf = KalmanFilter(dim_x=len(F), dim_z=H.shape[0])
    kf.x = np.asarray(x, dtype=np.float64).reshape(-1, 1)
    kf.P = np.asarray(P, dtype=np.float64)
    kf.F = np.asarray(F, dtype=np.float64)
    kf.Q = np.asarray(Q, dtype=np.float64)
    kf.H = H
    kf.R = np.asarray(R, dtype=np.float64)
    return kf


def predict(kf: KalmanFilter) -> None:
    """filterpy's ``kf.predict()`` (no control input) in its own numpy operations, in its order: the
    same ``x`` and ``P``. The prior is kept as filterpy keeps it, by reference rather than a copy
    (``x`` and ``P`` are replaced, never written in place)."""
    kf.x = np.dot(kf.F, kf.x)
    kf.P = kf._alpha_sq * np.dot(np.dot(kf.F, kf.P), kf.F.T) + kf.Q
    kf.x_prior, kf.P_prior = kf.x, kf.P


def update(kf: KalmanFilter, z: np.ndarray) -> None:
    """filterpy's ``kf.update(z)`` for a column ``z`` of ``dim_z`` rows (Joseph form) in its own numpy
    operations, in its order: the same ``x`` and ``P``. Without its bookkeeping (a deep copy of ``z``,
    the posterior copies: kept by reference), which costs as much as the algebra of a 3-state filter."""
    H, R = kf.H, kf.R
    kf._log_likelihood = kf._likelihood = kf._mahalanobis = None
    kf.y = z - np.dot(H, kf.x)
    PHT = np.dot(kf.P, H.T)
    kf.S = np.dot(H, PHT) + R
    kf.SI = kf.inv(kf.S)
    kf.K = np.dot(PHT, kf.SI)
    kf.x = kf.x + np.dot(kf.K, kf.y)
    I_KH = kf._I - np.dot(kf.K, H)
    kf.P = np.dot(np.dot(I_KH, kf.P), I_KH.T) + np.dot(np.dot(kf.K, R), kf.K.T)
    kf.z, kf.x_post, kf.P_post = z, kf.x, kf.P


class MotionModelEkf(ExtendedKalmanFilter):
    """filterpy's EKF with the state prediction ``x ← fx(x, dt)`` passed in.

    ``predict(u=dt)`` propagates the mean with ``fx`` and the covariance with the current ``F``
    and ``Q`` (``P = F P Fᵀ + Q``); set ``F`` (the Jacobian of ``fx``) and ``Q`` before each call.
    The state is a 1-D vector.
    """

    def __init__(self, dim_x: int, dim_z: int, fx: Callable[[np.ndarray, float], np.ndarray]) -> None:
        super().__init__(dim_x=dim_x, dim_z=dim_z)
        self.fx = fx
        self.x = np.zeros(dim_x)

    def predict_x(self, u: float = 0.0) -> None:
        self.x = self.fx(self.x, u)

    def update(self, z: np.ndarray | None, HJacobian: Callable[..., np.ndarray], Hx: Callable[..., np.ndarray],
               R: np.ndarray | float | None = None, args: tuple = (), hx_args: tuple = (),
               residual: Callable[[np.ndarray, np.ndarray], np.ndarray] = np.subtract,
               PHT: np.ndarray | None = None, S: np.ndarray | None = None) -> None:
        """filterpy's ``ExtendedKalmanFilter.update(z, HJacobian, Hx, R=, args=, hx_args=, residual=)``
        (Joseph form) in its own numpy operations, in its order: the same ``x`` and ``P``. ``PHT = P
        Hᵀ`` and ``S = H PHT + R`` when the caller formed them already (a gate before the update).
        Without filterpy's bookkeeping (a deep copy of ``z``, the posterior copies: kept by
        reference), which costs more than the 3 x 6 algebra itself."""
        if z is None:
            self.z, self.x_post, self.P_post = np.array([[None] * self.dim_z]).T, self.x, self.P
            return
        args = args if isinstance(args, tuple) else (args,)
        hx_args = hx_args if isinstance(hx_args, tuple) else (hx_args,)
        if R is None:
            R = self.R
        elif np.isscalar(R):
            R = np.eye(self.dim_z) * R
        if np.isscalar(z) and self.dim_z == 1:
            z = np.asarray([z], float)
        H = HJacobian(self.x, *args)
        if PHT is None:
            PHT = np.dot(self.P, H.T)
        if S is None:
            S = np.dot(H, PHT) + R
        self.S = S
        self.SI = inverse(S)
        self.K = PHT.dot(self.SI)
        self.y = residual(z, Hx(self.x, *hx_args))
        self.x = self.x + np.dot(self.K, self.y)
        I_KH = self._I - np.dot(self.K, H)
        self.P = np.dot(I_KH, self.P).dot(I_KH.T) + np.dot(self.K, R).dot(self.K.T)
        self._log_likelihood = self._likelihood = self._mahalanobis = None
        self.z, self.x_post, self.P_post = z, self.x, self.P


def inverse(a: np.ndarray) -> np.ndarray:
    """``scipy.linalg.inv(a)`` as filterpy calls it; a finite matrix skips scipy's own finiteness
    check (``np.asarray_chkfinite`` and its wrapping: two thirds of the call on a 3 x 3)."""
    if np.isfinite(a).all():
        return scipy.linalg.inv(a, check_finite=False)
    return scipy.linalg.inv(a)  # raises as filterpy's call does
