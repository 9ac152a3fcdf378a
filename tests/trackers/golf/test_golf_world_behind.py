"""The world behind the ball (trackers/golf/world_behind.py): in a fixed view a blob that does not
stand out from the recent pictures is refused; a moving ball is not; a moving view gives no judgement."""

import dataclasses

import numpy as np
import pytest

from trackreplay.trackers.appearance.color import to_grey

from trackreplay.schemas.records import InitRegion
from trackreplay.trackers.foreground.blobs import Blobs
from trackreplay.trackers.frame import Frame
from trackreplay.trackers.golf import GolfConfig, GolfTracker
from trackreplay.trackers.golf.config import WorldBehindConfig
from trackreplay.trackers.golf.world_behind import WorldBehind

NS = 33_333_333


def boxes(*points, side=11):
    """Blobs whose bounding boxes are ``side`` px squares centred at ``points``."""
    c = np.array(points, float).reshape(-1, 2)
    x0 = np.round(c - (side - 1) / 2).astype(np.int64)
    bbox = np.column_stack([x0, np.full((len(c), 2), side, np.int64)])
    n = len(c)
    return Blobs(c, np.full(n, side * side, float), np.full(n, np.nan), bbox, np.full((n, 3), np.nan))


def textured(backdrop):
    """The backdrop with 16 px squares 40 grey levels apart: a world a panning camera visibly moves."""
    image = backdrop().astype(np.int16)
    rows, cols = np.indices(image.shape[:2]) // 16
    image += (((rows + cols) % 2) * 40 - 20)[..., None].astype(np.int16)
    return np.clip(image, 0, 255).astype(np.uint8)


def scene(backdrop, draw_ball, ball, still=(200.0, 300.0), shift=(0, 0)):
    """A still white disc on a textured backdrop, the whole world moved by ``shift`` px (rows,
    columns), and the ball at ``ball`` (None: not drawn)."""
    image = np.roll(draw_ball(textured(backdrop), still, 5.0), shift, axis=(0, 1))
    return image if ball is None else draw_ball(image, ball, 5.0)



def test_a_still_disc_is_still_and_a_moving_ball_is_not(backdrop, draw_ball):
    world = WorldBehind(WorldBehindConfig())
    for k in range(6):
        world.push(k, scene(backdrop, draw_ball, (300.0 + 12 * k, 300.0)))
    now = scene(backdrop, draw_ball, (372.0, 300.0))

    grey = to_grey(now)
    behind = world.behind(6, now, grey[200:400, 100:500], (100, 200))
    assert behind is not None and len(behind.seen) == 6
    blobs = boxes((200.0, 300.0), (372.0, 300.0))
    assert behind.still(blobs, np.array([True, True])).tolist() == [True, False]
    assert behind.still(blobs, np.array([False, True])).tolist() == [False, False]  # only the blobs asked about


def test_no_judgement_when_the_view_moved_or_too_few_pictures(backdrop, draw_ball):

    world = WorldBehind(WorldBehindConfig())
    world.push(0, scene(backdrop, draw_ball, None))
    world.push(1, scene(backdrop, draw_ball, None))
    now = scene(backdrop, draw_ball, None)
    assert world.behind(2, now, to_grey(now)[200:400, 100:500], (100, 200)) is None  # 2 < min_frames
    moved = WorldBehind(WorldBehindConfig())
    for k in range(6):
        moved.push(k, scene(backdrop, draw_ball, None, shift=(6 * k, 6 * k)))  # a camera panning 6 px a frame each way
    now = scene(backdrop, draw_ball, None, shift=(36, 36))
    assert moved.behind(6, now, to_grey(now)[200:400, 100:500], (100, 200)) is None
    off = WorldBehind(WorldBehindConfig(frames=0))
    off.push(0, now)
    assert off.behind(1, now, to_grey(now)[200:400, 100:500], (100, 200)) is None


def test_config_is_checked():
    with pytest.raises(ValueError, match="world_behind"):
        WorldBehindConfig(frames=-1)
    with pytest.raises(ValueError, match="world_behind"):
        WorldBehindConfig(max_change=-1.0)


def _flight(backdrop, draw_ball, still_at):
    """A ball marked on frame 6 flies right 8 px a frame and is gone from frame 22 on; a still white
    disc as large as it lies ahead on its path, never in the search region while the ball was seen."""
    base = draw_ball(backdrop(), still_at, 5.0)
    path = [(300.0 + 8 * k, 250.0) for k in range(22)] + [None] * 14
    mark = InitRegion(6, 6 * NS, path[6][0], path[6][1], 14, 14, "ball")
    return [Frame(k, k * NS, base if p is None else draw_ball(base, p, 5.0), hints=(mark,) if k == 6 else (),
                  all_hints=(mark,)) for k, p in enumerate(path)]


def test_the_tracker_does_not_measure_a_still_disc_ahead_of_a_vanished_ball(backdrop, draw_ball):
    frames = _flight(backdrop, draw_ball, (528.0, 250.0))

    def run(config):
        tracker = GolfTracker(config, np.random.default_rng(0))
        return [tracker.step(f) for f in frames]

    on = run(GolfConfig())
    assert [s[0].status for s in on[6:22]].count("measured") >= 14  # the flying ball is measured
    assert not [s[0] for s in on[22:] if s[0].status == "measured"]  # the disc never is
    assert on[-1][0].status == "lost"
    off = run(dataclasses.replace(GolfConfig(), world_behind=WorldBehindConfig(frames=0)))
    wrong = [s[0] for s in off[22:] if s[0].status == "measured"]
    assert len(wrong) >= 5 and all(abs(s.x - 528.0) < 2 for s in wrong)  # without it: the disc, measured
