"""The model group tracks are smoothed with offline: the group EKF's own (§3.2, :mod:`.ekf`), its
transition Φ (eq. 3) and white-acceleration process noise, at the config the replay used."""

from __future__ import annotations

from trackreplay.trackers.groups.config import GroupsConfig
from trackreplay.trackers.groups.ekf import PHI, process_noise
from trackreplay.trackers.smoothing import SpaceSmoothing


def smoothing_model(config: GroupsConfig | None = None) -> SpaceSmoothing:
    """The EKF's 3-D constant velocity with its own acceleration noise (``config.ekf.accel_sigma``,
    as given, at ``rate_hz``). Only R's scale is chosen by maximum likelihood: with q free, the raw
    measurement's wander as members hide and show drew q after it (velocity RMSE 0.82 -> 1.15 m/s on
    groups-crossing); with the EKF's q the smoothed velocity is 0.82 -> 0.31 m/s (docs/smoothing.md)."""
    cfg = config if config is not None else GroupsConfig()
    return SpaceSmoothing("groups: the group EKF's 3-D constant velocity (seed 003 §3.2)", PHI, process_noise,
                          accel_grid=(cfg.ekf.accel_sigma,))
