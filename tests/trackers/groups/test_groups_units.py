"""Group tracker pieces on crafted data: EKF measurement model, gating and m_p*m_v association,
initial grouping, merging only when position AND velocity overlap, subtraction stereo vs full SGBM."""

from __future__ import annotations

import numpy as np

from trackreplay.trackers.geometry.stereo import StereoRig
from trackreplay.trackers.geometry.subtraction_stereo import (SgbmConfig, disparity_agreement, full_disparity,
                                                            subtraction_stereo)
from trackreplay.trackers.groups.association import associate
from trackreplay.trackers.groups.config import EkfConfig
from trackreplay.trackers.groups.ekf import GroupEkf, measurement, measurement_jacobian, state_from
from trackreplay.trackers.groups.grouping import initial_groups
from trackreplay.trackers.groups.merging import merge_sets, overlap_pairs

RIG = StereoRig(f=513.5, baseline=0.12, cx=319.5, cy=239.5)


def test_measurement_is_eq6_and_jacobian_matches_finite_differences():
    x = state_from(np.array([0.8, -1.2, 7.5]), np.array([0.02, 0.0, -0.01]))
    u, v, d = measurement(RIG, x)
    assert np.allclose([u - RIG.cx, v - RIG.cy, d], [0.8 * RIG.f / 7.5, -1.2 * RIG.f / 7.5, RIG.baseline * RIG.f / 7.5])
    H = measurement_jacobian(RIG, x)
    eps = 1e-6
    numeric = np.stack([(measurement(RIG, x + eps * e) - measurement(RIG, x - eps * e)) / (2 * eps) for e in np.eye(6)], axis=1)
    assert np.allclose(H, numeric, atol=1e-5)
    assert np.all(H[:, [1, 3, 5]] == 0)


def test_ekf_follows_a_known_3d_path_through_uvd():
    rng = np.random.default_rng(0)
    truth = np.array([-2.0, -1.0, 9.0])
    vel = np.array([0.03, 0.0, -0.02])  # m/frame
    ekf = GroupEkf(EkfConfig(), RIG, state_from(truth + [0.3, 0.2, 0.5], np.zeros(3)), np.diag([0.25, 1e-3] * 3))
    for _ in range(120):
        truth = truth + vel
        ekf.predict()
        z = RIG.to_uvd(truth[None])[0] + rng.normal(0, [2.0, 2.0, 0.1])
        ekf.update(z)
    assert np.linalg.norm(ekf.x[[0, 2, 4]] - truth) < 0.25
    assert np.linalg.norm(ekf.x[[1, 3, 5]] - vel) < 0.01


def test_gate_and_mp_mv_pick_the_group_moving_like_the_point():
    centres = np.array([[0.0, 0.0, 8.0], [0.4, 0.0, 8.0]])
    covs = np.array([np.eye(3) * 0.25] * 2)
    vmeans = np.array([[0.03, 0, 0], [-0.03, 0, 0]])
    vcovs = np.array([np.eye(3) * 1e-4] * 2)
    points = np.array([[0.25, 0, 8.0], [0.15, 0, 8.0], [5.0, 0, 8.0]])  # the first is nearer group 1 ...
    velocities = np.array([[0.03, 0, 0], [-0.03, 0, 0], [0, 0, 0]])  # ... but moves with group 0
    a = associate(points, velocities, centres, covs, vmeans, vcovs, gamma=11.34)
    assert a.labels.tolist() == [0, 1, -1]
    assert a.contested.tolist() == [True, True, False]
    # the paper's printed m_v * m_v would ignore position: the product uses both
    assert a.score[0, 0] > a.score[0, 1]


def test_initial_grouping_links_points_within_the_radius():
    pts = np.array([[0, 0, 8], [0.6, 0, 8], [1.2, 0, 8], [5, 0, 8], [5.5, 0, 8]], float)
    groups = initial_groups(pts, radius=1.0, min_points=2)
    assert [g.tolist() for g in groups] == [[0, 1, 2], [3, 4]]
    assert initial_groups(pts, radius=1.0, min_points=3)[0].tolist() == [0, 1, 2]


def test_merge_needs_position_and_velocity_overlap():
    centres = np.array([[0.0, 0.0, 8.0], [0.5, 0.0, 8.0], [0.5, 0.0, 8.2]])
    extents = np.array([np.eye(3) * 0.1] * 3)
    vcov = np.array([np.eye(3) * 1e-5] * 3)
    # groups 0 and 1 pass each other (opposite velocities); 0 and 2 walk together
    vel = np.array([[0.03, 0, 0], [-0.03, 0, 0], [0.03, 0, 0.0005]])
    both, d2p, d2v = overlap_pairs(centres, extents, vel, vcov, 11.34, 11.34)
    assert d2p[0, 1] < 11.34 and d2v[0, 1] > 11.34 and not both[0, 1]
    assert both[0, 2]
    assert [s.tolist() for s in merge_sets(both)] == [[0, 2]]


