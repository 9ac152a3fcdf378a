"""GroupsConfig.at_rate: per-frame parameters (given at 48 fps) rescaled to the log's frame rate."""

from __future__ import annotations

import numpy as np
import pytest

from trackreplay.trackers.groups.config import GroupsConfig, MergeConfig, TrackConfig


def test_defaults_at_48_fps_are_unchanged():
    cfg = GroupsConfig()
    assert cfg.at_rate(48.0) is cfg and cfg.at_rate(48.01) is cfg


def test_at_24_fps_every_per_frame_value_means_the_same_time():
    cfg = GroupsConfig()
    half = cfg.at_rate(24.0)
    assert half.klt.window == 3 and half.merge.frames == 4 and half.tracks.max_empty_frames == 6
    assert half.rate_hz == 24.0
    # the same continuous-time process noise q = a^2 dt (a in m/s^2 = accel_sigma / dt^2) and the
    # same initial velocity sigma in m/s
    q = lambda c, fps: (c.ekf.accel_sigma * fps**2) ** 2 / fps  # noqa: E731
    assert q(half, 24.0) == pytest.approx(q(cfg, 48.0))
    assert half.ekf.accel_sigma == pytest.approx(cfg.ekf.accel_sigma * 2**1.5)
    assert half.ekf.init_velocity_sigma * 24.0 == pytest.approx(cfg.ekf.init_velocity_sigma * 48.0)
    # eq. (7): the previous extent's weight after one second is the same
    assert half.association.alpha_s**24 == pytest.approx(cfg.association.alpha_s**48)
    # rate-free values are kept
    assert half.stereo == cfg.stereo and half.merge.gamma_velocity == cfg.merge.gamma_velocity
    assert half.grouping == cfg.grouping and half.ekf.sigma_d == cfg.ekf.sigma_d


def test_frame_counts_keep_their_floors_and_scaling_can_be_turned_off():
    cfg = GroupsConfig(merge=MergeConfig(frames=1), tracks=TrackConfig(max_empty_frames=0))
    slow = cfg.at_rate(5.0)
    assert slow.klt.window == 2 and slow.merge.frames == 1 and slow.tracks.max_empty_frames == 0
    fast = GroupsConfig().at_rate(96.0)
    assert fast.klt.window == 12 and fast.merge.frames == 16 and fast.tracks.max_empty_frames == 24
    off = GroupsConfig(scale_with_rate=False)
    assert off.at_rate(24.0) is off
    assert GroupsConfig().at_rate(float("nan")) == GroupsConfig()
    with pytest.raises(ValueError):
        GroupsConfig(rate_hz=0.0)
    assert np.isfinite(GroupsConfig().at_rate(30.0).ekf.accel_sigma)
