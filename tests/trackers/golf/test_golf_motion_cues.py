"""Cues from motion (ours, on top of seed 000): the moving silhouette against a world-fixed
background, the mixed-state stop and the samples drawn around each measured blob (ICONDENSATION-like)
(tentative tracks side by side: test_golf_honest)."""

import dataclasses

import cv2
import numpy as np

from trackreplay.schemas.records import InitRegion
from trackreplay.trackers.appearance.color import to_ycbcr
from trackreplay.trackers.frame import Frame
from trackreplay.trackers.golf import GolfConfig, GolfTracker
from trackreplay.trackers.golf.config import ContrastConfig, ParticleConfig, WorldBehindConfig
from trackreplay.trackers.golf.particles import motion
from trackreplay.trackers.golf.silhouette import contrast_silhouette, moving_silhouette, previous_in_pose


def cloudy_sky(seed: int = 1, size: tuple[int, int] = (240, 320)) -> np.ndarray:
    """Blue sky with small white puffs as bright as a distant ball (the clutter a LUT cannot reject)."""
    rng = np.random.default_rng(seed)
    h, w = size
    img = np.full((h, w, 3), (205.0, 160.0, 95.0)) + rng.normal(0.0, 2.0, (h, w, 3))
    for _ in range(60):
        x, y, r = rng.uniform(0, w), rng.uniform(0, h), rng.uniform(1.0, 2.5)
        cv2.circle(img, (int(x * 16), int(y * 16)), int(r * 16), (240, 238, 236), -1, cv2.LINE_AA, 4)
    return np.clip(img, 0, 255).astype(np.uint8)


def test_only_what_moves_against_the_world_is_in_the_moving_silhouette():
    # The camera pans 7 px left and 3 px up between frames (a pure rotation's homography is a shift
    # here); a 2 px ball sits among puffs as bright as it, and moved 9 px against the sky.
    world = cloudy_sky()
    H = np.array([[1.0, 0.0, -7.0], [0.0, 1.0, -3.0], [0.0, 0.0, 1.0]])  # previous pixels -> this frame's
    previous = world.copy()
    cv2.circle(previous, (150, 120), 1, (242, 242, 242), -1)
    now = cv2.warpPerspective(world, H, (320, 240), borderMode=cv2.BORDER_REFLECT)
    cv2.circle(now, (152, 111), 1, (242, 242, 242), -1)
    ycc = to_ycbcr(now[60:200, 60:260])
    before = previous_in_pose(previous, H, (60, 60), ycc.shape[:2])
    cfg, scale = ContrastConfig(), 1.0
    moving = moving_silhouette(ycc, before, 2.5, cfg, scale)
    ys, xs = np.nonzero(moving)
    assert len(xs) and np.all(np.hypot(xs + 60 - 152, ys + 60 - 111) <= 2.5)  # the ball and nothing else
    # The same ball, were it still against the sky, is not moving; the puffs pass the plain contrast test.
    assert contrast_silhouette(ycc, 2.5, ContrastConfig(min_contrast=15.0), scale).sum() > 5 * moving.sum()
    cv2.circle(previous, (159, 114), 1, (242, 242, 242), -1)  # where the ball is now, in the previous pose
    still = moving_silhouette(ycc, previous_in_pose(previous, H, (60, 60), ycc.shape[:2]), 2.5, cfg, scale)
    assert not still[111 - 60 - 3:111 - 60 + 4, 152 - 60 - 3:152 - 60 + 4].any()


def test_samples_stop_only_when_a_camera_follows_the_ball():
    cfg = ParticleConfig(stop_share=0.25, noise_pos_px=0.0, noise_vel_px=0.0)
    particles = np.tile([100.0, 100.0, 10.0, -5.0], (400, 1))
    followed = motion(cfg, 1.0, damp=False, steps=1, followed=True)(particles, np.random.default_rng(0))
    stopped = np.all(followed[:, 2:] == 0.0, axis=1)
    assert 60 <= stopped.sum() <= 140 and np.allclose(followed[stopped, :2], [100.0, 100.0])
    fixed = motion(cfg, 1.0, damp=False, steps=1, followed=False)(particles, np.random.default_rng(0))
    assert np.allclose(fixed[:, 2:], [10.0, -5.0]) and np.allclose(fixed[:, :2], [110.0, 95.0])
    missed = motion(cfg, 1.0, damp=True, steps=1, followed=True)(particles, np.random.default_rng(0))
    assert not np.any(np.all(missed[:, 2:] == 0.0, axis=1))  # after a miss the damping slows them instead


