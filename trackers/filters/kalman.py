"""Kalman and extended Kalman filters: filterpy's, in its textbook vocabulary (x, P, F, Q, H, R).

Linear models use ``filterpy.kalman.KalmanFilter`` (``update(z, R=, H=)`` takes the measurement
model per call). Nonlinear ones use :class:`MotionModelEkf`, filterpy's ``ExtendedKalmanFilter``
whose state prediction is a function the tracker passes in (filterpy's documented way: override
``predict_x``); ``update(z, HJacobian, Hx, R=)`` takes the measurement model per call.
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


class MotionModelEkf(ExtendedKalmanFilter):
    """filterpy's EKF with the state prediction ``x ← fx(x, dt)`` passed in.

    ``predict(u=dt)`` propagates the mean with ``fx`` and the covariance with the current ``F``
    and ``Q`` (``P = F P Fᵀ + Q``); set ``F`` (the Jacobian of ``fx``) and ``Q`` before each call.
    The state is a 1-D vector.

    ``predict`` and ``update`` are filterpy's arithmetic, the same operations in the same order
    (so the same floats), without the bookkeeping copies nothing here reads: ``x_prior``,
    ``P_prior``, ``x_post``, ``P_post`` and ``z`` are not kept (``S``, ``SI``, ``K``, ``y`` are).
    """

    def __init__(self, dim_x: int, dim_z: int, fx: Callable[[np.ndarray, float], np.ndarray]) -> None:
        super().__init__(dim_x=dim_x, dim_z=dim_z)
        self.fx = fx
        self.x = np.zeros(dim_x)

    def predict_x(self, u: float = 0.0) -> None:
        self.x = self.fx(self.x, u)

    def predict(self, u: float = 0.0) -> None:
        """``x ← fx(x, u)``, ``P ← F P Fᵀ + Q`` (filterpy's ``predict``)."""
        self.predict_x(u)
        F = self.F
        self.P = np.dot(F, self.P).dot(F.T) + self.Q

    def update(self, z, HJacobian, Hx, R=None, args=(), hx_args=(), residual=np.subtract) -> None:  # noqa: N803
        """filterpy's ``update`` (Joseph form), the same operations in the same order."""
        if z is None:
            super().update(z, HJacobian, Hx, R, args, hx_args, residual)
            return
        if not isinstance(args, tuple):
            args = (args,)
        if not isinstance(hx_args, tuple):
            hx_args = (hx_args,)
        if R is None:
            R = self.R
        elif np.isscalar(R):
            R = np.eye(self.dim_z) * R
        if self.dim_z == 1 and np.isscalar(z):
            z = np.asarray([z], float)
        dot = np.dot
        x, P = self.x, self.P
        H = HJacobian(x, *args)
        PHT = dot(P, H.T)
        self.S = S = dot(H, PHT) + R
        self.SI = SI = scipy.linalg.inv(S)
        self.K = K = PHT.dot(SI)
        hx = Hx(x, *hx_args)
        self.y = y = residual(z, hx)
        self.x = x + dot(K, y)
        I_KH = self._I - dot(K, H)
        self.P = dot(I_KH, P).dot(I_KH.T) + dot(K, R).dot(K.T)
        self._log_likelihood = None
        self._likelihood = None
        self._mahalanobis = None
