"""Marks placed on their ball (trackers/golf/snap.py): a loose or offset box drawn round the ball
becomes the ball's box; a tight box, a dark ball or a box on nothing stay as drawn."""

import dataclasses

import numpy as np
import pytest

from trackreplay.schemas.records import InitRegion
from trackreplay.trackers.frame import Frame
from trackreplay.trackers.golf import GolfConfig, GolfTracker
from trackreplay.trackers.golf.config import SnapConfig
from trackreplay.trackers.golf.snap import snap_to_ball

BALL = (400.3, 300.6)  # pixel-centre coordinates; a marked box's centre is x + w / 2 (edge coordinates)
EDGE = (BALL[0] + 0.5, BALL[1] + 0.5)


def box(dx, dy, side):
    return InitRegion(0, 0, EDGE[0] + dx, EDGE[1] + dy, side, side, "ball")


def test_a_loose_offset_box_becomes_the_balls_box(backdrop, draw_ball):
    img = draw_ball(backdrop(), BALL, 5.0)
    placed = snap_to_ball(img, box(4.0, -3.0, 20), SnapConfig(), core=0.8)
    assert placed.x == pytest.approx(EDGE[0], abs=0.3) and placed.y == pytest.approx(EDGE[1], abs=0.3)
    assert 9 <= placed.w <= 12 and 9 <= placed.h <= 12  # a 10 px disc (anti-aliased rim)
    assert placed.frame == 0 and placed.label == "ball"


def test_a_tight_box_stays_as_drawn(backdrop, draw_ball):
    img = draw_ball(backdrop(), BALL, 5.0)
    drawn = box(0.4, -0.4, 11)  # within a pixel of the ball, its samples' ellipse inside the ball
    assert snap_to_ball(img, drawn, SnapConfig(), core=0.8) == drawn


def test_no_bright_ball_no_change(backdrop, draw_ball):
    dark = draw_ball(backdrop(), BALL, 5.0, colour=(20, 60, 25))  # darker than the grass round it
    nothing = backdrop()
    for img in (dark, nothing):
        drawn = box(3.0, 2.0, 20)
        assert snap_to_ball(img, drawn, SnapConfig(), core=0.8) == drawn
    bright = draw_ball(backdrop(), BALL, 5.0)
    assert snap_to_ball(bright, box(3.0, 2.0, 20), SnapConfig(enabled=False), core=0.8) == box(3.0, 2.0, 20)


def test_a_large_bright_thing_is_not_a_ball(backdrop):
    img = backdrop()
    img[250:350, 350:450] = 240  # a white sign filling the window: touches its edge
    drawn = box(0.0, 0.0, 30)
    assert snap_to_ball(img, drawn, SnapConfig(), core=0.8) == drawn


def test_the_track_starts_on_the_ball_from_a_loose_box(backdrop, draw_ball):
    # A ball at rest beside a white tee peg, marked with a box 2.5x its size drawn off-centre: the
    # tracker measures the ball itself, with the ball's own area as its size.
    base = backdrop()
    img = draw_ball(base, BALL, 5.0)
    img[int(BALL[1]) + 4:int(BALL[1]) + 14, int(BALL[0]) + 9:int(BALL[0]) + 12] = 235  # the peg, in the loose box
    mark = InitRegion(0, 0, EDGE[0] + 5.0, EDGE[1] + 4.0, 26, 26, "ball")
    frames = [Frame(k, k * 33_333_333, img, hints=(mark,) if k == 0 else (), all_hints=(mark,)) for k in range(4)]

    def first(config):
        tracker = GolfTracker(config, np.random.default_rng(0))
        states = [tracker.step(f)[0] for f in frames]
        return states, tracker.look.targets.area

    states, area = first(GolfConfig())
    assert all(s.status == "measured" and np.hypot(s.x - BALL[0], s.y - BALL[1]) < 1.0 for s in states)
    assert area == pytest.approx(np.pi * 25, rel=0.25)
    # without the snap the box's grass is in the ball's samples; the ring round the box (lut.separable_from_ring)
    # is grass too, so the grass is not learned as ball and the track still starts on the ball
    unsnapped = GolfConfig(snap=dataclasses.replace(GolfConfig().snap, enabled=False))
    states, _ = first(unsnapped)
    assert all(s.status == "measured" and np.hypot(s.x - BALL[0], s.y - BALL[1]) < 1.0 for s in states)
    # without either, the grass is learned as ball: what the LUT picks out runs past twice the box, and the
    # mark is refused rather than tracked (tracker._marked_ball, blobs.spills_over)
    from trackreplay.schemas.errors import LogError

    with pytest.raises(LogError, match="holds no ball the golf tracker can tell from its surroundings"):
        first(dataclasses.replace(unsnapped, lut=dataclasses.replace(unsnapped.lut, ring_margin=0.0)))


def test_bad_settings_are_refused():
    from trackreplay.trackers.golf.config import ParticleConfig, ValidateConfig

    for bad in (lambda: SnapConfig(level=1.5), lambda: SnapConfig(window=1.0), lambda: ValidateConfig(still_px=-1.0),
                lambda: ParticleConfig(rest_roundness=-0.1)):
        with pytest.raises(ValueError):
            bad()
