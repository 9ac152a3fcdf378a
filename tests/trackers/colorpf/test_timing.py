"""The constants that describe time, at the log's frame interval (ColorPfConfig.frame_rate, colorpf.timing)."""

import math

import numpy as np
import pytest

from trackreplay.schemas.records import InitRegion
from trackreplay.trackers.colorpf.config import ColorPfConfig
from trackreplay.trackers.colorpf.timing import FrameClock, frames_for, interval_ratio, noise_for, smoothing_for
from trackreplay.trackers.colorpf.tracker import ColorPfTracker
from trackreplay.trackers.frame import Frame


def test_interval_ratio():
    assert interval_ratio(66_666_667, 30.0) == pytest.approx(2.0)
    assert interval_ratio(16_666_667, 30.0) == pytest.approx(0.5)
    # the stated rate: ns rounding, whole-ms stamps, 29.97 fps (exactly 1: such logs replay as before)
    for dt in (33_333_333, 33_333_334, 33_000_000, 34_000_000, 33_366_700):
        assert interval_ratio(dt, 30.0) == 1.0
    # no timing: per frame
    assert interval_ratio(None, 30.0) == interval_ratio(0, 30.0) == interval_ratio(-5, 30.0) == 1.0
    assert interval_ratio(66_666_667, None) == 1.0
    clock = FrameClock(30.0)
    assert [clock.step(t) for t in (0, 66_666_667, 133_333_333)] == [1.0, pytest.approx(2.0), pytest.approx(2.0)]


def test_conversions():
    # a random walk spreads with sqrt(time); a smoothing keeps its time constant; a count its duration
    assert np.allclose(noise_for(np.array([3.4, 10.0]), 2.0), [3.4 * math.sqrt(2), 10.0 * math.sqrt(2)])
    assert smoothing_for(0.9, 2.0) == pytest.approx(0.81)
    assert frames_for(30, 2.0) == 15 and frames_for(30, 0.5) == 60 and frames_for(1, 4.0) == 1
    assert frames_for(0, 2.0) == 0 and frames_for(0, 0.5) == 0  # 0 ("none", e.g. hold.max_frames) stays none
    assert noise_for(3.4, 1.0) == 3.4 and smoothing_for(0.9, 1.0) == 0.9 and frames_for(30, 1.0) == 30


def _still_walker(fps: float, frames: int, frame_rate: float | None = 30.0) -> ColorPfTracker:
    """A red walker that stays on its marked box: the early median is ready only when it holds
    reference.frames worth of time (every pixel of the marked box is never free of the track)."""
    rng = np.random.default_rng(0)
    floor = np.clip(rng.normal(120, 6, (120, 160, 3)), 0, 255).astype(np.uint8)
    image = floor.copy()
    image[40:76, 74:86] = (30, 30, 150)
    mark = InitRegion(0, 0, 80.0, 58.0, 12, 36, "target")
    tracker = ColorPfTracker(ColorPfConfig(frame_rate=frame_rate), np.random.default_rng(0))
    for i in range(frames):
        tracker.step(Frame(index=i, t_ns=int(round(i * 1e9 / fps)), image=image, all_hints=(mark,),
                           hints=(mark,) if i == 0 else ()))
    return tracker


def test_early_median_spans_the_same_time_at_half_the_rate():
    # reference.frames = 30 is 1 s at 30 fps: at 15 fps the median is taken after 15 frames (1 s), not 30 (2 s,
    # during which a passing car smeared itself over the walker's later path on otb_crossing at half the rate)
    assert _still_walker(30.0, 29).background.source == "early"  # still collecting
    assert _still_walker(30.0, 30).background.early_count == 30
    at_15 = _still_walker(15.0, 15)
    assert at_15.background.source == "used" and at_15.background.early_count == 15
    assert _still_walker(15.0, 15, frame_rate=None).background.source == "early"  # per frame: 30 of them


def test_stated_rate_replays_as_before():
    """A 30 fps log (whole-ms stamps) steps exactly as with frame_rate = None (the constants per frame)."""
    a, b = _still_walker(30.0, 12), _still_walker(30.0, 12, frame_rate=None)
    assert np.array_equal(a.pf.particles, b.pf.particles)


def test_position_noise_grows_with_the_interval():
    """At 15 fps the cloud's spread after a step is sqrt(2) times that at 30 fps (eq. (2)'s random walk)."""
    spreads = []
    for fps in (30.0, 15.0):
        tracker = _still_walker(fps, 1)
        tracker.pf.particles[:, :2] = tracker.pf.particles[:1, :2]  # one point: the spread is the noise alone
        before = tracker.pf.particles[:, :2].copy()
        tracker.pf.weights[:] = 1.0 / tracker.pf.n
        captured = {}
        predict = tracker.pf.predict

        def spy(transition, predict=predict, captured=captured):
            predict(transition)
            captured["moved"] = tracker.pf.particles[:, :2] - before

        tracker.pf.predict = spy
        tracker.step(Frame(index=1, t_ns=int(round(1e9 / fps)), image=np.zeros((120, 160, 3), np.uint8)))
        spreads.append(captured["moved"].std(axis=0))
    assert np.allclose(spreads[1] / spreads[0], math.sqrt(2.0), rtol=1e-6)


def test_one_dropped_frame_does_not_shorten_the_durations():
    """A review: reference.frames and hold.max_frames were converted with the last step's interval alone,
    so one 66 ms gap in a 30 fps log halved the early median's window there and then."""
    clock, t = FrameClock(30.0), 0
    for k in range(12):
        t += 66_666_667 if k == 6 else 33_333_333
        clock.step(t)
        if k == 6:
            assert abs(clock.ratio - 2.0) < 1e-6 and clock.typical == 1.0  # that step was two frames long; the log is still 30 fps
    slow, t = FrameClock(30.0), 0
    for _ in range(5):
        t += 66_666_667
        slow.step(t)
    assert abs(slow.typical - 2.0) < 1e-6  # a 15 fps log
