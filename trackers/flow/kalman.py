"""Per-axis Kalman filter with Gauss–Markov acceleration (§3.2, eq. 12–24).

State ``(x, ẋ, ẍ)`` with ``Φ = [[1, 1, 1/2], [0, 1, 1], [0, 0, α]]`` (eq. 23): the acceleration is
``α`` times the previous one plus white noise of variance ``q``; position and velocity are
observed (``H``, eq. 24) with variances ``r_pos``, ``r_vel``. The paper treats x and y as
independent with the same model, so there is one filter per axis — the project's one Kalman
vocabulary, filterpy's, built by ``trackers.filters.kalman.linear_kalman``.
"""

from __future__ import annotations

import numpy as np
from filterpy.kalman import KalmanFilter

from trackreplay.trackers.filters import kalman
from trackreplay.trackers.filters.kalman import linear_kalman


def transition(alpha: float) -> np.ndarray:
    """Φ of eq. 23 (one frame per time unit)."""
    return np.array([[1.0, 1.0, 0.5], [0.0, 1.0, 1.0], [0.0, 0.0, alpha]])


OBSERVATION = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])  # H of eq. 24


class AxisFilters:
    """Two independent filters (x and y axes) of eq. 23–24."""

    def __init__(
        self, position: tuple[float, float], alpha: float, q: float, r_pos: float, r_vel: float, p0: tuple[float, float, float]
    ) -> None:
        self.filters: list[KalmanFilter] = []
        for p in position:
            self.filters.append(linear_kalman(
                x=[float(p), 0.0, 0.0],
                P=np.diag(np.asarray(p0, dtype=np.float64)),  # eq. 22
                F=transition(alpha),
                Q=np.diag([0.0, 0.0, q]),  # noise enters only the acceleration (eq. 23)
                H=OBSERVATION.copy(),
                R=np.diag([r_pos, r_vel]),  # eq. 24
            ))

    def predict(self) -> None:
        """Propagation, eq. 19–20."""
        for kf in self.filters:
            kalman.predict(kf)

    def update(self, position: np.ndarray, velocity: np.ndarray) -> None:
        """Gain and update, eq. 16–18, with ``z = (position, velocity)`` per axis."""
        for axis, kf in enumerate(self.filters):
            kalman.update(kf, np.array([[position[axis]], [velocity[axis]]]))

    @property
    def state(self) -> np.ndarray:
        """(2, 3): per axis (x, ẋ, ẍ)."""
        return np.stack([kf.x[:, 0] for kf in self.filters]).astype(np.float64)

    @property
    def covariance(self) -> np.ndarray:
        """(2, 3, 3)."""
        return np.stack([kf.P for kf in self.filters]).astype(np.float64)

    @property
    def position(self) -> np.ndarray:
        return self.state[:, 0].copy()

    @property
    def velocity(self) -> np.ndarray:
        return self.state[:, 1].copy()
