"""trackers.lifecycle: a track held while unsupported, lost on the lost_after-th miss, restarted on a new match."""

from __future__ import annotations

import numpy as np
import pytest

from trackreplay.trackers.lifecycle import LifecycleConfig, Run, TrackLife


def test_a_track_is_predicted_until_the_lost_after_th_miss_in_a_row_and_a_supported_frame_forgives_them():
    life = TrackLife(LifecycleConfig(lost_after=3))
    assert [life.missed(), life.missed()] == ["predicted", "predicted"]
    assert not life.lost
    assert life.supported() == "measured" and life.misses == 0
    assert [life.missed() for _ in range(4)] == ["predicted", "predicted", "lost", "lost"]
    assert life.lost
    assert life.held() == "predicted" and life.misses == 4  # a held frame is neither support nor miss
    life.start()
    assert not life.lost and life.misses == 0


def test_a_track_dropped_now_is_lost_until_supported_and_keeps_a_longer_run_of_misses():
    life = TrackLife(LifecycleConfig(lost_after=4))
    life.missed()
    assert life.lose() == "lost" and life.lost and life.misses == 4
    assert life.missed() == "lost" and life.misses == 5
    assert life.lose() == "lost" and life.misses == 5  # already past it: the count stands
    assert life.supported() == "measured" and not life.lost


def test_stone_soups_time_steps_since_update_n_is_lost_after_n_plus_one():
    life = TrackLife(LifecycleConfig(lost_after=12 + 1))
    statuses = [life.missed() for _ in range(13)]
    assert statuses[:12] == ["predicted"] * 12 and statuses[12] == "lost"


def test_a_lost_track_restarts_after_reacquire_frames_matches_in_a_row_each_within_reach():
    life = TrackLife(LifecycleConfig(lost_after=1, reacquire_frames=3))
    reach = np.array([10.0, 10.0])
    assert not life.reacquiring(0, np.array([0.0, 0.0]), reach)  # not lost: nothing to reacquire
    life.missed()
    assert life.reacquiring(5, np.array([0.0, 0.0]), reach)
    assert life.reacquiring(6, np.array([9.0, 0.0]), reach)
    assert life.reacquiring(7, np.array([30.0, 0.0]), reach)  # too far: the run starts again
    assert life.reacquiring(8, np.array([31.0, 0.0]), reach)
    assert life.reacquiring(10, np.array([31.0, 0.0]), reach)  # a frame skipped: again
    assert life.reacquiring(11, np.array([31.0, 0.0]), reach)
    assert not life.reacquiring(12, np.array([31.0, 0.0]), reach)  # third in a row: restarted
    assert life.supported() == "measured" and not life.lost


def test_a_merged_track_is_as_recently_supported_as_its_most_recent_part():
    config = LifecycleConfig(lost_after=5)
    a, b = TrackLife(config), TrackLife(config)
    a.missed(), a.missed(), b.missed()
    merged = TrackLife.merged([a, b])
    assert merged.misses == 1 and merged.config is config


def test_a_run_is_within_its_limit_until_it_reaches_it_and_none_is_unbounded():
    run = Run()
    run.extend(), run.extend()
    assert run.within(3) and not run.within(2) and run.within(None)
    run.reset()
    assert run.count == 0 and not run.within(0)


@pytest.mark.parametrize("lost_after, reacquire", [(0, 1), (1, 0)])
def test_fewer_than_one_frame_is_refused(lost_after, reacquire):
    with pytest.raises(ValueError):
        LifecycleConfig(lost_after, reacquire)