# --- the two cues in the tracker, end to end --------------------------------------------------

NS = 33_333_333


def marked_sequence(backdrop, draw_ball, positions):
    """Frames with a 5 px ball at ``positions[k]``, marked on the first frame only (no camera pose)."""
    base = backdrop()
    regions = (InitRegion(0, 0, *positions[0], 14, 14, "ball"),)
    return [Frame(k, k * NS, draw_ball(base, p, 5.0), hints=regions if k == 0 else (), all_hints=regions)
            for k, p in enumerate(positions)]


def assert_followed(rows, path, unconfirmed=0):
    """Every row ``measured`` within 3 px of the ball, but the ``unconfirmed`` rows after the mark:
    a ball marked in flight, its first steps farther than its size from the mark, is `predicted`
    until a path from the mark confirms it (trackers/golf/validate.py, ``Validator.seed_at``)."""
    statuses = [s.status for s in rows]
    assert statuses == ["measured"] + ["predicted"] * unconfirmed + ["measured"] * (len(path) - 1 - unconfirmed), statuses
    for s, (x, y) in zip(rows, path):
        if s.status == "measured":
            assert abs(s.x - x) < 3 and abs(s.y - y) < 3


def track(frames, world_behind=None, **particles):
    """The golf tracker's rows over ``frames`` with the default config, ``particles`` fields replaced
    (and the world behind the ball's config, when given)."""
    cfg = GolfConfig()
    cfg = dataclasses.replace(cfg, particles=dataclasses.replace(cfg.particles, **particles))
    if world_behind is not None:
        cfg = dataclasses.replace(cfg, world_behind=world_behind)
    tracker = GolfTracker(cfg, np.random.default_rng(0))
    return [tracker.step(f)[0] for f in frames]


def test_a_followed_ball_that_stops_in_the_picture_is_still_measured(backdrop, draw_ball):
    # Hand-held view (no pose), the operator keeps the ball in the central half of the picture: it
    # crosses it at 25 px a frame, then from frame 10 on sits still (the operator caught up, or the
    # ball stopped). The mixed state's stopped samples are already where it is: every frame measured.
    path = [(400.0 + 25 * k, 360.0) for k in range(10)] + [(625.0, 360.0)] * 10
    frames = marked_sequence(backdrop, draw_ball, path)
    # The backdrop here stands still, so the world behind the ball (trackers/golf/world_behind.py) would
    # rightly refuse a ball at rest after it moved; this test is about the samples, so it is off.
    # (25 px a frame, 2.5 diameters: the first step from the mark is confirmed on frame 2, mark -> 1 -> 2)
    assert_followed(track(frames, world_behind=WorldBehindConfig(frames=0)), path, unconfirmed=1)
    # Constant-velocity samples alone run on past it: predicted as soon as it stops, and found
    # again only by the evidence a jump needs (a tentative track, three frames).
    moving_only = track(frames, stop_share=0.0)
    assert [s.status for s in moving_only[:10]] == ["measured", "predicted"] + ["measured"] * 8
    assert [s.status for s in moving_only[10:12]] == ["predicted"] * 2, [s.status for s in moving_only]
    assert all(abs(s.x - 625.0) < 2 for s in moving_only[12:] if s.status == "measured")


def test_a_ball_that_bounces_is_followed_by_the_samples_drawn_around_it(backdrop, draw_ball):
    # Near the top-left corner (outside the central half: no camera following, no stopped samples) a
    # ball falls 8 px a frame, and from frame 10 on rises as fast (a bounce: vertical velocity reversed).
    # Samples drawn around each measured blob, moving as it just moved, turn the cloud within a frame.
    path = [(100.0 + 6 * k, 40.0 + 8 * k) for k in range(10)]
    path += [(100.0 + 6 * k, 112.0 - 8 * (k - 9)) for k in range(10, 20)]
    frames = marked_sequence(backdrop, draw_ball, path)
    assert_followed(track(frames), path)
    # Without them the weights alone cannot turn a cloud that has no sample moving up: one frame
    # after the bounce the ball is off the prediction, and it is taken back only by the evidence
    # a jump needs (a tentative track, three frames).
    weights_only = track(frames, detection_share=0.0)
    assert [s.status for s in weights_only[:11]] == ["measured"] * 11
    assert [s.status for s in weights_only[11:13]] == ["predicted"] * 2, [s.status for s in weights_only]
    assert all(abs(s.y - path[k][1]) < 3 for k, s in enumerate(weights_only) if k >= 13 and s.status == "measured")
