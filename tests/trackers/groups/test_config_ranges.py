"""Values of the groups config that once gave an empty trajectory with exit 0, or an internal error."""

from __future__ import annotations

import pytest

from trackreplay.trackers.groups.config import (BackgroundConfig, GroundConfig, GroupingConfig, GroupsConfig, MergeConfig,
                                                TrackConfig)


@pytest.mark.parametrize("kwargs, message", [
    ({"rate_hz": 1e300}, "rate_hz must be a positive frame rate of at most 100000"),  # was ZeroDivisionError, exit 70
    ({"rate_hz": 0.0}, "rate_hz must be a positive frame rate"),
    ({"grouping": GroupingConfig(radius_m=-1.0)}, "grouping.radius_m must be a positive distance"),
    ({"grouping": GroupingConfig(radius_m=0.0)}, "grouping.radius_m must be a positive distance"),
    ({"merge": MergeConfig(keep_id_share=1.7)}, "merge.keep_id_share must be in \\[0, 1\\]"),
    ({"background": BackgroundConfig(threshold=300.0)}, "background.threshold must be in \\[0, 255\\]"),
])
def test_out_of_range_values_are_refused(kwargs, message):
    with pytest.raises(ValueError, match=message):
        GroupsConfig(**kwargs)
    GroupsConfig()  # the defaults pass


def test_an_unknown_near_gate_mode_is_refused():
    with pytest.raises(ValueError, match='grouping.near_gate must be "join", "leave" or "start"'):
        GroupingConfig(near_gate="absorb")


@pytest.mark.parametrize("make, message", [
    (lambda: GroundConfig(min_stature_m=1.8), "0 < min_stature_m <= stature_m <= max_stature_m"),
    (lambda: GroundConfig(max_stature_m=1.5), "0 < min_stature_m <= stature_m <= max_stature_m"),
    (lambda: GroundConfig(min_stature_m=0.0), "0 < min_stature_m <= stature_m <= max_stature_m"),
    (lambda: TrackConfig(ground_coast_sigma_m=-0.5), "tracks.ground_coast_sigma_m must be >= 0"),
    (lambda: GroupingConfig(connected="stereo"), 'grouping.connected must be "ground", "all" or "off"'),
])
def test_the_one_camera_rules_refuse_out_of_range_values(make, message):
    with pytest.raises(ValueError, match=message):
        make()
