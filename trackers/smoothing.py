"""How a tracker's tracks are smoothed offline: the motion model it declares in its spec
(:class:`trackreplay.trackers.base.TrackerSpec`). The replay side runs the smoother
(``trackreplay.replay.analysis.smooth``); a tracker says only which model and with what noise.

Two kinds: :class:`ImageSmoothing`, constant velocity of an image position (flow, colorpf, golf
and any tracker that declares nothing), and :class:`SpaceSmoothing`, constant velocity of a 3-D
position observed with a covariance (groups, with its EKF's own transition and process noise).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class ImageSmoothing:
    """Constant velocity in the image: per axis ``(p, v)`` in px and px/frame, one step per frame.

    White acceleration integrated over the frame: ``Q = q [[1/3, 1/2], [1/2, 1]]`` per axis. With
    ``observe_velocity`` the track's own ``vx, vy`` on measured rows are observations too (noise
    ``σ_v / √confidence``): the flow tracker's velocity is its primary measurement (mean optical
    flow), filtered by its own Kalman filter.
    """

    name: str = "image constant velocity"
    observe_velocity: bool = False
    # With raw observations (flow): observe the raw velocity (mean flow, eq. 11) instead of the
    # tracker's filtered one. Off: on flow-sim1-3 the raw mean flow made the smoothed velocity worse
    # (0.54 vs 0.48 px/frame RMSE) while the raw centroid made positions better (docs/smoothing.md).
    raw_velocity: bool = False
    velocity_lag: int = 0  # a raw velocity observed at frame k measures the state's velocity at k - lag

    @staticmethod
    def F() -> np.ndarray:  # noqa: N802 (textbook symbol)
        return np.kron(np.eye(2), np.array([[1.0, 1.0], [0.0, 1.0]]))

    @staticmethod
    def Q(q: float) -> np.ndarray:  # noqa: N802
        return np.kron(np.eye(2), q * np.array([[1.0 / 3.0, 0.5], [0.5, 1.0]]))

    @staticmethod
    def H() -> np.ndarray:  # noqa: N802
        """z = (x, y, vx, vy) from the state (x, vx, y, vy)."""
        H = np.zeros((4, 4))
        H[0, 0] = H[1, 2] = H[2, 1] = H[3, 3] = 1.0
        return H

    def describe(self, q: float, sigma: float) -> str:
        """A fit's noise in words (``trackreplay smooth`` prints it per track)."""
        return f"q {q:g} px²/frame³, σ {sigma:g} px"


@dataclass(frozen=True, eq=False)
class SpaceSmoothing:
    """Constant velocity of a 3-D position: state ``[X Ẋ Y Ẏ Z Ż]`` (m, m/frame), transition
    ``transition`` and process noise ``process_noise(a)`` for a white acceleration ``a`` (m/frame²),
    both the tracker's own filter's. Observed: the 3-D position, either the tracker's raw measurement
    with its covariance ``R`` (scaled by ``s²``, ``s`` from ``scale_grid`` by maximum likelihood) or,
    without raw measurements, the tracker's own ``X, Y, Z`` with noise ``σ`` from ``sigma_grid`` (m).

    ``accel_grid``: the accelerations tried. The tracker's own (one value) by default: a raw
    measurement that wanders (the mean of a group's points as members hide and show) draws maximum
    likelihood over ``a`` after the wander (docs/smoothing.md).
    """

    name: str
    transition: np.ndarray = field(repr=False)  # (6, 6)
    process_noise: Callable[[float], np.ndarray] = field(repr=False)  # a (m/frame²) -> (6, 6)
    accel_grid: tuple[float, ...]  # m/frame²
    scale_grid: tuple[float, ...] = (0.3, 1.0, 3.0)  # on the raw R (unitless)
    sigma_grid: tuple[float, ...] = (0.01, 0.03, 0.1, 0.3)  # m, on the tracker's X, Y, Z

    def F(self) -> np.ndarray:  # noqa: N802
        return np.array(self.transition, dtype=np.float64)

    def Q(self, accel: float) -> np.ndarray:  # noqa: N802
        return self.process_noise(accel)

    @staticmethod
    def H() -> np.ndarray:  # noqa: N802
        H = np.zeros((3, 6))
        H[0, 0] = H[1, 2] = H[2, 4] = 1.0
        return H

    def describe(self, q: float, scale: float) -> str:
        return f"q {q:g} (m/frame²)², R scale {scale:g}"


SmoothingModel = ImageSmoothing | SpaceSmoothing
DEFAULT_SMOOTHING = ImageSmoothing()
