"""reference.registration_tolerance: where the background was resampled into the frame's view, a pixel
is foreground only beyond its 3x3 neighbourhood's min/max (colorpf.foreground)."""

import cv2
import numpy as np
import pytest

from trackreplay.trackers.colorpf.camera import resamples, warp
from trackreplay.trackers.colorpf.config import ReferenceConfig
from trackreplay.trackers.colorpf.foreground import foreground_contrast, registration_band, tolerant_mask
from trackreplay.trackers.foreground.background import foreground_mask


def _zoom(scale: float, dx: float = 0.0, dy: float = 0.0, size: int = 120) -> np.ndarray:
    c = size / 2.0
    return np.array([[scale, 0.0, c - scale * c + dx], [0.0, scale, c - scale * c + dy], [0.0, 0.0, 1.0]])


def _floor(size: int = 120) -> np.ndarray:
    """A textured floor: smoothed noise (features of a few pixels), grey levels 40-250."""
    g = cv2.GaussianBlur(np.random.default_rng(0).normal(0, 1, (size, size)).astype(np.float32), (0, 0), 1.5)
    return np.repeat(np.clip(140 + g / g.std() * 50, 40, 250).astype(np.uint8)[..., None], 3, axis=-1)


def test_a_background_misregistered_by_a_subpixel_zoom_has_no_edge_foreground_with_the_tolerance():
    scene = _floor()
    frame = warp(scene, _zoom(1.03))  # the camera zoomed 3 %
    frame[45:75, 55:65] = 0  # a dark figure on the floor
    measured = _zoom(1.03, dx=0.7, dy=0.7)  # the measured transform, 0.7 px off per axis
    background = warp(scene, measured)
    band = registration_band(background, measured, "resampled")
    assert band is not None
    floor = np.ones(frame.shape[:2], bool)
    floor[43:77, 53:67] = False
    plain = foreground_mask(frame, background, 25.0, open_px=3)
    tolerant = tolerant_mask(frame, band, 25.0, 3)
    assert plain[floor].sum() > 150  # the texture's edges, under a pixel apart, survive the opening
    assert tolerant[floor].sum() == 0
    assert tolerant[45:75, 55:65].all()  # the figure (0 against 40..250) stays foreground
    # the cue: a box on the floor above the figure has no foreground with the band, the figure's box all
    xy, wh = np.array([[60.0, 60.0], [60.0, 20.0]]), np.array([12.0, 32.0])
    c_plain = foreground_contrast(frame, background, xy, wh, 25.0, 3)
    c_tolerant = foreground_contrast(frame, background, xy, wh, 25.0, 3, band=band)
    assert c_tolerant[1] == 0.0 and c_tolerant[0] > c_plain[0] > 0.5, (c_plain, c_tolerant)


@pytest.mark.parametrize("transform", [np.eye(3), _zoom(1.0, dx=3.0, dy=-1.0),
                                       np.array([[1.0, 0, -2], [0, 1.0, 5], [0, 0, 1]])])
def test_a_still_camera_or_a_whole_pixel_shift_keeps_the_plain_test(transform):
    """Nothing resampled: no band, so the mask is foreground_mask's exactly (bit-identical replays)."""
    assert not resamples(transform)
    background = warp(_floor(), transform)
    assert registration_band(background, transform, "resampled") is None


def test_resampled_and_never():
    assert resamples(_zoom(1.0, dx=0.5)) and resamples(_zoom(1.01))
    background = warp(_floor(), _zoom(1.03))
    assert registration_band(background, _zoom(1.03), "never") is None
    assert ReferenceConfig().registration_tolerance == "resampled"
    with pytest.raises(ValueError):
        ReferenceConfig(registration_tolerance="always")


def test_the_band_of_an_unresampled_background_is_the_plain_test():
    """With low == high == background the tolerant test is foreground_mask bit for bit."""
    rng = np.random.default_rng(1)
    background = rng.integers(0, 256, (40, 50, 3), dtype=np.uint8)
    image = rng.integers(0, 256, (40, 50, 3), dtype=np.uint8)
    assert np.array_equal(tolerant_mask(image, (background, background), 25.0, 3),
                          foreground_mask(image, background, 25.0, open_px=3))
