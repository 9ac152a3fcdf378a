"""The switches' defaults, config.PAPER and the validation of the switches' values."""

import dataclasses

import pytest

from trackreplay.replay.core.config import config_from_dict
from trackreplay.schemas.errors import TrackreplayError
from trackreplay.trackers.colorpf.config import PAPER, ColorPfConfig


def test_paper_overrides_change_only_the_default_departures():
    ours, paper = ColorPfConfig(), config_from_dict(ColorPfConfig, PAPER)
    assert paper.likelihood.kernel == "uniform" and paper.reference.update_rate == 0.0
    assert paper.likelihood.foreground == 0.0 and not paper.neighbour_check
    assert ours.likelihood.kernel == "epanechnikov" and ours.reference.update_rate > 0
    assert ours.likelihood.foreground > 0 and ours.neighbour_check
    assert paper.refine.mode == "none" and ours.refine.mode == "foreground"
    assert paper.reference.exclude == 0.0 and ours.reference.exclude >= 1.0
    assert not paper.hold.enabled and ours.hold.enabled
    assert not paper.camera.compensate and ours.camera.compensate
    assert paper.support.lost_unsupported == 0 and ours.support.lost_unsupported > 0
    assert paper.frame_rate is None and ours.frame_rate == 30.0  # per frame, whatever the rate
    assert (paper.reacquire_frames, paper.min_box_pixels) == (1, 0) and ours.reacquire_frames > 1 and ours.min_box_pixels > 0
    assert (paper.n_particles, paper.calibrate, paper.likelihood.grey) == (40, False, "hsv")  # issue 31's defaults off
    assert ours.n_particles > 40 and ours.calibrate and ours.likelihood.grey == "gradient" and not ours.camera.scale_size
    assert ours.redetect.enabled and not paper.redetect.enabled
    assert ours.reference.refuse_unseparated and not paper.reference.refuse_unseparated
    assert ours.reference.forget_on_change and not paper.reference.forget_on_change
    # everything else equal: the switches of ours that are off by default stay off under PAPER
    assert dataclasses.replace(paper, likelihood=ours.likelihood, reference=ours.reference,
                               neighbour_check=True, refine=ours.refine, hold=ours.hold, camera=ours.camera,
                               frame_rate=ours.frame_rate, reacquire_frames=ours.reacquire_frames,
                               min_box_pixels=ours.min_box_pixels, support=ours.support,
                               n_particles=ours.n_particles, calibrate=ours.calibrate, redetect=ours.redetect) == ours
    assert (ours.likelihood.parts, ours.motion.model, ours.size.no_plane) == (1, "random_walk", "constant")


@pytest.mark.parametrize("table, values", [
    ("likelihood", {"kernel": "gaussian"}), ("likelihood", {"parts": 0}), ("likelihood", {"foreground": -1.0}),
    ("reference", {"update_rate": 1.5}), ("reference", {"update_above": -0.1}),
    ("motion", {"model": "ballistic"}), ("motion", {"smoothing": 1.0}),
    ("refine", {"mode": "camshift"}), ("refine", {"iterations": 0}), ("refine", {"factor": 1.0}),
    ("refine", {"size_rate": 1.5}), ("refine", {"size_follows": "height"}), ("hold", {"anchor": "mark"}), ("hold", {"early": "mark"}),
    ("size", {"no_plane": "plane"}),
    ("reference", {"exclude": 0.5}), ("hold", {"smoothing": 1.0}), ("hold", {"max_frames": -1}),
    ("camera", {"min_corners": 2}), ("camera", {"renew": "never"}),
    ("reference", {"registration_tolerance": "always"}),
    ("redetect", {"stride": 0.0}), ("redetect", {"share": 0.0}), ("redetect", {"max_boxes": 0}),
])
def test_bad_switch_values_are_named(table, values):
    with pytest.raises(TrackreplayError, match=f"invalid {table} .*{next(iter(values))}"):
        config_from_dict(ColorPfConfig, {table: values})


def test_the_tracks_life_takes_lost_after_and_reacquire_frames():
    import numpy as np

    from trackreplay.trackers.colorpf.tracker import ColorPfTracker

    life = ColorPfTracker(ColorPfConfig(lost_after=2, reacquire_frames=4), np.random.default_rng(0)).life
    assert (life.config.lost_after, life.config.reacquire_frames) == (2, 4)
    assert [life.missed(), life.missed()] == ["predicted", "lost"]
