"""Issue 31's defaults beyond the grey cue (test_grey.py): the camera's zoom does not size the target
and the reported confidence is the fitted probability of being right (colorpf.calibration); the
region's bound on growth, refine.max_growth, is in test_refine_foreground.py."""

from __future__ import annotations

import numpy as np
import pytest

from trackreplay.replay.core.config import config_from_dict
from trackreplay.trackers.colorpf.calibration import COEFFICIENTS, RowEvidence, calibrated, cloud_evidence
from trackreplay.trackers.colorpf.config import PAPER, CameraConfig, ColorPfConfig, RefineConfig
from trackreplay.trackers.colorpf.tracker import ColorPfTracker


class _Zoom:
    """A camera measurement that says the scene grew 1.2x about the frame's centre."""

    def update(self, image, box):
        return np.array([[1.2, 0.0, -0.2 * image.shape[1] / 2], [0.0, 1.2, -0.2 * image.shape[0] / 2], [0, 0, 1]])


def _zoomed(scale_size: bool) -> ColorPfTracker:
    tracker = ColorPfTracker(ColorPfConfig(camera=CameraConfig(scale_size=scale_size)), np.random.default_rng(0))
    tracker.pf.initialise(np.array([100.0, 60.0, 20.0, 40.0]), np.array([2.0, 2.0, 0.0, 0.0]))
    tracker.camera = _Zoom()
    tracker._follow_camera(np.zeros((120, 200, 3), np.uint8))
    return tracker


def test_the_scene_zoom_moves_the_cloud_but_sizes_it_only_when_asked():
    kept, scaled = _zoomed(False), _zoomed(True)
    assert np.allclose(kept.pf.particles[:, 2:4], [20.0, 40.0])  # a camera driving behind a car: no growth
    assert np.allclose(scaled.pf.particles[:, 2:4], [24.0, 48.0])  # the previous behaviour, a zoom
    assert np.allclose(kept.pf.particles[:, :2], scaled.pf.particles[:, :2])  # both move with the scene
    assert np.allclose(kept.pf.estimate()[:2], [100.0 * 1.2 - 20.0, 60.0 * 1.2 - 12.0], atol=1.0)


def test_the_calibration_follows_the_evidence_and_paper_keeps_the_colour():
    tight = RowEvidence(0.9, True, False, 0.3, 0.5, 0.1, 0)
    assert calibrated(tight) == pytest.approx(1.0 / (1.0 + np.exp(-np.dot(COEFFICIENTS, tight.features()))), rel=1e-12)
    assert 0.0 < calibrated(RowEvidence(0.9, False, False, 0.3, 0.5, 0.1, 55)) < calibrated(tight) < 1.0
    assert calibrated(RowEvidence(0.9, True, False, -0.2, 0.5, 0.1, 0)) < calibrated(tight)  # mark inside the background
    assert calibrated(RowEvidence(0.9, True, False, 0.3, 0.5, 1.5, 0)) < calibrated(tight)  # a wide cloud
    share, spread = cloud_evidence(np.full(4, 0.25), np.array([[0, 0, 1, 1], [2, 0, 1, 1], [0, 2, 1, 1], [2, 2, 1, 1.0]]),
                                   np.array([1.0, 1.0, 4.0, 4.0]))
    assert share == 1.0 and spread == 0.25  # uniform weights; std 1 px per axis over a 4 px box
    paper = config_from_dict(ColorPfConfig, PAPER)
    assert not paper.calibrate and paper.n_particles == 40 and RefineConfig().max_growth == 1.5

