"""What the golf tracker carries between frames (trackers.golf.memory), its samples' moments and its
track life (trackers.lifecycle, with golf's max_predicted_frames)."""

import numpy as np
import pytest

from trackreplay.schemas.records import InitRegion
from trackreplay.trackers.filters.particles import ParticleFilter
from trackreplay.trackers.frame import Frame
from trackreplay.trackers.golf.blobs import BlobTargets
from trackreplay.trackers.golf.config import GolfConfig
from trackreplay.trackers.golf.marks import Marks
from trackreplay.trackers.golf.memory import BallLook, FrameView, PreviousFrame, Sightings
from trackreplay.trackers.golf.particles import SampleMoments
from trackreplay.trackers.golf.seen_before import LastSighting
from trackreplay.trackers.golf.tracker import GolfTracker

from .conftest import NS


def test_golf_s_life_is_predicted_for_max_predicted_frames_misses_then_lost():
    life = GolfConfig(max_predicted_frames=2).lifecycle
    assert life.lost_after == 3 and GolfConfig(max_predicted_frames=0).lifecycle.lost_after == 1
    with pytest.raises(ValueError, match="max_predicted_frames"):
        GolfConfig(max_predicted_frames=-1)


def test_a_ball_gone_is_predicted_then_lost_and_a_new_mark_restarts_it(backdrop, draw_ball):
    """Marked on frame 0, seen on 1-2, gone on 3-6: "predicted" on max_predicted_frames (2) of them, then
    "lost" (no position); a mark on frame 7 starts the track again, measured from there."""
    base = backdrop(height=360, width=640)
    marks = (InitRegion(0, 0, 320.0, 200.0, 12, 12, "ball"), InitRegion(7, 7 * NS, 200.0, 120.0, 12, 12, "ball"))
    tracker = GolfTracker(GolfConfig(max_predicted_frames=2), np.random.default_rng(0))
    statuses = []
    for k in range(10):
        image = base if 3 <= k <= 6 else draw_ball(base, (320.0, 200.0) if k < 3 else (200.0, 120.0), 6.0)
        states = tracker.step(Frame(k, k * NS, image, hints=tuple(r for r in marks if r.frame == k), all_hints=marks))
        statuses.append(states[0].status)
        assert (states[0].x is None) == (states[0].status == "lost")
    assert statuses == ["measured"] * 3 + ["predicted"] * 2 + ["lost"] * 2 + ["measured"] * 3
    assert tracker.life.misses == 0


def test_the_samples_moments_are_the_filter_s_and_follow_new_samples():
    pf = ParticleFilter(200, 4, np.random.default_rng(1))
    pf.initialise(np.array([10.0, 20.0, 1.0, -1.0]), np.array([3.0, 4.0, 0.5, 0.5]))
    samples = SampleMoments(pf)
    mean, spread = samples.moments(0)
    np.testing.assert_array_equal(spread, pf.spread(slice(0, 2)))
    np.testing.assert_array_equal(samples.estimate(), pf.estimate())
    assert samples.moments(0)[0] is mean  # once per set of samples
    samples.estimate()[0] = -1.0  # a copy: the caller may keep (and change) it
    assert samples.estimate()[0] == pf.estimate()[0]
    pf.weights = np.linspace(0.0, 1.0, 200) / 100.0  # a new set of weights
    assert samples.moments(0)[0] is not mean
    np.testing.assert_array_equal(samples.moments(2)[1], pf.spread(slice(2, 4)))
    np.testing.assert_array_equal(samples.estimate(), pf.estimate())


def test_the_pixel_scale_is_the_height_s_or_the_marked_ball_s_never_past_the_marked_size():
    look = BallLook()
    assert look.scale(540, 1080, 16.0) == 0.5  # no ball yet: the height's
    look.targets, look.marked_diameter = BlobTargets(np.pi / 4 * 32.0**2, 1.0), 24.0
    assert look.scale(540, 1080, 16.0) == pytest.approx(24.0 / 16.0)  # grown to 32 px: capped at the marked 24
    assert look.scale(540, 1080, 0.0) == 0.5  # reference_ball_px 0: the height alone


def _seen(x, y, diameter=6.0):
    return LastSighting(np.zeros((4, 4, 3), np.uint8), None, (x, y), diameter, 28.0)


def test_sightings_restart_on_a_mark():
    sightings = Sightings()
    first, again = _seen(1.0, 2.0), _seen(3.0, 4.0)
    sightings.add(4, 1.0, 2.0, first)
    sightings.add(5, 3.0, 4.0, again)
    assert (sightings.count, sightings.last_step, sightings.last) == (2, (5, 3.0, 4.0), again)
    sightings.restart()
    assert (sightings.count, sightings.last_step, sightings.last, sightings.first) == (0, None, None, None)


def test_a_ball_rests_until_it_moves_a_diameter_from_where_it_was_first_seen():
    sightings = Sightings()
    sightings.add(4, 100.0, 50.0, _seen(100.0, 50.0))
    assert sightings.resting(5) == (100.0, 50.0, 6.0)  # marked at rest: waiting to be struck
    assert sightings.resting(6) is None  # not measured on the frame before
    sightings.add(5, 104.0, 50.0, _seen(104.0, 50.0))
    assert sightings.resting(6) == (104.0, 50.0, 6.0)  # 4 px: still within a diameter
    sightings.add(6, 120.0, 50.0, _seen(120.0, 50.0))
    sightings.add(7, 101.0, 50.0, _seen(101.0, 50.0))
    assert sightings.resting(8) is None  # it moved: a ball at rest after that is not taken on trust
    sightings.restart()
    sightings.add(9, 101.0, 50.0, _seen(101.0, 50.0))
    assert sightings.resting(10) == (101.0, 50.0, 6.0)  # a new mark: at rest again


def test_the_log_s_marks_are_remembered_once_per_tuple_and_a_list_each_time():
    marks = Marks()
    log = (InitRegion(3, 0, 10.0, 10.0, 4, 4, "ball"),)
    marks.remember_log(log)
    marks.regions.clear()  # (were the tuple read again, its mark would come back)
    marks.remember_log(log)
    assert marks.regions == []
    marks.remember_log([InitRegion(5, 0, 10.0, 10.0, 4, 4, "ball")])
    assert [r.frame for r in marks.regions] == [5]


def test_a_frame_without_a_pose_has_no_pose_change_and_no_compensation(backdrop):
    image = backdrop(height=90, width=160)
    tracker = GolfTracker(GolfConfig(), np.random.default_rng(0))
    view = FrameView.of(Frame(1, NS, image), PreviousFrame.of(Frame(0, 0, image)), tracker.reinit, compensate=True)
    assert view.pose_change is None and not view.compensated and view.size == (160, 90)
    assert view.follows is False  # nothing measured yet, no camera moving
