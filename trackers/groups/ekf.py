"""§3.2 the group's EKF: constant velocity in camera coordinates, observed as ``[u v d]``.

State ``x = [x ẋ y ẏ z ż]ᵀ`` (eq. 1; m and m/frame), ``x_{k+1} = Φ x_k + Γ ω`` with Φ
block-diagonal ``[[1, 1], [0, 1]]`` (eqs. 2–3) and ω a white acceleration. Observation ``z = [u v d]``
(eq. 4) through ``f(x) = [x f/z, y f/z, b f/z]`` (eq. 6; plus the principal point, as the rig's
images carry it), linearised with the rig's Jacobian placed in the position columns.
"""

from __future__ import annotations

import numpy as np

from trackreplay.trackers.filters.kalman import MotionModelEkf
from trackreplay.trackers.geometry.stereo import StereoRig
from trackreplay.trackers.groups.config import EkfConfig

POS = [0, 2, 4]
VEL = [1, 3, 5]
PHI = np.kron(np.eye(3), np.array([[1.0, 1.0], [0.0, 1.0]]))  # eq. (3)


def process_noise(accel_sigma: float) -> np.ndarray:
    """Γ Γᵀ σ_a² for a white acceleration over one frame, per axis."""
    q = np.array([[0.25, 0.5], [0.5, 1.0]]) * accel_sigma**2
    return np.kron(np.eye(3), q)


def measurement(rig: StereoRig, x: np.ndarray) -> np.ndarray:
    """``f(x)``: the state's position as ``[u v d]`` (eq. 6)."""
    return rig.to_uvd(np.asarray(x)[POS])[0]


def measurement_jacobian(rig: StereoRig, x: np.ndarray) -> np.ndarray:
    """3×6 ``∂f/∂x``: the rig's 3×3 Jacobian in the position columns, zeros for the velocities."""
    H = np.zeros((3, 6))
    H[:, POS] = rig.jacobian(np.asarray(x)[POS])
    return H


def position_velocity(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    x = np.asarray(x)
    return x[POS], x[VEL]


def state_from(position: np.ndarray, velocity: np.ndarray) -> np.ndarray:
    x = np.zeros(6)
    x[POS], x[VEL] = position, velocity
    return x


class GroupEkf:
    """One group's filter on filterpy's EKF (:class:`MotionModelEkf`)."""

    def __init__(self, cfg: EkfConfig, rig: StereoRig, x0: np.ndarray, P0: np.ndarray) -> None:
        self.rig = rig
        self.kf = MotionModelEkf(6, 3, lambda x, dt: PHI @ x)
        self.kf.x = np.asarray(x0, dtype=np.float64).copy()
        self.kf.P = np.asarray(P0, dtype=np.float64).copy()
        self.kf.F = PHI
        self.kf.Q = process_noise(cfg.accel_sigma)
        self.kf.R = np.diag([cfg.sigma_u**2, cfg.sigma_v**2, cfg.sigma_d**2])

    @property
    def x(self) -> np.ndarray:
        return self.kf.x

    @property
    def P(self) -> np.ndarray:
        return self.kf.P

    def predict(self) -> None:
        self.kf.predict()

    def update(self, z: np.ndarray) -> None:
        """filterpy's ``update(z, HJacobian, Hx)`` with the rig's model (:meth:`MotionModelEkf.update`), then P symmetrised."""
        rig = self.rig
        self.kf.update(np.asarray(z, dtype=np.float64), lambda x: measurement_jacobian(rig, x), lambda x: measurement(rig, x))
        self.kf.P = 0.5 * (self.kf.P + self.kf.P.T)

    def set(self, x: np.ndarray, P: np.ndarray) -> None:
        self.kf.x = np.asarray(x, dtype=np.float64).copy()
        self.kf.P = np.asarray(P, dtype=np.float64).copy()