def test_merge_needs_the_member_points_measured_velocities_to_agree_too():
    from trackreplay.trackers.groups.config import MergeConfig
    from trackreplay.trackers.groups.merging import measured_velocities, merge_overlap

    rng = np.random.default_rng(0)
    centres = np.array([[0.0, 0.0, 8.0], [0.3, 0.0, 8.2]])
    extents = np.array([np.eye(3) * 0.1] * 2)
    # the EKF velocities agree (one drifted towards the other's), sigma 0.003 m/frame each
    vel = np.array([[0.030, 0, 0], [0.031, 0, 0]])
    vcov = np.array([np.eye(3) * 0.003**2] * 2)
    # the points' own velocities: 0.02 m/frame (1 m/s at 48 fps) apart, 30 points each, spread 0.01
    lam = np.concatenate([rng.normal([0.02, 0, 0], 0.01, (30, 3)), rng.normal([0.04, 0, 0], 0.01, (30, 3))])
    labels = np.repeat([0, 1], 30)
    cfg = MergeConfig(ground_velocity=False)
    means, covs = measured_velocities(lam, labels, 2, 2)
    assert np.allclose(covs[0], np.cov(lam[:30].T) / 30)
    gate = merge_overlap(centres, extents, vel, vcov, (means, covs), cfg)
    assert gate.position[0, 1] < 1 and gate.velocity[0, 1] < 1  # the EKF test alone would count the frame
    assert gate.measured[0, 1] > 1 and not gate.overlap[0, 1]
    # the same points moving alike: the frame counts
    same = merge_overlap(centres, extents, vel, vcov, measured_velocities(lam - np.where(labels[:, None] == 1, [0.02, 0, 0], 0.0),
                                                                          labels, 2, 2), cfg)
    assert same.measured[0, 1] < 1 and same.overlap[0, 1]
    # a group with fewer than min_points points has no measured velocity: the EKF test alone
    few = merge_overlap(centres, extents, vel, vcov, measured_velocities(lam, np.where(np.arange(60) < 59, 0, 1), 2, 2), cfg)
    assert np.isnan(few.measured[0, 1]) and few.overlap[0, 1]
    # along the line of sight (disparity slopes, errors shared by a surface's points) they are not tested
    deep = lam + np.where(labels[:, None] == 1, [-0.02, 0, 0.05], 0.0)  # the same across, 2.4 m/s apart in depth
    along = merge_overlap(centres, extents, vel, vcov, measured_velocities(deep, labels, 2, 2), cfg)
    assert along.measured[0, 1] < 1 and along.overlap[0, 1]
    # points gated by both groups are left out of a group's mean when it has enough of its own
    contested = np.zeros(60, bool)
    contested[30:45] = True  # half of group 1's points, moved to group 0's velocity: contested, not counted
    mixed = np.where((np.arange(60) >= 30)[:, None] & contested[:, None], lam - [0.02, 0, 0], lam)
    means_c, _ = measured_velocities(mixed, labels, 2, 2, contested)
    assert np.allclose(means_c[1], lam[45:].mean(axis=0))
    assert not merge_overlap(centres, extents, vel, vcov, measured_velocities(mixed, labels, 2, 2, contested), cfg).overlap[0, 1]
    # switched off: the EKF test alone
    assert merge_overlap(centres, extents, vel, vcov, (means, covs), MergeConfig(ground_velocity=False,
                                                                                 measured_velocity=False)).overlap[0, 1]


def _textured_pair(rng, shift_bg=4, shift_fg=11):
    h, w = 240, 320
    bg = rng.integers(0, 255, (h, w)).astype(np.uint8)
    bg = np.clip(np.kron(rng.integers(0, 255, (h // 2, w // 2)), np.ones((2, 2))), 0, 255).astype(np.uint8)
    fg = np.clip(np.kron(rng.integers(0, 255, (h // 2, w // 2)), np.ones((2, 2))), 0, 255).astype(np.uint8)
    mask = np.zeros((h, w), bool)
    mask[80:170, 150:220] = True
    left = np.where(mask, fg, bg)
    right = np.roll(bg, -shift_bg, axis=1).copy()
    rmask = np.roll(mask, -shift_fg, axis=1)
    right[rmask] = np.roll(fg, -shift_fg, axis=1)[rmask]
    return left, right, mask, rmask


def test_subtraction_stereo_equals_full_sgbm_inside_the_foreground():
    left, right, mask, rmask = _textured_pair(np.random.default_rng(1))
    cfg = SgbmConfig(num_disparities=32, block_size=5)
    full = full_disparity(left, right, cfg)
    sub = subtraction_stereo(left, right, mask, cfg, margin=16)
    within, exact, n = disparity_agreement(sub.disparity, full, mask, 1.0)
    assert n > 0.9 * mask.sum()
    assert within >= 0.98
    assert np.nanmedian(sub.disparity[mask]) == 11.0
    assert np.isnan(sub.disparity[~mask]).all()
    assert sub.matched_px < left.size
    checked = subtraction_stereo(left, right, mask, cfg, right_mask=rmask, margin=16)
    assert np.isfinite(checked.disparity).sum() >= 0.9 * np.isfinite(sub.disparity).sum()
